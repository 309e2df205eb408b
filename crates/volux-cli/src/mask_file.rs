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

/// Reads a grid given with `--FLAG path` that must lie on the voxels of `grid` (of `file`):
/// a mask or a label volume, applied by voxel index. One made on another lattice (another
/// orientation, a resampled copy) would land in the wrong place, so the geometry (dims,
/// spacing, origin, direction, unit) is checked; `noun` names it in the errors ("mask",
/// "label volume").
pub fn read_on_voxels(
    flag: &str,
    noun: &str,
    path: &Path,
    grid: &Grid,
    file: &Path,
) -> Result<Grid, CmdError> {
    let named = |e: &dyn std::fmt::Display| format!("--{flag} {}: {e}", path.display());
    let (data, _) = volux_io::load(path, &LoadOptions::default()).map_err(|e| named(&e))?;
    let Dataset::Grid(g) = data else {
        return Err(named(&format!("a {noun} is a grid; this is a tetrahedral mesh")).into());
    };
    volux_core::geometry_match::check_same_geometry(grid, &g).map_err(|e| {
        named(&format!(
            "the {noun} does not lie on {}'s voxels: {e}",
            file.display()
        ))
    })?;
    Ok(g)
}

/// Reads a saved sculpt mask for `grid` (of `file`): any grid file of the same geometry,
/// non-zero voxels kept.
fn read_mask(path: &Path, grid: &Grid, file: &Path) -> Result<SculptMask, CmdError> {
    let named = |e: &dyn std::fmt::Display| format!("--mask {}: {e}", path.display());
    let m = read_on_voxels("mask", "mask", path, grid, file)?;
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
