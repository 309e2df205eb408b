//! What an interactive front end shows while the user drags, and how a volume larger than
//! memory refines: the preview policy and the level-of-detail ladder, once for every
//! interactive front end (the viewer's render thread today, a notebook widget next).
//!
//! - While the user interacts, each frame is a **preview** at `1 / divisor` of the
//!   resolution, the divisor sized from the last preview's cost so that a preview takes about
//!   [`PREVIEW_BUDGET_MS`] ([`PreviewPolicy`]), with a fixed-step integrator in place of an
//!   error-controlled one ([`preview_method`]); the scene's own method draws the full frame
//!   once input stops.
//! - A bricked volume (a store rendered out of core) refines by level instead: the coarsest
//!   level at once, then each finer level down to the one its [`Lod`] picks for the view
//!   ([`lod_ladder`]), each level a frame drawn by a renderer from the
//!   [`RendererFactory`](crate::RendererFactory), so that a GPU backend draws it through its
//!   brick pool.
use std::sync::Arc;

use volux_render::bricked::{BrickedRenderer, BrickedVolume, Lod};
use volux_render::engine::Frame;
use volux_render::integrate::integrator::Integrator;
use volux_render::integrate::segment::SegmentRule;
use volux_render::scene::{Method, Scene};

/// Time a preview frame aims at (ms): the divisor of the resolution adapts to meet it.
pub const PREVIEW_BUDGET_MS: f64 = 25.0;

/// Coarsest preview: 1/8 of the resolution on each side.
pub const MAX_DIVISOR: usize = 8;

/// The divisor of the first preview, before any cost is measured.
pub const FIRST_DIVISOR: usize = 4;

/// The method a preview uses: the scene's, with adaptive or reference integration replaced
/// by fixed steps of one unit (the error-controlled frame follows when input stops).
pub fn preview_method(method: &Method) -> Method {
    match *method {
        Method::GridRaycast(mut g) => {
            if matches!(
                g.integrator,
                Integrator::AdaptiveSimpson(_) | Integrator::Reference
            ) {
                g.integrator = Integrator::Riemann { step: 1.0 };
            }
            Method::GridRaycast(g)
        }
        Method::TetRaycast(SegmentRule::AdaptiveSimpson(_)) => Method::TetRaycast(SegmentRule::Psi),
        m => m,
    }
}

/// The size of previews: the last preview's cost per pixel, and the divisor that meets
/// [`PREVIEW_BUDGET_MS`] at that cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PreviewPolicy {
    ns_per_pixel: Option<f64>,
}

impl PreviewPolicy {
    /// The divisor of the resolution of `scene`'s next preview: [`FIRST_DIVISOR`] before
    /// any preview was measured, then the one whose preview takes about
    /// [`PREVIEW_BUDGET_MS`], between 1 and [`MAX_DIVISOR`].
    pub fn divisor(&self, scene: &Scene) -> usize {
        let pixels = (scene.view.width * scene.view.height) as f64;
        match self.ns_per_pixel {
            None => FIRST_DIVISOR,
            Some(ns) => {
                let ms_full = pixels * ns * 1e-6;
                let k = (ms_full / PREVIEW_BUDGET_MS).sqrt().ceil() as usize;
                k.clamp(1, MAX_DIVISOR)
            }
        }
    }

    /// Records the cost of a preview `frame`.
    pub fn measured(&mut self, frame: &Frame) {
        let px = frame.stats.pixels.max(1) as f64;
        self.ns_per_pixel = Some(frame.stats.ms * 1e6 / px);
    }
}

/// The level `lod` picks for `scene` (the end of refinement).
pub fn target_level(volume: &Arc<BrickedVolume>, lod: Lod, scene: &Scene) -> usize {
    BrickedRenderer::new(volume.clone(), lod).level_for(scene)
}

/// The levels to draw for `scene`, one frame each: the coarsest level first (a few
/// chunks, on screen at once), then every finer level down to [`target_level`].
pub fn lod_ladder(volume: &Arc<BrickedVolume>, lod: Lod, scene: &Scene) -> Vec<usize> {
    let coarsest = volume.levels().saturating_sub(1);
    let target = target_level(volume, lod, scene).min(coarsest);
    (target..=coarsest).rev().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_render::integrate::adaptive::{AdaptiveParams, StepControl};
    use volux_render::scene::{GridRaycast, Volume};

    fn adaptive_params() -> AdaptiveParams {
        AdaptiveParams {
            tol: 0.01,
            h0: 0.5,
            hmin: 0.001,
            hmax: 0.5,
            control: StepControl::Coupled,
            early_termination: None,
        }
    }

    #[test]
    fn previews_use_fixed_steps() {
        let adaptive = Method::GridRaycast(GridRaycast {
            integrator: Integrator::AdaptiveSimpson(adaptive_params()),
            ..GridRaycast::default()
        });
        let Method::GridRaycast(g) = preview_method(&adaptive) else {
            panic!()
        };
        assert_eq!(g.integrator, Integrator::Riemann { step: 1.0 });
        let tet = Method::TetRaycast(SegmentRule::AdaptiveSimpson(adaptive_params()));
        assert_eq!(preview_method(&tet), Method::TetRaycast(SegmentRule::Psi));
        let plain = Method::GridRaycast(GridRaycast::default());
        assert_eq!(preview_method(&plain), plain);
        let reference = Method::GridRaycast(GridRaycast {
            integrator: Integrator::Reference,
            ..GridRaycast::default()
        });
        assert_eq!(preview_method(&reference), preview_method(&adaptive));
    }

    #[test]
    fn the_divisor_meets_the_budget_at_the_measured_cost() {
        let volume = Volume::from(volux_core::synth::marschner_lobb(8).unwrap());
        let camera = volux_core::CameraSpec::default()
            .resolve(&volume.bounds())
            .unwrap();
        let scene = Scene::new(camera, 400, 400, volume.preset_tf("auto").unwrap());
        let mut policy = PreviewPolicy::default();
        assert_eq!(policy.divisor(&scene), FIRST_DIVISOR);
        // 160,000 pixels at 625 ns each: 100 ms in full, so 1/2 on a side meets 25 ms.
        policy.ns_per_pixel = Some(625.0);
        assert_eq!(policy.divisor(&scene), 2);
        policy.ns_per_pixel = Some(1e9);
        assert_eq!(policy.divisor(&scene), MAX_DIVISOR);
        policy.ns_per_pixel = Some(1.0);
        assert_eq!(policy.divisor(&scene), 1);
    }
}
