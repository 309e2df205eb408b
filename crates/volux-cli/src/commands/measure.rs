//! `volux measure`: distance on the visible surface (seed `004` sec. 6.2). Each `--point`
//! pixel is picked where the opacity along its ray reaches 0.5 (after the clip planes and
//! the mask), and the polyline through the points is measured in world units: millimetres
//! from the data's spacing (or the unit the file gives, micrometres for microscopy), not
//! texture space (the seed's sec. 4.5.1 flaw).
//! `volux render --measure` measures the same way in the scene it renders and draws the
//! points and the polyline on the picture ([`Drawn`]).
use glam::DVec3;
use serde_json::json;
use volux_core::Image;
use volux_render::scene::{Scene, Volume};
use volux_render::sculpt::{pick, polyline_length, DEFAULT_PICK_OPACITY};

use super::common::CmdError;
use super::workbench;
use crate::cli::{MeasureArgs, RenderArgs};

/// Runs `volux measure`.
pub fn run(args: &MeasureArgs, given: &[String], show: bool) -> Result<(), CmdError> {
    if args.points.len() < 2 {
        return Err("give at least two --point X,Y to measure between".into());
    }
    let pixels = args
        .points
        .iter()
        .map(|s| workbench::pixel("point", s))
        .collect::<Result<Vec<_>, _>>()?;
    let bench = workbench::open(&args.view, given, show)?;
    let mut points = Vec::with_capacity(pixels.len());
    for (pixel, typed) in pixels.iter().zip(&args.points) {
        let what = format!("--point {typed}");
        workbench::in_image(&what, *pixel, bench.size())?;
        points.push(workbench::pick(&bench, *pixel, &what)?.world);
    }
    let length = polyline_length(&points);
    let unit = bench.grid.unit();
    if args.json {
        let xyz: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
        let mut v = json!({ "points": xyz, "length": length, "unit": unit });
        if unit == "mm" {
            v["length_mm"] = json!(length);
        }
        outln!("{v}")?;
    } else {
        print_text(&pixels, &points, length, unit)?;
    }
    Ok(())
}

/// The points and the length as text.
fn print_text(
    pixels: &[[f64; 2]],
    points: &[DVec3],
    length: f64,
    unit: &str,
) -> std::io::Result<()> {
    for (n, ([x, y], p)) in pixels.iter().zip(points).enumerate() {
        outln!(
            "point {} at pixel ({x}, {y}): ({:.3}, {:.3}, {:.3})",
            n + 1,
            p.x,
            p.y,
            p.z
        )?;
    }
    if points.len() < 2 {
        return Ok(());
    }
    outln!(
        "length: {length:.3} {unit} ({} segment{})",
        points.len() - 1,
        if points.len() == 2 { "" } else { "s" }
    )?;
    Ok(())
}

/// A measurement of `volux render --measure`: the pixels given, the surface points picked
/// under them, and the polyline's length.
pub struct Drawn {
    /// The pixels, continuous coordinates.
    pixels: Vec<[f64; 2]>,
    /// The world points picked.
    points: Vec<DVec3>,
    /// The polyline's length, world units.
    length: f64,
    /// The grid's unit of length (`mm`, `µm`).
    unit: String,
}

/// The line's width, the discs' radius (pixels) and their colour (linear RGB: a warm
/// yellow that stands out from bone, skin and the usual colour maps).
const LINE_WIDTH: f64 = 2.5;
const DISC_RADIUS: f64 = 4.0;
const MARK_RGB: [f32; 3] = [1.0, 0.78, 0.05];

impl Drawn {
    /// Measures `args.measure` in `scene` (clip planes and mask included) on `volume`, a
    /// grid loaded as such (`loaded_grid`); `None` when no `--measure` was given.
    pub fn pick(
        args: &RenderArgs,
        volume: &Volume,
        scene: &Scene,
        loaded_grid: bool,
    ) -> Result<Option<Self>, CmdError> {
        if args.measure.is_empty() {
            return Ok(None);
        }
        let (Volume::Grid(grid), true) = (volume, loaded_grid) else {
            return Err("--measure picks on grids; this render draws a tetrahedral mesh".into());
        };
        if args.measure.len() < 2 {
            return Err("give at least two --measure X,Y to measure between".into());
        }
        let size = (scene.view.width, scene.view.height);
        let mut pixels = Vec::with_capacity(args.measure.len());
        let mut points = Vec::with_capacity(args.measure.len());
        for typed in &args.measure {
            let what = format!("--measure {typed}");
            let pixel = workbench::pixel("measure", typed)?;
            workbench::in_image(&what, pixel, size)?;
            let hit = pick(grid, scene, (pixel[0], pixel[1]), DEFAULT_PICK_OPACITY)?
                .ok_or_else(|| workbench::no_surface(&what, pixel))?;
            pixels.push(pixel);
            points.push(hit.world);
        }
        let length = polyline_length(&points);
        Ok(Some(Self {
            pixels,
            points,
            length,
            unit: grid.unit().to_string(),
        }))
    }

    /// The measurements a session holds (its polylines of world points, as the viewer
    /// picked them) seen in `scene`: each point projected to its pixel, so that a session
    /// rendered larger or zoomed draws its lines where the points are.
    pub fn of_session(lines: &[Vec<DVec3>], scene: &Scene, unit: &str) -> Vec<Self> {
        let (w, h) = (scene.view.width, scene.view.height);
        lines
            .iter()
            .filter(|points| !points.is_empty())
            .map(|points| Self {
                pixels: points
                    .iter()
                    .map(|&p| {
                        let (x, y, _) = scene.view.camera.project(p, w, h);
                        [x, y]
                    })
                    .collect(),
                points: points.clone(),
                length: polyline_length(points),
                unit: unit.to_string(),
            })
            .collect()
    }

    /// Draws the points and the polyline on `image`.
    pub fn draw(&self, image: &mut Image) {
        image.draw_marked_polyline(&self.pixels, LINE_WIDTH, DISC_RADIUS, MARK_RGB);
    }

    /// Prints the points and the length on stdout, as `volux measure` does.
    pub fn print(&self) -> std::io::Result<()> {
        print_text(&self.pixels, &self.points, self.length, &self.unit)
    }
}
