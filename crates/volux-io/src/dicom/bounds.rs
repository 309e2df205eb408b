//! Element lengths checked against the file before `dicom-object` parses it.
//!
//! `dicom-parser` reserves and zero-fills each element's declared length before reading its
//! value, so a 10 KB file declaring a 4 GB element would take 4 GiB before failing. [`check`]
//! walks the element headers first (the file meta group in explicit VR little endian, then
//! the data set in its transfer syntax), skipping values with seeks, and refuses any defined
//! length that passes the end of the file: the PixelData element as
//! [`ErrorKind::Truncated`], any other as [`ErrorKind::Invalid`] naming the tag.
//!
//! Sequences and items are walked into, so nested elements are checked too; encapsulated
//! pixel data fragments are skipped. In implicit VR a defined-length value is walked into
//! when it starts with an item tag (a sequence), else skipped. The walk reads headers as the
//! parser does: an unknown VR has the long (4-byte) length form, and the content of an
//! undefined-length element other than pixel data is in the file's transfer syntax. An
//! undefined-length `UN` element of an explicit-VR file holds implicit-VR items (PS3.5
//! 6.2.2), which the parser misreads as explicit VR: it is refused here, naming the element,
//! rather than after the parser has allocated a misread length.
//!
//! A Deflated Explicit VR Little Endian file (1.2.840.10008.1.2.1.99) holds its data set as
//! a raw deflate stream after the file meta group: it is inflated here, at most the memory
//! budget's worth (a decompression bomb stops there with [`ErrorKind::Inflates`]), and the
//! inflated data set is walked the same way, each length checked against the inflated size.
//! `dicom-object` then inflates it again as it parses (through `flate2`, pure Rust).
use std::io::{BufReader, Cursor, Read, Seek, SeekFrom};
use std::path::Path;

use super::ts::{EXPLICIT_BE, IMPLICIT_LE};
use crate::error::{ErrorKind, ReadError, Result};
use crate::util::{file_len, io_error, open_regular};

/// An undefined length (sequences, items, encapsulated pixel data).
const UNDEFINED: u32 = u32::MAX;

/// The PixelData tag.
const PIXEL_DATA: (u16, u16) = (0x7FE0, 0x0010);

/// Deflated Explicit VR Little Endian: the data set is a deflate stream.
const DEFLATED: &str = "1.2.840.10008.1.2.1.99";

/// Explicit VRs whose length is 2 bytes (PS3.5 7.1.2, Table 7.1-2); every other VR, an
/// unknown one included (read as `UN` by the parser), has 2 reserved bytes and a 4-byte
/// length.
const SHORT_VRS: [&[u8; 2]; 21] = [
    b"AE", b"AS", b"AT", b"CS", b"DA", b"DS", b"DT", b"FL", b"FD", b"IS", b"LO", b"LT", b"PN",
    b"SH", b"SL", b"SS", b"ST", b"TM", b"UI", b"UL", b"US",
];

/// One element header.
struct Header {
    tag: (u16, u16),
    vr: Option<[u8; 2]>,
    len: u32,
}

/// A cursor over the file's element headers (or over an inflated data set).
struct Walker<'a, R> {
    path: &'a Path,
    r: R,
    /// What the lengths are checked against, in messages: "the file".
    place: &'static str,
    pos: u64,
    len: u64,
    explicit: bool,
    little: bool,
    /// Inside encapsulated pixel data: items are fragments, skipped whole.
    fragments: bool,
}

