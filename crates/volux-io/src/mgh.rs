//! FreeSurfer MGH (`.mgh`) and MGZ (`.mgz`, the same gzip-compressed) volumes, following
//! FreeSurfer's format page (<https://surfer.nmr.mgh.harvard.edu/fswiki/FsTutorial/MghFormat>)
//! and nibabel's `freesurfer/mghformat.py`, the reader the conformance test compares with.
//!
//! The header is 284 big-endian bytes: `version` (1), `width`, `height`, `depth`, `nframes`,
//! `type` (0 uchar, 1 int32, 3 float32, 4 int16, 10 uint16), `dof`, `goodRASFlag`, the voxel
//! sizes `delta[3]`, the direction cosines `Mdc` (three rows: the RAS direction of x, y and z)
//! and `Pxyz_c`, the RAS position of the volume's centre. The voxels follow, x fastest, one
//! frame after the other; after them an optional footer starts with the repetition time `TR`
//! (ms). The voxel-to-RAS affine is nibabel's `MGHHeader.get_affine`: columns `Mdc[j] *
//! delta[j]`, translation `Pxyz_c - Σ column_j * dim_j / 2` (the centre is voxel `dims / 2`);
//! a header whose `goodRASFlag` is 0 gets nibabel's default (`Mdc` rows (-1, 0, 0), (0, 0, 1),
//! (0, -1, 0), spacing 1, centre 0), with a note. RAS is turned into Volux's LPS. A vox2ras
//! whose axes are not orthogonal is refused (a grid cannot hold it).
//!
//! Frames are read one at a time: `timepoint` chooses the frame, recorded as a time axis with
//! its TR. int32 is converted to float32 with a note. No crate reads MGH; the header is a fixed
//! 284-byte struct, parsed here.
use std::io::Read;
use std::path::Path;

use glam::{DMat3, DVec3};
use volux_core::orientation::{ras_to_lps, split_scaled_axes};
use volux_core::volume_axes::{choose, AxisKind, ExtraAxis};
use volux_core::Grid;

use crate::dataset::VolumeChoice;
use crate::error::{ErrorKind, ReadError, Result};
use crate::raw::{self, ElemType};
use crate::util::{header_err, io_error, open_gz_input, read_exact_checked};

/// Bytes before the voxels.
const HEADER_BYTES: u64 = 284;

/// The header fields Volux uses.
#[derive(Clone, Debug)]
struct Header {
    dims: [i64; 3],
    frames: i64,
    ty: ElemType,
    good_ras: bool,
    delta: [f64; 3],
    /// Rows: the RAS directions of x, y, z.
    mdc: [[f64; 3]; 3],
    c_ras: [f64; 3],
}

fn be_i32(b: &[u8], at: usize) -> i32 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&b[at..at + 4]);
    i32::from_be_bytes(a)
}

fn be_f32(b: &[u8], at: usize) -> f64 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&b[at..at + 4]);
    f64::from(f32::from_be_bytes(a))
}

/// Parses the 284 header bytes `b`.
fn parse(path: &Path, b: &[u8]) -> Result<Header> {
    let version = be_i32(b, 0);
    if version != 1 {
        return Err(header_err(
            path,
            format!("MGH version {version}, expected 1 (not an MGH file?)"),
        ));
    }
    let d = |i: usize| i64::from(be_i32(b, 4 + 4 * i));
    let code = be_i32(b, 20);
    let ty = match code {
        0 => ElemType::U8,
        1 => ElemType::I32,
        3 => ElemType::F32,
        4 => ElemType::I16,
        10 => ElemType::U16,
        _ => {
            return Err(ReadError::new(
                path,
                ErrorKind::Unsupported(format!(
                    "MGH type {code}; Volux reads 0 (uchar), 1 (int), 3 (float), 4 (short) and \
                     10 (ushort)"
                )),
            ))
        }
    };
    let frames = d(3);
    if frames < 1 {
        return Err(header_err(
            path,
            format!("nframes is {frames}, expected at least 1"),
        ));
    }
    let good_ras = i16::from_be_bytes([b[28], b[29]]) != 0;
    let f = |at: usize| be_f32(b, at);
    Ok(Header {
        dims: [d(0), d(1), d(2)],
        frames,
        ty,
        good_ras,
        delta: [f(30), f(34), f(38)],
        mdc: std::array::from_fn(|r| std::array::from_fn(|c| f(42 + 12 * r + 4 * c))),
        c_ras: [f(78), f(82), f(86)],
    })
}

