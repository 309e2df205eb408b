//! `volux sculpt`: the eraser (seed `004` sec. 4.4) and the digger (sec. 4.5) applied in
//! command-line order to a grid in the view of `volux render`'s options, the mask written as
//! NRRD `u8` (1 kept, 0 removed) and, optionally, the steps saved in a session.
use std::time::Instant;

use volux_app::session::Session;

use super::common::CmdError;
use super::workbench::{self, Workbench};
use crate::cli::{SculptArgs, ToolKind};

/// One tool of the command line, parsed.
enum Tool {
    /// A disc swept through `points` (one point: a disc).
    Erase { points: Vec<[f64; 2]>, radius: f64 },
    /// A dig at a pixel.
    Dig { pixel: [f64; 2], radius: f64 },
}

/// Runs `volux sculpt`.
pub fn run(args: &SculptArgs, given: &[String], show: bool) -> Result<(), CmdError> {
    workbench::nrrd_path(&args.output, "--output")?;
    if args.session_out.is_some() && args.view.view_args.mask.is_some() {
        return Err(
            "--session-out saves the sculpt steps, not the starting --mask; \
                    give one or the other"
                .into(),
        );
    }
    let tools = tools(args)?;
    let mut bench = workbench::open(&args.view, given, show)?;
    for (tool, what) in &tools {
        for pixel in tool_pixels(tool) {
            workbench::in_image(what, pixel, bench.size())?;
        }
    }
    for (tool, what) in &tools {
        apply(&mut bench, tool, what)?;
    }
    let mask = bench.sculpt.mask().clone();
    workbench::write_u8_like(&bench.grid, mask.to_values(), &args.output)?;
    eprintln!(
        "wrote {} ({} of {} voxels removed)",
        args.output.display(),
        mask.removed_count(),
        bench.grid.len()
    );
    if let Some(path) = &args.session_out {
        let dataset = workbench::dataset_ref(&args.view);
        let session =
            Session::new(dataset, &bench.scene, Some([0.0; 3])).with_sculpt(&bench.sculpt);
        session.save(path)?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// The pixels a tool names.
fn tool_pixels(tool: &Tool) -> Vec<[f64; 2]> {
    match tool {
        Tool::Erase { points, .. } => points.clone(),
        Tool::Dig { pixel, .. } => vec![*pixel],
    }
}

/// The tools in command-line order, each with its option as typed (for messages).
fn tools(args: &SculptArgs) -> Result<Vec<(Tool, String)>, CmdError> {
    if args.order.is_empty() {
        return Err(
            "give at least one tool: --erase X,Y,R, --stroke X1,Y1,...,R or --dig X,Y,R".into(),
        );
    }
    args.order
        .iter()
        .map(|&(kind, n)| {
            Ok(match kind {
                ToolKind::Erase => {
                    let (pixel, radius) = workbench::pixel_radius("erase", &args.erase[n])?;
                    let points = vec![pixel];
                    (
                        Tool::Erase { points, radius },
                        format!("--erase {}", args.erase[n]),
                    )
                }
                ToolKind::Stroke => (
                    stroke(&args.stroke[n])?,
                    format!("--stroke {}", args.stroke[n]),
                ),
                ToolKind::Dig => {
                    let (pixel, radius) = workbench::pixel_radius("dig", &args.dig[n])?;
                    (
                        Tool::Dig { pixel, radius },
                        format!("--dig {}", args.dig[n]),
                    )
                }
            })
        })
        .collect()
}

/// Parses `--stroke X1,Y1,X2,Y2,...,R`.
fn stroke(s: &str) -> Result<Tool, CmdError> {
    let form = "X1,Y1,X2,Y2,...,R (pixels: points, then the radius R > 0)";
    let v = workbench::numbers("stroke", s, form)?;
    match v.split_last() {
        Some((&radius, xy)) if radius > 0.0 && !xy.is_empty() && xy.len() % 2 == 0 => {
            let points = xy.chunks(2).map(|p| [p[0], p[1]]).collect();
            Ok(Tool::Erase { points, radius })
        }
        _ => Err(format!("--stroke '{s}': expected {form}").into()),
    }
}

/// Applies one tool and prints what it removed.
fn apply(bench: &mut Workbench, tool: &Tool, what: &str) -> Result<(), CmdError> {
    let t = Instant::now();
    let removed = match tool {
        Tool::Erase { points, radius } => bench.erase(points.clone(), *radius)?,
        Tool::Dig { pixel, radius } => bench
            .dig(*pixel, *radius)?
            .ok_or_else(|| workbench::no_surface(what, *pixel))?,
    };
    let ms = t.elapsed().as_secs_f64() * 1e3;
    eprintln!("{what}: {removed} voxels removed, {ms:.1} ms");
    Ok(())
}
