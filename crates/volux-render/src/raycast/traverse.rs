//! One grid render: the classification and the intervals of the render, and the tiles
//! handed to the tile driver, each taking the lane stream or the ray-by-ray path.
use std::time::Instant;

use volux_core::image::Image;
use volux_core::sculpt::SculptMask;

use super::context::{
    cut_faces, local_clip_planes, Classification, Derived, LocalRays, PixelOut, RayContext,
};
use super::mask_tiles::MaskTiles;
use super::options::{Placement, RenderOptions, Rendered};
use crate::error::RenderError;
use crate::frame::{Rebuilt, RenderStats};
use crate::integrate::integrator::Integrator;
use crate::integrate::preintegrated::PreintegrationTable;
use crate::intervals::IntervalSource;
use crate::macrocell::{CellClass, MacrocellGrid, Occupancy};
use crate::sampling::Field;
use crate::sculpt::masked::Masked;
use crate::tiles::{render_tiles, TileGrid, TILE};

/// Whether empty-space skipping pays for itself: a ray walks every macrocell it crosses (a
/// few nanoseconds each) to save the samples of the empty ones, so skipping is used when the
/// expected samples saved per macrocell crossed, `empty fraction x BLOCK / sample spacing`,
/// reach one. Measured at 512x512: Marschner-Lobb with the bench's TF (3.3 % of macrocells
/// empty) renders 8 % faster without skipping at step 0.5 and 10 % slower at step 0.2; the
/// CT head with its automatic TF (2 % empty), faster without at both. Skipping never changes
/// the image (tested), so this only decides speed.
pub(crate) fn worth_skipping(empty_fraction: f64, integrator: &Integrator) -> bool {
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
        Integrator::Preintegrated { step } => Some(PreintegrationTable::new(
            &opts.tf,
            range,
            step * place.spacing.min_element(),
        )?),
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

/// Renders `field`, seen through the scene's sculpt mask when it has one (every path then
/// samples [`Masked`], and the macrocells the mask removes wholly are skipped), except in
/// the tiles whose rays cross only macrocells the mask leaves wholly visible
/// ([`MaskTiles`]): those are rendered as without the mask, which gives them the same
/// samples.
pub(crate) fn render_with<F: Field>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    opts: &RenderOptions,
    derived: Derived<'_>,
) -> Result<Rendered, RenderError> {
    if let Some(l) = &opts.labels {
        check_dims("label volume", l.dims(), place.dims)?;
    }
    if let Some(c) = &opts.data_colour {
        check_dims("colour", c.dims(), place.dims)?;
    }
    match opts.mask.as_deref() {
        Some(mask) => {
            check_dims("sculpt mask", mask.dims(), place.dims)?;
            let masked = Masked { inner: field, mask };
            let grid = TileGrid::new(opts.width, opts.height, TILE);
            let tiles = MaskTiles::new(mask, &place, opts, grid);
            if opts.labels.is_some() || opts.data_colour.is_some() || !tiles.any_untouched() {
                return render_sampled(&masked, place, range, opts, derived);
            }
            render_split(field, &masked, &tiles, place, range, opts, derived)
        }
        None => render_sampled(field, place, range, opts, derived),
    }
}

/// Refuses a mask or labels made for a grid of other dimensions.
fn check_dims(
    layer: &'static str,
    layer_dims: [usize; 3],
    grid_dims: [usize; 3],
) -> Result<(), RenderError> {
    if layer_dims == grid_dims {
        return Ok(());
    }
    Err(RenderError::LayerMismatch {
        layer,
        layer_dims,
        grid_dims,
    })
}

/// The macrocell classes with the sculpt mask's states folded in (one pass over a byte per
/// macrocell: the mask keeps its macrocell states up to date as the tools edit it, so
/// nothing is rebuilt from the voxels): wholly removed macrocells are skipped, partly removed
/// ones sampled through the mask. Empty macrocells stay skipped only when `skip_empty`
/// (skipping pays, [`worth_skipping`]): otherwise they are sampled, so that intervals break
/// only where the mask changes. `None` without a mask, or for a mask of other macrocells.
fn with_mask_states(
    classes: &[CellClass],
    mask: Option<&SculptMask>,
    skip_empty: bool,
) -> Option<Vec<CellClass>> {
    let mask = mask?;
    let count: usize = mask.blocks_per_axis().iter().product();
    (count == classes.len()).then(|| {
        classes
            .iter()
            .enumerate()
            .map(|(m, &c)| match c {
                _ if mask.block_removed(m) => CellClass::Skip,
                CellClass::Skip if skip_empty => CellClass::Skip,
                _ if mask.block_partial(m) => CellClass::SampleMasked,
                _ => CellClass::Sample,
            })
            .collect()
    })
}

fn render_sampled<F: Field>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    opts: &RenderOptions,
    derived: Derived<'_>,
) -> Result<Rendered, RenderError> {
    opts.validate()?;
    let start = Instant::now();
    with_context(field, place, range, opts, derived, |ctx| {
        render_tiles_of(ctx, derived.lanes, start)
    })
}

/// [`render_sampled`] of `masked` in the tiles the mask may change, and of `field` without
/// the mask in the others.
fn render_split<F: Field>(
    field: &F,
    masked: &Masked<'_, F>,
    tiles: &MaskTiles,
    place: Placement,
    range: [f64; 2],
    opts: &RenderOptions,
    derived: Derived<'_>,
) -> Result<Rendered, RenderError> {
    opts.validate()?;
    let start = Instant::now();
    let unmasked = RenderOptions {
        mask: None,
        ..opts.clone()
    };
    with_context(masked, place, range, opts, derived, |cut| {
        with_context(field, place, range, &unmasked, derived, |whole| {
            render_tiles_by(opts, start, |x0, y0| {
                if tiles.touched(x0, y0) {
                    tile_pixels(cut, derived.lanes, x0, y0)
                } else {
                    tile_pixels(whole, derived.lanes, x0, y0)
                }
            })
        })
    })
}

