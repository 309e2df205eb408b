//! A blocked copy of a grid for the lane streams' trilinear samples: the volume cut into
//! cell blocks of 8³ cells (called blocks, not bricks: a brick is a chunk of an out-of-core
//! volume, [`crate::bricked`], or of the GPU's brick pool), each stored with its far faces
//! (9³ samples, the next block's first layer repeated), blocks and their samples x fastest.
//!
//! Every cell's eight corners then lie in one block at fixed offsets: a sample costs one
//! block address and eight loads at constant displacements, within a few kilobytes (one or
//! two pages) instead of four rows up to a slice apart, so the rays of a lane block share
//! pages and cache lines. On Marschner-Lobb 256³ (64 MB of f32, more than the last-level
//! cache), perf put about 40 % of the lane stream's samples on the instructions just after
//! the row-major grid's corner loads; blocked, that frame's CPU time fell 1.2x (Riemann 0.5,
//! 512x512), while the heads, whose samples fit the cache, stayed within noise. The values and
//! the arithmetic are those of [`Trilinear`] (the copy holds each sample as f32, which every
//! scalar type converts to exactly, so the loads need no conversion): every sample is
//! bit-identical to it. The copy takes `(9/8)³ ≈ 1.42` f32 per grid sample (more for grids
//! whose sides are not multiples of 8): 1.42x an f32 grid, 2.8x an `i16` one, 5.7x a `u8`
//! one; it is built when it fits the memory budget.
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use volux_core::grid::Scalar;

use crate::sampling::{clamped_cell, Field, Trilinear, LANES};

/// Cells per block along each axis (a power of two).
pub(crate) const CELLS: usize = 8;
/// Samples per block along each axis: the cells and their far faces.
pub(crate) const SIDE: usize = CELLS + 1;

/// Samples per axis of the grids that are blocked (a power of two): the length of the
/// offset tables.
const AXIS_MAX: usize = 4096;
/// Samples per block.
pub(crate) const BLOCK: usize = SIDE * SIDE * SIDE;
/// Offsets of a cell's eight corners from its first sample in a block, x fastest.
pub(crate) const CORNERS: [usize; 8] = [
    0,
    1,
    SIDE,
    SIDE + 1,
    SIDE * SIDE,
    SIDE * SIDE + 1,
    SIDE * SIDE + SIDE,
    SIDE * SIDE + SIDE + 1,
];
/// Samples from a cell's first corner to its last, inclusive.
pub(crate) const REACH: usize = CORNERS[7] + 1;

/// The blocked samples of a grid (see the module docs).
pub(crate) struct CellBlocks {
    /// The blocks one after the other, each [`BLOCK`] samples `[z][y][x]`.
    samples: Vec<f32>,
    dims: [usize; 3],
    /// Per axis, the offset that the cell index adds to its first sample (the sum over the
    /// axes is the offset): `(c / 8) stride + (c % 8) side^a`, where `stride` is the blocks'
    /// offset along the axis; fixed-size, so masked indices need no bounds check.
    offsets: [Box<[i32; AXIS_MAX]>; 3],
    /// Largest coordinate and largest cell index per axis, as [`clamped_cell`] takes them.
    hi: [f32; 3],
    cell_max: [i32; 3],
    /// Read where a cell's samples would not fit (never: every cell's do).
    spare: [f32; REACH],
}

impl CellBlocks {
    /// Bytes the blocked copy of a grid with `dims` samples takes.
    pub(crate) fn bytes_for(dims: [usize; 3]) -> u64 {
        let n: u64 = Self::counts_for(dims).iter().map(|&c| c as u64).product();
        n.saturating_mul((BLOCK * std::mem::size_of::<f32>()) as u64)
    }

    fn counts_for(dims: [usize; 3]) -> [usize; 3] {
        dims.map(|n| n.saturating_sub(1).div_ceil(CELLS).max(1))
    }

