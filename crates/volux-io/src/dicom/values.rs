//! The value path of single-sample images, shared by uncompressed and decoded pixel data:
//! signed samples sign-extended from BitsStored, then the Modality LUT transformation of each
//! frame (PS3.3 C.11.1: RescaleSlope / RescaleIntercept, or the Modality LUT Sequence), then
//! an RT Dose's DoseGridScaling (PS3.3 C.8.8.3), as pydicom's `apply_modality_lut` and
//! a multiplication by DoseGridScaling give them.
use std::borrow::Cow;
use std::sync::Arc;

use volux_core::{Buffer, Samples};

use super::lut::Lut;
use super::pixels::Fmt;

/// The Modality LUT transformation of a frame (PS3.3 C.11.1).
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Modality {
    /// RescaleSlope and RescaleIntercept (1 and 0 when absent).
    Linear(f64, f64),
    /// The Modality LUT Sequence's table.
    Lut(Arc<Lut>),
}

/// What turns a frame's stored values into the grid's values.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct FrameValues {
    /// The Modality LUT transformation.
    pub modality: Modality,
    /// DoseGridScaling (RT Dose): the factor giving Gy.
    pub dose: Option<f64>,
}

impl FrameValues {
    /// Stored values kept as they are.
    fn identity(&self) -> bool {
        self.modality == Modality::Linear(1.0, 0.0) && self.dose.is_none()
    }

    /// The value of stored value `v`.
    #[inline]
    fn apply(&self, v: f64) -> f64 {
        let m = match &self.modality {
            Modality::Linear(slope, intercept) => v * slope + intercept,
            Modality::Lut(l) => f64::from(l.map(v as i64)),
        };
        match self.dose {
            Some(s) => m * s,
            None => m,
        }
    }
}

