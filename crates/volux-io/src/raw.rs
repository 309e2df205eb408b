//! Headerless raw grids described by a JSON sidecar (`F.json` beside data file `F`).
//!
//! The convention is the one of `shared/data/README.md`: the sidecar holds `dims_xyz`
//! `[x, y, z]`, `dtype` (`uint8`, `uint16`, `int16`, `float32`; `int8`, `uint32`, `int32` and
//! `float64` are accepted and converted to `float32` with a note), `endianness` (`little` or
//! `big`, default little), `compression` (`gzip`, `none`, or absent: gzip when the name ends in `.gz`), `spacing`, optional
//! `origin`, `direction` (the LPS directions of the index axes, three columns), `unit` (of
//! spacing and origin: `mm` when absent, `µm` for microscopy) and `value_range`. Data is x fastest, then y, then z. The sidecar is parsed with
//! `serde_json`; gzip data goes through `flate2` ([`crate::util::open_maybe_gz`]).
//!
//! Uncompressed little-endian data of a native type is memory-mapped
//! ([`volux_core::Buffer::map_file`]), not copied. The file length must match the sidecar
//! exactly: shorter is [`ErrorKind::Truncated`], longer is a header/data mismatch.
//!
//! [`write()`] writes the data and the sidecar (gzip when the data name ends in `.gz`);
//! [`write_with_progress`] reports progress and [`encoded_size`] tells in advance how many
//! bytes of data will be written.
//!
//! This module also holds the data-section helpers shared with [`crate::nrrd`] and
//! [`crate::metaimage`]: element types, decoding, mapping and ASCII parsing.
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use volux_core::{Buffer, Grid, Samples, ScalarType};

use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::error::WriteError;
use crate::util::{
    check_inflatable, header_err, io_error, open_gz_input, open_regular, read_exact_checked,
    read_regular, regular_metadata, write_chunked, Progress, PROGRESS_STEP,
};

/// Largest sidecar read (a sidecar is a few hundred bytes; anything huge is not one).
const MAX_SIDECAR_BYTES: u64 = 1 << 20;

/// The element type of a data section, including types converted to `f32` on load.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ElemType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl ElemType {
    /// Bytes per value.
    pub(crate) fn size(self) -> usize {
        match self {
            ElemType::I8 | ElemType::U8 => 1,
            ElemType::I16 | ElemType::U16 => 2,
            ElemType::I32 | ElemType::U32 | ElemType::F32 => 4,
            ElemType::I64 | ElemType::U64 | ElemType::F64 => 8,
        }
    }

    /// The grid type kept in memory when no conversion is needed.
    pub(crate) fn native(self) -> Option<ScalarType> {
        match self {
            ElemType::U8 => Some(ScalarType::U8),
            ElemType::U16 => Some(ScalarType::U16),
            ElemType::I16 => Some(ScalarType::I16),
            ElemType::F32 => Some(ScalarType::F32),
            _ => None,
        }
    }

    /// The sidecar name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            ElemType::I8 => "int8",
            ElemType::U8 => "uint8",
            ElemType::I16 => "int16",
            ElemType::U16 => "uint16",
            ElemType::I32 => "int32",
            ElemType::U32 => "uint32",
            ElemType::I64 => "int64",
            ElemType::U64 => "uint64",
            ElemType::F32 => "float32",
            ElemType::F64 => "float64",
        }
    }

    /// Parses a sidecar / numpy-style name (`uint8`, `int32`, `float64`, ...).
    fn from_sidecar(name: &str) -> Option<Self> {
        Some(match name.to_ascii_lowercase().as_str() {
            "int8" | "i8" => ElemType::I8,
            "uint8" | "u8" => ElemType::U8,
            "int16" | "i16" => ElemType::I16,
            "uint16" | "u16" => ElemType::U16,
            "int32" | "i32" => ElemType::I32,
            "uint32" | "u32" => ElemType::U32,
            "int64" | "i64" => ElemType::I64,
            "uint64" | "u64" => ElemType::U64,
            "float32" | "f32" | "float" => ElemType::F32,
            "float64" | "f64" | "double" => ElemType::F64,
            _ => return None,
        })
    }

    /// The note added when values are converted to `f32`.
    fn conversion_note(self) -> Option<String> {
        let why = match self {
            ElemType::I8 => "exact",
            ElemType::I32 | ElemType::U32 | ElemType::I64 | ElemType::U64 => {
                "integers above 2^24 lose precision"
            }
            ElemType::F64 => "precision reduced",
            _ => return None,
        };
        Some(format!("converted from {} to float32 ({why})", self.name()))
    }
}

