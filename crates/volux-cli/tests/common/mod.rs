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
