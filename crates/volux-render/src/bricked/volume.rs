//! A bricked volume as the engine renders it: a [`Multiscale`] pyramid with one brick cache
//! per level within a shared memory budget, the data range, and the choice of level
//! ([`Lod`]).
use std::sync::OnceLock;

use glam::DVec3;
use rayon::prelude::*;
use volux_core::bricked::{ChunkLayout, ChunkSource, Multiscale};
use volux_core::grid::Scalar;
use volux_core::histogram::Histogram;
use volux_core::Aabb;

use super::cache::{brick_bytes, BrickCache, CacheStats};
use super::field::{MAX_BRICK_SAMPLES, MAX_CHUNKS};
use crate::error::{Remedy, RenderError};
use crate::macrocell::MacrocellGrid;

/// Which pyramid level a render samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Lod {
    /// The coarsest level whose voxels project to at most about a pixel at the volume's
    /// centre (full resolution when the view is close).
    #[default]
    Auto,
    /// This level (0: full resolution), or the coarsest there is.
    Level(usize),
}

/// Where a bricked volume's value statistics (range, histogram, chunk ranges) come from:
/// framing and the transfer-function presets use them, so they decide whether a store
/// rendered out of core looks as the same data held whole.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoreStatistics {
    /// Recorded by the store (Volux's writer): nothing was read to find them, and they are
    /// the full level's.
    Recorded,
    /// Found by reading the full level twice at opening (a store that records none):
    /// the full level's, as in memory.
    ReadAtOpening,
    /// The range and chunk ranges are recorded, the histogram is not: the presets fit the
    /// histogram of this coarser level.
    HistogramOfLevel(usize),
}

impl StoreStatistics {
    /// What a user should know when the statistics are not simply recorded: the time spent
    /// reading them, or the presets fitted on a coarser level.
    pub fn note(self) -> Option<String> {
        match self {
            Self::Recorded => None,
            Self::ReadAtOpening => Some(
                "the store records no value statistics: its full level was read twice at \
                 opening to frame it and fit the presets as in memory (stores written by Volux \
                 record them)"
                    .into(),
            ),
            Self::HistogramOfLevel(level) => Some(format!(
                "the store records no histogram: the presets fit level {level}'s, so an \
                 automatic transfer function can differ slightly from the one of the data held \
                 whole"
            )),
        }
    }
}

/// A volume stored in chunks, rendered without holding it whole: each level's chunks are
/// read into a cache of bounded size as rays need them (seed `003`, done exactly: one pass,
/// opacity carried across bricks).
pub struct BrickedVolume {
    multiscale: Multiscale,
    caches: Vec<BrickCache>,
    /// Per level, the chunks as macrocells for empty-space skipping (built on first use;
    /// `None` when the store does not record every chunk's range).
    chunk_cells: Vec<OnceLock<Option<MacrocellGrid>>>,
    /// The full level's chunk ranges found by reading it, for a store that records neither
    /// them nor its range (x fastest); `None` when the store records its range.
    scanned_ranges: Option<Vec<[f64; 2]>>,
    range: [f64; 2],
    histogram: Histogram,
    statistics: StoreStatistics,
}

impl std::fmt::Debug for BrickedVolume {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BrickedVolume")
            .field("multiscale", &self.multiscale)
            .field("range", &self.range)
            .finish()
    }
}

/// The bins of the kept histogram (as many as the presets are fitted on,
/// `scene::HISTOGRAM_BINS`).
const KEPT_BINS: usize = volux_core::histogram::STORED_BINS;

/// The histogram is taken from the finest level with at most this many samples (read whole,
/// chunk by chunk: 64 MiB of f32).
const HISTOGRAM_SAMPLES: usize = 1 << 24;

