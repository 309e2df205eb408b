//! Volumes stored in chunks (bricks) and read one chunk at a time: the seam between chunked
//! storage (OME-Zarr in `volux-io`) and the bricked renderer (`volux-render`), after seed
//! `003` (volumes larger than memory, split into blocks). A [`ChunkSource`] is one
//! resolution level: a regular lattice of samples cut into chunks of one shape (the last
//! chunk along an axis is clipped to the grid); a [`Multiscale`] is the pyramid of levels,
//! each the one before averaged 2x along every axis.
use std::sync::Arc;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::grid::{Buffer, Grid, Samples, ScalarType};
use crate::histogram::{Histogram, STORED_BINS};

/// The geometry of a chunked level: samples per axis, chunk shape, voxel spacing and origin
/// (world units, axis-aligned), and the scalar type of its samples.
#[derive(Clone, Debug, PartialEq)]
pub struct ChunkLayout {
    /// Samples per axis, x fastest.
    pub dims: [usize; 3],
    /// Samples per chunk along each axis (edge chunks are clipped to `dims`).
    pub chunk: [usize; 3],
    /// Distance between samples per axis (world units, millimetres for medical data).
    pub spacing: [f64; 3],
    /// World position of sample (0, 0, 0).
    pub origin: [f64; 3],
    /// The type the samples are stored as.
    pub scalar: ScalarType,
}

impl ChunkLayout {
    /// A layout, checked: every dimension and chunk side at least 1, spacing finite and
    /// positive, origin finite.
    pub fn new(
        dims: [usize; 3],
        chunk: [usize; 3],
        spacing: [f64; 3],
        origin: [f64; 3],
        scalar: ScalarType,
    ) -> Result<Self> {
        if dims.contains(&0) || chunk.contains(&0) {
            return Err(Error::Chunked(format!(
                "a chunked volume needs at least one sample and one sample per chunk along each axis (dims {dims:?}, chunk {chunk:?})"
            )));
        }
        if spacing.iter().any(|s| !s.is_finite() || *s <= 0.0)
            || origin.iter().any(|o| !o.is_finite())
        {
            return Err(Error::Chunked(format!(
                "a chunked volume needs a finite positive spacing and a finite origin (spacing {spacing:?}, origin {origin:?})"
            )));
        }
        Ok(Self {
            dims,
            chunk,
            spacing,
            origin,
            scalar,
        })
    }

    /// Chunks per axis.
    pub fn chunks_per_axis(&self) -> [usize; 3] {
        std::array::from_fn(|a| self.dims[a].div_ceil(self.chunk[a]))
    }

    /// The number of chunks.
    pub fn chunk_count(&self) -> usize {
        self.chunks_per_axis().iter().product()
    }

    /// The first sample of chunk `c` and the samples it holds per axis (clipped to the grid).
    pub fn chunk_extent(&self, c: [usize; 3]) -> ([usize; 3], [usize; 3]) {
        let lo: [usize; 3] = std::array::from_fn(|a| c[a] * self.chunk[a]);
        let size = std::array::from_fn(|a| self.chunk[a].min(self.dims[a].saturating_sub(lo[a])));
        (lo, size)
    }

    /// [`ChunkLayout::chunk_extent`] of a chunk that must exist: an error names a chunk
    /// outside the grid of chunks.
    pub fn checked_extent(&self, c: [usize; 3]) -> Result<([usize; 3], [usize; 3])> {
        let n = self.chunks_per_axis();
        if (0..3).any(|a| c[a] >= n[a]) {
            return Err(Error::Chunked(format!(
                "chunk {c:?} is outside the {n:?} chunks of the volume"
            )));
        }
        Ok(self.chunk_extent(c))
    }

    /// The index of chunk `c`, x fastest.
    pub fn chunk_index(&self, c: [usize; 3]) -> usize {
        let n = self.chunks_per_axis();
        c[0] + n[0] * (c[1] + n[1] * c[2])
    }

    /// The chunk coordinates of index `i` (x fastest).
    pub fn chunk_coords(&self, i: usize) -> [usize; 3] {
        let n = self.chunks_per_axis();
        [i % n[0], (i / n[0]) % n[1], i / (n[0] * n[1])]
    }

