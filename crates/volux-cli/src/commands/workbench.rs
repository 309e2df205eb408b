//! What the sculpting commands share (seed `004` ch. 4-6): the grid seen in the view of the
//! command line (camera, size and transfer function defaulted as `volux render` does), its
//! sculpt state (clip planes, a starting mask), pixel arguments, and masks and label volumes
//! read and written as NRRD `u8` with the grid's geometry.
use std::path::Path;
use std::sync::Arc;

use volux_app::session::DatasetRef;
use volux_core::{Buffer, Grid, Samples};
use volux_io::Dataset;
use volux_render::scene::Volume;
use volux_render::sculpt::SurfacePoint;

use super::common::CmdError;
use crate::cli::ToolViewArgs;
use crate::settings::RenderPlan;

/// A grid in the view of the command line, with its sculpt state
/// ([`volux_app::tools::Workbench`]).
pub use volux_app::tools::Workbench;

/// Opens the grid of `view` in the view of the command line (`given`: the options typed,
/// for the scene's defaults): the scene as `volux render` builds it, its clip planes and mask
/// starting the sculpt state.
pub fn open(view: &ToolViewArgs, given: &[String], show: bool) -> Result<Workbench, CmdError> {
    let args = view.render_args(given);
    let plan = RenderPlan::new(&args)?;
    let (data, _) = super::common::load(&view.file, &view.load, show)?;
    let Dataset::Grid(grid) = data else {
        return Err(format!(
            "{}: sculpting, measuring and labelling apply to grids; this is a tetrahedral \
             mesh",
            view.file.display()
        )
        .into());
    };
    let grid = Arc::new(grid);
    let volume = Volume::Grid(grid.clone());
    let scene = plan.scene(&args, &volume, true)?;
    Ok(Workbench::new(grid, scene)?)
}

/// The visible surface under `pixel` (`what` names it in the error when there is none).
pub fn pick(bench: &Workbench, pixel: [f64; 2], what: &str) -> Result<SurfacePoint, CmdError> {
    bench.pick(pixel)?.ok_or_else(|| no_surface(what, pixel))
}

/// The error of a pixel whose ray shows no surface.
pub fn no_surface(what: &str, [x, y]: [f64; 2]) -> CmdError {
    format!(
        "{what}: pixel ({x}, {y}) shows no visible surface (its ray never reaches opacity 0.5 \
         under the transfer function, clip planes and mask)"
    )
    .into()
}

/// The dataset reference a session saves for `view`.
pub fn dataset_ref(view: &ToolViewArgs) -> DatasetRef {
    view.load.dataset(&view.file)
}

/// Writes `values` as an NRRD `u8` volume with `grid`'s geometry.
pub fn write_u8_like(grid: &Grid, values: Vec<u8>, path: &Path) -> Result<(), CmdError> {
    let s = grid.spacing().to_array();
    let o = grid.origin().to_array();
    let out = Grid::new(grid.dims(), s, o, Samples::U8(Buffer::owned(values)))?
        .with_direction(grid.direction())?;
    volux_io::nrrd::write(&out, path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(())
}

/// Checks that `path` names an NRRD file (`flag` for the message), before any work.
pub fn nrrd_path(path: &Path, flag: &str) -> Result<(), CmdError> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
    match ext.as_deref() {
        Some("nrrd") => Ok(()),
        _ => Err(format!(
            "{flag} {}: masks and labels are written as NRRD; name the file .nrrd",
            path.display()
        )
        .into()),
    }
}

/// Parses `flag`'s value `s` as `n` comma-separated finite numbers (`form` names them).
pub fn numbers(flag: &str, s: &str, form: &str) -> Result<Vec<f64>, CmdError> {
    let bad = || format!("--{flag} '{s}': expected {form}");
    let v: Vec<f64> = s
        .split(',')
        .map(|c| c.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    if v.iter().any(|x| !x.is_finite()) {
        return Err(bad().into());
    }
    Ok(v)
}

/// Checks that `pixel` lies in an image of `size` (`what` names it).
pub fn in_image(what: &str, [x, y]: [f64; 2], (w, h): (usize, usize)) -> Result<(), CmdError> {
    if (0.0..=w as f64).contains(&x) && (0.0..=h as f64).contains(&y) {
        return Ok(());
    }
    Err(format!("{what}: pixel ({x}, {y}) lies outside the {w}x{h} image (see --size)").into())
}

/// Parses a pixel `X,Y` of `flag`.
pub fn pixel(flag: &str, s: &str) -> Result<[f64; 2], CmdError> {
    match numbers(flag, s, "X,Y (pixels)")?.as_slice() {
        [x, y] => Ok([*x, *y]),
        _ => Err(format!("--{flag} '{s}': expected X,Y (pixels)").into()),
    }
}

/// Parses `X,Y,R` of `flag`: a pixel and a radius in pixels (> 0).
pub fn pixel_radius(flag: &str, s: &str) -> Result<([f64; 2], f64), CmdError> {
    let form = "X,Y,R (pixels, radius R > 0)";
    match numbers(flag, s, form)?.as_slice() {
        [x, y, r] if *r > 0.0 => Ok(([*x, *y], *r)),
        _ => Err(format!("--{flag} '{s}': expected {form}").into()),
    }
}
