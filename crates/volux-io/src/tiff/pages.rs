//! Decoding TIFF pages (IFDs, TIFF 6.0 section 2) into a preallocated grid through the
//! `tiff` crate: one page is one z slice.
//!
//! What a page may hold ([`page_info`]):
//! - photometric MINISBLACK (1) or MINISWHITE (0), one sample per pixel: 1, 2, 4 bits
//!   unsigned (unpacked to `uint8`), 8, 16, 32, 64 bits unsigned or signed, 16, 32, 64-bit
//!   float (`SampleFormat` 1, 2, 3). MINISWHITE is inverted by Volux (the type's maximum minus
//!   the value for unsigned samples, the negated value for signed and float ones, said in a
//!   note);
//! - RGB (2), 8 to 64 bits (any of the sample formats above), contiguous or planar
//!   (`PlanarConfiguration` 2), extra samples (alpha) ignored with a note;
//! - PALETTE (3), 1 to 16-bit indices: each replaced by the `ColorMap`'s 16-bit red, green and
//!   blue, as tifffile's `apply_colormap` does;
//! - YCbCr (6) in JPEG-compressed pages: converted to RGB (JFIF, as libjpeg does for libtiff
//!   and tifffile).
//!
//! Samples are kept in the grid's types ([`Stored::out_type`]): `int8` becomes `int16`
//! exactly, 32 and 64-bit integers and `float64` become `float32` with a note saying how many
//! values lost precision, `float16` becomes `float32` exactly. Strips or tiles; compressions
//! ([`compression_name`]): none, LZW, Deflate (8 and 32946), PackBits, JPEG (7, with
//! `JPEGTables`; zune-jpeg), Zstandard (50000), WebP (50001, 8-bit RGB(A); image-webp), CCITT
//! Group 4 (4); any other is refused by code and name. The declared volume is checked against the memory budget and against what
//! the file's bytes can decode to before anything is allocated, and every JPEG or WebP
//! strip's frame size against the strip's before it is decoded.
use std::collections::HashSet;
use std::path::Path;
use std::sync::Arc;

use ::tiff::decoder::{ifd::Value, Decoder, Limits};
use ::tiff::tags::{IfdPointer, Tag};
use ::tiff::TiffError;
use volux_core::color::Rgb;
use volux_core::grid::{Buffer, Samples};
use volux_core::volume_axes::{AxisKind, ExtraAxis};
use volux_core::{Grid, ScalarType};

use crate::error::{ErrorKind, ReadError, Result};
use crate::util::{io_error, max_inflated, open_regular};

use super::layout::{choose, Layout};
use super::source::{jpeg_frame_size, webp_frame_size, Source};

/// A TIFF decoder over a buffered, patchable file ([`Source`]).
pub type TiffDecoder = Decoder<Source>;

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
    let source = Source::new(file).map_err(|e| io_error(path, e))?;
    let dec = Decoder::new(source)
        .map_err(|e| tiff_err(path, e))?
        .with_limits(limits);
    Ok((dec, len))
}

/// The type of the samples a page stores.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stored {
    /// 1, 2 or 4-bit unsigned samples, packed (rows start on a byte).
    Bits(u8),
    /// 8-bit unsigned.
    U8,
    /// 8-bit signed.
    I8,
    /// 16-bit unsigned.
    U16,
    /// 16-bit signed.
    I16,
    /// 32-bit unsigned.
    U32,
    /// 32-bit signed.
    I32,
    /// 64-bit unsigned.
    U64,
    /// 64-bit signed.
    I64,
    /// IEEE half precision.
    F16,
    /// IEEE single precision.
    F32,
    /// IEEE double precision.
    F64,
}

impl Stored {
    /// From `BitsPerSample` and `SampleFormat` (1 unsigned, 2 signed, 3 float).
    fn from_tags(bits: u16, format: u16) -> Option<Self> {
        Some(match (bits, format) {
            (1 | 2 | 4, 1) => Stored::Bits(bits as u8),
            (8, 1) => Stored::U8,
            (8, 2) => Stored::I8,
            (16, 1) => Stored::U16,
            (16, 2) => Stored::I16,
            (16, 3) => Stored::F16,
            (32, 1) => Stored::U32,
            (32, 2) => Stored::I32,
            (32, 3) => Stored::F32,
            (64, 1) => Stored::U64,
            (64, 2) => Stored::I64,
            (64, 3) => Stored::F64,
            _ => return None,
        })
    }

    /// Bits per sample.
    pub fn bits(self) -> u32 {
        match self {
            Stored::Bits(b) => u32::from(b),
            Stored::U8 | Stored::I8 => 8,
            Stored::U16 | Stored::I16 | Stored::F16 => 16,
            Stored::U32 | Stored::I32 | Stored::F32 => 32,
            Stored::U64 | Stored::I64 | Stored::F64 => 64,
        }
    }

    /// The numpy-style name (`uint8`, `float64`, `1-bit`).
    pub fn name(self) -> String {
        match self {
            Stored::Bits(b) => format!("{b}-bit"),
            Stored::U8 => "uint8".into(),
            Stored::I8 => "int8".into(),
            Stored::U16 => "uint16".into(),
            Stored::I16 => "int16".into(),
            Stored::U32 => "uint32".into(),
            Stored::I32 => "int32".into(),
            Stored::U64 => "uint64".into(),
            Stored::I64 => "int64".into(),
            Stored::F16 => "float16".into(),
            Stored::F32 => "float32".into(),
            Stored::F64 => "float64".into(),
        }
    }

