//! The NIfTI header, version 1 (348 bytes) or 2 (540 bytes), or the Analyze 7.5 header NIfTI-1
//! grew from (348 bytes, no magic): byte order, version, dims, datatype, scaling, geometry,
//! validated the same way for all three.
use std::path::Path;

use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::util::header_err;

use super::layout::{Fields, RawFields, NIFTI1_BYTES, NIFTI2_BYTES};

/// The most header bytes a reader needs (a NIfTI-2 header).
pub(super) const MAX_HEADER_BYTES: usize = NIFTI2_BYTES;

/// Element types of the voxel data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Dtype {
    U8,
    I8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    /// `DT_RGB24`: three uint8 per voxel, interleaved (R, G, B).
    Rgb24,
    /// `DT_RGBA32`: four uint8 per voxel, interleaved (R, G, B, A).
    Rgba32,
}

impl Dtype {
    /// Maps the NIfTI `datatype` code; `None` for codes Volux does not read.
    fn from_code(code: i16) -> Option<Self> {
        Some(match code {
            2 => Dtype::U8,
            4 => Dtype::I16,
            8 => Dtype::I32,
            16 => Dtype::F32,
            64 => Dtype::F64,
            256 => Dtype::I8,
            512 => Dtype::U16,
            768 => Dtype::U32,
            1024 => Dtype::I64,
            1280 => Dtype::U64,
            128 => Dtype::Rgb24,
            2304 => Dtype::Rgba32,
            _ => return None,
        })
    }
    /// Bytes per value.
    pub(super) fn size(self) -> usize {
        match self {
            Dtype::U8 | Dtype::I8 => 1,
            Dtype::I16 | Dtype::U16 => 2,
            Dtype::Rgb24 => 3,
            Dtype::I32 | Dtype::U32 | Dtype::F32 | Dtype::Rgba32 => 4,
            Dtype::F64 | Dtype::I64 | Dtype::U64 => 8,
        }
    }
    /// The colour channels per voxel of `DT_RGB24` (3) and `DT_RGBA32` (4); `None` otherwise.
    pub(super) fn channels(self) -> Option<usize> {
        match self {
            Dtype::Rgb24 => Some(3),
            Dtype::Rgba32 => Some(4),
            _ => None,
        }
    }
    /// The NIfTI name of the type.
    pub(super) fn name(self) -> &'static str {
        match self {
            Dtype::U8 => "uint8",
            Dtype::I8 => "int8",
            Dtype::I16 => "int16",
            Dtype::U16 => "uint16",
            Dtype::I32 => "int32",
            Dtype::U32 => "uint32",
            Dtype::I64 => "int64",
            Dtype::U64 => "uint64",
            Dtype::F32 => "float32",
            Dtype::F64 => "float64",
            Dtype::Rgb24 => "rgb24",
            Dtype::Rgba32 => "rgba32",
        }
    }
}

/// Names of the NIfTI datatype codes Volux does not read, for error messages.
fn unsupported_dtype_name(code: i16) -> &'static str {
    match code {
        1 => "binary",
        32 => "complex64",
        1536 => "float128",
        1792 => "complex128",
        2048 => "complex256",
        _ => "unknown",
    }
}

/// Which header the file has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Version {
    /// NIfTI-1, 348 bytes.
    One,
    /// NIfTI-2, 540 bytes.
    Two,
    /// Analyze 7.5 (and SPM's variant of it), 348 bytes without a NIfTI magic: always a
    /// `.hdr` + `.img` pair.
    Analyze,
}

/// Which kind of header the caller expects: the format detection has told NIfTI (a magic) from
/// Analyze (none) already, and a NIfTI file whose magic is damaged is not read as Analyze.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Flavour {
    /// NIfTI-1 or NIfTI-2.
    Nifti,
    /// Analyze 7.5.
    Analyze,
}

