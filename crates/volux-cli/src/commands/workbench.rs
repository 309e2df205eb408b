//! What the sculpting commands share (seed `004` ch. 4-6): the grid seen in the view of the
//! command line (camera, size and transfer function defaulted as `volux render` does), its
//! sculpt state (clip planes, a starting mask), pixel arguments, and masks and label volumes
//! read and written as NRRD `u8` with the grid's geometry.
use std::path::Path;
use std::sync::Arc;

use volux_app::session::DatasetRef;
use volux_core::{Buffer, Grid, Samples};
use volux_io::Dataset;
use volux_render::scene::{Scene, Volume};
use volux_render::sculpt::{Sculpt, SculptStep, SurfacePoint};

use super::common::CmdError;
use crate::cli::ToolViewArgs;
use crate::settings::RenderPlan;

/// A grid in the view of the command line, with its sculpt state.
pub struct Workbench {
    /// The grid.
    pub grid: Arc<Grid>,
    /// The scene `volux render` would draw with the same options (no mask, no planes: the
    /// sculpt state holds them).
    pub scene: Scene,
    /// The clip planes of the command line and the starting mask.
    pub sculpt: Sculpt,
}

impl Workbench {
    /// Loads the grid of `view` and sets up its view and sculpt state (`given`: the options
    /// typed, checked as `volux render` checks them).
    pub fn open(view: &ToolViewArgs, given: &[String], show: bool) -> Result<Self, CmdError> {
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
        let mut scene = plan.scene(&args, &volume, true)?;
        let mut sculpt = Sculpt::new(&grid)?;
        for plane in std::mem::take(&mut scene.clip_planes) {
            sculpt.apply(SculptStep::AddPlane { plane })?;
        }
        // The scene read `--mask` (and framed what it leaves); the sculpt state owns it.
        if let Some(mask) = scene.mask.take() {
            sculpt = sculpt.with_mask(Arc::unwrap_or_clone(mask))?;
        }
        Ok(Self {
            grid,
            scene,
            sculpt,
        })
    }

    /// The image size, pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.scene.view.width, self.scene.view.height)
    }

    /// The visible surface under `pixel` (named `what` in the error when there is none).
    pub fn pick(&self, pixel: [f64; 2], what: &str) -> Result<SurfacePoint, CmdError> {
        self.sculpt
            .pick(&self.grid, &self.scene, pixel)?
            .ok_or_else(|| no_surface(what, pixel))
    }

    /// Writes `values` (one byte per voxel, x fastest) as an NRRD `u8` volume with the
    /// grid's spacing, origin and direction (atomically: no partial file).
    pub fn write_u8(&self, values: Vec<u8>, path: &Path) -> Result<(), CmdError> {
        write_u8_like(&self.grid, values, path)
    }
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
