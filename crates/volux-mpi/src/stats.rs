//! The figures of one rank of a distributed render, gathered to rank 0 for `--stats`.
use serde::{Deserialize, Serialize};
use volux_render::distributed::reads::ReadStats;
use volux_render::distributed::swap::CompositeStats;

/// What one rank did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RankStats {
    /// The rank.
    pub rank: usize,
    /// The chunks of its region.
    pub region_chunks: usize,
    /// Its region, chunk coordinates `[lo, hi)`.
    pub region: [[usize; 3]; 2],
    /// Chunks it read: its own, its neighbours' next to its faces, others.
    pub reads: ReadStats,
    /// Wall time of its region's render, milliseconds.
    pub render_ms: f64,
    /// Wall time of its part of the compositing (swap and gather), milliseconds.
    pub composite_ms: f64,
    /// Its messages and bytes while compositing.
    pub composite: CompositeStats,
}
