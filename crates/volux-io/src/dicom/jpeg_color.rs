//! The colour space of three-component JPEG frames, decided as pydicom decides it.
//!
//! pydicom decodes a JPEG frame's components as they are, takes the Photometric
//! Interpretation (PS3.3 C.7.6.3.1.2) as their colour space, corrected by the codestream
//! (component identifiers `R`, `G`, `B` mean RGB; a JFIF marker means YBR), and converts
//! YBR_FULL and YBR_FULL_422 to RGB. Volux does the same: 8-bit colour frames are decoded by
//! `jpeg-decoder` with its own colour transform switched off (module `codec`; left alone it
//! guesses from the component identifiers and markers, and would turn RGB components written
//! without an Adobe marker into nonsense that cannot be undone), and the components are
//! converted here when they are YBR. Lossless frames are never transformed by the decoder.
use dicom_core::value::Value;
use dicom_dictionary_std::tags;

use super::attrs::Obj;

/// What the decoded frames need.
#[derive(Debug, PartialEq, Eq)]
pub(super) enum Needs {
    /// They are RGB as decoded.
    Nothing,
    /// They are YBR_FULL components: convert them to RGB.
    YbrToRgb,
}

/// Markers of a JPEG codestream that decide its colour space.
#[derive(Debug, Default, PartialEq, Eq)]
struct Markers {
    ids: Vec<u8>,
    jfif: bool,
}

/// The markers before the first scan.
fn markers(data: &[u8]) -> Markers {
    let mut m = Markers::default();
    let mut at = 2usize;
    while let (Some(&0xFF), Some(&code)) = (data.get(at), data.get(at + 1)) {
        if code == 0xFF {
            at += 1;
            continue;
        }
        let Some(len) = data
            .get(at + 2..at + 4)
            .map(|b| usize::from(u16::from_be_bytes([b[0], b[1]])))
        else {
            break;
        };
        let body = data
            .get(at + 4..(at + 2 + len).min(data.len()))
            .unwrap_or(&[]);
        match code {
            0xE0 if body.starts_with(b"JFIF\0") => m.jfif = true,
            0xC0..=0xCF if !matches!(code, 0xC4 | 0xC8 | 0xCC) => {
                let n = usize::from(body.get(5).copied().unwrap_or(0));
                m.ids = (0..n)
                    .filter_map(|c| body.get(6 + 3 * c).copied())
                    .collect();
            }
            0xDA | 0xD9 => break,
            _ => {}
        }
        if len < 2 {
            break;
        }
        at += 2 + len;
    }
    m
}

/// The first fragment of the encapsulated pixel data (which starts the first frame).
fn first_fragment(obj: &Obj) -> Option<&[u8]> {
    match obj.element_opt(tags::PIXEL_DATA).ok().flatten()?.value() {
        Value::PixelSequence(s) => s.fragments().iter().find(|f| !f.is_empty()).map(|f| &f[..]),
        _ => None,
    }
}

/// What the decoded frames of a three-component JPEG image with PhotometricInterpretation
/// `pi` need, or why they cannot be read as pydicom reads them.
pub(super) fn needs(obj: &Obj, pi: &str) -> Result<Needs, String> {
    let Some(data) = first_fragment(obj) else {
        return Ok(Needs::Nothing);
    };
    decide(&markers(data), pi)
}

fn decide(m: &Markers, pi: &str) -> Result<Needs, String> {
    let rgb_ids = matches!(m.ids.as_slice(), [82, 71, 66] | [114, 103, 98]);
    // pydicom's colour space (DecodeRunner._conform_jpg_colorspace).
    let ybr = if rgb_ids {
        false
    } else if m.jfif && !pi.contains("YBR") {
        true
    } else {
        matches!(pi, "YBR_FULL" | "YBR_FULL_422")
    };
    Ok(if ybr { Needs::YbrToRgb } else { Needs::Nothing })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sof(ids: [u8; 3]) -> Vec<u8> {
        let mut v = vec![0xFF, 0xD8];
        v.extend_from_slice(&[0xFF, 0xC0, 0x00, 0x11, 8, 0, 1, 0, 1, 3]);
        for id in ids {
            v.extend_from_slice(&[id, 0x11, 0]);
        }
        v.extend_from_slice(&[0xFF, 0xDA, 0x00, 0x02]);
        v
    }

    #[test]
    fn pydicom_colour_spaces() {
        let m = markers(&sof([0, 1, 2]));
        assert_eq!(m.ids, [0, 1, 2]);
        // The Photometric Interpretation decides, unless the codestream says otherwise.
        assert_eq!(decide(&m, "RGB"), Ok(Needs::Nothing));
        assert_eq!(decide(&m, "YBR_FULL_422"), Ok(Needs::YbrToRgb));
        let mut adobe = vec![0xFF, 0xD8, 0xFF, 0xEE, 0x00, 0x0E];
        adobe.extend_from_slice(b"Adobe\0\x65\0\0\0\0\0");
        adobe.extend_from_slice(&sof([0, 1, 2])[2..]);
        let m = markers(&adobe);
        assert_eq!(decide(&m, "RGB"), Ok(Needs::Nothing));
        assert_eq!(decide(&m, "YBR_FULL"), Ok(Needs::YbrToRgb));
        // Identifiers R, G, B: RGB whatever the header says.
        assert_eq!(
            decide(&markers(&sof(*b"RGB")), "YBR_FULL"),
            Ok(Needs::Nothing)
        );
        // A JFIF marker: YBR even under an RGB Photometric Interpretation.
        let mut jfif = vec![0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x07];
        jfif.extend_from_slice(b"JFIF\0");
        jfif.extend_from_slice(&sof([1, 2, 3])[2..]);
        assert_eq!(decide(&markers(&jfif), "RGB"), Ok(Needs::YbrToRgb));
    }
}
