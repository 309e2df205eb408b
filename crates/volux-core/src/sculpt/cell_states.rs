//! The mask's summary per macrocell, kept up to date by every edit (`mask.rs`): whether the macrocell is
//! wholly visible, wholly removed or partly removed, and, for a partly removed one, the
//! corners of each of its cells. A point in a cell whose corners are all kept or all removed
//! is visible or not without interpolating; only the cells the cut surface crosses blend
//! their corners.

/// Voxels per brick side, and cells per macrocell side.
pub(super) const B: usize = 8;

/// A macrocell's state: every point in it visible, none, or some.
pub(super) const VISIBLE: u8 = 0;
pub(super) const REMOVED: u8 = 1;
pub(super) const PARTIAL: u8 = 2;

/// The corners of each cell of one partly removed macrocell: byte `i + 8 j + 64 k` for the
/// cell at (`i`, `j`, `k`) from the macrocell's first, bit `dx + 2 dy + 4 dz` set when the
/// corner at (`i + dx`, `j + dy`, `k + dz`) is kept (as [`SculptMask`](super::SculptMask)'s
/// interpolation reads them). 512 bytes a partly removed macrocell: a point's visibility is
/// then one byte read, and a blend only where the byte is mixed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct CellStates {
    corners: [u8; B * B * B],
}

impl CellStates {
    /// The corners of cell `c` (grid cell coordinates) of this macrocell.
    #[inline]
    pub(super) fn corners(&self, c: [usize; 3]) -> u8 {
        self.corners[c[0] % B + B * (c[1] % B) + B * B * (c[2] % B)]
    }
}

/// Byte `i` of `SPREAD[r]` holds bits `i` and `i + 1` of the nine-bit row `r`: the corner
/// pairs of a row's eight cells in one look-up (a loop over the cells made the eraser 25 %
/// slower, the summaries being rebuilt for every macrocell an edit touches).
const SPREAD: [u64; 512] = {
    let mut table = [0u64; 512];
    let mut r = 0;
    while r < 512 {
        let mut i = 0;
        while i < B {
            table[r] |= ((r as u64 >> i) & 3) << (8 * i);
            i += 1;
        }
        r += 1;
    }
    table
};

/// The state of a macrocell from the kept bits of its voxels, `rows[k][j]` bit `i` for the
/// voxel at (`i`, `j`, `k`) from its first (nine per axis, clamped to the grid), and for a
/// partly removed one its cells' corners: each a bit pair of four rows.
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
        corners: [0; B * B * B],
    };
    let spread = |r: u16| SPREAD[usize::from(r) & 511];
    for k in 0..B {
        for j in 0..B {
            let w = spread(rows[k][j])
                | spread(rows[k][j + 1]) << 2
                | spread(rows[k + 1][j]) << 4
                | spread(rows[k + 1][j + 1]) << 6;
            cells.corners[B * (j + B * k)..][..B].copy_from_slice(&w.to_le_bytes());
        }
    }
    (PARTIAL, Some(Box::new(cells)))
}
