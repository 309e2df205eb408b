//! NIfTI-1 and NIfTI-2 images: single-file `.nii` / `.nii.gz` (magic `n+1`, `n+2`) and
//! `.hdr` + `.img` pairs (magic `ni1`, `ni2`, the `.img` optionally gzipped), following the
//! NIfTI-1 specification (<https://nifti.nimh.nih.gov/nifti-1>, `nifti1.h`) and NIfTI-2's
//! (<https://nifti.nimh.nih.gov/nifti-2>, `nifti2.h`).
//!
//! The 348-byte NIfTI-1 header and the 540-byte NIfTI-2 header are parsed here (both are
//! fixed-layout, `layout.rs`; the version and byte order are those in which `sizeof_hdr`
//! reads 348 or 540). NIfTI-2 holds the same fields widened (64-bit dims, float64 geometry
//! and scaling), so both go through the same validation below; a NIfTI-2 file is noted. The `nifti` crate (0.18) was evaluated and rejected: it reads the
//! `dim` fields as `u16`, so a negative dimension becomes a huge one instead of an error; it
//! takes the byte order from `dim[0]` and never checks `sizeof_hdr`; it sizes the data from
//! `bitpix` (cast from `i16` to `usize`) rather than from the datatype; it reserves the whole
//! announced data size before checking what the file holds; and it cannot memory-map.
//!
//! - Dims: `dim[0]` 3, 2 (z = 1), or 4 to 7 with every extra dimension 1; others are
//!   [`ErrorKind::Unsupported`] (1-D, time series) or a header error (0, > 7).
//! - Types: uint8, int16, uint16 and float32 are kept natively (uncompressed little-endian data
//!   is memory-mapped); int8, int32, uint32 and float64 are converted to float32 with a note.
//! - `scl_slope` / `scl_inter` are applied when the slope is non-zero and not (1, 0); the values
//!   then become float32, with a note.
//! - Placement (LPS world, see [`volux_core::orientation`]): the sform when `sform_code > 0`
//!   (spacing = its column lengths, direction = its unit columns, origin = its translation),
//!   else the qform when `qform_code > 0` (quaternion rotation with `qfac`, spacing
//!   `|pixdim[1..=3]|`, origin `qoffset`), else axis-aligned at 0 with spacing
//!   `|pixdim[1..=3]|` (zero or non-finite entries become 1, with a note). NIfTI's RAS
//!   coordinates are turned into LPS by negating x and y (`affine.rs`); a sheared or
//!   degenerate affine is noted and the next method used.
//! - The data starts at `vox_offset` (at least 352 in a NIfTI-1 `.nii`, 544 in a NIfTI-2 one). Sizes are checked before any
//!   allocation: a file shorter than the dims need is [`ErrorKind::Truncated`]; data longer
//!   than the dims declare is read up to the declared size, with a note (for gzip, one byte
//!   past the data is probed, so the check costs nothing).
//! - `bitpix` must match the datatype; a header whose two fields disagree is refused.
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use volux_core::{Buffer, Grid, Samples, ScalarType};

use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::util::{
    header_err, io_error, open_maybe_gz, open_regular, read_exact_checked, regular_metadata,
};

mod affine;
mod header;
mod layout;
mod values;

use header::{show, Header, Version, MAX_HEADER_BYTES};

/// Reads a NIfTI-1 or NIfTI-2 `.nii`, `.nii.gz` or `.hdr` (with its `.img`) file.
pub fn read(path: &Path) -> Result<Grid> {
    let mut raw = Vec::with_capacity(MAX_HEADER_BYTES);
    open_maybe_gz(path)?
        .take(MAX_HEADER_BYTES as u64)
        .read_to_end(&mut raw)
        .map_err(|e| io_error(path, e))?;
    let hdr = header::parse(path, &raw)?;
    let mut notes = Vec::new();
    if hdr.version == Version::Two {
        notes.push("NIfTI-2 header (540 bytes, 64-bit dims)".to_string());
    }
    let (dims, count) =
        volux_core::limits::checked_dims(hdr.dims).map_err(|e| ReadError::new(path, e))?;
    let (data_path, offset) = data_location(path, &hdr, &mut notes)?;
    let bytes = count
        .checked_mul(hdr.dtype.size() as u64)
        .ok_or_else(|| header_err(path, "the data size overflows"))?;
    let scaling = values::scaling(&hdr, &mut notes);
    let span = Span {
        offset,
        bytes,
        count,
    };
    let (samples, surplus) = load_samples(&data_path, &hdr, span, scaling, &mut notes)?;
    notes.extend(surplus_note(&hdr, dims, bytes, surplus));
    let place = affine::placement(&hdr, spacing(&hdr, &mut notes), &mut notes);
    let grid = Grid::new(dims, place.spacing, place.origin, samples)
        .and_then(|g| g.with_direction(place.direction))
        .map_err(|e| ReadError::new(path, e))?;
    Ok(notes.into_iter().fold(grid, Grid::with_note))
}

