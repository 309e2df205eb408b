//! Reading a frame's bricks ahead of its rays (seed `003` loads each block before rendering
//! it; here the loads overlap the rendering): a worker thread reads the chunks the frame may
//! sample, nearest to the eye first (the order in which rays reach them), and decodes them
//! into the cache, while the render threads sample those already resident. It stops when the
//! frame ends, at the first chunk that cannot be read (the render reports it), and before
//! reading more than a share of the budget, so that it never evicts bricks the frame needs.
use std::sync::atomic::{AtomicBool, Ordering};

use glam::DVec3;
use volux_core::bricked::ChunkLayout;

use super::cache::BrickCache;
use crate::macrocell::{CellClass, Occupancy};

/// The share of the budget the prefetcher fills (the rest is left to the bricks the rays
/// need that it did not foresee).
const SHARE: u64 = 2;

/// The chunks a frame seen from `eye` (world) may sample, nearest first: every chunk, or
/// those `occupancy` does not skip; at most what fits in `budget / SHARE` bytes.
pub(crate) fn plan(
    layout: &ChunkLayout,
    occupancy: Option<&Occupancy<'_>>,
    eye: DVec3,
    brick_bytes: u64,
    budget: u64,
) -> Vec<[usize; 3]> {
    let (origin, spacing) = (layout.origin_vec(), layout.spacing_vec());
    let mut chunks: Vec<(f64, [usize; 3])> = (0..layout.chunk_count())
        .filter_map(|i| {
            let c = layout.chunk_coords(i);
            let (lo, size) = layout.chunk_extent(c);
            let centre = DVec3::from(std::array::from_fn::<f64, 3, _>(|a| {
                lo[a] as f64 + size[a] as f64 / 2.0
            }));
            let skipped = occupancy.is_some_and(|o| o.class_at(centre) == CellClass::Skip);
            (!skipped).then(|| ((origin + centre * spacing).distance_squared(eye), c))
        })
        .collect();
    chunks.sort_by(|a, b| a.0.total_cmp(&b.0));
    let room = (budget / SHARE / brick_bytes.max(1)) as usize;
    chunks.into_iter().take(room).map(|(_, c)| c).collect()
}

/// Reads `chunks` into `cache` in order, skipping those resident or being read, until `stop`
/// is raised or a chunk fails; returns how many it read.
pub(crate) fn run(cache: &BrickCache, chunks: &[[usize; 3]], stop: &AtomicBool) -> usize {
    let mut read = 0;
    for &c in chunks {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        match cache.prefetch(c) {
            Ok(true) => read += 1,
            Ok(false) => {}
            Err(_) => break,
        }
    }
    read
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::grid::ScalarType;

    #[test]
    fn the_nearest_chunks_come_first_within_the_share_of_the_budget() {
        let layout = ChunkLayout::new(
            [64, 64, 64],
            [16, 16, 16],
            [1.0; 3],
            [0.0; 3],
            ScalarType::F32,
        )
        .unwrap();
        let eye = DVec3::new(-100.0, 8.0, 8.0);
        let brick = 1000;
        let all = plan(&layout, None, eye, brick, u64::MAX / 4);
        assert_eq!(all.len(), 64);
        assert_eq!(all[0], [0, 0, 0]);
        let distance = |c: &[usize; 3]| {
            let p = DVec3::from(c.map(|i| i as f64 * 16.0 + 8.0));
            p.distance(eye)
        };
        assert!(all.windows(2).all(|w| distance(&w[0]) <= distance(&w[1])));
        // Half of a budget of ten bricks: five.
        let some = plan(&layout, None, eye, brick, 10 * brick);
        assert_eq!(some, all[..5].to_vec());
    }
}
