//! Region labelling (seed `004` sec. 6.2): every visible voxel takes the label of the nearest
//! picked point, the distance measured in world units with the grid's anisotropic spacing
//! (the seed measured in texture space, which it notes distorts non-cubic voxels).
use glam::DVec3;
use rayon::prelude::*;

use super::region::VoxelFrame;
use crate::error::{Error, Result};

/// A picked point (world) and the label (1 to 255) it gives; 0 means "no label".
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LabelSeed {
    /// The picked world point.
    pub point: DVec3,
    /// Its label, 1 to 255.
    pub label: u8,
}

/// One label per voxel (x fastest): the label of the seed nearest to the voxel's centre for
/// the voxels `visible` accepts, 0 elsewhere. Ties go to the first seed. Errors without seeds,
/// with a label 0 or a non-finite point, or when the volume does not fit in memory.
pub fn label_nearest(
    frame: &VoxelFrame,
    seeds: &[LabelSeed],
    visible: impl Fn(usize, usize, usize) -> bool + Sync,
) -> Result<Vec<u8>> {
    if seeds.is_empty() {
        return Err(Error::InvalidSculpt(
            "labelling needs at least one picked point".into(),
        ));
    }
    if let Some(s) = seeds.iter().find(|s| s.label == 0 || !s.point.is_finite()) {
        return Err(Error::InvalidSculpt(format!(
            "a picked point needs a label from 1 to 255 and a finite position, got label {} at {}",
            s.label, s.point
        )));
    }
    let [nx, ny, _] = frame.dims;
    let n = crate::limits::count_of(&frame.dims);
    crate::limits::check_alloc("the label volume", n, 1)?;
    // Distances in index space scaled by the spacing are world distances (the direction is
    // orthonormal).
    let s = frame.spacing();
    let centres: Vec<(DVec3, u8)> = seeds
        .iter()
        .map(|seed| (frame.index(seed.point) * s, seed.label))
        .collect();
    let mut out = vec![0u8; n as usize];
    out.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, slice)| {
            for j in 0..ny {
                for i in 0..nx {
                    if !visible(i, j, k) {
                        continue;
                    }
                    let v = DVec3::new(i as f64, j as f64, k as f64) * s;
                    slice[i + nx * j] = nearest(&centres, v);
                }
            }
        });
    Ok(out)
}

/// The label of the centre nearest to `v` (the first of equals).
#[inline]
fn nearest(centres: &[(DVec3, u8)], v: DVec3) -> u8 {
    let mut best = (f64::INFINITY, 0u8);
    for &(c, label) in centres {
        let d = (c - v).length_squared();
        if d < best.0 {
            best = (d, label);
        }
    }
    best.1
}
