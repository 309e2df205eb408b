//! Several volumes at the same positions in one series or enhanced multi-frame file: DWI
//! b-values and gradient directions, temporal positions, stacks. The frames (or slices) are
//! grouped by what tells them apart, one group is read ([`crate::VolumeChoice::timepoint`]),
//! and the grid records the axis ([`ExtraAxis`]).
//!
//! What tells the volumes apart, per frame or slice:
//! - DiffusionBValue (0018,9087) and DiffusionGradientOrientation (0018,9089), in the
//!   per-frame MR Diffusion Sequence (0018,9117) of an enhanced MR image (PS3.3 C.8.13.5.9)
//!   or at the top level; Siemens' private `B_value` (0019,xx0C) and `DiffusionGradient
//!   Direction` (0019,xx0E) of the "SIEMENS MR HEADER" block otherwise;
//! - TemporalPositionIndex (0020,9128) of the Frame Content Sequence (PS3.3 C.7.6.16.2.2)
//!   or TemporalPositionIdentifier (0020,0100) (PS3.3 C.7.6.1.1);
//! - StackID (0020,9056) of the Frame Content Sequence (PS3.3 C.7.6.16.2.2.4).
//!
//! The keys are used where they explain something: when they split the frames into several
//! groups of which one at least holds more than one frame, or frames share a position.
//! Otherwise (every frame its own key, at distinct positions) they are ignored and the frames
//! make one stack. Frames at the same position that no key tells apart remain an error
//! (module `geometry`).
use std::collections::HashSet;

use dicom_core::value::{PrimitiveValue, Value};
use dicom_dictionary_std::tags;
use dicom_object::mem::InMemElement;
use glam::DVec3;
use volux_core::volume_axes::{choose, AxisKind, ExtraAxis};

use super::attrs::{f64_1, f64s, grouped, int, items, private, string, Obj, VolumeKey};

/// The Siemens private block holding the diffusion attributes of classic MR images.
const SIEMENS_MR: &str = "SIEMENS MR HEADER";

/// The key of a data set, `frame` being the per-frame functional group of an enhanced
/// multi-frame image (its shared group and top level are looked at too).
pub(super) fn key(obj: &Obj, frame: Option<&Obj>) -> VolumeKey {
    let diffusion = tags::MR_DIFFUSION_SEQUENCE;
    let content = tags::FRAME_CONTENT_SEQUENCE;
    let b_value =
        grouped(obj, frame, diffusion, |o| f64_1(o, tags::DIFFUSION_B_VALUE)).or_else(|| {
            private_numbers(private(obj, 0x0019, SIEMENS_MR, 0x0C)?, Binary::Text)?
                .first()
                .copied()
        });
    let gradient = grouped(obj, frame, diffusion, |o| {
        items(o, tags::DIFFUSION_GRADIENT_DIRECTION_SEQUENCE)
            .and_then(|i| i.first())
            .and_then(vec3)
            .or_else(|| vec3(o))
    })
    .or_else(|| {
        let v = private_numbers(private(obj, 0x0019, SIEMENS_MR, 0x0E)?, Binary::F64)?;
        match v.as_slice() {
            [x, y, z] => Some([*x, *y, *z]),
            _ => None,
        }
    });
    let temporal = grouped(obj, frame, content, |o| {
        int(o, tags::TEMPORAL_POSITION_INDEX)
    })
    .or_else(|| int(obj, tags::TEMPORAL_POSITION_IDENTIFIER));
    let stack = grouped(obj, frame, content, |o| string(o, tags::STACK_ID));
    VolumeKey {
        temporal,
        b_value,
        gradient,
        stack,
    }
}

/// How a private value kept as bytes (an implicit-VR file's private element, whose VR no
/// dictionary gives) is encoded: Siemens' `B_value` is IS text, its gradient direction FD.
enum Binary {
    Text,
    F64,
}

