//! Region labelling (seed `004` sec. 6.2): the visible voxels take the labels of picked
//! points. The seed gives each voxel the label of the nearest point ([`RegionRule::Nearest`]),
//! the distance measured here in world units with the grid's anisotropic spacing (the seed
//! measured in texture space, which it notes distorts non-cubic voxels). That labels parts
//! no seed touches (a seed on the skull labels the head rest); [`RegionRule::Connected`]
//! (issue 41) grows a seed's region through the visible voxels it connects to instead
//! (`grow.rs`: breadth-first, 6-connected, in voxel steps).
use glam::DVec3;
use rayon::prelude::*;

use super::grow::{grow, Unclaimed};
use super::region::VoxelFrame;
use crate::error::{Error, Result};

/// How a labelling seed claims voxels.
///
/// The default is [`RegionRule::Nearest`] because it is what a seed saved before the rule
/// existed meant (a session without the field replays as it did); the CLI (`volux regions
/// --rule`) and the viewer give new seeds [`RegionRule::Connected`], what a seed placed on a
/// structure is expected to label.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum RegionRule {
    /// Every visible voxel no connected region holds that lies nearer (world distance) to
    /// this seed than to any other nearest-rule seed (seed `004` sec. 6.2).
    #[default]
    Nearest,
    /// The visible voxels reachable from the seed through visible voxels (6-connected);
    /// where regions meet, a voxel goes to the seed that reaches it in the fewest voxel
    /// steps, at equal steps to the earlier seed.
    Connected,
}

impl RegionRule {
    /// Both rules, connected first (the choice offered for new seeds).
    pub const ALL: [RegionRule; 2] = [RegionRule::Connected, RegionRule::Nearest];

    /// Its name, as saved and as `--rule` takes it.
    pub fn name(self) -> &'static str {
        match self {
            RegionRule::Nearest => "nearest",
            RegionRule::Connected => "connected",
        }
    }

    /// Whether it is [`RegionRule::Nearest`] (the saved default, left out of sessions).
    pub fn is_nearest(&self) -> bool {
        *self == RegionRule::Nearest
    }
}

/// A picked point (world), the label (1 to 255) it gives (0 means "no label") and how it
/// claims voxels.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LabelSeed {
    /// The picked world point.
    pub point: DVec3,
    /// Its label, 1 to 255.
    pub label: u8,
    /// How it claims voxels.
    #[serde(default)]
    pub rule: RegionRule,
}

/// One label per voxel (x fastest), 0 where no seed claims the voxel; only voxels `visible`
/// accepts are labelled. Connected seeds grow first ([`RegionRule::Connected`]: the voxels
/// no connected seed reaches stay 0 unless a nearest seed takes them); the visible voxels
/// they leave go to the nearest [`RegionRule::Nearest`] seed in world distance, ties to the
/// first seed. Errors without seeds, with a label 0 or a non-finite point, or when the
/// volume does not fit in memory.
pub fn label_regions(
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
    let n = crate::limits::count_of(&frame.dims);
    crate::limits::check_alloc("the label volume", n, 1)?;
    let mut out = vec![0u8; n as usize];
    // Distances in index space scaled by the spacing are world distances (the direction is
    // orthonormal).
    let s = frame.spacing();
    let of_rule = |rule: RegionRule| -> Vec<(DVec3, u8)> {
        seeds
            .iter()
            .filter(|seed| seed.rule == rule)
            .map(|seed| (frame.index(seed.point), seed.label))
            .collect()
    };
    let connected = of_rule(RegionRule::Connected);
    let centres: Vec<(DVec3, u8)> = of_rule(RegionRule::Nearest)
        .into_iter()
        .map(|(c, label)| (c * s, label))
        .collect();
    if connected.is_empty() {
        fill_nearest(frame, &centres, &mut out, visible);
        return Ok(out);
    }
    let mut unclaimed = Unclaimed::of(frame, &visible)?;
    grow(frame, &connected, &mut unclaimed, &mut out)?;
    if !centres.is_empty() {
        let [nx, ny, _] = frame.dims;
        fill_nearest(frame, &centres, &mut out, |i, j, k| {
            unclaimed.get(i + nx * (j + ny * k))
        });
    }
    Ok(out)
}

/// Gives each voxel `visible` accepts the label of the nearest of `centres` (index scaled by
/// the spacing).
fn fill_nearest(
    frame: &VoxelFrame,
    centres: &[(DVec3, u8)],
    out: &mut [u8],
    visible: impl Fn(usize, usize, usize) -> bool + Sync,
) {
    let [nx, ny, _] = frame.dims;
    let s = frame.spacing();
    out.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, slice)| {
            for j in 0..ny {
                for i in 0..nx {
                    if !visible(i, j, k) {
                        continue;
                    }
                    let v = DVec3::new(i as f64, j as f64, k as f64) * s;
                    slice[i + nx * j] = nearest(centres, v);
                }
            }
        });
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
