//! Field sampling of a bricked level: trilinear interpolation on the global sample lattice,
//! exact across brick faces (a cell whose corners lie in several chunks gathers each corner
//! from its own chunk), with the arithmetic of the in-core sampler
//! ([`Trilinear`](crate::sampling::Trilinear): the same cells, by [`clamped_cell`], and the
//! same lerps), so that a bricked render equals the in-core render of the same data.
//!
//! A warm level whose bricks fit twice in the budget is sampled through its whole copy in the
//! in-core layout ([`BrickCache::frame_bricks`]). Otherwise a lane finds its chunk and its
//! place in it through per-axis tables (no division), its brick through a table of the level's
//! bricks when they fit the budget (else through this thread's [memo](super::memo)), and,
//! when its cell lies within the brick (all but the cells on a chunk's far faces: 4.6 % of
//! cells for 64³ chunks), its eight corners at fixed displacements from one address.
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

use glam::{DVec3, Vec3};

use super::cache::{axis_offset, brick_bytes, Brick, BrickCache, FrameBricks, REACH};
use super::memo::{self, Entry, MAX_SLOTS};
use crate::raycast::cell_blocks::{
    cells_of_four, corners_in, lerp_corners, undefined_to_nan, CellBlocks,
};
use crate::sampling::{axis64, clamped_cell, Field, LANES};

/// The flags of a lane's offset (as [`BrickedField::locate`] gives it) marking a cell on a
/// chunk's far faces, one per axis.
const EDGE: usize = 7 << 61;

/// The layout of the axis tables' entries: the offset in the brick in the low 32 bits, one
/// far-face flag per axis in bits 32 to 34, and what the sample adds to its chunk's index
/// from bit 35 on; the sum of three axes' entries is then the sample's offset, flags and
/// chunk index at once (no field carries into the next).
const EDGE_SHIFT: u32 = 32;
const CHUNK_SHIFT: u32 = 35;
/// The most chunks and the most samples per brick the tables' fields hold.
pub(crate) const MAX_CHUNKS: u64 = 1 << (64 - CHUNK_SHIFT);
pub(crate) const MAX_BRICK_SAMPLES: u64 = 1 << EDGE_SHIFT;

/// The most bytes of bricks the memos of one render hold.
pub(crate) const MEMO_SHARE_MAX: u64 = 256 << 20;

/// Where a field finds a chunk's brick during its render.
enum Lookup {
    /// The level's whole copy ([`FrameBricks::Whole`]): the in-core bricked sampler.
    Whole(Arc<CellBlocks>),
    /// The level's bricks by chunk index ([`BrickCache::frame_table`], when the whole level
    /// fits the budget): one load per lane, no lock once a brick is in.
    Table(Vec<OnceLock<Arc<Brick>>>),
    /// Each thread's memo of the bricks it sampled last, with this many slots.
    Memo(usize),
}

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
    /// index, and what its place in the chunk adds to its offset in the brick, with the
    /// axis's far-face flag set where a cell starting there has its far corner in the next
    /// chunk (packed: [`CHUNK_SHIFT`]).
    axes: [Vec<u64>; 3],
    /// 1 along the axes with more than one sample.
    next: [usize; 3],
    lookup: Lookup,
    error: OnceLock<String>,
    failed: Arc<AtomicBool>,
}

