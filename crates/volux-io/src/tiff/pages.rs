//! Decoding TIFF pages (IFDs, TIFF 6.0 section 2) into a preallocated grid through the
//! `tiff` crate: one page is one z slice, read straight into its place in the volume.
//!
//! Pages must be grayscale (one sample per pixel) of 8 or 16 bits unsigned, 16 bits signed or
//! 32-bit float (`SampleFormat` 1, 2, 3), in strips or tiles, uncompressed, LZW, Deflate
//! (codes 8 and 32946) or PackBits. The declared volume is checked against the memory budget
//! and against what the file's bytes can decode to before anything is allocated.
use std::collections::HashSet;
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use ::tiff::decoder::{ifd::Value, Decoder, Limits};
use ::tiff::tags::{IfdPointer, Tag};
use ::tiff::{ColorType, TiffError};
use volux_core::grid::{Buffer, Samples};
use volux_core::{Grid, ScalarType};

use crate::error::{ErrorKind, ReadError, Result};
use crate::util::{io_error, max_inflated, open_regular};

use super::layout::Layout;

/// A TIFF decoder over a buffered file.
pub type TiffDecoder = Decoder<BufReader<File>>;

/// Largest tag value read (the OME-XML description, strip offsets): 16 MiB.
const MAX_TAG_BYTES: usize = 16 << 20;

/// A `tiff` crate error as a read error of `path`.
pub fn tiff_err(path: &Path, e: TiffError) -> ReadError {
    match e {
        TiffError::IoError(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => ReadError::new(
            path,
            ErrorKind::Invalid(format!(
                "TIFF data ends early (a strip, tile or tag points past the end of the file): {e}"
            )),
        ),
        TiffError::IoError(e) => io_error(path, e),
        TiffError::UnsupportedError(e) => {
            ReadError::new(path, ErrorKind::Unsupported(format!("TIFF: {e}")))
        }
        TiffError::LimitsExceeded => ReadError::new(
            path,
            ErrorKind::Invalid(format!(
                "TIFF: a tag or strip is larger than the {} MiB read for it",
                MAX_TAG_BYTES >> 20
            )),
        ),
        e => ReadError::new(path, ErrorKind::Header(format!("TIFF: {e}"))),
    }
}

/// Opens `path` (a regular file) as TIFF with bounded tag and strip sizes; returns the
/// decoder, positioned on the first page, and the file's length.
pub fn open(path: &Path) -> Result<(TiffDecoder, u64)> {
    let file = open_regular(path)?;
    let len = crate::util::file_len(path, &file)?;
    let mut limits = Limits::default();
    limits.ifd_value_size = MAX_TAG_BYTES;
    let dec = Decoder::new(BufReader::new(file))
        .map_err(|e| tiff_err(path, e))?
        .with_limits(limits);
    Ok((dec, len))
}

/// What a page holds: its size, sample type and compression.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PageInfo {
    /// Width (x) in pixels.
    pub width: usize,
    /// Height (y) in pixels.
    pub height: usize,
    /// Sample type.
    pub ty: ScalarType,
    /// The `Compression` tag (1 none, 5 LZW, 8 / 32946 Deflate, 32773 PackBits).
    pub compression: u16,
}

impl PageInfo {
    /// Bytes of one decoded page.
    pub fn bytes(&self) -> u64 {
        (self.width as u64)
            .saturating_mul(self.height as u64)
            .saturating_mul(self.ty.size() as u64)
    }

    /// The compression in words (`LZW compression`, `uncompressed`).
    pub fn compression_words(&self) -> String {
        match compression_name(self.compression) {
            Some("no") => "uncompressed".into(),
            Some(c) => format!("{c} compression"),
            None => format!("compression {}", self.compression),
        }
    }

    /// The sample type in words (`16-bit unsigned`).
    pub fn type_words(&self) -> &'static str {
        match self.ty {
            ScalarType::U8 => "8-bit unsigned",
            ScalarType::U16 => "16-bit unsigned",
            ScalarType::I16 => "16-bit signed",
            _ => "32-bit float",
        }
    }

    /// Most bytes `encoded` bytes of this page's compression can decode to.
    fn max_decoded(&self, encoded: u64) -> (u64, &'static str) {
        match self.compression {
            5 => (
                encoded.saturating_mul(4096).saturating_add(4096),
                "LZW: a code of 9 or more bits emits at most 4096 bytes",
            ),
            8 | 32946 => (max_inflated(encoded), "deflate expands at most 1032:1"),
            32773 => (
                encoded.saturating_mul(64).saturating_add(128),
                "PackBits expands at most 64:1",
            ),
            _ => (encoded, "uncompressed"),
        }
    }
}