/// Signed 8- and 16-bit samples sign-extended from their `stored` low bits (BitsStored): the
/// bits above the stored ones are not part of the value (a decoder may leave them 0, a
/// writer may fill them with the sign). Other samples are kept as they are.
pub(super) fn sign_extend(bytes: &[u8], fmt: Fmt, stored: u32) -> Cow<'_, [u8]> {
    let bits = 8 * fmt.size() as u32;
    if !matches!(fmt, Fmt::I8 | Fmt::I16) || stored == 0 || stored >= bits {
        return Cow::Borrowed(bytes);
    }
    let shift = bits - stored;
    Cow::Owned(if fmt == Fmt::I8 {
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

/// Turns the little-endian stored samples of all frames (`frames.len()` frames of equal
/// size) into the grid's samples: kept native when no frame transforms them (signed 8-bit
/// widened to int16, 32-bit integers and float64 to float32, noted); a Modality LUT gives
/// its entries (uint8 or uint16); RescaleSlope 1 with whole intercepts that keep the values
/// in int16 gives int16 (CT Hounsfield units); anything else float32.
pub(super) fn assemble(
    bytes: &[u8],
    fmt: Fmt,
    bits_stored: u32,
    frames: &[FrameValues],
    notes: &mut Vec<String>,
) -> Result<Samples, volux_core::Error> {
    let bytes = &*sign_extend(bytes, fmt, bits_stored);
    let n = bytes.len() / fmt.size();
    let per = n / frames.len().max(1);
    let frame_of = |i: usize| &frames[(i / per.max(1)).min(frames.len().saturating_sub(1))];
    if frames.is_empty() || frames.iter().all(FrameValues::identity) {
        return native(bytes, fmt, n, notes);
    }
    let luts: Vec<&Lut> = frames
        .iter()
        .filter_map(|f| match &f.modality {
            Modality::Lut(l) if f.dose.is_none() => Some(&**l),
            _ => None,
        })
        .collect();
    if luts.len() == frames.len() {
        let l = luts[0];
        notes.push(format!(
            "Modality LUT (Modality LUT Sequence: {} entries from stored value {}, {}-bit) \
             applied",
            l.entries.len(),
            l.first,
            if l.bits8 { 8 } else { 16 }
        ));
        let map = |i: usize| match &frame_of(i).modality {
            Modality::Lut(l) => l.map(fmt.get(bytes, i) as i64),
            Modality::Linear(..) => 0,
        };
        return Ok(if luts.iter().all(|l| l.bits8) {
            Samples::U8(Buffer::owned((0..n).map(|i| map(i) as u8).collect()))
        } else {
            Samples::U16(Buffer::owned((0..n).map(map).collect()))
        });
    }
    if let Some(s) = shifted_i16(bytes, fmt, n, &frame_of, frames) {
        notes.push("RescaleIntercept applied; values stored as int16".into());
        return Ok(s);
    }
    volux_core::limits::check_alloc("float32 pixels", n as u64, 4)?;
    if frames
        .iter()
        .any(|f| matches!(f.modality, Modality::Lut(_)))
    {
        notes.push("Modality LUT (Modality LUT Sequence) applied".into());
    }
    if frames
        .iter()
        .any(|f| matches!(f.modality, Modality::Linear(m, b) if (m, b) != (1.0, 0.0)))
    {
        notes.push("RescaleSlope / RescaleIntercept applied; values stored as float32".into());
    }
    if let Some(s) = frames.iter().find_map(|f| f.dose) {
        notes.push(format!(
            "DoseGridScaling {s} applied: dose in Gy, stored as float32"
        ));
    }
    Ok(Samples::F32(Buffer::owned(
        (0..n)
            .map(|i| frame_of(i).apply(fmt.get(bytes, i)) as f32)
            .collect(),
    )))
}

/// Samples kept as stored.
fn native(
    bytes: &[u8],
    fmt: Fmt,
    n: usize,
    notes: &mut Vec<String>,
) -> Result<Samples, volux_core::Error> {
    use volux_core::ScalarType;
    Ok(match fmt {
        Fmt::U8 => Samples::U8(Buffer::owned(bytes.to_vec())),
        Fmt::I8 => {
            notes.push("signed 8-bit pixels widened to int16".into());
            Samples::I16(Buffer::owned(
                bytes.iter().map(|&b| i16::from(b as i8)).collect(),
            ))
        }
        Fmt::U16 => Samples::from_bytes(ScalarType::U16, bytes, true)?,
        Fmt::I16 => Samples::from_bytes(ScalarType::I16, bytes, true)?,
        Fmt::F32 => Samples::from_bytes(ScalarType::F32, bytes, true)?,
        Fmt::U32 | Fmt::I32 | Fmt::F64 => {
            if fmt != Fmt::F64 {
                notes.push(format!(
                    "32-bit {} pixels converted to float32",
                    if fmt == Fmt::I32 {
                        "signed"
                    } else {
                        "unsigned"
                    }
                ));
            }
            volux_core::limits::check_alloc("float32 pixels", n as u64, 4)?;
            Samples::F32(Buffer::owned(
                (0..n).map(|i| fmt.get(bytes, i) as f32).collect(),
            ))
        }
    })
}

/// Integer data of at most 16 bits with slope 1 and whole intercepts whose shifted values
/// fit int16.
fn shifted_i16<'a>(
    bytes: &[u8],
    fmt: Fmt,
    n: usize,
    frame_of: &impl Fn(usize) -> &'a FrameValues,
    frames: &[FrameValues],
) -> Option<Samples> {
    if !matches!(fmt, Fmt::U8 | Fmt::I8 | Fmt::U16 | Fmt::I16)
        || frames.iter().any(|f| {
            f.dose.is_some()
                || !matches!(f.modality, Modality::Linear(m, b) if m == 1.0 && b.fract() == 0.0)
        })
    {
        return None;
    }
    let fits = |v: f64| (f64::from(i16::MIN)..=f64::from(i16::MAX)).contains(&v);
    (0..n)
        .all(|i| fits(frame_of(i).apply(fmt.get(bytes, i))))
        .then(|| {
            Samples::I16(Buffer::owned(
                (0..n)
                    .map(|i| frame_of(i).apply(fmt.get(bytes, i)) as i16)
                    .collect(),
            ))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn linear(m: f64, b: f64) -> FrameValues {
        FrameValues {
            modality: Modality::Linear(m, b),
            dose: None,
        }
    }

    #[test]
    fn signed_values_are_sign_extended_from_bits_stored() {
        // 12 bits stored: 0x0FFF is -1, 0x0800 is -2048, 0x07FF is 2047, whatever the bits
        // above (0 from a decoder, the sign from a writer, junk).
        let words: [u16; 5] = [0x0FFF, 0x0800, 0x07FF, 0xFFFF, 0xA001];
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        let out = sign_extend(&bytes, Fmt::I16, 12);
        let v: Vec<i16> = out
            .chunks_exact(2)
            .map(|c| i16::from_le_bytes([c[0], c[1]]))
            .collect();
        assert_eq!(v, [-1, -2048, 2047, -1, 1]);
        // 8-bit, 4 stored.
        assert_eq!(
            &*sign_extend(&[0x0F, 0x08, 0x07], Fmt::I8, 4),
            &[0xFF, 0xF8, 0x07]
        );
        // Unsigned, full-width or 32-bit data is kept as it is.
        assert!(matches!(
            sign_extend(&bytes, Fmt::U16, 12),
            Cow::Borrowed(_)
        ));
        assert!(matches!(
            sign_extend(&bytes, Fmt::I16, 16),
            Cow::Borrowed(_)
        ));
        assert!(matches!(sign_extend(&bytes, Fmt::I16, 0), Cow::Borrowed(_)));
        assert!(matches!(
            sign_extend(&bytes[..8], Fmt::I32, 12),
            Cow::Borrowed(_)
        ));
    }

    #[test]
    fn dose_grid_scaling_of_32_bit_dose_is_exact_in_float32() {
        // 32-bit unsigned dose past 2^24, scaled by 1e-6 as float64 then rounded once.
        let v: [u32; 3] = [0, 1_254_000, 4_000_000_017];
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let f = [FrameValues {
            modality: Modality::Linear(1.0, 0.0),
            dose: Some(1e-6),
        }];
        let mut notes = Vec::new();
        let s = assemble(&bytes, Fmt::U32, 32, &f, &mut notes).unwrap();
        for (i, x) in v.iter().enumerate() {
            assert_eq!(s.get_f32(i), (f64::from(*x) * 1e-6) as f32);
        }
        assert!(
            notes.iter().any(|n| n.contains("DoseGridScaling")),
            "{notes:?}"
        );
    }

    #[test]
    fn modality_lut_maps_per_frame() {
        let lut = Arc::new(Lut {
            first: 2,
            entries: vec![100, 200, 300],
            bits8: false,
        });
        let f = [FrameValues {
            modality: Modality::Lut(lut),
            dose: None,
        }];
        let mut notes = Vec::new();
        let s = assemble(&[0, 2, 3, 4, 9], Fmt::U8, 8, &f, &mut notes).unwrap();
        let v: Vec<f32> = (0..5).map(|i| s.get_f32(i)).collect();
        assert_eq!(v, [100.0, 100.0, 200.0, 300.0, 300.0]);
        assert!(notes[0].contains("Modality LUT"), "{notes:?}");
    }

    #[test]
    fn rescale_gives_int16_or_float32() {
        let mut notes = Vec::new();
        let bytes: Vec<u8> = [0u16, 1000, 4095]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let s = assemble(&bytes, Fmt::U16, 12, &[linear(1.0, -1024.0)], &mut notes).unwrap();
        assert!(matches!(s, Samples::I16(_)));
        assert_eq!(s.get_f32(2), 3071.0);
        let s = assemble(&bytes, Fmt::U16, 12, &[linear(0.5, 0.0)], &mut notes).unwrap();
        assert!(matches!(s, Samples::F32(_)));
        assert_eq!(s.get_f32(2), 2047.5);
    }
}
