//! Pixel data of uncompressed transfer syntaxes (extraction, length checks) and the value
//! path shared with the compressed ones (sign extension, rescaling).
use std::borrow::Cow;
use std::path::Path;

use dicom_core::value::{PrimitiveValue, Value};
use dicom_dictionary_std::tags;
use volux_core::grid::Scalar;
use volux_core::{with_samples, Buffer, Samples, ScalarType};

use super::attrs::{ImageInfo, Obj};
use super::ts::{bits_read, is_native, ts_name, unsupported, EXPLICIT_BE, IMPLICIT_LE};
use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;

/// Checks that the pixel format is one Volux decodes.
pub(super) fn check_format(info: &ImageInfo) -> Result<(), ErrorKind> {
    let ts = info.transfer_syntax.as_str();
    if !is_native(ts) {
        if let Some(why) = unsupported(ts) {
            return Err(ErrorKind::Unsupported(why));
        }
    }
    if info.samples_per_pixel != 1 {
        return Err(ErrorKind::Unsupported(format!(
            "SamplesPerPixel {} ({}): Volux reads single-channel images",
            info.samples_per_pixel, info.photometric
        )));
    }
    let bits = bits_read(ts);
    if !bits.contains(&info.bits) {
        return Err(ErrorKind::Unsupported(format!(
            "BitsAllocated {}: Volux reads {} in transfer syntax {ts} ({})",
            info.bits,
            if bits.len() == 3 {
                "8, 16 and 32"
            } else {
                "8 and 16"
            },
            ts_name(ts)
        )));
    }
    Ok(())
}

/// Bytes of one frame.
pub(super) fn frame_bytes(info: &ImageInfo) -> Option<u64> {
    u64::from(info.rows)
        .checked_mul(u64::from(info.cols))?
        .checked_mul(u64::from(info.bits / 8))
}

/// The PixelData of `obj` as a little-endian byte stream, exactly `expected` bytes long;
/// a note in `notes` when the element holds more (Rows, Columns or NumberOfFrames smaller
/// than the data: the header may be wrong).
pub(super) fn le_bytes<'a>(
    path: &Path,
    obj: &'a Obj,
    expected: u64,
    notes: &mut Vec<String>,
) -> Result<Cow<'a, [u8]>> {
    let err = |k: ErrorKind| ReadError::new(path, k);
    let elem = obj
        .element_opt(tags::PIXEL_DATA)
        .ok()
        .flatten()
        .ok_or_else(|| {
            err(ErrorKind::Invalid(
                "no PixelData (7FE0,0010) element".into(),
            ))
        })?;
    let prim = match elem.value() {
        Value::Primitive(p) => p,
        _ => {
            return Err(err(ErrorKind::Unsupported(
                "encapsulated (compressed) pixel data".into(),
            )))
        }
    };
    let bytes = to_le(prim);
    let found = bytes.len() as u64;
    if found < expected {
        return Err(err(ErrorKind::Truncated { expected, found }));
    }
    // An odd length is padded to even by one byte; more than that is data the header does
    // not describe.
    if found > expected + 1 {
        notes.push(format!(
            "{}: the pixel data holds {found} bytes, more than the {expected} that Rows x \
             Columns x NumberOfFrames x BitsAllocated describe; the rest is not read",
            path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned()
            )
        ));
    }
    Ok(match bytes {
        Cow::Borrowed(b) => Cow::Borrowed(b.get(..expected as usize).unwrap_or(b)),
        Cow::Owned(mut v) => {
            v.truncate(expected as usize);
            Cow::Owned(v)
        }
    })
}

/// Raw bytes in little-endian order: OB values are the file bytes (8-bit data in any
/// transfer syntax, or little-endian words), OW and wider values are native numbers decoded
/// by the parser in the file's byte order.
fn to_le(p: &PrimitiveValue) -> Cow<'_, [u8]> {
    fn le<T: Copy, const N: usize>(v: &[T], f: impl Fn(T) -> [u8; N]) -> Cow<'static, [u8]> {
        Cow::Owned(v.iter().flat_map(|x| f(*x)).collect())
    }
    match p {
        PrimitiveValue::U8(v) => Cow::Borrowed(&v[..]),
        PrimitiveValue::U16(v) => le(v, u16::to_le_bytes),
        PrimitiveValue::I16(v) => le(v, i16::to_le_bytes),
        PrimitiveValue::U32(v) => le(v, u32::to_le_bytes),
        PrimitiveValue::I32(v) => le(v, i32::to_le_bytes),
        PrimitiveValue::F32(v) => le(v, f32::to_le_bytes),
        other => other.to_bytes().into_owned().into(),
    }
}

