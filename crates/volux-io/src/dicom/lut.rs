//! Lookup tables: the Modality LUT (PS3.3 C.11.1) and the Palette Color LUTs (PS3.3
//! C.7.6.3.1.5, C.7.6.3.1.6, segmented ones C.7.9.2), read as pydicom's
//! `apply_modality_lut` and `apply_color_lut` read them.
//!
//! A LUT Descriptor has three values: the number of entries (0 meaning 65536), the first
//! stored value mapped (in the pixel data's representation, so signed when
//! PixelRepresentation is 1), and the nominal bits of an entry. A stored value below the
//! first mapped one takes the first entry, one past the last entry the last.
use dicom_core::value::{PrimitiveValue, Value};
use dicom_core::Tag;
use dicom_dictionary_std::tags;

use super::attrs::{items, Obj};

/// Entries of a lookup table and the stored value the first one maps.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Lut {
    /// The stored value mapped to `entries[0]`.
    pub first: i64,
    /// The table (at least one entry).
    pub entries: Vec<u16>,
    /// Entries of 8 bits (else 16).
    pub bits8: bool,
}

impl Lut {
    /// The entry for stored value `v`, clamped to the table's ends.
    #[inline]
    pub fn map(&self, v: i64) -> u16 {
        let last = self.entries.len().saturating_sub(1) as i64;
        let i = v.saturating_sub(self.first).clamp(0, last);
        self.entries.get(i as usize).copied().unwrap_or(0)
    }
}

/// The three values of a LUT Descriptor: entries (0 read as 65536), first mapped value
/// (made signed for signed pixel data), bits.
fn descriptor(obj: &Obj, tag: Tag, signed: bool) -> Result<(usize, i64, u32), String> {
    let name = tag_name(tag);
    let v: Vec<i64> = obj
        .element_opt(tag)
        .ok()
        .flatten()
        .and_then(|e| e.to_multi_int::<i64>().ok())
        .ok_or_else(|| format!("{name} is missing or not three numbers"))?;
    let [n, first, bits] = v.as_slice() else {
        return Err(format!("{name} has {} values instead of 3", v.len()));
    };
    let n = match *n {
        0 => 65536,
        n if (1..=65535).contains(&n) => n as usize,
        n => return Err(format!("{name} gives {n} entries")),
    };
    // The first mapped value is US or SS as the pixel data (PS3.3 C.11.1.1.1).
    let first = if signed && *first > 32767 {
        first - 65536
    } else {
        *first
    };
    Ok((n, first, *bits as u32))
}

/// A readable name for the tags this module reads.
fn tag_name(tag: Tag) -> String {
    let name = match tag {
        tags::LUT_DESCRIPTOR => "LUTDescriptor",
        tags::LUT_DATA => "LUTData",
        tags::RED_PALETTE_COLOR_LOOKUP_TABLE_DESCRIPTOR => "RedPaletteColorLookupTableDescriptor",
        tags::GREEN_PALETTE_COLOR_LOOKUP_TABLE_DESCRIPTOR => {
            "GreenPaletteColorLookupTableDescriptor"
        }
        tags::BLUE_PALETTE_COLOR_LOOKUP_TABLE_DESCRIPTOR => "BluePaletteColorLookupTableDescriptor",
        tags::RED_PALETTE_COLOR_LOOKUP_TABLE_DATA => "RedPaletteColorLookupTableData",
        tags::GREEN_PALETTE_COLOR_LOOKUP_TABLE_DATA => "GreenPaletteColorLookupTableData",
        tags::BLUE_PALETTE_COLOR_LOOKUP_TABLE_DATA => "BluePaletteColorLookupTableData",
        tags::SEGMENTED_RED_PALETTE_COLOR_LOOKUP_TABLE_DATA => {
            "SegmentedRedPaletteColorLookupTableData"
        }
        tags::SEGMENTED_GREEN_PALETTE_COLOR_LOOKUP_TABLE_DATA => {
            "SegmentedGreenPaletteColorLookupTableData"
        }
        tags::SEGMENTED_BLUE_PALETTE_COLOR_LOOKUP_TABLE_DATA => {
            "SegmentedBluePaletteColorLookupTableData"
        }
        _ => "",
    };
    format!("{name} ({:04X},{:04X})", tag.group(), tag.element())
}

/// The 16-bit words of a LUT's data (US or OW values as the parser decoded them, in the
/// file's byte order), or its bytes as little-endian words when it was kept as bytes.
fn words(obj: &Obj, tag: Tag) -> Option<Vec<u16>> {
    let e = obj.element_opt(tag).ok().flatten()?;
    match e.value() {
        Value::Primitive(PrimitiveValue::U16(v)) => Some(v.to_vec()),
        Value::Primitive(PrimitiveValue::I16(v)) => Some(v.iter().map(|&x| x as u16).collect()),
        Value::Primitive(PrimitiveValue::U8(b)) => Some(
            b.chunks(2)
                .map(|c| u16::from_le_bytes([c[0], c.get(1).copied().unwrap_or(0)]))
                .collect(),
        ),
        _ => None,
    }
}

