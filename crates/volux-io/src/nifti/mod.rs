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
//! - Dims: `dim[0]` 3, 2 (z = 1), or 4 to 7. A file with several volumes along `dim[4]` (a time
//!   series: fMRI, ASL, perfusion; DWI) or `dim[5]` (vector and tensor components) is read one
//!   3-D volume at a time: [`VolumeChoice::timepoint`] along `dim[4]`, [`VolumeChoice::component`]
//!   along `dim[5]` (default 0), the volume `(t, c)` lying at `c * dim[4] + t` volumes from
//!   `vox_offset` (`volumes.rs`; the grid records the axes and what the header says they mean).
//!   `dim[6]` or `dim[7]` above 1 is [`ErrorKind::Unsupported`]; 1-D too; 0 or > 7 is a header
//!   error.
//! - Types: uint8, int16, uint16 and float32 are kept natively (uncompressed little-endian data
//!   is memory-mapped, the chosen volume at its own offset); int8, int32, uint32, int64,
//!   uint64 and float64 are converted to float32 with a note. RGB24 and RGBA32 are colour
//!   ([`volux_core::color::Rgb`]; alpha dropped with a note), or the one channel `component`
//!   asks for.
//! - Analyze 7.5 pairs ([`read_analyze`]): the same 348-byte layout without a magic; SPM's
//!   scaling and nibabel's placement (`affine.rs`, `values.rs`).
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

use crate::dataset::VolumeChoice;
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
mod volumes;

use header::{show, Flavour, Header, Version, MAX_HEADER_BYTES};

/// Reads a NIfTI-1 or NIfTI-2 `.nii`, `.nii.gz`, or `.hdr` + `.img` pair (either file of the
/// pair may be named): the volume of `choice` when the file holds several.
pub fn read(path: &Path, choice: VolumeChoice) -> Result<Grid> {
    read_flavour(path, choice, Flavour::Nifti)
}

/// Reads an Analyze 7.5 (or SPM) `.hdr` + `.img` pair (either file may be named), placed as
/// nibabel places it (`affine.rs`): x flipped, origin from SPM's `originator` or the centre.
pub fn read_analyze(path: &Path, choice: VolumeChoice) -> Result<Grid> {
    read_flavour(path, choice, Flavour::Analyze)
}

fn read_flavour(path: &Path, choice: VolumeChoice, flavour: Flavour) -> Result<Grid> {
    let header_path = header_file(path);
    let mut raw = Vec::with_capacity(MAX_HEADER_BYTES);
    open_maybe_gz(&header_path)?
        .take(MAX_HEADER_BYTES as u64)
        .read_to_end(&mut raw)
        .map_err(|e| io_error(&header_path, e))?;
    let hdr = header::parse(&header_path, &raw, flavour)?;
    let mut notes = Vec::new();
    if hdr.version == Version::Two {
        notes.push("NIfTI-2 header (540 bytes, 64-bit dims)".to_string());
    }
    let (dims, count) =
        volux_core::limits::checked_dims(hdr.dims).map_err(|e| ReadError::new(path, e))?;
    let (data_path, offset) = data_location(&header_path, &hdr, &mut notes)?;
    let pick = volumes::pick(&header_path, &hdr, choice, &mut notes)?;
    let bytes = count
        .checked_mul(hdr.dtype.size() as u64)
        .ok_or_else(|| header_err(path, "the data size overflows"))?;
    let total = bytes
        .checked_mul(pick.count)
        .filter(|&t| t < u64::MAX - offset)
        .ok_or_else(|| header_err(path, "the data size overflows"))?;
    let span = Span {
        start: offset,
        offset: offset + pick.index * bytes,
        bytes,
        count,
        end: offset + total,
        last: pick.index + 1 == pick.count,
    };
    let scaling = match (hdr.dtype.channels(), hdr.version) {
        (Some(_), _) => None,
        (None, Version::Analyze) => values::analyze_scaling(&hdr, &mut notes),
        (None, _) => values::scaling(&hdr, &mut notes),
    };
    let (voxels, surplus) = load_voxels(&data_path, &hdr, span, scaling, pick.channel, &mut notes)?;
    notes.extend(surplus_note(&hdr, dims, total, surplus));
    let spacing = spacing(&hdr, &mut notes);
    let place = match hdr.version {
        Version::Analyze => affine::analyze_placement(&hdr, spacing, &mut notes),
        _ => affine::placement(&hdr, spacing, &mut notes),
    };
    let grid = match voxels {
        Voxels::Scalar(samples) => Grid::new(dims, place.spacing, place.origin, samples),
        Voxels::Colour(rgb) => {
            if hdr.dtype.channels() == Some(4) {
                notes.push("rgba32: the alpha channel was dropped (component 3 reads it)".into());
            }
            Grid::from_rgb(dims, place.spacing, place.origin, rgb)
        }
    }
    .and_then(|g| g.with_direction(place.direction))
    .map_err(|e| ReadError::new(path, e))?;
    let grid = pick.axes.into_iter().fold(grid, Grid::with_extra_axis);
    Ok(notes.into_iter().fold(grid, Grid::with_note))
}

