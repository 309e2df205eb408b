//! The RGBA f32 linear framebuffer, its PNG output and input, and image comparison.
//!
//! Pixels hold premultiplied linear RGBA, the natural result of front-to-back compositing.
//! PNG output composites over a background (or keeps alpha), encodes to sRGB, and writes to a
//! temporary name that is renamed into place, so a failed write never leaves a partial file.
//!
//! [`compare`] measures how far apart two images are (RMSE, largest and mean error per
//! channel, share of pixels over a threshold): `volux compare`, the accuracy and benchmark
//! commands and the tests all use it.
use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};

mod draw;

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

    /// The image over `background` as opaque 8-bit sRGB RGBA, as [`Image::encode_png`] writes
    /// it with that background: what a viewer puts on screen is what a screenshot saves.
    pub fn to_srgba8(&self, background: [f32; 3]) -> Vec<u8> {
        let opts = PngOptions {
            background: Some(background),
            sixteen_bit: false,
        };
        let rgb = self.display_values(&opts);
        let mut out = Vec::with_capacity(self.pixels.len() * 4);
        for p in rgb.chunks_exact(3) {
            out.extend(p.iter().map(|v| (v * 255.0).round() as u8));
            out.push(255);
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
    write_atomically_with(path, |f| f.write_all(bytes))
}

/// Like [`write_atomically`], for content produced by `write` (streamed, so large files need
/// no buffer): `write` fills the temporary file (and flushes what it wraps around it), which
/// is then synced and renamed to `path`. On any error the temporary file is removed.
pub fn write_atomically_with(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        write(&mut f)?;
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

/// How far apart two images are, per channel (every channel, alpha included, counts).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImageDiff {
    /// Root mean square error over all channels.
    pub rmse: f64,
    /// Largest absolute error of any channel.
    pub max_error: f64,
    /// Mean absolute error over all channels.
    pub mean_error: f64,
    /// Fraction (0..1) of pixels with some channel off by more than the threshold.
    pub fraction_over: f64,
    /// Fraction (0..1) of pixels off by more than the threshold, per channel R, G, B, A.
    pub fraction_over_per_channel: [f64; 4],
    /// Pixels compared.
    pub pixels: usize,
}

/// Compares two equally long lists of RGBA values; `threshold` is the per-channel error
/// above which a pixel counts as different.
pub fn compare(a: &[[f64; 4]], b: &[[f64; 4]], threshold: f64) -> ImageDiff {
    let (mut sq, mut sum, mut max) = (0.0, 0.0, 0.0f64);
    let (mut over, mut per) = (0usize, [0usize; 4]);
    for (p, q) in a.iter().zip(b) {
        let mut worst = 0.0f64;
        for c in 0..4 {
            let d = (p[c] - q[c]).abs();
            sq += d * d;
            sum += d;
            worst = worst.max(d);
            per[c] += usize::from(d > threshold);
        }
        max = max.max(worst);
        over += usize::from(worst > threshold);
    }
    let n = a.len().min(b.len());
    let m = n.max(1) as f64;
    ImageDiff {
        rmse: (sq / (4.0 * m)).sqrt(),
        max_error: max,
        mean_error: sum / (4.0 * m),
        fraction_over: over as f64 / m,
        fraction_over_per_channel: per.map(|k| k as f64 / m),
        pixels: n,
    }
}

impl Image {
    /// Compares with `other` (linear premultiplied values); errors when the sizes differ.
    pub fn compare(&self, other: &Image, threshold: f64) -> Result<ImageDiff> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(Error::SizeMismatch {
                expected: (self.width * self.height) as u64,
                actual: (other.width * other.height) as u64,
            });
        }
        Ok(compare(&self.values64(), &other.values64(), threshold))
    }

    /// The pixels in `f64`.
    pub fn values64(&self) -> Vec<[f64; 4]> {
        self.pixels.iter().map(|p| p.map(f64::from)).collect()
    }

    /// The absolute difference with `other`, times `scale`, clamped to 1, as an opaque
    /// image (RGB of the difference; pixels where only alpha differs show its difference in
    /// grey).
    pub fn difference(&self, other: &Image, scale: f32) -> Result<Image> {
        let values = difference_values(&self.values64(), &other.values64(), scale);
        Image::from_pixels(self.width, self.height, values)
    }
}

