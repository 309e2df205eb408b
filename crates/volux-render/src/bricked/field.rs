//! Field sampling of a bricked level: trilinear interpolation on the global sample lattice,
//! exact across brick faces (a cell whose corners lie in several chunks gathers each corner
//! from its own chunk), with the arithmetic of the in-core sampler
//! ([`Trilinear`](crate::sampling::Trilinear): the same cells, by [`clamped_cell`], and the
//! same lerps), so that a bricked render equals the in-core render of the same data.
//!
//! A lane finds its chunk and its place in it through two per-axis tables (no division),
//! its brick through this thread's [memo](super::memo), and, when its cell lies within
//! the brick (all but the cells on a chunk's far faces: 4.6 % of cells for 64³ chunks), its
//! eight corners at fixed displacements from one address.
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

use glam::{DVec3, Vec3};

use super::cache::{axis_offset, Brick, BrickCache, CORNERS, REACH};
use super::memo::{self, Entry, MAX_SLOTS};
use crate::sampling::{axis64, clamped_cell, Field, LANES};

/// The flag of [`BrickedField`]'s axis tables marking a chunk's far face.
const EDGE: usize = 1 << (usize::BITS - 1);

/// A bricked level as a [`Field`] for one render. A chunk that cannot be read makes its
/// samples undefined, keeps the first error and raises `failed` (the render is stopped and
/// the error returned instead of the image).
pub(crate) struct BrickedField<'a> {
    cache: &'a BrickCache,
    id: u64,
    dims: [usize; 3],
    /// Largest coordinate and largest cell index per axis, as [`clamped_cell`] takes them.
    hi: [f32; 3],
    cell_max: [i32; 3],
    /// Per axis and sample index: what the sample's chunk coordinate adds to the chunk's
    /// index, and what its place in the chunk adds to its offset in the brick, with [`EDGE`]
    /// set where a cell starting there has its far corner in the next chunk.
    axes: [Vec<[usize; 2]>; 3],
    /// 1 along the axes with more than one sample.
    next: [usize; 3],
    /// Memo slots this field uses.
    slots: usize,
    error: OnceLock<String>,
    failed: Arc<AtomicBool>,
}

impl<'a> BrickedField<'a> {
    /// The field of `cache`'s level, whose per-thread memos hold at most `memo_bytes` bytes
    /// of bricks over `threads` threads; `failed` is raised on the first chunk error.
    pub(crate) fn new(
        cache: &'a BrickCache,
        memo_bytes: u64,
        threads: usize,
        failed: Arc<AtomicBool>,
    ) -> Self {
        let layout = cache.layout();
        let (dims, chunk) = (layout.dims, layout.chunk);
        let counts = layout.chunks_per_axis();
        let next = dims.map(|n| usize::from(n > 1));
        let chunk_stride = [1, counts[0], counts[0] * counts[1]];
        let axes = std::array::from_fn(|a| {
            let c = chunk[a].max(1);
            (0..dims[a])
                .map(|i| {
                    let (lo, local) = (i / c * c, i % c);
                    let size = c.min(dims[a] - lo);
                    let edge = if local + next[a] < size { 0 } else { EDGE };
                    [i / c * chunk_stride[a], axis_offset(chunk, a, local) | edge]
                })
                .collect()
        });
        let brick_bytes = chunk.iter().product::<usize>() as u64 * 4;
        Self {
            cache,
            id: memo::new_id(),
            dims,
            hi: dims.map(|n| n.saturating_sub(1) as f32),
            cell_max: dims.map(|n| n.saturating_sub(2) as i32),
            axes,
            next,
            slots: memo::slots_for(memo_bytes, brick_bytes, threads),
            error: OnceLock::new(),
            failed,
        }
    }

    /// The field of `cache`'s level for a render on the current rayon pool, whose threads'
    /// memos hold at most a quarter of the cache's budget (at least four bricks per thread).
    pub(crate) fn for_render(cache: &'a BrickCache, failed: Arc<AtomicBool>) -> Self {
        let threads = rayon::current_num_threads();
        Self::new(cache, cache.budget() / 4, threads, failed)
    }

    /// The first chunk error of the render, if any.
    pub(crate) fn error(&self) -> Option<&String> {
        self.error.get()
    }

    /// Drops this field's bricks from the threads' memos (at the end of a render).
    pub(crate) fn forget(&self) {
        memo::forget(self.id);
    }