    /// In words (`16-bit unsigned`, `32-bit float`).
    pub fn words(self) -> String {
        let kind = match self {
            Stored::I8 | Stored::I16 | Stored::I32 | Stored::I64 => "signed",
            Stored::F16 | Stored::F32 | Stored::F64 => "float",
            _ => "unsigned",
        };
        format!("{}-bit {kind}", self.bits())
    }

    /// The grid type the samples are kept in.
    pub fn out_type(self) -> ScalarType {
        match self {
            Stored::Bits(_) | Stored::U8 => ScalarType::U8,
            Stored::I8 | Stored::I16 => ScalarType::I16,
            Stored::U16 => ScalarType::U16,
            _ => ScalarType::F32,
        }
    }

    /// Whether the samples are unsigned integers.
    fn unsigned(self) -> bool {
        matches!(
            self,
            Stored::Bits(_) | Stored::U8 | Stored::U16 | Stored::U32 | Stored::U64
        )
    }
}

/// How a page's samples are to be seen (`PhotometricInterpretation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Photometric {
    /// 0: grayscale, white is 0 (inverted on reading).
    MinIsWhite,
    /// 1: grayscale, black is 0.
    MinIsBlack,
    /// 2: red, green, blue.
    Rgb,
    /// 3: indices into the `ColorMap`.
    Palette,
    /// 6: luma and chroma (JPEG-compressed pages only), converted to RGB.
    YCbCr,
}

/// What a page holds: its size, samples and compression.
#[derive(Clone, Debug, PartialEq)]
pub struct PageInfo {
    /// Width (x) in pixels.
    pub width: usize,
    /// Height (y) in pixels.
    pub height: usize,
    /// The stored sample type.
    pub stored: Stored,
    /// The photometric interpretation.
    pub photometric: Photometric,
    /// Samples per pixel the decoder delivers: 1 (grayscale, palette), 3 (RGB, YCbCr), 4 (RGB
    /// with an alpha as its first extra sample).
    pub decoded_samples: usize,
    /// Extra samples per pixel (`ExtraSamples`), ignored.
    pub extra: usize,
    /// Whether the samples are stored in separate planes (`PlanarConfiguration` 2).
    pub planar: bool,
    /// The `Compression` tag.
    pub compression: u16,
    /// The palette: 2^bits red values, then green, then blue.
    pub colormap: Option<Arc<[u16]>>,
}

impl PageInfo {
    /// Whether the page is colour (RGB, palette, YCbCr).
    pub fn is_color(&self) -> bool {
        !matches!(
            self.photometric,
            Photometric::MinIsBlack | Photometric::MinIsWhite
        )
    }

    /// The grid type of the samples read from this page.
    pub fn out_type(&self) -> ScalarType {
        match (self.photometric, self.stored) {
            (Photometric::Palette, _) => ScalarType::U16,
            // -(-32768) does not fit in int16.
            (Photometric::MinIsWhite, Stored::I16) => ScalarType::F32,
            (_, s) => s.out_type(),
        }
    }

    /// Bytes the decoder delivers for one page.
    pub fn decoded_bytes(&self) -> u64 {
        let row_bits = (self.width as u64)
            .saturating_mul(self.decoded_samples as u64)
            .saturating_mul(u64::from(self.stored.bits()));
        row_bits.div_ceil(8).saturating_mul(self.height as u64)
    }

    /// The compression in words (`LZW compression`, `uncompressed`).
    pub fn compression_words(&self) -> String {
        match compression_name(self.compression) {
            "no" => "uncompressed".into(),
            c => format!("{c} compression"),
        }
    }

    /// The samples in words (`16-bit unsigned`, `8-bit unsigned RGB (planar)`).
    pub fn type_words(&self) -> String {
        let colour = match self.photometric {
            Photometric::Rgb if self.planar => " RGB (planar)",
            Photometric::Rgb => " RGB",
            Photometric::Palette => " palette indices",
            Photometric::YCbCr => " YCbCr",
            _ => "",
        };
        format!("{}{colour}", self.stored.words())
    }

    /// Most bytes `encoded` bytes of this page's compression can decode to, and why.
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
            7 => (
                encoded.saturating_mul(16384),
                "JPEG: at least one bit per 8x8 block, upsampled at most 4x4, of 2-byte samples",
            ),
            50000 => (
                encoded.saturating_mul(43_691).saturating_add(1 << 17),
                "Zstandard: a 3-byte RLE block emits at most 128 KiB",
            ),
            50001 => (
                u64::MAX,
                "WebP lossless can code a pixel in no bits: only the memory budget bounds it",
            ),
            4 => (
                encoded.saturating_mul(8 * 8192).saturating_add(1 << 16),
                "CCITT Group 4: one bit codes at most a line of 65535 pixels",
            ),
            _ => (encoded, "uncompressed"),
        }
    }
}

/// The name of a `Compression` code (TIFF 6.0, libtiff's and tifffile's registries); the
/// codes Volux decodes are listed in [`decodes`].
pub fn compression_name(code: u16) -> &'static str {
    match code {
        1 => "no",
        2 => "CCITT modified Huffman RLE",
        3 => "CCITT Group 3 fax",
        4 => "CCITT Group 4 fax",
        5 => "LZW",
        6 => "old-style JPEG",
        7 => "JPEG",
        8 | 32946 => "Deflate",
        9 | 10 => "JBIG",
        32771 => "NeXT 2-bit RLE",
        32773 => "PackBits",
        32809 => "ThunderScan RLE",
        32895..=32898 => "IT8",
        32908 => "Pixar log",
        32909 => "Pixar film",
        33003 | 33005 | 34712 | 34713 => "JPEG 2000",
        34661 => "JBIG (ISO)",
        34676 => "SGI LogLuv",
        34677 => "SGI LogLuv24",
        34887 => "LERC",
        34892 => "lossy JPEG (DNG)",
        34925 => "LZMA",
        34926 => "Zstandard (old code)",
        34927 => "WebP (old code)",
        34933 => "PNG",
        34934 => "JPEG XR",
        50000 => "Zstandard",
        50001 => "WebP",
        50002 | 52546 => "JPEG XL",
        _ => "unknown",
    }
}

