//! The bytes the `tiff` crate decodes from: a buffered file whose reads can be patched, so
//! that a page's `PhotometricInterpretation` reads as BlackIsZero while its samples are
//! decoded.
//!
//! The crate inverts MINISWHITE (photometric 0) samples itself (to `1 - v` for floats, and
//! refuses signed ones) and refuses PALETTE (photometric 3) pages, whose samples are indices.
//! Volux wants the stored samples in both cases, to apply its own inversion (the one its notes
//! name) and the ColorMap: [`Source::patch_photometric`] makes the current page's
//! `PhotometricInterpretation` entry read as 1 (BlackIsZero) until [`Source::clear`], and the
//! caller re-reads the page's directory through it before decoding. Nothing is written to
//! the file.
//!
//! [`jpeg_frame_size`] reads the frame size a JPEG-compressed strip or tile declares, so that
//! the reader can refuse, before the JPEG decoder allocates for it, one larger than the strip.
use std::fs::File;
use std::io::{self, BufReader, Read, Seek, SeekFrom};

/// A buffered file with byte ranges replaced on reading.
#[derive(Debug)]
pub struct Source {
    inner: BufReader<File>,
    pos: u64,
    patches: Vec<(u64, Vec<u8>)>,
    /// Whether the file is little-endian (`II`).
    pub little_endian: bool,
    /// Whether the file is BigTIFF (version 43: 8-byte offsets, 20-byte IFD entries).
    pub bigtiff: bool,
}

/// `PhotometricInterpretation`.
const PHOTOMETRIC: u16 = 262;
/// Most IFD entries scanned for the photometric entry (the crate reads at most this many).
const MAX_ENTRIES: u64 = 1 << 20;

impl Source {
    /// Wraps `file`, reading its header's byte order and version (an unknown header is left
    /// for the decoder to refuse).
    pub fn new(file: File) -> io::Result<Self> {
        let mut inner = BufReader::new(file);
        let mut head = [0u8; 4];
        let got = read_up_to(&mut inner, &mut head)?;
        inner.seek(SeekFrom::Start(0))?;
        let little_endian = got < 2 || &head[..2] != b"MM";
        let version = if little_endian {
            u16::from_le_bytes([head[2], head[3]])
        } else {
            u16::from_be_bytes([head[2], head[3]])
        };
        Ok(Self {
            inner,
            pos: 0,
            patches: Vec::new(),
            little_endian,
            bigtiff: got == 4 && version == 43,
        })
    }

    /// Makes the `PhotometricInterpretation` entry of the directory at `ifd` read as 1
    /// (BlackIsZero). Returns whether the entry was found with a SHORT or LONG value.
    pub fn patch_photometric(&mut self, ifd: u64) -> io::Result<bool> {
        let saved = self.pos;
        let found = self.find_entry(ifd, PHOTOMETRIC);
        self.seek(SeekFrom::Start(saved))?;
        let Some((at, ty)) = found? else {
            return Ok(false);
        };
        let bytes = match (ty, self.little_endian) {
            (3, true) => 1u16.to_le_bytes().to_vec(),
            (3, false) => 1u16.to_be_bytes().to_vec(),
            (4, true) => 1u32.to_le_bytes().to_vec(),
            (4, false) => 1u32.to_be_bytes().to_vec(),
            _ => return Ok(false),
        };
        self.patches.push((at, bytes));
        Ok(true)
    }

    /// Removes every patch.
    pub fn clear(&mut self) {
        self.patches.clear();
    }

    /// The file offset of the value of entry `tag` in the directory at `ifd`, and its type.
    fn find_entry(&mut self, ifd: u64, tag: u16) -> io::Result<Option<(u64, u16)>> {
        self.inner.seek(SeekFrom::Start(ifd))?;
        let (count, entry, value_at) = if self.bigtiff {
            (self.read_uint(8)?, 20u64, 12u64)
        } else {
            (self.read_uint(2)?, 12, 8)
        };
        let first = ifd + if self.bigtiff { 8 } else { 2 };
        for i in 0..count.min(MAX_ENTRIES) {
            let at = first + i * entry;
            self.inner.seek(SeekFrom::Start(at))?;
            if self.read_uint(2)? == u64::from(tag) {
                let ty = self.read_uint(2)? as u16;
                return Ok(Some((at + value_at, ty)));
            }
        }
        Ok(None)
    }

