//! Standard attributes stored with VR `UN` (unknown) in explicit-VR files, decoded by the
//! data dictionary's VR.
//!
//! A file converted from implicit VR by a tool that did not know an attribute writes it as
//! `UN` (PS3.5 6.2.2): the value bytes are those of the original encoding, little endian for
//! files that came from implicit VR little endian. `dicom-parser` keeps a `UN` value as raw
//! bytes, so PixelSpacing `0.859375\0.859375` would read as the numbers 48, 46, ... Like
//! pydicom and dcmtk, the value of every `UN` element whose tag the standard dictionary
//! (PS3.6) knows is re-read here by the dictionary's VR: strings split at `\`, binary numbers
//! in the file's byte order. Private tags, sequences and bulk (OB/OW) values stay as they are.
use dicom_core::dictionary::{DataDictionary, VirtualVr};
use dicom_core::header::Header;
use dicom_core::value::{PrimitiveValue, Value, C};
use dicom_core::{DataElement, Tag, VR};
use dicom_dictionary_std::StandardDataDictionary;

use super::attrs::Obj;

/// Re-reads the `UN` elements of `obj` (and of its sequences' items) by the dictionary's VR;
/// `little`: the file's byte order.
pub(super) fn resolve(obj: &mut Obj, little: bool) {
    let un: Vec<Tag> = obj
        .iter()
        .filter(|e| e.vr() == VR::UN)
        .map(|e| e.tag())
        .collect();
    for tag in un {
        let Some(vr) = dictionary_vr(tag) else {
            continue;
        };
        let Some(bytes) = obj.get(tag).and_then(|e| match e.value() {
            Value::Primitive(PrimitiveValue::U8(b)) => Some(b.to_vec()),
            _ => None,
        }) else {
            continue;
        };
        if let Some(v) = decode(vr, &bytes, little) {
            obj.put(DataElement::new(tag, vr, v));
        }
    }
    let seqs: Vec<Tag> = obj
        .iter()
        .filter(|e| e.items().is_some_and(|i| !i.is_empty()))
        .map(|e| e.tag())
        .collect();
    for tag in seqs {
        obj.update_value(tag, |v| {
            if let Some(items) = v.items_mut() {
                for item in items.iter_mut() {
                    resolve(item, little);
                }
            }
        });
    }
}

/// The VR the standard dictionary gives `tag`, when it is one a value can be re-read by.
fn dictionary_vr(tag: Tag) -> Option<VR> {
    if tag.group() % 2 == 1 {
        return None;
    }
    match StandardDataDictionary.by_tag(tag)?.vr {
        VirtualVr::Exact(VR::SQ | VR::UN | VR::OB | VR::OW) => None,
        VirtualVr::Exact(vr) => Some(vr),
        // US or SS by PixelRepresentation: the attributes concerned (smallest / largest
        // pixel values, LUT descriptors) are read as unsigned, as pydicom does without it.
        VirtualVr::Xs | VirtualVr::Lt => Some(VR::US),
        _ => None,
    }
}

/// `N` bytes of a number in little-endian order.
fn le<const N: usize>(c: &[u8], little: bool) -> [u8; N] {
    let mut a = [0u8; N];
    a.copy_from_slice(c);
    if !little {
        a.reverse();
    }
    a
}

/// The numbers of `bytes`, `N` bytes each; `None` when the length is not a multiple of `N`.
fn nums<const N: usize, T>(bytes: &[u8], little: bool, f: impl Fn([u8; N]) -> T) -> Option<C<T>> {
    bytes
        .len()
        .is_multiple_of(N)
        .then(|| bytes.chunks_exact(N).map(|c| f(le(c, little))).collect())
}

/// The value of `bytes` read as `vr` (PS3.5 6.2); `None` when the length does not fit the VR.
fn decode(vr: VR, bytes: &[u8], little: bool) -> Option<PrimitiveValue> {
    let b = bytes;
    Some(match vr {
        VR::US => PrimitiveValue::U16(nums(b, little, u16::from_le_bytes)?),
        VR::SS => PrimitiveValue::I16(nums(b, little, i16::from_le_bytes)?),
        VR::UL => PrimitiveValue::U32(nums(b, little, u32::from_le_bytes)?),
        VR::SL => PrimitiveValue::I32(nums(b, little, i32::from_le_bytes)?),
        VR::FL => PrimitiveValue::F32(nums(b, little, f32::from_le_bytes)?),
        VR::FD => PrimitiveValue::F64(nums(b, little, f64::from_le_bytes)?),
        VR::UV => PrimitiveValue::U64(nums(b, little, u64::from_le_bytes)?),
        VR::SV => PrimitiveValue::I64(nums(b, little, i64::from_le_bytes)?),
        VR::AT => {
            let w = nums(b, little, u16::from_le_bytes)?;
            if w.len() % 2 != 0 {
                return None;
            }
            PrimitiveValue::Tags(w.chunks_exact(2).map(|p| Tag(p[0], p[1])).collect())
        }
        VR::OD | VR::OF | VR::OL | VR::OV => return None,
        _ => {
            let s = String::from_utf8_lossy(b);
            let s = s.trim_end_matches(['\0', ' ']);
            if matches!(vr, VR::LT | VR::ST | VR::UT | VR::UR) {
                PrimitiveValue::from(s.to_string())
            } else {
                PrimitiveValue::Strs(s.split('\\').map(|p| p.trim().to_string()).collect())
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use dicom_dictionary_std::tags;

    #[test]
    fn un_values_are_read_by_the_dictionary_vr() {
        let mut obj = Obj::new_empty();
        let un = |tag, b: &[u8]| DataElement::new(tag, VR::UN, PrimitiveValue::from(b.to_vec()));
        obj.put(un(tags::PIXEL_SPACING, b"0.859375\\0.859375 "));
        obj.put(un(tags::ROWS, &[0x00, 0x02]));
        obj.put(un(tags::FRAME_TIME, b"33.3"));
        obj.put(un(Tag(0x0013, 0x1010), b"private"));
        resolve(&mut obj, true);
        let e = obj.get(tags::PIXEL_SPACING).unwrap();
        assert_eq!(e.vr(), VR::DS);
        assert_eq!(e.to_multi_float64().unwrap(), vec![0.859375, 0.859375]);
        assert_eq!(obj.get(tags::ROWS).unwrap().to_int::<u32>().unwrap(), 512);
        assert_eq!(obj.get(Tag(0x0013, 0x1010)).unwrap().vr(), VR::UN);
        // Big endian.
        let mut obj = Obj::new_empty();
        obj.put(un(tags::ROWS, &[0x02, 0x00]));
        obj.put(un(tags::DOSE_GRID_SCALING, b"1.5e-5"));
        resolve(&mut obj, false);
        assert_eq!(obj.get(tags::ROWS).unwrap().to_int::<u32>().unwrap(), 512);
        // A value whose length does not fit the VR stays raw.
        let mut obj = Obj::new_empty();
        obj.put(un(tags::ROWS, &[1, 2, 3]));
        resolve(&mut obj, true);
        assert_eq!(obj.get(tags::ROWS).unwrap().vr(), VR::UN);
    }
}
