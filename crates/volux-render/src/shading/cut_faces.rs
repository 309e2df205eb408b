//! The faces that cuts expose, lit with the cut's own normal.
//!
//! A clip plane or the sculpt mask cuts the volume along a surface that the data does not
//! have: inside homogeneous tissue the field's gradient there is small (unlit) or points
//! along the tissue's own boundaries, so a cut face looks like a flat decal. Seed `004`
//! (sec. 4) draws the volume of interest through clip planes and an interpolated mask and
//! cites Weiskopf, Engel and Ertl, "Interactive clipping techniques for texture-based
//! volume visualization and volume shading" (2003), who light a thin layer under the clip
//! surface with the clip geometry's normal instead of the gradient. Volux does the same:
//!
//! - behind a clip plane, within [`CutFaces::layer`] world units of it (at least one voxel
//!   and one lattice step, so every ray has a lit sample there), the normal is the plane's;
//! - where the sculpt mask's cell has kept and removed corners (the exposed surface and the
//!   voxel-thick layer under it, [`SculptMask::cut_gradient`]), the normal is the gradient
//!   of the interpolated mask, by central differences over a voxel on either side;
//! - elsewhere the field's gradient lights the sample as before.
//!
//! The replaced gradient has a length above the model's threshold, so cut faces are lit
//! whatever the data's gradient there. Isosurfaces keep the field's gradient: a cut through
//! an isosurface leaves its shell open, it exposes no face.
use glam::{DVec3, Vec3};
use volux_core::sculpt::SculptMask;
use volux_core::voi::ClipPlane;

use super::blinn_phong::BlinnPhong;
use super::lanes::Lanes3;
use crate::sampling::LANES;

/// A clip plane in voxel space: `a . p + b` is the world distance of voxel point `p` from
/// the plane (positive on the kept side), `normal` its unit normal in the grid's local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
struct VoxelPlane {
    a: Vec3,
    b: f32,
    normal: Vec3,
}

/// What lights the faces that clip planes and the sculpt mask expose (see the module docs).
#[derive(Clone, Debug)]
pub struct CutFaces<'a> {
    planes: Vec<VoxelPlane>,
    mask: Option<&'a SculptMask>,
    /// World units per voxel along each axis, inverted (mask gradients are per voxel).
    inv_spacing: Vec3,
    /// The depth behind a clip plane lit with its normal, world units.
    layer: f32,
    /// The length given to a cut normal: above the lighting model's threshold.
    strength: f32,
}

impl<'a> CutFaces<'a> {
    /// The cut faces of a grid with sample (0, 0, 0) at `origin` and `spacing` between
    /// samples (its local frame), cut by `planes` (in that frame) and `mask`, lit by
    /// `model`; the planes' normals light `layer` world units behind them. `None` when
    /// nothing is cut (no plane, and no mask or one that removes nothing).
    pub fn new(
        planes: &[ClipPlane],
        mask: Option<&'a SculptMask>,
        (origin, spacing): (DVec3, DVec3),
        model: &BlinnPhong,
        layer: f64,
    ) -> Option<Self> {
        let mask = mask.filter(|m| !m.is_untouched());
        if planes.is_empty() && mask.is_none() {
            return None;
        }
        let planes = planes
            .iter()
            .map(|p| VoxelPlane {
                a: (p.normal * spacing).as_vec3(),
                b: (p.normal.dot(origin) + p.offset) as f32,
                normal: p.normal.as_vec3(),
            })
            .collect();
        Some(Self {
            planes,
            mask,
            inv_spacing: spacing.recip().as_vec3(),
            layer: layer as f32,
            strength: Self::strength(model),
        })
    }

    /// The length given to a cut's normal under `model`: above its threshold, so that a cut
    /// face is lit whatever the data's gradient there.
    pub fn strength(model: &BlinnPhong) -> f32 {
        (model.min_gradient * 2.0).max(1.0)
    }

    /// The depth behind a clip plane lit with its normal, world units.
    pub fn layer(&self) -> f32 {
        self.layer
    }

