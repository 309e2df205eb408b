//! `--mask MASK.nrrd`: a sculpt mask saved by `volux sculpt` or the viewer, read for the
//! grid it was made on (its geometry checked), as `render`, `sculpt`, `measure` and
//! `regions` use it.
use std::path::Path;
use std::sync::Arc;

use volux_core::sculpt::SculptMask;
use volux_core::Grid;
use volux_io::{Dataset, LoadOptions};
use volux_render::scene::{Scene, Volume};

use crate::commands::common::CmdError;

/// Reads a saved sculpt mask for `grid` (of `file`): any grid file of the same geometry
/// (dims, spacing, origin, direction, unit), non-zero voxels kept.
fn read_mask(path: &Path, grid: &Grid, file: &Path) -> Result<SculptMask, CmdError> {
    let named = |e: &dyn std::fmt::Display| format!("--mask {}: {e}", path.display());
    let (data, _) = volux_io::load(path, &LoadOptions::default()).map_err(|e| named(&e))?;
    let Dataset::Grid(m) = data else {
        return Err(named(&"a mask is a grid; this is a tetrahedral mesh").into());
    };
    // A mask made on another lattice (another orientation, a resampled copy) would be
    // applied by voxel index to the wrong place.
    volux_core::geometry_match::check_same_geometry(grid, &m).map_err(|e| {
        named(&format!(
            "the mask does not lie on {}'s voxels: {e}",
            file.display()
        ))
    })?;
    let s = m.samples();
    let values: Vec<u8> = (0..s.len())
        .map(|i| u8::from(s.get_f32(i) != 0.0))
        .collect();
    Ok(SculptMask::from_values(m.dims(), &values).map_err(|e| named(&e))?)
}

/// Puts the mask at `path` into `scene` (`volux render --mask`): grids only.
pub fn add_mask(
    path: &Path,
    volume: &Volume,
    file: &Path,
    scene: &mut Scene,
) -> Result<(), CmdError> {
    let Volume::Grid(grid) = volume else {
        return Err(format!(
            "--mask applies to grids; {} is rendered as a tetrahedral mesh",
            file.display()
        )
        .into());
    };
    let mask = read_mask(path, grid, file)?;
    // A mask that removes nothing changes no pixel: leave the scene without one, as the
    // engine's sculpt state does (`Sculpt::apply_to`).
    scene.mask = (!mask.is_untouched()).then(|| Arc::new(mask));
    Ok(())
}