impl<'a> BrickedField<'a> {
    /// The field of `cache`'s level through per-thread memos that hold at most
    /// `memo_bytes` bytes of bricks over `threads` threads; `failed` is raised on the first
    /// chunk error.
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
                    let edge = u64::from(local + next[a] >= size) << (EDGE_SHIFT + a as u32);
                    let offset = axis_offset(chunk, a, local) as u64;
                    ((i / c * chunk_stride[a]) as u64) << CHUNK_SHIFT | edge | offset
                })
                .collect()
        });
        Self {
            cache,
            id: memo::new_id(),
            dims,
            hi: dims.map(|n| n.saturating_sub(1) as f32),
            cell_max: dims.map(|n| n.saturating_sub(2) as i32),
            axes,
            next,
            lookup: Lookup::Memo(memo::slots_for(memo_bytes, brick_bytes(chunk), threads)),
            error: OnceLock::new(),
            failed,
        }
    }

    /// The field of `cache`'s level for a render on the current rayon pool: through a table
    /// of the level's bricks when they all fit the budget, else through the threads' memos,
    /// which hold at most a quarter of the cache's budget and at most [`MEMO_SHARE_MAX`]
    /// (at least four bricks per thread): bricks a memo holds after the cache evicted them
    /// are memory beyond the budget.
    pub(crate) fn for_render(cache: &'a BrickCache, failed: Arc<AtomicBool>) -> Self {
        let threads = rayon::current_num_threads();
        let share = (cache.budget() / 4).min(MEMO_SHARE_MAX);
        let mut field = Self::new(cache, share, threads, failed);
        field.lookup = match cache.frame_bricks() {
            Some(FrameBricks::Whole(whole)) => Lookup::Whole(whole),
            Some(FrameBricks::Table(table)) => Lookup::Table(table),
            None => field.lookup,
        };
        field
    }

    /// How the field finds its bricks: "whole", "table" or "memo".
    #[cfg(test)]
    pub(crate) fn lookup_name(&self) -> &'static str {
        match self.lookup {
            Lookup::Whole(_) => "whole",
            Lookup::Table(_) => "table",
            Lookup::Memo(_) => "memo",
        }
    }

    /// The first chunk error of the render, if any.
    pub(crate) fn error(&self) -> Option<&String> {
        self.error.get()
    }

    /// Drops this field's bricks from the threads' memos (at the end of a render).
    pub(crate) fn forget(&self) {
        if let Lookup::Memo(_) = self.lookup {
            memo::forget(self.id);
        }
    }

    /// Keeps the first chunk error and stops the render.
    #[cold]
    fn fail(&self, e: String) {
        let _ = self.error.set(e);
        self.failed.store(true, Ordering::Relaxed);
    }

    /// The brick of chunk `index`, from `memo` (with `slots` slots) or the cache; `None`
    /// (the error kept) when the chunk cannot be read.
    #[inline(always)]
    fn brick<'m>(
        &self,
        memo: &'m mut [Entry; MAX_SLOTS],
        slots: usize,
        index: usize,
    ) -> Option<&'m Brick> {
        let entry = &mut memo[memo::slot_of(index, slots)];
        let hit = matches!(&*entry, Some((id, at, _)) if *id == self.id && *at == index);
        if !hit {
            match self.cache.get(self.cache.layout().chunk_coords(index)) {
                Ok(b) => *entry = Some((self.id, index, b)),
                Err(e) => {
                    self.fail(e);
                    return None;
                }
            }
        }
        entry.as_ref().map(|(_, _, b)| &**b)
    }

    /// The brick of chunk `index` from `table`, read into it by the first lane that needs it.
    #[inline(always)]
    fn table_brick<'t>(
        &self,
        table: &'t [OnceLock<Arc<Brick>>],
        index: usize,
    ) -> Option<&'t Brick> {
        let slot = table.get(index)?;
        match slot.get() {
            Some(b) => Some(b),
            None => self.load(slot, index),
        }
    }

    /// Reads chunk `index` into its `slot` of the table.
    #[cold]
    #[inline(never)]
    fn load<'t>(&self, slot: &'t OnceLock<Arc<Brick>>, index: usize) -> Option<&'t Brick> {
        match self.cache.get(self.cache.layout().chunk_coords(index)) {
            Ok(b) => Some(slot.get_or_init(|| b)),
            Err(e) => {
                self.fail(e);
                None
            }
        }
    }

    /// The chunk index of sample `s` and its offset in that chunk's brick, with [`EDGE`] set
    /// when a cell starting there has corners in the next chunks (`None` outside the grid).
    #[inline(always)]
    fn locate(&self, s: [usize; 3]) -> Option<(usize, usize)> {
        let v = self.axes[0].get(s[0])? + self.axes[1].get(s[1])? + self.axes[2].get(s[2])?;
        let edge = (v >> EDGE_SHIFT & 7) << 61;
        Some((
            (v >> CHUNK_SHIFT) as usize,
            (u64::from(v as u32) | edge) as usize,
        ))
    }

    /// The samples of the eight corners of the cell starting at `cell`, x fastest.
    #[inline(always)]
    fn corner_samples(&self, cell: [usize; 3]) -> [[usize; 3]; 8] {
        let n = self.next;
        std::array::from_fn(|q| {
            [
                cell[0] + n[0] * (q & 1),
                cell[1] + n[1] * (q >> 1 & 1),
                cell[2] + n[2] * (q >> 2 & 1),
            ]
        })
    }

    /// The eight corners of `cell` (x fastest) through the memo, NaN where a chunk cannot be
    /// read.
    #[inline(always)]
    fn corners(&self, memo: &mut [Entry; MAX_SLOTS], slots: usize, cell: [usize; 3]) -> [f32; 8] {
        let Some((index, at)) = self.locate(cell) else {
            return [f32::NAN; 8];
        };
        if at & EDGE == 0 {
            return match self.brick(memo, slots, index) {
                Some(b) => gather(&b.values, at),
                None => [f32::NAN; 8],
            };
        }
        // On a chunk's far face: each corner from its own chunk.
        self.corner_samples(cell)
            .map(|s| self.value(memo, slots, s).unwrap_or(f32::NAN))
    }

    /// Sample (`i`, `j`, `k`) of the grid through the memo.
    #[inline(always)]
    fn value(&self, memo: &mut [Entry; MAX_SLOTS], slots: usize, s: [usize; 3]) -> Option<f32> {
        let (index, at) = self.locate(s)?;
        self.brick(memo, slots, index)?
            .values
            .get(at & !EDGE)
            .copied()
    }

    /// Sample (`i`, `j`, `k`) of the grid through `table`.
    #[inline(always)]
    fn table_value(&self, table: &[OnceLock<Arc<Brick>>], s: [usize; 3]) -> Option<f32> {
        let (index, at) = self.locate(s)?;
        self.table_brick(table, index)?
            .values
            .get(at & !EDGE)
            .copied()
    }

    /// `N` samples, NaN where undefined: cells and fractions lane-wise, each lane's chunk and
    /// offset from the axis tables, its corners from its brick (through the table or the
    /// memo), the lerps lane-wise.
    // Lane loops index several per-lane arrays at once: that is what vectorizes.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn sample_points<const N: usize>(&self, p: &[[f32; N]; 3]) -> [f32; N] {
        match (&self.lookup, N.is_multiple_of(4)) {
            (Lookup::Whole(whole), true) => return undefined_to_nan(whole.sample_raw_lanes(p)),
            (Lookup::Table(table), true) => return self.table_lanes(table, p),
            _ => {}
        }
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
        let c = match &self.lookup {
            Lookup::Whole(whole) => {
                let mut c = [[f32::NAN; N]; 8];
                for (l, &cell) in cells.iter().enumerate() {
                    let corners = whole.cell_corners(cell);
                    for q in 0..8 {
                        c[q][l] = corners[q];
                    }
                }
                c
            }
            Lookup::Table(table) => self.table_corners(table, &cells, &index, &at),
            Lookup::Memo(slots) => self.memo_corners(*slots, &cells, &index, &at),
        };
        undefined_to_nan(lerp_corners(&c, &frac))
    }

    /// `N` samples (`N` a multiple of 4) through `table`, NaN where undefined, in the in-core
    /// bricked sampler's order (`Bricks::sample_raw_lanes`): four lanes at a time from the
    /// positions to the lerps, so that their cells, fractions and corners stay in registers.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn table_lanes<const N: usize>(
        &self,
        table: &[OnceLock<Arc<Brick>>],
        p: &[[f32; N]; 3],
    ) -> [f32; N] {
        let mut out = [0.0f32; N];
        for g in (0..N).step_by(4) {
            let (cell, frac) = cells_of_four(p, g, self.hi, self.cell_max);
            // Every lane gathers from its own brick without a branch on its data (the far
            // faces of a brick's last cell blocks hold copies, read and then replaced);
            // lanes on a chunk's far faces or in a brick not read yet are redone after.
            let mut c = [[0.0f32; 4]; 8];
            let mut redo = 0u32;
            let mut cells = [[0usize; 3]; 4];
            for k in 0..4 {
                // Written out: array `map`s went through an outlined `try_map`.
                cells[k] = [
                    cell[0][k].max(0) as usize,
                    cell[1][k].max(0) as usize,
                    cell[2][k].max(0) as usize,
                ];
                let (index, at) = self.locate(cells[k]).unwrap_or((usize::MAX, EDGE));
                let values = match table.get(index).and_then(OnceLock::get) {
                    Some(b) => &b.values[..],
                    None => &[],
                };
                redo |= u32::from(at & EDGE != 0 || values.is_empty()) << k;
                let corners = gather(values, at & !EDGE);
                for q in 0..8 {
                    c[q][k] = corners[q];
                }
            }
            while redo != 0 {
                let k = redo.trailing_zeros() as usize;
                redo &= redo - 1;
                let corners = self.table_corners_one(table, cells[k]);
                for q in 0..8 {
                    c[q][k] = corners[q];
                }
            }
            out[g..g + 4].copy_from_slice(&lerp_corners(&c, &frac));
        }
        undefined_to_nan(out)
    }

    /// The eight corners of `cell` through `table`, each from its own chunk (a cell on a
    /// chunk's far faces), NaN where undefined; reads the chunks not read yet.
    #[inline(never)]
    fn table_corners_one(&self, table: &[OnceLock<Arc<Brick>>], cell: [usize; 3]) -> [f32; 8] {
        let s = self.corner_samples(cell);
        let v = |q: usize| self.table_value(table, s[q]).unwrap_or(f32::NAN);
        // Written out: `map` went through an outlined `try_map`.
        [v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7)]
    }

    /// The corners of `N` lanes through `table` (`index`, `at`: each lane's chunk and offset).
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn table_corners<const N: usize>(
        &self,
        table: &[OnceLock<Arc<Brick>>],
        cells: &[[usize; 3]; N],
        index: &[usize; N],
        at: &[usize; N],
    ) -> [[f32; N]; 8] {
        let mut c = [[f32::NAN; N]; 8];
        for l in 0..N {
            let corners = if at[l] & EDGE == 0 {
                match self.table_brick(table, index[l]) {
                    Some(b) => gather(&b.values, at[l]),
                    None => [f32::NAN; 8],
                }
            } else {
                // On a chunk's far face: each corner from its own chunk.
                self.corner_samples(cells[l])
                    .map(|s| self.table_value(table, s).unwrap_or(f32::NAN))
            };
            for q in 0..8 {
                c[q][l] = corners[q];
            }
        }
        c
    }

    /// The corners of `N` lanes through this thread's memo: each lane's brick made resident
    /// in the memo (once per run of lanes in one chunk), the corners gathered through
    /// read-only lookups that reuse the previous lane's brick, and the lanes on a chunk's far
    /// faces (or whose brick another lane's displaced) sampled corner by corner.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn memo_corners<const N: usize>(
        &self,
        slots: usize,
        cells: &[[usize; 3]; N],
        index: &[usize; N],
        at: &[usize; N],
    ) -> [[f32; N]; 8] {
        let mut c = [[f32::NAN; N]; 8];
        memo::with_memo(|memo| {
            let mut last = usize::MAX;
            for l in 0..N {
                if at[l] & EDGE == 0 && index[l] != last {
                    last = index[l];
                    // Errors are kept by `brick`; the lane then reads NaN below.
                    let _ = self.brick(memo, slots, last);
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
                    _ => self.resident(memo, slots, index[l]),
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
                let corners = self.corners(memo, slots, cells[l]);
                for q in 0..8 {
                    c[q][l] = corners[q];
                }
            }
        });
        c
    }

    /// The samples of chunk `index`'s brick if this thread's memo holds it.
    #[inline(always)]
    fn resident<'m>(
        &self,
        memo: &'m [Entry; MAX_SLOTS],
        slots: usize,
        index: usize,
    ) -> Option<&'m [f32]> {
        match &memo[memo::slot_of(index, slots)] {
            Some((id, at, b)) if *id == self.id && *at == index => Some(&b.values),
            _ => None,
        }
    }
}

