//! The sculpt mask: one bit per voxel in sparse 8³ bricks, with a per-macrocell summary.
use rayon::prelude::*;

use super::cell_states::{summarize, CellStates, B, PARTIAL, REMOVED, VISIBLE};
use super::cut::{covered_bricks, cut_brick, valid_bits, WORDS};
use super::region::{Coverage, Region};
use crate::error::{Error, Result};

/// One brick of the mask: wholly kept, wholly removed, or one bit per voxel (x fastest, then
/// y, then z; bit set = kept). Bricks are kept normalized: `Bits` only when its in-range voxels
/// are mixed.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Brick {
    Kept,
    Removed,
    Bits(Box<[u64; WORDS]>),
}

impl Brick {
    #[inline]
    fn get(&self, local: usize) -> bool {
        match self {
            Self::Kept => true,
            Self::Removed => false,
            Self::Bits(w) => (w[local >> 6] >> (local & 63)) & 1 == 1,
        }
    }

    /// The brick of `bits`, normalized against the bits of its in-range voxels `valid`.
    fn from_bits(bits: [u64; WORDS], valid: &[u64; WORDS]) -> Self {
        let masked = std::array::from_fn::<u64, WORDS, _>(|w| bits[w] & valid[w]);
        if masked == *valid {
            Self::Kept
        } else if masked.iter().all(|&w| w == 0) {
            Self::Removed
        } else {
            Self::Bits(Box::new(masked))
        }
    }
}

/// The local bit of voxel (`i`, `j`, `k`) in its brick.
#[inline]
fn local_bit(i: usize, j: usize, k: usize) -> usize {
    (i % B) | (j % B) << 3 | (k % B) << 6
}

/// The trilinear blend at `f` of a cell's kept (1) and removed (0) corners, `bits` as
/// [`SculptMask::corner_bits`] gives them.
#[inline]
fn blend(bits: u8, f: [f32; 3]) -> f32 {
    let v = |corner: u8| f32::from((bits >> corner) & 1);
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let x00 = lerp(v(0), v(1), f[0]);
    let x10 = lerp(v(2), v(3), f[0]);
    let x01 = lerp(v(4), v(5), f[0]);
    let x11 = lerp(v(6), v(7), f[0]);
    lerp(lerp(x00, x10, f[1]), lerp(x01, x11, f[1]), f[2])
}

/// The gradient of [`blend`] at `f` (per unit of `f`): the derivative of the trilinear
/// interpolation along each axis.
fn blend_gradient(bits: u8, f: [f32; 3]) -> [f32; 3] {
    let v = |corner: u8| f32::from((bits >> corner) & 1);
    let [fx, fy, fz] = f;
    let (gx, gy, gz) = (1.0 - fx, 1.0 - fy, 1.0 - fz);
    [
        gy * gz * (v(1) - v(0))
            + fy * gz * (v(3) - v(2))
            + gy * fz * (v(5) - v(4))
            + fy * fz * (v(7) - v(6)),
        gx * gz * (v(2) - v(0))
            + fx * gz * (v(3) - v(1))
            + gx * fz * (v(6) - v(4))
            + fx * fz * (v(7) - v(5)),
        gx * gy * (v(4) - v(0))
            + fx * gy * (v(5) - v(1))
            + gx * fy * (v(6) - v(2))
            + fx * fy * (v(7) - v(3)),
    ]
}

/// Whether the point at `f` in a cell with kept corners `bits` is visible: from the bits
/// alone when they agree (no arithmetic), else by the blend.
#[inline(always)]
fn visible_at(bits: u8, f: [f32; 3]) -> bool {
    match bits {
        0xFF => true,
        0 => false,
        bits => blend(bits, f) >= 0.5,
    }
}

