//! `volux compare A.png B.png`: how far apart two images are (RMSE, largest error, share of
//! pixels over a threshold), with an optional difference image.
use std::path::Path;

use volux_core::heatmap::{heat_map, heat_map_legend_text};
use volux_core::image::{compare, read_png, PngOptions};

use super::common::CmdError;

/// Options of `volux compare`.
pub struct Args<'a> {
    pub a: &'a Path,
    pub b: &'a Path,
    pub threshold: f64,
    pub diff: Option<&'a Path>,
    pub diff_max: Option<f32>,
    pub json: bool,
}

pub fn run(args: &Args<'_>) -> Result<(), CmdError> {
    if !(args.threshold.is_finite() && args.threshold >= 0.0) {
        return Err(format!(
            "--threshold {} must be a non-negative number",
            args.threshold
        )
        .into());
    }
    let (a, b) = (read_png(args.a)?, read_png(args.b)?);
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "the images differ in size: {}x{} and {}x{}",
            a.width, a.height, b.width, b.height
        )
        .into());
    }
    let c = compare(&a.rgba, &b.rgba, args.threshold);
    if let Some(path) = args.diff {
        crate::settings::png_path(path, "--diff")?;
        write_diff(&a.rgba, &b.rgba, (a.width, a.height), args.diff_max, path)?;
    }
    if args.json {
        outln!(
            "{}",
            serde_json::json!({
                "width": a.width, "height": a.height, "rmse": c.rmse, "max_error": c.max_error,
                "mean_error": c.mean_error, "threshold": args.threshold,
                "pct_over": 100.0 * c.fraction_over,
            })
        )?;
    } else {
        outln!(
            "{}x{}: RMSE {:.3e}, max error {:.3e}, mean error {:.3e}, {:.2} % of pixels over {}",
            a.width,
            a.height,
            c.rmse,
            c.max_error,
            c.mean_error,
            100.0 * c.fraction_over,
            crate::numbers::human(args.threshold)
        )?;
    }
    Ok(())
}

/// Writes the per-pixel largest channel difference as a heat map with its legend.
fn write_diff(
    a: &[[f64; 4]],
    b: &[[f64; 4]],
    (w, h): (usize, usize),
    max: Option<f32>,
    path: &Path,
) -> Result<(), CmdError> {
    let diffs: Vec<f32> = a
        .iter()
        .zip(b)
        .map(|(p, q)| (0..4).map(|c| (p[c] - q[c]).abs()).fold(0.0, f64::max) as f32)
        .collect();
    let largest = diffs.iter().copied().fold(0.0f32, f32::max);
    let max = match max {
        Some(m) if m.is_finite() && m > 0.0 => m,
        Some(m) => return Err(format!("--diff-max {m} must be a positive number").into()),
        None => largest.max(1.0 / 255.0),
    };
    heat_map(&diffs, w, h, max)?
        .write_png(path, &PngOptions::default())
        .map_err(|e| format!("{}: {e}", path.display()))?;
    eprintln!(
        "wrote {} (largest channel difference per pixel; {})",
        path.display(),
        heat_map_legend_text(max)
    );
    Ok(())
}