impl Version {
    /// The header's size in bytes.
    pub(super) fn header_bytes(self) -> usize {
        match self {
            Version::One | Version::Analyze => NIFTI1_BYTES,
            Version::Two => NIFTI2_BYTES,
        }
    }
    /// Where the voxels of a single-file `.nii` start at the earliest (header + 4 extension
    /// bytes).
    pub(super) fn min_nii_offset(self) -> u64 {
        self.header_bytes() as u64 + 4
    }
    /// `NIfTI-1` or `NIfTI-2`.
    pub(super) fn name(self) -> &'static str {
        match self {
            Version::One => "NIfTI-1",
            Version::Two => "NIfTI-2",
            Version::Analyze => "Analyze 7.5",
        }
    }
}

/// The header fields Volux uses, validated; NIfTI-1's fields are widened exactly to NIfTI-2's
/// types.
#[derive(Clone, Debug)]
pub(super) struct Header {
    pub version: Version,
    /// Little-endian file (from the `sizeof_hdr` check).
    pub le: bool,
    /// `dim[0]`, the number of dimensions (1 to 7).
    pub dim0: i64,
    /// `dim[1..=3]` folded to three dims (`dim[0]` 2 gives z = 1).
    pub dims: [i64; 3],
    /// `dim[4]` when `dim[0]` reaches 4, else 1: volumes along time (or another list).
    pub volumes: i64,
    /// `dim[5]` when `dim[0]` reaches 5, else 1: values per voxel (vectors, tensors).
    pub components: i64,
    pub dtype: Dtype,
    /// The first `dim[i]` past `dim[0]` that is above 1, as `(i, dim[i])`: the data may hold
    /// more than the dims declare (a time series written with `dim[0]` 3, say).
    pub unused_dim: Option<(usize, i64)>,
    /// `pixdim[1..=3]`.
    pub pixdim: [f64; 3],
    /// `pixdim[4]`: the step between volumes along `dim[4]` (the repetition time of fMRI).
    pub step: f64,
    /// `intent_code` (0 for Analyze, whose field at that place is unused).
    pub intent_code: i32,
    /// `xyzt_units`.
    pub xyzt_units: i32,
    /// `cal_max`, `cal_min`.
    pub cal: [f64; 2],
    /// Analyze: `glmax`, `glmin`.
    pub gl: [i32; 2],
    /// Analyze: SPM's `originator` (origin voxel, 1-based).
    pub originator: [i16; 5],
    pub vox_offset: f64,
    pub scl_slope: f64,
    pub scl_inter: f64,
    pub qform_code: i32,
    pub sform_code: i32,
    pub qoffset: [f64; 3],
    /// `quatern_b`, `quatern_c`, `quatern_d`.
    pub quatern: [f64; 3],
    /// `pixdim[0]`, the qform's `qfac` (-1: the third axis is reflected).
    pub qfac: f64,
    /// `srow_x`, `srow_y`, `srow_z`.
    pub srow: [[f64; 4]; 3],
    /// `n+1` / `n+2` (single file) rather than `ni1` / `ni2` (`.hdr` + `.img`).
    pub single_file: bool,
}