impl BrickedVolume {
    /// `multiscale` with its bricks cached within `budget` bytes, shared by all levels (one
    /// least-recently-used order over them). Finds the statistics that framing and the
    /// transfer-function presets use, the same as for the data held whole:
    /// - the value range, recorded by the store (Volux's writer records it), else read chunk
    ///   by chunk from the full level, with each chunk's range (for framing and empty-space
    ///   skipping, [`BrickedVolume::chunk_cells`]);
    /// - the full level's histogram, recorded by the store, else counted in a second read of
    ///   the full level when the first one was needed anyway; a store that records its range
    ///   but not its histogram gets the one of its finest level of at most 2^24 samples
    ///   ([`BrickedVolume::statistics`] says which).
    ///
    /// Errors name a chunk that cannot be read.
    pub fn open(multiscale: Multiscale, budget: u64) -> Result<Self, RenderError> {
        for level in multiscale.levels() {
            check_addressable(level.layout())?;
        }
        let full = multiscale.full();
        let (range, scanned_ranges) = match full.value_range() {
            Some(r) => (r, None),
            None => {
                let (r, chunks) = scan_range(full.as_ref())?;
                (r, Some(chunks))
            }
        };
        // The full level's histogram when the store records it over the same range (the
        // presets then fit as on the data in memory), else one of a coarse level.
        let recorded = full
            .value_histogram()
            .filter(|h| h.min == range[0] && h.max == range[1] && h.counts.len() == KEPT_BINS);
        let (histogram, statistics) = match recorded {
            Some(h) => (h, StoreStatistics::Recorded),
            None if scanned_ranges.is_some() => (
                full_histogram(full.as_ref(), range)?,
                StoreStatistics::ReadAtOpening,
            ),
            None => {
                let (h, level) = coarse_histogram(&multiscale, range)?;
                let statistics = match level {
                    0 => StoreStatistics::Recorded,
                    l => StoreStatistics::HistogramOfLevel(l),
                };
                (h, statistics)
            }
        };
        let caches = BrickCache::shared(multiscale.levels(), budget);
        let chunk_cells = caches.iter().map(|_| OnceLock::new()).collect();
        Ok(Self {
            multiscale,
            caches,
            chunk_cells,
            scanned_ranges,
            range,
            histogram,
            statistics,
        })
    }

    /// The cache figures of all levels together (hits, chunks read, bytes decoded,
    /// evictions; the pool's peak).
    pub fn cache_totals(&self) -> CacheStats {
        (0..self.levels()).filter_map(|l| self.cache_stats(l)).fold(
            CacheStats::default(),
            |t, s| CacheStats {
                hits: t.hits + s.hits,
                misses: t.misses + s.misses,
                bytes_read: t.bytes_read + s.bytes_read,
                evictions: t.evictions + s.evictions,
                rereads: t.rereads + s.rereads,
                peak_bytes: t.peak_bytes.max(s.peak_bytes),
            },
        )
    }

    /// The pyramid.
    pub fn multiscale(&self) -> &Multiscale {
        &self.multiscale
    }

    /// The figures of level `level`'s cache.
    pub fn cache_stats(&self, level: usize) -> Option<CacheStats> {
        self.caches.get(level).map(BrickCache::stats)
    }

    /// Level `level`'s chunks as macrocells of one chunk each, for empty-space skipping
    /// under the current TF from the ranges the store records (no chunk is read): each
    /// macrocell's range is the union of its chunk's and of the next chunks' along each axis,
    /// whose first samples its cells reach. `None` when a chunk's range is unknown.
    pub fn chunk_cells(&self, level: usize) -> Option<&MacrocellGrid> {
        let source = self.multiscale.levels().get(level)?;
        self.chunk_cells
            .get(level)?
            .get_or_init(|| {
                let layout = source.layout();
                let recorded: Option<Vec<[f64; 2]>> = (0..layout.chunk_count())
                    .map(|i| source.chunk_range(layout.chunk_coords(i)))
                    .collect();
                let scanned = (level == 0).then(|| self.scanned_ranges.clone()).flatten();
                chunk_cells(layout, &recorded.or(scanned)?)
            })
            .as_ref()
    }

    /// Where the range, histogram and chunk ranges come from.
    pub fn statistics(&self) -> StoreStatistics {
        self.statistics
    }

    /// The full-resolution level's world box.
    pub fn bounds(&self) -> Aabb {
        let l = self.multiscale.full().layout();
        let origin = l.origin_vec();
        let far = origin + l.spacing_vec() * DVec3::from(l.dims.map(|d| (d - 1) as f64));
        Aabb {
            min: origin.min(far),
            max: origin.max(far),
        }
    }