impl<R: Read + Seek> Walker<'_, R> {
    /// Bytes left after the current position.
    fn left(&self) -> u64 {
        self.len.saturating_sub(self.pos)
    }

    /// Reads `N` bytes (the caller has checked they are there).
    fn bytes<const N: usize>(&mut self) -> Result<[u8; N]> {
        let mut b = [0u8; N];
        self.r
            .read_exact(&mut b)
            .map_err(|e| io_error(self.path, e))?;
        self.pos += N as u64;
        Ok(b)
    }

    fn u16(&mut self) -> Result<u16> {
        let b = self.bytes::<2>()?;
        Ok(if self.little {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        })
    }

    fn u32(&mut self) -> Result<u32> {
        let b = self.bytes::<4>()?;
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    /// Moves `n` bytes forward.
    fn skip(&mut self, n: u64) -> Result<()> {
        let n = i64::try_from(n).unwrap_or(i64::MAX);
        self.r
            .seek_relative(n)
            .map_err(|e| io_error(self.path, e))?;
        self.pos = self.pos.saturating_add(n as u64);
        Ok(())
    }

    /// The next `N` bytes without consuming them, if present.
    fn peek<const N: usize>(&mut self) -> Result<Option<[u8; N]>> {
        if self.left() < N as u64 {
            return Ok(None);
        }
        let b = self.bytes::<N>()?;
        self.r
            .seek_relative(-(N as i64))
            .map_err(|e| io_error(self.path, e))?;
        self.pos -= N as u64;
        Ok(Some(b))
    }

    /// The next 4 bytes without consuming them, if present.
    fn peek4(&mut self) -> Result<Option<[u8; 4]>> {
        self.peek::<4>()
    }

    /// An error when the undefined-length `UN` element `h` of an explicit-VR data set holds
    /// its items in implicit VR, as PS3.5 6.2.2 has them: the parser reads them in the file's
    /// explicit VR, so every length after would be misread.
    fn implicit_un_sequence(&mut self, h: &Header) -> Result<()> {
        let Some(b) = self.peek::<14>()? else {
            return Ok(());
        };
        let item = [0xFE, 0xFF, 0x00, 0xE0];
        let item_len = u32::from_le_bytes([b[4], b[5], b[6], b[7]]);
        if b[..4] != item || item_len == 0 || (b[8..10] == [0xFE, 0xFF]) {
            return Ok(());
        }
        if b[12].is_ascii_uppercase() && b[13].is_ascii_uppercase() {
            return Ok(());
        }
        Err(ReadError::new(
            self.path,
            ErrorKind::Unsupported(format!(
                "element ({:04X},{:04X}) has VR UN and an undefined length, so its items are in \
                 implicit VR (PS3.5 6.2.2), which the DICOM parser (dicom-rs) reads as explicit \
                 VR",
                h.tag.0, h.tag.1
            )),
        ))
    }

    /// The next element header; `None` where fewer bytes than a header are left (the parser
    /// reports those).
    fn header(&mut self) -> Result<Option<Header>> {
        if self.left() < 8 {
            return Ok(None);
        }
        let tag = (self.u16()?, self.u16()?);
        if tag.0 == 0xFFFE || !self.explicit {
            let len = self.u32()?;
            return Ok(Some(Header { tag, vr: None, len }));
        }
        let vr = self.bytes::<2>()?;
        let len = if !SHORT_VRS.contains(&&vr) {
            if self.left() < 6 {
                return Ok(None);
            }
            self.skip(2)?;
            self.u32()?
        } else {
            u32::from(self.u16()?)
        };
        Ok(Some(Header {
            tag,
            vr: Some(vr),
            len,
        }))
    }

    /// An error unless `h`'s value fits in the rest of the file.
    fn check_len(&self, h: &Header) -> Result<()> {
        let (len, left) = (u64::from(h.len), self.left());
        if len <= left {
            return Ok(());
        }
        if h.tag == PIXEL_DATA {
            return Err(ReadError::new(
                self.path,
                ErrorKind::Truncated {
                    expected: len,
                    found: left,
                },
            ));
        }
        Err(ReadError::new(
            self.path,
            ErrorKind::Invalid(format!(
                "element ({:04X},{:04X}) declares {len} bytes, but only {left} bytes are left in \
                 {}",
                h.tag.0, h.tag.1, self.place
            )),
        ))
    }

    /// Whether the defined-length value of `h` holds elements to walk into.
    fn is_sequence(&mut self, h: &Header) -> Result<bool> {
        if h.tag.0 == 0xFFFE {
            // An item of a sequence holds elements; a fragment holds pixel bytes.
            return Ok(h.tag.1 == 0xE000 && !self.fragments);
        }
        match h.vr {
            Some(vr) => Ok(&vr == b"SQ"),
            None => {
                let item: [u8; 4] = if self.little {
                    [0xFE, 0xFF, 0x00, 0xE0]
                } else {
                    [0xFF, 0xFE, 0xE0, 0x00]
                };
                Ok(h.len > 0 && self.peek4()? == Some(item))
            }
        }
    }

    /// Walks the element headers to the end of the file, or to the first tag `keep` refuses.
    fn walk(&mut self, keep: impl Fn((u16, u16)) -> bool) -> Result<()> {
        loop {
            let at = self.pos;
            let Some(h) = self.header()? else {
                return Ok(());
            };
            if !keep(h.tag) {
                self.r
                    .seek(SeekFrom::Start(at))
                    .map_err(|e| io_error(self.path, e))?;
                self.pos = at;
                return Ok(());
            }
            self.step(&h)?;
        }
    }

    /// Handles one header: checks its length and skips or enters its value.
    fn step(&mut self, h: &Header) -> Result<()> {
        if h.tag == (0xFFFE, 0xE0DD) {
            self.fragments = false;
        }
        if h.len == UNDEFINED {
            if self.explicit && self.little && h.vr == Some(*b"UN") {
                self.implicit_un_sequence(h)?;
            }
            self.fragments |= h.tag == PIXEL_DATA;
            return Ok(());
        }
        self.check_len(h)?;
        if !self.is_sequence(h)? {
            self.skip(u64::from(h.len))?;
        }
        Ok(())
    }

    /// Reads the value of `h` (a short string) after checking its length.
    fn text(&mut self, h: &Header) -> Result<String> {
        self.check_len(h)?;
        let mut v = vec![0u8; h.len.min(256) as usize];
        self.r
            .read_exact(&mut v)
            .map_err(|e| io_error(self.path, e))?;
        self.pos += v.len() as u64;
        self.skip(u64::from(h.len) - v.len() as u64)?;
        Ok(String::from_utf8_lossy(&v)
            .trim_end_matches(['\0', ' '])
            .to_string())
    }
}