/// Parses the header at the start of `raw` (the first bytes of `path`, up to 540): NIfTI-1 or
/// NIfTI-2 by `sizeof_hdr`, or Analyze 7.5 when `flavour` says so.
pub(super) fn parse(path: &Path, raw: &[u8], flavour: Flavour) -> Result<Header> {
    let (le, version) = byte_order(path, raw)?;
    let version = match (flavour, version) {
        (Flavour::Analyze, Version::One) => Version::Analyze,
        (Flavour::Analyze, _) => {
            return Err(header_err(
                path,
                "sizeof_hdr is 540 (a NIfTI-2 header), not the 348 of an Analyze 7.5 header",
            ))
        }
        (Flavour::Nifti, v) => v,
    };
    let need = version.header_bytes();
    if raw.len() < need {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected: need as u64,
                found: raw.len() as u64,
            },
        ));
    }
    let f = Fields::new(raw, le);
    let r = match version {
        Version::One | Version::Analyze => f.nifti1(),
        Version::Two => f.nifti2(),
    };
    let single_file = check_magic(path, version, &r)?;
    let (dims, volumes, components) = fold_dims(path, &r.dim)?;
    let dtype = datatype(path, r.datatype)?;
    check_bitpix(path, dtype, r.datatype, r.bitpix)?;
    let analyze = version == Version::Analyze;
    Ok(Header {
        version,
        le,
        dim0: r.dim[0],
        dims,
        volumes,
        components,
        dtype,
        unused_dim: unused_dim(&r.dim),
        pixdim: [r.pixdim[1], r.pixdim[2], r.pixdim[3]],
        step: r.pixdim[4],
        intent_code: if analyze { 0 } else { r.intent_code },
        xyzt_units: if analyze { 0 } else { r.xyzt_units },
        cal: r.cal,
        gl: r.gl,
        originator: r.originator,
        vox_offset: r.vox_offset,
        scl_slope: r.scl_slope,
        scl_inter: r.scl_inter,
        qform_code: r.qform_code,
        sform_code: r.sform_code,
        qoffset: r.qoffset,
        quatern: r.quatern,
        qfac: r.pixdim[0],
        srow: r.srow,
        single_file,
    })
}

/// `v` as written: a value that a float32 holds exactly (every NIfTI-1 value) is shown as the
/// float32 it was, so notes say `0.1` rather than `0.10000000149011612`.
pub(super) fn show(v: f64) -> String {
    let single = v as f32;
    if f64::from(single) == v || v.is_nan() {
        single.to_string()
    } else {
        v.to_string()
    }
}

/// The datatype of `code`; [`ErrorKind::Unsupported`] naming the codes Volux does not read.
fn datatype(path: &Path, code: i16) -> Result<Dtype> {
    Dtype::from_code(code).ok_or_else(|| {
        ReadError::new(
            path,
            ErrorKind::Unsupported(format!(
                "NIfTI datatype code {code} ({}); Volux reads uint8, int8, int16, uint16, int32, \
                 uint32, int64, uint64, float32, float64, rgb24 and rgba32",
                unsupported_dtype_name(code)
            )),
        )
    })
}

/// `bitpix` must be the bits of one value of the datatype: a header that disagrees with itself
/// is refused rather than trusting either field.
fn check_bitpix(path: &Path, dtype: Dtype, code: i16, bitpix: i16) -> Result<()> {
    let want = dtype.size() * 8;
    if i64::from(bitpix) == want as i64 {
        return Ok(());
    }
    Err(header_err(
        path,
        format!(
            "bitpix {bitpix} disagrees with datatype {code} ({}, {want} bits per value)",
            dtype.name()
        ),
    ))
}

/// The first `dim[i]`, `i` past `dim[0]` (valid: 1 to 7), that is above 1.
fn unused_dim(dim: &[i64; 8]) -> Option<(usize, i64)> {
    let n = usize::try_from(dim[0]).ok()?;
    (n + 1..8).map(|i| (i, dim[i])).find(|&(_, d)| d > 1)
}

/// The byte order and version: `sizeof_hdr` is 348 (NIfTI-1) or 540 (NIfTI-2) in the file's
/// order.
fn byte_order(path: &Path, b: &[u8]) -> Result<(bool, Version)> {
    let Some(&[b0, b1, b2, b3]) = b.get(..4) else {
        return Err(ReadError::new(
            path,
            ErrorKind::Truncated {
                expected: NIFTI1_BYTES as u64,
                found: b.len() as u64,
            },
        ));
    };
    let raw = [b0, b1, b2, b3];
    let version = |v: i32| match v {
        348 => Some(Version::One),
        540 => Some(Version::Two),
        _ => None,
    };
    let (le, be) = (i32::from_le_bytes(raw), i32::from_be_bytes(raw));
    match (version(le), version(be)) {
        (Some(v), _) => Ok((true, v)),
        (None, Some(v)) => Ok((false, v)),
        (None, None) => {
            let short = b.len() < NIFTI1_BYTES;
            let kind = if short {
                ErrorKind::Truncated {
                    expected: NIFTI1_BYTES as u64,
                    found: b.len() as u64,
                }
            } else {
                ErrorKind::Header(format!(
                    "sizeof_hdr is {le}, expected 348 (NIfTI-1) or 540 (NIfTI-2): not a NIfTI file"
                ))
            };
            Err(ReadError::new(path, kind))
        }
    }
}

