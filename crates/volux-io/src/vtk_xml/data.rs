//! `<DataArray>` payloads: `ascii`, `binary` (base64 inline) and `appended` (raw or base64),
//! each optionally split into zlib blocks by `vtkZLibDataCompressor`.
//!
//! Binary payloads start with a size header of `header_type` words (UInt32 or UInt64, in the
//! file's byte order): uncompressed, one word giving the byte count; compressed, the block
//! count, the block size, the size of the last block (0 = full) and each block's compressed
//! size. Base64 writers encode that header either together with the data or as its own base64
//! stream; both are accepted inline, and appended base64 is read as two streams.
use std::io::Read;

use base64::engine::general_purpose::{GeneralPurpose, GeneralPurposeConfig};
use base64::engine::DecodePaddingMode;
use base64::Engine;
use flate2::read::ZlibDecoder;

use super::tree::Elem;
use crate::cells::{NumType, Values};

/// Lenient base64 (padding optional, trailing bits allowed).
const B64: GeneralPurpose = GeneralPurpose::new(
    &base64::alphabet::STANDARD,
    GeneralPurposeConfig::new()
        .with_decode_padding_mode(DecodePaddingMode::Indifferent)
        .with_decode_allow_trailing_bits(true),
);

type R<T> = Result<T, String>;

/// How the file encodes binary payloads.
#[derive(Clone, Copy, Debug)]
pub struct Encoding<'a> {
    /// Byte order of values and header words.
    pub little: bool,
    /// Size of the header words (4 or 8).
    pub word: usize,
    /// Whether payloads are zlib-compressed.
    pub compressed: bool,
    /// The bytes after `_` in `<AppendedData>`, and whether they are raw (else base64).
    pub appended: Option<(&'a [u8], bool)>,
}

impl Encoding<'_> {
    fn word_at(&self, b: &[u8], i: usize) -> R<u64> {
        let s = i
            .checked_mul(self.word)
            .and_then(|a| b.get(a..a + self.word))
            .ok_or("the binary size header is cut short")?;
        let mut w = [0u8; 8];
        if self.little {
            w[..self.word].copy_from_slice(s);
            Ok(u64::from_le_bytes(w))
        } else {
            w[8 - self.word..].copy_from_slice(s);
            Ok(u64::from_be_bytes(w))
        }
    }

    /// Header length in bytes for the payload starting at `b` (needs the block count).
    fn header_len(&self, b: &[u8]) -> R<usize> {
        if !self.compressed {
            return Ok(self.word);
        }
        let nb = self.word_at(b, 0)?;
        (nb as usize)
            .checked_add(3)
            .and_then(|n| n.checked_mul(self.word))
            .filter(|_| nb < u32::MAX as u64)
            .ok_or_else(|| format!("absurd block count {nb}"))
    }

    /// Bytes of data that follow a header of `header_len(b)` bytes at `b`.
    fn data_len(&self, b: &[u8]) -> R<u64> {
        if !self.compressed {
            return self.word_at(b, 0);
        }
        let nb = self.word_at(b, 0)? as usize;
        (0..nb).try_fold(0u64, |acc, i| {
            Ok(acc.saturating_add(self.word_at(b, 3 + i)?))
        })
    }

    /// Bytes the header at `b` says the payload decodes to (inflated, for compressed data).
    fn declared_len(&self, b: &[u8]) -> R<u64> {
        if !self.compressed {
            return self.word_at(b, 0);
        }
        let nb = self.word_at(b, 0)?;
        let block = self.word_at(b, 1)?;
        let last = self.word_at(b, 2)?;
        Ok(match nb {
            0 => 0,
            _ => {
                (nb - 1)
                    .saturating_mul(block)
                    .saturating_add(if last == 0 { block } else { last })
            }
        })
    }

    /// The payload of a raw byte stream that starts with the size header. When the dataset
    /// says how many bytes the array must hold (`expected`), a header declaring another size
    /// is refused before anything is inflated or copied.
    fn payload(&self, b: &[u8], expected: Option<u64>) -> R<Vec<u8>> {
        let h = self.header_len(b)?;
        if let Some(want) = expected {
            let declared = self.declared_len(b)?;
            if declared != want {
                return Err(format!(
                    "the size header declares {declared} bytes, but the dataset's size asks for \
                     {want} bytes of values; nothing was decoded"
                ));
            }
        }
        let n = self.data_len(b)?;
        let data = b.get(h..).filter(|d| d.len() as u64 >= n).ok_or_else(|| {
            format!(
                "truncated: the size header announces {n} bytes, {} are present",
                b.len().saturating_sub(h)
            )
        })?;
        if !self.compressed {
            return Ok(data[..n as usize].to_vec());
        }
        self.inflate(b, data)
    }

    /// Decompresses the zlib blocks described by the header at `b`. The declared sizes are
    /// checked against what the compressed bytes can hold before anything is inflated, the
    /// output grows block by block, and a block inflating to more than announced stops.
    fn inflate(&self, b: &[u8], mut data: &[u8]) -> R<Vec<u8>> {
        let nb = self.word_at(b, 0)? as usize;
        let block = self.word_at(b, 1)?;
        let last = self.word_at(b, 2)?;
        let total = match nb {
            0 => 0,
            _ => (nb as u64 - 1)
                .saturating_mul(block)
                .saturating_add(if last == 0 { block } else { last }),
        };
        volux_core::limits::check_alloc("decompressed array", total, 1)
            .map_err(|e| e.to_string())?;
        check_inflatable(total, self.data_len(b)?)?;
        let mut out = Vec::with_capacity(total.min(FIRST_CHUNK) as usize);
        for i in 0..nb {
            let c = self.word_at(b, 3 + i)? as usize;
            let want = if i + 1 == nb && last != 0 {
                last
            } else {
                block
            };
            let (chunk, rest) = data.split_at(c.min(data.len()));
            data = rest;
            inflate_block(chunk, want, &mut out).map_err(|m| format!("zlib block {i}: {m}"))?;
        }
        Ok(out)
    }
}