/// Which voxels of a grid are kept after sculpting (seed `004` sec. 4.4.1, at full resolution):
/// see the [module documentation](crate::sculpt). Starts with every voxel kept. Two masks are
/// equal when they keep the same voxels (whatever edits led there).
#[derive(Clone, Debug)]
pub struct SculptMask {
    dims: [usize; 3],
    bricks_per_axis: [usize; 3],
    bricks: Vec<Brick>,
    blocks_per_axis: [usize; 3],
    /// [`VISIBLE`], [`REMOVED`] or [`PARTIAL`] per macrocell.
    blocks: Vec<u8>,
    /// The cells' corner states of each partly removed macrocell.
    cells: Vec<Option<Box<CellStates>>>,
    /// Bumped by every change, so that renderers can key caches on it.
    generation: u64,
}

impl PartialEq for SculptMask {
    fn eq(&self, other: &Self) -> bool {
        // Bricks are normalized, so equal voxels are equal bricks; the macrocell states
        // follow from the bricks.
        self.dims == other.dims && self.bricks == other.bricks
    }
}

impl Eq for SculptMask {}

/// What one edit changed: the bricks as they were before it, so that
/// [`SculptMask::restore`] undoes it bit for bit.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MaskEdit {
    before: Vec<(usize, Brick)>,
    removed_voxels: u64,
}

impl MaskEdit {
    /// Whether the edit changed nothing.
    pub fn is_empty(&self) -> bool {
        self.before.is_empty()
    }

    /// The bricks (8³ voxels) the edit changed.
    pub fn bricks_changed(&self) -> usize {
        self.before.len()
    }

    /// The voxels the edit removed.
    pub fn removed_voxels(&self) -> u64 {
        self.removed_voxels
    }
}

impl SculptMask {
    /// Voxel cells per macrocell side: the same blocks as the renderer's macrocell grid.
    pub const BLOCK: usize = 8;

    /// A mask of a grid of `dims` samples with every voxel kept. Errors on a zero dimension.
    pub fn new(dims: [usize; 3]) -> Result<Self> {
        if dims.contains(&0) {
            return Err(Error::InvalidDims {
                dims: dims.map(|d| d as i64),
                reason: "a sculpt mask needs at least one voxel per axis".into(),
            });
        }
        let bricks_per_axis = dims.map(|d| d.div_ceil(B));
        let blocks_per_axis = dims.map(|d| d.saturating_sub(1).max(1).div_ceil(Self::BLOCK));
        let n = crate::limits::count_of(&bricks_per_axis);
        crate::limits::check_alloc("the sculpt mask's bricks", n, 16)?;
        let blocks = crate::limits::count_of(&blocks_per_axis) as usize;
        Ok(Self {
            dims,
            bricks_per_axis,
            bricks: vec![Brick::Kept; n as usize],
            blocks_per_axis,
            blocks: vec![VISIBLE; blocks],
            cells: vec![None; blocks],
            generation: 0,
        })
    }

    /// The mask of `values` (one per voxel, x fastest; non-zero = kept), e.g. read from a
    /// saved NRRD. Errors when the count is not `dims`' product.
    pub fn from_values(dims: [usize; 3], values: &[u8]) -> Result<Self> {
        let mut mask = Self::new(dims)?;
        let expected = crate::limits::count_of(&dims);
        if values.len() as u64 != expected {
            return Err(Error::SizeMismatch {
                expected,
                actual: values.len() as u64,
            });
        }
        let kept = |i: usize, j: usize, k: usize| values[i + dims[0] * (j + dims[1] * k)] != 0;
        mask.bricks = (0..mask.bricks.len())
            .into_par_iter()
            .map(|b| mask.brick_of(b, |i, j, k, _| kept(i, j, k)))
            .collect();
        mask.update_blocks_all();
        Ok(mask)
    }

    /// One byte per voxel, x fastest: 1 where kept, 0 where removed (the NRRD export).
    pub fn to_values(&self) -> Vec<u8> {
        let [nx, ny, _] = self.dims;
        let mut out = vec![0u8; self.dims.iter().product()];
        out.par_chunks_mut(nx * ny)
            .enumerate()
            .for_each(|(k, slice)| {
                for j in 0..ny {
                    for i in 0..nx {
                        slice[i + nx * j] = u8::from(self.voxel(i, j, k));
                    }
                }
            });
        out
    }