/// Decoded samples and the conversion note, if any.
pub(crate) struct Decoded {
    pub(crate) samples: Samples,
    pub(crate) note: Option<String>,
}

/// Decodes `bytes` holding values of `ty`; non-native types become `f32`.
pub(crate) fn decode(path: &Path, ty: ElemType, bytes: &[u8], le: bool) -> Result<Decoded> {
    let samples = match ty.native() {
        Some(st) => Samples::from_bytes(st, bytes, le).map_err(|e| ReadError::new(path, e))?,
        None => Samples::F32(Buffer::owned(convert_to_f32(ty, bytes, le))),
    };
    Ok(Decoded {
        samples,
        note: ty.conversion_note(),
    })
}

/// Converts values of a non-native type to `f32`.
fn convert_to_f32(ty: ElemType, bytes: &[u8], le: bool) -> Vec<f32> {
    let n = ty.size();
    bytes
        .chunks_exact(n)
        .map(|c| {
            let mut b = [0u8; 8];
            b[..n].copy_from_slice(c);
            if !le {
                b[..n].reverse();
            }
            let [b0, b1, b2, b3, ..] = b;
            let w = [b0, b1, b2, b3];
            match ty {
                ElemType::I8 => b0 as i8 as f32,
                ElemType::I32 => i32::from_le_bytes(w) as f32,
                ElemType::U32 => u32::from_le_bytes(w) as f32,
                // Straight to float32 (one rounding, as numpy's cast).
                ElemType::I64 => i64::from_le_bytes(b) as f32,
                ElemType::U64 => u64::from_le_bytes(b) as f32,
                ElemType::F64 => f64::from_le_bytes(b) as f32,
                _ => f32::from_le_bytes(w),
            }
        })
        .collect()
}

/// Bytes `count` values of `ty` take, checked against the memory limit.
pub(crate) fn data_bytes(path: &Path, ty: ElemType, count: u64) -> Result<u64> {
    volux_core::limits::check_alloc("data", count, ty.size() as u64)
        .map_err(|e| ReadError::new(path, e))
}

/// Reads `count` uncompressed values of `ty` that start at byte `offset` of `path` and end
/// the file exactly. Native little-endian data is memory-mapped when aligned.
pub(crate) fn read_plain(
    path: &Path,
    offset: u64,
    ty: ElemType,
    le: bool,
    count: u64,
) -> Result<Decoded> {
    // Memory-mapped data takes no memory of the budget (pages come and go with the file):
    // the budget is checked only before data is copied, so a file larger than the budget
    // (or than memory) can be mapped and streamed (`volux convert IN OUT.ome.zarr`).
    let need = count
        .checked_mul(ty.size() as u64)
        .ok_or_else(|| header_err(path, "value count too large"))?;
    let file_len = regular_metadata(path)?.len();
    check_section_len(path, file_len, offset, need)?;
    if le {
        if let Some(samples) = try_map(path, offset, ty, count)? {
            // Non-finite f32 values are replaced in a copy (`Grid::new`): that copy is
            // charged to the budget.
            if let Samples::F32(b) = &samples {
                use rayon::prelude::*;
                if b.as_slice().par_iter().any(|v| !v.is_finite()) {
                    data_bytes(path, ty, count)?;
                }
            }
            return Ok(Decoded {
                samples,
                note: None,
            });
        }
    }
    data_bytes(path, ty, count)?;
    let mut f = open_regular(path)?;
    f.seek(SeekFrom::Start(offset))
        .map_err(|e| io_error(path, e))?;
    let bytes = read_exact_checked(path, f, need)?;
    decode(path, ty, &bytes, le)
}