/// Checks the magic string against the version; returns whether the data is in the same file
/// (`n+1`, `n+2`).
fn check_magic(path: &Path, version: Version, r: &RawFields) -> Result<bool> {
    let single = match (version, &r.magic) {
        (Version::One, b"n+1\0") | (Version::Two, b"n+2\0") => true,
        (Version::One, b"ni1\0") | (Version::Two, b"ni2\0") => false,
        (Version::Analyze, b"n+1\0" | b"ni1\0") => {
            return Err(header_err(
                path,
                "the header has a NIfTI-1 magic: it is a NIfTI file, not Analyze 7.5",
            ))
        }
        (Version::Analyze, _) => false,
        (v, m) => {
            let want = match v {
                Version::Two => "\"n+2\" or \"ni2\"",
                _ => {
                    "\"n+1\" or \"ni1\" (an Analyze 7.5 header, without a magic, is read from \
                     a .hdr beside its .img)"
                }
            };
            return Err(ReadError::new(
                path,
                ErrorKind::Unsupported(format!(
                    "magic {:?} of a {} header is not {want}",
                    String::from_utf8_lossy(m).trim_end_matches('\0'),
                    v.name()
                )),
            ));
        }
    };
    if let Some(sig) = r.signature {
        if sig != *b"\r\n\x1a\n" {
            return Err(header_err(
                path,
                format!(
                    "the NIfTI-2 magic ends in {sig:02x?}, not 0d 0a 1a 0a: the file was altered \
                     (a text-mode transfer changes line ends)"
                ),
            ));
        }
    }
    Ok(single)
}

/// Folds `dim[0..8]` to x, y, z (`dim[0]` 2 gives z = 1) and the volumes along `dim[4]` and
/// `dim[5]` (1 when `dim[0]` stops before them); `dim[6]` and `dim[7]` must be 1.
fn fold_dims(path: &Path, dim: &[i64; 8]) -> Result<([i64; 3], i64, i64)> {
    let n = dim[0];
    if !(1..=7).contains(&n) {
        return Err(header_err(
            path,
            format!("dim[0] is {n}, expected 1 to 7 dimensions"),
        ));
    }
    let d = |i: usize| if (i as i64) <= n { dim[i] } else { 1 };
    match n {
        1 => Err(ReadError::new(
            path,
            ErrorKind::Unsupported("a 1-D NIfTI image (dim[0] = 1)".into()),
        )),
        2 => Ok(([d(1), d(2), 1], 1, 1)),
        _ => {
            if let Some(i) = (6..=n as usize).find(|&i| dim[i] != 1) {
                return Err(ReadError::new(
                    path,
                    ErrorKind::Unsupported(format!(
                        "a {n}-D NIfTI image with dims {:?}: Volux reads volumes along dim[4] \
                         (time) and dim[5] (components), and dim[{i}] is {}",
                        &dim[1..=n as usize],
                        dim[i]
                    )),
                ));
            }
            for i in 4..=5 {
                if d(i) < 1 {
                    return Err(header_err(
                        path,
                        format!("dim[{i}] is {}, expected at least 1", d(i)),
                    ));
                }
            }
            Ok(([d(1), d(2), d(3)], d(4), d(5)))
        }
    }
}