/// Walks the file meta group (explicit VR little endian) and returns the transfer syntax.
fn meta_group<R: Read + Seek>(w: &mut Walker<'_, R>) -> Result<String> {
    let mut ts = String::new();
    while w.left() >= 8 {
        let at = w.pos;
        let Some(h) = w.header()? else { break };
        if h.tag.0 != 0x0002 {
            w.r.seek(SeekFrom::Start(at))
                .map_err(|e| io_error(w.path, e))?;
            w.pos = at;
            break;
        }
        if h.tag == (0x0002, 0x0010) {
            ts = w.text(&h)?;
        } else {
            w.step(&h)?;
        }
    }
    Ok(ts)
}

/// Checks every element length of the DICOM file `path` (a regular file with the 128-byte
/// preamble and `DICM`) against the bytes left in the file, before anything is allocated.
pub(super) fn check(path: &Path) -> Result<()> {
    check_with(path, false)
}

/// Checks the element lengths of the header of `path`, up to its PixelData element (whose
/// value is not read when a file is scanned): a file cut inside its pixel data passes.
pub(super) fn check_header(path: &Path) -> Result<()> {
    check_with(path, true)
}

fn check_with(path: &Path, header_only: bool) -> Result<()> {
    let file = open_regular(path)?;
    let len = file_len(path, &file)?;
    let mut w = Walker {
        path,
        r: BufReader::new(file),
        place: "the file",
        pos: 0,
        len,
        explicit: true,
        little: true,
        fragments: false,
    };
    if len < 132 {
        return Ok(());
    }
    w.skip(132)?;
    let ts = meta_group(&mut w)?;
    if ts == DEFLATED {
        return check_deflated(path, w.r);
    }
    w.explicit = ts != IMPLICIT_LE;
    w.little = ts != EXPLICIT_BE;
    if w.explicit {
        implicit_data_set(&mut w, &ts)?;
    }
    w.walk(|tag| !(header_only && tag == PIXEL_DATA))
}

/// An error when a data set whose transfer syntax says explicit VR starts with an element
/// whose VR is not two capital letters but whose bytes read as an implicit-VR header: the
/// writer encoded the data set in implicit VR (pydicom guesses so and reads it; the parser
/// follows the transfer syntax and would misread every length).
fn implicit_data_set<R: Read + Seek>(w: &mut Walker<'_, R>, ts: &str) -> Result<()> {
    if w.left() < 8 {
        return Ok(());
    }
    let at = w.pos;
    let head = w.bytes::<8>()?;
    w.r.seek(SeekFrom::Start(at))
        .map_err(|e| io_error(w.path, e))?;
    w.pos = at;
    let vr_like = head[4].is_ascii_uppercase() && head[5].is_ascii_uppercase();
    let len = u32::from_le_bytes([head[4], head[5], head[6], head[7]]);
    if vr_like || !w.little || u64::from(len) > w.left() - 8 {
        return Ok(());
    }
    Err(ReadError::new(
        w.path,
        ErrorKind::Invalid(format!(
            "the data set is encoded in implicit VR, but its transfer syntax {ts} ({}) is an \
             explicit-VR one (its first element ({:04X},{:04X}) has no VR)",
            super::ts::ts_name(ts),
            u16::from_le_bytes([head[0], head[1]]),
            u16::from_le_bytes([head[2], head[3]])
        )),
    ))
}