/// The numbers of a private element: decoded as its VR says where the file gave one,
/// else from its bytes as `binary` says (little endian: implicit VR is little endian).
fn private_numbers(e: &InMemElement, binary: Binary) -> Option<Vec<f64>> {
    let v: Vec<f64> = match (e.value(), binary) {
        (Value::Primitive(PrimitiveValue::U8(b)), Binary::Text) => std::str::from_utf8(b)
            .ok()?
            .trim_matches(|c: char| c == '\0' || c.is_whitespace())
            .split('\\')
            .map(|t| t.trim().parse::<f64>().ok())
            .collect::<Option<_>>()?,
        (Value::Primitive(PrimitiveValue::U8(b)), Binary::F64) => {
            if b.len() % 8 != 0 {
                return None;
            }
            b.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                .collect()
        }
        _ => e.to_multi_float64().ok()?,
    };
    (!v.is_empty() && v.iter().all(|x| x.is_finite())).then_some(v)
}

/// DiffusionGradientOrientation of a data set.
fn vec3(o: &Obj) -> Option<[f64; 3]> {
    match f64s(o, tags::DIFFUSION_GRADIENT_ORIENTATION)?.as_slice() {
        [x, y, z] => Some([*x, *y, *z]),
        _ => None,
    }
}

/// The frames of the chosen volume and what the grid records about the others.
#[derive(Debug)]
pub(super) struct Picked {
    /// Indices (into the input) of the chosen volume's frames, in input order.
    pub frames: Vec<usize>,
    /// The axis along which the file holds several volumes.
    pub axis: Option<ExtraAxis>,
    /// What was read, for the grid's notes.
    pub notes: Vec<String>,
}

/// Groups `keys` (one per frame, in input order; `rank` orders the frames by acquisition,
/// e.g. InstanceNumber) into volumes and picks volume `timepoint`.
pub(super) fn pick(
    keys: &[VolumeKey],
    positions: &[Option<DVec3>],
    rank: &[usize],
    timepoint: usize,
) -> Result<Picked, volux_core::Error> {
    let all = || Picked {
        frames: (0..keys.len()).collect(),
        axis: None,
        notes: Vec::new(),
    };
    // Distinct keys in acquisition order, with their frames.
    let mut volumes: Vec<(VolumeKey, Vec<usize>)> = Vec::new();
    for &i in rank {
        let Some(k) = keys.get(i) else { continue };
        match volumes.iter_mut().find(|(v, _)| v == k) {
            Some((_, f)) => f.push(i),
            None => volumes.push((k.clone(), vec![i])),
        }
    }
    let largest = volumes.iter().map(|(_, f)| f.len()).max().unwrap_or(0);
    if volumes.len() <= 1 || (largest <= 1 && !shared_positions(positions)) {
        return Ok(all());
    }
    if volumes.iter().all(|(k, _)| k.temporal.is_some()) {
        volumes.sort_by_key(|(k, _)| k.temporal);
    }
    let n = volumes.len();
    let chosen = choose("timepoint", timepoint, n)?;
    let keys: Vec<&VolumeKey> = volumes.iter().map(|(k, _)| k).collect();
    let varies = |f: &dyn Fn(&VolumeKey) -> String| {
        keys.iter().map(|k| f(k)).collect::<HashSet<_>>().len() > 1
    };
    let axis = if varies(&|k| format!("{:?}", k.temporal)) {
        ExtraAxis::new(AxisKind::Time, n, Some(chosen)).with_values(
            keys.iter()
                .map(|k| k.temporal.map_or(f64::NAN, |t| t as f64))
                .collect(),
            "temporal position (TemporalPositionIndex / TemporalPositionIdentifier)",
        )
    } else if varies(&|k| format!("{:?}{:?}", k.b_value, k.gradient)) {
        ExtraAxis::new(AxisKind::Volume, n, Some(chosen)).with_values(
            keys.iter().map(|k| k.b_value.unwrap_or(f64::NAN)).collect(),
            "b-value (s/mm²)",
        )
    } else {
        let ids: Vec<String> = keys
            .iter()
            .map(|k| k.stack.clone().unwrap_or_else(|| "-".into()))
            .collect();
        ExtraAxis::new(AxisKind::Volume, n, Some(chosen))
            .with_meaning(format!("StackID {}", ids.join(", ")))
    };
    let (key, mut frames) = volumes.swap_remove(chosen);
    frames.sort_unstable();
    let what = describe(&key);
    let notes = vec![format!(
        "{n} volumes at the same positions ({}); timepoint {chosen} read ({what}, {} of {} \
         frames)",
        axis.meaning,
        frames.len(),
        rank.len()
    )];
    Ok(Picked {
        frames,
        axis: Some(axis),
        notes,
    })
}