    /// The blocked copy of `values` laid out x fastest with `dims` samples per axis; `None`
    /// unless `values` holds exactly that many samples (at least one), each side has at most
    /// [`AXIS_MAX`], the copy's offsets fit in `i32` and it takes at most `budget` bytes.
    pub(crate) fn build<T: Scalar>(values: &[T], dims: [usize; 3], budget: u64) -> Option<Self> {
        let count = dims[0].checked_mul(dims[1])?.checked_mul(dims[2])?;
        if count != values.len() {
            return None;
        }
        let [nx, ny, _] = dims;
        Self::build_from(dims, budget, |x, y, z| {
            values[x + nx * (y + ny * z)].to_f32()
        })
    }

    /// The blocked copy of the grid of `dims` samples whose sample (`x`, `y`, `z`) is
    /// `value(x, y, z)` (called from several threads); `None` under the conditions of
    /// [`Bricks::build`].
    pub(crate) fn build_from(
        dims: [usize; 3],
        budget: u64,
        value: impl Fn(usize, usize, usize) -> f32 + Sync,
    ) -> Option<Self> {
        let count = dims[0].checked_mul(dims[1])?.checked_mul(dims[2])?;
        let small = dims.iter().all(|&n| n <= AXIS_MAX);
        let bytes = Self::bytes_for(dims);
        let len = bytes / std::mem::size_of::<f32>() as u64;
        if count == 0 || !small || bytes > budget || len > i32::MAX as u64 {
            return None;
        }
        let counts = Self::counts_for(dims);
        let [nx, ny, nz] = dims;
        let mut samples = vec![0.0f32; len as usize];
        samples
            .par_chunks_mut(BLOCK)
            .enumerate()
            .for_each(|(b, block)| {
                let (bi, bj, bk) = (
                    b % counts[0],
                    b / counts[0] % counts[1],
                    b / counts[0] / counts[1],
                );
                for (r, row) in block.chunks_mut(SIDE).enumerate() {
                    let (v, w) = (r % SIDE, r / SIDE);
                    let z = (CELLS * bk + w).min(nz - 1);
                    let y = (CELLS * bj + v).min(ny - 1);
                    for (u, s) in row.iter_mut().enumerate() {
                        let x = (CELLS * bi + u).min(nx - 1);
                        *s = value(x, y, z);
                    }
                }
            });
        let strides = [1, counts[0], counts[0] * counts[1]].map(|c| c * BLOCK);
        let offsets = std::array::from_fn(|a| {
            let step = [1, SIDE, SIDE * SIDE][a];
            Box::new(std::array::from_fn(|c| {
                ((c / CELLS) * strides[a] + (c % CELLS) * step).min(i32::MAX as usize) as i32
            }))
        });
        Some(Self {
            samples,
            dims,
            offsets,
            hi: dims.map(|n| n.saturating_sub(1) as f32),
            cell_max: dims.map(|n| n.saturating_sub(2) as i32),
            spare: [0.0; REACH],
        })
    }

    /// The offset of the first sample of the cell `(i, j, k)` (each within `[0, cell_max]`).
    #[inline(always)]
    fn offset(&self, cell: [i32; 3]) -> i32 {
        let at = |a: usize| self.offsets[a][cell[a] as usize & (AXIS_MAX - 1)];
        at(0) + at(1) + at(2)
    }

    /// Bytes the copy takes.
    pub(crate) fn bytes(&self) -> u64 {
        (self.samples.len() * std::mem::size_of::<f32>()) as u64
    }

    /// The eight corners of cell (`i`, `j`, `k`) (each within `[0, cell_max]`, or 0 along
    /// an axis of one sample), x fastest.
    pub(crate) fn cell_corners(&self, cell: [usize; 3]) -> [f32; 8] {
        self.corners(self.offset(cell.map(|c| c.min(i32::MAX as usize) as i32)))
    }

