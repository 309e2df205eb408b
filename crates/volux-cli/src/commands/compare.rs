//! `volux compare A.png B.png`: how far apart two images are (RMSE, largest error, share of
//! pixels over a threshold), with an optional difference image.
use std::path::Path;

use volux_core::image::PngOptions;
use volux_core::Image;

use super::CmdError;

/// Options of `volux compare`.
pub struct Args<'a> {
    pub a: &'a Path,
    pub b: &'a Path,
    pub threshold: f64,
    pub diff: Option<&'a Path>,
    pub scale: f32,
    pub json: bool,
}

/// A decoded PNG: channel values in `[0, 1]`, RGBA (grey and RGB get alpha 1).
struct Decoded {
    width: usize,
    height: usize,
    rgba: Vec<[f64; 4]>,
}

fn decode(path: &Path) -> Result<Decoded, CmdError> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut dec = png::Decoder::new(std::io::BufReader::new(file));
    dec.set_transformations(png::Transformations::EXPAND);
    let mut reader = dec
        .read_info()
        .map_err(|e| format!("{}: not a readable PNG ({e})", path.display()))?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("{}: not a readable PNG ({e})", path.display()))?;
    let ch = info.color_type.samples();
    let sixteen = info.bit_depth == png::BitDepth::Sixteen;
    let bytes = if sixteen { 2 } else { 1 };
    let max = if sixteen { 65535.0 } else { 255.0 };
    let value = |i: usize| -> f64 {
        if sixteen {
            f64::from(u16::from_be_bytes([buf[2 * i], buf[2 * i + 1]])) / max
        } else {
            f64::from(buf[i]) / max
        }
    };
    let n = (info.width as usize) * (info.height as usize);
    if info.buffer_size() < n * ch * bytes {
        return Err(format!("{}: truncated image data", path.display()).into());
    }
    let rgba = (0..n)
        .map(|p| {
            let v = |c: usize| value(p * ch + c);
            match ch {
                1 => [v(0), v(0), v(0), 1.0],
                2 => [v(0), v(0), v(0), v(1)],
                3 => [v(0), v(1), v(2), 1.0],
                _ => [v(0), v(1), v(2), v(3)],
            }
        })
        .collect();
    Ok(Decoded {
        width: info.width as usize,
        height: info.height as usize,
        rgba,
    })
}

/// The comparison of two images.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Comparison {
    pub rmse: f64,
    pub max_error: f64,
    pub mean_error: f64,
    pub pct_over: f64,
    pub pixels: usize,
}

fn compare(a: &Decoded, b: &Decoded, threshold: f64) -> Comparison {
    let (mut sq, mut sum, mut max, mut over) = (0.0, 0.0, 0.0f64, 0usize);
    for (p, q) in a.rgba.iter().zip(&b.rgba) {
        let mut worst = 0.0f64;
        for c in 0..4 {
            let d = (p[c] - q[c]).abs();
            sq += d * d;
            sum += d;
            worst = worst.max(d);
        }
        max = max.max(worst);
        over += usize::from(worst > threshold);
    }
    let n = a.rgba.len().max(1);
    Comparison {
        rmse: (sq / (4 * n) as f64).sqrt(),
        max_error: max,
        mean_error: sum / (4 * n) as f64,
        pct_over: 100.0 * over as f64 / n as f64,
        pixels: a.rgba.len(),
    }
}

pub fn run(args: &Args<'_>) -> Result<(), CmdError> {
    if !(args.threshold.is_finite() && args.threshold >= 0.0) {
        return Err(format!(
            "--threshold {} must be a non-negative number",
            args.threshold
        )
        .into());
    }
    let (a, b) = (decode(args.a)?, decode(args.b)?);
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "the images differ in size: {}x{} and {}x{}",
            a.width, a.height, b.width, b.height
        )
        .into());
    }
    let c = compare(&a, &b, args.threshold);
    if let Some(path) = args.diff {
        let pixels = a
            .rgba
            .iter()
            .zip(&b.rgba)
            .map(|(p, q)| {
                let d = |k: usize| ((p[k] - q[k]).abs() as f32 * args.scale).min(1.0);
                [d(0), d(1), d(2), 1.0]
            })
            .collect();
        Image::from_pixels(a.width, a.height, pixels)?
            .write_png(path, &PngOptions::default())
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "width": a.width, "height": a.height, "rmse": c.rmse, "max_error": c.max_error,
                "mean_error": c.mean_error, "threshold": args.threshold, "pct_over": c.pct_over,
            })
        );
    } else {
        println!(
            "{}x{}: RMSE {:.3e}, max error {:.3e}, mean error {:.3e}, {:.2} % of pixels over {}",
            a.width, a.height, c.rmse, c.max_error, c.mean_error, c.pct_over, args.threshold
        );
    }
    Ok(())
}