/// Signed 8- and 16-bit samples sign-extended from their `stored` low bits (BitsStored): the
/// bits above the stored ones are not part of the value (a decoder may leave them 0, a
/// writer may fill them with the sign). Unsigned and 32-bit samples are kept as they are.
fn sign_extend(bytes: &[u8], bits: u32, stored: u32, signed: bool) -> Cow<'_, [u8]> {
    if !signed || stored == 0 || stored >= bits || bits > 16 {
        return Cow::Borrowed(bytes);
    }
    let shift = bits - stored;
    Cow::Owned(if bits == 8 {
        bytes
            .iter()
            .map(|&b| (((b << shift) as i8) >> shift) as u8)
            .collect()
    } else {
        bytes
            .chunks_exact(2)
            .flat_map(|c| ((i16::from_le_bytes([c[0], c[1]]) << shift) >> shift).to_le_bytes())
            .collect()
    })
}

/// Turns the little-endian bytes of all slices (stored values, whatever the transfer
/// syntax) into samples: signed values are sign-extended from `bits_stored`, then each
/// slice's `(slope, intercept)` is applied: integers stay native when no rescale is needed,
/// become int16 when slope is 1 and the shifted values fit (CT Hounsfield units), float32
/// otherwise.
pub(super) fn assemble(
    bytes: &[u8],
    (bits, bits_stored, signed): (u32, u32, bool),
    rescale: &[(f64, f64)],
    notes: &mut Vec<String>,
) -> Result<Samples, volux_core::Error> {
    let bytes = &*sign_extend(bytes, bits, bits_stored, signed);
    let raw = match (bits, signed) {
        (8, false) => Samples::from_bytes(ScalarType::U8, bytes, true)?,
        (8, true) => {
            notes.push("signed 8-bit pixels widened to int16".into());
            Samples::I16(Buffer::owned(
                bytes.iter().map(|&b| i16::from(b as i8)).collect(),
            ))
        }
        (16, false) => Samples::from_bytes(ScalarType::U16, bytes, true)?,
        (16, true) => Samples::from_bytes(ScalarType::I16, bytes, true)?,
        _ => {
            notes.push(format!(
                "32-bit {} pixels converted to float32",
                if signed { "signed" } else { "unsigned" }
            ));
            Samples::F32(Buffer::owned(
                bytes
                    .chunks_exact(4)
                    .map(|c| {
                        let a = [c[0], c[1], c[2], c[3]];
                        if signed {
                            i32::from_le_bytes(a) as f32
                        } else {
                            u32::from_le_bytes(a) as f32
                        }
                    })
                    .collect(),
            ))
        }
    };
    if rescale.iter().all(|&r| r == (1.0, 0.0)) {
        return Ok(raw);
    }
    let slice_len = raw.len() / rescale.len().max(1);
    if let Some(s) = shifted_i16(&raw, rescale, slice_len) {
        notes.push("RescaleIntercept applied; values stored as int16".into());
        return Ok(s);
    }
    volux_core::limits::check_alloc("float32 pixels", raw.len() as u64, 4)?;
    notes.push("RescaleSlope / RescaleIntercept applied; values stored as float32".into());
    let out: Vec<f32> = with_samples!(&raw, |s| s
        .chunks(slice_len.max(1))
        .zip(rescale)
        .flat_map(|(c, &(m, b))| c
            .iter()
            .map(move |v| (f64::from(v.to_f32()) * m + b) as f32))
        .collect());
    Ok(Samples::F32(Buffer::owned(out)))
}