/// Checks that the section `[offset, offset + need)` ends the file exactly.
pub(crate) fn check_section_len(path: &Path, file_len: u64, offset: u64, need: u64) -> Result<()> {
    let found = file_len.saturating_sub(offset);
    if found < need {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected: need,
                found,
            },
        ));
    }
    if found > need {
        return Err(header_err(
            path,
            format!(
                "header/data size mismatch: the file has {} bytes after the {need} bytes of data the header describes",
                found - need
            ),
        ));
    }
    Ok(())
}

/// Memory-maps native little-endian data; `None` when the type or alignment does not allow it.
fn try_map(path: &Path, offset: u64, ty: ElemType, count: u64) -> Result<Option<Samples>> {
    let n = usize::try_from(count).map_err(|_| header_err(path, "value count too large"))?;
    let err = |e| ReadError::new(path, e);
    Ok(match ty {
        ElemType::U8 => Buffer::map_file(path, offset, n)
            .map_err(err)?
            .map(Samples::U8),
        ElemType::U16 => Buffer::map_file(path, offset, n)
            .map_err(err)?
            .map(Samples::U16),
        ElemType::I16 => Buffer::map_file(path, offset, n)
            .map_err(err)?
            .map(Samples::I16),
        ElemType::F32 => Buffer::map_file(path, offset, n)
            .map_err(err)?
            .map(Samples::F32),
        _ => None,
    })
}

/// Reads `count` values of `ty` from a (decompressing) stream, which must then be at its end.
pub(crate) fn read_stream(
    path: &Path,
    mut reader: impl Read,
    ty: ElemType,
    le: bool,
    count: u64,
) -> Result<Decoded> {
    let need = data_bytes(path, ty, count)?;
    let bytes = read_exact_checked(path, &mut reader, need)?;
    let mut extra = [0u8; 1];
    let more = reader
        .read(&mut extra)
        .map_err(|e| ReadError::new(path, e))?;
    if more > 0 {
        return Err(header_err(
            path,
            format!("header/data size mismatch: the data holds more than the {need} bytes the header describes"),
        ));
    }
    decode(path, ty, &bytes, le)
}

/// Parses `count` whitespace-separated ASCII values of `ty` (exactly that many).
pub(crate) fn parse_ascii(path: &Path, text: &str, ty: ElemType, count: u64) -> Result<Decoded> {
    // Every value takes at least one byte, so a header asking for more cannot be satisfied.
    if count > text.len() as u64 {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected: count,
                found: text.split_ascii_whitespace().count() as u64,
            },
        ));
    }
    let n = count as usize;
    let mut tokens = text.split_ascii_whitespace();
    let samples = match ty {
        ElemType::U8 => Samples::U8(Buffer::owned(parse_tokens(path, &mut tokens, n)?)),
        ElemType::U16 => Samples::U16(Buffer::owned(parse_tokens(path, &mut tokens, n)?)),
        ElemType::I16 => Samples::I16(Buffer::owned(parse_tokens(path, &mut tokens, n)?)),
        _ => Samples::F32(Buffer::owned(parse_float_tokens(path, &mut tokens, ty, n)?)),
    };
    if tokens.next().is_some() {
        return Err(header_err(
            path,
            format!("header/data size mismatch: more than the {count} values the header describes"),
        ));
    }
    Ok(Decoded {
        samples,
        note: ty.conversion_note(),
    })
}