/// Inflates the data set that follows the file meta group (at most the memory budget) and
/// walks its element headers (explicit VR little endian).
fn check_deflated(path: &Path, rest: impl Read) -> Result<()> {
    let limit = volux_core::limits::memory_limit();
    let data = crate::util::read_to_limit(
        path,
        flate2::read::DeflateDecoder::new(rest),
        limit,
        "the deflated data set",
        || "the memory budget".into(),
    )
    .map_err(|e| match e.kind {
        ErrorKind::Io(io) => ReadError::new(
            path,
            ErrorKind::Invalid(format!(
                "the deflated data set (transfer syntax {DEFLATED}) cannot be inflated: {io}"
            )),
        ),
        _ => e,
    })?;
    let mut w = Walker {
        path,
        len: data.len() as u64,
        r: Cursor::new(data),
        place: "the inflated data set",
        pos: 0,
        explicit: true,
        little: true,
        fragments: false,
    };
    w.walk(|_| true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dicom_core::{DataElement, PrimitiveValue, VR};
    use dicom_dictionary_std::tags;

    /// The shared multi-frame file, or `None` (with a message) when the data is absent.
    fn emri() -> Option<std::path::PathBuf> {
        let p = volux_testkit::data::shared("pydicom_emri_small/emri_small.dcm");
        if p.is_none() {
            eprintln!("skipped: pydicom_emri_small is absent");
        }
        p
    }

    /// Byte offset of the first `needle` in `hay`.
    fn find(hay: &[u8], needle: &[u8]) -> usize {
        hay.windows(needle.len()).position(|w| w == needle).unwrap()
    }

    #[test]
    fn valid_files_pass() {
        let Some(p) = emri() else { return };
        check(&p).unwrap();
        let dir = tempfile::tempdir().unwrap();
        for ts in [IMPLICIT_LE, EXPLICIT_BE] {
            let mut obj = dicom_object::open_file(&p).unwrap();
            obj.meta_mut().transfer_syntax = ts.to_string();
            let out = dir.path().join("re.dcm");
            obj.write_to_file(&out).unwrap();
            check(&out).unwrap();
        }
    }

    #[test]
    fn a_huge_declared_element_is_refused_before_parsing() {
        let Some(p) = emri() else { return };
        let dir = tempfile::tempdir().unwrap();
        // A long text element whose 4-byte length is patched to almost 4 GB.
        let mut obj = dicom_object::open_file(&p).unwrap();
        obj.put(DataElement::new(
            tags::PATIENT_COMMENTS,
            VR::LT,
            PrimitiveValue::from("hostile"),
        ));
        obj.put(DataElement::new(
            tags::DERIVATION_DESCRIPTION,
            VR::UT,
            PrimitiveValue::from("hostile!"),
        ));
        let out = dir.path().join("ut.dcm");
        obj.write_to_file(&out).unwrap();
        let mut bytes = std::fs::read(&out).unwrap();
        let at = find(&bytes, b"UT\0\0") + 4;
        bytes[at..at + 4].copy_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
        bytes.truncate(10_000);
        std::fs::write(&out, &bytes).unwrap();
        let e = check(&out).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("ut.dcm") && msg.contains("declares 4294967280 bytes"),
            "{msg}"
        );
        // The reader refuses it through the same check (the parser is never reached).
        let e = super::super::read(&out, None, Default::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("declares 4294967280 bytes"), "{e}");
        // A pixel data element declaring 4 GB is a truncated file.
        let mut bytes = std::fs::read(&p).unwrap();
        let at = find(&bytes, &[0xE0, 0x7F, 0x10, 0x00]) + 8;
        bytes[at..at + 4].copy_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
        let out = dir.path().join("px.dcm");
        std::fs::write(&out, &bytes).unwrap();
        let e = super::super::read(&out, None, Default::default()).unwrap_err();
        assert!(
            matches!(
                e.kind,
                ErrorKind::Truncated {
                    expected: 4294967280,
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn special_files_are_refused() {
        use crate::util::hostile::*;
        let dir = tempfile::tempdir().unwrap();
        let zero = zero_link(dir.path(), "z.dcm");
        assert_refused(
            super::super::read(&zero, None, Default::default()),
            "z.dcm",
            "(a character device)",
        );
        let looped = link_loop(dir.path(), "l.dcm");
        assert_refused(
            super::super::read(&looped, None, Default::default()),
            "l.dcm",
            "loop",
        );
        if let Some(f) = fifo(dir.path(), "f.dcm") {
            assert_refused(
                super::super::read(&f, None, Default::default()),
                "f.dcm",
                "(a FIFO)",
            );
        }
    }
}
