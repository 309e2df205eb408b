//! Compressed (encapsulated) pixel data, decoded with `dicom-pixeldata` to the stored values.
//!
//! Only pure-Rust codecs are linked: RLE Lossless, JPEG baseline / extended / lossless
//! (`jpeg-decoder`) and JPEG 2000 (`openjp2`, the Rust port of OpenJPEG). JPEG-LS has no
//! pure-Rust decoder among `dicom-pixeldata`'s features (it goes through CharLS, a C++
//! library), so JPEG-LS files are [`ErrorKind::Unsupported`] naming the transfer syntax.
//!
//! The decoders size their output from Rows x Columns and copy what the codestream holds
//! into it, trusting the two to agree (a JPEG or JPEG 2000 frame larger than Rows x Columns
//! would overrun the buffer and panic, one that declares 65535 x 65535 would allocate
//! gigabytes). So before a frame is decoded its codestream header is read here and checked
//! against the DICOM header: the JPEG frame header (SOF: precision, lines, samples per line,
//! components), the JPEG 2000 image and tile size (SIZ: size, offset, components, precision,
//! subsampling) and the RLE header (segment count and offsets). The whole decoded size
//! (Rows x Columns x frames x bytes) is checked against the memory budget before the first
//! frame is decoded, and each decoded frame's length is checked before use.
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
        let checked = match fam {
            Family::Rle => check_rle(&data, info),
            Family::Jpeg => check_jpeg(&data, info),
            Family::Jpeg2000 => check_j2k(&data, info),
        };
        checked.map_err(|e| {
            let kind = match e {
                Bad::Invalid(m) => ErrorKind::Invalid(format!("{name} frame {}: {m}", i + 1)),
                Bad::Unsupported(m) => {
                    ErrorKind::Unsupported(format!("transfer syntax {ts} ({name}): {m}"))
                }
            };
            ReadError::new(path, kind)
        })?;
        let px = obj.decode_pixel_data_frame(i as u32).map_err(|e| {
            invalid(
                path,
                format!("cannot decode {name} frame {}: {}", i + 1, chain(&e)),
            )
        })?;
        let got = px.data();
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

/// Whether a JPEG marker is a start of frame (SOF0-3, 5-7, 9-11, 13-15).
fn is_sof(m: u8) -> bool {
    matches!(m, 0xC0..=0xCF) && !matches!(m, 0xC4 | 0xC8 | 0xCC)
}

/// The JPEG frame header (SOF) against Rows, Columns, SamplesPerPixel and BitsAllocated.
fn check_jpeg(data: &[u8], info: &ImageInfo) -> Result<(), Bad> {
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
            if !matches!(m, 0xC3 | 0xC7 | 0xCB | 0xCF) && p != 8 {
                return Err(Bad::Unsupported(format!(
                    "a {p}-bit DCT-based (lossy) JPEG frame: jpeg-decoder decodes 8-bit lossy \
                     and 2- to 16-bit lossless JPEG"
                )));
            }
            if (p <= 8) != (info.bits == 8) || p > 16 {
                return Err(Bad::Invalid(format!(
                    "the JPEG precision is {p} bits, which does not fit BitsAllocated {}",
                    info.bits
                )));
            }
            return Ok(());
        }
        if len < 2 {
            return Err(Bad::Invalid(format!(
                "a JPEG marker segment of length {len} at byte {at}"
            )));
        }
        at += 2 + len;
    }
}

/// The JPEG 2000 image size (SIZ) against Rows, Columns, SamplesPerPixel and BitsAllocated.
/// The DICOM JPEG 2000 transfer syntaxes carry a bare codestream (no JP2 boxes, PS3.5 A.4.4).
fn check_j2k(data: &[u8], info: &ImageInfo) -> Result<(), Bad> {
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

    fn msg(r: Result<(), Bad>) -> String {
        match r {
            Ok(()) => panic!("accepted"),
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
        check_jpeg(&jpeg(0xC3, 12, 32, 16, 1), &i).unwrap();
        assert!(msg(check_jpeg(&jpeg(0xC3, 12, 33, 16, 1), &i)).contains("16 x 33"));
        assert!(msg(check_jpeg(&jpeg(0xC3, 12, 32, 16, 3), &i)).contains("3 components"));
        // 8-bit precision in 16-bit samples, 16-bit in 8-bit: refused.
        assert!(msg(check_jpeg(&jpeg(0xC3, 8, 32, 16, 1), &i)).contains("precision"));
        assert!(
            msg(check_jpeg(&jpeg(0xC3, 16, 32, 16, 1), &info(32, 16, 8))).contains("precision")
        );
        // 12-bit DCT: unsupported (jpeg-decoder), not invalid.
        assert!(msg(check_jpeg(&jpeg(0xC1, 12, 32, 16, 1), &i)).starts_with("unsupported"));
        check_jpeg(&jpeg(0xC0, 8, 32, 16, 1), &info(32, 16, 8)).unwrap();
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
        // A JP2 file (boxes) instead of a bare codestream.
        assert!(msg(check_j2k(b"\0\0\0\x0CjP  \r\n\x87\n", &i)).contains("codestream"));
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
}
