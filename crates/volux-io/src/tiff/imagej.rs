//! ImageJ TIFF metadata: the `ImageDescription` ImageJ writes (`ij.io.FileSaver`'s
//! `getDescriptionString`, also written by `tifffile` with `imagej=True`):
//!
//! ```text
//! ImageJ=1.54f
//! images=30        (pages in the file)
//! channels=2       (C, default 1)
//! slices=5         (Z)
//! frames=3         (T, default 1)
//! hyperstack=true
//! unit=micron      (also `\u00B5m`, `um`, `nm`, `mm`, ...)
//! spacing=0.5      (z spacing, in `unit`)
//! finterval=2.5    (time between frames, in `tunit`, default seconds)
//! ```
//!
//! X and Y spacing are `1 / XResolution` and `1 / YResolution` (pixels per `unit`). ImageJ
//! stores hyperstack pages in CZT order: channel fastest, then z, then time, so the page of
//! (c, z, t) is `c + C * (z + Z * t)`.
use std::path::Path;

use volux_core::volume_axes::{AxisKind, ExtraAxis};

use crate::error::{ErrorKind, ReadError, Result};

use super::layout::{choose, micrometres_per, positive, Layout};

/// The fields of an ImageJ description that Volux uses.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImageJ {
    /// `images=`: pages in the file.
    pub images: Option<usize>,
    /// `channels=`.
    pub channels: Option<usize>,
    /// `slices=`.
    pub slices: Option<usize>,
    /// `frames=`.
    pub frames: Option<usize>,
    /// `unit=`.
    pub unit: Option<String>,
    /// `spacing=` (z, in `unit`).
    pub spacing: Option<f64>,
    /// `finterval=` (time between frames, in `tunit`).
    pub finterval: Option<f64>,
    /// `tunit=` (default `sec`).
    pub tunit: Option<String>,
}

/// Whether `desc` is an ImageJ description (it starts with `ImageJ=`).
pub fn is_imagej(desc: &str) -> bool {
    desc.trim_start().starts_with("ImageJ=")
}

/// Parses an ImageJ description; unknown keys are ignored, a count that is not a number is
/// a header error.
pub fn parse(path: &Path, desc: &str) -> Result<ImageJ> {
    let mut ij = ImageJ::default();
    let count = |k: &str, v: &str| {
        v.parse::<usize>().map_err(|_| {
            ReadError::new(
                path,
                ErrorKind::Header(format!("ImageJ description: {k}={v} is not a count")),
            )
        })
    };
    for line in desc.lines() {
        let Some((k, v)) = line.split_once('=') else {
            continue;
        };
        let (k, v) = (k.trim(), v.trim());
        match k {
            "images" => ij.images = Some(count(k, v)?),
            "channels" => ij.channels = Some(count(k, v)?),
            "slices" => ij.slices = Some(count(k, v)?),
            "frames" => ij.frames = Some(count(k, v)?),
            "unit" => ij.unit = Some(v.to_string()),
            "tunit" => ij.tunit = Some(v.to_string()),
            "finterval" => ij.finterval = v.parse::<f64>().ok().filter(|f| f.is_finite()),
            "spacing" => {
                ij.spacing = Some(v.parse::<f64>().map_err(|_| {
                    ReadError::new(
                        path,
                        ErrorKind::Header(format!(
                            "ImageJ description: spacing={v} is not a number"
                        )),
                    )
                })?)
            }
            _ => {}
        }
    }
    Ok(ij)
}

impl ImageJ {
    /// (C, Z, T): channels and frames default to 1, slices to the pages left.
    pub fn czt(&self, pages: usize) -> (usize, usize, usize) {
        let c = self.channels.unwrap_or(1).max(1);
        let t = self.frames.unwrap_or(1).max(1);
        let images = self.images.unwrap_or(pages);
        let z = self.slices.unwrap_or(images / (c * t)).max(1);
        (c, z, t)
    }