    /// The brick of chunk `index`, from `memo` or the cache; `None` (the error kept) when
    /// the chunk cannot be read.
    #[inline(always)]
    fn brick<'m>(&self, memo: &'m mut [Entry; MAX_SLOTS], index: usize) -> Option<&'m Brick> {
        let entry = &mut memo[memo::slot_of(index, self.slots)];
        let hit = matches!(&*entry, Some((id, at, _)) if *id == self.id && *at == index);
        if !hit {
            match self.cache.get(self.cache.layout().chunk_coords(index)) {
                Ok(b) => *entry = Some((self.id, index, b)),
                Err(e) => {
                    let _ = self.error.set(e);
                    self.failed.store(true, Ordering::Relaxed);
                    return None;
                }
            }
        }
        entry.as_ref().map(|(_, _, b)| &**b)
    }

    /// The chunk index of sample `s` and its offset in that chunk's brick, with [`EDGE`] set
    /// when a cell starting there has corners in the next chunks (`None` outside the grid).
    #[inline(always)]
    fn locate(&self, s: [usize; 3]) -> Option<(usize, usize)> {
        let [x, y, z] = [
            self.axes[0].get(s[0])?,
            self.axes[1].get(s[1])?,
            self.axes[2].get(s[2])?,
        ];
        let edge = (x[1] | y[1] | z[1]) & EDGE;
        let at = (x[1] & !EDGE) + (y[1] & !EDGE) + (z[1] & !EDGE);
        Some((x[0] + y[0] + z[0], at | edge))
    }

    /// The eight corners of `cell` (x fastest), NaN where a chunk cannot be read.
    #[inline(always)]
    fn corners(&self, memo: &mut [Entry; MAX_SLOTS], cell: [usize; 3]) -> [f32; 8] {
        let Some((index, at)) = self.locate(cell) else {
            return [f32::NAN; 8];
        };
        if at & EDGE == 0 {
            return match self.brick(memo, index) {
                Some(b) => gather(&b.values, at),
                None => [f32::NAN; 8],
            };
        }
        // On a chunk's far face: each corner from its own chunk.
        let n = self.next;
        std::array::from_fn(|q| {
            let s = [
                cell[0] + n[0] * (q & 1),
                cell[1] + n[1] * (q >> 1 & 1),
                cell[2] + n[2] * (q >> 2 & 1),
            ];
            self.value(memo, s).unwrap_or(f32::NAN)
        })
    }

    /// Sample (`i`, `j`, `k`) of the grid.
    #[inline(always)]
    fn value(&self, memo: &mut [Entry; MAX_SLOTS], s: [usize; 3]) -> Option<f32> {
        let (index, at) = self.locate(s)?;
        self.brick(memo, index)?.values.get(at & !EDGE).copied()
    }

    /// `N` samples, NaN where undefined. Cells and fractions lane-wise; then each lane's
    /// brick is made resident in the memo (once per run of lanes in one chunk), the corners
    /// gathered through read-only lookups that reuse the previous lane's brick, and the lanes
    /// on a chunk's far faces (or whose brick another lane's displaced) sampled corner by
    /// corner; the lerps lane-wise.
    // Lane loops index several per-lane arrays at once: that is what vectorizes.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn sample_points<const N: usize>(&self, p: &[[f32; N]; 3]) -> [f32; N] {
        let (mut cell, mut frac) = ([[0i32; N]; 3], [[0.0f32; N]; 3]);
        for a in 0..3 {
            for l in 0..N {
                (cell[a][l], frac[a][l]) = clamped_cell(p[a][l], self.hi[a], self.cell_max[a]);
            }
        }
        let cells: [[usize; 3]; N] = std::array::from_fn(|l| {
            [
                cell[0][l].max(0) as usize,
                cell[1][l].max(0) as usize,
                cell[2][l].max(0) as usize,
            ]
        });
        let mut index = [usize::MAX; N];
        let mut at = [EDGE; N];
        for l in 0..N {
            if let Some((i, o)) = self.locate(cells[l]) {
                (index[l], at[l]) = (i, o);
            }
        }
        let mut c = [[f32::NAN; N]; 8];
        memo::with_memo(|memo| {
            let mut last = usize::MAX;
            for l in 0..N {
                if at[l] & EDGE == 0 && index[l] != last {
                    last = index[l];
                    // Errors are kept by `brick`; the lane then reads NaN below.
                    let _ = self.brick(memo, last);
                }
            }
            let mut missed = 0u64;
            let mut last: Option<(usize, &[f32])> = None;
            for l in 0..N {
                if at[l] & EDGE != 0 {
                    missed |= 1 << l;
                    continue;
                }
                let values = match last {
                    Some((i, v)) if i == index[l] => Some(v),
                    _ => self.resident(memo, index[l]),
                };
                match values {
                    Some(v) => {
                        last = Some((index[l], v));
                        let corners = gather(v, at[l]);
                        for q in 0..8 {
                            c[q][l] = corners[q];
                        }
                    }
                    None => missed |= 1 << l,
                }
            }
            while missed != 0 {
                let l = missed.trailing_zeros() as usize;
                missed &= missed - 1;
                let corners = self.corners(memo, cells[l]);
                for q in 0..8 {
                    c[q][l] = corners[q];
                }
            }
        });
        let mut out = lerp_corners(&c, &frac);
        for v in out.iter_mut() {
            if !v.is_finite() {
                *v = f32::NAN;
            }
        }
        out
    }

    /// The samples of chunk `index`'s brick if this thread's memo holds it.
    #[inline(always)]
    fn resident<'m>(&self, memo: &'m [Entry; MAX_SLOTS], index: usize) -> Option<&'m [f32]> {
        match &memo[memo::slot_of(index, self.slots)] {
            Some((id, at, b)) if *id == self.id && *at == index => Some(&b.values),
            _ => None,
        }
    }
}