    /// Samples per axis of the grid the mask belongs to.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// A number that changes whenever the mask does.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Whether no voxel has been removed.
    pub fn is_untouched(&self) -> bool {
        self.bricks.iter().all(|b| *b == Brick::Kept)
    }

    /// Whether voxel (`i`, `j`, `k`) is kept (each index below its dimension).
    #[inline]
    pub fn voxel(&self, i: usize, j: usize, k: usize) -> bool {
        let [bx, by, _] = self.bricks_per_axis;
        let b = i / B + bx * (j / B + by * (k / B));
        self.bricks[b].get(local_bit(i, j, k))
    }

    /// The voxels removed so far.
    pub fn removed_count(&self) -> u64 {
        let [nx, ny, nz] = self.dims;
        (0..nz)
            .into_par_iter()
            .map(|k| {
                let mut n = 0u64;
                for j in 0..ny {
                    for i in 0..nx {
                        n += u64::from(!self.voxel(i, j, k));
                    }
                }
                n
            })
            .sum()
    }

    /// Macrocells per axis (as the renderer's macrocell grid for these dims).
    pub fn blocks_per_axis(&self) -> [usize; 3] {
        self.blocks_per_axis
    }

    /// Whether every point of macrocell `index` (x fastest) is removed: rays skip it.
    #[inline]
    pub fn block_removed(&self, index: usize) -> bool {
        self.blocks[index] == REMOVED
    }

    /// Whether macrocell `index` (x fastest) is partly removed: its points are visible or not
    /// by [`SculptMask::visible`]'s interpolation (elsewhere all or none of them are).
    #[inline]
    pub fn block_partial(&self, index: usize) -> bool {
        self.blocks[index] == PARTIAL
    }

    /// The interpolated mask at voxel coordinates `p` (the trilinear blend of the kept (1)
    /// and removed (0) voxels of its cell), clamped to the grid as the samplers clamp.
    pub fn value(&self, p: [f32; 3]) -> f32 {
        let (c, f) = self.cell_of(p);
        self.interpolate(c, f)
    }

    /// Whether the point at voxel coordinates `p` is visible: [`SculptMask::value`] >= 0.5
    /// (the seed's threshold), answered from the macrocell's state when it is wholly visible
    /// or removed, then from the cell's corners when they agree.
    #[inline(always)]
    pub fn visible(&self, p: [f32; 3]) -> bool {
        let (c, f) = self.cell_of(p);
        self.visible_in(c, f)
    }

    /// The gradient of [`SculptMask::value`] at voxel coordinates `p` (per voxel, pointing
    /// into what is kept) where the point's cell has both kept and removed corners, i.e. on
    /// the surface the sculpting exposed and in the voxel-thick layer under it; `None`
    /// elsewhere, and where the gradient vanishes. Shading lights the exposed surface with
    /// this normal (seed `004` sec. 4.4.1's interpolated mask; Weiskopf, Engel and Ertl 2003,
    /// cited there, light clipped faces with the clip geometry's normal).
    pub fn cut_gradient(&self, p: [f32; 3]) -> Option<[f32; 3]> {
        let (c, f) = self.cell_of(p);
        let [bx, by, _] = self.blocks_per_axis;
        let b = c[0] / Self::BLOCK + bx * (c[1] / Self::BLOCK + by * (c[2] / Self::BLOCK));
        let bits = match self.blocks[b] {
            VISIBLE | REMOVED => return None,
            _ => match self.cells[b].as_deref() {
                Some(cells) => cells.corners(c),
                None => self.corner_bits(c),
            },
        };
        if bits == 0 || bits == 0xFF {
            return None;
        }
        let g = blend_gradient(bits, f);
        (g != [0.0; 3]).then_some(g)
    }

