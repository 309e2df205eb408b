//! Pixel data of uncompressed transfer syntaxes: which element holds it (PixelData,
//! FloatPixelData, DoubleFloatPixelData), its length checked against the header, its bytes
//! in little-endian order whatever the transfer syntax, single-bit samples unpacked; and the
//! sample format the value path (module `values`) and the colour path (module `color`) share.
use std::borrow::Cow;
use std::path::Path;

use dicom_core::value::{PrimitiveValue, Value};
use dicom_core::Tag;
use dicom_dictionary_std::tags;

use super::attrs::{ImageInfo, Obj};
use super::ts::{bits_read, is_native, ts_name, unsupported, EXPLICIT_BE, IMPLICIT_LE};
use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;

/// The type of the samples after extraction (single-bit samples unpacked to bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Fmt {
    /// Unsigned 8-bit (and unpacked single-bit).
    U8,
    /// Signed 8-bit.
    I8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit.
    I16,
    /// Unsigned 32-bit.
    U32,
    /// Signed 32-bit.
    I32,
    /// FloatPixelData (OF).
    F32,
    /// DoubleFloatPixelData (OD).
    F64,
}

impl Fmt {
    /// Bytes per sample.
    pub fn size(self) -> usize {
        match self {
            Fmt::U8 | Fmt::I8 => 1,
            Fmt::U16 | Fmt::I16 => 2,
            Fmt::U32 | Fmt::I32 | Fmt::F32 => 4,
            Fmt::F64 => 8,
        }
    }

    /// The integer format of BitsAllocated `bits` (1, 8, 16, 32) and PixelRepresentation.
    pub fn integer(bits: u32, signed: bool) -> Option<Self> {
        Some(match (bits, signed) {
            (1, _) => Fmt::U8,
            (8, false) => Fmt::U8,
            (8, true) => Fmt::I8,
            (16, false) => Fmt::U16,
            (16, true) => Fmt::I16,
            (32, false) => Fmt::U32,
            (32, true) => Fmt::I32,
            _ => return None,
        })
    }

    /// Sample `i` of little-endian `b` as a number.
    #[inline]
    pub fn get(self, b: &[u8], i: usize) -> f64 {
        let w = |n: usize| &b[i * n..i * n + n];
        match self {
            Fmt::U8 => f64::from(b[i]),
            Fmt::I8 => f64::from(b[i] as i8),
            Fmt::U16 => f64::from(u16::from_le_bytes([w(2)[0], w(2)[1]])),
            Fmt::I16 => f64::from(i16::from_le_bytes([w(2)[0], w(2)[1]])),
            Fmt::U32 => f64::from(u32::from_le_bytes(w(4).try_into().unwrap_or([0; 4]))),
            Fmt::I32 => f64::from(i32::from_le_bytes(w(4).try_into().unwrap_or([0; 4]))),
            Fmt::F32 => f64::from(f32::from_le_bytes(w(4).try_into().unwrap_or([0; 4]))),
            Fmt::F64 => f64::from_le_bytes(w(8).try_into().unwrap_or([0; 8])),
        }
    }
}

/// The photometric interpretations read with three samples per pixel.
const COLOR: [&str; 7] = [
    "RGB",
    "YBR_FULL",
    "YBR_FULL_422",
    "YBR_RCT",
    "YBR_ICT",
    "YBR_PARTIAL_420",
    "YBR_PARTIAL_422",
];

/// Checks that the pixel format is one Volux decodes (PS3.3 C.7.6.3: SamplesPerPixel,
/// PhotometricInterpretation, BitsAllocated).
pub(super) fn check_format(info: &ImageInfo) -> Result<(), ErrorKind> {
    let ts = info.transfer_syntax.as_str();
    let native = is_native(ts);
    if !native {
        if let Some(why) = unsupported(ts) {
            return Err(ErrorKind::Unsupported(why));
        }
    }
    let pi = info.photometric.as_str();
    match info.samples_per_pixel {
        1 if !COLOR.contains(&pi) => {}
        3 if COLOR.contains(&pi) => {}
        n => {
            return Err(ErrorKind::Unsupported(format!(
                "SamplesPerPixel {n} with PhotometricInterpretation {pi:?}: Volux reads one \
                 sample (MONOCHROME1, MONOCHROME2, PALETTE COLOR) or three (RGB, YBR_FULL, \
                 YBR_FULL_422, and YBR_RCT, YBR_ICT, YBR_PARTIAL in compressed data)"
            )))
        }
    }
    if native && pi.starts_with("YBR") && !matches!(pi, "YBR_FULL" | "YBR_FULL_422") {
        return Err(ErrorKind::Unsupported(format!(
            "PhotometricInterpretation {pi} in uncompressed pixel data: Volux converts \
             YBR_FULL and YBR_FULL_422 to RGB"
        )));
    }
    if pi == "YBR_FULL_422" && native && info.cols % 2 == 1 {
        return Err(ErrorKind::Invalid(format!(
            "YBR_FULL_422 with an odd number of Columns ({}): two pixels of a row share their \
             Cb and Cr (PS3.3 C.7.6.3.1.2)",
            info.cols
        )));
    }
    if matches!(pi, "YBR_FULL" | "YBR_FULL_422") && info.bits != 8 {
        return Err(ErrorKind::Unsupported(format!(
            "{pi} with BitsAllocated {}: YBR is converted to RGB for 8-bit samples only",
            info.bits
        )));
    }
    let bits = bits_read(ts);
    if !bits.contains(&info.bits) {
        return Err(ErrorKind::Unsupported(format!(
            "BitsAllocated {}: Volux reads {} in transfer syntax {ts} ({})",
            info.bits,
            if native {
                "1, 8, 16, 32 and 64 (DoubleFloatPixelData)"
            } else if bits.len() == 3 {
                "8, 16 and 32"
            } else {
                "8 and 16"
            },
            ts_name(ts)
        )));
    }
    if info.bits == 1 && info.samples_per_pixel != 1 {
        return Err(ErrorKind::Unsupported(
            "BitsAllocated 1 with SamplesPerPixel 3".into(),
        ));
    }
    Ok(())
}