/// Whether Volux decodes compression `code`.
pub fn decodes(code: u16) -> bool {
    matches!(code, 1 | 4 | 5 | 7 | 8 | 32946 | 32773 | 50000 | 50001)
}

/// The compressions decoded, in words, for refusals.
const DECODED: &str =
    "uncompressed, LZW, Deflate, PackBits, JPEG, Zstandard, WebP and CCITT Group 4";

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

/// A tag of the current page as unsigned integers, if present.
fn tag_uints(path: &Path, dec: &mut TiffDecoder, tag: Tag) -> Result<Option<Vec<u64>>> {
    dec.find_tag_unsigned_vec::<u64>(tag)
        .map_err(|e| tiff_err(path, e))
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

/// The name of a photometric interpretation Volux reads.
fn photometric_code_name(p: Photometric) -> &'static str {
    match p {
        Photometric::MinIsWhite => "MINISWHITE",
        Photometric::MinIsBlack => "MINISBLACK",
        Photometric::Rgb => "RGB",
        Photometric::Palette => "palette",
        Photometric::YCbCr => "YCbCr",
    }
}

/// The name of a photometric interpretation Volux does not read.
fn photometric_name(code: u64) -> String {
    let name = match code {
        4 => "transparency mask",
        5 => "CMYK (separated)",
        8 => "CIE L*a*b*",
        9 => "ICC L*a*b*",
        10 => "ITU L*a*b*",
        32803 => "colour filter array (raw sensor data)",
        32844 => "LogL",
        32845 => "LogLuv",
        34892 => "linear raw",
        _ => "unknown",
    };
    format!("photometric interpretation {code} ({name})")
}