    /// The smallest and largest sample of the full-resolution level.
    pub fn range(&self) -> [f64; 2] {
        self.range
    }

    /// The histogram the presets fit ([`BrickedVolume::statistics`] says of which level) over
    /// [`BrickedVolume::range`] with `bins` bins
    /// (from the kept one of 256 bins, each counted in the new bin holding its centre, when
    /// `bins` differs).
    pub fn histogram(&self, bins: usize) -> Histogram {
        let h = &self.histogram;
        if h.counts.len() == bins {
            return h.clone();
        }
        let bins = bins.max(1);
        let mut counts = vec![0u64; bins];
        for (b, &n) in h.counts.iter().enumerate() {
            let centre = (b as f64 + 0.5) / h.counts.len() as f64;
            counts[((centre * bins as f64) as usize).min(bins - 1)] += n;
        }
        Histogram {
            counts,
            ..h.clone()
        }
    }

    /// The smallest spacing of the full-resolution level.
    pub fn unit_length(&self) -> f64 {
        self.multiscale
            .full()
            .layout()
            .spacing
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min)
    }

    /// The level `lod` picks when a pixel covers `pixel` world units at the volume's centre:
    /// the coarsest whose smallest spacing is at most that (full resolution when none is).
    pub fn level_for(&self, lod: Lod, pixel: f64) -> usize {
        let last = self.caches.len() - 1;
        match lod {
            Lod::Level(n) => n.min(last),
            Lod::Auto => (0..=last)
                .rev()
                .find(|&n| {
                    let s = self.caches[n].layout().spacing;
                    s.iter().cloned().fold(f64::INFINITY, f64::min) <= pixel
                })
                .unwrap_or(0),
        }
    }

    /// Level `level`'s cache.
    pub fn cache(&self, level: usize) -> Option<&BrickCache> {
        self.caches.get(level)
    }

    /// The number of levels.
    pub fn levels(&self) -> usize {
        self.caches.len()
    }

    /// The bytes of bricks resident now, over every level's cache (what a viewer's status
    /// line shows against [`BrickedVolume::budget`]).
    pub fn resident_bytes(&self) -> u64 {
        self.caches.iter().map(BrickCache::resident_bytes).sum()
    }

    /// The memory budget the volume was opened with (bytes).
    pub fn budget(&self) -> u64 {
        self.caches.first().map_or(0, BrickCache::budget)
    }
}

/// The range of the level's finite samples and each chunk's (`[0, 0]` for a chunk with
/// none), read one chunk per thread at a time.
fn scan_range(level: &dyn ChunkSource) -> Result<([f64; 2], Vec<[f64; 2]>), RenderError> {
    let layout = level.layout();
    let ranges: Result<Vec<[f64; 2]>, volux_core::Error> = (0..layout.chunk_count())
        .into_par_iter()
        .map(|i| {
            let s = level.read_chunk(layout.chunk_coords(i))?;
            Ok(volux_core::with_samples!(&s, |v| v.iter().fold(
                [f64::INFINITY, f64::NEG_INFINITY],
                |r, x| {
                    let x = f64::from(x.to_f32());
                    if x.is_finite() {
                        [r[0].min(x), r[1].max(x)]
                    } else {
                        r
                    }
                }
            )))
        })
        .collect();
    let ranges = ranges?;
    let r = ranges
        .iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |a, b| {
            [a[0].min(b[0]), a[1].max(b[1])]
        });
    if r[0] > r[1] {
        return Err(RenderError::Data(volux_core::Error::Chunked(
            "the volume has no finite sample".into(),
        )));
    }
    // A chunk with no finite sample as Volux's writer records it.
    let ranges = ranges
        .into_iter()
        .map(|c| if c[0] <= c[1] { c } else { [0.0, 0.0] })
        .collect();
    Ok((r, ranges))
}