    /// The eight corners of the cell whose first sample is at `offset`, x fastest.
    #[inline(always)]
    fn corners(&self, offset: i32) -> [f32; 8] {
        // One test (`offset` zero-extended, so the end cannot overflow) instead of two.
        let at = offset as u32 as usize;
        let c = self
            .samples
            .get(at..at + REACH)
            .and_then(|s| s.first_chunk::<REACH>())
            .unwrap_or(&self.spare);
        corners_in(c)
    }

    /// The trilinear values at `N` points (`N` a multiple of 4), each bit-identical to
    /// [`Trilinear::sample_raw`]: cells and fractions lane-wise, each lane's offset and
    /// corners in scalar registers, the corners of four lanes gathered into four-lane arrays
    /// and the lerps run lane-wise.
    // Lane loops index several per-lane arrays at once: that is what vectorizes.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(crate) fn sample_raw_lanes<const N: usize>(&self, p: &[[f32; N]; 3]) -> [f32; N] {
        let mut out = [0.0f32; N];
        // Four lanes at a time from the positions on, so that their cells and fractions stay
        // in registers (16-lane arrays of them went through the stack, zeroed first).
        for g in (0..N).step_by(4) {
            let (cell, frac) = cells_of_four(p, g, self.hi, self.cell_max);
            let mut c = [[0.0f32; 4]; 8];
            for k in 0..4 {
                let corners = self.corners(self.offset([cell[0][k], cell[1][k], cell[2][k]]));
                for q in 0..8 {
                    c[q][k] = corners[q];
                }
            }
            out[g..g + 4].copy_from_slice(&lerp_corners(&c, &frac));
        }
        out
    }
}

/// The cells and fractions ([`clamped_cell`]) of lanes `g` to `g + 3` of `p`, per axis, for
/// a grid whose largest coordinates are `hi` and largest cell indices `cell_max`.
#[inline(always)]
pub(crate) fn cells_of_four<const N: usize>(
    p: &[[f32; N]; 3],
    g: usize,
    hi: [f32; 3],
    cell_max: [i32; 3],
) -> ([[i32; 4]; 3], [[f32; 4]; 3]) {
    let (mut cell, mut frac) = ([[0i32; 4]; 3], [[0.0f32; 4]; 3]);
    for a in 0..3 {
        for k in 0..4 {
            (cell[a][k], frac[a][k]) = clamped_cell(p[a][g + k], hi[a], cell_max[a]);
        }
    }
    (cell, frac)
}

/// The eight corners, x fastest, of the cell whose samples start `window` (a block's samples
/// from the cell's first corner on).
#[inline(always)]
pub(crate) fn corners_in(window: &[f32; REACH]) -> [f32; 8] {
    // Written out: where this is not inlined into the lane stream, `CORNERS.map` went through
    // an outlined `try_map` per cell (a third of a blocked level's frame).
    [
        window[CORNERS[0]],
        window[CORNERS[1]],
        window[CORNERS[2]],
        window[CORNERS[3]],
        window[CORNERS[4]],
        window[CORNERS[5]],
        window[CORNERS[6]],
        window[CORNERS[7]],
    ]
}

/// The trilinear values of `N` cells from their corners `c` (`c[q][l]`: corner `q` of lane
/// `l`, x fastest) and fractions `f`, with the lerps of [`Trilinear`], lane-wise.
#[inline(always)]
pub(crate) fn lerp_corners<const N: usize>(c: &[[f32; N]; 8], f: &[[f32; N]; 3]) -> [f32; N] {
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

/// Trilinear sampling through the blocked copy, with the row-major sampler for the f64
/// reference path.
pub(crate) struct BlockedTrilinear<'a, T> {
    pub(crate) blocks: &'a CellBlocks,
    pub(crate) linear: Trilinear<'a, T>,
}

/// NaN for every non-finite value (undefined samples).
#[inline(always)]
pub(crate) fn undefined_to_nan<const N: usize>(mut r: [f32; N]) -> [f32; N] {
    for v in r.iter_mut() {
        if !v.is_finite() {
            *v = f32::NAN;
        }
    }
    r
}

