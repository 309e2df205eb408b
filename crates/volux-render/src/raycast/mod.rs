//! Image-order traversal of regular grids: one ray per pixel, exact ray/box entry and exit,
//! front-to-back compositing with early ray termination, parallel over square image tiles.
//!
//! Each ray is handed to one of the [`Integrator`]s of [`crate::integrate`] as a
//! [`RayMedium`](crate::integrate::RayMedium) (trilinear reconstruction of [`crate::sampling`], classification of
//! [`crate::classify`]); steps are given in voxel units (the smallest spacing), as in the seed
//! `001_...txt`. A tile takes one of these paths:
//!
//! - Riemann sums and pre-integration, emission only or shaded with the cached gradient
//!   volume: the lane stream (`raycast/stream.rs`), 16 rays advanced together;
//! - adaptive Simpson with coupled control, emission only or shaded with the cached gradient
//!   volume: `raycast/adaptive_stream.rs`, four rays' steps sampled and judged together in
//!   f32 lanes;
//! - maximum intensity projection: `raycast/mip_stream.rs`, 16 rays sampled together;
//! - everything else (isosurfaces, decoupled adaptive Simpson, trapezoid, Simpson, the
//!   reference): ray by ray.
//!
//! The paths compute the same sums (tested). Output does not depend on the number of threads:
//! every pixel is computed independently.
use std::time::Instant;

use glam::{DVec3, Vec3};
use volux_core::{Image, RayGenerator, TransferFunction};

use crate::classify::{BreakpointRanks, ClassifyTable, LaneTable};
use crate::composite::RayAccumulator;
use crate::engine::Rebuilt;
use crate::integrate::preintegrated::PreintegrationTable;
use crate::integrate::Integrator;
use crate::intervals::IntervalSource;
use crate::macrocell::{MacrocellGrid, Occupancy};
use crate::sampling::Field;
use crate::shading::{BlinnPhong, GradientVolume};
use crate::tiles::{render_tiles, TileGrid, TILE};
use crate::RenderError;

/// One pixel's result.
#[derive(Clone, Copy, Debug, Default)]
struct PixelOut {
    rgba: [f32; 4],
    samples: u64,
    error: f32,
    missed: bool,
    hit: bool,
}

impl PixelOut {
    /// A hit ray composited into `acc` with `samples` samples (no error estimate).
    fn composited(acc: &RayAccumulator, samples: u64) -> Self {
        Self {
            rgba: acc.rgba,
            samples,
            error: 0.0,
            missed: false,
            hit: true,
        }
    }
}

/// Whether empty-space skipping pays for itself: a ray walks every macrocell it crosses (a
/// few nanoseconds each) to save the samples of the empty ones, so skipping is used when the
/// expected samples saved per macrocell crossed, `empty fraction x BLOCK / sample spacing`,
/// reach one. Measured at 512x512: Marschner-Lobb with the bench's TF (3.3 % of macrocells
/// empty) renders 8 % faster without skipping at step 0.5 and 10 % slower at step 0.2; the
/// CT head with its automatic TF (2 % empty), faster without at both. Skipping never changes
/// the image (tested), so this only decides speed.
fn worth_skipping(empty_fraction: f64, integrator: &Integrator) -> bool {
    let spacing = match *integrator {
        Integrator::Riemann { step }
        | Integrator::Trapezoid { step }
        | Integrator::Preintegrated { step } => step,
        Integrator::Simpson { step } => step / 2.0,
        // Four samples per step, steps up to hmax.
        Integrator::AdaptiveSimpson(p) => p.hmax / 4.0,
        _ => 0.01,
    };
    empty_fraction * MacrocellGrid::BLOCK as f64 / spacing.max(1e-6) >= 1.0
}

/// Renders any [`Field`] placed in the world, classifying with `opts.tf` over `range`
/// (without empty-space skipping).
pub fn render_field<F: Field>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    opts: &RenderOptions,
) -> Result<Rendered, RenderError> {
    render_field_in(field, place, range, None, opts)
}

/// [`render_field`] with rays sampled only in the `intervals` the volume gives (the seam of
/// bricked and out-of-core grids: they supply the sampler, `field`, and the intervals).
pub fn render_field_in<F: Field>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    intervals: Option<&dyn IntervalSource>,
    opts: &RenderOptions,
) -> Result<Rendered, RenderError> {
    let pre = match opts.integrator {
        Integrator::Preintegrated { step } => Some(
            PreintegrationTable::new(&opts.tf, range, step * place.spacing.min_element())
                .map_err(RenderError::InvalidOptions)?,
        ),
        _ => None,
    };
    render_with(
        field,
        place,
        range,
        opts,
        Derived {
            macrocells: None,
            classification: None,
            intervals,
            preintegration: pre.as_ref(),
            gradients: None,
            lanes: true,
        },
    )
}

