//! One region of a distributed render of a bricked level
//! ([`crate::distributed`]): the level sampled through its brick cache, rays only inside the
//! region ([`render_cache_region`]).
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use glam::DMat3;

use super::cache::BrickCache;
use super::field::BrickedField;
use super::render::stopped_by;
use crate::distributed::error::DistributedError;
use crate::distributed::kdtree::KdSplit;
use crate::distributed::part::Part;
use crate::distributed::region::render_region;
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
    let failed = Arc::new(AtomicBool::new(false));
    let field = BrickedField::for_render(cache, failed.clone());
    let opts = stopped_by(opts, failed);
    let out = render_region(&field, level_placement(cache), range, split, region, &opts);
    field.forget();
    match field.error() {
        Some(e) => Err(RenderError::Data(volux_core::Error::Chunked(e.clone())).into()),
        None => out,
    }
}