/// Reads an MGH or MGZ file: the frame `choice.timepoint` when it holds several.
pub fn read(path: &Path, choice: VolumeChoice) -> Result<Grid> {
    let input = open_gz_input(path)?;
    let (gzip, file_len) = (input.gzip, input.file_len);
    let mut reader = input.reader;
    let head = read_exact_checked(path, &mut reader, HEADER_BYTES)?;
    let mut hdr = parse(path, &head)?;
    let mut notes = Vec::new();
    if !hdr.good_ras {
        notes.push(
            "goodRASFlag is 0: the default orientation (coronal), spacing 1 and centre 0 were \
             used, as nibabel does"
                .to_string(),
        );
        hdr.delta = [1.0; 3];
        hdr.mdc = [[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]];
        hdr.c_ras = [0.0; 3];
    }
    let (dims, count) =
        volux_core::limits::checked_dims(hdr.dims).map_err(|e| ReadError::new(path, e))?;
    let frames = usize::try_from(hdr.frames).map_err(|_| header_err(path, "nframes too large"))?;
    let t = choose("timepoint", choice.timepoint, frames).map_err(|e| ReadError::new(path, e))?;
    let (spacing, origin, direction) = placement(path, &hdr, dims)?;
    let bytes = count
        .checked_mul(hdr.ty.size() as u64)
        .ok_or_else(|| header_err(path, "the data size overflows"))?;
    let total = bytes
        .checked_mul(hdr.frames as u64)
        .ok_or_else(|| header_err(path, "the data size overflows"))?;
    let reach = HEADER_BYTES.saturating_add(total);
    if gzip {
        let max = crate::util::max_inflated(file_len);
        if reach > max {
            return Err(ReadError::new(
                path,
                ErrorKind::Undeliverable {
                    declared: reach,
                    available: file_len,
                    max,
                    how: "deflate expands at most 1032:1",
                },
            ));
        }
    } else if file_len < reach {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected: total,
                found: file_len.saturating_sub(HEADER_BYTES),
            },
        ));
    }
    let before = bytes * t as u64;
    skip(path, &mut reader, before, total)?;
    let data = read_exact_checked(path, &mut reader, bytes)?;
    let decoded = raw::decode(path, hdr.ty, &data, false)?;
    drop(data);
    let mut grid = raw::make_grid(path, dims, spacing, origin, decoded, Vec::new())?
        .with_direction(direction)
        .map_err(|e| ReadError::new(path, e))?;
    if frames > 1 {
        let after = total - before - bytes;
        skip(path, &mut reader, after, total)?;
        let tr = read_tr(&mut reader);
        let axis = ExtraAxis::new(AxisKind::Time, frames, Some(t));
        grid = grid.with_extra_axis(match tr {
            Some(tr) if tr > 0.0 => axis.with_meaning(format!("TR {tr} ms")),
            _ => axis,
        });
    }
    Ok(notes.into_iter().fold(grid, Grid::with_note))
}

/// Skips `n` bytes of the voxel data (`total` bytes in all, for the error).
fn skip(path: &Path, reader: &mut impl Read, n: u64, total: u64) -> Result<()> {
    let got =
        std::io::copy(&mut reader.take(n), &mut std::io::sink()).map_err(|e| io_error(path, e))?;
    if got < n {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected: total,
                found: got,
            },
        ));
    }
    Ok(())
}

/// The footer's TR (ms), when the file has a footer.
fn read_tr(reader: &mut impl Read) -> Option<f64> {
    let mut b = [0u8; 4];
    reader.read_exact(&mut b).ok()?;
    let tr = f32::from_be_bytes(b);
    tr.is_finite().then_some(f64::from(tr))
}

/// Spacing, origin and direction in LPS from nibabel's vox2ras (see the module docs). A
/// vox2ras whose axes are not orthogonal (or zero, or not finite) is refused: a Volux grid
/// cannot hold it, and placing the voxels elsewhere would misplace them without a word.
fn placement(path: &Path, hdr: &Header, dims: [usize; 3]) -> Result<([f64; 3], [f64; 3], DMat3)> {
    let cols: [DVec3; 3] = std::array::from_fn(|j| DVec3::from(hdr.mdc[j]) * hdr.delta[j]);
    let centre = cols
        .iter()
        .zip(dims)
        .fold(DVec3::ZERO, |acc, (c, d)| acc + *c * (d as f64) / 2.0);
    let origin = ras_to_lps(DVec3::from(hdr.c_ras) - centre);
    let m = DMat3::from_cols(
        ras_to_lps(cols[0]),
        ras_to_lps(cols[1]),
        ras_to_lps(cols[2]),
    );
    let unusable = |why: String| {
        ReadError::new(
            path,
            ErrorKind::Unsupported(format!(
                "an MGH vox2ras (Mdc rows times delta) that is not an orthogonal grid: {why}"
            )),
        )
    };
    let (spacing, direction) = split_scaled_axes(m).map_err(|e| unusable(e.to_string()))?;
    if !origin.is_finite() {
        return Err(unusable(format!("centre {origin} is not finite")));
    }
    Ok((spacing, origin.to_array(), direction))
}