    /// [`SculptMask::visible`] of the point at `f` in cell `c`: from the macrocell's state,
    /// then from the cell's corners, blended only when they differ.
    #[inline(always)]
    fn visible_in(&self, c: [usize; 3], f: [f32; 3]) -> bool {
        let [bx, by, _] = self.blocks_per_axis;
        let b = c[0] / Self::BLOCK + bx * (c[1] / Self::BLOCK + by * (c[2] / Self::BLOCK));
        match self.blocks[b] {
            VISIBLE => true,
            REMOVED => false,
            _ => match self.cells[b].as_deref() {
                Some(cells) => visible_at(cells.corners(c), f),
                None => visible_at(self.corner_bits(c), f),
            },
        }
    }

    /// [`SculptMask::visible`] for `N` points at once (lane `l` at `x[l]`, `y[l]`, `z[l]`):
    /// the macrocells are found for all lanes together (straight-line code the compiler
    /// vectorizes), and only lanes in partly removed macrocells interpolate. `keep[l]` is
    /// cleared where the point is hidden.
    #[inline]
    pub fn visible_lanes<const N: usize>(&self, p: &[[f32; N]; 3], keep: &mut [bool; N]) {
        let [bx, by, _] = self.blocks_per_axis;
        let top: [f32; 3] = std::array::from_fn(|a| self.dims[a].saturating_sub(2) as f32);
        let mut block = [0u32; N];
        for (l, b) in block.iter_mut().enumerate() {
            // The cell's macrocell: floor of the clamped coordinate (NaN clamps to 0).
            let c: [u32; 3] = std::array::from_fn(|a| p[a][l].max(0.0).min(top[a]) as u32 >> 3);
            *b = c[0] + bx as u32 * (c[1] + by as u32 * c[2]);
        }
        for l in 0..N {
            let state = self.blocks[block[l] as usize];
            if state != VISIBLE {
                keep[l] &= state == PARTIAL && self.visible([p[0][l], p[1][l], p[2][l]]);
            }
        }
    }

    /// Which of the points `lanes` picks (bit `l` for the point at `x[l]`, `y[l]`, `z[l]`)
    /// are hidden, as [`SculptMask::visible`] decides: bit `l` set for a hidden one. The
    /// cells and the positions in them are found for all lanes together (straight-line code
    /// the compiler vectorizes: one by one, the float to index conversions cost more than
    /// the rest of the test), then each picked lane reads its macrocell's state, its cell's
    /// corners, and interpolates only in cells the cut crosses.
    #[inline]
    pub fn hidden_lanes<const N: usize>(&self, p: &[[f32; N]; 3], lanes: u32) -> u32 {
        // Rounding by adding 2^23 is exact below 2^22; larger grids take `visible`.
        const ROUND: f32 = 8_388_608.0;
        if self.dims.iter().any(|&d| d > 1 << 22) {
            return (0..N.min(32))
                .filter(|&l| lanes >> l & 1 == 1 && !self.visible([p[0][l], p[1][l], p[2][l]]))
                .fold(0, |h, l| h | 1 << l);
        }
        let hi: [f32; 3] = std::array::from_fn(|a| self.dims[a].saturating_sub(1) as f32);
        let top: [f32; 3] = std::array::from_fn(|a| self.dims[a].saturating_sub(2) as f32);
        let mut cell = [[0u32; N]; 3];
        let mut frac = [[0f32; N]; 3];
        for a in 0..3 {
            for l in 0..N {
                // Clamped as `cell_of` clamps (NaN to 0: `max` and `min` return the number),
                // then the cell's corner `floor(min(x, top))` by float operations and bits
                // (vectorized; `as` conversions are not, and cost more than the rest).
                let x = p[a][l].max(0.0).min(hi[a]);
                let xc = x.min(top[a]);
                let big = xc + ROUND;
                let near = big - ROUND;
                let down = near > xc;
                cell[a][l] = (big.to_bits() & 0x7F_FFFF) - u32::from(down);
                frac[a][l] = x - (near - if down { 1.0 } else { 0.0 });
            }
        }
        let mut hidden = 0;
        let all = if N >= 32 { u32::MAX } else { (1u32 << N) - 1 };
        let mut left = lanes & all;
        while left != 0 {
            let l = left.trailing_zeros() as usize;
            left &= left - 1;
            let c = [0, 1, 2].map(|a| cell[a][l] as usize);
            let visible = self.visible_in(c, [0, 1, 2].map(|a| frac[a][l]));
            hidden |= u32::from(!visible) << l;
        }
        hidden
    }