/// Parses `n` integer tokens of a native type.
fn parse_tokens<'a, T: std::str::FromStr>(
    path: &Path,
    tokens: &mut impl Iterator<Item = &'a str>,
    n: usize,
) -> Result<Vec<T>> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let tok = tokens.next().ok_or_else(|| ascii_short(path, n, i))?;
        let v = tok.parse().map_err(|_| {
            ReadError::new(
                path,
                ErrorKind::Invalid(format!(
                    "value {i} '{tok}' is not a valid {}",
                    type_name::<T>()
                )),
            )
        })?;
        out.push(v);
    }
    Ok(out)
}

/// Parses `n` tokens as `f32` (floats, and integer types converted to float).
fn parse_float_tokens<'a>(
    path: &Path,
    tokens: &mut impl Iterator<Item = &'a str>,
    ty: ElemType,
    n: usize,
) -> Result<Vec<f32>> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let tok = tokens.next().ok_or_else(|| ascii_short(path, n, i))?;
        if matches!(ty, ElemType::I64 | ElemType::U64) {
            // 64-bit integers parsed whole, so that one rounding makes them float32.
            let v = tok
                .parse::<i64>()
                .map(|v| v as f32)
                .or_else(|_| tok.parse::<u64>().map(|v| v as f32));
            if let Ok(v) = v {
                out.push(v);
                continue;
            }
        }
        let v: f64 = tok.parse().map_err(|_| {
            ReadError::new(
                path,
                ErrorKind::Invalid(format!("value {i} '{tok}' is not a number")),
            )
        })?;
        let integral = !matches!(ty, ElemType::F32 | ElemType::F64);
        if integral && v.fract() != 0.0 {
            return Err(ReadError::new(
                path,
                ErrorKind::Invalid(format!("value {i} '{tok}' is not a valid {}", ty.name())),
            ));
        }
        out.push(v as f32);
    }
    Ok(out)
}

fn type_name<T>() -> &'static str {
    let full = std::any::type_name::<T>();
    full.rsplit("::").next().unwrap_or(full)
}

fn ascii_short(path: &Path, expected: usize, found: usize) -> ReadError {
    ReadError::new(
        path,
        ErrorKind::Truncated {
            expected: expected as u64,
            found: found as u64,
        },
    )
}

/// Builds the grid from decoded data, adding the conversion note and `notes`.
pub(crate) fn make_grid(
    path: &Path,
    dims: [usize; 3],
    spacing: [f64; 3],
    origin: [f64; 3],
    data: Decoded,
    notes: Vec<String>,
) -> Result<Grid> {
    let mut grid =
        Grid::new(dims, spacing, origin, data.samples).map_err(|e| ReadError::new(path, e))?;
    for note in data.note.into_iter().chain(notes) {
        grid = grid.with_note(note);
    }
    Ok(grid)
}

/// The keys of a raw sidecar that the reader uses.
#[derive(serde::Deserialize)]
struct Sidecar {
    #[serde(default)]
    kind: Option<String>,
    #[serde(default)]
    dims_xyz: Option<[i64; 3]>,
    #[serde(default)]
    dtype: Option<String>,
    #[serde(default)]
    endianness: Option<String>,
    #[serde(default)]
    compression: Option<String>,
    #[serde(default)]
    spacing: Option<[f64; 3]>,
    #[serde(default)]
    origin: Option<[f64; 3]>,
    /// The LPS world directions of the index axes i, j, k (three columns), as `volux info
    /// --json` prints them; absent: the identity.
    #[serde(default)]
    direction: Option<[[f64; 3]; 3]>,
    /// The unit of spacing and origin (`mm` when absent).
    #[serde(default)]
    unit: Option<String>,
    #[serde(default)]
    value_range: Option<[f64; 2]>,
}

/// The data file and its sidecar for `path` (either of the two).
fn data_and_sidecar(path: &Path) -> (PathBuf, PathBuf) {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    match name.strip_suffix(".json") {
        Some(data) if !data.is_empty() => (path.with_file_name(data), path.to_path_buf()),
        _ => (
            path.to_path_buf(),
            path.with_file_name(format!("{name}.json")),
        ),
    }
}