/// The compressions read, by `Compression` tag.
fn compression_name(code: u16) -> Option<&'static str> {
    Some(match code {
        1 => "no",
        5 => "LZW",
        8 | 32946 => "Deflate",
        32773 => "PackBits",
        _ => return None,
    })
}

/// A tag of the current page as a number (rationals divided out), if present.
pub fn tag_number(path: &Path, dec: &mut TiffDecoder, tag: Tag) -> Result<Option<f64>> {
    let v = dec.find_tag(tag).map_err(|e| tiff_err(path, e))?;
    Ok(v.and_then(number))
}

/// A tag value as a number; the first of a list.
fn number(v: Value) -> Option<f64> {
    Some(match v {
        Value::Byte(x) => x as f64,
        Value::Short(x) => x as f64,
        Value::Unsigned(x) => x as f64,
        Value::UnsignedBig(x) => x as f64,
        Value::Signed(x) => x as f64,
        Value::SignedShort(x) => x as f64,
        Value::Float(x) => x as f64,
        Value::Double(x) => x,
        Value::Rational(n, d) => n as f64 / d as f64,
        Value::SRational(n, d) => n as f64 / d as f64,
        Value::List(l) => return l.into_iter().next().and_then(number),
        _ => return None,
    })
}

/// The `ImageDescription` of the current page, if any (not text: `None`).
pub fn description(path: &Path, dec: &mut TiffDecoder) -> Result<Option<String>> {
    match dec
        .find_tag(Tag::ImageDescription)
        .map_err(|e| tiff_err(path, e))?
    {
        Some(Value::Ascii(s)) => Ok(Some(s)),
        Some(Value::List(l)) => Ok(l.into_iter().find_map(|v| match v {
            Value::Ascii(s) => Some(s),
            _ => None,
        })),
        _ => Ok(None),
    }
}

/// The size, type and compression of the current page; other colour types, bit depths and
/// compressions are [`ErrorKind::Unsupported`] naming them.
pub fn page_info(path: &Path, dec: &mut TiffDecoder, page: usize) -> Result<PageInfo> {
    let unsupported = |what: String| {
        ReadError::new(
            path,
            ErrorKind::Unsupported(format!("TIFF page {page}: {what}")),
        )
    };
    let (w, h) = dec.dimensions().map_err(|e| tiff_err(path, e))?;
    let color = dec.colortype().map_err(|e| tiff_err(path, e))?;
    let bits = match color {
        ColorType::Gray(b) => b,
        other => {
            return Err(unsupported(format!(
                "{other:?} pixels; Volux reads grayscale (one sample per pixel) stacks"
            )))
        }
    };
    let format = tag_number(path, dec, Tag::SampleFormat)?.unwrap_or(1.0) as u16;
    let ty = match (bits, format) {
        (8, 1) => ScalarType::U8,
        (16, 1) => ScalarType::U16,
        (16, 2) => ScalarType::I16,
        (32, 3) => ScalarType::F32,
        (b, f) => {
            let kind = match f {
                1 => "unsigned",
                2 => "signed",
                3 => "float",
                _ => "other-format",
            };
            return Err(unsupported(format!(
                "{b}-bit {kind} samples; Volux reads 8/16-bit unsigned, 16-bit signed and \
                 32-bit float"
            )));
        }
    };
    let compression = tag_number(path, dec, Tag::Compression)?.unwrap_or(1.0) as u16;
    if compression_name(compression).is_none() {
        return Err(unsupported(format!(
            "compression {compression}; Volux reads uncompressed, LZW, Deflate and PackBits"
        )));
    }
    Ok(PageInfo {
        width: w as usize,
        height: h as usize,
        ty,
        compression,
    })
}

/// The number of pages (IFDs) in the file, walking the chain of directories without reading
/// their values; a chain that loops is an error.
pub fn count_pages(path: &Path, dec: &mut TiffDecoder) -> Result<usize> {
    let first = dec.ifd_pointer();
    let mut seen: HashSet<IfdPointer> = HashSet::new();
    let mut next = first;
    while let Some(ptr) = next {
        if !seen.insert(ptr) {
            return Err(ReadError::new(
                path,
                ErrorKind::Header("TIFF: the chain of pages (IFDs) loops".into()),
            ));
        }
        next = dec
            .read_directory(ptr)
            .map_err(|e| tiff_err(path, e))?
            .next();
    }
    if let Some(p) = first {
        // Back on the first page for the readers that follow.
        dec.goto_offset_u64(p.0).map_err(|e| io_error(path, e))?;
    }
    Ok(seen.len())
}