/// The header of a pair: `x.hdr` (or `x.hdr.gz`) for `x.img` / `x.img.gz` when it exists;
/// any other path is its own header.
fn header_file(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    let Some(stem_len) = [".img.gz", ".img"]
        .iter()
        .find(|s| lower.ends_with(*s))
        .map(|s| name.len() - s.len())
    else {
        return path.to_path_buf();
    };
    let stem = name.get(..stem_len).unwrap_or(&name);
    [format!("{stem}.hdr"), format!("{stem}.hdr.gz")]
        .iter()
        .map(|c| path.with_file_name(c))
        .find(|p| p.exists())
        .unwrap_or_else(|| path.to_path_buf())
}

/// Where the chosen volume lies in the (decompressed) data file: `bytes` bytes holding `count`
/// values from byte `offset`; the data of all volumes ends at `end`.
#[derive(Clone, Copy, Debug)]
struct Span {
    /// Where the first volume starts.
    start: u64,
    offset: u64,
    bytes: u64,
    count: u64,
    end: u64,
    /// Whether the chosen volume is the file's last (a gzip stream is probed for more data
    /// only then, so that reading the first volume of a long series inflates only it).
    last: bool,
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

/// The voxels read: scalar samples, or colour.
enum Voxels {
    Scalar(Samples),
    Colour(volux_core::color::Rgb),
}

/// The voxels of `span` (memory-mapped when possible) and what the file holds after the data.
fn load_voxels(
    path: &Path,
    hdr: &Header,
    span: Span,
    scaling: Option<(f64, f64)>,
    channel: Option<usize>,
    notes: &mut Vec<String>,
) -> Result<(Voxels, Surplus)> {
    let gzip = is_gzip(path)?;
    if let Some(k) = hdr.dtype.channels() {
        let (data, surplus) = read_bytes(path, gzip, span, notes)?;
        let voxels = match values::decode_colour(path, &data, k, channel)? {
            values::Colour::Rgb(rgb) => Voxels::Colour(rgb),
            values::Colour::Channel(s) => Voxels::Scalar(s),
        };
        return Ok((voxels, surplus));
    }
    if !gzip {
        let surplus = check_length(path, span)?;
        if let (None, Some(ty)) = (scaling, mappable(hdr)) {
            if let Some(samples) = map(path, ty, span)? {
                return Ok((Voxels::Scalar(samples), surplus));
            }
        }
    }
    let (data, surplus) = read_bytes(path, gzip, span, notes)?;
    let samples = values::decode(path, hdr, &data, scaling, notes)?;
    Ok((Voxels::Scalar(samples), surplus))
}

/// The bytes of `span`, from a gzip stream or a plain file (whose length is checked first).
fn read_bytes(
    path: &Path,
    gzip: bool,
    span: Span,
    notes: &mut Vec<String>,
) -> Result<(Vec<u8>, Surplus)> {
    if gzip {
        return read_gz(path, span, notes);
    }
    let surplus = check_length(path, span)?;
    Ok((read_plain(path, span.offset, span.bytes)?, surplus))
}

/// A note when the data holds more than the dims declare (the extra is not read).
fn surplus_note(hdr: &Header, dims: [usize; 3], total: u64, surplus: Surplus) -> Option<String> {
    let [x, y, z] = dims;
    let mut shape = format!("{x}x{y}x{z}");
    for n in [hdr.volumes, hdr.components] {
        if n > 1 || hdr.components > 1 {
            shape.push_str(&format!("x{n}"));
        }
    }
    let declared = format!("dims {shape} of {} declare", hdr.dtype.name());
    let hint = match hdr.unused_dim {
        Some((i, d)) => format!(" (dim[0] is {} but dim[{i}] is {d})", hdr.dim0),
        None => String::new(),
    };
    match surplus {
        Surplus::None => None,
        Surplus::Bytes(n) => Some(format!(
            "the data holds {n} bytes more than the {total} that {declared}{hint}; they were ignored"
        )),
        Surplus::Some => Some(format!(
            "the data continues past the {total} bytes that {declared}{hint}; the rest was ignored"
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
        return Ok((image_file(path, hdr)?, offset));
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
fn image_file(path: &Path, hdr: &Header) -> Result<PathBuf> {
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
                    "{} puts the voxels in a separate file, but neither {} nor {} exists",
                    pair_name(hdr),
                    candidates[0],
                    candidates[1]
                )),
            )
        })
}