    /// An unsigned integer of `n` bytes in the file's byte order, from the inner reader.
    fn read_uint(&mut self, n: usize) -> io::Result<u64> {
        let mut b = [0u8; 8];
        self.inner.read_exact(&mut b[..n])?;
        let mut v = 0u64;
        for k in 0..n {
            let byte = if self.little_endian {
                b[n - 1 - k]
            } else {
                b[k]
            };
            v = (v << 8) | u64::from(byte);
        }
        Ok(v)
    }
}

/// Reads into `buf` until it is full or the reader ends; returns the bytes read.
fn read_up_to(r: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

impl Read for Source {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        let start = self.pos;
        let end = start + n as u64;
        for (at, bytes) in &self.patches {
            let p_end = at + bytes.len() as u64;
            let lo = start.max(*at);
            let hi = end.min(p_end);
            for o in lo..hi {
                buf[(o - start) as usize] = bytes[(o - at) as usize];
            }
        }
        self.pos = end;
        Ok(n)
    }
}

impl Seek for Source {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        self.pos = self.inner.seek(to)?;
        Ok(self.pos)
    }
}

/// The frame size (width, height) declared by the JPEG stream at `offset` (`len` bytes) of
/// `r`: the first SOF marker's. `None` when the stream holds no frame header before its scan
/// data, or ends first. The reader's position is restored.
pub fn jpeg_frame_size<R: Read + Seek>(
    r: &mut R,
    offset: u64,
    len: u64,
) -> io::Result<Option<(u32, u32)>> {
    let saved = r.stream_position()?;
    let found = scan_sof(r, offset, len);
    r.seek(SeekFrom::Start(saved))?;
    found
}

fn scan_sof<R: Read + Seek>(r: &mut R, offset: u64, len: u64) -> io::Result<Option<(u32, u32)>> {
    let end = offset.saturating_add(len);
    let mut at = offset;
    r.seek(SeekFrom::Start(at))?;
    let mut b2 = [0u8; 2];
    if read_up_to(r, &mut b2)? < 2 || b2 != [0xFF, 0xD8] {
        return Ok(None);
    }
    at += 2;
    while at + 4 <= end {
        r.seek(SeekFrom::Start(at))?;
        let mut m = [0u8; 4];
        if read_up_to(r, &mut m)? < 4 || m[0] != 0xFF {
            return Ok(None);
        }
        let marker = m[1];
        if marker == 0xFF {
            at += 1; // fill byte
            continue;
        }
        let seg = u64::from(u16::from_be_bytes([m[2], m[3]]));
        let is_sof = matches!(marker, 0xC0..=0xCF) && !matches!(marker, 0xC4 | 0xC8 | 0xCC);
        if is_sof {
            let mut f = [0u8; 5];
            if read_up_to(r, &mut f)? < 5 {
                return Ok(None);
            }
            let h = u32::from(u16::from_be_bytes([f[1], f[2]]));
            let w = u32::from(u16::from_be_bytes([f[3], f[4]]));
            return Ok(Some((w, h)));
        }
        if marker == 0xDA || marker == 0xD9 || seg < 2 {
            return Ok(None);
        }
        at += 2 + seg;
    }
    Ok(None)
}

/// The canvas size (width, height) declared by the WebP stream at `offset` (`len` bytes) of
/// `r`: from its first chunk, `VP8 ` (lossy), `VP8L` (lossless) or `VP8X` (extended). `None`
/// when it is not one of those. The reader's position is restored.
pub fn webp_frame_size<R: Read + Seek>(
    r: &mut R,
    offset: u64,
    len: u64,
) -> io::Result<Option<(u32, u32)>> {
    let saved = r.stream_position()?;
    r.seek(SeekFrom::Start(offset))?;
    let mut h = [0u8; 30];
    let got = read_up_to(r, &mut h)?.min(len.min(30) as usize);
    r.seek(SeekFrom::Start(saved))?;
    if got < 30 || &h[..4] != b"RIFF" || &h[8..12] != b"WEBP" {
        return Ok(None);
    }
    let d = &h[20..];
    let le16 = |b: &[u8]| u32::from(u16::from_le_bytes([b[0], b[1]]));
    let le24 = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], 0]);
    Ok(match &h[12..16] {
        b"VP8 " if d[3..6] == [0x9d, 0x01, 0x2a] => {
            Some((le16(&d[6..]) & 0x3fff, le16(&d[8..]) & 0x3fff))
        }
        b"VP8L" if d[0] == 0x2f => {
            let bits = u32::from_le_bytes([d[1], d[2], d[3], d[4]]);
            Some(((bits & 0x3fff) + 1, ((bits >> 14) & 0x3fff) + 1))
        }
        b"VP8X" => Some((le24(&d[4..]) + 1, le24(&d[7..]) + 1)),
        _ => None,
    })
}