/// The Modality LUT of `obj` (its first Modality LUT Sequence item), if it has one.
pub(super) fn modality(obj: &Obj, signed: bool) -> Option<Result<Lut, String>> {
    let item = items(obj, tags::MODALITY_LUT_SEQUENCE)?.first()?;
    Some(
        (|| {
            let (n, first, bits) = descriptor(item, tags::LUT_DESCRIPTOR, signed)?;
            let data = words(item, tags::LUT_DATA)
                .ok_or_else(|| format!("{} is missing", tag_name(tags::LUT_DATA)))?;
            if data.len() < n {
                return Err(format!(
                    "{} holds {} entries, but the LUT Descriptor gives {n}",
                    tag_name(tags::LUT_DATA),
                    data.len()
                ));
            }
            Ok(Lut {
                first,
                entries: data[..n].to_vec(),
                bits8: bits <= 8,
            })
        })()
        .map_err(|m| format!("Modality LUT Sequence (0028,3000): {m}")),
    )
}

/// The red, green and blue Palette Color LUTs of a PALETTE COLOR image.
pub(super) fn palette(obj: &Obj, signed: bool) -> Result<[Lut; 3], String> {
    let channels = [
        (
            tags::RED_PALETTE_COLOR_LOOKUP_TABLE_DESCRIPTOR,
            tags::RED_PALETTE_COLOR_LOOKUP_TABLE_DATA,
            tags::SEGMENTED_RED_PALETTE_COLOR_LOOKUP_TABLE_DATA,
        ),
        (
            tags::GREEN_PALETTE_COLOR_LOOKUP_TABLE_DESCRIPTOR,
            tags::GREEN_PALETTE_COLOR_LOOKUP_TABLE_DATA,
            tags::SEGMENTED_GREEN_PALETTE_COLOR_LOOKUP_TABLE_DATA,
        ),
        (
            tags::BLUE_PALETTE_COLOR_LOOKUP_TABLE_DESCRIPTOR,
            tags::BLUE_PALETTE_COLOR_LOOKUP_TABLE_DATA,
            tags::SEGMENTED_BLUE_PALETTE_COLOR_LOOKUP_TABLE_DATA,
        ),
    ];
    let mut out = Vec::with_capacity(3);
    for (desc, data, segmented) in channels {
        out.push(one_palette(obj, desc, data, segmented, signed)?);
    }
    let lens: Vec<usize> = out.iter().map(|l| l.entries.len()).collect();
    if lens.iter().any(|&l| l != lens[0]) {
        return Err(format!(
            "the red, green and blue Palette Color LUTs have {lens:?} entries: they must agree"
        ));
    }
    out.try_into()
        .map_err(|_| "three Palette Color LUTs expected".to_string())
}

/// One channel's Palette Color LUT: plain data (8- or 16-bit entries, told apart by the
/// data's length as pydicom does) or segmented data (PS3.3 C.7.9.2).
fn one_palette(
    obj: &Obj,
    desc: Tag,
    data: Tag,
    segmented: Tag,
    signed: bool,
) -> Result<Lut, String> {
    let (n, first, bits) = descriptor(obj, desc, signed)?;
    if let Some(w) = words(obj, data) {
        let bytes = w.len() * 2;
        let entries: Vec<u16> = if bytes == n || bytes == n + 1 {
            // 8-bit entries, two to a word (the low byte first).
            w.iter()
                .flat_map(|x| x.to_le_bytes())
                .take(n)
                .map(u16::from)
                .collect()
        } else if w.len() == n {
            w
        } else {
            return Err(format!(
                "{} holds {bytes} bytes, which are neither {n} 8-bit nor {n} 16-bit entries \
                 ({} gives {n} entries)",
                tag_name(data),
                tag_name(desc)
            ));
        };
        let bits8 = bytes <= n + 1;
        return Ok(Lut {
            first,
            entries,
            bits8,
        });
    }
    if let Some(w) = words(obj, segmented) {
        let values: Vec<u16> = if bits <= 8 {
            w.iter()
                .flat_map(|x| x.to_le_bytes())
                .map(u16::from)
                .collect()
        } else {
            w
        };
        let entries = expand_segmented(&values, bits <= 8)
            .map_err(|m| format!("{}: {m}", tag_name(segmented)))?;
        if entries.len() < n {
            return Err(format!(
                "{} expands to {} entries, but {} gives {n}",
                tag_name(segmented),
                entries.len(),
                tag_name(desc)
            ));
        }
        return Ok(Lut {
            first,
            entries: entries[..n].to_vec(),
            bits8: bits <= 8,
        });
    }
    Err(format!(
        "PALETTE COLOR without {} or {}",
        tag_name(data),
        tag_name(segmented)
    ))
}

