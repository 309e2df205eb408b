//! The fixed-layout 348-byte NIfTI-1 header: byte order, dims, datatype, scaling, geometry.
use std::path::Path;

use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::util::header_err;

/// Size of a NIfTI-1 header; `sizeof_hdr` must hold it (in the file's byte order).
pub(super) const HEADER_BYTES: usize = 348;
/// Where the voxels of a single-file `.nii` start at the earliest (header + 4 extension bytes).
pub(super) const MIN_NII_OFFSET: u64 = 352;

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

/// The header fields Volux uses.
#[derive(Clone, Debug)]
pub(super) struct Header {
    /// Little-endian file (from the `sizeof_hdr` check).
    pub le: bool,
    /// `dim[0]`, the number of dimensions (1 to 7).
    pub dim0: i16,
    /// `dim[1..=3]` folded to three dims (`dim[0]` 2 gives z = 1).
    pub dims: [i64; 3],
    pub dtype: Dtype,
    /// The first `dim[i]` past `dim[0]` that is above 1, as `(i, dim[i])`: the data may hold
    /// more than the dims declare (a time series written with `dim[0]` 3, say).
    pub unused_dim: Option<(usize, i16)>,
    /// `pixdim[1..=3]`.
    pub pixdim: [f32; 3],
    pub vox_offset: f32,
    pub scl_slope: f32,
    pub scl_inter: f32,
    pub qform_code: i16,
    pub sform_code: i16,
    pub qoffset: [f32; 3],
    /// `quatern_b`, `quatern_c`, `quatern_d`.
    pub quatern: [f32; 3],
    /// `pixdim[0]`, the qform's `qfac` (-1: the third axis is reflected).
    pub qfac: f32,
    /// `srow_x`, `srow_y`, `srow_z`.
    pub srow: [[f32; 4]; 3],
    /// `n+1` (single file) rather than `ni1` (`.hdr` + `.img`).
    pub single_file: bool,
}

/// Little/big-endian field access on the raw header bytes (all offsets are in range because the
/// slice is exactly [`HEADER_BYTES`] long and the offsets are constants below it).
struct Fields<'a> {
    b: &'a [u8; HEADER_BYTES],
    le: bool,
}

impl Fields<'_> {
    fn bytes<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut out = [0u8; N];
        out.copy_from_slice(&self.b[at..at + N]);
        out
    }
    fn i16(&self, at: usize) -> i16 {
        let b = self.bytes::<2>(at);
        if self.le {
            i16::from_le_bytes(b)
        } else {
            i16::from_be_bytes(b)
        }
    }
    fn f32(&self, at: usize) -> f32 {
        let b = self.bytes::<4>(at);
        if self.le {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    }
    fn f32s<const N: usize>(&self, at: usize) -> [f32; N] {
        std::array::from_fn(|i| self.f32(at + 4 * i))
    }
}

/// Parses the 348 header bytes of `path`.
pub(super) fn parse(path: &Path, raw: &[u8]) -> Result<Header> {
    let b: &[u8; HEADER_BYTES] = raw
        .get(..HEADER_BYTES)
        .and_then(|s| s.try_into().ok())
        .ok_or_else(|| header_err(path, "the NIfTI-1 header is shorter than 348 bytes"))?;
    let le = byte_order(path, b)?;
    let f = Fields { b, le };
    let single_file = check_magic(path, &f.bytes::<4>(344))?;
    let dim: [i16; 8] = std::array::from_fn(|i| f.i16(40 + 2 * i));
    let dims = fold_dims(path, &dim)?;
    let dtype = datatype(path, f.i16(70))?;
    check_bitpix(path, dtype, f.i16(70), f.i16(72))?;
    let pix: [f32; 8] = f.f32s(76);
    Ok(Header {
        le,
        dim0: dim[0],
        dims,
        dtype,
        unused_dim: unused_dim(&dim),
        pixdim: [pix[1], pix[2], pix[3]],
        vox_offset: f.f32(108),
        scl_slope: f.f32(112),
        scl_inter: f.f32(116),
        qform_code: f.i16(252),
        sform_code: f.i16(254),
        qoffset: f.f32s(268),
        quatern: f.f32s(256),
        qfac: pix[0],
        srow: [f.f32s(280), f.f32s(296), f.f32s(312)],
        single_file,
    })
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
fn unused_dim(dim: &[i16; 8]) -> Option<(usize, i16)> {
    let n = usize::try_from(dim[0]).ok()?;
    (n + 1..8).map(|i| (i, dim[i])).find(|&(_, d)| d > 1)
}

/// The byte order: `sizeof_hdr` is 348 in the file's order.
fn byte_order(path: &Path, b: &[u8; HEADER_BYTES]) -> Result<bool> {
    let raw = [b[0], b[1], b[2], b[3]];
    match (i32::from_le_bytes(raw), i32::from_be_bytes(raw)) {
        (348, _) => Ok(true),
        (_, 348) => Ok(false),
        (540, _) | (_, 540) => Err(ReadError::new(
            path,
            ErrorKind::Unsupported("NIfTI-2 (sizeof_hdr 540); Volux reads NIfTI-1".into()),
        )),
        (v, _) => Err(header_err(
            path,
            format!("sizeof_hdr is {v}, expected 348: not a NIfTI-1 file"),
        )),
    }
}

/// Checks the magic string; returns whether the data is in the same file (`n+1`).
fn check_magic(path: &Path, magic: &[u8; 4]) -> Result<bool> {
    match magic {
        b"n+1\0" => Ok(true),
        b"ni1\0" => Ok(false),
        _ => Err(ReadError::new(
            path,
            ErrorKind::Unsupported(format!(
                "magic {:?} is neither \"n+1\" nor \"ni1\" (ANALYZE 7.5 files are not read)",
                String::from_utf8_lossy(magic).trim_end_matches('\0')
            )),
        )),
    }
}

/// Folds `dim[0..8]` to x, y, z: `dim[0]` 2 gives z = 1, 3 is a volume, 4 to 7 are accepted
/// when every extra dimension is 1.
fn fold_dims(path: &Path, dim: &[i16; 8]) -> Result<[i64; 3]> {
    let n = dim[0];
    if !(1..=7).contains(&n) {
        return Err(header_err(
            path,
            format!("dim[0] is {n}, expected 1 to 7 dimensions"),
        ));
    }
    let d = |i: usize| i64::from(dim[i]);
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