/// Data derived from the volume and the TF that a render uses, built (and cached) by the caller.
#[derive(Clone, Copy, Default)]
struct Derived<'a> {
    macrocells: Option<&'a MacrocellGrid>,
    /// The classification, when the caller keeps one (built here otherwise).
    classification: Option<&'a Classification>,
    /// The caller's intervals (a bricked grid's), instead of the macrocells'.
    intervals: Option<&'a dyn IntervalSource>,
    preintegration: Option<&'a PreintegrationTable>,
    gradients: Option<&'a GradientVolume>,
    /// Whether tiles may take the lane paths.
    lanes: bool,
}

fn render_with<F: Field>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    opts: &RenderOptions,
    derived: Derived<'_>,
) -> Result<Rendered, RenderError> {
    opts.validate()?;
    let start = Instant::now();
    let owned;
    let classification = match derived.classification {
        Some(c) if c.is_for(opts, range, derived.macrocells) => c,
        _ => {
            owned = Classification::new(opts, range, derived.macrocells);
            &owned
        }
    };
    let table = &classification.table;
    let occupancy = derived
        .macrocells
        .zip(classification.empty.as_deref())
        .map(|(m, empty)| Occupancy::from_flags(m, empty));
    let intervals = derived
        .intervals
        .or(occupancy.as_ref().map(|o| o as &dyn IntervalSource))
        .filter(|i| !opts.mip && worth_skipping(i.empty_fraction(), &opts.integrator));
    let breakpoints = opts.tf.resolved(range).breakpoints();
    let (lane_table, breakpoint_ranks) = match opts.integrator {
        Integrator::Riemann { step } => (
            Some(table.for_step((step * place.spacing.min_element()) as f32)),
            None,
        ),
        Integrator::Trapezoid { .. } => (Some(table.for_lanes()), None),
        Integrator::AdaptiveSimpson(_) => {
            let lanes = table.for_lanes();
            let ranks = lanes.breakpoint_ranks(&breakpoints);
            (Some(lanes), Some(ranks))
        }
        _ => (None, None),
    };
    let ctx = RayContext {
        field,
        place,
        table,
        intervals,
        preintegration: derived.preintegration,
        gradients: derived.gradients,
        lane_table,
        breakpoint_ranks,
        tf: opts.tf.resolved(range),
        breakpoints,
        rays: opts.camera.rays(opts.width, opts.height),
        opts,
    };
    let grid = TileGrid::new(opts.width, opts.height, TILE);
    let out = render_tiles(&grid, &opts.control, |_, r| {
        let (x0, y0) = (r.x0, r.y0);
        let px = if !derived.lanes {
            ctx.tile_ray_by_ray(x0, y0)
        } else if opts.mip {
            ctx.mip_stream(x0, y0)
        } else if let Some(st) = ctx.packet_table() {
            ctx.lane_stream(st, x0, y0)
        } else if let Some(pt) = ctx.preintegrated_stream_table() {
            ctx.lane_stream(pt, x0, y0)
        } else if let Some(tr) = ctx.trapezoid_stream_rule() {
            ctx.lane_stream(&tr, x0, y0)
        } else if let Some(p) = ctx.adaptive_stream_params() {
            ctx.adaptive_stream(p, x0, y0)
        } else {
            ctx.tile_ray_by_ray(x0, y0)
        };
        (px, ())
    })?
    .pixels;
    let (w, h) = (opts.width, opts.height);
    let stats = RenderStats {
        rays: out.iter().filter(|p| p.hit).count() as u64,
        samples: out.iter().map(|p| p.samples).sum(),
        seconds: start.elapsed().as_secs_f64(),
        rays_over_tolerance: out.iter().filter(|p| p.missed).count() as u64,
        rebuilt: Rebuilt::ALL,
    };
    let error_map = out.iter().map(|p| p.error).collect();
    let image = Image::from_pixels(w, h, out.iter().map(|p| p.rgba).collect())?;
    Ok(Rendered {
        image,
        stats,
        error_map,
    })
}

/// Entry and exit distances of a ray through the box [lo, hi] (slab test), if it hits.
pub fn ray_box(origin: DVec3, dir: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let inv = dir.recip();
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    let near = t0.min(t1);
    let far = t0.max(t1);
    // NaN (0 * inf, ray in a slab plane) is ignored by max/min below.
    let tn = near.x.max(near.y).max(near.z).max(0.0);
    let tf = far.x.min(far.y).min(far.z);
    (tf > tn).then_some((tn, tf))
}

/// The classification of a render, what depends on the transfer function: its table and
/// the macrocells' empty flags (zero extinction over a macrocell's range and no isovalue in
/// it). A renderer keeps it between frames ([`Classification::is_for`]).
pub(crate) struct Classification {
    /// What it was built from: the TF as given, the data range, the isovalues.
    tf: TransferFunction,
    range: [f64; 2],
    isovalues: Vec<f32>,
    table: ClassifyTable,
    /// Empty flags per macrocell (when built for a macrocell grid).
    empty: Option<Vec<bool>>,
}