    /// Spacing as a vector.
    pub fn spacing_vec(&self) -> DVec3 {
        DVec3::from(self.spacing)
    }

    /// Origin as a vector.
    pub fn origin_vec(&self) -> DVec3 {
        DVec3::from(self.origin)
    }

    /// Bytes the whole level takes in memory.
    pub fn bytes(&self) -> u128 {
        self.dims.iter().map(|&d| d as u128).product::<u128>() * self.scalar.size() as u128
    }
}

/// One resolution level of a chunked volume, read chunk by chunk (the bricked renderer never
/// holds the whole level). Implementations must be cheap to share between threads: chunks
/// are read from worker threads.
pub trait ChunkSource: Send + Sync {
    /// The level's geometry.
    fn layout(&self) -> &ChunkLayout;

    /// The samples of chunk `c` (chunk coordinates): exactly the chunk's in-grid samples
    /// (`layout().chunk_extent(c).1`, x fastest), of `layout().scalar`. A missing chunk of a
    /// store with a fill value reads as the fill value; a corrupt, truncated or mis-sized chunk
    /// is an error that names it.
    fn read_chunk(&self, c: [usize; 3]) -> Result<Samples>;

    /// The smallest and largest sample of chunk `c` when the store records them (no read);
    /// `None` when unknown.
    fn chunk_range(&self, _c: [usize; 3]) -> Option<[f64; 2]> {
        None
    }

    /// The smallest and largest sample of the level when known without reading it.
    fn value_range(&self) -> Option<[f64; 2]> {
        None
    }

    /// The histogram of the level's samples over [`ChunkSource::value_range`] in
    /// [`STORED_BINS`] bins, when known without reading the level (Volux's OME-Zarr writer
    /// records it): the transfer-function presets then fit a store read out of core as
    /// they fit the same data held whole.
    fn value_histogram(&self) -> Option<Histogram> {
        None
    }
}

/// A pyramid of levels, level 0 at full resolution; each next level halves the samples per
/// axis (rounding up) by 2x averaging and doubles the spacing.
#[derive(Clone)]
pub struct Multiscale {
    levels: Vec<Arc<dyn ChunkSource>>,
    /// What the volume is called (a file name, an array path), for messages.
    pub name: String,
}

impl std::fmt::Debug for Multiscale {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Multiscale")
            .field("name", &self.name)
            .field(
                "levels",
                &self
                    .levels
                    .iter()
                    .map(|l| l.layout().clone())
                    .collect::<Vec<_>>(),
            )
            .finish()
    }
}

impl Multiscale {
    /// A pyramid of `levels`, full resolution first; at least one level.
    pub fn new(name: impl Into<String>, levels: Vec<Arc<dyn ChunkSource>>) -> Result<Self> {
        if levels.is_empty() {
            return Err(Error::Chunked(
                "a multiscale volume needs at least one level".into(),
            ));
        }
        Ok(Self {
            levels,
            name: name.into(),
        })
    }

    /// The levels, full resolution first.
    pub fn levels(&self) -> &[Arc<dyn ChunkSource>] {
        &self.levels
    }

    /// Level 0.
    pub fn full(&self) -> &Arc<dyn ChunkSource> {
        &self.levels[0]
    }
}

/// A grid in memory seen as chunks (tests, and converting an in-core or memory-mapped grid
/// to a chunked store): each chunk read copies its samples out of the grid.
#[derive(Clone, Debug)]
pub struct GridChunks {
    grid: Arc<Grid>,
    layout: ChunkLayout,
}

impl GridChunks {
    /// `grid` cut into chunks of `chunk` samples per axis (its direction, if any, is not
    /// carried: chunked levels are axis-aligned).
    pub fn new(grid: Arc<Grid>, chunk: [usize; 3]) -> Result<Self> {
        let layout = ChunkLayout::new(
            grid.dims(),
            chunk,
            grid.spacing().to_array(),
            grid.origin().to_array(),
            grid.scalar_type(),
        )?;
        Ok(Self { grid, layout })
    }
}

