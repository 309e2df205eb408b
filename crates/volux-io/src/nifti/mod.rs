//! NIfTI-1 images: single-file `.nii` / `.nii.gz` (magic `n+1`) and `.hdr` + `.img` pairs
//! (magic `ni1`, the `.img` optionally gzipped), following the NIfTI-1 specification
//! (<https://nifti.nimh.nih.gov/nifti-1>, `nifti1.h`).
//!
//! The 348-byte header is parsed here (it is fixed-layout; the byte order is the one in which
//! `sizeof_hdr` reads 348). The `nifti` crate (0.18) was evaluated and rejected: it reads the
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
//! - Spacing is `|pixdim[1..=3]|` (zero or non-finite entries become 1, with a note); the origin
//!   is the sform translation when `sform_code > 0`, else the quaternion offset when
//!   `qform_code > 0`, else 0. Rotations, shears and flips in the sform / qform are not applied
//!   (the grid stays in voxel index order; noted).
//! - The data starts at `vox_offset` (at least 352 in a `.nii`). Sizes are checked before any
//!   allocation: a file shorter than the dims need is [`ErrorKind::Truncated`].
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use volux_core::{Buffer, Grid, Samples, ScalarType};

use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::util::{header_err, open_maybe_gz, read_exact_checked};

mod header;
mod values;

use header::{Header, HEADER_BYTES, MIN_NII_OFFSET};

/// Reads a NIfTI-1 `.nii`, `.nii.gz` or `.hdr` (with its `.img`) file.
pub fn read(path: &Path) -> Result<Grid> {
    let raw = read_exact_checked(path, open_maybe_gz(path)?, HEADER_BYTES as u64)?;
    let hdr = header::parse(path, &raw)?;
    let mut notes = Vec::new();
    let (dims, count) =
        volux_core::limits::checked_dims(hdr.dims).map_err(|e| ReadError::new(path, e))?;
    check_bitpix(&hdr, &mut notes);
    let (data_path, offset) = data_location(path, &hdr, &mut notes)?;
    let bytes = count
        .checked_mul(hdr.dtype.size() as u64)
        .ok_or_else(|| header_err(path, "the data size overflows"))?;
    let scaling = values::scaling(&hdr, &mut notes);
    let samples = match (scaling, mappable(&hdr)) {
        (None, Some(ty)) if !is_gzip(&data_path)? => map(&data_path, ty, offset, bytes, count)?,
        _ => None,
    };
    let samples = match samples {
        Some(s) => s,
        None => {
            let data = read_data(&data_path, offset, bytes)?;
            values::decode(&data_path, &hdr, &data, scaling, &mut notes)?
        }
    };
    let spacing = spacing(&hdr, &mut notes);
    let origin = origin(&hdr, &mut notes);
    let grid = Grid::new(dims, spacing, origin, samples).map_err(|e| ReadError::new(path, e))?;
    Ok(notes.into_iter().fold(grid, Grid::with_note))
}

/// Notes a `bitpix` that disagrees with the datatype (the datatype wins).
fn check_bitpix(hdr: &Header, notes: &mut Vec<String>) {
    let want = hdr.dtype.size() * 8;
    if i64::from(hdr.bitpix) != want as i64 {
        notes.push(format!(
            "bitpix {} disagrees with datatype {} ({want} bits); the datatype was used",
            hdr.bitpix,
            hdr.dtype.name()
        ));
    }
}

