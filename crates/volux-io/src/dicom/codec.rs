//! Compressed (encapsulated) pixel data, decoded to the stored values.
//!
//! Only pure-Rust codecs are linked:
//! - RLE Lossless: decoded here (PS3.5 Annex G: one PackBits segment per byte of each
//!   sample, most significant byte first), for 8-, 16- and 32-bit samples and any number of
//!   samples per pixel, delivered interleaved (R G B R G B ...) and little-endian;
//! - JPEG baseline (8-bit), extended (8-bit) and lossless (2..16-bit): `jpeg-decoder`,
//!   through `dicom-pixeldata`; 12-bit extended (sequential DCT, Huffman, grey): module
//!   `jpeg12`, Volux's own decoder;
//! - JPEG-LS lossless and near-lossless: `pure_jpegls` (single-component streams; CharLS,
//!   the C++ reference decoder that `dicom-pixeldata` offers, needs CMake to build);
//! - JPEG 2000 and High-Throughput JPEG 2000 (Part 15): `openjp2`, the Rust port of
//!   OpenJPEG (its `ht_dec` decodes HT code-blocks), through `dicom-pixeldata`.
//!
//! 12-bit lossy JPEG has its own decoder because `jpeg-decoder` and `zune-jpeg` decode 8-bit
//! DCT frames only, and the one pure-Rust 12-bit decoder found (`libjpeg-turbo-rs` 0.3)
//! panics on damaged Huffman tables (64 of 3000 mutated frames: an index out of bounds in
//! its Huffman table, an arithmetic overflow). 12-bit progressive, arithmetic-coded or colour
//! frames, and DCT frames of other precisions, are [`ErrorKind::Unsupported`].
//!
//! The decoders size their output from Rows x Columns and copy what the codestream holds
//! into it, trusting the two to agree (a JPEG or JPEG 2000 frame larger than Rows x Columns
//! would overrun the buffer and panic, one that declares 65535 x 65535 would allocate
//! gigabytes). So before a frame is decoded its codestream header is read here and checked
//! against the DICOM header: the JPEG frame header (SOF: precision, lines, samples per line,
//! components), the JPEG-LS frame, preset and scan headers (SOF55, LSE, SOS), the JPEG 2000
//! image and tile size (SIZ: size, offset, components, precision, subsampling) and the RLE
//! header (segment count and offsets, and the length each segment unpacks to). The whole
//! decoded size (Rows x Columns x frames x bytes) is checked against the memory budget
//! before the first frame is decoded, and each decoded frame's length is checked before use.
use std::borrow::Cow;
use std::path::Path;

use dicom_core::value::Value;
use dicom_dictionary_std::tags;
use dicom_pixeldata::PixelDecoder;

use super::attrs::ImageInfo;
use super::ts::{family, ts_name, unsupported, Family};
use crate::error::{ErrorKind, ReadError, Result};

fn invalid(path: &Path, msg: String) -> ReadError {
    ReadError::new(path, ErrorKind::Invalid(msg))
}

/// Decodes all `frames` frames of `obj` (in file order) to little-endian stored values,
/// exactly `frame` bytes each.
pub(super) fn decode(
    path: &Path,
    obj: &dicom_object::DefaultDicomObject,
    info: &ImageInfo,
    frames: usize,
    frame: u64,
) -> Result<Vec<u8>> {
    let ts = info.transfer_syntax.as_str();
    let fam = family(ts).ok_or_else(|| {
        ReadError::new(
            path,
            ErrorKind::Unsupported(unsupported(ts).unwrap_or_default()),
        )
    })?;
    let total = frame
        .checked_mul(frames as u64)
        .ok_or_else(|| invalid(path, "the pixel data size overflows".into()))?;
    volux_core::limits::check_alloc("decoded pixel data", total, 1)
        .map_err(|e| ReadError::new(path, e))?;
    let (fragments, offsets) = fragments(path, obj)?;
    let name = ts_name(ts);
    let mut out = Vec::with_capacity(total as usize);
    for i in 0..frames {
        let data = frame_data(&fragments, &offsets, frames, i).ok_or_else(|| {
            invalid(
                path,
                format!(
                    "the {name} pixel data has no data for frame {} of {frames} ({} \
                     fragments)",
                    i + 1,
                    fragments.len()
                ),
            )
        })?;
        let bad = |e: Bad| {
            let kind = match e {
                Bad::Invalid(m) => ErrorKind::Invalid(format!("{name} frame {}: {m}", i + 1)),
                Bad::Unsupported(m) => {
                    ErrorKind::Unsupported(format!("transfer syntax {ts} ({name}): {m}"))
                }
            };
            ReadError::new(path, kind)
        };
        let cannot =
            |m: String| invalid(path, format!("cannot decode {name} frame {}: {m}", i + 1));
        let decoded: Cow<'_, [u8]>;
        let px;
        match fam {
            Family::Rle => {
                check_rle(&data, info).map_err(bad)?;
                decoded = Cow::Owned(decode_rle(&data, info).map_err(bad)?);
            }
            Family::JpegLs => {
                check_jls(&data, info).map_err(bad)?;
                decoded = Cow::Owned(decode_jls(&data, info).map_err(cannot)?);
            }
            Family::Jpeg if check_jpeg(&data, info).map_err(bad)? => {
                let v = super::jpeg12::decode(&data, info.rows, info.cols).map_err(cannot)?;
                decoded = Cow::Owned(v.iter().flat_map(|x| x.to_le_bytes()).collect());
            }
            Family::Jpeg if info.samples_per_pixel == 3 && info.bits == 8 => {
                decoded = Cow::Owned(decode_jpeg_components(&data).map_err(cannot)?);
            }
            Family::Jpeg | Family::Jpeg2000 => {
                if fam == Family::Jpeg2000 {
                    check_j2k(&data, info).map_err(bad)?;
                }
                px = obj
                    .decode_pixel_data_frame(i as u32)
                    .map_err(|e| cannot(chain(&e)))?;
                decoded = Cow::Borrowed(px.data());
            }
        }
        let got = &*decoded;
        if got.len() as u64 != frame {
            return Err(invalid(
                path,
                format!(
                    "{name} frame {} decodes to {} bytes, not the {frame} of Rows x Columns x \
                     BitsAllocated",
                    i + 1,
                    got.len()
                ),
            ));
        }
        out.extend_from_slice(got);
    }
    Ok(out)
}

