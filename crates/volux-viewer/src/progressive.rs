//! Progressive level of detail for bricked volumes (issue 19: "the viewer shows coarse
//! levels at once and refines to full resolution"). After every new scene the render thread
//! ([`crate::render_service`]) walks a ladder of pyramid levels, coarsest first, down to
//! the level the volume's [`Lod`](volux_render::bricked::Lod) picks for the view (full resolution when the user asks for
//! it): each level is one frame, rendered in the background and superseded as soon as the
//! scene changes again. The ladder is the application layer's
//! ([`volux_app::preview::lod_ladder`]), each level drawn by the factory's renderer; this
//! module holds what the status line says: the level a frame shows ([`LevelShown`]) and the
//! cache's figures ([`CacheFigures`]).
use volux_render::bricked::{BrickedVolume, CacheStats};

/// The level a frame of a bricked volume shows, and where refinement stops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelShown {
    /// The level drawn (0: full resolution).
    pub level: usize,
    /// The pyramid's number of levels.
    pub levels: usize,
    /// The level refinement ends at for this scene.
    pub target: usize,
    /// Samples per axis of the level drawn.
    pub dims: [usize; 3],
}

impl LevelShown {
    /// Whether refinement is done (this is the target level).
    pub fn is_final(&self) -> bool {
        self.level == self.target
    }

    /// The status line's words: "level 2 of 0–3, 64x64x64 — refining to level 0…", then
    /// "level 0, 256x256x256 — full resolution" (or "— as fine as the view needs" when the
    /// automatic level stops above 0).
    pub fn describe(&self) -> String {
        let [x, y, z] = self.dims;
        let head = format!(
            "level {} of 0–{}, {x}x{y}x{z}",
            self.level,
            self.levels.saturating_sub(1)
        );
        if !self.is_final() {
            format!("{head} — refining to level {}…", self.target)
        } else if self.level == 0 {
            format!("{head} — full resolution")
        } else {
            format!("{head} — as fine as the view needs (tick Full resolution for level 0)")
        }
    }
}

/// The brick caches' figures, over all levels. A hit ratio is not among them: it counts the
/// rays' lookups, which stay near 100 % hits while the cache evicts and reads the same
/// chunks again; the chunks read, and how many of them were read again, say what it costs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheFigures {
    /// Bytes of bricks resident now.
    pub resident_bytes: u64,
    /// The memory budget.
    pub budget: u64,
    /// Chunks read from the store.
    pub chunks_read: u64,
    /// Chunks read again after they were evicted (part of `chunks_read`).
    pub rereads: u64,
}

impl CacheFigures {
    /// The figures of `volume` now.
    pub fn of(volume: &BrickedVolume) -> Self {
        Self::from_stats(
            volume.resident_bytes(),
            volume.budget(),
            &volume.cache_totals(),
        )
    }

    /// The figures of caches holding `resident_bytes` of `budget`, with counters `stats`.
    pub fn from_stats(resident_bytes: u64, budget: u64, stats: &CacheStats) -> Self {
        Self {
            resident_bytes,
            budget,
            chunks_read: stats.misses,
            rereads: stats.rereads,
        }
    }

    /// "cache 12.0 of 32.0 MiB, 680 chunks read, 22 read again" ("none read again" while
    /// the budget holds every chunk the views needed).
    pub fn describe(&self) -> String {
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        let chunks = if self.chunks_read == 1 {
            "chunk"
        } else {
            "chunks"
        };
        let again = match self.rereads {
            0 => "none".to_string(),
            n => n.to_string(),
        };
        format!(
            "cache {:.1} of {:.1} MiB, {} {chunks} read, {again} read again",
            mib(self.resident_bytes),
            mib(self.budget),
            self.chunks_read,
        )
    }
}

/// What a frame of `level` shows, refining towards `target`.
pub fn level_shown(volume: &BrickedVolume, level: usize, target: usize) -> LevelShown {
    let dims = volume
        .multiscale()
        .levels()
        .get(level)
        .map_or([0; 3], |l| l.layout().dims);
    LevelShown {
        level,
        levels: volume.levels(),
        target,
        dims,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_status_words_name_the_level_and_the_goal() {
        let mut l = LevelShown {
            level: 2,
            levels: 4,
            target: 0,
            dims: [16, 16, 16],
        };
        assert_eq!(
            l.describe(),
            "level 2 of 0–3, 16x16x16 — refining to level 0…"
        );
        l.level = 0;
        l.dims = [64, 64, 64];
        assert!(
            l.describe().ends_with("full resolution"),
            "{}",
            l.describe()
        );
        l.level = 1;
        l.target = 1;
        assert!(l.describe().contains("as fine as the view needs"));
    }

    /// A thrashing cache's line says how many chunks were read and read again, not the
    /// lookups' hit ratio (near 100 % whatever the thrashing).
    #[test]
    fn the_cache_line_counts_chunks_read_again() {
        let stats = CacheStats {
            hits: 2_000_000,
            misses: 680,
            evictions: 650,
            rereads: 22,
            ..CacheStats::default()
        };
        let c = CacheFigures::from_stats(12 << 20, 32 << 20, &stats);
        assert_eq!(
            c.describe(),
            "cache 12.0 of 32.0 MiB, 680 chunks read, 22 read again"
        );
        let calm = CacheStats {
            hits: 10,
            misses: 1,
            ..CacheStats::default()
        };
        let c = CacheFigures::from_stats(3 << 20, 1 << 30, &calm);
        assert_eq!(
            c.describe(),
            "cache 3.0 of 1024.0 MiB, 1 chunk read, none read again"
        );
    }
}
