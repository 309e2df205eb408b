//! TIFF stacks: multi-page TIFF (one page per z slice), ImageJ hyperstacks, single-file
//! OME-TIFF, and folders of numbered single-page TIFF slices; read through the `tiff` crate
//! (pure Rust: LZW, Deflate and PackBits without C libraries, BigTIFF too).
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
//! and timepoints (an index out of range is an error saying how many there are). Samples are
//! grayscale 8/16-bit unsigned, 16-bit signed or 32-bit float ([`pages`]); the volume is
//! checked against the memory budget and against what the file can decode to before it is
//! allocated, then filled page by page. The grid's notes say the flavour, page count,
//! compression, sample type and where the spacing comes from.
use std::path::Path;

use ::tiff::tags::Tag;
use volux_core::Grid;

use crate::error::{ErrorKind, ReadError, Result};

pub mod folder;
pub mod imagej;
pub mod layout;
pub mod ome;
pub mod pages;

use layout::{choose, plain_spacing, Layout};
use pages::{grid, resolution, tag_number, tiff_err, Volume};

/// Reads a TIFF stack, an ImageJ hyperstack, an OME-TIFF, or (when `path` is a folder) a
/// folder of numbered TIFF slices; `channel` and `timepoint` choose among several.
pub fn read(path: &Path, channel: usize, timepoint: usize) -> Result<Grid> {
    if crate::util::data_metadata(path)?.is_dir() {
        return folder::read(path, channel, timepoint);
    }
    let (mut dec, len) = pages::open(path)?;
    let first = pages::page_info(path, &mut dec, 0)?;
    let desc = pages::description(path, &mut dec)?;
    let res = resolution(path, &mut dec)?;
    let unit = tag_number(path, &mut dec, Tag::ResolutionUnit)?;
    let n = pages::count_pages(path, &mut dec)?;
    let layout = match desc.as_deref() {
        Some(d) if ome::is_ome(d) => ome::parse(path, d)?.layout(
            path,
            n,
            (first.width, first.height, first.ty),
            channel,
            timepoint,
        )?,
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
    pages::check_volume(path, &first, layout.ifds.len(), len)?;
    let mut volume = Volume::new(first, layout.ifds.len());
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
    grid(path, what, first, volume, layout)
}
