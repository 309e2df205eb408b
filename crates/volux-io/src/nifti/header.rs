//! The NIfTI header, version 1 (348 bytes) or 2 (540 bytes): byte order, version, dims,
//! datatype, scaling, geometry, validated the same way for both.
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
    F32,
    F64,
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
            _ => return None,
        })
    }
    /// Bytes per value.
    pub(super) fn size(self) -> usize {
        match self {
            Dtype::U8 | Dtype::I8 => 1,
            Dtype::I16 | Dtype::U16 => 2,
            Dtype::I32 | Dtype::U32 | Dtype::F32 => 4,
            Dtype::F64 => 8,
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
            Dtype::F32 => "float32",
            Dtype::F64 => "float64",
        }
    }
}

/// Names of the NIfTI datatype codes Volux does not read, for error messages.
fn unsupported_dtype_name(code: i16) -> &'static str {
    match code {
        1 => "binary",
        32 => "complex64",
        128 => "rgb24",
        1024 => "int64",
        1280 => "uint64",
        1536 => "float128",
        1792 => "complex128",
        2048 => "complex256",
        2304 => "rgba32",
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
}

impl Version {
    /// The header's size in bytes.
    pub(super) fn header_bytes(self) -> usize {
        match self {
            Version::One => NIFTI1_BYTES,
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
    pub dtype: Dtype,
    /// The first `dim[i]` past `dim[0]` that is above 1, as `(i, dim[i])`: the data may hold
    /// more than the dims declare (a time series written with `dim[0]` 3, say).
    pub unused_dim: Option<(usize, i64)>,
    /// `pixdim[1..=3]`.
    pub pixdim: [f64; 3],
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
/// NIfTI-2 by `sizeof_hdr`.
pub(super) fn parse(path: &Path, raw: &[u8]) -> Result<Header> {
    let (le, version) = byte_order(path, raw)?;
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
        Version::One => f.nifti1(),
        Version::Two => f.nifti2(),
    };
    let single_file = check_magic(path, version, &r)?;
    let dims = fold_dims(path, &r.dim)?;
    let dtype = datatype(path, r.datatype)?;
    check_bitpix(path, dtype, r.datatype, r.bitpix)?;
    Ok(Header {
        version,
        le,
        dim0: r.dim[0],
        dims,
        dtype,
        unused_dim: unused_dim(&r.dim),
        pixdim: [r.pixdim[1], r.pixdim[2], r.pixdim[3]],
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
                 uint32, float32 and float64",
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
        (v, m) => {
            let want = match v {
                Version::One => "\"n+1\" or \"ni1\" (ANALYZE 7.5 files are not read)",
                Version::Two => "\"n+2\" or \"ni2\"",
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

/// Folds `dim[0..8]` to x, y, z: `dim[0]` 2 gives z = 1, 3 is a volume, 4 to 7 are accepted
/// when every extra dimension is 1.
fn fold_dims(path: &Path, dim: &[i64; 8]) -> Result<[i64; 3]> {
    let n = dim[0];
    if !(1..=7).contains(&n) {
        return Err(header_err(
            path,
            format!("dim[0] is {n}, expected 1 to 7 dimensions"),
        ));
    }
    let d = |i: usize| dim[i];
    match n {
        1 => Err(ReadError::new(
            path,
            ErrorKind::Unsupported("a 1-D NIfTI image (dim[0] = 1)".into()),
        )),
        2 => Ok([d(1), d(2), 1]),
        3 => Ok([d(1), d(2), d(3)]),
        _ => {
            let extra = &dim[4..=n as usize];
            if extra.iter().all(|&v| v == 1) {
                Ok([d(1), d(2), d(3)])
            } else {
                Err(ReadError::new(
                    path,
                    ErrorKind::Unsupported(format!(
                        "a {n}-D NIfTI image with dims {:?}: Volux reads one 3-D volume (dims 4 \
                         and up must be 1)",
                        &dim[1..=n as usize]
                    )),
                ))
            }
        }
    }
}