/// Reads and parses the sidecar (a regular file of at most [`MAX_SIDECAR_BYTES`]).
fn read_sidecar(sidecar: &Path) -> Result<Sidecar> {
    let text = read_regular(sidecar, MAX_SIDECAR_BYTES)?;
    let car: Sidecar = serde_json::from_slice(&text)
        .map_err(|e| header_err(sidecar, format!("sidecar JSON: {e}")))?;
    match car.kind.as_deref() {
        None | Some("grid") => Ok(car),
        Some(kind) => Err(ReadError::new(
            sidecar,
            ErrorKind::Unsupported(format!(
                "the sidecar describes a '{kind}' dataset, not a raw grid"
            )),
        )),
    }
}

/// What the sidecar says about the data, validated.
struct Layout {
    dims: [usize; 3],
    count: u64,
    ty: ElemType,
    little_endian: bool,
    gzip: bool,
}

fn layout(sidecar: &Path, car: &Sidecar) -> Result<Layout> {
    let dims = car
        .dims_xyz
        .ok_or_else(|| header_err(sidecar, "sidecar has no 'dims_xyz'"))?;
    let (dims, count) =
        volux_core::limits::checked_dims(dims).map_err(|e| ReadError::new(sidecar, e))?;
    let dtype = car
        .dtype
        .as_deref()
        .ok_or_else(|| header_err(sidecar, "sidecar has no 'dtype'"))?;
    let ty = ElemType::from_sidecar(dtype).ok_or_else(|| {
        ReadError::new(
            sidecar,
            ErrorKind::Unsupported(format!(
                "dtype '{dtype}' (known: uint8, uint16, int16, float32, int8, uint32, int32, int64, uint64, float64)"
            )),
        )
    })?;
    let little_endian = match car.endianness.as_deref().map(str::to_ascii_lowercase) {
        None => true,
        Some(e) if e == "little" || e == "le" => true,
        Some(e) if e == "big" || e == "be" => false,
        Some(e) => {
            return Err(header_err(
                sidecar,
                format!("endianness '{e}' (little or big)"),
            ))
        }
    };
    let gzip = match car.compression.as_deref().map(str::to_ascii_lowercase) {
        None => sidecar.to_string_lossy().ends_with(".gz.json"),
        Some(c) if c == "none" || c.is_empty() => false,
        Some(c) if c == "gzip" || c == "gz" => true,
        Some(c) => {
            return Err(ReadError::new(
                sidecar,
                ErrorKind::Unsupported(format!("compression '{c}' (gzip or none)")),
            ))
        }
    };
    Ok(Layout {
        dims,
        count,
        ty,
        little_endian,
        gzip,
    })
}

/// Reads gzip data the sidecar describes: the file must be gzip (magic bytes `1f 8b`), and
/// its compressed length must be able to hold the declared size before anything is inflated.
fn read_gzip_data(data_path: &Path, l: &Layout) -> Result<Decoded> {
    let input = open_gz_input(data_path)?;
    if !input.gzip {
        return Err(header_err(
            data_path,
            "the sidecar says 'compression: gzip', but the data is not gzip (it does not start \
             with the gzip magic bytes 1f 8b); set 'compression' to 'none'",
        ));
    }
    let need = data_bytes(data_path, l.ty, l.count)?;
    check_inflatable(data_path, input.file_len, need)?;
    read_stream(data_path, input.reader, l.ty, l.little_endian, l.count)
}

/// Replaces a size error on data the sidecar calls uncompressed by a clearer one when the
/// data is gzip after all (a plain file of exactly the declared size is read whatever its
/// first bytes are).
fn gzip_said_none(data_path: &Path, e: ReadError) -> ReadError {
    let size_error = matches!(e.kind, ErrorKind::Truncated { .. } | ErrorKind::Header(_));
    if size_error && starts_with_gzip_magic(data_path) {
        return header_err(
            data_path,
            "the sidecar says the data is uncompressed ('compression: none'), but it is gzip \
             (it starts with the gzip magic bytes 1f 8b); set 'compression' to 'gzip'",
        );
    }
    e
}

