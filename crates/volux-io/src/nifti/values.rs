//! Decoding NIfTI voxel bytes: native types as they are, others (or scaled data) to float32;
//! `DT_RGB24` / `DT_RGBA32` as colour ([`volux_core::color::Rgb`]) or one channel.
use std::path::Path;

use rayon::prelude::*;
use volux_core::color::Rgb;
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

/// The `(slope, intercept)` of an Analyze 7.5 file, as SPM2 (`spm_vol_ana.m`) and nibabel's
/// `Spm2AnalyzeHeader` find it: SPM's scale factor in `funused1` (at the place of NIfTI's
/// `scl_slope`) when finite and non-zero, with `funused2` as intercept when finite; else
/// `cal_max - cal_min` over `glmax - glmin` when both are non-zero; else none. (1, 0) is none.
pub(super) fn analyze_scaling(hdr: &Header, notes: &mut Vec<String>) -> Option<(f64, f64)> {
    let (slope, inter) = (hdr.scl_slope, hdr.scl_inter);
    let (slope, inter, from) = if slope.is_finite() && slope != 0.0 {
        let inter = if inter.is_finite() { inter } else { 0.0 };
        (
            slope,
            inter,
            "SPM scale factor (funused1) and intercept (funused2)",
        )
    } else {
        let raw = f64::from(hdr.gl[0]) - f64::from(hdr.gl[1]);
        let cal = hdr.cal[0] - hdr.cal[1];
        if raw == 0.0 || cal == 0.0 || !cal.is_finite() {
            return None;
        }
        let slope = cal / raw;
        let inter = hdr.cal[1] - slope * f64::from(hdr.gl[1]);
        (
            slope,
            inter,
            "SPM2 scaling from cal_min/cal_max over glmin/glmax",
        )
    };
    if slope == 1.0 && inter == 0.0 {
        return None;
    }
    notes.push(format!(
        "{from} applied: slope {}, intercept {}; values stored as float32",
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
            if hdr.dtype.size() >= 4 {
                " (values beyond 2^24 may lose precision)"
            } else {
                ""
            }
        ));
    }
    let size = hdr.dtype.size();
    volux_core::limits::check_alloc("float32 voxels", (data.len() / size) as u64, 4)
        .map_err(err)?;
    let (dtype, le) = (hdr.dtype, hdr.le);
    let values: Vec<f32> = data
        .par_chunks_exact(size)
        .map(|c| match scaling {
            // 64-bit integers straight to float32: one rounding, as numpy's cast.
            None => match dtype {
                Dtype::I64 => i64::from_le_bytes(ordered(c, le)) as f32,
                Dtype::U64 => u64::from_le_bytes(ordered(c, le)) as f32,
                _ => element(dtype, c, le) as f32,
            },
            Some((slope, inter)) => (element(dtype, c, le) * slope + inter) as f32,
        })
        .collect();
    Ok(Samples::F32(Buffer::owned(values)))
}

/// What a colour volume (`DT_RGB24`, `DT_RGBA32`) is read as.
pub(super) enum Colour {
    /// Red, green and blue (alpha dropped).
    Rgb(Rgb),
    /// One channel as a uint8 scalar.
    Channel(Samples),
}

/// Splits interleaved colour bytes (`channels` uint8 per voxel, `data` exactly the voxels)
/// into red, green and blue, or into the one channel `pick`.
pub(super) fn decode_colour(
    path: &Path,
    data: &[u8],
    channels: usize,
    pick: Option<usize>,
) -> Result<Colour> {
    let channel = |k: usize| -> Vec<u8> { data.chunks_exact(channels).map(|px| px[k]).collect() };
    match pick {
        Some(k) => Ok(Colour::Channel(Samples::U8(Buffer::owned(channel(k))))),
        None => Rgb::new([0, 1, 2].map(|k| Samples::U8(Buffer::owned(channel(k)))))
            .map(Colour::Rgb)
            .map_err(|e| ReadError::new(path, e)),
    }
}

/// The 8 bytes of `c` in little-endian order.
fn ordered(c: &[u8], le: bool) -> [u8; 8] {
    let mut a = arr::<8>(c);
    if !le {
        a.reverse();
    }
    a
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
        Dtype::I64 => i64::from_le_bytes(ordered(c, le)) as f64,
        Dtype::U64 => u64::from_le_bytes(ordered(c, le)) as f64,
        // Colour is split by `decode_colour`, never scaled.
        Dtype::Rgb24 | Dtype::Rgba32 => f64::from(c.first().copied().unwrap_or(0)),
    }
}
