//! Where a tool's region cuts the mask (seed `004` sec. 4.4-4.5, at full resolution): the
//! bricks it touches, found by halving boxes of bricks from the region's bounds
//! ([`covered_bricks`]: a box the region misses or covers wholly is settled with one
//! coverage test, so an eraser's cone through a 512³ grid tests the bricks along its wall and
//! not every brick), and the bits a brick keeps ([`cut_brick`]: its eight 4³ octants are
//! settled the same way, and only the voxels of the octants the region's surface crosses are
//! tested one by one).
use super::cell_states::B;
use super::region::{Coverage, Region};

/// Bits of one brick (`B³`, x fastest, then y, then z; bit set = kept), in 64-bit words: word
/// `k` is the plane `k`, byte `j` of it the row `j`.
pub(super) const WORDS: usize = B * B * B / 64;

/// Voxels per octant side.
const HALF: usize = B / 2;

/// The bricks (index `i + bx (j + by k)` for `bricks_per_axis = [bx, by, _]`) that `region`
/// may touch within the voxel box `[lo, hi]`, each with its coverage (never
/// [`Coverage::None`]): boxes of bricks are halved along their longest side until the region
/// misses one, covers it wholly or it is one brick. A box's coverage is tested on its
/// bricks' voxels (clamped to `dims`), so that `All` holds for every voxel of each brick in it.
pub(super) fn covered_bricks(
    region: &(impl Region + ?Sized),
    dims: [usize; 3],
    bricks_per_axis: [usize; 3],
    lo: [usize; 3],
    hi: [usize; 3],
) -> Vec<(usize, Coverage)> {
    let mut out = Vec::new();
    let boxes = BrickBoxes {
        dims,
        bricks_per_axis,
    };
    boxes.descend(region, lo.map(|v| v / B), hi.map(|v| v / B), &mut out);
    out
}

/// The brick grid [`covered_bricks`] walks.
struct BrickBoxes {
    dims: [usize; 3],
    bricks_per_axis: [usize; 3],
}

impl BrickBoxes {
    /// Adds the bricks of the box `[blo, bhi]` (brick coordinates, inclusive) that `region`
    /// touches.
    fn descend(
        &self,
        region: &(impl Region + ?Sized),
        blo: [usize; 3],
        bhi: [usize; 3],
        out: &mut Vec<(usize, Coverage)>,
    ) {
        let vlo = blo.map(|b| (b * B) as f64);
        let vhi: [f64; 3] =
            std::array::from_fn(|a| ((bhi[a] + 1) * B).min(self.dims[a]) as f64 - 1.0);
        match region.coverage(vlo, vhi) {
            Coverage::None => {}
            Coverage::All => self.push_all(blo, bhi, out),
            Coverage::Some => {
                let longest = (0..3).max_by_key(|&a| bhi[a] - blo[a]).unwrap_or(0);
                if bhi[longest] == blo[longest] {
                    out.push((self.index(blo), Coverage::Some));
                    return;
                }
                let mid = (blo[longest] + bhi[longest]) / 2;
                let (mut left_hi, mut right_lo) = (bhi, blo);
                left_hi[longest] = mid;
                right_lo[longest] = mid + 1;
                self.descend(region, blo, left_hi, out);
                self.descend(region, right_lo, bhi, out);
            }
        }
    }

    fn push_all(&self, blo: [usize; 3], bhi: [usize; 3], out: &mut Vec<(usize, Coverage)>) {
        for k in blo[2]..=bhi[2] {
            for j in blo[1]..=bhi[1] {
                for i in blo[0]..=bhi[0] {
                    out.push((self.index([i, j, k]), Coverage::All));
                }
            }
        }
    }

    fn index(&self, c: [usize; 3]) -> usize {
        let [bx, by, _] = self.bricks_per_axis;
        c[0] + bx * (c[1] + by * c[2])
    }
}

/// The bits of the voxels `[lo, hi]` (inclusive, a brick's in-range voxels; `lo` a multiple
/// of the brick side) within their brick.
pub(super) fn valid_bits(lo: [usize; 3], hi: [usize; 3]) -> [u64; WORDS] {
    let n = std::array::from_fn::<usize, 3, _>(|a| hi[a] - lo[a] + 1);
    let row = (1u64 << n[0]) - 1;
    let plane = (0..n[1]).fold(0u64, |p, j| p | row << (B * j));
    std::array::from_fn(|k| if k < n[2] { plane } else { 0 })
}

/// The kept bits `old` of the brick of voxels `[lo, hi]` with the voxels of `region` removed.
/// Each 4³ octant the region misses keeps its bits and each it covers loses them, by one
/// coverage test; the voxels of the others are tested one by one, those already removed
/// skipped.
pub(super) fn cut_brick(
    region: &(impl Region + ?Sized),
    lo: [usize; 3],
    hi: [usize; 3],
    old: &[u64; WORDS],
) -> [u64; WORDS] {
    let mut bits = *old;
    for octant in 0..8 {
        let o = [octant & 1, (octant >> 1) & 1, octant >> 2];
        let olo: [usize; 3] = std::array::from_fn(|a| lo[a] + HALF * o[a]);
        if (0..3).any(|a| olo[a] > hi[a]) {
            continue;
        }
        let ohi: [usize; 3] = std::array::from_fn(|a| (olo[a] + HALF - 1).min(hi[a]));
        match region.coverage(olo.map(|v| v as f64), ohi.map(|v| v as f64)) {
            Coverage::None => {}
            Coverage::All => {
                let row = 0x0F0F_0F0Fu64 << (HALF * o[0] + B * HALF * o[1]);
                for w in &mut bits[HALF * o[2]..][..HALF] {
                    *w &= !row;
                }
            }
            Coverage::Some => cut_voxels(region, olo, ohi, &mut bits),
        }
    }
    bits
}

/// Clears the kept bits of the voxels `[lo, hi]` of one brick that `region` holds, a row at
/// a time ([`Region::contains_row`]); rows with nothing kept are skipped.
fn cut_voxels(
    region: &(impl Region + ?Sized),
    lo: [usize; 3],
    hi: [usize; 3],
    bits: &mut [u64; WORDS],
) {
    let width = hi[0] - lo[0] + 1;
    for k in lo[2]..=hi[2] {
        let word = &mut bits[k % B];
        for j in lo[1]..=hi[1] {
            let shift = lo[0] % B + B * (j % B);
            let kept = (*word >> shift) & ((1 << width) - 1);
            if kept != 0 {
                *word &= !((region.contains_row(lo[0], hi[0], j, k) & kept) << shift);
            }
        }
    }
}