    /// The pages of channel `channel` and timepoint `timepoint` and the spacing, for a file
    /// of `pages` pages whose first page has resolution `res` (pixels per unit, x and y).
    pub fn layout(
        &self,
        path: &Path,
        pages: usize,
        channel: usize,
        timepoint: usize,
        res: [Option<f64>; 2],
    ) -> Result<Layout> {
        let (c, z, t) = self.czt(pages);
        let channel = choose(path, "channel", channel, c)?;
        let timepoint = choose(path, "timepoint", timepoint, t)?;
        let needed = c.saturating_mul(z).saturating_mul(t);
        if needed > pages {
            return Err(ReadError::new(
                path,
                ErrorKind::Invalid(format!(
                    "the ImageJ description declares {c} channel(s) x {z} slice(s) x {t} \
                     frame(s) = {needed} images, but the file has {pages} pages (ImageJ's \
                     contiguous layout of stacks over 4 GiB is not read)"
                )),
            ));
        }
        let ifds = (0..z).map(|k| channel + c * (k + z * timepoint)).collect();
        let mut notes = Vec::new();
        let mut axes = Vec::new();
        if c > 1 || t > 1 {
            notes.push(format!(
                "ImageJ hyperstack of {c} channel(s), {z} slice(s), {t} frame(s) (CZT order): \
                 channel {channel}, timepoint {timepoint} read"
            ));
        }
        if c > 1 {
            axes.push(ExtraAxis::new(AxisKind::Channel, c, Some(channel)));
        }
        if t > 1 {
            let mut time = ExtraAxis::new(AxisKind::Time, t, Some(timepoint));
            if let Some(f) = self.finterval.filter(|&f| f > 0.0) {
                let unit = self.tunit.as_deref().unwrap_or("sec");
                time = time.with_meaning(format!("step {f} {unit}"));
            }
            axes.push(time);
        }
        let (spacing, spacing_note) = self.spacing(path, res)?;
        Ok(Layout {
            ifds,
            spacing,
            spacing_note,
            flavour: "ImageJ",
            notes,
            axes,
        })
    }

    /// Spacing from the resolution tags and `spacing=`, converted to micrometres when `unit=`
    /// is a length, and its note.
    pub fn spacing(&self, path: &Path, res: [Option<f64>; 2]) -> Result<([f64; 3], String)> {
        let xy = |r: Option<f64>, what| -> Result<Option<f64>> {
            r.map(|r| positive(path, what, r).map(|r| 1.0 / r))
                .transpose()
        };
        let x = xy(res[0], "XResolution")?;
        let y = xy(res[1], "YResolution")?;
        let z = self
            .spacing
            .map(|s| positive(path, "ImageJ spacing", s))
            .transpose()?;
        if x.is_none() && y.is_none() && z.is_none() {
            return Ok((
                [1.0; 3],
                "no spacing information (ImageJ description without spacing, no resolution \
                 tags): spacing 1"
                    .into(),
            ));
        }
        let raw = [x.unwrap_or(1.0), y.or(x).unwrap_or(1.0), z.unwrap_or(1.0)];
        let missing_z = if z.is_none() {
            " (no spacing= for z: 1)"
        } else {
            ""
        };
        let unit = self.unit.as_deref().unwrap_or("");
        Ok(match micrometres_per(unit) {
            Some(f) => (
                raw.map(|v| v * f),
                format!(
                    "spacing in micrometres, from the ImageJ description (unit={unit}) and \
                     the resolution tags{missing_z}"
                ),
            ),
            None => (
                raw,
                format!(
                    "spacing in ImageJ's unit '{}' (not a length Volux converts), from the \
                     ImageJ description and the resolution tags{missing_z}",
                    if unit.is_empty() { "none" } else { unit }
                ),
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hyperstack_pages_are_czt() {
        let p = Path::new("x.tif");
        let ij = parse(
            p,
            "ImageJ=1.11a\nimages=30\nchannels=2\nslices=5\nframes=3\nhyperstack=true\nunit=micron\nspacing=0.5\n",
        )
        .unwrap();
        assert_eq!(ij.czt(30), (2, 5, 3));
        let l = ij.layout(p, 30, 1, 2, [Some(4.0), Some(2.0)]).unwrap();
        assert_eq!(l.ifds, vec![21, 23, 25, 27, 29]);
        assert_eq!(l.spacing, [0.25, 0.5, 0.5]);
        assert_eq!(l.axes.len(), 2);
        assert_eq!(l.axes[0].kind, AxisKind::Channel);
        assert_eq!((l.axes[1].len, l.axes[1].chosen), (3, Some(2)));
        let e = ij.layout(p, 30, 2, 0, [None, None]).unwrap_err();
        assert!(
            matches!(
                e.kind,
                ErrorKind::Data(volux_core::Error::NoSuchVolume {
                    option: "channel",
                    index: 2,
                    len: 2
                })
            ),
            "{e}"
        );
    }

    #[test]
    fn escaped_micro_sign_and_nm() {
        assert_eq!(micrometres_per("\\u00B5m"), Some(1.0));
        assert_eq!(micrometres_per("nm"), Some(1e-3));
        assert_eq!(micrometres_per("pixel"), None);
    }
}
