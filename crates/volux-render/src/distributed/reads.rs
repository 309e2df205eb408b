//! A chunk source that counts what a rank reads ([`CountedChunks`]): its own region's
//! chunks, the neighbours' chunks next to its faces (trilinear cells and steps straddling a
//! face read them), and any other (none, when the split works as designed).
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use volux_core::bricked::{ChunkLayout, ChunkSource};
use volux_core::grid::Samples;

use super::kdtree::ChunkBox;

/// What a rank read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ReadStats {
    /// Chunks of its own region read.
    pub own: u64,
    /// Chunks of neighbouring regions read (next to a face, edge or corner of its box).
    pub neighbours: u64,
    /// Chunks read farther away (0 unless something is wrong).
    pub other: u64,
    /// Bytes of samples read (as stored).
    pub bytes: u64,
}

/// `inner` with every chunk read counted against `region`.
pub struct CountedChunks {
    inner: Arc<dyn ChunkSource>,
    region: ChunkBox,
    own: AtomicU64,
    neighbours: AtomicU64,
    other: AtomicU64,
    bytes: AtomicU64,
}

impl CountedChunks {
    /// Counts the reads of `inner` by the rank of `region`.
    pub fn new(inner: Arc<dyn ChunkSource>, region: ChunkBox) -> Self {
        Self {
            inner,
            region,
            own: AtomicU64::new(0),
            neighbours: AtomicU64::new(0),
            other: AtomicU64::new(0),
            bytes: AtomicU64::new(0),
        }
    }

    /// The counts so far.
    pub fn stats(&self) -> ReadStats {
        ReadStats {
            own: self.own.load(Ordering::Relaxed),
            neighbours: self.neighbours.load(Ordering::Relaxed),
            other: self.other.load(Ordering::Relaxed),
            bytes: self.bytes.load(Ordering::Relaxed),
        }
    }
}

impl ChunkSource for CountedChunks {
    fn layout(&self) -> &ChunkLayout {
        self.inner.layout()
    }

    fn read_chunk(&self, c: [usize; 3]) -> volux_core::Result<Samples> {
        let s = self.inner.read_chunk(c)?;
        let counter = if self.region.contains(c) {
            &self.own
        } else if self.region.near(c) {
            &self.neighbours
        } else {
            &self.other
        };
        counter.fetch_add(1, Ordering::Relaxed);
        let (_, size) = self.layout().chunk_extent(c);
        let bytes = size.iter().product::<usize>() * self.layout().scalar.size();
        self.bytes.fetch_add(bytes as u64, Ordering::Relaxed);
        Ok(s)
    }

    fn chunk_range(&self, c: [usize; 3]) -> Option<[f64; 2]> {
        self.inner.chunk_range(c)
    }

    fn value_range(&self) -> Option<[f64; 2]> {
        self.inner.value_range()
    }
}