    /// The cut's normal at voxel point `p` (a gradient of length above the model's
    /// threshold, world frame of the grid), or `None` where no cut face is near: the nearest
    /// clip plane within the layer first, then the sculpt mask's exposed surface.
    #[inline]
    pub fn normal(&self, p: Vec3) -> Option<Vec3> {
        self.plane_normal(p).or_else(|| self.mask_normal(p))
    }

    /// [`CutFaces::normal`] from the sculpt mask alone: where `p`'s cell is cut
    /// ([`SculptMask::cut_gradient`]), the central differences of the interpolated mask at
    /// one voxel on either side along each axis. Wider than the cell's own trilinear
    /// gradient, which follows the voxels' staircase (a carved ball's wall then leans up to
    /// 45 degrees off its true normal); the differences average two cells, as the field's
    /// gradient does.
    #[inline]
    fn mask_normal(&self, p: Vec3) -> Option<Vec3> {
        let mask = self.mask?;
        mask.cut_gradient(p.to_array())?;
        let g = Vec3::from(mask_differences(mask, p)) * self.inv_spacing;
        let n = g.normalize_or_zero();
        (n != Vec3::ZERO).then_some(n * self.strength)
    }

    /// The gradient that lights a volume sample at voxel point `p` whose field gradient is
    /// `g`: the cut's normal near a cut face, else `g`.
    #[inline]
    pub fn lighting_gradient(&self, p: Vec3, g: Vec3) -> Vec3 {
        self.normal(p).unwrap_or(g)
    }

    /// [`CutFaces::lighting_gradient`] of every lane: lane `l` at voxel point
    /// (`p[0][l]`, `p[1][l]`, `p[2][l]`) with field gradient `g[..][l]`, replaced in place.
    /// Only the lanes in the bit mask `mask_lanes` consult the sculpt mask (the others lie
    /// where the caller knows it hides nothing).
    #[allow(clippy::needless_range_loop)]
    #[inline]
    pub fn lighting_gradient_lanes(&self, p: &Lanes3, g: &mut Lanes3, mask_lanes: u32) {
        for l in 0..LANES {
            let point = Vec3::new(p[0][l], p[1][l], p[2][l]);
            let cut = if mask_lanes >> l & 1 == 1 {
                self.normal(point)
            } else {
                self.plane_normal(point)
            };
            if let Some(n) = cut {
                for a in 0..3 {
                    g[a][l] = n[a];
                }
            }
        }
    }

    /// [`CutFaces::normal`] from the clip planes alone.
    #[inline]
    fn plane_normal(&self, p: Vec3) -> Option<Vec3> {
        let mut nearest: Option<(f32, Vec3)> = None;
        for plane in &self.planes {
            let d = plane.a.dot(p) + plane.b;
            if (0.0..self.layer).contains(&d) && nearest.is_none_or(|(best, _)| d < best) {
                nearest = Some((d, plane.normal));
            }
        }
        nearest.map(|(_, n)| n * self.strength)
    }
}

