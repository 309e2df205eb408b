//! Decoding NIfTI voxel bytes: native types as they are, others (or scaled data) to float32.
use std::path::Path;

use rayon::prelude::*;
use volux_core::{Buffer, Samples, ScalarType};

use super::header::{show, Dtype, Header};
use crate::error::ReadError;
use crate::error::Result;

/// The Volux scalar type a NIfTI datatype is kept as, when it is kept natively.
pub(super) fn native_type(dtype: Dtype) -> Option<ScalarType> {
    match dtype {
        Dtype::U8 => Some(ScalarType::U8),
        Dtype::I16 => Some(ScalarType::I16),
        Dtype::U16 => Some(ScalarType::U16),
        Dtype::F32 => Some(ScalarType::F32),
        _ => None,
    }
}

/// The `(slope, intercept)` to apply, if any: `scl_slope` non-zero and not (1, 0). A non-finite
/// slope or intercept is ignored with a note.
pub(super) fn scaling(hdr: &Header, notes: &mut Vec<String>) -> Option<(f64, f64)> {
    let (slope, inter) = (hdr.scl_slope, hdr.scl_inter);
    if slope == 0.0 || (slope == 1.0 && inter == 0.0) {
        return None;
    }
    if !slope.is_finite() || !inter.is_finite() {
        notes.push(format!(
            "scl_slope {} / scl_inter {} are not finite and were ignored",
            show(slope),
            show(inter)
        ));
        return None;
    }
    notes.push(format!(
        "scl_slope {} and scl_inter {} applied; values stored as float32",
        show(slope),
        show(inter)
    ));
    Some((slope, inter))
}

/// Decodes `data` (exactly the voxel bytes) into samples, applying `scaling`.
pub(super) fn decode(
    path: &Path,
    hdr: &Header,
    data: &[u8],
    scaling: Option<(f64, f64)>,
    notes: &mut Vec<String>,
) -> Result<Samples> {
    let err = |e| ReadError::new(path, e);
    if let (None, Some(ty)) = (scaling, native_type(hdr.dtype)) {
        return Samples::from_bytes(ty, data, hdr.le).map_err(err);
    }
    if native_type(hdr.dtype).is_none() {
        notes.push(format!(
            "converted from {} to float32{}",
            hdr.dtype.name(),
            if hdr.dtype.size() == 4 || hdr.dtype == Dtype::F64 {
                " (values beyond 2^24 may lose precision)"
            } else {
                ""
            }
        ));
    }
    let size = hdr.dtype.size();
    volux_core::limits::check_alloc("float32 voxels", (data.len() / size) as u64, 4)
        .map_err(err)?;
    let (slope, inter) = scaling.unwrap_or((1.0, 0.0));
    let (dtype, le) = (hdr.dtype, hdr.le);
    let values: Vec<f32> = data
        .par_chunks_exact(size)
        .map(|c| (element(dtype, c, le) * slope + inter) as f32)
        .collect();
    Ok(Samples::F32(Buffer::owned(values)))
}

/// The first `N` bytes of `c` (zero-padded; callers pass chunks of exactly `N` bytes).
fn arr<const N: usize>(c: &[u8]) -> [u8; N] {
    let mut a = [0u8; N];
    a.iter_mut().zip(c).for_each(|(d, s)| *d = *s);
    a
}

/// One value of `dtype` from its bytes.
fn element(dtype: Dtype, c: &[u8], le: bool) -> f64 {
    macro_rules! num {
        ($t:ty, $n:literal) => {{
            let a = arr::<$n>(c);
            f64::from(if le {
                <$t>::from_le_bytes(a)
            } else {
                <$t>::from_be_bytes(a)
            })
        }};
    }
    match dtype {
        Dtype::U8 => num!(u8, 1),
        Dtype::I8 => num!(i8, 1),
        Dtype::I16 => num!(i16, 2),
        Dtype::U16 => num!(u16, 2),
        Dtype::I32 => num!(i32, 4),
        Dtype::U32 => num!(u32, 4),
        Dtype::F32 => num!(f32, 4),
        Dtype::F64 => num!(f64, 8),
    }
}
