//! Where the brick pool's bricks come from ([`PoolSource`]): a grid in memory, or one level
//! of a bricked volume read through its brick cache (out of core).
use std::collections::HashMap;
use std::sync::Arc;

use volux_core::Grid;
use volux_render::backend_kit::Placement;
use volux_render::backend_kit::{level_placement, Brick, BrickCache};
use volux_render::bricked::BrickedVolume;

use crate::error::GpuError;

/// A grid, whole in memory or stored in chunks, that the pool reads bricks of.
#[derive(Clone)]
pub enum PoolSource {
    /// A grid in memory.
    Grid(Arc<Grid>),
    /// Level `.1` of a bricked volume.
    Level(Arc<BrickedVolume>, usize),
}

impl PoolSource {
    /// Where the grid lies in the world.
    pub(crate) fn placement(&self) -> Result<Placement, GpuError> {
        match self {
            Self::Grid(g) => Ok(Placement::of(g)),
            Self::Level(v, level) => Ok(level_placement(cache(v, *level)?)),
        }
    }

    /// The data range the transfer function is placed on (the whole volume's).
    pub(crate) fn range(&self) -> [f64; 2] {
        match self {
            Self::Grid(g) => g.range(),
            Self::Level(v, _) => v.range(),
        }
    }

    /// Writes into `out` the samples `lo + [0, side)` per axis (x fastest), each index
    /// clamped to the grid, as `f32` with undefined and infinite values as NaN.
    pub(crate) fn read_box(
        &self,
        lo: [usize; 3],
        side: usize,
        dims: [usize; 3],
        out: &mut [f32],
    ) -> Result<(), GpuError> {
        let index = |l: usize, a: usize| (lo[a] + l).min(dims[a] - 1);
        let finite = |v: f32| if v.is_finite() { v } else { f32::NAN };
        match self {
            Self::Grid(g) => {
                let s = g.samples();
                for (n, v) in out.iter_mut().enumerate() {
                    let (i, j, k) = (
                        index(n % side, 0),
                        index(n / side % side, 1),
                        index(n / (side * side), 2),
                    );
                    *v = finite(s.get_f32(i + dims[0] * (j + dims[1] * k)));
                }
            }
            Self::Level(vol, level) => {
                let cache = cache(vol, *level)?;
                let chunk = cache.layout().chunk;
                let mut bricks: HashMap<[usize; 3], Arc<Brick>> = HashMap::new();
                for (n, v) in out.iter_mut().enumerate() {
                    let p = [
                        index(n % side, 0),
                        index(n / side % side, 1),
                        index(n / (side * side), 2),
                    ];
                    let c = [p[0] / chunk[0], p[1] / chunk[1], p[2] / chunk[2]];
                    let brick = match bricks.get(&c) {
                        Some(b) => b.clone(),
                        None => {
                            let b = cache.get(c).map_err(GpuError::Failed)?;
                            bricks.insert(c, b.clone());
                            b
                        }
                    };
                    *v = finite(brick.at(p[0], p[1], p[2]));
                }
            }
        }
        Ok(())
    }
}

fn cache(v: &BrickedVolume, level: usize) -> Result<&BrickCache, GpuError> {
    v.cache(level).ok_or_else(|| {
        GpuError::Failed(format!(
            "level {level} does not exist: the volume has {} levels",
            v.levels()
        ))
    })
}