/// Appends the `want` bytes the zlib `chunk` inflates to onto `out`; fewer or more is an
/// error, and inflation stops one byte after `want`.
fn inflate_block(chunk: &[u8], want: u64, out: &mut Vec<u8>) -> R<()> {
    check_inflatable(want, chunk.len() as u64)?;
    let mut z = ZlibDecoder::new(chunk);
    let got = (&mut z)
        .take(want)
        .read_to_end(out)
        .map_err(|e| e.to_string())?;
    if got as u64 != want {
        return Err(format!("holds {got} bytes, the header announces {want}"));
    }
    let mut more = [0u8; 1];
    if z.read(&mut more).map_err(|e| e.to_string())? > 0 {
        return Err(format!(
            "inflates to more than the {want} bytes the header announces; decoding stopped there"
        ));
    }
    Ok(())
}

/// First capacity of an inflated array; it grows as blocks are inflated.
const FIRST_CHUNK: u64 = 4 << 20;

/// An error unless `compressed` bytes of zlib data can inflate to `declared` bytes (deflate
/// expands at most 1032:1): a size header claiming 1 GiB for a few bytes is refused before
/// anything is inflated.
fn check_inflatable(declared: u64, compressed: u64) -> R<()> {
    let max = crate::util::max_inflated(compressed);
    if declared > max {
        return Err(format!(
            "the size header declares {declared} bytes, but {compressed} bytes of zlib data \
             inflate to at most {max} (deflate expands at most 1032:1)"
        ));
    }
    Ok(())
}

fn b64(chars: &[u8]) -> R<Vec<u8>> {
    B64.decode(chars).map_err(|e| format!("bad base64: {e}"))
}

/// Base64 characters needed for `n` bytes.
fn b64_len(n: usize) -> usize {
    n.div_ceil(3).saturating_mul(4)
}

