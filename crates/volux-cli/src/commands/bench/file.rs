//! `volux bench FILE -- [render options]`: warm frames of any file with any transfer
//! function and method. The render options are parsed as `volux render` parses them, the
//! scene is built the same way, and a turntable of one first frame (which builds the caches)
//! and `--frames` warm frames is rendered with one renderer (`volux render --orbit`'s loop).
use std::ffi::OsString;
use std::path::Path;

use serde_json::json;
use volux_io::Dataset;
use volux_render::engine::{FrameStats, MethodStats};

use super::super::common::{self, CmdError};
use super::super::orbit;
use crate::cli::Command;
use crate::settings::RenderPlan;

/// Bench options that select suite cases, refused with a FILE.
const SUITE_ONLY: [&str; 4] = ["quick", "suite", "only", "grid-size"];

/// Render options the bench sets itself.
const SET_BY_BENCH: [&str; 4] = ["orbit", "no-write", "session", "output"];

/// Times the first frame and `frames` warm frames of `file` rendered with `render`.
pub fn run(
    file: &Path,
    render: &[String],
    frames: usize,
    as_json: bool,
    given: &[String],
) -> Result<(), CmdError> {
    if let Some(o) = SUITE_ONLY.iter().find(|o| given.iter().any(|g| g == *o)) {
        return Err(format!(
            "--{o} selects suite cases; with a FILE the render options after -- set the case"
        )
        .into());
    }
    if frames == 0 {
        return Err("--frames must be at least 1".into());
    }
    let mut argv: Vec<OsString> = vec!["volux".into(), "render".into(), file.into()];
    argv.extend(render.iter().map(OsString::from));
    let cli = crate::parse_from(argv).map_err(|e| {
        format!(
            "the render options after --: {}",
            crate::one_line(&e.to_string())
        )
    })?;
    let Command::Render(args) = cli.command else {
        unreachable!("parsed as `volux render`")
    };
    if let Some(o) = SET_BY_BENCH
        .iter()
        .find(|o| args.given.iter().any(|g| g == *o))
    {
        return Err(
            format!("--{o} is set by the bench (it renders a turntable, writing nothing)").into(),
        );
    }
    let plan = RenderPlan::new(&args)?;
    // A store with --lod (or over the budget) is timed out of core, as `volux render` draws it.
    let (volume, loaded_grid) = match crate::commands::bricked::volume(file, &args)? {
        Some(v) => (v, false),
        None => {
            let (data, _) = common::load(file, &args.load, false)?;
            let loaded_grid = matches!(data, Dataset::Grid(_));
            (crate::settings::volume(data, &args)?, loaded_grid)
        }
    };
    let scene = plan.scene(&args, &volume, loaded_grid)?;
    let mut stats: Vec<FrameStats> = Vec::with_capacity(frames + 1);
    orbit::frames(
        frames + 1,
        360.0 / frames as f64,
        &volume,
        &scene,
        |_, _, f| {
            stats.push(f.stats.clone());
            Ok(())
        },
    )?;
    let first = stats[0].ms;
    let mut warm: Vec<f64> = stats[1..].iter().map(|s| s.ms).collect();
    warm.sort_by(f64::total_cmp);
    let median = warm[warm.len() / 2];
    let (unit, per_s) = rate(&stats[1..]);
    let (w, h) = (scene.view.width, scene.view.height);
    let method = scene.method.resolve(&volume)?.name();
    if as_json {
        let v = json!({
            "file": file.display().to_string(), "method": method, "width": w, "height": h,
            "first_ms": first, "warm_median_ms": median, "warm_min_ms": warm[0],
            "warm_max_ms": warm[warm.len() - 1], "warm_frames": warm.len(),
            "rate_unit": unit, "rate_per_s": per_s,
            "threads": rayon::current_num_threads(),
        });
        outln!("{v}")?;
    } else {
        outln!(
            "{} ({method}, {w}x{h}): first frame {first:.1} ms; warm frames median {median:.1} ms \
             (min {:.1}, max {:.1}, {} frames); {:.2} M {unit}/s",
            file.display(),
            warm[0],
            warm[warm.len() - 1],
            warm.len(),
            per_s / 1e6
        )?;
    }
    Ok(())
}

/// The method's work rate over `frames`: samples/s (grid ray casting), tets/s (PT),
/// segments/s (tet ray casting).
fn rate(frames: &[FrameStats]) -> (&'static str, f64) {
    let seconds: f64 = frames.iter().map(|s| s.ms * 1e-3).sum();
    let (unit, work) = frames
        .iter()
        .fold(("pixels", 0.0), |(_, n), s| match &s.method {
            MethodStats::GridRaycast(r) => ("samples", n + r.samples as f64),
            MethodStats::ProjectedTetrahedra(p) => ("tets", n + p.tets as f64),
            MethodStats::TetRaycast(t) => ("segments", n + t.segments as f64),
            _ => ("pixels", n + s.pixels as f64),
        });
    (unit, work / seconds.max(1e-12))
}