/// Integer data with slope 1 and whole intercepts whose shifted values fit int16.
fn shifted_i16(raw: &Samples, rescale: &[(f64, f64)], slice_len: usize) -> Option<Samples> {
    if raw.scalar_type() == ScalarType::F32
        || rescale.iter().any(|&(m, b)| m != 1.0 || b.fract() != 0.0)
    {
        return None;
    }
    let fits = |v: f64| (f64::from(i16::MIN)..=f64::from(i16::MAX)).contains(&v);
    let ok = with_samples!(raw, |s| s.chunks(slice_len.max(1)).zip(rescale).all(
        |(c, &(_, b))| {
            let (lo, hi) = c
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                    let v = f64::from(v.to_f32());
                    (l.min(v), h.max(v))
                });
            c.is_empty() || (fits(lo + b) && fits(hi + b))
        }
    ));
    ok.then(|| {
        let out: Vec<i16> = with_samples!(raw, |s| s
            .chunks(slice_len.max(1))
            .zip(rescale)
            .flat_map(|(c, &(_, b))| c.iter().map(move |v| (f64::from(v.to_f32()) + b) as i16))
            .collect());
        Samples::I16(Buffer::owned(out))
    })
}

/// For a file the parser could not read: the declared and present bytes of its PixelData
/// when the file ends inside it (found by scanning for the PixelData element header).
pub(super) fn truncation(path: &Path, transfer_syntax: &str) -> Option<(u64, u64)> {
    let data = crate::util::read_regular(path, volux_core::limits::memory_limit()).ok()?;
    let (tag, explicit, le): (&[u8], bool, bool) = match transfer_syntax {
        IMPLICIT_LE => (&[0xE0, 0x7F, 0x10, 0x00], false, true),
        EXPLICIT_BE => (&[0x7F, 0xE0, 0x00, 0x10], true, false),
        _ => (&[0xE0, 0x7F, 0x10, 0x00], true, true),
    };
    let hit = |i: usize| {
        let rest = data.get(i + 4..)?;
        let (len_at, start) = if explicit {
            matches!(rest.get(..4)?, b"OW\0\0" | b"OB\0\0").then_some((i + 8, i + 12))?
        } else {
            (i + 4, i + 8)
        };
        let l: [u8; 4] = data.get(len_at..len_at + 4)?.try_into().ok()?;
        let len = if le {
            u32::from_le_bytes(l)
        } else {
            u32::from_be_bytes(l)
        };
        Some((
            u64::from(len),
            (data.len() as u64).saturating_sub(start as u64),
        ))
    };
    data.windows(4)
        .enumerate()
        .filter(|(_, w)| *w == tag)
        .find_map(|(i, _)| hit(i))
        .filter(|&(len, found)| len != u32::MAX as u64 && found < len)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_values_are_sign_extended_from_bits_stored() {
        // 12 bits stored: 0x0FFF is -1, 0x0800 is -2048, 0x07FF is 2047, whatever the bits
        // above (0 from a decoder, the sign from a writer, junk).
        let words: [u16; 5] = [0x0FFF, 0x0800, 0x07FF, 0xFFFF, 0xA001];
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        let out = sign_extend(&bytes, 16, 12, true);
        let v: Vec<i16> = out
            .chunks_exact(2)
            .map(|c| i16::from_le_bytes([c[0], c[1]]))
            .collect();
        assert_eq!(v, [-1, -2048, 2047, -1, 1]);
        // 8-bit, 4 stored.
        assert_eq!(
            &*sign_extend(&[0x0F, 0x08, 0x07], 8, 4, true),
            &[0xFF, 0xF8, 0x07]
        );
        // Unsigned, full-width or 32-bit data is kept as it is.
        assert!(matches!(
            sign_extend(&bytes, 16, 12, false),
            Cow::Borrowed(_)
        ));
        assert!(matches!(
            sign_extend(&bytes, 16, 16, true),
            Cow::Borrowed(_)
        ));
        assert!(matches!(sign_extend(&bytes, 16, 0, true), Cow::Borrowed(_)));
        assert!(matches!(
            sign_extend(&bytes[..8], 32, 12, true),
            Cow::Borrowed(_)
        ));
    }
}
