//! Tetrahedral meshes resampled onto a regular grid by barycentric interpolation.
//!
//! Each grid point inside a tet gets the linear interpolant of the tet's vertex scalars (exact
//! for the piecewise-linear field); points outside every tet are NaN, which the sampler treats
//! as "no data", so non-convex meshes keep their holes. [`ResampleRenderer`] ray casts the
//! result with the grid ray caster ([`Method::Resample`]): an alternative to cell projection
//! and cell-to-cell ray casting whose error is the trilinear re-interpolation of the
//! piecewise-linear field, O(h^2) in the grid spacing. The resampled grid has the mesh's
//! world placement (origin at the mesh's bounding-box corner, unrotated), so the scene's
//! clipping planes pass to the grid ray caster unchanged, which clips its rays exactly
//! (seed `004` sec. 4).
use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;
use volux_core::limits::{check_alloc, count_of};
use volux_core::TetMesh;

use crate::error::RenderError;
use crate::frame::Frame;
use crate::raycast::{grid_frame, render_field, Placement, RenderOptions};
use crate::renderer::{wrong_method, Renderer};
use crate::sampling::Trilinear;
use crate::scene::{Method, Scene};
use crate::tiles::Control;

/// A mesh resampled on a grid: f32 values (NaN outside the mesh) and their placement.
#[derive(Clone, Debug)]
pub struct Resampled {
    /// Values, x fastest, NaN outside the mesh.
    pub values: Vec<f32>,
    /// Where the grid sits in the world.
    pub place: Placement,
}

/// Resamples `mesh` onto a grid whose longest side has `max_dim` samples.
pub fn resample_mesh(mesh: &TetMesh, max_dim: usize) -> Result<Resampled, volux_core::Error> {
    let b = mesh.bounds();
    let ext = (b.max - b.min).max(DVec3::splat(1e-12));
    let h = ext.max_element() / (max_dim.max(2) - 1) as f64;
    let dims = [0, 1, 2].map(|a| ((ext[a] / h).ceil() as usize + 1).max(2));
    let bytes = check_alloc("the resampled grid", count_of(&dims), 4)?;
    let mut values = vec![f32::NAN; (bytes / 4) as usize];
    let pos = mesh.positions();
    let sc = mesh.scalars();
    for tet in mesh.tets() {
        let p = tet.map(|v| pos[v as usize].as_dvec3());
        let s = tet.map(|v| sc[v as usize] as f64);
        let (e1, e2, e3) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
        let det = e1.cross(e2).dot(e3);
        if det.abs() < 1e-300 {
            continue;
        }
        let (lo, hi) = (
            p[0].min(p[1]).min(p[2]).min(p[3]),
            p[0].max(p[1]).max(p[2]).max(p[3]),
        );
        let i0 = ((lo - b.min) / h).map(|v| v.ceil().max(0.0));
        let i1 = ((hi - b.min) / h).map(|v| v.floor());
        let tol = 1e-9;
        for k in i0.z as usize..=(i1.z.max(-1.0) as usize).min(dims[2] - 1) {
            for j in i0.y as usize..=(i1.y.max(-1.0) as usize).min(dims[1] - 1) {
                for i in i0.x as usize..=(i1.x.max(-1.0) as usize).min(dims[0] - 1) {
                    let q = b.min + DVec3::new(i as f64, j as f64, k as f64) * h - p[0];
                    // Barycentric coordinates by Cramer's rule.
                    let l1 = q.cross(e2).dot(e3) / det;
                    let l2 = e1.cross(q).dot(e3) / det;
                    let l3 = e1.cross(e2).dot(q) / det;
                    let l0 = 1.0 - l1 - l2 - l3;
                    if l0 >= -tol && l1 >= -tol && l2 >= -tol && l3 >= -tol {
                        let v = l0 * s[0] + l1 * s[1] + l2 * s[2] + l3 * s[3];
                        values[i + dims[0] * (j + dims[1] * k)] = v as f32;
                    }
                }
            }
        }
    }
    Ok(Resampled {
        values,
        place: Placement {
            origin: b.min,
            spacing: DVec3::splat(h),
            dims,
            direction: glam::DMat3::IDENTITY,
        },
    })
}

/// Ray casting of a mesh resampled onto a grid; the resampled grid is kept while the
/// number of samples does not change.
pub struct ResampleRenderer {
    mesh: Arc<TetMesh>,
    resampled: Option<(usize, Resampled)>,
}

impl ResampleRenderer {
    /// A renderer for `mesh`; the grid is built on the first frame.
    pub fn new(mesh: Arc<TetMesh>) -> Self {
        Self {
            mesh,
            resampled: None,
        }
    }
}

impl Renderer for ResampleRenderer {
    fn name(&self) -> &'static str {
        "resample"
    }

    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError> {
        let started = Instant::now();
        let Method::Resample { samples, raycast } = scene.method else {
            return Err(wrong_method("resample", &scene.method));
        };
        scene.validate()?;
        crate::renderer::no_voxel_layers("resample", scene)?;
        let built = !matches!(&self.resampled, Some((n, _)) if *n == samples);
        if built {
            self.resampled = Some((samples, resample_mesh(&self.mesh, samples)?));
        }
        let Some((_, r)) = self.resampled.as_ref() else {
            return Err(RenderError::Internal(
                "the resampled grid is missing".into(),
            ));
        };
        let field = Trilinear::new(&r.values, r.place.dims);
        let opts = RenderOptions::from_scene(scene, &raycast, control);
        let mut out = render_field(&field, r.place, self.mesh.range(), &opts)?;
        out.stats.rebuilt.data = built;
        Ok(grid_frame(out, &raycast, started))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_field_is_reproduced_and_holes_stay_empty() {
        let m = volux_core::synth::torus_tets(24).unwrap();
        let r = resample_mesh(&m, 40).unwrap();
        let d = r.place.dims;
        // The centre of the torus hole is outside the mesh.
        let c = [d[0] / 2, d[1] / 2, d[2] / 2];
        assert!(r.values[c[0] + d[0] * (c[1] + d[1] * c[2])].is_nan());
        let inside = r.values.iter().filter(|v| !v.is_nan()).count();
        assert!(inside > 100);
        let g = volux_core::synth::smooth_tets(5 * 27).unwrap();
        let r = resample_mesh(&g, 7).unwrap();
        assert!(
            r.values.iter().all(|v| v.is_finite()),
            "a cube mesh covers its whole grid"
        );
    }
}