/// The eight corners of the cell whose first sample is at `at` in a brick's `values`, x
/// fastest (NaN if they would not fit: never for a cell within the brick).
#[inline(always)]
fn gather(values: &[f32], at: usize) -> [f32; 8] {
    match values.get(at..).and_then(|v| v.first_chunk::<REACH>()) {
        Some(c) => corners_in(c),
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
        let corners = self.corner_samples([i, j, k]);
        let value = |v: Option<f32>| v.map(f64::from);
        let v: [f64; 8] = match &self.lookup {
            Lookup::Whole(whole) => whole.cell_corners([i, j, k]).map(f64::from),
            Lookup::Table(table) => {
                let mut v = [0.0f64; 8];
                for (v, s) in v.iter_mut().zip(corners) {
                    *v = value(self.table_value(table, s))?;
                }
                v
            }
            Lookup::Memo(slots) => memo::with_memo(|memo| {
                let mut v = [0.0f64; 8];
                for (v, s) in v.iter_mut().zip(corners) {
                    *v = value(self.value(memo, *slots, s))?;
                }
                Some(v)
            })?,
        };
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let c0 = lerp(lerp(v[0], v[1], fx), lerp(v[2], v[3], fx), fy);
        let c1 = lerp(lerp(v[4], v[5], fx), lerp(v[6], v[7], fx), fy);
        let r = lerp(c0, c1, fz);
        r.is_finite().then_some(r)
    }
}
