//! What each frame of a multi-frame file says about itself: its position (the per-frame
//! Plane Position Sequence of an enhanced image, PS3.3 C.7.6.16.2.3, or an RT Dose's
//! GridFrameOffsetVector, C.8.8.3.2), its RescaleSlope / RescaleIntercept (Pixel Value
//! Transformation Sequence, C.7.6.16.2.9) and what tells it apart from frames at the same
//! position (module `volumes`).
use dicom_dictionary_std::tags;
use glam::DVec3;

use super::attrs::VolumeKey;
use super::attrs::{self, f64s, frame_group, ImageInfo, Obj};

/// One frame before it is read.
#[derive(Clone, Debug)]
pub(super) struct Frame {
    /// Its ImagePositionPatient.
    pub position: Option<DVec3>,
    /// `(RescaleSlope, RescaleIntercept)`.
    pub rescale: (f64, f64),
    /// What tells it apart from frames at the same position.
    pub key: VolumeKey,
}

/// The frames of `obj` (`frames` of them); notes say how RT Dose frames were placed.
pub(super) fn of_file(
    obj: &Obj,
    info: &ImageInfo,
    frames: usize,
    notes: &mut Vec<String>,
) -> Vec<Frame> {
    if frames <= 1 {
        return vec![Frame {
            position: info.position,
            rescale: info.rescale,
            key: info.key.clone(),
        }];
    }
    let mut out: Vec<Frame> = (0..frames)
        .map(|i| {
            let g = frame_group(obj, i);
            Frame {
                position: g
                    .and_then(|g| attrs::items(g, tags::PLANE_POSITION_SEQUENCE))
                    .and_then(|p| p.first())
                    .and_then(attrs::position),
                rescale: attrs::rescale(obj, g),
                key: super::volumes::key(obj, g),
            }
        })
        .collect();
    if out.iter().all(|f| f.position.is_none()) {
        if let Some(p) = grid_frame_positions(obj, info, frames, notes) {
            for (f, p) in out.iter_mut().zip(p) {
                f.position = Some(p);
            }
        }
    }
    out
}

/// The frame positions of an RT Dose (PS3.3 C.8.8.3.2): GridFrameOffsetVector holds one
/// offset a frame along the normal of ImageOrientationPatient. When its first value is 0 the
/// offsets are relative to ImagePositionPatient (type 1); otherwise they are the frames'
/// z coordinates (type 2, allowed only for the axial orientation 1\0\0\0\1\0).
fn grid_frame_positions(
    obj: &Obj,
    info: &ImageInfo,
    frames: usize,
    notes: &mut Vec<String>,
) -> Option<Vec<DVec3>> {
    let offsets = f64s(obj, tags::GRID_FRAME_OFFSET_VECTOR)?;
    let ipp = attrs::position(obj)?;
    if offsets.len() != frames {
        notes.push(format!(
            "GridFrameOffsetVector has {} offsets for {frames} frames: not used",
            offsets.len()
        ));
        return None;
    }
    let o = info.orientation.unwrap_or([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let n = DVec3::new(o[0], o[1], o[2]).cross(DVec3::new(o[3], o[4], o[5]));
    if n.length() < 1e-6 {
        return None;
    }
    let n = n.normalize();
    let axial = (n - DVec3::Z).length() < 1e-6;
    if offsets[0] == 0.0 || !axial {
        if offsets[0] != 0.0 {
            notes.push(
                "GridFrameOffsetVector starts with a non-zero offset in a non-axial \
                 orientation: read as offsets from ImagePositionPatient"
                    .into(),
            );
        }
        notes.push(
            "frames placed by GridFrameOffsetVector (offsets from ImagePositionPatient along \
             the slice normal)"
                .into(),
        );
        return Some(offsets.iter().map(|&d| ipp + d * n).collect());
    }
    notes.push("frames placed by GridFrameOffsetVector (z coordinates)".into());
    Some(
        offsets
            .iter()
            .map(|&z| DVec3::new(ipp.x, ipp.y, z))
            .collect(),
    )
}