/// The absolute difference of two lists of RGBA values, times `scale`, clamped to 1, as
/// opaque pixels.
pub fn difference_values(a: &[[f64; 4]], b: &[[f64; 4]], scale: f32) -> Vec<[f32; 4]> {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            let d = |k: usize| ((p[k] - q[k]).abs() as f32 * scale).min(1.0);
            if d(0) + d(1) + d(2) == 0.0 {
                [d(3), d(3), d(3), 1.0]
            } else {
                [d(0), d(1), d(2), 1.0]
            }
        })
        .collect()
}

/// A decoded PNG: stored channel values scaled to `[0, 1]`, as RGBA (grey and RGB get alpha
/// 1).
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedPng {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major RGBA values in `[0, 1]` (as stored: sRGB for Volux's output).
    pub rgba: Vec<[f64; 4]>,
}

/// Reads a PNG of any colour type and bit depth (palettes expanded).
pub fn read_png(path: &Path) -> Result<DecodedPng> {
    let bad = |e: &dyn std::fmt::Display| {
        Error::Png(format!("{}: not a readable PNG ({e})", path.display()))
    };
    let file = std::fs::File::open(path)?;
    let mut dec = png::Decoder::new(std::io::BufReader::new(file));
    dec.set_transformations(png::Transformations::EXPAND);
    let mut reader = dec.read_info().map_err(|e| bad(&e))?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(|e| bad(&e))?;
    let ch = info.color_type.samples();
    let sixteen = info.bit_depth == png::BitDepth::Sixteen;
    let bytes = if sixteen { 2 } else { 1 };
    let n = (info.width as usize) * (info.height as usize);
    if info.buffer_size() < n * ch * bytes {
        return Err(bad(&"truncated image data"));
    }
    let value = |i: usize| -> f64 {
        if sixteen {
            f64::from(u16::from_be_bytes([buf[2 * i], buf[2 * i + 1]])) / 65535.0
        } else {
            f64::from(buf[i]) / 255.0
        }
    };
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
    Ok(DecodedPng {
        width: info.width as usize,
        height: info.height as usize,
        rgba,
    })
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

    #[test]
    fn streamed_writes_are_atomic() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.bin");
        write_atomically_with(&p, |f| f.write_all(b"abc")).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"abc");
        let e = write_atomically_with(&p, |f| {
            f.write_all(b"partial")?;
            Err(std::io::Error::other("disk full"))
        })
        .unwrap_err();
        assert!(e.to_string().contains("disk full"), "{e}");
        // The old file is kept and no temporary file is left.
        assert_eq!(std::fs::read(&p).unwrap(), b"abc");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn comparison_reports_the_errors_it_is_given() {
        let a = Image::from_pixels(2, 1, vec![[0.0, 0.0, 0.0, 0.0], [0.5, 0.5, 0.5, 1.0]]).unwrap();
        let mut b = a.clone();
        b.pixels_mut()[1][0] = 0.7;
        let d = a.compare(&b, 0.1).unwrap();
        assert!((d.max_error - 0.2).abs() < 1e-6);
        assert!((d.mean_error - 0.2 / 8.0).abs() < 1e-6);
        assert!((d.rmse - (0.04f64 / 8.0).sqrt()).abs() < 1e-6);
        assert_eq!(d.fraction_over, 0.5);
        assert_eq!(d.fraction_over_per_channel, [0.5, 0.0, 0.0, 0.0]);
        assert_eq!(a.compare(&a, 0.0).unwrap().max_error, 0.0);
        assert!(a.compare(&Image::new(1, 2), 0.1).is_err());
        let diff = a.difference(&b, 10.0).unwrap();
        assert_eq!(diff.get(1, 0), [1.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn png_round_trip_and_bad_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        let img = Image::from_pixels(2, 1, vec![[1.0, 0.0, 0.0, 1.0], [0.0; 4]]).unwrap();
        img.write_png(
            &p,
            &PngOptions {
                background: None,
                sixteen_bit: true,
            },
        )
        .unwrap();
        let d = read_png(&p).unwrap();
        assert_eq!((d.width, d.height), (2, 1));
        assert_eq!(d.rgba, vec![[1.0, 0.0, 0.0, 1.0], [0.0; 4]]);
        std::fs::write(&p, b"not a png").unwrap();
        assert!(read_png(&p).is_err());
        assert!(read_png(&dir.path().join("missing.png")).is_err());
    }
}
