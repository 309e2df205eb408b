//! `volux measure`: distance on the visible surface (seed `004` sec. 6.2). Each `--point`
//! pixel is picked where the opacity along its ray reaches 0.5 (after the clip planes and
//! the mask), and the polyline through the points is measured in world units: millimetres
//! from the data's spacing, not texture space (the seed's sec. 4.5.1 flaw).
use glam::DVec3;
use serde_json::json;
use volux_render::sculpt::polyline_length;

use super::common::CmdError;
use super::workbench::{self, Workbench};
use crate::cli::MeasureArgs;

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
    let bench = Workbench::open(&args.view, given, show)?;
    let mut points = Vec::with_capacity(pixels.len());
    for (pixel, typed) in pixels.iter().zip(&args.points) {
        let what = format!("--point {typed}");
        workbench::in_image(&what, *pixel, bench.size())?;
        points.push(bench.pick(*pixel, &what)?.world);
    }
    let length = polyline_length(&points);
    if args.json {
        let xyz: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
        println!("{}", json!({ "points": xyz, "length_mm": length }));
    } else {
        print_text(&pixels, &points, length);
    }
    Ok(())
}

/// The points and the length as text.
fn print_text(pixels: &[[f64; 2]], points: &[DVec3], length: f64) {
    for (n, ([x, y], p)) in pixels.iter().zip(points).enumerate() {
        println!(
            "point {} at pixel ({x}, {y}): ({:.3}, {:.3}, {:.3})",
            n + 1,
            p.x,
            p.y,
            p.z
        );
    }
    println!(
        "length: {length:.3} mm ({} segment{})",
        points.len() - 1,
        if points.len() == 2 { "" } else { "s" }
    );
}