/// Whether the regular file `path` starts with the gzip magic bytes.
fn starts_with_gzip_magic(path: &Path) -> bool {
    let mut head = [0u8; 2];
    open_regular(path)
        .is_ok_and(|f| f.take(2).read_exact(&mut head).is_ok() && head == [0x1f, 0x8b])
}

/// The dims a raw grid's sidecar declares, validated, without reading the data: front ends
/// check what a render would build from the grid (a tetrahedral mesh) before loading it.
pub fn dims(path: &Path) -> Result<[usize; 3]> {
    let (_, sidecar) = data_and_sidecar(path);
    let car = read_sidecar(&sidecar)?;
    Ok(layout(&sidecar, &car)?.dims)
}

/// Reads a raw grid through its sidecar; `path` is the data file or the sidecar itself.
pub fn read(path: &Path) -> Result<Grid> {
    let (data_path, sidecar) = data_and_sidecar(path);
    let car = read_sidecar(&sidecar)?;
    let l = layout(&sidecar, &car)?;
    let data = if l.gzip {
        read_gzip_data(&data_path, &l)?
    } else {
        read_plain(&data_path, 0, l.ty, l.little_endian, l.count)
            .map_err(|e| gzip_said_none(&data_path, e))?
    };
    let mut notes = Vec::new();
    let spacing = car.spacing.unwrap_or_else(|| {
        notes.push("sidecar has no spacing: 1 assumed".to_string());
        [1.0; 3]
    });
    let mut grid = make_grid(
        &data_path,
        l.dims,
        spacing,
        car.origin.unwrap_or([0.0; 3]),
        data,
        notes,
    )?;
    if let Some(u) = &car.unit {
        let symbol = volux_core::units::length_symbol(u).ok_or_else(|| {
            header_err(
                &sidecar,
                format!("unit '{u}' is not a length unit (mm, µm, nm, cm, m)"),
            )
        })?;
        grid = grid.with_unit(symbol);
    }
    if let Some([i, j, k]) = car.direction {
        let d = glam::DMat3::from_cols(i.into(), j.into(), k.into());
        grid = grid
            .with_direction(d)
            .map_err(|e| ReadError::new(&sidecar, e))?;
    }
    let differs = |a: f64, b: f64| (a - b).abs() > 1e-6 * a.abs().max(b.abs()).max(1.0);
    Ok(match car.value_range {
        Some(r) if differs(r[0], grid.range()[0]) || differs(r[1], grid.range()[1]) => {
            let note = format!(
                "sidecar value_range {r:?} differs from the data's range {:?}",
                grid.range()
            );
            grid.with_note(note)
        }
        _ => grid,
    })
}

/// The samples as little-endian bytes of their native type.
pub(crate) fn samples_le_bytes(samples: &Samples) -> Vec<u8> {
    fn le<T: Copy, const N: usize>(s: &[T], f: impl Fn(T) -> [u8; N]) -> Vec<u8> {
        s.iter().flat_map(|&v| f(v)).collect()
    }
    match samples {
        Samples::U8(b) => b.to_vec(),
        Samples::U16(b) => le(b, u16::to_le_bytes),
        Samples::I16(b) => le(b, i16::to_le_bytes),
        Samples::F32(b) => le(b, f32::to_le_bytes),
    }
}

/// Bytes of data [`write()`] produces for `grid` before any compression (values times their
/// size; the sidecar is not counted), so a caller can warn before writing a huge file.
pub fn encoded_size(grid: &Grid) -> u64 {
    (grid.len() as u64).saturating_mul(grid.scalar_type().size() as u64)
}

/// Writes `grid` as raw little-endian data in its native type at `path`, plus the sidecar
/// `path.json` (`dims_xyz`, `dtype`, `endianness`, `compression`, `spacing`, `origin`,
/// `direction`, `value_range`). A data name ending in `.gz` (e.g. `ct.raw.gz`, sidecar `ct.raw.gz.json`)
/// is gzip-compressed. Both files are written atomically (temporary name, then rename).
pub fn write(grid: &Grid, path: &Path) -> Result<(), WriteError> {
    write_with_progress(grid, path, &|_, _| {})
}