/// Runs `body` with the context of a render of `field` (the classification, the intervals,
/// the lane tables, the rays): what every tile of the render shares.
pub(crate) fn with_context<F: Field, R>(
    field: &F,
    place: Placement,
    range: [f64; 2],
    opts: &RenderOptions,
    derived: Derived<'_>,
    body: impl FnOnce(&RayContext<'_, F>) -> R,
) -> R {
    let turned;
    let opts = match lights_to_local(opts, &place) {
        Some(o) => {
            turned = o;
            &turned
        }
        None => opts,
    };
    let owned;
    let classification = match derived.classification {
        Some(c) if c.is_for(opts, range, derived.macrocells) => c,
        _ => {
            owned = Classification::new(opts, range, derived.macrocells);
            &owned
        }
    };
    let table = &classification.table;
    let skip_empty = |classes: &[CellClass]| {
        let empty = classes.iter().filter(|c| **c == CellClass::Skip).count();
        let fraction = empty as f64 / classes.len().max(1) as f64;
        worth_skipping(fraction, &opts.integrator)
    };
    let masked_classes = classification
        .classes
        .as_deref()
        .and_then(|c| with_mask_states(c, opts.mask.as_deref(), skip_empty(c)));
    let occupancy = derived
        .macrocells
        .zip(
            masked_classes
                .as_deref()
                .or(classification.classes.as_deref()),
        )
        .map(|(m, classes)| Occupancy::from_classes(m, classes));
    // With a mask, the macrocells' intervals tell where it hides nothing: always walked
    // (unless the caller brings its own intervals, which do not tell).
    let mask_classes = occupancy
        .as_ref()
        .filter(|_| masked_classes.is_some() && derived.intervals.is_none() && !opts.mip);
    let intervals = derived
        .intervals
        .or(occupancy.as_ref().map(|o| o as &dyn IntervalSource))
        .filter(|i| {
            !opts.mip
                && (mask_classes.is_some() || worth_skipping(i.empty_fraction(), &opts.integrator))
        });
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
    let clip = local_clip_planes(&place, &opts.clip_planes);
    let ctx = RayContext {
        field,
        place,
        table,
        intervals,
        mask_classes,
        preintegration: derived.preintegration,
        gradients: derived.gradients,
        lane_table,
        breakpoint_ranks,
        tf: opts.tf.resolved(range),
        breakpoints,
        rays: LocalRays {
            world: opts.camera.rays(opts.width, opts.height),
            place,
        },
        cut_faces: cut_faces(opts, &place, &clip),
        clip,
        opts,
    };
    body(&ctx)
}

/// Renders the tiles of the image with `ctx` (`lanes`: whether tiles may take the lane
/// paths), timed from `start`.
fn render_tiles_of<F: Field>(
    ctx: &RayContext<'_, F>,
    lanes: bool,
    start: Instant,
) -> Result<Rendered, RenderError> {
    render_tiles_by(ctx.opts, start, |x0, y0| tile_pixels(ctx, lanes, x0, y0))
}

/// The pixels of the tile whose first pixel is (`x0`, `y0`), by the path its options take.
fn tile_pixels<F: Field>(
    ctx: &RayContext<'_, F>,
    lanes: bool,
    x0: usize,
    y0: usize,
) -> Vec<PixelOut> {
    let opts = ctx.opts;
    // Label and data colours are looked up ray by ray.
    if !lanes || opts.labels.is_some() || opts.data_colour.is_some() {
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
    }
}

/// The image of `opts` from the pixels `tile` gives each tile, with its stats, timed from
/// `start`.
fn render_tiles_by(
    opts: &RenderOptions,
    start: Instant,
    tile: impl Fn(usize, usize) -> Vec<PixelOut> + Sync,
) -> Result<Rendered, RenderError> {
    let grid = TileGrid::new(opts.width, opts.height, TILE);
    let out = render_tiles(&grid, &opts.control, |_, r| (tile(r.x0, r.y0), ()))?.pixels;
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

/// `opts` with its directional lights turned into the local frame of `place` (`None` when
/// nothing changes: an axis-aligned grid, or headlights only). Lighting a local-frame
/// gradient `g` with the local light `Dᵀ L` is lighting the world normal `D g` with `L`
/// (dot products are kept by the orthonormal `D`), so samples are shaded as in the world.
fn lights_to_local(opts: &RenderOptions, place: &Placement) -> Option<RenderOptions> {
    use crate::shading::blinn_phong::Light;
    let turn = |m: &mut Option<crate::shading::blinn_phong::BlinnPhong>| {
        if let Some(Light::Direction(l)) = m.as_mut().map(|m| &mut m.light) {
            *l = place.vector_to_local(l.as_dvec3()).as_vec3();
        }
    };
    let directional = |m: &Option<crate::shading::blinn_phong::BlinnPhong>| matches!(m, Some(b) if matches!(b.light, Light::Direction(_)));
    if place.is_axis_aligned() || !(directional(&opts.shading) || directional(&opts.iso_lighting)) {
        return None;
    }
    let mut o = opts.clone();
    turn(&mut o.shading);
    turn(&mut o.iso_lighting);
    Some(o)
}