/// Where the voxels lie in the (decompressed) data file: `bytes` bytes holding `count` values
/// from byte `offset`.
#[derive(Clone, Copy, Debug)]
struct Span {
    offset: u64,
    bytes: u64,
    count: u64,
}

/// What the data file holds past the voxels the dims declare.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Surplus {
    /// Nothing: the dims explain the data.
    None,
    /// This many bytes (an uncompressed file).
    Bytes(u64),
    /// Some bytes (a gzip stream, not decompressed further).
    Some,
}

/// The voxels of `path` (memory-mapped when possible) and what the file holds after them.
fn load_samples(
    path: &Path,
    hdr: &Header,
    span: Span,
    scaling: Option<(f64, f64)>,
    notes: &mut Vec<String>,
) -> Result<(Samples, Surplus)> {
    if is_gzip(path)? {
        let (data, surplus) = read_gz(path, span, notes)?;
        return Ok((values::decode(path, hdr, &data, scaling, notes)?, surplus));
    }
    let surplus = check_length(path, span.offset, span.bytes)?;
    if let (None, Some(ty)) = (scaling, mappable(hdr)) {
        if let Some(samples) = map(path, ty, span)? {
            return Ok((samples, surplus));
        }
    }
    let data = read_plain(path, span.offset, span.bytes)?;
    Ok((values::decode(path, hdr, &data, scaling, notes)?, surplus))
}

/// A note when the data holds more than the dims declare (the extra is not read).
fn surplus_note(hdr: &Header, dims: [usize; 3], bytes: u64, surplus: Surplus) -> Option<String> {
    let [x, y, z] = dims;
    let declared = format!("dims {x}x{y}x{z} of {} declare", hdr.dtype.name());
    let hint = match hdr.unused_dim {
        Some((i, d)) => format!(" (dim[0] is {} but dim[{i}] is {d})", hdr.dim0),
        None => String::new(),
    };
    match surplus {
        Surplus::None => None,
        Surplus::Bytes(n) => Some(format!(
            "the data holds {n} bytes more than the {bytes} that {declared}{hint}; they were ignored"
        )),
        Surplus::Some => Some(format!(
            "the data continues past the {bytes} bytes that {declared}{hint}; the rest was ignored"
        )),
    }
}

/// The file holding the voxels and the byte offset of the first one.
fn data_location(path: &Path, hdr: &Header, notes: &mut Vec<String>) -> Result<(PathBuf, u64)> {
    let v = hdr.vox_offset;
    if !v.is_finite() || v < 0.0 || v.fract() != 0.0 || v > 1e15 {
        return Err(header_err(
            path,
            format!(
                "vox_offset {} is not a non-negative whole number of bytes",
                show(v)
            ),
        ));
    }
    let offset = v as u64;
    if !hdr.single_file {
        return Ok((image_file(path)?, offset));
    }
    let min = hdr.version.min_nii_offset();
    if offset < min {
        notes.push(format!(
            "vox_offset {offset} is below the minimum {min} of a {} .nii file; {min} was used",
            hdr.version.name()
        ));
        return Ok((path.to_path_buf(), min));
    }
    Ok((path.to_path_buf(), offset))
}

/// The `.img` (or `.img.gz`) file next to a `.hdr` header of a `ni1` pair.
fn image_file(path: &Path) -> Result<PathBuf> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    let stem_len = [".hdr.gz", ".hdr", ".nii.gz", ".nii"]
        .iter()
        .find(|s| lower.ends_with(*s))
        .map_or(name.len(), |s| name.len() - s.len());
    let stem = name.get(..stem_len).unwrap_or(&name);
    let candidates = [format!("{stem}.img"), format!("{stem}.img.gz")];
    candidates
        .iter()
        .map(|c| path.with_file_name(c))
        .find(|p| p.exists())
        .ok_or_else(|| {
            ReadError::new(
                path,
                ErrorKind::Invalid(format!(
                    "magic \"ni1\" puts the voxels in a separate file, but neither {} nor {} exists",
                    candidates[0], candidates[1]
                )),
            )
        })
}