impl<T: Scalar> Field for BlockedTrilinear<'_, T> {
    fn dims(&self) -> [usize; 3] {
        self.blocks.dims
    }

    #[inline(always)]
    fn sample(&self, p: Vec3) -> Option<f32> {
        let r = self
            .blocks
            .sample_raw_lanes(&[[p.x; 4], [p.y; 4], [p.z; 4]])[0];
        r.is_finite().then_some(r)
    }

    #[inline(always)]
    fn sample_lanes(&self, p: &[[f32; LANES]; 3]) -> [f32; LANES] {
        undefined_to_nan(self.blocks.sample_raw_lanes(p))
    }

    #[inline(always)]
    fn sample4(&self, p: &[[f32; 4]; 3]) -> [f32; 4] {
        undefined_to_nan(self.blocks.sample_raw_lanes(p))
    }

    fn sample64(&self, p: DVec3) -> Option<f64> {
        self.linear.sample64(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points inside, on the faces, outside, NaN and on block boundaries.
    fn points(dims: [usize; 3]) -> Vec<Vec3> {
        let mut out = Vec::new();
        let mut s = 0x9e37_79b9u32;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32
        };
        for _ in 0..2000 {
            let p: [f32; 3] = std::array::from_fn(|a| (next() * 1.4 - 0.2) * dims[a] as f32);
            out.push(Vec3::from(p));
        }
        for v in [-1.0, 0.0, 7.0, 7.5, 8.0, 8.25, 15.999, 16.0, 1e9, f32::NAN] {
            out.push(Vec3::splat(v));
            out.push(Vec3::new(v, 3.5, 8.0));
        }
        out
    }

    fn check<T: Scalar>(values: &[T], dims: [usize; 3]) {
        let linear = Trilinear::new(values, dims);
        let Some(blocks) = CellBlocks::build(values, dims, u64::MAX) else {
            panic!("no blocks for {dims:?}");
        };
        let field = BlockedTrilinear {
            blocks: &blocks,
            linear,
        };
        let pts = points(dims);
        for chunk in pts.chunks_exact(LANES) {
            let p: [[f32; LANES]; 3] =
                std::array::from_fn(|a| std::array::from_fn(|l| chunk[l][a]));
            let (got, want) = (field.sample_lanes(&p), linear.sample_lanes(&p));
            for l in 0..LANES {
                assert_eq!(got[l].to_bits(), want[l].to_bits(), "{dims:?} {}", chunk[l]);
                let one = field.sample(chunk[l]).map(f32::to_bits);
                assert_eq!(one, linear.sample(chunk[l]).map(f32::to_bits));
            }
        }
    }

    #[test]
    fn bricked_samples_equal_row_major_ones() {
        for dims in [
            [1, 1, 1],
            [2, 2, 2],
            [9, 9, 9],
            [17, 8, 3],
            [1, 20, 1],
            [30, 17, 26],
        ] {
            let n = dims[0] * dims[1] * dims[2];
            let f: Vec<f32> = (0..n).map(|i| ((i * 37 % 101) as f32).sin()).collect();
            check(&f, dims);
            let b: Vec<u8> = (0..n).map(|i| (i * 53 % 251) as u8).collect();
            check(&b, dims);
            let s: Vec<i16> = (0..n).map(|i| (i * 7919 % 4001) as i16 - 2000).collect();
            check(&s, dims);
        }
    }

    #[test]
    fn bricks_respect_the_budget_and_the_slice_length() {
        let v = vec![1.0f32; 27];
        let bytes = CellBlocks::bytes_for([3, 3, 3]);
        assert_eq!(bytes, 729 * 4);
        assert!(CellBlocks::build(&v, [3, 3, 3], bytes).is_some());
        assert!(CellBlocks::build(&v, [3, 3, 3], bytes - 1).is_none());
        assert!(CellBlocks::build(&v[..26], [3, 3, 3], u64::MAX).is_none());
        assert!(CellBlocks::build::<f32>(&[], [0, 0, 0], u64::MAX).is_none());
    }
}