/// [`write()`], reporting `(bytes written, total bytes)` to `progress` as the data goes out:
/// once at the start, every few MiB, and at the end. Bytes are counted before compression,
/// so the total is [`encoded_size`].
pub fn write_with_progress(
    grid: &Grid,
    path: &Path,
    progress: &dyn Fn(u64, u64),
) -> Result<(), WriteError> {
    let (data_path, sidecar) = data_and_sidecar(path);
    let werr = |p: &Path| {
        let p = p.to_path_buf();
        move |source: volux_core::Error| WriteError { path: p, source }
    };
    let gzip = data_path
        .to_string_lossy()
        .to_ascii_lowercase()
        .ends_with(".gz");
    let text = serde_json::to_vec_pretty(&sidecar_json(grid, gzip))
        .map_err(|e| werr(&sidecar)(volux_core::Error::Json(e)))?;
    volux_core::image::write_atomically_with(&data_path, |file| {
        write_data(file, grid.samples(), gzip, encoded_size(grid), progress)
    })
    .map_err(werr(&data_path))?;
    volux_core::image::write_atomically(&sidecar, &text).map_err(werr(&sidecar))
}

/// What [`write()`] cannot store of `grid`, in words (one note each): the colour of an RGB
/// grid (its luminance is written). Front ends say these before writing.
pub fn unstored(grid: &Grid) -> Vec<String> {
    let mut out = Vec::new();
    if grid.color().is_some() {
        out.push(
            "raw files hold one scalar per voxel: the colour is not stored, its luminance is \
             written (write .nrrd to keep the colour)"
                .to_string(),
        );
    }
    out
}

/// The sidecar [`write()`] puts beside the data.
fn sidecar_json(grid: &Grid, gzip: bool) -> serde_json::Value {
    let d = grid.direction();
    serde_json::json!({
        "kind": "grid",
        "format": "raw",
        "dims_xyz": grid.dims(),
        "layout": "x fastest, then y, then z (C-order array [z][y][x])",
        "dtype": grid.scalar_type().name(),
        "endianness": "little",
        "compression": if gzip { "gzip" } else { "none" },
        "spacing": grid.spacing().to_array(),
        "origin": grid.origin().to_array(),
        "space": "LPS",
        "unit": grid.unit(),
        "direction": [d.x_axis.to_array(), d.y_axis.to_array(), d.z_axis.to_array()],
        "value_range": grid.range(),
    })
}

/// Streams the samples to `file`, gzip-compressed when asked, reporting progress.
fn write_data(
    file: &mut std::fs::File,
    samples: &Samples,
    gzip: bool,
    total: u64,
    progress: &dyn Fn(u64, u64),
) -> std::io::Result<()> {
    let buffered = std::io::BufWriter::new(file);
    if gzip {
        let enc = flate2::write::GzEncoder::new(buffered, flate2::Compression::default());
        let mut out = Progress::new(enc, total, PROGRESS_STEP, progress);
        write_samples(&mut out, samples)?;
        out.into_inner().finish()?.flush()
    } else {
        let mut out = Progress::new(buffered, total, PROGRESS_STEP, progress);
        write_samples(&mut out, samples)?;
        out.flush()
    }
}