    /// The cell of `p` (clamped to the grid) and the position in it.
    #[inline]
    fn cell_of(&self, p: [f32; 3]) -> ([usize; 3], [f32; 3]) {
        let mut c = [0usize; 3];
        let mut f = [0f32; 3];
        for a in 0..3 {
            let hi = (self.dims[a] - 1) as f32;
            let x = p[a].clamp(0.0, hi);
            let cell = (x as usize).min(self.dims[a].saturating_sub(2));
            c[a] = cell;
            f[a] = if x.is_nan() { 0.0 } else { x - cell as f32 };
        }
        (c, f)
    }

    fn interpolate(&self, c: [usize; 3], f: [f32; 3]) -> f32 {
        blend(self.corner_bits(c), f)
    }

    /// Which corners of cell `c` are kept: bit `dx + 2 dy + 4 dz` for the corner at
    /// `c + (dx, dy, dz)` (clamped to the grid). A cell inside one brick (seven in eight
    /// along each axis) reads that brick once: its two z layers are two words, each corner
    /// pair a shift and a mask.
    #[inline]
    fn corner_bits(&self, c: [usize; 3]) -> u8 {
        let inside = (0..3).all(|a| c[a] % B != B - 1 && c[a] + 1 < self.dims[a]);
        if inside {
            let [bx, by, _] = self.bricks_per_axis;
            let b = c[0] / B + bx * (c[1] / B + by * (c[2] / B));
            return match &self.bricks[b] {
                Brick::Kept => 0xFF,
                Brick::Removed => 0,
                Brick::Bits(w) => {
                    // Word `k` holds z layer `k` (bit `i + 8 j`, as `local_bit`).
                    let shift = c[0] % B + B * (c[1] % B);
                    let (near, far) = (w[c[2] % B] >> shift, w[c[2] % B + 1] >> shift);
                    let pair = |w: u64, dy: usize| ((w >> (B * dy)) & 3) as u8;
                    pair(near, 0) | pair(near, 1) << 2 | pair(far, 0) << 4 | pair(far, 1) << 6
                }
            };
        }
        let n = std::array::from_fn::<usize, 3, _>(|a| (c[a] + 1).min(self.dims[a] - 1));
        let mut bits = 0u8;
        for corner in 0..8 {
            let pick = |a: usize| if corner >> a & 1 == 1 { n[a] } else { c[a] };
            bits |= u8::from(self.voxel(pick(0), pick(1), pick(2))) << corner;
        }
        bits
    }

    /// Removes every kept voxel of `region` and returns what changed (for
    /// [`SculptMask::restore`]). The bricks the region touches are found by halving boxes of
    /// bricks (`cut::covered_bricks`); those it covers wholly are removed without looking at
    /// their voxels, and only the others are cut (`cut::cut_brick`), in parallel. The macrocell
    /// states of the bricks changed are updated.
    pub fn remove(&mut self, region: &(impl Region + ?Sized)) -> MaskEdit {
        let Some((lo, hi)) = region.index_bounds(self.dims) else {
            return MaskEdit::default();
        };
        let candidates = covered_bricks(region, self.dims, self.bricks_per_axis, lo, hi);
        let changed: Vec<(usize, Brick, u64)> = candidates
            .into_par_iter()
            .filter_map(|(b, coverage)| self.removed_in(b, coverage, region))
            .collect();
        let mut edit = MaskEdit::default();
        for (b, brick, removed) in changed {
            let old = std::mem::replace(&mut self.bricks[b], brick);
            edit.before.push((b, old));
            edit.removed_voxels += removed;
        }
        self.after_change(&edit);
        edit
    }