/// The trilinear values of `N` cells from their corners `c` (`c[q][l]`: corner `q` of lane
/// `l`, x fastest) and fractions `f`, with the lerps of
/// [`Trilinear`](crate::sampling::Trilinear), lane-wise.
#[inline(always)]
fn lerp_corners<const N: usize>(c: &[[f32; N]; 8], f: &[[f32; N]; 3]) -> [f32; N] {
    let lerp = |a: [f32; N], b: [f32; N], t: [f32; N]| -> [f32; N] {
        std::array::from_fn(|l| a[l] + (b[l] - a[l]) * t[l])
    };
    let c00 = lerp(c[0], c[1], f[0]);
    let c10 = lerp(c[2], c[3], f[0]);
    let c01 = lerp(c[4], c[5], f[0]);
    let c11 = lerp(c[6], c[7], f[0]);
    let c0 = lerp(c00, c10, f[1]);
    let c1 = lerp(c01, c11, f[1]);
    lerp(c0, c1, f[2])
}

/// The eight corners of the cell whose first sample is at `at` in a brick's `values`, x
/// fastest (NaN if they would not fit: never for a cell within the brick).
#[inline(always)]
fn gather(values: &[f32], at: usize) -> [f32; 8] {
    match values.get(at..).and_then(|v| v.first_chunk::<REACH>()) {
        // Written out: `CORNERS.map` went through an outlined `try_map` per cell.
        Some(c) => [
            c[CORNERS[0]],
            c[CORNERS[1]],
            c[CORNERS[2]],
            c[CORNERS[3]],
            c[CORNERS[4]],
            c[CORNERS[5]],
            c[CORNERS[6]],
            c[CORNERS[7]],
        ],
        None => [f32::NAN; 8],
    }
}

impl Field for BrickedField<'_> {
    fn dims(&self) -> [usize; 3] {
        self.dims
    }

    #[inline]
    fn sample(&self, p: Vec3) -> Option<f32> {
        let v = self.sample_points(&[[p.x], [p.y], [p.z]])[0];
        v.is_finite().then_some(v)
    }

    #[inline]
    fn sample_lanes(&self, p: &[[f32; LANES]; 3]) -> [f32; LANES] {
        self.sample_points(p)
    }

    #[inline]
    fn sample4(&self, p: &[[f32; 4]; 3]) -> [f32; 4] {
        self.sample_points(p)
    }

    /// The in-core f64 path's arithmetic on the same corners.
    fn sample64(&self, p: DVec3) -> Option<f64> {
        let (i, fx) = axis64(p.x, self.dims[0]);
        let (j, fy) = axis64(p.y, self.dims[1]);
        let (k, fz) = axis64(p.z, self.dims[2]);
        let n = self.next;
        let v: [f64; 8] = memo::with_memo(|memo| {
            let mut v = [0.0f64; 8];
            for (q, v) in v.iter_mut().enumerate() {
                let s = [
                    i + n[0] * (q & 1),
                    j + n[1] * (q >> 1 & 1),
                    k + n[2] * (q >> 2 & 1),
                ];
                *v = f64::from(self.value(memo, s)?);
            }
            Some(v)
        })?;
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let c0 = lerp(lerp(v[0], v[1], fx), lerp(v[2], v[3], fx), fy);
        let c1 = lerp(lerp(v[4], v[5], fx), lerp(v[6], v[7], fx), fy);
        let r = lerp(c0, c1, fz);
        r.is_finite().then_some(r)
    }
}
