//! The proxy geometry of texture slicing (seed `004` §3.3, Fig. 3.2 b): the volume of
//! interest (the grid's sample box cut by the clip planes, §4.3.2) swept by planes
//! perpendicular to the view direction `h` apart (the Weighted Sweep Graph of §4.2.2,
//! [`ConvexVoi::sweep`]), each slice polygon split into a fan of triangles, back to front.
use glam::DVec3;
use volux_core::voi::{ClipPlane, ConvexVoi};
use volux_core::{Aabb, Error};
use volux_render::backend_kit::Placement;

use crate::error::GpuError;

/// Where the slices are cut, in the grid's local frame (world units).
pub(crate) struct Sweep {
    /// The eye.
    pub(crate) eye: DVec3,
    /// The unit view direction: slices are perpendicular to it.
    pub(crate) forward: DVec3,
    /// The distance between slices.
    pub(crate) h: f64,
}

/// The triangles of the slices of the grid at `place` cut by `planes` (local frame), back
/// to front, three vertices each, as positions relative to the eye; none when nothing of the
/// grid is in front of the eye and inside the planes.
pub(crate) fn slice_triangles(
    place: &Placement,
    planes: &[ClipPlane],
    sweep: &Sweep,
) -> Result<Vec<[f32; 3]>, GpuError> {
    let Some(voi) = volume_of_interest(place, planes, sweep)? else {
        return Ok(Vec::new());
    };
    let slices = voi
        .sweep(sweep.forward, sweep.h)
        .map_err(|e| GpuError::OverLimit {
            what: format!("slicing at a step of {}", sweep.h),
            limit: e.to_string(),
        })?;
    let mut out = Vec::new();
    for polygon in slices.iter().rev() {
        fan(polygon, sweep.eye, &mut out);
    }
    Ok(out)
}

/// The sample box cut by `planes` and by a plane just in front of the eye (rays start at
/// the eye, or on its plane for orthographic cameras, as the ray caster's); `None` when
/// nothing is left.
fn volume_of_interest(
    place: &Placement,
    planes: &[ClipPlane],
    sweep: &Sweep,
) -> Result<Option<ConvexVoi>, GpuError> {
    let last = DVec3::from_array(place.dims.map(|n| n.saturating_sub(1) as f64));
    let bounds = Aabb {
        min: place.origin,
        max: place.origin + place.spacing * last,
    };
    let mut voi = match ConvexVoi::from_aabb(&bounds) {
        Ok(v) => v,
        Err(Error::EmptyVolumeOfInterest(_)) => return Ok(None),
        Err(e) => return Err(GpuError::Failed(e.to_string())),
    };
    let near = ClipPlane {
        normal: sweep.forward,
        offset: -sweep.forward.dot(sweep.eye) - 1e-6 * bounds.diagonal(),
    };
    for plane in planes.iter().chain([&near]) {
        match voi.cut(plane) {
            Ok(_) => {}
            Err(Error::EmptyVolumeOfInterest(_)) => return Ok(None),
            Err(e) => return Err(GpuError::Failed(e.to_string())),
        }
    }
    Ok(Some(voi))
}

/// The convex `polygon` as a fan of triangles from its first vertex, relative to `eye`.
fn fan(polygon: &[DVec3], eye: DVec3, out: &mut Vec<[f32; 3]>) {
    let at = |k: usize| (polygon[k] - eye).as_vec3().to_array();
    for k in 1..polygon.len().saturating_sub(1) {
        out.extend([at(0), at(k), at(k + 1)]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn place() -> Placement {
        Placement {
            origin: DVec3::new(1.0, 2.0, 3.0),
            spacing: DVec3::new(1.0, 0.5, 2.0),
            dims: [11, 21, 6],
            direction: glam::DMat3::IDENTITY,
        }
    }

    fn area(tris: &[[f32; 3]]) -> f64 {
        tris.chunks(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|p| DVec3::from_array(p.map(f64::from)));
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    #[test]
    fn axis_slices_of_a_box_are_its_cross_sections_back_to_front() {
        let sweep = Sweep {
            eye: DVec3::new(6.0, 7.0, -10.0),
            forward: DVec3::Z,
            h: 1.0,
        };
        let tris = slice_triangles(&place(), &[], &sweep).unwrap();
        // Planes z = 3, 4, ..., 13 through a 10 x 10 box: two triangles each, 100 in area
        // (the planes through the faces z = 3 and z = 13 only touch the box: no polygon).
        assert_eq!(tris.len() % 3, 0);
        let slices = tris.len() / 6;
        assert!((9..=11).contains(&slices), "{slices}");
        assert!((area(&tris) / slices as f64 - 100.0).abs() < 1e-3);
        let depth = |t: &[f32; 3]| t[2];
        assert!(depth(&tris[0]) > depth(&tris[tris.len() - 1]), "back first");
    }

    #[test]
    fn a_clip_plane_or_the_eye_plane_removing_everything_leaves_no_slice() {
        let sweep = Sweep {
            eye: DVec3::new(6.0, 7.0, -10.0),
            forward: DVec3::Z,
            h: 1.0,
        };
        let away = ClipPlane::new(1.0, 0.0, 0.0, -100.0).unwrap();
        assert!(slice_triangles(&place(), &[away], &sweep)
            .unwrap()
            .is_empty());
        let behind = Sweep {
            forward: -DVec3::Z,
            ..sweep
        };
        assert!(slice_triangles(&place(), &[], &behind).unwrap().is_empty());
        let half = ClipPlane::new(1.0, 0.0, 0.0, -6.0).unwrap();
        let cut = slice_triangles(&place(), &[half], &sweep).unwrap();
        assert!((area(&cut) / (cut.len() / 6) as f64 - 50.0).abs() < 1e-3);
    }
}