/// The file holding the voxels and the byte offset of the first one.
fn data_location(path: &Path, hdr: &Header, notes: &mut Vec<String>) -> Result<(PathBuf, u64)> {
    let v = hdr.vox_offset;
    if !v.is_finite() || v < 0.0 || v.fract() != 0.0 || v > 1e15 {
        return Err(header_err(
            path,
            format!("vox_offset {v} is not a non-negative whole number of bytes"),
        ));
    }
    let offset = v as u64;
    if !hdr.single_file {
        return Ok((image_file(path)?, offset));
    }
    if offset < MIN_NII_OFFSET {
        notes.push(format!(
            "vox_offset {offset} is below the minimum {MIN_NII_OFFSET} of a .nii file; {MIN_NII_OFFSET} was used"
        ));
        return Ok((path.to_path_buf(), MIN_NII_OFFSET));
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
        .find(|p| p.is_file())
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
    let mut f = std::fs::File::open(path).map_err(|e| ReadError::new(path, e))?;
    let n = f.read(&mut magic).map_err(|e| ReadError::new(path, e))?;
    Ok(n == 2 && magic == [0x1f, 0x8b])
}

/// The native scalar type when the data can be memory-mapped as it is.
fn mappable(hdr: &Header) -> Option<ScalarType> {
    if !hdr.le {
        return None;
    }
    values::native_type(hdr.dtype)
}

/// Memory-maps `count` values of `ty` at `offset`; `None` when mapping is not possible.
fn map(
    path: &Path,
    ty: ScalarType,
    offset: u64,
    bytes: u64,
    count: u64,
) -> Result<Option<Samples>> {
    check_length(path, offset, bytes)?;
    let n = usize::try_from(count).map_err(|_| header_err(path, "the voxel count is too large"))?;
    let err = |e| ReadError::new(path, e);
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

/// An uncompressed file must hold `offset + bytes` bytes.
fn check_length(path: &Path, offset: u64, bytes: u64) -> Result<()> {
    let len = std::fs::metadata(path)
        .map_err(|e| ReadError::new(path, e))?
        .len();
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
    Ok(())
}

/// Reads `bytes` bytes of voxel data starting at `offset` (of the decompressed stream).
fn read_data(path: &Path, offset: u64, bytes: u64) -> Result<Vec<u8>> {
    if !is_gzip(path)? {
        check_length(path, offset, bytes)?;
        let mut f = std::fs::File::open(path).map_err(|e| ReadError::new(path, e))?;
        f.seek(SeekFrom::Start(offset))
            .map_err(|e| ReadError::new(path, e))?;
        return read_exact_checked(path, std::io::BufReader::new(f), bytes);
    }
    let mut stream = open_maybe_gz(path)?;
    let skipped = std::io::copy(&mut (&mut stream).take(offset), &mut std::io::sink())
        .map_err(|e| ReadError::new(path, e))?;
    if skipped < offset {
        return Err(header_err(
            path,
            format!("vox_offset {offset} is past the end of the data ({skipped} bytes)"),
        ));
    }
    read_exact_checked(path, stream, bytes)
}

/// Spacing from `|pixdim[1..=3]|`; zero or non-finite entries become 1 (noted for the axes the
/// image has).
fn spacing(hdr: &Header, notes: &mut Vec<String>) -> [f64; 3] {
    let mut out = [1.0; 3];
    for (axis, (&p, o)) in hdr.pixdim.iter().zip(out.iter_mut()).enumerate() {
        let v = f64::from(p).abs();
        if v.is_finite() && v > 0.0 {
            *o = v;
        } else if hdr.dims[axis] > 1 {
            notes.push(format!(
                "pixdim[{}] is {p}; a spacing of 1 was used on that axis",
                axis + 1
            ));
        }
    }
    out
}

/// Origin from the sform translation, else the qform offset, else 0.
fn origin(hdr: &Header, notes: &mut Vec<String>) -> [f64; 3] {
    let (o, which) = if hdr.sform_code > 0 {
        note_sform_rotation(hdr, notes);
        (hdr.srow.map(|r| r[3]), "sform")
    } else if hdr.qform_code > 0 {
        (hdr.qoffset, "qform")
    } else {
        return [0.0; 3];
    };
    let o = o.map(f64::from);
    if o.iter().all(|v| v.is_finite()) {
        o
    } else {
        notes.push(format!(
            "the {which} origin {o:?} is not finite; (0, 0, 0) was used"
        ));
        [0.0; 3]
    }
}

/// Notes an sform whose 3x3 part is not diagonal with positive entries (not applied).
fn note_sform_rotation(hdr: &Header, notes: &mut Vec<String>) {
    let axis_aligned = hdr.srow.iter().enumerate().all(|(r, row)| {
        row.iter()
            .take(3)
            .enumerate()
            .all(|(c, &v)| if r == c { v > 0.0 } else { v == 0.0 })
    });
    if !axis_aligned {
        notes.push(
            "the sform has a rotation, shear or flip, which is not applied: the grid is in voxel \
             index order with spacing from pixdim"
                .into(),
        );
    }
}
