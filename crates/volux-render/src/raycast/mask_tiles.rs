//! The tiles of a frame that the sculpt mask can change (seed `004` sec. 4.4: the mask hides
//! what the tools cut away, and nothing elsewhere). A ray that crosses only macrocells the
//! mask leaves wholly visible samples exactly what it samples without the mask, so the tiles
//! whose rays miss every removed or partly removed macrocell are rendered as if there were no
//! mask: no macrocell walk and no mask test. Which tiles those are is found by projecting the
//! boxes of the macrocells the mask touches (runs of them along x, one box each) onto the
//! screen: a box in front of the eye projects inside the bounding box of its corners' pixels.
use glam::DVec3;
use volux_core::sculpt::SculptMask;

use super::options::{Placement, RenderOptions};
use crate::tiles::TileGrid;

/// Pixels added around each projected box: the rays of a pixel leave from within it (jitter
/// included), and the projection and the ray generator round differently.
const MARGIN_PX: f64 = 1.5;

/// Per tile of a [`TileGrid`], whether the sculpt mask can change it.
pub(crate) struct MaskTiles {
    touched: Vec<bool>,
    grid: TileGrid,
}

impl MaskTiles {
    /// The tiles of `grid` whose rays (the camera and image of `opts`) may cross a macrocell
    /// of `mask` that is not wholly visible, for a grid placed by `place`.
    pub(crate) fn new(
        mask: &SculptMask,
        place: &Placement,
        opts: &RenderOptions,
        grid: TileGrid,
    ) -> Self {
        let mut tiles = Self {
            touched: vec![false; grid.cols * grid.rows],
            grid,
        };
        for (lo, hi) in touched_boxes(mask) {
            if !tiles.mark_box(place, opts, lo, hi) {
                tiles.touched.fill(true);
                break;
            }
        }
        tiles
    }

    /// Whether the tile whose first pixel is (`x0`, `y0`) may be changed by the mask.
    pub(crate) fn touched(&self, x0: usize, y0: usize) -> bool {
        let (c, r) = (x0 / self.grid.side, y0 / self.grid.side);
        self.touched
            .get(c + self.grid.cols * r)
            .copied()
            .unwrap_or(true)
    }

    /// Whether some tile is out of the mask's reach.
    pub(crate) fn any_untouched(&self) -> bool {
        self.touched.iter().any(|t| !t)
    }

    /// Marks the tiles the voxel box `[lo, hi]` projects onto; `false` when a corner lies at
    /// or behind the eye (the projection is then unbounded).
    fn mark_box(&mut self, place: &Placement, opts: &RenderOptions, lo: DVec3, hi: DVec3) -> bool {
        let (w, h) = (opts.width, opts.height);
        let perspective = matches!(
            opts.camera.projection,
            volux_core::camera::Projection::Perspective { .. }
        );
        let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for corner in 0..8 {
            let pick = |a: usize| if corner >> a & 1 == 1 { hi[a] } else { lo[a] };
            let ijk = DVec3::new(pick(0), pick(1), pick(2));
            let world = place.origin + place.direction * (place.spacing * ijk);
            let (x, y, depth) = opts.camera.project(world, w, h);
            if (perspective && depth <= 0.0) || !(x.is_finite() && y.is_finite()) {
                return false;
            }
            min = [min[0].min(x), min[1].min(y)];
            max = [max[0].max(x), max[1].max(y)];
        }
        let side = self.grid.side as f64;
        let range = |lo: f64, hi: f64, n: usize| {
            let first = ((lo - MARGIN_PX) / side).floor().max(0.0);
            let last = ((hi + MARGIN_PX) / side).floor().min(n as f64 - 1.0);
            (first <= last).then_some((first as usize, last as usize))
        };
        let (Some(cols), Some(rows)) = (
            range(min[0], max[0], self.grid.cols),
            range(min[1], max[1], self.grid.rows),
        ) else {
            return true;
        };
        for r in rows.0..=rows.1 {
            self.touched[self.grid.cols * r..][cols.0..=cols.1].fill(true);
        }
        true
    }
}

/// The voxel boxes (inclusive corners) of the runs along x of macrocells the mask does not
/// leave wholly visible. A macrocell covers the voxels `[8 I, 8 I + 8]` per axis, clamped to
/// the grid (its cells read the first layer of the next).
fn touched_boxes(mask: &SculptMask) -> Vec<(DVec3, DVec3)> {
    let [mx, my, mz] = mask.blocks_per_axis();
    let top = mask.dims().map(|d| d.saturating_sub(1) as f64);
    let block = SculptMask::BLOCK as f64;
    let corner = |c: [usize; 3], hi: bool| {
        DVec3::from(std::array::from_fn::<f64, 3, _>(|a| {
            let v = (c[a] as f64 + f64::from(u8::from(hi))) * block;
            v.min(top[a])
        }))
    };
    let mut boxes = Vec::new();
    for k in 0..mz {
        for j in 0..my {
            let mut i = 0;
            while i < mx {
                let m = i + mx * (j + my * k);
                if !(mask.block_removed(m) || mask.block_partial(m)) {
                    i += 1;
                    continue;
                }
                let start = i;
                while i < mx && {
                    let m = i + mx * (j + my * k);
                    mask.block_removed(m) || mask.block_partial(m)
                } {
                    i += 1;
                }
                boxes.push((corner([start, j, k], false), corner([i - 1, j, k], true)));
            }
        }
    }
    boxes
}

#[cfg(test)]
mod tests;
