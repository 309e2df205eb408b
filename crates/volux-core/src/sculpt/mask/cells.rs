//! The mask's summary per macrocell, kept up to date by every edit: whether the macrocell is
//! wholly visible, wholly removed or partly removed, and, for a partly removed one, which of
//! its cells have all eight corners kept or all removed. A point in such a cell is visible or
//! not without interpolating; only the cells the cut surface crosses blend their corners.
use rayon::prelude::*;

use super::{SculptMask, B, PARTIAL, REMOVED, VISIBLE};

/// The cells of one partly removed macrocell with all corners kept, and with all removed:
/// bit `i + 8 j` of word `k` for the cell at (`i`, `j`, `k`) from the macrocell's first.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct CellStates {
    kept: [u64; B],
    removed: [u64; B],
}

/// Whether a cell's corners are all kept, all removed, or mixed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Corners {
    Kept,
    Removed,
    Mixed,
}

impl CellStates {
    /// The corners of cell `c` (grid cell coordinates) of this macrocell.
    #[inline]
    pub(super) fn corners(&self, c: [usize; 3]) -> Corners {
        let (word, bit) = (c[2] % B, c[0] % B + B * (c[1] % B));
        if (self.kept[word] >> bit) & 1 == 1 {
            Corners::Kept
        } else if (self.removed[word] >> bit) & 1 == 1 {
            Corners::Removed
        } else {
            Corners::Mixed
        }
    }
}

impl SculptMask {
    /// Recomputes the summaries of the macrocells around the bricks `bricks` (a macrocell
    /// reads the voxels of its own brick and the first layer of the next).
    pub(super) fn update_blocks_of(&mut self, bricks: &[usize]) {
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
    pub(super) fn update_blocks_all(&mut self) {
        let summaries: Vec<_> = (0..self.blocks.len())
            .into_par_iter()
            .map(|m| self.block_summary(m))
            .collect();
        (self.blocks, self.cells) = summaries.into_iter().unzip();
    }

    /// The state of macrocell `m` (its voxels `[8 I, 8 I + 8]` per axis, clamped to the
    /// grid) and, when partly removed, its cells' corner states. The voxels are read a row of
    /// nine at a time (a byte of one brick word and a bit of the next brick), and a row of
    /// cells is four rows ANDed (all kept) or NORed (all removed) with their shifted selves.
    fn block_summary(&self, m: usize) -> (u8, Option<Box<CellStates>>) {
        let [mx, my, _] = self.blocks_per_axis;
        let c = [m % mx, (m / mx) % my, m / (mx * my)];
        let lo = c.map(|c| c * Self::BLOCK);
        let bricks = self.bricks_between(lo, self.summary_hi(lo));
        if bricks.iter().all(|&b| self.bricks[b] == super::Brick::Kept) {
            return (VISIBLE, None);
        }
        if bricks
            .iter()
            .all(|&b| self.bricks[b] == super::Brick::Removed)
        {
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
        let all = (1u16 << (B + 1)) - 1;
        let any_kept = rows.iter().flatten().any(|r| *r != 0);
        let any_removed = rows.iter().flatten().any(|r| *r != all);
        match (any_kept, any_removed) {
            (true, false) => return (VISIBLE, None),
            (false, true) => return (REMOVED, None),
            _ => {}
        }
        let mut cells = CellStates {
            kept: [0; B],
            removed: [0; B],
        };
        for k in 0..B {
            for j in 0..B {
                let (a, b, c, d) = (
                    rows[k][j],
                    rows[k][j + 1],
                    rows[k + 1][j],
                    rows[k + 1][j + 1],
                );
                let (kept, none) = (a & b & c & d, !(a | b | c | d) & all);
                let kept = u64::from(kept & (kept >> 1) & 0xFF);
                let removed = u64::from(none & (none >> 1) & 0xFF);
                cells.kept[k] |= kept << (B * j);
                cells.removed[k] |= removed << (B * j);
            }
        }
        (PARTIAL, Some(Box::new(cells)))
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
            super::Brick::Kept => 0xFF,
            super::Brick::Removed => 0,
            super::Brick::Bits(w) => (w[k % B] >> (B * (j % B))) as u8,
        }
    }
}