/// Refuses, before allocating, a volume of `depth` pages like `info` that the memory budget
/// cannot hold or that `encoded` bytes of files cannot decode to.
pub fn check_volume(path: &Path, info: &PageInfo, depth: usize, encoded: u64) -> Result<()> {
    let declared = info.bytes().saturating_mul(depth as u64);
    volux_core::limits::check_alloc("the TIFF volume", declared, 1)
        .map_err(|e| ReadError::new(path, e))?;
    let (max, how) = info.max_decoded(encoded);
    if declared > max {
        return Err(ReadError::new(
            path,
            ErrorKind::Undeliverable {
                declared,
                available: encoded,
                max,
                how,
            },
        ));
    }
    Ok(())
}

/// The samples of a volume being filled, in their native type.
enum Planes {
    U8(Vec<u8>),
    U16(Vec<u16>),
    I16(Vec<i16>),
    F32(Vec<f32>),
}

/// A volume being filled page by page.
pub struct Volume {
    info: PageInfo,
    planes: Planes,
}

impl Volume {
    /// A zeroed volume of `depth` pages like `info` (check it with [`check_volume`] first).
    pub fn new(info: PageInfo, depth: usize) -> Self {
        let n = info.width * info.height * depth;
        let planes = match info.ty {
            ScalarType::U8 => Planes::U8(vec![0; n]),
            ScalarType::U16 => Planes::U16(vec![0; n]),
            ScalarType::I16 => Planes::I16(vec![0; n]),
            _ => Planes::F32(vec![0.0; n]),
        };
        Self { info, planes }
    }

    /// Decodes the current page of `dec` (page `page` of `path`) into slice `z`; a page of
    /// another size or type is an error naming both.
    pub fn read_page(
        &mut self,
        path: &Path,
        dec: &mut TiffDecoder,
        page: usize,
        z: usize,
    ) -> Result<()> {
        let info = page_info(path, dec, page)?;
        if (info.width, info.height, info.ty) != (self.info.width, self.info.height, self.info.ty) {
            return Err(ReadError::new(
                path,
                ErrorKind::Invalid(format!(
                    "TIFF page {page} is {}x{} {}, but the first is {}x{} {}; all slices \
                     must agree",
                    info.width,
                    info.height,
                    info.type_words(),
                    self.info.width,
                    self.info.height,
                    self.info.type_words()
                )),
            ));
        }
        let plane = self.info.width * self.info.height;
        let r = z * plane..(z + 1) * plane;
        let bytes: &mut [u8] = match &mut self.planes {
            Planes::U8(v) => &mut v[r],
            Planes::U16(v) => bytemuck::cast_slice_mut(&mut v[r]),
            Planes::I16(v) => bytemuck::cast_slice_mut(&mut v[r]),
            Planes::F32(v) => bytemuck::cast_slice_mut(&mut v[r]),
        };
        dec.read_image_bytes(bytes).map_err(|e| tiff_err(path, e))
    }

    /// The samples read.
    pub fn into_samples(self) -> Samples {
        match self.planes {
            Planes::U8(v) => Samples::U8(Buffer::owned(v)),
            Planes::U16(v) => Samples::U16(Buffer::owned(v)),
            Planes::I16(v) => Samples::I16(Buffer::owned(v)),
            Planes::F32(v) => Samples::F32(Buffer::owned(v)),
        }
    }
}

/// `XResolution` and `YResolution` of the current page.
pub fn resolution(path: &Path, dec: &mut TiffDecoder) -> Result<[Option<f64>; 2]> {
    Ok([
        tag_number(path, dec, Tag::XResolution)?,
        tag_number(path, dec, Tag::YResolution)?,
    ])
}

/// The grid of a filled `volume`, with notes: `what` (the pages read), the compression and
/// sample type of `first`, the spacing's source and the layout's notes.
pub fn grid(
    path: &Path,
    what: String,
    first: PageInfo,
    volume: Volume,
    layout: Layout,
) -> Result<Grid> {
    let dims = [first.width, first.height, layout.ifds.len()];
    let mut grid = Grid::new(dims, layout.spacing, [0.0; 3], volume.into_samples())
        .map_err(|e| ReadError::new(path, e))?
        .with_note(format!(
            "{what}, {}, {}",
            first.compression_words(),
            first.type_words()
        ))
        .with_note(layout.spacing_note);
    for n in layout.notes {
        grid = grid.with_note(n);
    }
    Ok(grid)
}
