//! Connected region growing for [`RegionRule::Connected`](super::RegionRule) seeds (issue 41;
//! seed `004` sec. 6.2 labels by the nearest point only): a breadth-first growth from all
//! connected seeds at once through the 6-connected visible voxels. A voxel goes to the seed
//! whose region reaches it in the fewest steps; at equal steps to the earlier seed (the
//! queue holds each step's voxels in seed order, so the first claim is the earliest seed's).
//! Memory: one visibility bit per voxel, the label array being written, and the queue (the
//! growth front); no recursion.
use std::collections::VecDeque;

use glam::DVec3;
use rayon::prelude::*;

use super::region::VoxelFrame;
use crate::error::{Error, Result};

/// Words of visibility bits one parallel task fills.
const WORDS_PER_TASK: usize = 1024;

/// One bit per voxel (x fastest): visible and not yet claimed by a connected seed.
pub(super) struct Unclaimed {
    words: Vec<u64>,
}

impl Unclaimed {
    /// The voxels of `frame` that `visible` accepts (evaluated in parallel, once each).
    pub(super) fn of(
        frame: &VoxelFrame,
        visible: &(impl Fn(usize, usize, usize) -> bool + Sync),
    ) -> Result<Self> {
        let [nx, ny, _] = frame.dims;
        let n = crate::limits::count_of(&frame.dims);
        let word_count = n.div_ceil(64);
        crate::limits::check_alloc("the visible-voxel bits", word_count, 8)?;
        let n = n as usize;
        let mut words = vec![0u64; word_count as usize];
        words
            .par_chunks_mut(WORDS_PER_TASK)
            .enumerate()
            .for_each(|(task, chunk)| {
                let mut v = task * WORDS_PER_TASK * 64;
                let (mut i, mut j, mut k) = (v % nx, v / nx % ny, v / (nx * ny));
                for word in chunk {
                    for bit in 0..64 {
                        if v >= n {
                            return;
                        }
                        if visible(i, j, k) {
                            *word |= 1 << bit;
                        }
                        v += 1;
                        i += 1;
                        if i == nx {
                            i = 0;
                            j += 1;
                            if j == ny {
                                j = 0;
                                k += 1;
                            }
                        }
                    }
                }
            });
        Ok(Self { words })
    }

    /// Whether voxel `v` (linear index) is visible and unclaimed.
    #[inline]
    pub(super) fn get(&self, v: usize) -> bool {
        self.words[v >> 6] >> (v & 63) & 1 == 1
    }

    /// Claims voxel `v`: returns whether it was visible and unclaimed, and clears it.
    #[inline]
    fn take(&mut self, v: usize) -> bool {
        let (word, bit) = (&mut self.words[v >> 6], 1u64 << (v & 63));
        let was = *word & bit != 0;
        *word &= !bit;
        was
    }
}

/// Grows the regions of `seeds` (continuous voxel index of the picked point, label) through
/// `unclaimed` into `out` (one label per voxel, x fastest; claimed voxels are cleared from
/// `unclaimed`). A seed starts from the visible voxel nearest (world distance) to its point
/// among the 3×3×3 voxels about it (the picked surface point lies between voxels; the
/// nearest one may be empty); a seed with none labels nothing. Errors when an axis has more
/// voxels than the queue's 32-bit coordinates hold.
pub(super) fn grow(
    frame: &VoxelFrame,
    seeds: &[(DVec3, u8)],
    unclaimed: &mut Unclaimed,
    out: &mut [u8],
) -> Result<()> {
    let [nx, ny, nz] = frame.dims;
    if frame.dims.iter().any(|&d| u32::try_from(d).is_err()) {
        return Err(Error::InvalidSculpt(format!(
            "connected labelling handles up to {} voxels per axis, the grid has {:?}",
            u32::MAX,
            frame.dims
        )));
    }
    let at = |[i, j, k]: [u32; 3]| i as usize + nx * (j as usize + ny * k as usize);
    // Every start is chosen before any is claimed: a seed's start does not depend on the
    // seeds before it (two seeds on one voxel: the first takes it).
    let starts: Vec<_> = seeds
        .iter()
        .map(|&(c, label)| (start(frame, unclaimed, c), label))
        .collect();
    let mut queue = VecDeque::new();
    for (s, label) in starts {
        let Some(s) = s else { continue };
        if unclaimed.take(at(s)) {
            out[at(s)] = label;
            queue.push_back(s);
        }
    }
    let top = [nx - 1, ny - 1, nz - 1].map(|d| d as u32);
    while let Some(v) = queue.pop_front() {
        let label = out[at(v)];
        for axis in 0..3 {
            for up in [false, true] {
                let mut w = v;
                match up {
                    false if v[axis] > 0 => w[axis] -= 1,
                    true if v[axis] < top[axis] => w[axis] += 1,
                    _ => continue,
                }
                let n = at(w);
                if unclaimed.take(n) {
                    out[n] = label;
                    queue.push_back(w);
                }
            }
        }
    }
    Ok(())
}

/// The visible voxel nearest (world distance, the first in x-fastest order of equals) to
/// continuous index `c` among the 3×3×3 voxels about its rounding.
fn start(frame: &VoxelFrame, unclaimed: &Unclaimed, c: DVec3) -> Option<[u32; 3]> {
    let [nx, ny, _] = frame.dims;
    let r = c.round();
    let mut best: Option<(f64, [u32; 3])> = None;
    for dk in -1..=1 {
        for dj in -1..=1 {
            for di in -1..=1 {
                let v = r + DVec3::new(f64::from(di), f64::from(dj), f64::from(dk));
                let inside = (0..3).all(|a| v[a] >= 0.0 && v[a] < frame.dims[a] as f64);
                if !inside {
                    continue;
                }
                let ijk = [v.x as u32, v.y as u32, v.z as u32];
                let n = ijk[0] as usize + nx * (ijk[1] as usize + ny * ijk[2] as usize);
                if !unclaimed.get(n) {
                    continue;
                }
                let d = ((v - c) * frame.spacing()).length_squared();
                if best.is_none_or(|(b, _)| d < b) {
                    best = Some((d, ijk));
                }
            }
        }
    }
    best.map(|(_, ijk)| ijk)
}
