//! Clipping planes in Projected Tetrahedra (seed `004` sec. 4): each pixel's ray is kept
//! only where it is inside every plane, a window `[z_in, z_out]` of view depth (the plane
//! distances are linear along the ray), and every fragment is trimmed to its pixel's window
//! as the tet ray caster trims its segments: the front moves to `max(z_f, z_in)`, the back
//! to `min(z_b, z_out)`, the scalars (and gradients) are interpolated linearly along the
//! segment at the new ends (the field is linear in the cell, and view depth is an affine
//! function of the ray parameter), and a fragment wholly outside is dropped. Cells with all
//! four vertices outside one plane are culled before rasterization ([`outside_a_plane`]).
use glam::{DVec3, Vec3};
use volux_core::voi::{clip_by_planes, ClipPlane};
use volux_core::Camera;

use crate::tiles::Rect;

/// A pixel's window of view depth `[z_in, z_out]`; empty (`z_in > z_out`) when the pixel's
/// ray is outside some plane everywhere.
pub type Window = [f32; 2];

/// The window of a ray that no plane clips.
pub const ALL: Window = [f32::NEG_INFINITY, f32::INFINITY];

/// The windows of the pixels of `rect` in a `width x height` image, row by row: per pixel,
/// the part of its centre's ray ([`Camera::ray`]) inside all `planes`, in view depth.
pub fn tile_windows(
    camera: &Camera,
    (width, height): (usize, usize),
    planes: &[ClipPlane],
    rect: Rect,
) -> Vec<Window> {
    let rays = camera.rays(width, height);
    let (_, _, forward) = camera.basis();
    let mut out = Vec::with_capacity(rect.area());
    for y in rect.y0..rect.y1 {
        for x in rect.x0..rect.x1 {
            let r = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
            // Scaled so that the ray parameter is the view depth (the origin is on the eye
            // plane in both projections).
            let dir = r.dir / r.dir.dot(forward);
            let all = (f64::NEG_INFINITY, f64::INFINITY);
            out.push(match clip_by_planes(planes, r.origin, dir, all) {
                Some((z0, z1)) => [z0 as f32, z1 as f32],
                None => [f32::INFINITY, f32::NEG_INFINITY],
            });
        }
    }
    out
}

/// A fragment's segment along its pixel's ray: front and back view depth and scalar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthSpan {
    /// Front depth.
    pub z_f: f32,
    /// Front scalar.
    pub s_f: f32,
    /// Back depth.
    pub z_b: f32,
    /// Back scalar.
    pub s_b: f32,
}

impl DepthSpan {
    /// The part of the span inside `[z0, z1]` and the fractions of the old span at its new
    /// ends (for interpolating other attributes); `None` when none of it is inside (a span
    /// that only touches the window is outside, as in the tet ray caster's trim).
    #[inline(always)]
    pub fn trim(self, [z0, z1]: Window) -> Option<(DepthSpan, [f32; 2])> {
        if self.z_b <= z0 || self.z_f >= z1 || z0 > z1 {
            return None;
        }
        let d = self.z_b - self.z_f;
        let (a, b) = if d > 0.0 {
            let frac = |z: f32| (z - self.z_f) / d;
            (frac(self.z_f.max(z0)), frac(self.z_b.min(z1)))
        } else {
            (0.0, 1.0)
        };
        let at = |f: f32| self.s_f + (self.s_b - self.s_f) * f;
        let span = DepthSpan {
            z_f: self.z_f.max(z0),
            s_f: if a > 0.0 { at(a) } else { self.s_f },
            z_b: self.z_b.min(z1),
            s_b: if b < 1.0 { at(b) } else { self.s_b },
        };
        Some((span, [a, b]))
    }
}

/// Front and back gradients `g` of a span moved to the fractions `ends` of it.
#[inline]
pub fn trim_gradients((g_f, g_b): (Vec3, Vec3), [a, b]: [f32; 2]) -> (Vec3, Vec3) {
    let at = |f: f32| if f < 1.0 { g_f + (g_b - g_f) * f } else { g_b };
    (at(a), at(b))
}

/// Whether all four vertices `p` are strictly outside one of `planes`: no point of the
/// cell is drawn, so the cell can be culled.
#[inline]
pub fn outside_a_plane(planes: &[ClipPlane], p: &[DVec3; 4]) -> bool {
    planes
        .iter()
        .any(|pl| p.iter().all(|&v| pl.distance(v) < 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_span_is_trimmed_to_the_window_with_linear_scalars() {
        let s = DepthSpan {
            z_f: 1.0,
            s_f: 0.0,
            z_b: 5.0,
            s_b: 8.0,
        };
        let (t, f) = s.trim([2.0, 4.0]).unwrap();
        assert_eq!(
            (t, f),
            (
                DepthSpan {
                    z_f: 2.0,
                    s_f: 2.0,
                    z_b: 4.0,
                    s_b: 6.0
                },
                [0.25, 0.75]
            )
        );
        assert_eq!(s.trim(ALL), Some((s, [0.0, 1.0])));
        assert_eq!(s.trim([6.0, 9.0]), None);
        assert_eq!(s.trim([-1.0, 0.5]), None);
        assert_eq!(s.trim([3.0, 2.0]), None);
        let g = trim_gradients((Vec3::ZERO, Vec3::X * 4.0), f);
        assert_eq!(g, (Vec3::X, Vec3::X * 3.0));
    }

    #[test]
    fn cells_outside_one_plane_are_culled() {
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let keep_right = |x: f64| ClipPlane::new(1.0, 0.0, 0.0, -x).unwrap();
        assert!(outside_a_plane(&[keep_right(1.5)], &p));
        assert!(!outside_a_plane(&[keep_right(0.5)], &p));
        // Touching the plane is not outside.
        assert!(!outside_a_plane(&[keep_right(1.0)], &p));
        assert!(!outside_a_plane(&[], &p));
    }
}
