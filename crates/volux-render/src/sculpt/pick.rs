//! Picking the visible surface under a pixel (seed `004` sec. 4.5 and 6.2): the first point
//! along the pixel's ray, after the clipping planes and the sculpt mask, where the accumulated
//! opacity reaches a threshold. The digger removes a ball there; measurement and region
//! labelling take their points there.
//!
//! The ray is sampled every `step` with the exact transfer function in f64 (the renderers'
//! Riemann model: each sample's extinction holds over the step after it), and the crossing
//! is placed inside its step exactly for that model (`s = ln((1 - a0) / (1 - threshold)) /
//! tau`), so the point moves continuously with the threshold. An isosurface crossing adds its
//! opacity where the linearly interpolated value meets the isovalue, as the renderers draw it.
use glam::DVec3;
use volux_core::voi::clip_by_planes;
use volux_core::{Grid, TransferFunction};

use super::masked::Masked;
use crate::error::{RenderError, Setting, SettingError};
use crate::integrate::Integrator;
use crate::isosurface::Isovalue;
use crate::raycast::clip::ray_box;
use crate::raycast::options::Placement;
use crate::sampling::{Field, Trilinear};
use crate::scene::{Method, Scene};

/// The opacity at which [`pick`] finds the surface by default.
pub const DEFAULT_PICK_OPACITY: f64 = 0.5;

/// A point on the visible surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The world point.
    pub world: DVec3,
    /// Its distance from the ray's origin (the eye in perspective), world units.
    pub distance: f64,
    /// Its depth along the camera's forward axis (for converting screen sizes at it).
    pub depth: f64,
}

/// The first point of `scene` on `grid` along the ray through pixel (`px`, `py`) (continuous
/// pixel coordinates, x right, y down, centres at +0.5) where the accumulated opacity reaches
/// `threshold` (in (0, 1)), after the scene's clipping planes and mask; `None` when the ray
/// stays under it. The step is the scene's Riemann step, else half a voxel.
pub fn pick(
    grid: &Grid,
    scene: &Scene,
    (px, py): (f64, f64),
    threshold: f64,
) -> Result<Option<SurfacePoint>, RenderError> {
    if !(px.is_finite() && py.is_finite()) {
        return Err(
            SettingError::new(Setting::PickPixel, format!("({px}, {py})"), "finite").into(),
        );
    }
    if !(threshold > 0.0 && threshold < 1.0) {
        return Err(SettingError::new(Setting::PickThreshold, threshold, "in (0, 1)").into());
    }
    scene.validate()?;
    let (w, h) = (scene.view.width, scene.view.height);
    let ray = scene.view.camera.ray(px, py, w, h);
    let place = Placement::of(grid);
    let origin = place.point_to_local(ray.origin);
    let dir = place.vector_to_local(ray.dir);
    let Some(window) = ray_box(origin, dir, place.origin, place.origin + place.extent()) else {
        return Ok(None);
    };
    let planes = crate::raycast::local_clip_planes(&place, &scene.clip_planes);
    let Some(window) = clip_by_planes(&planes, origin, dir, window) else {
        return Ok(None);
    };
    let march = March {
        o_v: (origin - place.origin) / place.spacing,
        d_v: dir / place.spacing,
        window,
        step: step_of(scene) * place.spacing.min_element(),
        tf: scene.appearance.effective_tf().resolved(grid.range()),
        isovalues: scene.appearance.isosurfaces.as_slice(),
        threshold,
    };
    let t = volux_core::with_samples!(grid.samples(), |s| {
        let linear = Trilinear::new(s, grid.dims());
        match scene.mask.as_deref() {
            Some(mask) => march.first_hit(&Masked {
                inner: &linear,
                mask,
            }),
            None => march.first_hit(&linear),
        }
    });
    Ok(t.map(|t| {
        let world = ray.origin + ray.dir * t;
        let (_, _, forward) = scene.view.camera.basis();
        SurfacePoint {
            world,
            distance: t,
            depth: (world - scene.view.camera.eye).dot(forward),
        }
    }))
}

/// The step of picking, in voxels: the scene's Riemann step, else half a voxel.
fn step_of(scene: &Scene) -> f64 {
    match scene.method {
        Method::GridRaycast(g) => match g.integrator {
            Integrator::Riemann { step } | Integrator::Preintegrated { step } => step,
            _ => 0.5,
        },
        _ => 0.5,
    }
}

/// One ray's march: voxel-space origin and direction (world `t`), the clipped window, the
/// world step, the resolved TF and isovalues.
struct March<'a> {
    o_v: DVec3,
    d_v: DVec3,
    window: (f64, f64),
    step: f64,
    tf: TransferFunction,
    isovalues: &'a [Isovalue],
    threshold: f64,
}

impl March<'_> {
    /// The distance where the opacity first reaches the threshold.
    fn first_hit(&self, field: &impl Field) -> Option<f64> {
        let (t0, t1) = self.window;
        let mut alpha = 0.0f64;
        let mut prev: Option<(f64, f64)> = None;
        let mut t = t0;
        while t <= t1 {
            let v = field.sample64(self.o_v + self.d_v * t);
            if let (Some((tp, vp)), Some(v)) = (prev, v) {
                if let Some(hit) = self.iso_hit(&mut alpha, (tp, vp), (t, v)) {
                    return Some(hit);
                }
            }
            if let Some(v) = v {
                let tau = self.tf.tau_per_world(v);
                let h = self.step.min(t1 - t);
                let after = 1.0 - (1.0 - alpha) * (-tau * h).exp();
                if after >= self.threshold && tau > 0.0 {
                    let s = ((1.0 - alpha) / (1.0 - self.threshold)).ln() / tau;
                    return Some(t + s.clamp(0.0, h));
                }
                alpha = after;
            }
            prev = v.map(|v| (t, v));
            t += self.step;
        }
        None
    }

    /// Composites the isosurfaces crossed between two samples (nearest first) and returns
    /// the crossing where the opacity reaches the threshold.
    fn iso_hit(&self, alpha: &mut f64, (ta, va): (f64, f64), (tb, vb): (f64, f64)) -> Option<f64> {
        let mut hits: Vec<(f64, f64)> = self
            .isovalues
            .iter()
            .filter_map(|iso| {
                let c = f64::from(iso.value);
                let crosses = (va - c) * (vb - c) <= 0.0 && va != vb;
                crosses.then(|| {
                    (
                        ta + (tb - ta) * (c - va) / (vb - va),
                        f64::from(iso.rgba[3]),
                    )
                })
            })
            .collect();
        hits.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (t, a) in hits {
            *alpha += (1.0 - *alpha) * a;
            if *alpha >= self.threshold {
                return Some(t);
            }
        }
        None
    }
}