/// Bytes of one frame once extracted: Rows x Columns x SamplesPerPixel samples of
/// BitsAllocated / 8 bytes (one byte for single-bit samples, once unpacked).
pub(super) fn frame_bytes(info: &ImageInfo) -> Option<u64> {
    u64::from(info.rows)
        .checked_mul(u64::from(info.cols))?
        .checked_mul(u64::from(info.samples_per_pixel))?
        .checked_mul(u64::from((info.bits / 8).max(1)))
}

/// Bytes `frames` frames take in uncompressed pixel data (PS3.5 8.1.1): single-bit samples
/// packed eight to a byte across frame boundaries, YBR_FULL_422 with two samples a pixel
/// (PS3.3 C.7.6.3.1.2).
fn stored_bytes(info: &ImageInfo, frames: u64) -> Option<u64> {
    let pixels = u64::from(info.rows)
        .checked_mul(u64::from(info.cols))?
        .checked_mul(frames)?;
    match (info.bits, info.photometric.as_str()) {
        (1, _) => Some(pixels.div_ceil(8)),
        (_, "YBR_FULL_422") => pixels.checked_mul(2 * u64::from(info.bits / 8)),
        (bits, _) => pixels
            .checked_mul(u64::from(info.samples_per_pixel))?
            .checked_mul(u64::from(bits / 8)),
    }
}

/// The pixel element of `obj`: PixelData, FloatPixelData or DoubleFloatPixelData.
fn element(obj: &Obj) -> Option<(Tag, &dicom_object::mem::InMemElement)> {
    [
        tags::PIXEL_DATA,
        tags::FLOAT_PIXEL_DATA,
        tags::DOUBLE_FLOAT_PIXEL_DATA,
    ]
    .into_iter()
    .find_map(|t| Some((t, obj.element_opt(t).ok().flatten()?)))
}

/// The uncompressed pixel data of `frames` frames of `obj`, as little-endian samples (single
/// bits unpacked to bytes of 0 or 1; YBR_FULL_422 still subsampled), and their format. A
/// note in `notes` when the element holds more than the header describes.
pub(super) fn native<'a>(
    path: &Path,
    obj: &'a Obj,
    info: &ImageInfo,
    frames: u64,
    notes: &mut Vec<String>,
) -> Result<(Cow<'a, [u8]>, Fmt)> {
    let err = |k: ErrorKind| ReadError::new(path, k);
    let invalid = |m: String| err(ErrorKind::Invalid(m));
    let (tag, elem) = element(obj).ok_or_else(|| {
        invalid(
            "no pixel data: none of PixelData (7FE0,0010), FloatPixelData (7FE0,0008), \
             DoubleFloatPixelData (7FE0,0009)"
                .into(),
        )
    })?;
    let fmt = match (tag, info.bits) {
        (tags::FLOAT_PIXEL_DATA, 32) => Fmt::F32,
        (tags::DOUBLE_FLOAT_PIXEL_DATA, 64) => Fmt::F64,
        (tags::PIXEL_DATA, 64) => {
            return Err(err(ErrorKind::Unsupported(
                "BitsAllocated 64 in PixelData (7FE0,0010): 64-bit integer pixels".into(),
            )))
        }
        (tags::PIXEL_DATA, b) => Fmt::integer(b, info.signed)
            .ok_or_else(|| invalid(format!("BitsAllocated {b} in PixelData")))?,
        (t, b) => {
            return Err(invalid(format!(
                "BitsAllocated {b} with {} ({:04X},{:04X}), which holds {}-bit floats",
                if t == tags::FLOAT_PIXEL_DATA {
                    "FloatPixelData"
                } else {
                    "DoubleFloatPixelData"
                },
                t.group(),
                t.element(),
                if t == tags::FLOAT_PIXEL_DATA { 32 } else { 64 }
            )))
        }
    };
    let prim = match elem.value() {
        Value::Primitive(p) => p,
        _ => {
            return Err(err(ErrorKind::Unsupported(
                "encapsulated (compressed) pixel data".into(),
            )))
        }
    };
    let expected = stored_bytes(info, frames)
        .ok_or_else(|| invalid("the pixel data size overflows".into()))?;
    let big = info.transfer_syntax == EXPLICIT_BE;
    let bytes = match prim {
        // Single bits are read in the file's byte order (pydicom swaps only 8-bit OW words).
        PrimitiveValue::U16(v) if big && info.bits == 1 => {
            Cow::Owned(v.iter().flat_map(|x| x.to_be_bytes()).collect())
        }
        _ => to_le(prim, if info.bits == 1 { 1 } else { fmt.size() }, big),
    };
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
    let bytes = match bytes {
        Cow::Borrowed(b) => Cow::Borrowed(b.get(..expected as usize).unwrap_or(b)),
        Cow::Owned(mut v) => {
            v.truncate(expected as usize);
            Cow::Owned(v)
        }
    };
    if info.bits == 1 {
        let pixels = u64::from(info.rows) * u64::from(info.cols) * frames;
        volux_core::limits::check_alloc("unpacked single-bit pixels", pixels, 1)
            .map_err(|e| ReadError::new(path, e))?;
        notes.push("single-bit pixels (BitsAllocated 1) unpacked to uint8 0 / 1".into());
        return Ok((Cow::Owned(unpack_bits(&bytes, pixels as usize)), Fmt::U8));
    }
    if fmt == Fmt::F64 {
        notes.push("DoubleFloatPixelData (float64) converted to float32".into());
    }
    Ok((bytes, fmt))
}