impl Encoding<'_> {
    /// Decodes a header encoded as its own base64 stream followed by the data stream, reading
    /// at most the data the header announces; returns header + data bytes.
    fn split_streams(&self, chars: &[u8]) -> R<Vec<u8>> {
        let prefix = chars
            .get(..b64_len(self.word))
            .ok_or("base64 data too short")?;
        let h = self.header_len(&b64(prefix)?)?;
        let hc = chars.get(..b64_len(h)).ok_or("base64 header cut short")?;
        let mut bytes = b64(hc)?;
        bytes.truncate(h);
        let dl = usize::try_from(self.data_len(&bytes)?).map_err(|e| e.to_string())?;
        let rest = &chars[hc.len()..];
        let dc = rest.get(..b64_len(dl).min(rest.len())).unwrap_or(&[]);
        bytes.extend(b64(dc)?);
        Ok(bytes)
    }

    /// The payload of inline base64 text (whitespace removed).
    fn inline(&self, chars: &[u8], expected: Option<u64>) -> R<Vec<u8>> {
        let single = || b64(chars).and_then(|b| self.payload(&b, expected));
        let split = || {
            self.split_streams(chars)
                .and_then(|b| self.payload(&b, expected))
        };
        if self.compressed {
            split().or_else(|e| single().map_err(|_| e))
        } else {
            single().or_else(|e| split().map_err(|_| e))
        }
    }

    /// The payload at `offset` in the appended section.
    fn appended(&self, offset: usize, expected: Option<u64>) -> R<Vec<u8>> {
        let (bytes, raw) = self
            .appended
            .ok_or("format=\"appended\" but the file has no <AppendedData>")?;
        let at = bytes
            .get(offset..)
            .ok_or_else(|| format!("offset {offset} is beyond the appended data"))?;
        if raw {
            self.payload(at, expected)
        } else {
            self.split_streams(at)
                .and_then(|b| self.payload(&b, expected))
        }
    }
}

/// How many values a `<DataArray>` must hold, when the dataset says it.
#[derive(Clone, Copy, Debug)]
pub enum Expect {
    /// One tuple (of NumberOfComponents values) per point or cell.
    Tuples(u64),
    /// This many values, whatever NumberOfComponents says (the 3 x NumberOfPoints
    /// coordinates).
    Values(u64),
    /// Unknown (connectivity, whose length depends on the cell types).
    Unknown,
}

/// Decodes a `<DataArray>`: its values and number of components. A binary array whose size
/// header declares another size than `expect` asks for is refused before it is inflated, so
/// a small grid cannot make the reader inflate a bomb.
pub fn decode(e: &Elem, enc: &Encoding, expect: Expect) -> R<(Values, usize)> {
    let name = e.attr("Name").unwrap_or("(unnamed)");
    let t = e
        .attr("type")
        .ok_or_else(|| format!("array '{name}' has no type"))?;
    let ty = NumType::from_xml(t).ok_or_else(|| format!("array '{name}': unknown type '{t}'"))?;
    let ncomp = match e.attr("NumberOfComponents") {
        Some(s) => s
            .trim()
            .parse::<usize>()
            .ok()
            .filter(|&k| (1..=64).contains(&k))
            .ok_or_else(|| format!("array '{name}': bad NumberOfComponents '{s}'"))?,
        None => 1,
    };
    let format = e.attr("format").unwrap_or("ascii");
    let values = match expect {
        Expect::Tuples(t) => Some(t.saturating_mul(ncomp as u64)),
        Expect::Values(v) => Some(v),
        Expect::Unknown => None,
    };
    let expected = values.map(|v| v.saturating_mul(ty.size() as u64));
    let bytes = match format {
        "ascii" => return Ok((ascii(&e.text, ty, name)?, ncomp)),
        "binary" => {
            let chars: Vec<u8> = e
                .text
                .bytes()
                .filter(|b| !b.is_ascii_whitespace())
                .collect();
            enc.inline(&chars, expected)
        }
        "appended" => {
            let off = e.attr("offset").unwrap_or("0").trim();
            let off = off
                .parse::<usize>()
                .map_err(|_| format!("array '{name}': bad offset '{off}'"))?;
            enc.appended(off, expected)
        }
        f => return Err(format!("array '{name}': unknown format '{f}'")),
    }
    .map_err(|m| format!("array '{name}': {m}"))?;
    if bytes.len() % ty.size() != 0 {
        return Err(format!(
            "array '{name}': {} bytes is not a whole number of {} values",
            bytes.len(),
            ty.name()
        ));
    }
    Ok((Values::decode(&bytes, ty, enc.little), ncomp))
}

fn ascii(text: &str, ty: NumType, name: &str) -> R<Values> {
    let v = text
        .split_ascii_whitespace()
        .enumerate()
        .map(|(i, t)| {
            t.parse::<f64>()
                .map_err(|_| format!("array '{name}': value {i} '{t}' is not a number"))
        })
        .collect::<R<Vec<f64>>>()?;
    Ok(Values::from_f64(v, ty))
}