/// What kind of header pair `hdr` is, for messages.
fn pair_name(hdr: &Header) -> &'static str {
    match hdr.version {
        Version::One => "this NIfTI-1 header (magic \"ni1\")",
        Version::Two => "this NIfTI-2 header (magic \"ni2\")",
        Version::Analyze => "an Analyze 7.5 header",
    }
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

/// An uncompressed file must hold the data of every volume (to `span.end`); returns what it
/// holds beyond.
fn check_length(path: &Path, span: Span) -> Result<Surplus> {
    let len = regular_metadata(path)?.len();
    if len < span.end {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected: span.end - span.start,
                found: len.saturating_sub(span.start),
            },
        ));
    }
    Ok(match len - span.end {
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

/// Reads the voxels of `span` from a gzip stream (refused first when the compressed file
/// cannot inflate to so many bytes), then, for the last volume, probes one more byte to tell
/// whether the stream holds more than the dims declare (a stream that fails there is noted).
fn read_gz(path: &Path, span: Span, notes: &mut Vec<String>) -> Result<(Vec<u8>, Surplus)> {
    let compressed = regular_metadata(path)?.len();
    let reach = span.offset.saturating_add(span.bytes);
    let max = crate::util::max_inflated(compressed);
    if reach > max {
        return Err(ReadError::new(
            path,
            ErrorKind::Undeliverable {
                declared: reach,
                available: compressed,
                max,
                how: "deflate expands at most 1032:1",
            },
        ));
    }
    let mut stream = open_maybe_gz(path)?;
    let mut skip = |n: u64| {
        std::io::copy(&mut (&mut stream).take(n), &mut std::io::sink())
            .map_err(|e| ReadError::new(path, e))
    };
    let start = span.start;
    let skipped = skip(start)?;
    if skipped < start {
        return Err(header_err(
            path,
            format!("vox_offset {start} is past the end of the data ({skipped} bytes)"),
        ));
    }
    let before = span.offset - start;
    let skipped = skip(before)?;
    if skipped < before {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected: span.end - start,
                found: skipped,
            },
        ));
    }
    let data = read_exact_checked(path, &mut stream, span.bytes)?;
    if !span.last {
        return Ok((data, Surplus::None));
    }
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
