//! `volux bench`: speed figures of every renderer, through the engine API.
//!
//! - [`grid`]: ms/frame and samples/s of grid ray casting per integrator;
//! - [`pt`]: tets/s of Projected Tetrahedra per colour mode, and its accuracy against the
//!   brute-force reference;
//! - [`tetray`]: ms/frame of tetrahedral ray casting;
//! - [`gpu`](mod@gpu): the GPU backend's grid ray casting, upload time and device memory;
//! - [`targets`]: the grid speed targets, cases in turn, fastest frame per case;
//! - [`file`](mod@file): warm frames of any file with any render options.
//!
//! Each case renders through a [`Renderer`](volux_render::engine::Renderer) kept for its volume, as a viewer would, and times
//! [`FrameStats::ms`](volux_render::engine::FrameStats::ms), the wall time of the render call.
use super::common::CmdError;
use crate::cli::Suite;

mod common;
pub mod file;
mod gpu;
mod grid;
mod pt;
mod sculpt;
mod targets;
mod tetray;
mod voi;

/// Refuses the options that would change nothing: `--frames` with `--quick` (one frame per
/// case), `--quick` with the targets (they have no quick form), `--grid-size` with the mesh
/// suites, and fewer than one frame.
pub fn check_options(
    quick: bool,
    frames: usize,
    suite: Suite,
    given: &[String],
) -> Result<(), CmdError> {
    let given = |name: &str| given.iter().any(|g| g == name);
    if frames == 0 {
        return Err("--frames 0: each case needs at least one frame".into());
    }
    if quick && given("frames") {
        return Err("--quick renders one frame per case; drop --quick or --frames".into());
    }
    if quick && suite == Suite::Voi {
        return Err(
            "--quick does not apply to --suite voi: its cuts and frames have no quick form".into(),
        );
    }
    if quick && suite == Suite::Targets {
        return Err(
            "--quick does not apply to --suite targets: the targets are measured at \
                    their own sizes (use --frames to shorten them)"
                .into(),
        );
    }
    if given("grid-size") && matches!(suite, Suite::Pt | Suite::Tetray) {
        return Err(
            "--grid-size sizes the synthetic grids of the grid and targets suites; \
                    the mesh suites have none"
                .into(),
        );
    }
    Ok(())
}

/// Runs `suite`; prints a table per suite, or one JSON list.
pub fn run(
    quick: bool,
    frames: usize,
    n: usize,
    as_json: bool,
    suite: Suite,
    only: Option<&str>,
) -> Result<(), CmdError> {
    if only.is_some()
        && !matches!(
            suite,
            Suite::Grid | Suite::All | Suite::Targets | Suite::Gpu
        )
    {
        return Err(
            "--only selects cases of the grid suite or datasets of the targets and gpu suites"
                .into(),
        );
    }
    let rows = match suite {
        Suite::Targets => targets::run(n, frames, as_json, only)?,
        Suite::Grid => grid::run(quick, frames, n, as_json, only)?,
        Suite::Pt => pt::run(quick, frames, as_json)?,
        Suite::Tetray => tetray::run(quick, frames, as_json)?,
        Suite::Voi => voi::run(frames, n, as_json)?,
        Suite::Gpu => gpu::run(quick, frames, n, as_json, only)?,
        Suite::All => {
            let mut rows = grid::run(quick, frames, n, as_json, only)?;
            rows.extend(pt::run(quick, frames, as_json)?);
            rows.extend(tetray::run(quick, frames, as_json)?);
            rows
        }
    };
    if as_json {
        outln!("{}", serde_json::Value::Array(rows))?;
    }
    Ok(())
}