impl ChunkSource for GridChunks {
    fn layout(&self) -> &ChunkLayout {
        &self.layout
    }

    fn read_chunk(&self, c: [usize; 3]) -> Result<Samples> {
        let (lo, size) = self.layout.checked_extent(c)?;
        let dims = self.layout.dims;
        fn copy<T: crate::grid::Scalar>(
            v: &[T],
            dims: [usize; 3],
            lo: [usize; 3],
            size: [usize; 3],
        ) -> Buffer<T> {
            let mut out = Vec::with_capacity(size.iter().product());
            for k in lo[2]..lo[2] + size[2] {
                for j in lo[1]..lo[1] + size[1] {
                    let row = dims[0] * (j + dims[1] * k);
                    out.extend_from_slice(&v[row + lo[0]..row + lo[0] + size[0]]);
                }
            }
            Buffer::owned(out)
        }
        Ok(match self.grid.samples() {
            Samples::U8(b) => Samples::U8(copy(b.as_slice(), dims, lo, size)),
            Samples::U16(b) => Samples::U16(copy(b.as_slice(), dims, lo, size)),
            Samples::I16(b) => Samples::I16(copy(b.as_slice(), dims, lo, size)),
            Samples::F32(b) => Samples::F32(copy(b.as_slice(), dims, lo, size)),
        })
    }

    /// Scanned from the grid in memory (what a store records in its attributes); infinite
    /// when the chunk has no finite sample.
    fn chunk_range(&self, c: [usize; 3]) -> Option<[f64; 2]> {
        use crate::grid::Scalar;
        let samples = self.read_chunk(c).ok()?;
        let mut r = [f64::INFINITY, f64::NEG_INFINITY];
        crate::with_samples!(&samples, |v| {
            for x in v.iter() {
                let x = f64::from(x.to_f32());
                if x.is_finite() {
                    r = [r[0].min(x), r[1].max(x)];
                }
            }
        });
        Some(r)
    }

    fn value_range(&self) -> Option<[f64; 2]> {
        Some(self.grid.range())
    }

    fn value_histogram(&self) -> Option<Histogram> {
        Some(Histogram::of_grid(&self.grid, STORED_BINS))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_reads_back_chunk_by_chunk_with_clipped_edge_chunks() {
        let dims = [7, 5, 3];
        let values: Vec<f32> = (0..7 * 5 * 3).map(|i| i as f32).collect();
        let grid = Grid::new(
            dims,
            [1.0, 2.0, 3.0],
            [0.5; 3],
            Samples::F32(Buffer::owned(values)),
        )
        .unwrap();
        let chunks = GridChunks::new(Arc::new(grid.clone()), [4, 4, 2]).unwrap();
        let layout = chunks.layout();
        assert_eq!(layout.chunks_per_axis(), [2, 2, 2]);
        let mut seen = 0;
        for i in 0..layout.chunk_count() {
            let c = layout.chunk_coords(i);
            assert_eq!(layout.chunk_index(c), i);
            let (lo, size) = layout.chunk_extent(c);
            let Samples::F32(b) = chunks.read_chunk(c).unwrap() else {
                panic!("f32 chunk")
            };
            assert_eq!(b.len(), size.iter().product::<usize>());
            for (n, v) in b.as_slice().iter().enumerate() {
                let (x, y, z) = (
                    n % size[0],
                    (n / size[0]) % size[1],
                    n / (size[0] * size[1]),
                );
                assert_eq!(*v, grid.value(lo[0] + x, lo[1] + y, lo[2] + z));
            }
            seen += b.len();
        }
        assert_eq!(seen, 7 * 5 * 3);
        assert!(chunks.read_chunk([2, 0, 0]).is_err());
        assert!(ChunkLayout::new([0, 1, 1], [1; 3], [1.0; 3], [0.0; 3], ScalarType::U8).is_err());
        assert!(
            ChunkLayout::new([1; 3], [1; 3], [0.0, 1.0, 1.0], [0.0; 3], ScalarType::U8).is_err()
        );
    }
}