/// The full level's histogram over `range` with [`KEPT_BINS`] bins, counted chunk by chunk
/// (the counts of [`Histogram::from_values`] on the level held whole).
fn full_histogram(level: &dyn ChunkSource, range: [f64; 2]) -> Result<Histogram, RenderError> {
    let layout = level.layout();
    let counts: Result<Vec<u64>, volux_core::Error> = (0..layout.chunk_count())
        .into_par_iter()
        .map(|i| {
            let s = level.read_chunk(layout.chunk_coords(i))?;
            Ok(volux_core::with_samples!(&s, |v| Histogram::from_values(
                v, range, KEPT_BINS
            )
            .counts))
        })
        .try_reduce(
            || vec![0u64; KEPT_BINS],
            |mut a, b| {
                a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                Ok(a)
            },
        );
    Ok(Histogram {
        min: range[0],
        max: range[1],
        counts: counts?,
    })
}

/// The histogram over `range` of the finest level with at most [`HISTOGRAM_SAMPLES`]
/// samples (the full level when it is that small: the presets then match the in-core grid's),
/// and that level.
fn coarse_histogram(ms: &Multiscale, range: [f64; 2]) -> Result<(Histogram, usize), RenderError> {
    let bins = KEPT_BINS;
    let Some((index, level)) = ms
        .levels()
        .iter()
        .enumerate()
        .find(|(_, l)| l.layout().dims.iter().product::<usize>() <= HISTOGRAM_SAMPLES)
    else {
        let coarsest = ms
            .levels()
            .last()
            .map_or(0, |l| l.layout().dims.iter().product::<usize>());
        return Err(RenderError::OverLimit {
            what: format!("{}: the coarsest level (samples)", ms.name),
            count: coarsest as u64,
            limit: HISTOGRAM_SAMPLES as u64,
            remedy: Some(Remedy::WritePyramid),
        });
    };
    let layout = level.layout();
    let mut values: Vec<f32> = Vec::with_capacity(layout.dims.iter().product());
    for i in 0..layout.chunk_count() {
        let s = level.read_chunk(layout.chunk_coords(i))?;
        volux_core::with_samples!(&s, |v| values.extend(v.iter().map(|x| x.to_f32())));
    }
    Ok((Histogram::from_values(&values, range, bins), index))
}

/// The macrocells of [`BrickedVolume::chunk_cells`].
fn chunk_cells(layout: &ChunkLayout, ranges: &[[f64; 2]]) -> Option<MacrocellGrid> {
    let n = layout.chunks_per_axis();
    let cells = (0..ranges.len())
        .map(|i| {
            let c = layout.chunk_coords(i);
            let mut r = [f64::INFINITY, f64::NEG_INFINITY];
            for q in 0..8 {
                let d = [q & 1, q >> 1 & 1, q >> 2 & 1];
                let at: [usize; 3] = std::array::from_fn(|a| c[a] + d[a]);
                if (0..3).all(|a| at[a] < n[a]) {
                    let s = ranges[layout.chunk_index(at)];
                    r = [r[0].min(s[0]), r[1].max(s[1])];
                }
            }
            // Widened to f32 outward, so that every sample stays inside.
            let lo = r[0] as f32;
            let hi = r[1] as f32;
            let lo = if f64::from(lo) > r[0] {
                lo.next_down()
            } else {
                lo
            };
            let hi = if f64::from(hi) < r[1] {
                hi.next_up()
            } else {
                hi
            };
            [lo, hi]
        })
        .collect();
    MacrocellGrid::from_ranges(n, layout.chunk, cells)
}

/// Refuses a level whose chunks the field's tables cannot address: more than
/// [`MAX_CHUNKS`] chunks, or bricks of more than [`MAX_BRICK_SAMPLES`] samples.
fn check_addressable(layout: &ChunkLayout) -> Result<(), RenderError> {
    let chunks = layout.chunk_count() as u64;
    let samples = brick_bytes(layout.chunk) / 4;
    if chunks <= MAX_CHUNKS && samples <= MAX_BRICK_SAMPLES {
        return Ok(());
    }
    Err(RenderError::Data(volux_core::Error::Chunked(format!(
        "a level of {:?} samples in chunks of {:?} cannot be rendered out of core (at most \
         {MAX_CHUNKS} chunks and {MAX_BRICK_SAMPLES} samples per chunk): rechunk it with \
         `volux convert --chunk`",
        layout.dims, layout.chunk
    ))))
}