/// A volume's key in words.
fn describe(k: &VolumeKey) -> String {
    let mut parts = Vec::new();
    if let Some(t) = k.temporal {
        parts.push(format!("temporal position {t}"));
    }
    if let Some(b) = k.b_value {
        parts.push(format!("b-value {b}"));
    }
    if let Some(g) = k.gradient {
        parts.push(format!("gradient [{}, {}, {}]", g[0], g[1], g[2]));
    }
    if let Some(s) = &k.stack {
        parts.push(format!("StackID {s}"));
    }
    if parts.is_empty() {
        "no key".into()
    } else {
        parts.join(", ")
    }
}

/// Whether two frames lie at the same position (within a micrometre).
fn shared_positions(positions: &[Option<DVec3>]) -> bool {
    let mut seen = HashSet::new();
    positions
        .iter()
        .flatten()
        .any(|p| !seen.insert((p * 1000.0).round().to_array().map(|v| v as i64)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(v: f64) -> VolumeKey {
        VolumeKey {
            b_value: Some(v),
            ..Default::default()
        }
    }

    fn at(z: &[f64]) -> Vec<Option<DVec3>> {
        z.iter().map(|&z| Some(DVec3::new(0.0, 0.0, z))).collect()
    }

    #[test]
    fn b_values_at_the_same_positions_make_volumes() {
        // 2 b-values x 3 slices, interleaved.
        let keys = [b(0.0), b(1000.0), b(0.0), b(1000.0), b(0.0), b(1000.0)];
        let pos = at(&[0.0, 0.0, 1.0, 1.0, 2.0, 2.0]);
        let rank: Vec<usize> = (0..6).collect();
        let p = pick(&keys, &pos, &rank, 1).unwrap();
        assert_eq!(p.frames, vec![1, 3, 5]);
        let a = p.axis.unwrap();
        assert_eq!((a.kind, a.len, a.chosen), (AxisKind::Volume, 2, Some(1)));
        assert_eq!(a.values, vec![0.0, 1000.0]);
        assert!(p.notes[0].contains("b-value 1000"), "{:?}", p.notes);
        let e = pick(&keys, &pos, &rank, 2).unwrap_err();
        assert!(matches!(
            e,
            volux_core::Error::NoSuchVolume {
                index: 2,
                len: 2,
                ..
            }
        ));
    }

    #[test]
    fn temporal_positions_are_sorted_and_make_a_time_axis() {
        let t = |v| VolumeKey {
            temporal: Some(v),
            ..Default::default()
        };
        let keys = [t(2), t(2), t(1), t(1)];
        let pos = at(&[0.0, 1.0, 0.0, 1.0]);
        let p = pick(&keys, &pos, &[0, 1, 2, 3], 0).unwrap();
        assert_eq!(p.frames, vec![2, 3]);
        let a = p.axis.unwrap();
        assert_eq!(a.kind, AxisKind::Time);
        assert_eq!(a.values, vec![1.0, 2.0]);
    }

    #[test]
    fn keys_that_explain_nothing_are_ignored() {
        // One key: one volume.
        let p = pick(&[b(0.0), b(0.0)], &at(&[0.0, 1.0]), &[0, 1], 0).unwrap();
        assert_eq!((p.frames, p.axis), (vec![0, 1], None));
        // Every frame its own key at distinct positions: one stack.
        let p = pick(&[b(0.0), b(5.0)], &at(&[0.0, 1.0]), &[0, 1], 0).unwrap();
        assert_eq!((p.frames, p.axis), (vec![0, 1], None));
        // Two single-slice volumes at one position (two DWI mosaics).
        let p = pick(&[b(0.0), b(5.0)], &at(&[0.0, 0.0]), &[0, 1], 1).unwrap();
        assert_eq!(p.frames, vec![1]);
    }
}