/// Writes the samples as little-endian bytes of their native type.
fn write_samples(out: &mut impl Write, samples: &Samples) -> std::io::Result<()> {
    let none = |_: &[u8]| {};
    match samples {
        Samples::U8(b) => b.chunks(1 << 20).try_for_each(|c| out.write_all(c)),
        Samples::U16(b) => write_chunked(out, b, |v, o| o.extend(v.to_le_bytes()), none),
        Samples::I16(b) => write_chunked(out, b, |v, o| o.extend(v.to_le_bytes()), none),
        Samples::F32(b) => write_chunked(out, b, |v, o| o.extend(v.to_le_bytes()), none),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::hostile::*;
    use volux_testkit::mutate::gzip;

    /// Writes a sidecar `name.json` for a `dims` uint8 volume with `compression`.
    fn sidecar(dir: &Path, name: &str, dims: [u64; 3], compression: &str) -> PathBuf {
        let p = dir.join(format!("{name}.json"));
        let json = format!(
            r#"{{"dims_xyz": [{}, {}, {}], "dtype": "uint8", "compression": "{compression}"}}"#,
            dims[0], dims[1], dims[2]
        );
        std::fs::write(&p, json).unwrap();
        dir.join(name)
    }

    #[test]
    fn special_data_and_sidecar_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // A sidecar that is a link to /dev/zero was read until memory ran out.
        std::fs::write(d.join("z.raw"), [1u8; 8]).unwrap();
        zero_link(d, "z.raw.json");
        assert_refused(read(&d.join("z.raw")), "z.raw.json", "(a character device)");
        let data = sidecar(d, "dz.raw", [2, 2, 2], "none");
        std::os::unix::fs::symlink("/dev/zero", &data).unwrap();
        assert_refused(read(&data), "dz.raw", "(a character device)");
        let data = sidecar(d, "gz.raw.gz", [2, 2, 2], "gzip");
        std::os::unix::fs::symlink("/dev/zero", &data).unwrap();
        assert_refused(read(&data), "gz.raw.gz", "(a character device)");
        link_loop(d, "loop.raw.json");
        assert_refused(
            read(&d.join("loop.raw")),
            "loop.raw.json",
            "loop of symbolic links",
        );
        let data = sidecar(d, "f.raw", [2, 2, 2], "none");
        if fifo(d, "f.raw").is_some() {
            assert_refused(read(&data), "f.raw", "(a FIFO)");
        }
    }

    #[test]
    fn compression_mismatches_say_which() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let plain = sidecar(d, "plain.raw", [4, 4, 4], "gzip");
        std::fs::write(&plain, [7u8; 64]).unwrap();
        let e = read(&plain).unwrap_err().to_string();
        assert!(
            e.contains("plain.raw: ")
                && e.contains("says 'compression: gzip', but the data is not gzip"),
            "{e}"
        );
        let gz = sidecar(d, "gz.raw", [4, 4, 4], "none");
        std::fs::write(&gz, gzip(&[7u8; 64])).unwrap();
        let e = read(&gz).unwrap_err().to_string();
        assert!(
            e.contains("gz.raw: ")
                && e.contains("uncompressed ('compression: none'), but it is gzip"),
            "{e}"
        );
        // Plain data of exactly the declared size is read even if it starts with 1f 8b.
        let ok = sidecar(d, "ok.raw", [4, 1, 1], "none");
        std::fs::write(&ok, [0x1f, 0x8b, 0, 0]).unwrap();
        assert_eq!(read(&ok).unwrap().value(1, 0, 0), 139.0);
    }

    #[test]
    fn gzip_bombs_stop_at_the_declared_size() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // 64 MiB of zeros behind a sidecar declaring 1 KiB: inflation stops after 1 KiB + 1.
        let bomb = sidecar(d, "bomb.raw.gz", [16, 16, 4], "gzip");
        std::fs::write(&bomb, gzip(&vec![0u8; 64 << 20])).unwrap();
        let e = read(&bomb).unwrap_err().to_string();
        assert!(
            e.contains("bomb.raw.gz") && e.contains("holds more than the 1024 bytes"),
            "{e}"
        );
        // A tiny file declaring 6 GiB is refused before inflating: deflate cannot expand it so.
        let tiny = sidecar(d, "tiny.raw.gz", [2048, 2048, 1536], "gzip");
        std::fs::write(&tiny, gzip(&[0u8; 100])).unwrap();
        let e = read(&tiny).unwrap_err();
        crate::util::hostile::assert_undeliverable(&e, 6442450944);
    }
}