/// The size, samples and compression of the current page; what Volux does not read is
/// [`ErrorKind::Unsupported`] naming it, in one line.
pub fn page_info(path: &Path, dec: &mut TiffDecoder, page: usize) -> Result<PageInfo> {
    let unsupported = |what: String| {
        ReadError::new(
            path,
            ErrorKind::Unsupported(format!("TIFF page {page}: {what}")),
        )
    };
    let (w, h) = dec.dimensions().map_err(|e| tiff_err(path, e))?;
    let first =
        |v: Option<Vec<u64>>, default: u64| v.and_then(|v| v.first().copied()).unwrap_or(default);
    let photometric_code = first(tag_uints(path, dec, Tag::PhotometricInterpretation)?, 1);
    let samples = first(tag_uints(path, dec, Tag::SamplesPerPixel)?, 1);
    let bits = first(tag_uints(path, dec, Tag::BitsPerSample)?, 1);
    let format = first(tag_uints(path, dec, Tag::SampleFormat)?, 1);
    let planar = first(tag_uints(path, dec, Tag::PlanarConfiguration)?, 1) == 2;
    let compression = first(tag_uints(path, dec, Tag::Compression)?, 1) as u16;
    let extras = tag_uints(path, dec, Tag::ExtraSamples)?.unwrap_or_default();
    if !decodes(compression) {
        return Err(unsupported(format!(
            "compression {compression} ({}); Volux reads {DECODED}",
            compression_name(compression)
        )));
    }
    if first(tag_uints(path, dec, Tag::FillOrder)?, 1) == 2 {
        return Err(unsupported(
            "FillOrder 2 (the bits of each byte stored in reverse order); Volux reads \
             FillOrder 1"
                .into(),
        ));
    }
    let stored =
        Stored::from_tags(bits.min(u16::MAX as u64) as u16, format as u16).ok_or_else(|| {
            let kind = match format {
                1 => "unsigned",
                2 => "signed",
                3 => "float",
                _ => "other-format",
            };
            unsupported(format!(
                "{bits}-bit {kind} samples; Volux reads 8, 16, 32 and 64-bit integers and \
                 floats (1, 2 and 4-bit unsigned ones too)"
            ))
        })?;
    let photometric = match photometric_code {
        0 => Photometric::MinIsWhite,
        1 => Photometric::MinIsBlack,
        2 => Photometric::Rgb,
        3 => Photometric::Palette,
        6 if compression == 7 => Photometric::YCbCr,
        6 => {
            return Err(unsupported(
                "YCbCr samples without JPEG compression (chroma subsampled); Volux reads \
                 YCbCr in JPEG-compressed pages"
                    .into(),
            ))
        }
        c => {
            return Err(unsupported(format!(
                "{}; Volux reads grayscale, RGB, palette and JPEG YCbCr pages",
                photometric_name(c)
            )))
        }
    };
    // Samples beyond the photometric ones: those ExtraSamples lists, and for RGB a fourth
    // without it (taken as alpha, as the `tiff` crate and tifffile do).
    let colour_samples = samples.saturating_sub(extras.len() as u64);
    let want: usize = match photometric {
        Photometric::Rgb | Photometric::YCbCr => 3,
        _ => 1,
    };
    let rgb_alpha = photometric == Photometric::Rgb && colour_samples == 4;
    let extra = samples.saturating_sub(want as u64) as usize;
    if (colour_samples != want as u64 && !rgb_alpha) || (want == 1 && extra > 0) {
        let what = photometric_code_name(photometric);
        return Err(unsupported(format!(
            "{samples} samples per pixel ({extra} extra) in a {what} page; Volux reads {want}{}",
            if want == 3 {
                " colour samples (and ignores extra ones)"
            } else {
                " sample per pixel there"
            }
        )));
    }
    if matches!(stored, Stored::Bits(_)) && want == 3 {
        return Err(unsupported(format!(
            "{bits}-bit colour samples; Volux reads 8 to 64-bit ones"
        )));
    }
    if compression == 7 && !matches!(stored, Stored::U8) {
        return Err(unsupported(format!(
            "JPEG-compressed {} samples; Volux reads 8-bit JPEG",
            stored.words()
        )));
    }
    if compression == 50001 && (photometric != Photometric::Rgb || stored != Stored::U8 || planar) {
        return Err(unsupported(format!(
            "WebP compression of {} {} samples{}; WebP holds 8-bit RGB(A), contiguous",
            stored.words(),
            photometric_code_name(photometric),
            if planar { " (planar)" } else { "" }
        )));
    }
    if compression == 4 && !matches!(stored, Stored::Bits(1)) {
        return Err(unsupported(format!(
            "CCITT Group 4 compression of {} samples (it codes 1-bit ones)",
            stored.words()
        )));
    }
    let colormap = if photometric == Photometric::Palette {
        if !matches!(stored, Stored::Bits(_) | Stored::U8 | Stored::U16) {
            return Err(unsupported(format!(
                "palette indices of {}; Volux reads unsigned indices of up to 16 bits",
                stored.words()
            )));
        }
        let need = 1usize << stored.bits();
        let map = dec
            .find_tag_unsigned_vec::<u16>(Tag::ColorMap)
            .map_err(|e| tiff_err(path, e))?
            .ok_or_else(|| unsupported("a palette page without a ColorMap".into()))?;
        // TIFF 6.0: 3 x 2^bits values. A longer one (tifffile writes 3 x 256 for 4-bit
        // indices) is read as tifffile reads it: three rows of a third each.
        if map.len() % 3 != 0 || map.len() / 3 < need {
            return Err(ReadError::new(
                path,
                ErrorKind::Invalid(format!(
                    "TIFF page {page}: the ColorMap holds {} values; {}-bit indices need 3 x \
                     {need}",
                    map.len(),
                    stored.bits(),
                )),
            ));
        }
        Some(Arc::from(map))
    } else {
        None
    };
    // The crate delivers RGBA when the first extra sample is an alpha (1 associated, 2
    // unassociated), and drops other extra samples.
    let alpha =
        rgb_alpha || (photometric == Photometric::Rgb && matches!(extras.first(), Some(1 | 2)));
    let decoded_samples = want + usize::from(alpha);
    Ok(PageInfo {
        width: w as usize,
        height: h as usize,
        stored,
        photometric,
        decoded_samples,
        extra,
        planar: planar && want == 3,
        compression,
        colormap,
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

/// Which samples of a colour page the grid keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Keep {
    /// The one sample of a grayscale page.
    Gray,
    /// Red, green and blue.
    Rgb,
    /// One colour channel (0 red, 1 green, 2 blue) as the scalar.
    Channel(usize),
}

impl Keep {
    /// How many planes the grid holds.
    fn planes(self) -> usize {
        match self {
            Keep::Rgb => 3,
            _ => 1,
        }
    }
}

/// Refuses, before allocating, a volume of `depth` pages like `info` (keeping `keep`) that
/// the memory budget cannot hold or that `encoded` bytes of files cannot decode to.
pub fn check_volume(
    path: &Path,
    info: &PageInfo,
    keep: Keep,
    depth: usize,
    encoded: u64,
) -> Result<()> {
    let voxels = (info.width as u64)
        .saturating_mul(info.height as u64)
        .saturating_mul(depth as u64);
    // The colour planes and the luminance the grid derives from them.
    let planes = match keep {
        Keep::Rgb => 4,
        _ => 1,
    };
    let declared = voxels
        .saturating_mul(planes)
        .saturating_mul(info.out_type().size() as u64)
        .saturating_add(info.decoded_bytes());
    volux_core::limits::check_alloc("the TIFF volume", declared, 1)
        .map_err(|e| ReadError::new(path, e))?;
    let decoded = info.decoded_bytes().saturating_mul(depth as u64);
    let (max, how) = info.max_decoded(encoded);
    if decoded > max {
        return Err(ReadError::new(
            path,
            ErrorKind::Undeliverable {
                declared: decoded,
                available: encoded,
                max,
                how,
            },
        ));
    }
    Ok(())
}

/// The samples of a volume being filled, in the grid's types.
enum Planes {
    U8(Vec<u8>),
    U16(Vec<u16>),
    I16(Vec<i16>),
    F32(Vec<f32>),
}

impl Planes {
    fn new(ty: ScalarType, n: usize) -> Self {
        match ty {
            ScalarType::U8 => Planes::U8(vec![0; n]),
            ScalarType::U16 => Planes::U16(vec![0; n]),
            ScalarType::I16 => Planes::I16(vec![0; n]),
            _ => Planes::F32(vec![0.0; n]),
        }
    }

    fn into_samples(self) -> Samples {
        match self {
            Planes::U8(v) => Samples::U8(Buffer::owned(v)),
            Planes::U16(v) => Samples::U16(Buffer::owned(v)),
            Planes::I16(v) => Samples::I16(Buffer::owned(v)),
            Planes::F32(v) => Samples::F32(Buffer::owned(v)),
        }
    }

    /// The bytes of slice `r`, to decode into directly.
    fn bytes_mut(&mut self, r: std::ops::Range<usize>) -> &mut [u8] {
        match self {
            Planes::U8(v) => &mut v[r],
            Planes::U16(v) => bytemuck::cast_slice_mut(&mut v[r]),
            Planes::I16(v) => bytemuck::cast_slice_mut(&mut v[r]),
            Planes::F32(v) => bytemuck::cast_slice_mut(&mut v[r]),
        }
    }
}

/// A volume being filled page by page.
pub struct Volume {
    info: PageInfo,
    keep: Keep,
    planes: Vec<Planes>,
    /// A page's decoded bytes (8-aligned, so any sample type can be viewed in place).
    page: Vec<u64>,
    /// Values rounded on the way to `float32`.
    inexact: u64,
}

impl Volume {
    /// A zeroed volume of `depth` pages like `info`, keeping `keep` (check it with
    /// [`check_volume`] first).
    pub fn new(info: PageInfo, keep: Keep, depth: usize) -> Self {
        let n = info.width * info.height * depth;
        let planes = (0..keep.planes())
            .map(|_| Planes::new(info.out_type(), n))
            .collect();
        Self {
            info,
            keep,
            planes,
            page: Vec::new(),
            inexact: 0,
        }
    }

    /// Whether the decoder's bytes go straight into the grid: one stored sample per pixel,
    /// of the grid's type, unchanged.
    fn direct(&self) -> bool {
        let i = &self.info;
        i.photometric == Photometric::MinIsBlack
            && i.decoded_samples == 1
            && matches!(
                (i.stored, i.out_type()),
                (Stored::U8, ScalarType::U8)
                    | (Stored::U16, ScalarType::U16)
                    | (Stored::I16, ScalarType::I16)
                    | (Stored::F32, ScalarType::F32)
            )
    }

    /// Decodes the current page of `dec` (page `page` of `path`) into slice `z`; a page of
    /// another size or kind is an error naming both.
    pub fn read_page(
        &mut self,
        path: &Path,
        dec: &mut TiffDecoder,
        page: usize,
        z: usize,
    ) -> Result<()> {
        let info = page_info(path, dec, page)?;
        let same = (info.width, info.height, info.stored, info.photometric)
            == (
                self.info.width,
                self.info.height,
                self.info.stored,
                self.info.photometric,
            )
            && info.decoded_samples == self.info.decoded_samples
            && info.planar == self.info.planar
            && info.colormap == self.info.colormap;
        if !same {
            return Err(ReadError::new(
                path,
                ErrorKind::Invalid(format!(
                    "TIFF page {page} is {}x{} {}, but the first is {}x{} {}; all slices \
                     must agree{}",
                    info.width,
                    info.height,
                    info.type_words(),
                    self.info.width,
                    self.info.height,
                    self.info.type_words(),
                    if info.colormap != self.info.colormap {
                        " (their ColorMaps differ)"
                    } else {
                        ""
                    }
                )),
            ));
        }
        if matches!(info.compression, 7 | 50001) {
            check_frames(path, dec, page, &info)?;
        }
        let patched = matches!(
            info.photometric,
            Photometric::MinIsWhite | Photometric::Palette
        );
        if patched {
            // Let the crate decode the stored samples: Volux applies the inversion or the
            // ColorMap.
            let ifd = dec.ifd_pointer().map(|p| p.0).unwrap_or(0);
            let found = dec
                .inner()
                .patch_photometric(ifd)
                .map_err(|e| io_error(path, e))?;
            if !found {
                return Err(ReadError::new(
                    path,
                    ErrorKind::Header(format!(
                        "TIFF page {page}: PhotometricInterpretation is not a SHORT or LONG"
                    )),
                ));
            }
            if let Err(e) = dec.seek_to_image(page) {
                dec.inner().clear();
                return Err(tiff_err(path, e));
            }
        }
        let r = self.decode(path, dec, z);
        if patched {
            dec.inner().clear();
        }
        r
    }

    /// Decodes the current page into slice `z`, converting the samples to the grid's.
    fn decode(&mut self, path: &Path, dec: &mut TiffDecoder, z: usize) -> Result<()> {
        let plane = self.info.width * self.info.height;
        let r = z * plane..(z + 1) * plane;
        if self.direct() {
            let bytes = self.planes[0].bytes_mut(r);
            return dec.read_image_bytes(bytes).map_err(|e| tiff_err(path, e));
        }
        let len = usize::try_from(self.info.decoded_bytes()).unwrap_or(usize::MAX);
        self.page.clear();
        self.page.resize(len.div_ceil(8), 0);
        let bytes = &mut bytemuck::cast_slice_mut::<u64, u8>(&mut self.page)[..len];
        dec.read_image_bytes(bytes).map_err(|e| tiff_err(path, e))?;
        let bytes = &bytemuck::cast_slice::<u64, u8>(&self.page)[..len];
        let info = &self.info;
        let channels: &[usize] = match self.keep {
            Keep::Gray => &[0],
            Keep::Rgb => &[0, 1, 2],
            Keep::Channel(0) => &[0],
            Keep::Channel(1) => &[1],
            Keep::Channel(_) => &[2],
        };
        for (k, &c) in channels.iter().enumerate() {
            let dst = &mut self.planes[k];
            self.inexact += match (info.photometric, info.stored) {
                (Photometric::YCbCr, _) => {
                    ycbcr_channel(bytes, c, dst, r.clone());
                    0
                }
                (_, Stored::Bits(b)) => {
                    unpack(bytes, info, b, c, dst, r.clone());
                    0
                }
                _ => {
                    // Sample `k` of pixel `j` lies at `start + j * step` of the page; a
                    // palette page's one sample gives every colour channel.
                    let palette = info.colormap.as_deref().map(|m| (m, c));
                    let k = if palette.is_some() { 0 } else { c };
                    let at = if info.planar {
                        (k * plane, 1)
                    } else {
                        (k, info.decoded_samples)
                    };
                    let invert = info.photometric == Photometric::MinIsWhite;
                    convert(bytes, info.stored, at, dst, r.clone(), invert, palette).ok_or_else(
                        || {
                            ReadError::new(
                                path,
                                ErrorKind::Invalid(
                                    "TIFF: the decoded page is smaller than its size says".into(),
                                ),
                            )
                        },
                    )?
                }
            };
        }
        Ok(())
    }

    /// The grid of the filled volume: `dims` (x, y, z), the layout's spacing and notes, `what`
    /// (the pages read) with the compression and sample type, and notes on every value
    /// transform applied.
    pub fn into_grid(self, path: &Path, what: String, layout: Layout) -> Result<Grid> {
        let info = &self.info;
        let dims = [info.width, info.height, layout.ifds.len()];
        let voxels = (dims[0] * dims[1] * dims[2]) as u64;
        let mut notes = vec![
            format!(
                "{what}, {}, {}",
                info.compression_words(),
                info.type_words()
            ),
            layout.spacing_note,
        ];
        notes.extend(layout.notes);
        notes.extend(self.value_notes(voxels));
        let keep = self.keep;
        let mut planes = self.planes.into_iter().map(Planes::into_samples);
        let err = |e| ReadError::new(path, e);
        let mut grid = match (keep, planes.next(), planes.next(), planes.next()) {
            (Keep::Rgb, Some(r), Some(g), Some(b)) => {
                let rgb = Rgb::new([r, g, b]).map_err(err)?;
                Grid::from_rgb(dims, layout.spacing, [0.0; 3], rgb).map_err(err)?
            }
            (_, Some(s), _, _) => Grid::new(dims, layout.spacing, [0.0; 3], s).map_err(err)?,
            _ => {
                return Err(ReadError::new(
                    path,
                    ErrorKind::Invalid("TIFF: no samples were read".into()),
                ))
            }
        };
        if let Keep::Channel(c) = keep {
            grid = grid.with_extra_axis(ExtraAxis::new(AxisKind::Color, 3, Some(c)));
        }
        for axis in layout.axes {
            grid = grid.with_extra_axis(axis);
        }
        for n in notes {
            grid = grid.with_note(n);
        }
        Ok(grid)
    }

    /// The notes on the value transforms applied to `voxels` voxels.
    fn value_notes(&self, voxels: u64) -> Vec<String> {
        let info = &self.info;
        let mut notes = Vec::new();
        let values = voxels * self.planes.len() as u64;
        match info.photometric {
            Photometric::MinIsWhite => notes.push(if info.stored.unsigned() {
                let max = 2u128.pow(info.stored.bits()) - 1;
                format!(
                    "MINISWHITE (photometric 0: white is 0): values inverted to {max} - v, so \
                     that higher is brighter"
                )
            } else {
                format!(
                    "MINISWHITE (photometric 0: white is 0): values negated (-v), so that \
                     higher is brighter{}",
                    if info.stored == Stored::I16 {
                        " (as float32: -(-32768) does not fit in int16)"
                    } else {
                        ""
                    }
                )
            }),
            Photometric::Palette => notes.push(format!(
                "palette (photometric 3): each {}-bit index replaced by the ColorMap's 16-bit \
                 {}",
                info.stored.bits(),
                match self.keep {
                    Keep::Channel(c) => format!("{} (colour channel {c})", COLOUR[c.min(2)]),
                    _ => "red, green and blue".into(),
                }
            )),
            Photometric::YCbCr => notes
                .push("JPEG YCbCr converted to RGB (JFIF full-range BT.601, as libjpeg)".into()),
            _ => {}
        }
        if info.compression == 7 {
            notes.push(
                "JPEG is lossy: the values are zune-jpeg's decoding, which may differ from \
                 other decoders' by rounding"
                    .into(),
            );
        }
        if info.compression == 50001 {
            notes.push(
                "WebP (lossy unless written lossless): the values are image-webp's decoding, \
                 which may differ from libwebp's by rounding where lossy"
                    .into(),
            );
        }
        if info.extra > 0 {
            notes.push(format!(
                "{} extra sample(s) per pixel (ExtraSamples: alpha or other) ignored",
                info.extra
            ));
        }
        if let Keep::Channel(c) = self.keep {
            if info.photometric != Photometric::Palette {
                notes.push(format!(
                    "colour channel {c} ({}) read as the scalar",
                    COLOUR[c.min(2)]
                ));
            }
        }
        if info.photometric != Photometric::Palette {
            let name = info.stored.name();
            let out = info.out_type();
            let lossy = match info.stored {
                Stored::U32 | Stored::I32 | Stored::U64 | Stored::I64 => {
                    Some("integers above 2^24 lose precision")
                }
                Stored::F64 => Some("precision reduced"),
                _ => None,
            };
            let note = match (info.stored, lossy) {
                (Stored::U8 | Stored::U16 | Stored::F32, _) => None,
                (Stored::I16, _) if out == ScalarType::I16 => None,
                (_, Some(why)) => Some(if self.inexact > 0 {
                    format!(
                        "converted from {name} to float32 ({why}: {} of {values} values \
                         rounded)",
                        self.inexact
                    )
                } else {
                    format!("converted from {name} to float32 ({why}; every value here fits)")
                }),
                (_, None) => Some(format!("converted from {name} to {} (exact)", out.name())),
            };
            notes.extend(note);
        }
        notes
    }
}

/// The colour channels' names.
const COLOUR: [&str; 3] = ["red", "green", "blue"];

/// Converts channel `c` of a YCbCr page (3 interleaved 8-bit samples per pixel) to red (0),
/// green (1) or blue (2) in `dst[r]`, as libjpeg's `ycc_rgb_convert` (16-bit fixed point).
fn ycbcr_channel(bytes: &[u8], c: usize, dst: &mut Planes, r: std::ops::Range<usize>) {
    const HALF: i32 = 1 << 15;
    let fix = |x: f64| (x * 65536.0 + 0.5) as i32;
    let (cr_r, cb_g, cr_g, cb_b) = (fix(1.40200), fix(0.34414), fix(0.71414), fix(1.77200));
    let Planes::U8(dst) = dst else { return };
    for (d, p) in dst[r].iter_mut().zip(bytes.chunks_exact(3)) {
        let y = i32::from(p[0]);
        let cb = i32::from(p[1]) - 128;
        let cr = i32::from(p[2]) - 128;
        let v = match c {
            0 => y + ((cr_r * cr + HALF) >> 16),
            1 => y + ((-cb_g * cb - cr_g * cr + HALF) >> 16),
            _ => y + ((cb_b * cb + HALF) >> 16),
        };
        *d = v.clamp(0, 255) as u8;
    }
}

/// Unpacks the `b`-bit samples (1, 2 or 4, most significant first, rows starting on a byte)
/// of a grayscale or palette page into `dst[r]`: palette indices through channel `c` of the
/// ColorMap, MINISWHITE inverted to `2^b - 1 - v`.
fn unpack(
    bytes: &[u8],
    info: &PageInfo,
    b: u8,
    c: usize,
    dst: &mut Planes,
    r: std::ops::Range<usize>,
) {
    let b = usize::from(b);
    let w = info.width;
    let row_bytes = (w * b).div_ceil(8);
    let mask = (1u16 << b) - 1;
    let sample = |j: usize| -> u16 {
        let (y, x) = (j / w, j % w);
        let bit = x * b;
        let byte = bytes.get(y * row_bytes + bit / 8).copied().unwrap_or(0);
        (u16::from(byte) >> (8 - b - bit % 8)) & mask
    };
    match (dst, &info.colormap) {
        (Planes::U16(dst), Some(map)) => {
            let row = &map[c * (map.len() / 3)..];
            for (j, d) in dst[r].iter_mut().enumerate() {
                *d = row[usize::from(sample(j))];
            }
        }
        (Planes::U8(dst), _) => {
            let invert = info.photometric == Photometric::MinIsWhite;
            for (j, d) in dst[r].iter_mut().enumerate() {
                let v = sample(j);
                *d = if invert { mask - v } else { v } as u8;
            }
        }
        _ => {}
    }
}

/// `float16` bits as `f32` (exact).
fn f16_to_f32(h: u16) -> f32 {
    let sign = u32::from(h >> 15) << 31;
    let exp = u32::from((h >> 10) & 0x1f);
    let man = u32::from(h & 0x3ff);
    let bits = match (exp, man) {
        (0, 0) => sign,
        (0, m) => {
            // Subnormal: normalise the mantissa.
            let shift = m.leading_zeros() - 21;
            let m = (m << shift) & 0x3ff;
            sign | ((127 - 15 + 1 - shift) << 23) | (m << 13)
        }
        (0x1f, m) => sign | 0x7f80_0000 | (m << 13),
        (e, m) => sign | ((e + 127 - 15) << 23) | (m << 13),
    };
    f32::from_bits(bits)
}

/// Converts one sample per pixel of a decoded page (`bytes`, samples of `stored` in native
/// byte order; pixel `j`'s sample at `start + j * step`) into `dst[r]`: through the
/// `palette`'s channel, MINISWHITE-inverted, or widened / rounded to the grid's type. Returns
/// how many values were rounded on the way to `float32`, or `None` when `bytes` are too few.
fn convert(
    bytes: &[u8],
    stored: Stored,
    (start, step): (usize, usize),
    dst: &mut Planes,
    r: std::ops::Range<usize>,
    invert: bool,
    palette: Option<(&[u16], usize)>,
) -> Option<u64> {
    let size = (stored.bits() / 8) as usize;
    let needed = (start + r.len().saturating_sub(1) * step + 1) * size;
    if bytes.len() < needed || r.is_empty() {
        return None;
    }
    let mut inexact = 0u64;
    macro_rules! fill {
        ($dst:expr, $t:ty, $f:expr) => {{
            let src: &[$t] = bytemuck::cast_slice(bytes);
            #[allow(unused_mut)]
            let mut f = $f;
            for (j, d) in $dst[r].iter_mut().enumerate() {
                *d = f(src[start + j * step]);
            }
        }};
    }
    let mut rounded = |exact: bool| {
        if !exact {
            inexact += 1;
        }
    };
    match (dst, stored, palette) {
        (Planes::U16(d), Stored::U8, Some((map, c))) => {
            let row = &map[c * (map.len() / 3)..];
            fill!(d, u8, |v: u8| row[usize::from(v)])
        }
        (Planes::U16(d), Stored::U16, Some((map, c))) => {
            let row = &map[c * (map.len() / 3)..];
            fill!(d, u16, |v: u16| row[usize::from(v)])
        }
        (Planes::U8(d), Stored::U8, None) => fill!(d, u8, |v: u8| if invert { !v } else { v }),
        (Planes::U16(d), Stored::U16, None) => {
            fill!(d, u16, |v: u16| if invert { !v } else { v })
        }
        (Planes::I16(d), Stored::I16, None) => fill!(d, i16, |v: i16| v),
        (Planes::I16(d), Stored::I8, None) => {
            fill!(d, i8, |v: i8| if invert {
                -i16::from(v)
            } else {
                i16::from(v)
            })
        }
        (Planes::F32(d), Stored::I16, None) => {
            fill!(d, i16, |v: i16| if invert {
                -f32::from(v)
            } else {
                f32::from(v)
            })
        }
        (Planes::F32(d), Stored::U32, None) => fill!(d, u32, |v: u32| {
            let x = if invert { !v } else { v };
            let f = x as f32;
            rounded(f as u64 == u64::from(x));
            f
        }),
        (Planes::F32(d), Stored::I32, None) => fill!(d, i32, |v: i32| {
            let x = if invert { -i64::from(v) } else { i64::from(v) };
            let f = x as f32;
            rounded(f as i64 == x);
            f
        }),
        (Planes::F32(d), Stored::U64, None) => fill!(d, u64, |v: u64| {
            let x = if invert { !v } else { v };
            let f = x as f32;
            rounded(f as u128 == u128::from(x));
            f
        }),
        (Planes::F32(d), Stored::I64, None) => fill!(d, i64, |v: i64| {
            let x = if invert {
                -i128::from(v)
            } else {
                i128::from(v)
            };
            let f = x as f32;
            rounded(f as i128 == x);
            f
        }),
        (Planes::F32(d), Stored::F16, None) => fill!(d, u16, |v: u16| {
            let f = f16_to_f32(v);
            if invert {
                -f
            } else {
                f
            }
        }),
        (Planes::F32(d), Stored::F32, None) => fill!(d, f32, |v: f32| if invert { -v } else { v }),
        (Planes::F32(d), Stored::F64, None) => fill!(d, f64, |v: f64| {
            let x = if invert { -v } else { v };
            let f = x as f32;
            rounded(f64::from(f) == x || x.is_nan());
            f
        }),
        _ => return None,
    }
    Some(inexact)
}

/// Refuses a JPEG or WebP strip or tile of the current page whose frame is larger than the
/// strip, or whose frame size cannot be found, before the decoder allocates for it (zune-jpeg
/// and image-webp allocate what the stream's header declares, up to 16384 x 16384 pixels).
fn check_frames(path: &Path, dec: &mut TiffDecoder, page: usize, info: &PageInfo) -> Result<()> {
    let tiled = dec
        .find_tag(Tag::TileOffsets)
        .map_err(|e| tiff_err(path, e))?
        .is_some();
    let (offsets, counts, cw, ch) = if tiled {
        let tw = tag_number(path, dec, Tag::TileWidth)?.unwrap_or(0.0) as u64;
        let tl = tag_number(path, dec, Tag::TileLength)?.unwrap_or(0.0) as u64;
        (Tag::TileOffsets, Tag::TileByteCounts, tw, tl)
    } else {
        let rows = tag_number(path, dec, Tag::RowsPerStrip)?
            .map_or(info.height as u64, |r| r as u64)
            .min(info.height as u64);
        (
            Tag::StripOffsets,
            Tag::StripByteCounts,
            info.width as u64,
            rows,
        )
    };
    let offsets = tag_uints(path, dec, offsets)?.unwrap_or_default();
    let counts = tag_uints(path, dec, counts)?.unwrap_or_default();
    let tables = if info.compression == 7 {
        dec.find_tag_unsigned_vec::<u8>(Tag::JPEGTables)
            .map_err(|e| tiff_err(path, e))?
    } else {
        None
    };
    let what = if tiled { "tile" } else { "strip" };
    let codec = compression_name(info.compression);
    for (i, (&off, &len)) in offsets.iter().zip(&counts).enumerate() {
        let io = |e| io_error(path, e);
        let size = if info.compression == 7 {
            let size = jpeg_frame_size(dec.inner(), off, len).map_err(io)?;
            match (size, &tables) {
                (None, Some(t)) => {
                    jpeg_frame_size(&mut std::io::Cursor::new(t), 0, t.len() as u64).map_err(io)?
                }
                (size, _) => size,
            }
        } else {
            webp_frame_size(dec.inner(), off, len).map_err(io)?
        };
        let invalid = |m: String| {
            ReadError::new(
                path,
                ErrorKind::Invalid(format!("TIFF page {page}: {codec} {what} {i} {m}")),
            )
        };
        match size {
            Some((w, h)) if u64::from(w) > cw || u64::from(h) > ch => {
                return Err(invalid(format!(
                    "declares a {w}x{h} frame, larger than the {cw}x{ch} {what}"
                )))
            }
            Some(_) => {}
            None => return Err(invalid("has no frame header (its size is unknown)".into())),
        }
    }
    Ok(())
}

/// `XResolution` and `YResolution` of the current page.
pub fn resolution(path: &Path, dec: &mut TiffDecoder) -> Result<[Option<f64>; 2]> {
    Ok([
        tag_number(path, dec, Tag::XResolution)?,
        tag_number(path, dec, Tag::YResolution)?,
    ])
}

/// What the grid keeps of pages like `first`: the gray sample, the colour, or the colour
/// channel `component` (an index past the page's channels is
/// [`volux_core::Error::NoSuchVolume`]).
pub fn keep(path: &Path, first: &PageInfo, component: Option<usize>) -> Result<Keep> {
    let channels = if first.is_color() { 3 } else { 1 };
    Ok(match component {
        Some(c) => {
            let c = choose(path, "component", c, channels)?;
            if first.is_color() {
                Keep::Channel(c)
            } else {
                Keep::Gray
            }
        }
        None if first.is_color() => Keep::Rgb,
        None => Keep::Gray,
    })
}
