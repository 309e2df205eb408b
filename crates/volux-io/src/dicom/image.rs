//! From the stored samples of the chosen frames, in stack order, to the grid: the value model
//! of the image (monochrome values through the Modality LUT and DoseGridScaling, colour,
//! palette colour), the geometry of the ordered stack, and the notes and extra axes that say
//! what was read.
use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

use volux_core::volume_axes::{AxisKind, ExtraAxis};
use volux_core::Grid;

use super::attrs::{ImageInfo, Obj};
use super::color::{self, Colour};
use super::geometry::Stack;
use super::lut::{self, Lut};
use super::pixels::Fmt;
use super::ts::is_native;
use super::values::{self, FrameValues, Modality};
use crate::error::{ErrorKind, ReadError, Result};

/// How stored samples become the grid's values.
pub(super) enum Model {
    /// One sample a pixel, each frame through its Modality LUT transformation.
    Mono(Vec<FrameValues>),
    /// Three samples a pixel, interleaved RGB.
    Color,
    /// PALETTE COLOR: the stored values index these red, green and blue LUTs.
    Palette(Box<[Lut; 3]>),
}

/// The value model of an image from its data set `obj`, for frames with these `rescale`
/// values (a Modality LUT Sequence, which the frames share, takes their place).
pub(super) fn model(
    path: &Path,
    obj: &Obj,
    info: &ImageInfo,
    rescale: &[(f64, f64)],
) -> Result<Model> {
    let invalid = |m: String| ReadError::new(path, ErrorKind::Invalid(m));
    if info.samples_per_pixel == 3 {
        return Ok(Model::Color);
    }
    if info.photometric == "PALETTE COLOR" {
        return lut::palette(obj, info.signed)
            .map(|l| Model::Palette(Box::new(l)))
            .map_err(|m| invalid(format!("PALETTE COLOR: {m}")));
    }
    let modality = match lut::modality(obj, info.signed) {
        Some(Ok(l)) => Some(Arc::new(l)),
        Some(Err(m)) => return Err(invalid(m)),
        None => None,
    };
    Ok(Model::Mono(
        rescale
            .iter()
            .map(|&(m, b)| FrameValues {
                modality: match &modality {
                    Some(l) => Modality::Lut(l.clone()),
                    None => Modality::Linear(m, b),
                },
                dose: info.dose_scaling,
            })
            .collect(),
    ))
}

/// Brings the extracted samples of all frames of a colour image to interleaved RGB: planes
/// interleaved (PlanarConfiguration 1, uncompressed data only: the decoders interleave),
/// YBR_FULL_422 expanded (uncompressed), YBR_FULL converted (uncompressed, RLE and JPEG
/// 2000, whose decoder gives only YBR_RCT / YBR_ICT as RGB; JPEG: module `jpeg_color`).
pub(super) fn to_rgb<'a>(
    info: &ImageInfo,
    bytes: Cow<'a, [u8]>,
    fmt: Fmt,
    notes: &mut Vec<String>,
) -> Cow<'a, [u8]> {
    if info.samples_per_pixel != 3 {
        return bytes;
    }
    let native = is_native(&info.transfer_syntax);
    let pi = info.photometric.as_str();
    let mut bytes = bytes;
    if native && pi == "YBR_FULL_422" {
        bytes = Cow::Owned(color::expand_422(&bytes));
    } else if native && info.planar {
        let frame = info.rows as usize * info.cols as usize * 3 * fmt.size();
        bytes = Cow::Owned(color::interleave(&bytes, frame, fmt.size()));
    }
    // The JPEG 2000 decoder gives YBR_RCT / YBR_ICT as RGB; YBR_FULL it leaves, and pydicom
    // converts it as it converts uncompressed YBR_FULL.
    let j2k = super::ts::family(&info.transfer_syntax) == Some(super::ts::Family::Jpeg2000);
    if (native || j2k || info.transfer_syntax == super::ts::RLE) && pi.starts_with("YBR_FULL") {
        color::ybr_to_rgb(bytes.to_mut());
        notes.push(format!("{pi} converted to RGB"));
    }
    bytes
}

/// Builds the grid from the ordered little-endian samples of the stack's frames.
#[allow(clippy::too_many_arguments)]
pub(super) fn build(
    path: &Path,
    info: &ImageInfo,
    stack: &Stack,
    (data, fmt): (&[u8], Fmt),
    model: &Model,
    component: Option<usize>,
    axis: Option<ExtraAxis>,
    mut notes: Vec<String>,
) -> Result<Grid> {
    let err = |e| ReadError::new(path, e);
    let dims = [
        i64::from(info.cols),
        i64::from(info.rows),
        stack.order.len() as i64,
    ];
    let (dims, _) = volux_core::limits::checked_dims(dims).map_err(err)?;
    let [row, col] = info.pixel_spacing.unwrap_or_else(|| {
        notes.push("no PixelSpacing: an in-plane spacing of 1 was used".into());
        [1.0, 1.0]
    });
    let spacing = [col, row, stack.z_spacing];
    let origin = stack.origin.into();
    let colour = match model {
        Model::Mono(frames) => {
            if let Some(index) = component.filter(|&c| c > 0) {
                return Err(err(volux_core::Error::NoSuchVolume {
                    option: "component",
                    index,
                    len: 1,
                }));
            }
            let samples =
                values::assemble(data, fmt, info.bits_stored, frames, &mut notes).map_err(err)?;
            if info.photometric == "MONOCHROME1" {
                notes.push(
                    "MONOCHROME1: low values are displayed bright; values kept as stored".into(),
                );
            }
            Colour::Channel(samples)
        }
        Model::Color => {
            color::channels(data, fmt, info.bits_stored, component, &mut notes).map_err(err)?
        }
        Model::Palette(luts) => {
            color::palette(data, fmt, info.bits_stored, luts, component, &mut notes).map_err(err)?
        }
    };
    let is_colour = !matches!(model, Model::Mono(_));
    let grid = match colour {
        Colour::Rgb(rgb) => Grid::from_rgb(dims, spacing, origin, rgb),
        Colour::Channel(samples) => Grid::new(dims, spacing, origin, samples),
    }
    .and_then(|g| g.with_direction(stack.direction))
    .map_err(err)?;
    let mut grid = notes.into_iter().fold(grid, Grid::with_note);
    if let (true, Some(c)) = (is_colour, component) {
        grid = grid
            .with_extra_axis(ExtraAxis::new(AxisKind::Color, 3, Some(c)))
            .with_note(format!(
                "colour channel {c} ({}) read",
                ["red", "green", "blue"][c]
            ));
    }
    if let Some(a) = axis {
        grid = grid.with_extra_axis(a);
    }
    Ok(grid)
}