/// An 8-bit colour JPEG frame's components as they are coded, interleaved, upsampled to full
/// resolution but not colour-transformed: module `jpeg_color` decides, as pydicom does, whether
/// they are YBR (`jpeg-decoder` would otherwise guess from the markers, PS3.5 8.2.1 leaving the
/// colour space to the Photometric Interpretation).
fn decode_jpeg_components(data: &[u8]) -> Result<Vec<u8>, String> {
    let mut d = jpeg_decoder::Decoder::new(data);
    // `RGB` interleaves the three components untouched; `None` (0.3.2) writes them plane
    // after plane past its output and panics.
    d.set_color_transform(jpeg_decoder::ColorTransform::RGB);
    d.decode().map_err(|e| e.to_string())
}

/// Why a codestream header is refused.
#[derive(Debug)]
enum Bad {
    /// Damaged or inconsistent with the DICOM header.
    Invalid(String),
    /// Valid, but not decoded by the linked codecs.
    Unsupported(String),
}

impl From<String> for Bad {
    fn from(m: String) -> Self {
        Self::Invalid(m)
    }
}

impl From<&str> for Bad {
    fn from(m: &str) -> Self {
        Self::Invalid(m.into())
    }
}

/// An error and its sources on one line.
fn chain(e: &dyn std::error::Error) -> String {
    let mut msg = e.to_string();
    let mut src = e.source();
    while let Some(s) = src {
        msg.push_str(": ");
        msg.push_str(&s.to_string());
        src = s.source();
    }
    msg
}

/// The fragments and basic offset table of the encapsulated PixelData.
fn fragments<'a>(
    path: &Path,
    obj: &'a dicom_object::DefaultDicomObject,
) -> Result<(Vec<&'a [u8]>, Vec<u32>)> {
    let elem = obj
        .element_opt(tags::PIXEL_DATA)
        .ok()
        .flatten()
        .ok_or_else(|| invalid(path, "no PixelData (7FE0,0010) element".into()))?;
    match elem.value() {
        Value::PixelSequence(seq) => Ok((
            seq.fragments().iter().map(|f| f.as_slice()).collect(),
            seq.offset_table().to_vec(),
        )),
        _ => {
            let ts = obj.meta().transfer_syntax();
            Err(invalid(
                path,
                format!(
                    "transfer syntax {ts} ({}) is a compressed one, but the pixel data is not \
                     encapsulated (no fragments)",
                    ts_name(ts)
                ),
            ))
        }
    }
}

/// The encoded bytes of frame `i`, gathered as `dicom-encoding` gathers them for the
/// decoders: one fragment per frame when the counts agree, else by the basic offset table.
fn frame_data<'a>(
    fragments: &[&'a [u8]],
    offsets: &[u32],
    frames: usize,
    i: usize,
) -> Option<Cow<'a, [u8]>> {
    if fragments.len() == frames {
        return fragments.get(i).map(|f| Cow::Borrowed(*f));
    }
    let base = match (offsets.get(i), i) {
        (Some(&o), _) => o as usize,
        (None, 0) => 0,
        (None, _) => return None,
    };
    let next = offsets.get(i + 1).map(|&o| o as usize);
    let (mut at, mut data) = (0usize, Vec::new());
    for f in fragments {
        if at >= base {
            data.extend_from_slice(f);
        }
        at = at.saturating_add(f.len() + 8);
        if next.is_some_and(|n| at >= n) {
            break;
        }
    }
    Some(Cow::Owned(data))
}

/// Bytes per sample.
fn bytes_of(info: &ImageInfo) -> usize {
    (info.bits / 8) as usize
}