    /// Undoes `edit` (the last edit not yet undone): its bricks are put back as they were.
    pub fn restore(&mut self, edit: &MaskEdit) {
        for (b, brick) in &edit.before {
            self.bricks[*b] = brick.clone();
        }
        self.after_change(edit);
    }

    fn after_change(&mut self, edit: &MaskEdit) {
        if edit.is_empty() {
            return;
        }
        self.generation += 1;
        let bricks: Vec<usize> = edit.before.iter().map(|(b, _)| *b).collect();
        self.update_blocks_of(&bricks);
    }

    /// Brick `b`, which `region` covers as `coverage` says, with the region removed, and the
    /// voxels removed; `None` when nothing changes.
    fn removed_in(
        &self,
        b: usize,
        coverage: Coverage,
        region: &(impl Region + ?Sized),
    ) -> Option<(usize, Brick, u64)> {
        let old = &self.bricks[b];
        let (lo, hi) = self.brick_voxels(b);
        let valid = valid_bits(lo, hi);
        let bits = match old {
            Brick::Removed => return None,
            Brick::Kept => valid,
            Brick::Bits(w) => **w,
        };
        let kept = |w: &[u64; WORDS]| w.iter().map(|w| u64::from(w.count_ones())).sum::<u64>();
        match coverage {
            Coverage::None => None,
            Coverage::All => Some((b, Brick::Removed, kept(&bits))),
            Coverage::Some => {
                let cut = cut_brick(region, lo, hi, &bits);
                (cut != bits).then(|| (b, Brick::from_bits(cut, &valid), kept(&bits) - kept(&cut)))
            }
        }
    }

    /// The brick `b` whose in-range voxel (`i`, `j`, `k`), local bit `local`, is kept when
    /// `kept` says so.
    fn brick_of(
        &self,
        b: usize,
        mut kept: impl FnMut(usize, usize, usize, usize) -> bool,
    ) -> Brick {
        let (lo, hi) = self.brick_voxels(b);
        let mut bits = [0u64; WORDS];
        let mut valid = [0u64; WORDS];
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    let l = local_bit(i, j, k);
                    valid[l >> 6] |= 1 << (l & 63);
                    if kept(i, j, k, l) {
                        bits[l >> 6] |= 1 << (l & 63);
                    }
                }
            }
        }
        Brick::from_bits(bits, &valid)
    }

    /// The first and last voxel of brick `b`.
    fn brick_voxels(&self, b: usize) -> ([usize; 3], [usize; 3]) {
        let [bx, by, _] = self.bricks_per_axis;
        let c = [b % bx, (b / bx) % by, b / (bx * by)];
        let lo = c.map(|c| c * B);
        let hi = std::array::from_fn(|a| (lo[a] + B - 1).min(self.dims[a] - 1));
        (lo, hi)
    }

    /// The bricks holding voxels between `lo` and `hi` (inclusive).
    fn bricks_between(&self, lo: [usize; 3], hi: [usize; 3]) -> Vec<usize> {
        let [bx, by, _] = self.bricks_per_axis;
        let mut out = Vec::new();
        for k in lo[2] / B..=hi[2] / B {
            for j in lo[1] / B..=hi[1] / B {
                for i in lo[0] / B..=hi[0] / B {
                    out.push(i + bx * (j + by * k));
                }
            }
        }
        out
    }
}

impl SculptMask {
    /// Recomputes the summaries of the macrocells around the bricks `bricks` (a macrocell
    /// reads the voxels of its own brick and the first layer of the next).
    fn update_blocks_of(&mut self, bricks: &[usize]) {
        let [bx, by, _] = self.bricks_per_axis;
        let [mx, my, mz] = self.blocks_per_axis;
        let mut blocks: Vec<usize> = Vec::new();
        for &b in bricks {
            let c = [b % bx, (b / bx) % by, b / (bx * by)];
            for dk in 0..2 {
                for dj in 0..2 {
                    for di in 0..2 {
                        let (i, j, k) = (
                            c[0].checked_sub(di),
                            c[1].checked_sub(dj),
                            c[2].checked_sub(dk),
                        );
                        if let (Some(i), Some(j), Some(k)) = (i, j, k) {
                            if i < mx && j < my && k < mz {
                                blocks.push(i + mx * (j + my * k));
                            }
                        }
                    }
                }
            }
        }
        blocks.sort_unstable();
        blocks.dedup();
        let summaries: Vec<_> = blocks.par_iter().map(|&m| self.block_summary(m)).collect();
        for (m, (state, cells)) in blocks.into_iter().zip(summaries) {
            self.blocks[m] = state;
            self.cells[m] = cells;
        }
    }

