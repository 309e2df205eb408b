//! One region of a distributed render of a bricked level
//! ([`crate::distributed`]): the level sampled through its brick cache, rays only inside the
//! region ([`render_cache_region`]), and the whole frame of every rank, composited by
//! binary swap or, for adaptive Simpson, passed along the state pipeline
//! ([`render_cache_frame`]).
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use glam::DMat3;

use super::cache::BrickCache;
use super::field::BrickedField;
use super::render::stopped_by;
use crate::distributed::error::DistributedError;
use crate::distributed::exchange::Exchange;
use crate::distributed::kdtree::KdSplit;
use crate::distributed::part::Part;
use crate::distributed::pipeline::{render_pipelined, RankTimes};
use crate::distributed::region::{is_pipelined, render_region};
use crate::error::RenderError;
use crate::raycast::{Placement, RenderOptions};
use crate::sampling::Reconstruction;

/// The world placement of `cache`'s level (axis-aligned, as for [`super::render_level`]).
pub fn level_placement(cache: &BrickCache) -> Placement {
    let l = cache.layout();
    Placement {
        origin: l.origin_vec(),
        spacing: l.spacing_vec(),
        dims: l.dims,
        direction: DMat3::IDENTITY,
    }
}

/// Renders region `region` of `split` of the level `cache` reads, classified over `range`
/// (the full level's data range, as the single-process render uses), into the rank's part
/// of the frame (a partial image, premultiplied, no background, or the region's MIP maxima;
/// see
/// [`render_region`](crate::distributed::region::render_region) for what is exact). Only
/// the region's chunks and their neighbours across its faces are read. A chunk that cannot
/// be read stops the render with an error naming it.
pub fn render_cache_region(
    cache: &BrickCache,
    range: [f64; 2],
    split: &KdSplit,
    region: usize,
    opts: &RenderOptions,
) -> Result<Part, DistributedError> {
    check(cache, split, opts)?;
    with_field(cache, opts, |field, opts| {
        render_region(field, level_placement(cache), range, split, region, opts)
    })
}

/// This rank's whole part of a distributed frame of the level `cache` reads (region
/// `region` of `split`, classified over `range`), every rank calling it with the view's
/// visibility order `order` of the ranks of `ex`: adaptive Simpson through the state
/// pipeline ([`render_pipelined`]: the single-process image bit for bit, early termination
/// as `opts` have it), every other integrator rendered by region
/// ([`render_cache_region`]) and composited by binary swap. Rank 0 gets the image.
pub fn render_cache_frame<E: Exchange + ?Sized>(
    cache: &BrickCache,
    range: [f64; 2],
    (split, region): (&KdSplit, usize),
    opts: &RenderOptions,
    ex: &mut E,
    order: &[usize],
) -> Result<(Option<volux_core::Image>, RankTimes), DistributedError> {
    if !is_pipelined(opts) {
        let t = std::time::Instant::now();
        let part = render_cache_region(cache, range, split, region, opts)?;
        let render_seconds = t.elapsed().as_secs_f64();
        let (image, composite) = part.combine(ex, order)?;
        let stats = RankTimes {
            render_seconds,
            composite,
        };
        return Ok((image, stats));
    }
    check(cache, split, opts)?;
    let place = level_placement(cache);
    with_field(cache, opts, |field, opts| {
        render_pipelined(field, (place, range), (split, region), opts, ex, order)
    })
}

/// Refuses cubic reconstruction, and a split of another level.
fn check(
    cache: &BrickCache,
    split: &KdSplit,
    opts: &RenderOptions,
) -> Result<(), DistributedError> {
    if opts.reconstruction != Reconstruction::Trilinear {
        return Err(DistributedError::Unsupported(
            "cubic reconstruction on bricked volumes".into(),
        ));
    }
    if split.chunks_per_axis() != cache.layout().chunks_per_axis() {
        return Err(DistributedError::Unsupported(format!(
            "a split of {:?} chunks for a level of {:?}",
            split.chunks_per_axis(),
            cache.layout().chunks_per_axis()
        )));
    }
    Ok(())
}

/// Runs `body` on the level as a field and the options stopped by a chunk error; the
/// chunk error, if one happened, instead of the result.
fn with_field<T>(
    cache: &BrickCache,
    opts: &RenderOptions,
    body: impl FnOnce(&BrickedField<'_>, &RenderOptions) -> Result<T, DistributedError>,
) -> Result<T, DistributedError> {
    let failed = Arc::new(AtomicBool::new(false));
    let field = BrickedField::for_render(cache, failed.clone());
    let opts = stopped_by(opts, failed);
    let out = body(&field, &opts);
    field.forget();
    match field.error() {
        Some(e) => Err(RenderError::Data(volux_core::Error::Chunked(e.clone())).into()),
        None => out,
    }
}
