//! `volux compare A.png B.png`: how far apart two images are (RMSE, largest error, share of
//! pixels over a threshold), with an optional difference image.
use std::path::Path;

use volux_core::image::{compare, difference_values, read_png, PngOptions};
use volux_core::Image;

use super::common::CmdError;

/// Options of `volux compare`.
pub struct Args<'a> {
    pub a: &'a Path,
    pub b: &'a Path,
    pub threshold: f64,
    pub diff: Option<&'a Path>,
    pub scale: f32,
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
        let pixels = difference_values(&a.rgba, &b.rgba, args.scale);
        Image::from_pixels(a.width, a.height, pixels)?
            .write_png(path, &PngOptions::default())
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "width": a.width, "height": a.height, "rmse": c.rmse, "max_error": c.max_error,
                "mean_error": c.mean_error, "threshold": args.threshold,
                "pct_over": 100.0 * c.fraction_over,
            })
        );
    } else {
        println!(
            "{}x{}: RMSE {:.3e}, max error {:.3e}, mean error {:.3e}, {:.2} % of pixels over {}",
            a.width,
            a.height,
            c.rmse,
            c.max_error,
            c.mean_error,
            100.0 * c.fraction_over,
            args.threshold
        );
    }
    Ok(())
}
