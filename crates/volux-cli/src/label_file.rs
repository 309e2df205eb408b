//! `volux render --labels LABELS.nrrd`: a label volume saved by `volux regions` (or any
//! segmentation on the data's voxels: integers 0 to 255, 0 unlabelled) coloured in the
//! render as the viewer colours its regions (seed `004` sec. 6.2): each label takes its
//! palette colour ([`palette_colour`]), the opacity stays the transfer function's.
use std::path::Path;
use std::sync::Arc;

use volux_render::scene::{Scene, Volume};
use volux_render::sculpt::labels::palette_colour;
use volux_render::sculpt::LabelVolume;

use crate::commands::common::CmdError;

/// Puts the labels at `path` into `scene`, for the grid of `volume` read from `file`: the
/// label file must lie on the grid's voxels (dims, spacing, origin, direction) and hold
/// integers 0 to 255; scenes that draw no labels (MIP, meshes) are refused with the reason.
pub fn add_labels(
    path: &Path,
    volume: &Volume,
    file: &Path,
    scene: &mut Scene,
) -> Result<(), CmdError> {
    let named = |e: &dyn std::fmt::Display| format!("--labels {}: {e}", path.display());
    let Volume::Grid(grid) = volume else {
        return Err(named(&format!(
            "labels colour grids; {} is rendered as a tetrahedral mesh",
            file.display()
        ))
        .into());
    };
    if let Some(why) = scene.labels_not_drawn() {
        return Err(named(&why).into());
    }
    let labels = crate::mask_file::read_on_voxels("labels", "label volume", path, grid, file)?;
    let s = labels.samples();
    let mut values = Vec::with_capacity(s.len());
    for i in 0..s.len() {
        let v = s.get_f32(i);
        if !(v.fract() == 0.0 && (0.0..=255.0).contains(&v)) {
            return Err(named(&format!(
                "voxel {i} holds {v}, not a label (integers 0 to 255)"
            ))
            .into());
        }
        values.push(v as u8);
    }
    let colours: Vec<(u8, [f32; 3])> = (1..=255u8)
        .filter_map(|l| palette_colour(l).map(|c| (l, c)))
        .collect();
    let volume = LabelVolume::new(grid.dims(), values, &colours).map_err(|e| named(&e))?;
    scene.labels = Some(Arc::new(volume));
    Ok(())
}
