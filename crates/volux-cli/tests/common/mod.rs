//! Helpers shared by the end-to-end tests of the `volux` binary.
#![allow(dead_code)] // each test crate uses its own subset

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `volux` binary with `args` in `dir`.
pub fn volux(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_volux"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the volux binary runs")
}

/// The pixels of an 8-bit PNG, one slice of channel values per pixel, and its size.
pub fn png_pixels(path: &Path) -> (u32, u32, Vec<Vec<u8>>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let ch = info.color_type.samples();
    let px = buf[..info.buffer_size()]
        .chunks(ch)
        .map(<[u8]>::to_vec)
        .collect();
    (info.width, info.height, px)
}

/// The fraction of pixels that differ from the top-left one (the background) by more than 8
/// in some channel.
pub fn coverage(px: &[Vec<u8>]) -> f64 {
    let bg = &px[0];
    px.iter()
        .filter(|p| p.iter().zip(bg).any(|(a, b)| a.abs_diff(*b) > 8))
        .count() as f64
        / px.len() as f64
}

/// Compares two 8-bit PNGs of the same size: mean absolute difference per channel at most
/// 1.0 (of 255) and at most 1 % of the pixels with a channel off by more than 16; the
/// baseline must show something (over 100 pixels brighter than 8). Returns the figures, or
/// what failed.
pub fn png_close(got: &Path, want: &Path) -> Result<String, String> {
    let (w, h, a) = png_pixels(got);
    let (gw, gh, b) = png_pixels(want);
    if (w, h) != (gw, gh) {
        return Err(format!("size {w}x{h}, baseline {gw}x{gh}"));
    }
    let channels = a.iter().zip(&b).flat_map(|(p, q)| p.iter().zip(q));
    let (sum, count) = channels.fold((0.0, 0usize), |(s, n), (x, y)| {
        (s + f64::from(x.abs_diff(*y)), n + 1)
    });
    let mean = sum / count.max(1) as f64;
    let far = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 16))
        .count() as f64
        / f64::from(w * h);
    let lit = b
        .iter()
        .filter(|p| p.iter().take(3).any(|&c| c > 8))
        .count();
    let figures = format!(
        "mean |diff| {mean:.3}/255, {:.2} % pixels off by > 16, {lit} lit pixels in the baseline",
        far * 100.0
    );
    if lit <= 100 {
        return Err(format!("the baseline shows nothing: {figures}"));
    }
    if mean > 1.0 || far > 0.01 {
        return Err(figures);
    }
    Ok(figures)
}
