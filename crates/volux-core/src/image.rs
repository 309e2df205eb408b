//! The RGBA f32 linear framebuffer and its PNG output.
//!
//! Pixels hold premultiplied linear RGBA, the natural result of front-to-back compositing.
//! PNG output composites over a background (or keeps alpha), encodes to sRGB, and writes to a
//! temporary name that is renamed into place, so a failed write never leaves a partial file.
use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};

/// A framebuffer of premultiplied linear RGBA `f32` pixels, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    width: usize,
    height: usize,
    pixels: Vec<[f32; 4]>,
}

/// How PNG output treats alpha and bit depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PngOptions {
    /// Composite over this linear RGB colour; `None` keeps alpha (RGBA output).
    pub background: Option<[f32; 3]>,
    /// Write 16 bits per channel instead of 8.
    pub sixteen_bit: bool,
}

impl Default for PngOptions {
    fn default() -> Self {
        Self {
            background: Some([0.0; 3]),
            sixteen_bit: false,
        }
    }
}

/// Linear to sRGB transfer curve.
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB to linear transfer curve.
pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

impl Image {
    /// A transparent black image.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            pixels: vec![[0.0; 4]; width * height],
        }
    }
    /// Builds an image from pixels (row-major, top row first).
    pub fn from_pixels(width: usize, height: usize, pixels: Vec<[f32; 4]>) -> Result<Self> {
        if pixels.len() != width * height {
            return Err(Error::SizeMismatch {
                expected: (width * height) as u64,
                actual: pixels.len() as u64,
            });
        }
        Ok(Self {
            width,
            height,
            pixels,
        })
    }
    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }
    /// All pixels, row-major.
    pub fn pixels(&self) -> &[[f32; 4]] {
        &self.pixels
    }
    /// Mutable pixels, row-major.
    pub fn pixels_mut(&mut self) -> &mut [[f32; 4]] {
        &mut self.pixels
    }
    /// Pixel (x, y).
    pub fn get(&self, x: usize, y: usize) -> [f32; 4] {
        self.pixels[y * self.width + x]
    }
    /// Fraction of pixels with alpha above `threshold`.
    pub fn coverage(&self, threshold: f32) -> f64 {
        let n = self.pixels.iter().filter(|p| p[3] > threshold).count();
        n as f64 / self.pixels.len().max(1) as f64
    }

    /// Display values (sRGB, straight alpha, 0..1) of every pixel.
    fn display_values(&self, opts: &PngOptions) -> Vec<f32> {
        let ch = if opts.background.is_some() { 3 } else { 4 };
        let mut out = Vec::with_capacity(self.pixels.len() * ch);
        for p in &self.pixels {
            let a = p[3].clamp(0.0, 1.0);
            match opts.background {
                Some(bg) => {
                    for (c, b) in p.iter().zip(bg) {
                        out.push(linear_to_srgb(c + (1.0 - a) * b));
                    }
                }
                None => {
                    for c in &p[..3] {
                        let v = if a > 0.0 { c / a } else { 0.0 };
                        out.push(linear_to_srgb(v));
                    }
                    out.push(a);
                }
            }
        }
        out
    }

    /// Encodes the image as PNG bytes.
    pub fn encode_png(&self, opts: &PngOptions) -> Result<Vec<u8>> {
        let values = self.display_values(opts);
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, self.width as u32, self.height as u32);
            enc.set_color(if opts.background.is_some() {
                png::ColorType::Rgb
            } else {
                png::ColorType::Rgba
            });
            enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
            let data: Vec<u8> = if opts.sixteen_bit {
                enc.set_depth(png::BitDepth::Sixteen);
                values
                    .iter()
                    .flat_map(|v| ((v * 65535.0).round() as u16).to_be_bytes())
                    .collect()
            } else {
                enc.set_depth(png::BitDepth::Eight);
                values.iter().map(|v| (v * 255.0).round() as u8).collect()
            };
            let mut w = enc.write_header().map_err(|e| Error::Png(e.to_string()))?;
            w.write_image_data(&data)
                .map_err(|e| Error::Png(e.to_string()))?;
        }
        Ok(bytes)
    }

    /// Writes the image as PNG, through a temporary file renamed into place.
    pub fn write_png(&self, path: &Path, opts: &PngOptions) -> Result<()> {
        let bytes = self.encode_png(opts)?;
        write_atomically(path, &bytes)
    }
}

/// Writes `bytes` to `path` through `path.tmp-<pid>` and a rename, so readers never see a
/// partial file and a failure leaves nothing behind.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    Ok(result?)
}

/// The temporary name used while writing `path`.
pub fn temp_path(path: &Path) -> std::path::PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".tmp-{}", std::process::id()));
    path.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trip() {
        for i in 0..=10 {
            let x = i as f32 / 10.0;
            assert!((srgb_to_linear(linear_to_srgb(x)) - x).abs() < 1e-5);
        }
    }

    #[test]
    fn png_written_atomically() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        let mut img = Image::new(3, 2);
        img.pixels_mut()[0] = [0.5, 0.25, 0.0, 0.5];
        img.write_png(&p, &PngOptions::default()).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let bad = dir.path().join("missing-dir").join("b.png");
        assert!(img.write_png(&bad, &PngOptions::default()).is_err());
    }
}