/// The most entries a LUT can have (a descriptor gives at most 65536).
const MAX_ENTRIES: usize = 1 << 16;

/// Expands segmented palette data (PS3.3 C.7.9.2) as pydicom's `_expand_segmented_lut`
/// does: discrete segments (opcode 0), linear ones (1, rounded half to even from the
/// previous entry), indirect ones (2, re-reading earlier segments at a word offset). The
/// output is bounded by 65536 entries and the indirection depth by 8.
fn expand_segmented(data: &[u16], bytes: bool) -> Result<Vec<u16>, String> {
    let mut lut = Vec::new();
    expand(data, bytes, None, &mut lut, 0)?;
    Ok(lut)
}

fn expand(
    data: &[u16],
    bytes: bool,
    segments: Option<usize>,
    lut: &mut Vec<u16>,
    depth: u32,
) -> Result<(), String> {
    if depth > 8 {
        return Err("indirect segments nest more than 8 deep".into());
    }
    let mut at = 0usize;
    let mut read = 0usize;
    while at + 1 < data.len() {
        let (op, len) = (data[at], usize::from(data[at + 1]));
        at += 2;
        match op {
            0 => {
                let seg = data
                    .get(at..at + len)
                    .ok_or("a discrete segment runs past the data")?;
                lut.extend_from_slice(seg);
                at += len;
            }
            1 => {
                let y0 = *lut.last().ok_or("the first segment is a linear one")?;
                let y1 = *data.get(at).ok_or("a linear segment runs past the data")?;
                at += 1;
                if y0 == y1 || len == 0 {
                    lut.extend(std::iter::repeat_n(y1, len));
                } else {
                    let (a, b) = (f64::from(y0), f64::from(y1));
                    let step = (b - a) / len as f64;
                    let start = a + step;
                    // numpy.linspace(start, b, len), then numpy.around.
                    let d = if len > 1 {
                        (b - start) / (len - 1) as f64
                    } else {
                        0.0
                    };
                    for i in 0..len {
                        let v = if i + 1 == len && len > 1 {
                            b
                        } else {
                            start + i as f64 * d
                        };
                        lut.push(v.round_ties_even().clamp(0.0, 65535.0) as u16);
                    }
                }
            }
            2 => {
                if lut.is_empty() {
                    return Err("the first segment is an indirect one".into());
                }
                let offset = if bytes {
                    let b = data
                        .get(at..at + 4)
                        .ok_or("an indirect segment runs past the data")?;
                    at += 4;
                    (usize::from(b[3]) << 8 | usize::from(b[2])) << 16
                        | (usize::from(b[1]) << 8 | usize::from(b[0]))
                } else {
                    let w = data
                        .get(at..at + 2)
                        .ok_or("an indirect segment runs past the data")?;
                    at += 2;
                    usize::from(w[1]) << 16 | usize::from(w[0])
                };
                let rest = data
                    .get(offset..)
                    .ok_or("an indirect segment points past the data")?;
                expand(rest, bytes, Some(len), lut, depth + 1)?;
            }
            op => return Err(format!("unknown segment type {op}")),
        }
        if lut.len() > MAX_ENTRIES {
            return Err(format!("the segments expand past {MAX_ENTRIES} entries"));
        }
        read += 1;
        if Some(read) == segments {
            return Ok(());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lut_maps_and_clamps() {
        let l = Lut {
            first: -2,
            entries: vec![10, 20, 30],
            bits8: true,
        };
        assert_eq!(
            [-5, -2, -1, 0, 1, 99].map(|v| l.map(v)),
            [10, 10, 20, 30, 30, 30]
        );
    }

    #[test]
    fn segmented_palette_expands_as_pydicom() {
        // Discrete 3 entries, a linear ramp of 4 to 100, then the first 1 segment again.
        let data = [0, 3, 0, 10, 20, 1, 4, 100, 2, 1, 0, 0];
        let lut = expand_segmented(&data, false).unwrap();
        // linspace(20 + 20, 100, 4), as pydicom gives it.
        assert_eq!(lut, vec![0, 10, 20, 40, 60, 80, 100, 0, 10, 20]);
        assert!(expand_segmented(&[1, 2, 5], false).is_err());
        assert!(expand_segmented(&[0, 5, 1], false).is_err());
        // An indirect segment pointing at itself stops at the depth limit.
        let e = expand_segmented(&[0, 1, 7, 2, 1, 7, 0, 2, 1, 0, 0], false).unwrap_err();
        assert!(e.contains("8 deep"), "{e}");
    }
}
