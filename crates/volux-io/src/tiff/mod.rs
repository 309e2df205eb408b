//! TIFF stacks: multi-page TIFF (one page per z slice), ImageJ hyperstacks, single-file
//! OME-TIFF, and folders of numbered single-page TIFF slices; read through the `tiff` crate
//! (pure Rust: LZW, Deflate, PackBits, JPEG through zune-jpeg, WebP through image-webp, CCITT
//! Group 4 through `fax`; Zstandard through `zstd`, which builds the C zstd library with `cc`;
//! BigTIFF, strips and tiles). Other compressions are refused in one line naming their code
//! and name.
//!
//! Which pages form the volume and its spacing come from the first page's
//! `ImageDescription`:
//! - OME-XML ([`ome`], OME Data Model): `Size*`, `DimensionOrder`, `TiffData`,
//!   `PhysicalSize*` with units, converted to micrometres;
//! - ImageJ ([`imagej`], ImageJ's `FileSaver`): `channels`, `slices`, `frames` (pages in CZT
//!   order), `unit`, `spacing` (z) with x and y from the resolution tags;
//! - anything else: every page is a z slice, x and y spacing from the TIFF resolution tags
//!   (TIFF 6.0 section 8), z equal to x; without them spacing 1.
//!
//! `channel` and `timepoint` choose among an ImageJ hyperstack's or an OME-TIFF's channels
//! and timepoints (an index out of range is [`volux_core::Error::NoSuchVolume`]); the grid
//! records the file's channel and time axes ([`ExtraAxis`] of kind
//! [`AxisKind::Channel`] and [`AxisKind::Time`]).
//!
//! Samples ([`pages`]): grayscale of 1 to 64 bits (integers and floats; `int8` kept as
//! `int16`, 32 and 64-bit integers and `float64` as `float32` with a note counting the values
//! rounded), MINISWHITE inverted with a note, RGB (contiguous or planar) and PALETTE (through
//! the 16-bit `ColorMap`) as colour grids ([`Grid::from_rgb`]; `VolumeChoice::component`
//! picks one channel as a scalar grid instead), JPEG YCbCr converted to RGB. The volume is
//! checked against the memory budget and against what the file can decode to before it is
//! allocated, then filled page by page. The grid's notes say the flavour, page count,
//! compression, sample type, where the spacing comes from, and every value transform applied.
use std::path::Path;

use ::tiff::tags::Tag;
#[cfg(doc)]
use volux_core::volume_axes::{AxisKind, ExtraAxis};
use volux_core::Grid;

use crate::dataset::VolumeChoice;
use crate::error::{ErrorKind, ReadError, Result};

pub mod folder;
pub mod imagej;
pub mod layout;
pub mod ome;
pub mod pages;
pub mod source;

use layout::{choose, plain_spacing, Layout};
use pages::{resolution, tag_number, tiff_err, Volume};

/// Reads a TIFF stack, an ImageJ hyperstack, an OME-TIFF, or (when `path` is a folder) a
/// folder of numbered TIFF slices; `channel` and `choice.timepoint` choose among several,
/// `choice.component` one colour channel of a colour image.
pub fn read(path: &Path, channel: usize, choice: VolumeChoice) -> Result<Grid> {
    let timepoint = choice.timepoint;
    if crate::util::data_metadata(path)?.is_dir() {
        return folder::read(path, channel, choice);
    }
    let (mut dec, len) = pages::open(path)?;
    let first = pages::page_info(path, &mut dec, 0)?;
    let keep = pages::keep(path, &first, choice.component)?;
    let desc = pages::description(path, &mut dec)?;
    let res = resolution(path, &mut dec)?;
    let unit = tag_number(path, &mut dec, Tag::ResolutionUnit)?;
    let n = pages::count_pages(path, &mut dec)?;
    let layout = match desc.as_deref() {
        Some(d) if ome::is_ome(d) => {
            ome::parse(path, d)?.layout(path, n, &first, channel, timepoint)?
        }
        Some(d) if imagej::is_imagej(d) => {
            imagej::parse(path, d)?.layout(path, n, channel, timepoint, res)?
        }
        _ => {
            choose(path, "channel", channel, 1)?;
            choose(path, "timepoint", timepoint, 1)?;
            let (spacing, spacing_note) = plain_spacing(path, res, unit)?;
            Layout {
                ifds: (0..n).collect(),
                spacing,
                spacing_note,
                flavour: "plain",
                notes: Vec::new(),
                axes: Vec::new(),
            }
        }
    };
    if let Some(&bad) = layout.ifds.iter().find(|&&i| i >= n) {
        return Err(ReadError::new(
            path,
            ErrorKind::Invalid(format!(
                "the {} metadata places a slice on page {bad}, but the file has {n} pages",
                layout.flavour
            )),
        ));
    }
    pages::check_volume(path, &first, keep, layout.ifds.len(), len)?;
    let mut volume = Volume::new(first, keep, layout.ifds.len());
    for (z, &ifd) in layout.ifds.iter().enumerate() {
        dec.seek_to_image(ifd).map_err(|e| tiff_err(path, e))?;
        volume.read_page(path, &mut dec, ifd, z)?;
    }
    let kind = match layout.flavour {
        "ImageJ" => "ImageJ TIFF",
        "OME" => "OME-TIFF",
        _ => "TIFF",
    };
    let what = format!("{kind}: {n} pages");
    volume.into_grid(path, what, layout)
}