/// The central differences of `mask`'s interpolated value at voxel point `p`, one voxel on
/// either side along each axis (points clamped to the grid as the mask clamps them), per
/// voxel.
#[inline]
pub fn mask_differences(mask: &SculptMask, p: Vec3) -> [f32; 3] {
    std::array::from_fn(|a| {
        let (mut lo, mut hi) = (p, p);
        lo[a] -= 1.0;
        hi[a] += 1.0;
        0.5 * (mask.value(hi.to_array()) - mask.value(lo.to_array()))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::sculpt::{Ball, VoxelFrame};

    fn model() -> BlinnPhong {
        BlinnPhong {
            min_gradient: 40.0,
            ..BlinnPhong::default()
        }
    }

    #[test]
    fn a_plane_lights_its_layer_with_its_normal_and_nothing_else() {
        // Spacing 2 x 1 x 0.5 from origin (10, 0, 0); the plane x = 20 keeps x >= 20.
        let plane = ClipPlane::new(1.0, 0.0, 0.0, -20.0).unwrap();
        let place = (DVec3::new(10.0, 0.0, 0.0), DVec3::new(2.0, 1.0, 0.5));
        let cuts = CutFaces::new(&[plane], None, place, &model(), 1.5).unwrap();
        // Voxel x = 5 is world x = 20: on the plane.
        let on = cuts.normal(Vec3::new(5.2, 3.0, 3.0)).unwrap();
        assert_eq!(on.normalize(), Vec3::X);
        assert!(on.length() >= 40.0, "lit above the threshold: {on}");
        // 1.6 world units behind it: past the layer; in front of it: cut away.
        assert_eq!(cuts.normal(Vec3::new(5.8, 3.0, 3.0)), None);
        assert_eq!(cuts.normal(Vec3::new(4.9, 3.0, 3.0)), None);
        let g = Vec3::new(0.0, 7.0, 0.0);
        assert_eq!(cuts.lighting_gradient(Vec3::new(9.0, 1.0, 1.0), g), g);
        // The lanes agree with the point, whichever lanes consult the mask.
        let p = [
            std::array::from_fn(|l| 4.5 + 0.1 * l as f32),
            [1.0; LANES],
            [0.0; LANES],
        ];
        for mask_lanes in [0, u32::MAX, 0b1010] {
            let mut gl = [[0.0f32; LANES]; 3];
            gl[1] = [7.0; LANES];
            cuts.lighting_gradient_lanes(&p, &mut gl, mask_lanes);
            for l in 0..LANES {
                let point = Vec3::new(p[0][l], p[1][l], p[2][l]);
                let want = cuts.lighting_gradient(point, g);
                assert_eq!(Vec3::new(gl[0][l], gl[1][l], gl[2][l]), want, "lane {l}");
            }
        }
        assert!(CutFaces::new(&[], None, place, &model(), 1.0).is_none());
    }

    #[test]
    fn a_carved_hole_is_lit_with_the_masks_normal_in_world_units() {
        let dims = [24, 24, 24];
        let spacing = DVec3::new(1.0, 1.0, 3.0);
        let mut mask = SculptMask::new(dims).unwrap();
        assert!(
            CutFaces::new(&[], Some(&mask), (DVec3::ZERO, spacing), &model(), 1.0).is_none(),
            "an untouched mask cuts nothing"
        );
        let grid = volux_core::Grid::new(
            dims,
            spacing.to_array(),
            [0.0; 3],
            volux_core::grid::Samples::U8(volux_core::grid::Buffer::owned(vec![0; 24 * 24 * 24])),
        )
        .unwrap();
        let frame = VoxelFrame::of(&grid);
        mask.remove(&Ball::new(DVec3::new(12.0, 12.0, 36.0), 7.0, frame).unwrap());
        let cuts = CutFaces::new(&[], Some(&mask), (DVec3::ZERO, spacing), &model(), 1.0).unwrap();
        // On the hole's wall along +x and along +z (world 7 from the centre), the normal
        // points out of the hole along that axis, in world units despite the spacing.
        let wall_x = cuts
            .normal(Vec3::new(18.9, 12.0, 12.0))
            .unwrap()
            .normalize();
        assert!(wall_x.x > 0.95, "{wall_x}");
        let wall_z = cuts
            .normal(Vec3::new(12.0, 12.0, 14.2))
            .unwrap()
            .normalize();
        assert!(wall_z.z > 0.95, "{wall_z}");
        // Far from the hole, and inside it, nothing.
        assert_eq!(cuts.normal(Vec3::new(2.0, 2.0, 2.0)), None);
        assert_eq!(cuts.normal(Vec3::new(12.0, 12.0, 12.0)), None);
        // A lane outside the mask lanes keeps its gradient.
        let mut p = [[0.0f32; LANES]; 3];
        p[0] = [18.9; LANES];
        p[1] = [12.0; LANES];
        p[2] = [12.0; LANES];
        let mut g = [[0.0f32; LANES]; 3];
        cuts.lighting_gradient_lanes(&p, &mut g, 1);
        assert!(g[0][0] > 0.0 && g[0][1] == 0.0);
    }
}
