//! The mask's summary per macrocell, kept up to date by every edit (`mask.rs`): whether the macrocell is
//! wholly visible, wholly removed or partly removed, and, for a partly removed one, which of
//! its cells have all eight corners kept or all removed. A point in such a cell is visible or
//! not without interpolating; only the cells the cut surface crosses blend their corners.

/// Voxels per brick side, and cells per macrocell side.
pub(super) const B: usize = 8;

/// A macrocell's state: every point in it visible, none, or some.
pub(super) const VISIBLE: u8 = 0;
pub(super) const REMOVED: u8 = 1;
pub(super) const PARTIAL: u8 = 2;

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

/// The state of a macrocell from the kept bits of its voxels, `rows[k][j]` bit `i` for the
/// voxel at (`i`, `j`, `k`) from its first (nine per axis, clamped to the grid), and for a
/// partly removed one its cells' corner states: a row of cells is four rows ANDed (all kept)
/// or NORed (all removed) with their shifted selves.
pub(super) fn summarize(rows: &[[u16; B + 1]; B + 1]) -> (u8, Option<Box<CellStates>>) {
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