/// Single-bit samples, the first in the least significant bit of the first byte (PS3.5
/// 8.1.1), one byte (0 or 1) each.
fn unpack_bits(bytes: &[u8], pixels: usize) -> Vec<u8> {
    (0..pixels).map(|i| (bytes[i / 8] >> (i % 8)) & 1).collect()
}

/// Raw bytes in little-endian order, `size` bytes a sample. The parser decodes OW (and
/// wider) values as numbers in the file's byte order and keeps OB values as the file's
/// bytes; in Explicit VR Big Endian the samples of OB data, and 32-bit samples read as OW
/// words, are big-endian numbers that are turned around here (pydicom reads them so). 8-bit
/// samples in OW words come out as the words' little-endian bytes, as pydicom swaps them.
fn to_le(p: &PrimitiveValue, size: usize, big: bool) -> Cow<'_, [u8]> {
    fn le<T: Copy, const N: usize>(v: &[T], f: impl Fn(T) -> [u8; N]) -> Cow<'static, [u8]> {
        Cow::Owned(v.iter().flat_map(|x| f(*x)).collect())
    }
    match p {
        PrimitiveValue::U8(v) if big && size > 1 => Cow::Owned(
            v.chunks(size)
                .flat_map(|c| c.iter().rev().copied())
                .collect(),
        ),
        PrimitiveValue::U8(v) => Cow::Borrowed(&v[..]),
        PrimitiveValue::U16(v) if big && size == 4 => Cow::Owned(
            v.chunks(2)
                .flat_map(|w| {
                    (u32::from(w[0]) << 16 | u32::from(w.get(1).copied().unwrap_or(0)))
                        .to_le_bytes()
                })
                .collect(),
        ),
        PrimitiveValue::U16(v) => le(v, u16::to_le_bytes),
        PrimitiveValue::I16(v) => le(v, i16::to_le_bytes),
        PrimitiveValue::U32(v) => le(v, u32::to_le_bytes),
        PrimitiveValue::I32(v) => le(v, i32::to_le_bytes),
        PrimitiveValue::F32(v) => le(v, f32::to_le_bytes),
        PrimitiveValue::F64(v) => le(v, f64::to_le_bytes),
        other => other.to_bytes().into_owned().into(),
    }
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
    use dicom_core::value::C;

    #[test]
    fn big_endian_words_become_little_endian_samples() {
        // 32-bit samples read as OW words (big-endian file): 0x00010002 then 0xA0B0C0D0.
        let ow = PrimitiveValue::U16(C::from_vec(vec![0x0001, 0x0002, 0xA0B0, 0xC0D0]));
        let le32: Vec<u32> = to_le(&ow, 4, true)
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(le32, [0x0001_0002, 0xA0B0_C0D0]);
        // Little endian: the words are already in order.
        let le32: Vec<u32> = to_le(&ow, 4, false)
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(le32, [0x0002_0001, 0xC0D0_A0B0]);
        // 16-bit samples in OB bytes of a big-endian file.
        let ob = PrimitiveValue::U8(C::from_vec(vec![0x01, 0x02, 0x03, 0x04]));
        assert_eq!(&*to_le(&ob, 2, true), &[0x02, 0x01, 0x04, 0x03]);
        assert_eq!(&*to_le(&ob, 1, true), &[0x01, 0x02, 0x03, 0x04]);
    }

    #[test]
    fn single_bits_unpack_least_significant_first() {
        assert_eq!(
            unpack_bits(&[0b1000_0101, 0b0000_0010], 10),
            [1, 0, 1, 0, 0, 0, 0, 1, 0, 1]
        );
    }
}
