//! Rendering a bricked volume: one level through its brick cache, as a field of the grid ray
//! caster ([`render_level`]), and the engine's [`Renderer`] for bricked volumes
//! ([`BrickedRenderer`]: grid ray casting, the level chosen per frame by its [`Lod`]).
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use glam::DMat3;

use super::cache::brick_bytes;
use super::field::BrickedField;
use super::prefetch;
use super::volume::{BrickedVolume, Lod};
use crate::classify::ClassifyTable;
use crate::error::{Refusal, Remedy, RenderError};
use crate::frame::Frame;
use crate::integrate::Integrator;
use crate::intervals::IntervalSource;
use crate::macrocell::Occupancy;
use crate::raycast::{
    grid_frame, grid_settings, render_field_in, Placement, RenderOptions, Rendered,
};
use crate::renderer::Renderer;
use crate::scene::Scene;
use crate::tiles::Control;

/// Grid ray casting of a [`BrickedVolume`], at the level its [`Lod`] picks for each frame.
pub struct BrickedRenderer {
    volume: Arc<BrickedVolume>,
    lod: Lod,
}

impl BrickedRenderer {
    /// A renderer of `volume` choosing levels by `lod`.
    pub fn new(volume: Arc<BrickedVolume>, lod: Lod) -> Self {
        Self { volume, lod }
    }

    /// The level the next frame of `scene` samples.
    pub fn level_for(&self, scene: &Scene) -> usize {
        let cam = &scene.view.camera;
        let centre = self.volume.bounds().center();
        let forward = (cam.target - cam.eye).normalize_or_zero();
        let depth = (centre - cam.eye).dot(forward);
        let pixel = crate::sculpt::pixel_size_at(cam, scene.view.height, depth);
        self.volume.level_for(self.lod, pixel)
    }
}

impl Renderer for BrickedRenderer {
    fn name(&self) -> &'static str {
        "raycast"
    }

    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError> {
        let started = Instant::now();
        let settings = grid_settings(scene)?;
        let opts = RenderOptions::from_scene(scene, &settings, control);
        let r = render_level(&self.volume, self.level_for(scene), &opts)?;
        Ok(grid_frame(r, &settings, started))
    }
}

/// Renders level `level` with `opts` (trilinear reconstruction; no sculpt mask or
/// labels: they are full-resolution voxel layers of in-core grids). A chunk that cannot
/// be read stops the render with an error naming it; no image is returned.
pub fn render_level(
    volume: &BrickedVolume,
    level: usize,
    opts: &RenderOptions,
) -> Result<Rendered, RenderError> {
    refuse_voxel_layers(opts)?;
    let cache = volume.cache(level).ok_or(RenderError::NoSuchLevel {
        level,
        levels: volume.levels(),
    })?;
    let range = volume.range();
    let failed = Arc::new(AtomicBool::new(false));
    let field = BrickedField::for_render(cache, failed.clone());
    let opts = stopped_by(opts, failed);
    let table = ClassifyTable::new(&opts.tf, range, ClassifyTable::DEFAULT_SIZE);
    let isovalues: Vec<f32> = opts
        .isosurfaces
        .as_slice()
        .iter()
        .map(|i| i.value)
        .collect();
    // Chunks whose range the TF makes transparent are skipped (intervals cost a walk of
    // the chunks a ray crosses, a few per ray: only when some are empty). Not under MIP,
    // and not for adaptive Simpson, whose subdivision would start afresh in every interval
    // (measured: within its tolerance of the in-core image, 4.6e-4, not within 1e-6).
    let adaptive = matches!(opts.integrator, Integrator::AdaptiveSimpson(_));
    let occupancy = volume
        .chunk_cells(level)
        .filter(|_| !opts.mip && !adaptive)
        .map(|cells| Occupancy::new(cells, &table, &isovalues));
    let intervals = occupancy
        .as_ref()
        .filter(|o| o.empty_fraction() > 0.0)
        .map(|o| o as &dyn IntervalSource);
    // The frame's chunks read ahead of its rays, nearest first, on a worker thread.
    let layout = cache.layout();
    let ahead = prefetch::plan(
        layout,
        occupancy.as_ref(),
        opts.camera.eye,
        brick_bytes(layout.chunk),
        cache.budget(),
    );
    let ahead: Vec<[usize; 3]> = ahead
        .into_iter()
        .filter(|&c| !cache.is_resident(c))
        .collect();
    let stop = AtomicBool::new(false);
    let out = std::thread::scope(|s| {
        // A warm frame (all its chunks resident) starts no worker.
        let worker = (!ahead.is_empty()).then(|| s.spawn(|| prefetch::run(cache, &ahead, &stop)));
        let out = render_field_in(&field, placement(layout), range, intervals, &opts);
        stop.store(true, Ordering::Relaxed);
        if let Some(w) = worker {
            let _ = w.join();
        }
        out
    });
    field.forget();
    match field.error() {
        Some(e) => Err(RenderError::Data(volux_core::Error::Chunked(e.clone()))),
        None => out,
    }
}

/// The world placement of a chunked level (axis-aligned).
fn placement(l: &volux_core::bricked::ChunkLayout) -> Placement {
    Placement {
        origin: l.origin_vec(),
        spacing: l.spacing_vec(),
        dims: l.dims,
        direction: DMat3::IDENTITY,
    }
}

/// Masks, labels and cubic filters are refused with the reason.
fn refuse_voxel_layers(opts: &RenderOptions) -> Result<(), RenderError> {
    use crate::sampling::Reconstruction;
    let what = if opts.mask.is_some() {
        "a sculpt mask"
    } else if opts.labels.is_some() {
        "region labels"
    } else if opts.reconstruction != Reconstruction::Trilinear {
        "cubic reconstruction"
    } else {
        return Ok(());
    };
    Err(Refusal::new(
        "out-of-core rendering",
        format!(
            "samples bricks trilinearly and has no voxel layers: {what} needs the volume in memory"
        ),
        Some(Remedy::LoadLevel),
    )
    .into())
}

/// `opts` with `failed` as its cancel flag, so that a chunk error stops the render early (a
/// caller's own flag is left alone).
pub(super) fn stopped_by(opts: &RenderOptions, failed: Arc<AtomicBool>) -> RenderOptions {
    let mut opts = opts.clone();
    if opts.control.cancel.is_none() {
        opts.control = Control {
            cancel: Some(failed),
            progress: opts.control.progress.clone(),
        };
    }
    opts
}