impl Classification {
    /// Classifies with `opts`' TF over `range`, and flags the empty macrocells of `cells`.
    pub(crate) fn new(
        opts: &RenderOptions,
        range: [f64; 2],
        cells: Option<&MacrocellGrid>,
    ) -> Self {
        let table = ClassifyTable::new(&opts.tf, range, ClassifyTable::DEFAULT_SIZE);
        let isovalues = isovalues(opts);
        let empty = cells.map(|m| m.empty_flags(&table, &isovalues));
        Self {
            tf: opts.tf.clone(),
            range,
            isovalues,
            table,
            empty,
        }
    }

    /// Whether this was built for `opts`' TF and isovalues, `range`, and (when `cells` is
    /// given) has the empty flags.
    pub(crate) fn is_for(
        &self,
        opts: &RenderOptions,
        range: [f64; 2],
        cells: Option<&MacrocellGrid>,
    ) -> bool {
        self.tf == opts.tf
            && self.range == range
            && self.isovalues == isovalues(opts)
            && (cells.is_none() || self.empty.is_some())
    }
}

fn isovalues(opts: &RenderOptions) -> Vec<f32> {
    opts.isosurfaces
        .as_slice()
        .iter()
        .map(|i| i.value)
        .collect()
}

/// Everything a ray needs, shared by all rays of a render.
struct RayContext<'a, F> {
    field: &'a F,
    place: Placement,
    table: &'a ClassifyTable,
    /// Where rays sample (`None`: everywhere between entry and exit).
    intervals: Option<&'a dyn IntervalSource>,
    preintegration: Option<&'a PreintegrationTable>,
    gradients: Option<&'a GradientVolume>,
    /// The classification for the lane-wise paths: per-slab colour and opacity for the
    /// Riemann step (no `exp` per sample), colour and extinction for adaptive Simpson.
    lane_table: Option<LaneTable>,
    /// Breakpoint counts per lane-table entry, for adaptive Simpson's hidden-peak test.
    breakpoint_ranks: Option<BreakpointRanks>,
    tf: TransferFunction,
    breakpoints: Vec<f64>,
    /// The camera's rays for this image size.
    rays: RayGenerator,
    opts: &'a RenderOptions,
}

/// The classified medium along one ray through a grid, in voxel space.
struct GridRay<'a, F> {
    field: &'a F,
    o_v: DVec3,
    d_v: DVec3,
    table: &'a ClassifyTable,
    /// Classify exactly with this TF instead of the table (the reference path).
    exact: Option<&'a TransferFunction>,
    breakpoints: &'a [f64],
    /// Shading of the emitted colour: the lighting model and the ray's context.
    shade: Option<RayShading<'a>>,
}

/// What a [`GridRay`] needs to light its samples.
struct RayShading<'a> {
    model: &'a BlinnPhong,
    gradients: Option<&'a GradientVolume>,
    spacing: Vec3,
    view: Vec3,
}

/// A ray of maximum intensity projection: voxel-space origin and direction, the extent and
/// the step of its sample lattice (world units).
#[derive(Clone, Copy, Debug, Default)]
struct MipRay {
    o_v: DVec3,
    d_v: DVec3,
    t0: f64,
    t1: f64,
    step: f64,
}

/// Distances in `[t0, t1]` where the voxel-space ray `o_v + t d_v` crosses an integer plane
/// (a voxel boundary), with `t0` and `t1`, sorted.
pub fn voxel_crossings(o_v: DVec3, d_v: DVec3, t0: f64, t1: f64) -> Vec<f64> {
    let mut ts = vec![t0, t1];
    for a in 0..3 {
        if d_v[a].abs() < 1e-300 {
            continue;
        }
        let (x0, x1) = (o_v[a] + d_v[a] * t0, o_v[a] + d_v[a] * t1);
        let (lo, hi) = (x0.min(x1).ceil() as i64, x0.max(x1).floor() as i64);
        ts.extend(
            (lo..=hi)
                .map(|k| (k as f64 - o_v[a]) / d_v[a])
                .filter(|t| *t > t0 && *t < t1),
        );
    }
    ts.sort_by(f64::total_cmp);
    ts.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    ts
}

/// The voxel-space position of a world point (for tests and tools).
pub fn to_voxel(place: &Placement, p: DVec3) -> Vec3 {
    ((p - place.origin) / place.spacing).as_vec3()
}

mod adaptive_stream;
mod mip_stream;
mod options;
mod rays;
mod renderer;
mod stream;
#[cfg(test)]
mod tests;

pub use options::{Placement, RenderOptions, RenderStats, Rendered};
use rays::{pixel, pixel_hash};
pub(crate) use renderer::grid_frame;
pub use renderer::{render_grid, GridRenderer};