/// Whether the file starts with the gzip magic bytes.
fn is_gzip(path: &Path) -> Result<bool> {
    let mut magic = [0u8; 2];
    let mut f = open_regular(path)?;
    let n = f.read(&mut magic).map_err(|e| io_error(path, e))?;
    Ok(n == 2 && magic == [0x1f, 0x8b])
}

/// The native scalar type when the data can be memory-mapped as it is.
fn mappable(hdr: &Header) -> Option<ScalarType> {
    if !hdr.le {
        return None;
    }
    values::native_type(hdr.dtype)
}

/// Memory-maps the values of `span` as `ty`; `None` when mapping is not possible.
fn map(path: &Path, ty: ScalarType, span: Span) -> Result<Option<Samples>> {
    let n = usize::try_from(span.count)
        .map_err(|_| header_err(path, "the voxel count is too large"))?;
    let err = |e| ReadError::new(path, e);
    let offset = span.offset;
    Ok(match ty {
        ScalarType::U8 => Buffer::map_file(path, offset, n)
            .map_err(err)?
            .map(Samples::U8),
        ScalarType::U16 => Buffer::map_file(path, offset, n)
            .map_err(err)?
            .map(Samples::U16),
        ScalarType::I16 => Buffer::map_file(path, offset, n)
            .map_err(err)?
            .map(Samples::I16),
        _ => Buffer::map_file(path, offset, n)
            .map_err(err)?
            .map(Samples::F32),
    })
}

/// An uncompressed file must hold `offset + bytes` bytes; returns what it holds beyond them.
fn check_length(path: &Path, offset: u64, bytes: u64) -> Result<Surplus> {
    let len = regular_metadata(path)?.len();
    let found = len.saturating_sub(offset);
    if found < bytes {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected: bytes,
                found,
            },
        ));
    }
    Ok(match found - bytes {
        0 => Surplus::None,
        n => Surplus::Bytes(n),
    })
}

/// Reads `bytes` bytes at `offset` of an uncompressed file (its length already checked).
fn read_plain(path: &Path, offset: u64, bytes: u64) -> Result<Vec<u8>> {
    let mut f = open_regular(path)?;
    f.seek(SeekFrom::Start(offset))
        .map_err(|e| io_error(path, e))?;
    read_exact_checked(path, std::io::BufReader::new(f), bytes)
}

/// Reads the voxels of `span` from a gzip stream, then probes one more byte to tell whether
/// the stream holds more than the dims declare (a stream that fails there is noted).
fn read_gz(path: &Path, span: Span, notes: &mut Vec<String>) -> Result<(Vec<u8>, Surplus)> {
    let mut stream = open_maybe_gz(path)?;
    let offset = span.offset;
    let skipped = std::io::copy(&mut (&mut stream).take(offset), &mut std::io::sink())
        .map_err(|e| ReadError::new(path, e))?;
    if skipped < offset {
        return Err(header_err(
            path,
            format!("vox_offset {offset} is past the end of the data ({skipped} bytes)"),
        ));
    }
    let data = read_exact_checked(path, &mut stream, span.bytes)?;
    let surplus = match stream.read(&mut [0u8; 1]) {
        Ok(0) => Surplus::None,
        Ok(_) => Surplus::Some,
        Err(e) => {
            notes.push(format!(
                "the gzip stream after the voxel data is damaged: {e}"
            ));
            Surplus::None
        }
    };
    Ok((data, surplus))
}

/// Spacing from `|pixdim[1..=3]|`; zero or non-finite entries become 1 (noted for the axes the
/// image has).
fn spacing(hdr: &Header, notes: &mut Vec<String>) -> [f64; 3] {
    let mut out = [1.0; 3];
    for (axis, (&p, o)) in hdr.pixdim.iter().zip(out.iter_mut()).enumerate() {
        let v = p.abs();
        if v.is_finite() && v > 0.0 {
            *o = v;
        } else if hdr.dims[axis] > 1 {
            notes.push(format!(
                "pixdim[{}] is {}; a spacing of 1 was used on that axis",
                axis + 1,
                show(p)
            ));
        }
    }
    out
}