/// The RLE header: as many segments as bytes per pixel, at increasing offsets inside the
/// fragment.
fn check_rle(data: &[u8], info: &ImageInfo) -> Result<(), Bad> {
    let word = |i: usize| {
        data.get(i * 4..i * 4 + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let n = word(0).ok_or("the data is shorter than the 64-byte RLE header")?;
    let want = bytes_of(info) * info.samples_per_pixel as usize;
    if want > 15 {
        return Err(Bad::Unsupported(format!(
            "BitsAllocated {} x SamplesPerPixel {} needs {want} RLE segments, more than the 15 \
             an RLE header lists",
            info.bits, info.samples_per_pixel
        )));
    }
    if n as usize != want {
        return Err(Bad::Invalid(format!(
            "the RLE header lists {n} segments, but BitsAllocated {} x SamplesPerPixel {} \
             needs {want}",
            info.bits, info.samples_per_pixel
        )));
    }
    let mut starts = Vec::with_capacity(want + 1);
    let mut prev = 64u32;
    for s in 1..=want {
        let o = word(s).ok_or("the data is shorter than the 64-byte RLE header")?;
        if o < prev || o as usize > data.len() {
            return Err(Bad::Invalid(format!(
                "RLE segment {s} starts at byte {o}, outside the {} bytes of the frame or \
                 before the previous segment",
                data.len()
            )));
        }
        starts.push(o as usize);
        prev = o;
    }
    starts.push(data.len());
    // Each segment holds one byte of every pixel: Rows x Columns bytes once unpacked (one
    // more where a pad byte ends the segment).
    let pixels = u64::from(info.rows) * u64::from(info.cols);
    for (s, w) in starts.windows(2).enumerate() {
        let n = packbits_len(&data[w[0]..w[1]]);
        if n < pixels || n > pixels + 1 {
            return Err(Bad::Invalid(format!(
                "RLE segment {} unpacks to {n} bytes, but Rows x Columns is {pixels}",
                s + 1
            )));
        }
    }
    Ok(())
}

/// The length a PackBits segment unpacks to, counted from its run headers; runs cut off by
/// the segment's end are not counted (the decoder adapter unwraps the read of a cut run,
/// and indexes its output up to Rows x Columns: both panic on a segment that falls short).
fn packbits_len(seg: &[u8]) -> u64 {
    let (mut at, mut n) = (0usize, 0u64);
    while let Some(&h) = seg.get(at) {
        let (adds, next) = match h {
            0..=127 => (u64::from(h) + 1, at + usize::from(h) + 2),
            128 => (0, at + 1),
            _ => (257 - u64::from(h), at + 2),
        };
        if next > seg.len() {
            break;
        }
        n += adds;
        at = next;
    }
    n
}

/// Unpacks the first `n` bytes of a PackBits segment (PS3.5 G.3.1): a header byte h of
/// 0..=127 copies the next h + 1 bytes, 129..=255 repeats the next byte 257 - h times, 128
/// does nothing. `None` when the segment holds fewer than `n` bytes.
fn unpack_bits(seg: &[u8], n: usize) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(n);
    let mut at = 0usize;
    while out.len() < n {
        let h = *seg.get(at)?;
        match h {
            0..=127 => {
                let run = seg.get(at + 1..at + 2 + usize::from(h))?;
                out.extend_from_slice(run);
                at += 2 + usize::from(h);
            }
            128 => at += 1,
            _ => {
                let b = *seg.get(at + 1)?;
                out.resize(out.len() + 257 - usize::from(h), b);
                at += 2;
            }
        }
    }
    out.truncate(n);
    Some(out)
}

/// Decodes one RLE frame (its header checked by [`check_rle`]) to interleaved little-endian
/// samples: segment `s * bytes + b` holds byte `b` (0 the most significant) of sample `s` of
/// every pixel (PS3.5 G.2).
fn decode_rle(data: &[u8], info: &ImageInfo) -> Result<Vec<u8>, Bad> {
    let bytes = bytes_of(info);
    let spp = info.samples_per_pixel as usize;
    let pixels = info.rows as usize * info.cols as usize;
    let segments = bytes * spp;
    let word = |i: usize| {
        data.get(i * 4..i * 4 + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let mut out = vec![0u8; pixels * segments];
    for k in 0..segments {
        let start = word(k + 1).ok_or("the data is shorter than the 64-byte RLE header")?;
        let end = if k + 1 < segments {
            word(k + 2).ok_or("the data is shorter than the 64-byte RLE header")?
        } else {
            data.len()
        };
        let seg = data
            .get(start..end)
            .ok_or_else(|| format!("RLE segment {} lies outside the frame", k + 1))?;
        let plane = unpack_bits(seg, pixels).ok_or_else(|| {
            format!(
                "RLE segment {} unpacks to fewer than the {pixels} bytes of Rows x Columns",
                k + 1
            )
        })?;
        let (s, b) = (k / bytes, k % bytes);
        let offset = s * bytes + (bytes - 1 - b);
        for (p, &v) in plane.iter().enumerate() {
            out[p * segments + offset] = v;
        }
    }
    Ok(out)
}

/// A JPEG-LS marker segment's 16-bit big-endian field at `i`.
fn be16(data: &[u8], i: usize) -> Option<u16> {
    data.get(i..i + 2).map(|b| u16::from_be_bytes([b[0], b[1]]))
}

/// The JPEG-LS headers (ITU-T T.87 C.2) against the DICOM header and what `pure_jpegls`
/// decodes: the frame header (SOF55: precision, lines, samples per line, components), the
/// preset parameters (LSE id 1: MAXVAL, T1..T3, RESET; ids 2..4 are mapping tables) and the
/// scan header (SOS: components, NEAR, interleave mode, point transform).
fn check_jls(data: &[u8], info: &ImageInfo) -> Result<(), Bad> {
    if data.get(..2) != Some(&[0xFF, 0xD8][..]) {
        return Err("the data does not start with a JPEG-LS SOI marker".into());
    }
    let (mut at, mut precision, mut maxval) = (2usize, None, 0u32);
    loop {
        let (Some(&ff), Some(&m)) = (data.get(at), data.get(at + 1)) else {
            return Err("the JPEG-LS data ends before its scan header (SOS)".into());
        };
        if ff != 0xFF {
            return Err(Bad::Invalid(format!("no JPEG-LS marker at byte {at}")));
        }
        let len = usize::from(be16(data, at + 2).ok_or("the JPEG-LS data ends inside a marker")?);
        let seg = data
            .get(at + 4..at + 2 + len.max(2))
            .filter(|_| len >= 2)
            .ok_or_else(|| {
                format!("the JPEG-LS marker segment at byte {at} is cut or too short")
            })?;
        let field = |i: usize| seg.get(i).copied().ok_or("a JPEG-LS header is too short");
        match m {
            0xF7 => {
                let p = u32::from(field(0)?);
                let y = u32::from(be16(seg, 1).ok_or("a JPEG-LS SOF55 header is too short")?);
                let x = u32::from(be16(seg, 3).ok_or("a JPEG-LS SOF55 header is too short")?);
                let nf = u32::from(field(5)?);
                if (y, x) != (info.rows, info.cols) || nf != info.samples_per_pixel {
                    return Err(Bad::Invalid(format!(
                        "the JPEG-LS frame is {x} x {y} with {nf} components, but Columns x Rows \
                         is {} x {} with SamplesPerPixel {}",
                        info.cols, info.rows, info.samples_per_pixel
                    )));
                }
                if !(2..=16).contains(&p) || p > info.bits {
                    return Err(Bad::Invalid(format!(
                        "the JPEG-LS precision is {p} bits, which does not fit BitsAllocated {}",
                        info.bits
                    )));
                }
                if nf != 1 {
                    return Err(Bad::Unsupported(format!(
                        "a {nf}-component JPEG-LS frame: pure_jpegls decodes single-component \
                         streams"
                    )));
                }
                precision = Some(p);
                maxval = (1u32 << p) - 1;
            }
            0xF8 => {
                let id = field(0)?;
                if id != 1 {
                    return Err(Bad::Unsupported(format!(
                        "a JPEG-LS preset segment of id {id} (mapping tables) is not decoded"
                    )));
                }
                let p = precision.ok_or("a JPEG-LS LSE segment before the frame header")?;
                let v = |i| {
                    be16(seg, i)
                        .map(u32::from)
                        .ok_or("a JPEG-LS LSE segment is too short")
                };
                let (mv, t1, t2, t3, reset) = (v(1)?, v(3)?, v(5)?, v(7)?, v(9)?);
                let full = (1u32 << p) - 1;
                if mv > full || reset < 3 || [t1, t2, t3].iter().any(|&t| t > mv.max(full)) {
                    return Err(Bad::Invalid(format!(
                        "JPEG-LS preset parameters MAXVAL {mv} T1 {t1} T2 {t2} T3 {t3} RESET \
                         {reset} do not fit {p}-bit samples"
                    )));
                }
                if mv > 0 {
                    maxval = mv;
                }
            }
            0xDD => {
                return Err(Bad::Unsupported(
                    "JPEG-LS restart intervals (DRI) are not decoded by pure_jpegls".into(),
                ))
            }
            0xDA => {
                precision.ok_or("the JPEG-LS scan comes before the frame header (SOF55)")?;
                let ns = usize::from(field(0)?);
                let near = u32::from(field(1 + 2 * ns)?);
                let ilv = field(2 + 2 * ns)?;
                let al = field(3 + 2 * ns)? & 0x0F;
                if ns != 1 || ilv != 0 {
                    return Err(Bad::Unsupported(format!(
                        "a JPEG-LS scan of {ns} components in interleave mode {ilv}: \
                         pure_jpegls decodes single-component scans"
                    )));
                }
                if near > (maxval / 2).min(255) {
                    return Err(Bad::Invalid(format!(
                        "the JPEG-LS scan's NEAR is {near}, over min(255, MAXVAL {maxval} / 2)"
                    )));
                }
                if al != 0 {
                    return Err(Bad::Unsupported(format!(
                        "a JPEG-LS point transform of {al} bits is not decoded"
                    )));
                }
                return Ok(());
            }
            0xD9 => return Err("the JPEG-LS data ends (EOI) before its scan".into()),
            0xC0..=0xCF if is_sof(m) => {
                return Err(Bad::Invalid(format!(
                    "a JPEG frame header (SOF marker {m:02X}) in JPEG-LS pixel data"
                )))
            }
            _ => {}
        }
        at += 2 + len;
    }
}

/// Decodes one JPEG-LS frame (headers checked by [`check_jls`]) to little-endian samples.
fn decode_jls(data: &[u8], info: &ImageInfo) -> Result<Vec<u8>, String> {
    let (px, _, _) = jpegls::decode(data, info.cols, info.rows).map_err(|e| e.to_string())?;
    Ok(if info.bits == 8 {
        px.iter().map(|&v| v as u8).collect()
    } else {
        px.iter().flat_map(|v| v.to_le_bytes()).collect()
    })
}

/// Whether a JPEG marker is a start of frame (SOF0-3, 5-7, 9-11, 13-15).
fn is_sof(m: u8) -> bool {
    matches!(m, 0xC0..=0xCF) && !matches!(m, 0xC4 | 0xC8 | 0xCC)
}

/// The JPEG frame header (SOF) against Rows, Columns, SamplesPerPixel and BitsAllocated;
/// `true` for a 12-bit sequential DCT frame (decoded by module `jpeg12`, not `jpeg-decoder`).
fn check_jpeg(data: &[u8], info: &ImageInfo) -> Result<bool, Bad> {
    if data.get(..2) != Some(&[0xFF, 0xD8][..]) {
        return Err("the data does not start with a JPEG SOI marker".into());
    }
    let mut at = 2usize;
    loop {
        let (Some(&ff), Some(&m)) = (data.get(at), data.get(at + 1)) else {
            return Err("the JPEG data ends before its frame header (SOF)".into());
        };
        if ff != 0xFF {
            return Err(Bad::Invalid(format!("no JPEG marker at byte {at}")));
        }
        if m == 0xFF {
            at += 1; // fill byte
            continue;
        }
        if matches!(m, 0x01 | 0xD0..=0xD7) {
            at += 2;
            continue;
        }
        let len = data
            .get(at + 2..at + 4)
            .map(|b| usize::from(u16::from_be_bytes([b[0], b[1]])))
            .ok_or("the JPEG data ends inside a marker segment")?;
        if m == 0xDA || m == 0xD9 {
            return Err("the JPEG data has no frame header (SOF) before its scan".into());
        }
        if is_sof(m) {
            let h = data
                .get(at + 4..at + 10)
                .ok_or("the JPEG data ends inside its frame header (SOF)")?;
            let (p, y, x, nf) = (
                u32::from(h[0]),
                u32::from(u16::from_be_bytes([h[1], h[2]])),
                u32::from(u16::from_be_bytes([h[3], h[4]])),
                u32::from(h[5]),
            );
            if (y, x) != (info.rows, info.cols) || nf != info.samples_per_pixel {
                return Err(Bad::Invalid(format!(
                    "the JPEG frame is {x} x {y} with {nf} components, but Columns x Rows is \
                     {} x {} with SamplesPerPixel {}",
                    info.cols, info.rows, info.samples_per_pixel
                )));
            }
            // SOF3, 7, 11, 15 are lossless; the others DCT-based.
            let twelve = p == 12 && matches!(m, 0xC0 | 0xC1);
            if !matches!(m, 0xC3 | 0xC7 | 0xCB | 0xCF) && p != 8 && !twelve {
                return Err(Bad::Unsupported(if p == 12 {
                    format!(
                        "a 12-bit progressive or arithmetic-coded JPEG frame (marker {m:02X}): \
                         Volux decodes 12-bit sequential Huffman-coded frames"
                    )
                } else {
                    format!(
                        "a {p}-bit DCT-based (lossy) JPEG frame: the JPEG standard's DCT \
                         processes are 8- or 12-bit"
                    )
                }));
            }
            if twelve && nf != 1 {
                return Err(Bad::Unsupported(format!(
                    "a 12-bit lossy JPEG frame of {nf} components: Volux decodes 12-bit grey"
                )));
            }
            if (p <= 8) != (info.bits == 8) || p > 16 {
                return Err(Bad::Invalid(format!(
                    "the JPEG precision is {p} bits, which does not fit BitsAllocated {}",
                    info.bits
                )));
            }
            return Ok(twelve);
        }
        if len < 2 {
            return Err(Bad::Invalid(format!(
                "a JPEG marker segment of length {len} at byte {at}"
            )));
        }
        at += 2 + len;
    }
}

/// The JP2 signature box (ISO/IEC 15444-1 I.5.1).
const JP2_SIGNATURE: [u8; 12] = [0, 0, 0, 12, b'j', b'P', b' ', b' ', 0x0D, 0x0A, 0x87, 0x0A];

/// The contiguous codestream box (`jp2c`) of a JP2 file, walked box by box (each box length
/// checked against the data); `None` when there is none.
fn jp2_codestream(data: &[u8]) -> Option<&[u8]> {
    let mut at = 0usize;
    while at + 8 <= data.len() {
        let len = u32::from_be_bytes(data[at..at + 4].try_into().ok()?) as usize;
        let kind = &data[at + 4..at + 8];
        let (head, len) = match len {
            0 => (8, data.len() - at),
            1 => {
                let l = u64::from_be_bytes(data.get(at + 8..at + 16)?.try_into().ok()?);
                (16, usize::try_from(l).ok()?)
            }
            l => (8, l),
        };
        if len < head || at.checked_add(len)? > data.len() {
            return None;
        }
        if kind == b"jp2c" {
            return Some(&data[at + head..at + len]);
        }
        at += len;
    }
    None
}

/// The JPEG 2000 image size (SIZ) against Rows, Columns, SamplesPerPixel and BitsAllocated.
/// The DICOM JPEG 2000 transfer syntaxes carry a bare codestream (PS3.5 A.4.4); some writers
/// (older GDCM) wrap it in a JP2 file, whose codestream box is checked instead (the decoder
/// reads either).
fn check_j2k(data: &[u8], info: &ImageInfo) -> Result<(), Bad> {
    if data.starts_with(&JP2_SIGNATURE) {
        let Some(cs) = jp2_codestream(data) else {
            return Err("the data is a JP2 file without a readable codestream box (jp2c)".into());
        };
        return check_j2k(cs, info);
    }
    if data.get(..4) != Some(&[0xFF, 0x4F, 0xFF, 0x51][..]) {
        return Err(
            "the data does not start with a JPEG 2000 codestream (SOC then SIZ markers)".into(),
        );
    }
    let u16_at = |i: usize| data.get(i..i + 2).map(|b| u16::from_be_bytes([b[0], b[1]]));
    let u32_at = |i: usize| {
        data.get(i..i + 4)
            .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
    };
    let short = || "the JPEG 2000 data ends inside its SIZ marker segment".to_string();
    // SIZ: Lsiz Rsiz Xsiz Ysiz XOsiz YOsiz XTsiz YTsiz XTOsiz YTOsiz Csiz, then per component
    // Ssiz XRsiz YRsiz.
    let base = 4;
    let xsiz = u32_at(base + 4).ok_or_else(short)?;
    let ysiz = u32_at(base + 8).ok_or_else(short)?;
    let xo = u32_at(base + 12).ok_or_else(short)?;
    let yo = u32_at(base + 16).ok_or_else(short)?;
    let csiz = u16_at(base + 36).ok_or_else(short)?;
    let (w, h) = (xsiz.checked_sub(xo), ysiz.checked_sub(yo));
    if (w, h) != (Some(info.cols), Some(info.rows)) || u32::from(csiz) != info.samples_per_pixel {
        return Err(Bad::Invalid(format!(
            "the JPEG 2000 image is {} x {} with {csiz} components, but Columns x Rows is {} x \
             {} with SamplesPerPixel {}",
            i64::from(xsiz) - i64::from(xo),
            i64::from(ysiz) - i64::from(yo),
            info.cols,
            info.rows,
            info.samples_per_pixel
        )));
    }
    for c in 0..usize::from(csiz) {
        let at = base + 38 + 3 * c;
        let s = data.get(at..at + 3).ok_or_else(short)?;
        let precision = u32::from(s[0] & 0x7F) + 1;
        if precision > info.bits || (s[1], s[2]) != (1, 1) {
            return Err(Bad::Invalid(format!(
                "JPEG 2000 component {c} has {precision}-bit samples subsampled {} x {}, but \
                 BitsAllocated is {} (full-resolution components of at most that many bits \
                 are read)",
                s[1], s[2], info.bits
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(rows: u32, cols: u32, bits: u32) -> ImageInfo {
        ImageInfo {
            path: "t.dcm".into(),
            transfer_syntax: String::new(),
            series_uid: String::new(),
            rows,
            cols,
            bits,
            bits_stored: bits,
            signed: false,
            samples_per_pixel: 1,
            photometric: "MONOCHROME2".into(),
            frames: 1,
            frames_stated: None,
            position: None,
            orientation: None,
            instance: None,
            pixel_spacing: None,
            spacing_between: None,
            thickness: None,
            rescale: (1.0, 0.0),
            planar: false,
            dose_scaling: None,
            key: Default::default(),
        }
    }

    fn msg<T>(r: Result<T, Bad>) -> String {
        match r {
            Ok(_) => panic!("accepted"),
            Err(Bad::Invalid(m)) => format!("invalid: {m}"),
            Err(Bad::Unsupported(m)) => format!("unsupported: {m}"),
        }
    }

    /// SOI, a DQT-like segment, then a SOF of marker `m`.
    fn jpeg(m: u8, p: u8, y: u16, x: u16, nf: u8) -> Vec<u8> {
        let mut v = vec![
            0xFF, 0xD8, 0xFF, 0xDB, 0x00, 0x04, 0xAA, 0xBB, 0xFF, m, 0x00, 0x0B, p,
        ];
        v.extend_from_slice(&y.to_be_bytes());
        v.extend_from_slice(&x.to_be_bytes());
        v.extend_from_slice(&[nf, 1, 0x11, 0]);
        v
    }

    #[test]
    fn jpeg_frame_header_against_the_dicom_header() {
        let i = info(32, 16, 16);
        assert!(!check_jpeg(&jpeg(0xC3, 12, 32, 16, 1), &i).unwrap());
        assert!(msg(check_jpeg(&jpeg(0xC3, 12, 33, 16, 1), &i)).contains("16 x 33"));
        assert!(msg(check_jpeg(&jpeg(0xC3, 12, 32, 16, 3), &i)).contains("3 components"));
        // 8-bit precision in 16-bit samples, 16-bit in 8-bit: refused.
        assert!(msg(check_jpeg(&jpeg(0xC3, 8, 32, 16, 1), &i)).contains("precision"));
        assert!(
            msg(check_jpeg(&jpeg(0xC3, 16, 32, 16, 1), &info(32, 16, 8))).contains("precision")
        );
        // 12-bit sequential DCT: Volux's own decoder; progressive 12-bit, 12-bit colour and
        // 16-bit DCT: unsupported, not invalid.
        assert!(check_jpeg(&jpeg(0xC1, 12, 32, 16, 1), &i).unwrap());
        assert!(msg(check_jpeg(&jpeg(0xC2, 12, 32, 16, 1), &i)).starts_with("unsupported"));
        assert!(msg(check_jpeg(&jpeg(0xC1, 16, 32, 16, 1), &i)).contains("16-bit DCT"));
        let mut rgb = info(32, 16, 16);
        rgb.samples_per_pixel = 3;
        assert!(msg(check_jpeg(&jpeg(0xC1, 12, 32, 16, 3), &rgb)).contains("3 components"));
        assert!(!check_jpeg(&jpeg(0xC0, 8, 32, 16, 1), &info(32, 16, 8)).unwrap());
        // Cut anywhere before the SOF's fields: a clear error.
        let full = jpeg(0xC3, 12, 32, 16, 1);
        for n in 0..full.len() - 4 {
            assert!(check_jpeg(&full[..n], &i).is_err(), "{n}");
        }
        // No SOF before the scan; a zero-length segment.
        let sos = [0xFF, 0xD8, 0xFF, 0xDA, 0x00, 0x08];
        assert!(msg(check_jpeg(&sos, &i)).contains("no frame header"));
        let zero = [0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x00, 0xFF, 0xC3];
        assert!(msg(check_jpeg(&zero, &i)).contains("length 0"));
    }

    /// SOC, SIZ of one component.
    fn j2k(w: u32, h: u32, xo: u32, ssiz: u8, sub: u8) -> Vec<u8> {
        let mut v = vec![0xFF, 0x4F, 0xFF, 0x51, 0x00, 0x29, 0x00, 0x00];
        for x in [w, h, xo, 0, w, h, 0, 0] {
            v.extend_from_slice(&x.to_be_bytes());
        }
        v.extend_from_slice(&1u16.to_be_bytes());
        v.extend_from_slice(&[ssiz, sub, 1]);
        v
    }

    #[test]
    fn j2k_image_size_against_the_dicom_header() {
        let i = info(20, 30, 16);
        check_j2k(&j2k(30, 20, 0, 11, 1), &i).unwrap();
        check_j2k(&j2k(35, 20, 5, 15, 1), &i).unwrap();
        assert!(msg(check_j2k(&j2k(31, 20, 0, 11, 1), &i)).contains("31 x 20"));
        // An offset past the size: negative width, no overflow.
        assert!(msg(check_j2k(&j2k(3, 20, 9, 11, 1), &i)).contains("-6 x 20"));
        assert!(msg(check_j2k(&j2k(30, 20, 0, 16, 1), &i)).contains("17-bit"));
        assert!(msg(check_j2k(&j2k(30, 20, 0, 11, 2), &i)).contains("subsampled 2 x 1"));
        let full = j2k(30, 20, 0, 11, 1);
        for n in 0..full.len() {
            assert!(check_j2k(&full[..n], &i).is_err(), "{n}");
        }
        // A JP2 file (boxes) without a codestream box, and one holding the codestream.
        assert!(msg(check_j2k(b"\0\0\0\x0CjP  \r\n\x87\n", &i)).contains("jp2c"));
        let cs = j2k(30, 20, 0, 11, 1);
        let mut jp2 = JP2_SIGNATURE.to_vec();
        jp2.extend_from_slice(&(8 + cs.len() as u32).to_be_bytes());
        jp2.extend_from_slice(b"jp2c");
        jp2.extend_from_slice(&cs);
        check_j2k(&jp2, &i).unwrap();
        // A box longer than the data.
        jp2[12..16].copy_from_slice(&1000u32.to_be_bytes());
        assert!(msg(check_j2k(&jp2, &i)).contains("jp2c"));
    }

    #[test]
    fn rle_header_and_segment_lengths() {
        let i = info(2, 3, 16);
        // Two segments of 6 bytes: a literal of 6, and a run of 6.
        let mut v = vec![0u8; 64];
        v[0..4].copy_from_slice(&2u32.to_le_bytes());
        v[4..8].copy_from_slice(&64u32.to_le_bytes());
        v[8..12].copy_from_slice(&71u32.to_le_bytes());
        v.extend_from_slice(&[5, 1, 2, 3, 4, 5, 6]);
        v.extend_from_slice(&[(257u16 - 6) as u8, 9]);
        check_rle(&v, &i).unwrap();
        // A pad byte ending a segment is accepted (a no-op, or one byte more); two more
        // bytes are not.
        let mut padded = v.clone();
        padded.push(0x80);
        check_rle(&padded, &i).unwrap();
        let mut more = v.clone();
        more.extend_from_slice(&[1, 7, 7]);
        assert!(msg(check_rle(&more, &i)).contains("unpacks to 8 bytes"));
        // A run cut by the end of the segment does not count.
        assert!(msg(check_rle(&v[..v.len() - 1], &i)).contains("unpacks to 0 bytes"));
        let mut one = v.clone();
        one[0] = 1;
        assert!(msg(check_rle(&one, &i)).contains("lists 1 segments"));
        let mut back = v.clone();
        back[8..12].copy_from_slice(&10u32.to_le_bytes());
        assert!(msg(check_rle(&back, &i)).contains("segment 2 starts at byte 10"));
        assert!(check_rle(&v[..40], &i).is_err());
    }

    #[test]
    fn frames_from_fragments() {
        let (a, b, c): (&[u8], &[u8], &[u8]) = (b"aa", b"bbbb", b"cc");
        // One fragment per frame.
        assert_eq!(
            frame_data(&[a, b], &[], 2, 1).as_deref(),
            Some(&b"bbbb"[..])
        );
        assert_eq!(frame_data(&[a, b], &[], 2, 2), None);
        // Two frames over three fragments, by the offset table (item headers count 8).
        let f = [a, b, c];
        assert_eq!(frame_data(&f, &[0, 10], 2, 0).as_deref(), Some(&b"aa"[..]));
        assert_eq!(
            frame_data(&f, &[0, 10], 2, 1).as_deref(),
            Some(&b"bbbbcc"[..])
        );
        // No offset table: only frame 0 (all fragments) is found.
        assert_eq!(frame_data(&f, &[], 2, 0).as_deref(), Some(&b"aabbbbcc"[..]));
        assert_eq!(frame_data(&f, &[], 2, 1), None);
        // An offset past the data: an empty frame, which the decoders refuse.
        assert_eq!(
            frame_data(&f, &[0, u32::MAX], 2, 1).as_deref(),
            Some(&b""[..])
        );
    }

    /// SOI, SOF55 (precision, Y, X, one component), optionally an LSE, then SOS with NEAR,
    /// interleave mode and point transform.
    fn jls(p: u8, y: u16, x: u16, nf: u8, lse: Option<[u16; 5]>, near: u8, ilv: u8) -> Vec<u8> {
        let mut v = vec![0xFF, 0xD8, 0xFF, 0xF7, 0x00, 8 + 3 * nf, p];
        v.extend_from_slice(&y.to_be_bytes());
        v.extend_from_slice(&x.to_be_bytes());
        v.push(nf);
        for c in 0..nf {
            v.extend_from_slice(&[c + 1, 0x11, 0]);
        }
        if let Some(l) = lse {
            v.extend_from_slice(&[0xFF, 0xF8, 0x00, 13, 1]);
            for x in l {
                v.extend_from_slice(&x.to_be_bytes());
            }
        }
        v.extend_from_slice(&[0xFF, 0xDA, 0x00, 8, 1, 1, 0, near, ilv, 0]);
        v
    }

    #[test]
    fn jpeg_ls_headers_against_the_dicom_header() {
        let i = info(32, 16, 16);
        check_jls(&jls(12, 32, 16, 1, None, 0, 0), &i).unwrap();
        check_jls(&jls(16, 32, 16, 1, Some([4095, 0, 0, 0, 64]), 3, 0), &i).unwrap();
        assert!(msg(check_jls(&jls(12, 33, 16, 1, None, 0, 0), &i)).contains("16 x 33"));
        assert!(
            msg(check_jls(&jls(12, 32, 16, 1, None, 0, 0), &info(32, 16, 8)))
                .contains("precision is 12 bits")
        );
        assert!(msg(check_jls(&jls(17, 32, 16, 1, None, 0, 0), &i)).contains("precision"));
        // 8 bits stored in 16 allocated: read as 16-bit samples.
        check_jls(&jls(8, 32, 16, 1, None, 0, 0), &i).unwrap();
        // NEAR over MAXVAL / 2, a RESET under 3, MAXVAL over the precision: invalid.
        assert!(
            msg(check_jls(&jls(2, 32, 16, 1, None, 2, 0), &info(32, 16, 8))).contains("NEAR is 2")
        );
        assert!(msg(check_jls(
            &jls(12, 32, 16, 1, Some([4095, 0, 0, 0, 2]), 0, 0),
            &i
        ))
        .contains("RESET 2"));
        assert!(msg(check_jls(
            &jls(12, 32, 16, 1, Some([9000, 0, 0, 0, 64]), 0, 0),
            &i
        ))
        .contains("MAXVAL 9000"));
        // Three components, or an interleaved scan: unsupported (pure_jpegls), by name.
        let mut rgb = info(32, 16, 8);
        rgb.samples_per_pixel = 3;
        assert!(msg(check_jls(&jls(8, 32, 16, 3, None, 0, 1), &rgb))
            .starts_with("unsupported: a 3-component"));
        assert!(msg(check_jls(&jls(12, 32, 16, 1, None, 0, 2), &i))
            .starts_with("unsupported: a JPEG-LS scan of 1 components in interleave mode 2"));
        // Cut anywhere before the scan header's end: a clear error.
        let full = jls(12, 32, 16, 1, Some([4095, 0, 0, 0, 64]), 0, 0);
        for n in 0..full.len() {
            assert!(check_jls(&full[..n], &i).is_err(), "{n}");
        }
        // A JPEG (not JPEG-LS) frame header.
        let mut sof = jls(12, 32, 16, 1, None, 0, 0);
        sof[3] = 0xC3;
        assert!(msg(check_jls(&sof, &i)).contains("SOF marker C3"));
    }

    /// A PackBits segment holding `bytes` as literal runs of at most 128.
    fn literal(bytes: &[u8]) -> Vec<u8> {
        bytes
            .chunks(128)
            .flat_map(|c| std::iter::once((c.len() - 1) as u8).chain(c.iter().copied()))
            .collect()
    }

    /// An RLE frame of `planes` byte planes.
    fn rle_frame(planes: &[Vec<u8>]) -> Vec<u8> {
        let segs: Vec<Vec<u8>> = planes.iter().map(|p| literal(p)).collect();
        let mut v = vec![0u8; 64];
        v[..4].copy_from_slice(&(segs.len() as u32).to_le_bytes());
        let mut at = 64u32;
        for (k, s) in segs.iter().enumerate() {
            v[4 + 4 * k..8 + 4 * k].copy_from_slice(&at.to_le_bytes());
            at += s.len() as u32;
        }
        for s in segs {
            v.extend_from_slice(&s);
        }
        v
    }

    /// RGB of 32-bit samples: 12 segments (R MSB..LSB, G..., B...) become interleaved
    /// little-endian samples R G B R G B (PS3.5 G.2, PlanarConfiguration 0).
    #[test]
    fn rle_32_bit_rgb_is_interleaved_little_endian() {
        let mut i = info(2, 3, 32);
        i.samples_per_pixel = 3;
        let value = |p: usize, s: usize| 0x0102_0304u32 * (p as u32 + 1) + 0x1000_0000 * s as u32;
        let planes: Vec<Vec<u8>> = (0..3)
            .flat_map(|s| {
                (0..4).map(move |b| {
                    (0..6)
                        .map(|p| (value(p, s) >> (24 - 8 * b)) as u8)
                        .collect()
                })
            })
            .collect();
        let frame = rle_frame(&planes);
        check_rle(&frame, &i).unwrap();
        let out = decode_rle(&frame, &i).unwrap();
        let want: Vec<u8> = (0..6)
            .flat_map(|p| (0..3).flat_map(move |s| value(p, s).to_le_bytes()))
            .collect();
        assert_eq!(out, want);
        // Repeat runs and a pad byte decode the same.
        let mut runs = info(2, 3, 8);
        runs.samples_per_pixel = 1;
        let mut f = vec![0u8; 64];
        f[..4].copy_from_slice(&1u32.to_le_bytes());
        f[4..8].copy_from_slice(&64u32.to_le_bytes());
        f.extend_from_slice(&[(257u16 - 4) as u8, 9, 1, 5, 6, 0x80]);
        assert_eq!(decode_rle(&f, &runs).unwrap(), [9, 9, 9, 9, 5, 6]);
        // 4 bytes x 4 samples: more than the 15 segments of an RLE header.
        let mut cmyk = info(2, 3, 32);
        cmyk.samples_per_pixel = 4;
        assert!(msg(check_rle(&frame, &cmyk)).contains("15"));
    }

    /// The committed RGB 32-bit RLE fixture (pydicom's RLE frame encoder) decodes to its
    /// native original's bytes, through the whole codec path.
    #[test]
    fn rle_rgb32_fixture_matches_its_original() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/dicom_compressed");
        let rle = dir.join("rgb32_rle.dcm");
        let info = super::super::scan(&rle).unwrap().unwrap();
        assert_eq!((info.samples_per_pixel, info.bits), (3, 32));
        let obj = dicom_object::open_file(&rle).unwrap();
        let frame = u64::from(info.rows * info.cols * 3 * 4);
        let got = decode(&rle, &obj, &info, 1, frame).unwrap();
        let native = dicom_object::open_file(dir.join("rgb32_native.dcm")).unwrap();
        let want = native
            .element(tags::PIXEL_DATA)
            .unwrap()
            .to_bytes()
            .unwrap();
        assert_eq!(&got[..], &want[..]);
    }
}