    /// Recomputes every macrocell's summary.
    fn update_blocks_all(&mut self) {
        let summaries: Vec<_> = (0..self.blocks.len())
            .into_par_iter()
            .map(|m| self.block_summary(m))
            .collect();
        (self.blocks, self.cells) = summaries.into_iter().unzip();
    }

    /// The state of macrocell `m` (its voxels `[8 I, 8 I + 8]` per axis, clamped to the
    /// grid) and, when partly removed, its cells' corner states ([`summarize`]). The voxels
    /// are read a row of nine at a time (a byte of one brick word and a bit of the next brick).
    fn block_summary(&self, m: usize) -> (u8, Option<Box<CellStates>>) {
        let [mx, my, _] = self.blocks_per_axis;
        let c = [m % mx, (m / mx) % my, m / (mx * my)];
        let lo = c.map(|c| c * Self::BLOCK);
        let bricks = self.bricks_between(lo, self.summary_hi(lo));
        if bricks.iter().all(|&b| self.bricks[b] == Brick::Kept) {
            return (VISIBLE, None);
        }
        if bricks.iter().all(|&b| self.bricks[b] == Brick::Removed) {
            return (REMOVED, None);
        }
        let mut rows = [[0u16; B + 1]; B + 1];
        for (dk, plane) in rows.iter_mut().enumerate() {
            for (dj, row) in plane.iter_mut().enumerate() {
                let j = (lo[1] + dj).min(self.dims[1] - 1);
                let k = (lo[2] + dk).min(self.dims[2] - 1);
                *row = self.row_bits(lo[0], j, k);
            }
        }
        summarize(&rows)
    }

    /// The last voxel per axis a macrocell starting at `lo` reads.
    fn summary_hi(&self, lo: [usize; 3]) -> [usize; 3] {
        std::array::from_fn(|a| (lo[a] + Self::BLOCK).min(self.dims[a] - 1))
    }

    /// The kept bits of the nine voxels `i0..=i0 + 8` of row (`j`, `k`), `i0` a multiple of
    /// the brick side: bit `d` for voxel `min(i0 + d, last)`, clamped to the grid's last
    /// voxel as the cells clamp their corners.
    fn row_bits(&self, i0: usize, j: usize, k: usize) -> u16 {
        let last = self.dims[0] - 1;
        let mut bits = u16::from(self.brick_row(i0, j, k));
        if i0 + B <= last {
            bits |= u16::from(self.voxel(i0 + B, j, k)) << B;
        } else {
            // Past the grid's edge: every bit repeats the last voxel's.
            let edge = (bits >> (last - i0)) & 1;
            let keep = (1u16 << (last - i0 + 1)) - 1;
            bits = (bits & keep)
                | if edge == 1 {
                    !keep & ((1 << (B + 1)) - 1)
                } else {
                    0
                };
        }
        bits
    }

    /// The eight kept bits of row (`j`, `k`) in the brick holding voxel `i0` (a multiple of
    /// the brick side): a byte of one word.
    fn brick_row(&self, i0: usize, j: usize, k: usize) -> u8 {
        let [bx, by, _] = self.bricks_per_axis;
        let b = i0 / B + bx * (j / B + by * (k / B));
        match &self.bricks[b] {
            Brick::Kept => 0xFF,
            Brick::Removed => 0,
            Brick::Bits(w) => (w[k % B] >> (B * (j % B))) as u8,
        }
    }
}
