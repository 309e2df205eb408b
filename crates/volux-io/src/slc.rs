//! VolVis SLC volumes (`.slc`, the format of `vtkSLCReader` and of classic data such as
//! Neghip): an ASCII header, an RGB icon, then the slices along z, each raw or run-length
//! encoded.
//!
//! Layout, as `vtkSLCReader` reads it (tokens separated by white space):
//! `11111` (magic), `nx ny nz bits` (bits per voxel, 8), `sx sy sz` (spacing), `unit origin
//! model compression` (only `compression` is used: 0 raw, 1 run-length), `icon_w icon_h X`
//! followed directly by the icon's red, green and blue planes (`icon_w icon_h` bytes each), then
//! per slice either `nx ny` raw bytes or `size X` followed directly by `size` run-length bytes.
//! A run-length byte `c` with `c & 0x7f = n`: `n = 0` ends the slice; `c & 0x80` copies the
//! next `n` bytes; otherwise the next byte is repeated `n` times.
//!
//! Every count is checked: a slice that decodes to more or fewer bytes than `nx ny`, a
//! truncated file or an unsupported voxel size is an error naming the file, never a panic.
//! No crate reads SLC; the format is a dozen lines of header and a byte-wise decoder.
use std::path::Path;

use volux_core::Grid;

use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::raw::{self, ElemType};
use crate::util::{header_err, read_regular};

/// The magic number that starts an SLC file.
pub const MAGIC: &str = "11111";

/// Whether `head` (the first bytes of a file) starts with the SLC magic number.
pub fn is_slc(head: &[u8]) -> bool {
    let text = head.trim_ascii_start();
    text.strip_prefix(MAGIC.as_bytes())
        .is_some_and(|rest| rest.first().is_some_and(u8::is_ascii_whitespace))
}

/// A cursor over the file's bytes that reads white-space separated tokens and raw bytes.
struct Cursor<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    /// The next token (after white space), for the header field `what`.
    fn token(&mut self, what: &str) -> Result<&'a str> {
        while self.bytes.get(self.at).is_some_and(u8::is_ascii_whitespace) {
            self.at += 1;
        }
        let start = self.at;
        while self
            .bytes
            .get(self.at)
            .is_some_and(|b| !b.is_ascii_whitespace() && *b != b'X')
        {
            self.at += 1;
        }
        let token = &self.bytes[start..self.at];
        if token.is_empty() {
            return Err(header_err(self.path, format!("no {what}")));
        }
        std::str::from_utf8(token).map_err(|_| header_err(self.path, format!("{what} is not text")))
    }

    /// The next token parsed as a number.
    fn number<T: std::str::FromStr>(&mut self, what: &str) -> Result<T> {
        let t = self.token(what)?;
        t.parse()
            .map_err(|_| header_err(self.path, format!("{what} '{t}' is not a number")))
    }

    /// Skips white space and the `X` that ends a size field; the data starts right after it.
    fn marker(&mut self, what: &str) -> Result<()> {
        while self.bytes.get(self.at).is_some_and(u8::is_ascii_whitespace) {
            self.at += 1;
        }
        if self.bytes.get(self.at) != Some(&b'X') {
            return Err(header_err(self.path, format!("no 'X' after {what}")));
        }
        self.at += 1;
        Ok(())
    }

    /// An error unless `n` more bytes are left.
    fn ensure(&self, n: u64) -> Result<()> {
        let left = (self.bytes.len() - self.at) as u64;
        if n > left {
            return Err(ReadError::new(
                self.path,
                ErrorKind::Truncated {
                    expected: n,
                    found: left,
                },
            ));
        }
        Ok(())
    }

    /// The next `n` bytes.
    fn take(&mut self, n: u64) -> Result<&'a [u8]> {
        self.ensure(n)?;
        let out = &self.bytes[self.at..self.at + n as usize];
        self.at += n as usize;
        Ok(out)
    }
}

/// Decodes one run-length encoded slice of `out.len()` bytes into `out`; the error names
/// what went wrong.
pub fn decode_rle(mut input: &[u8], out: &mut [u8]) -> std::result::Result<(), String> {
    let mut filled = 0;
    while let Some((&c, rest)) = input.split_first() {
        input = rest;
        let n = usize::from(c & 0x7f);
        if n == 0 {
            break;
        }
        if filled + n > out.len() {
            return Err(format!("runs exceed the slice's {} bytes", out.len()));
        }
        if c & 0x80 != 0 {
            let Some((run, rest)) = input.split_at_checked(n) else {
                return Err("a literal run is cut short".into());
            };
            out[filled..filled + n].copy_from_slice(run);
            input = rest;
        } else {
            let Some((&v, rest)) = input.split_first() else {
                return Err("a repeated run has no value".into());
            };
            out[filled..filled + n].fill(v);
            input = rest;
        }
        filled += n;
    }
    if filled != out.len() {
        return Err(format!("decodes to {filled} of {} bytes", out.len()));
    }
    Ok(())
}

/// The header fields Volux uses.
struct Header {
    dims: [usize; 3],
    spacing: [f64; 3],
    compressed: bool,
}

fn read_header(c: &mut Cursor<'_>) -> Result<Header> {
    let path = c.path;
    if c.token("magic number")? != MAGIC {
        return Err(header_err(
            path,
            "not an SLC file (magic number is not 11111)",
        ));
    }
    let mut dims = [0i64; 3];
    for (d, name) in dims.iter_mut().zip(["x size", "y size", "z size"]) {
        *d = c.number(name)?;
    }
    let (dims, _) = volux_core::limits::checked_dims(dims).map_err(|e| ReadError::new(path, e))?;
    let bits: u32 = c.number("bits per voxel")?;
    if bits != 8 {
        return Err(ReadError::new(
            path,
            ErrorKind::Unsupported(format!("{bits} bits per voxel (only 8)")),
        ));
    }
    let mut spacing = [0f64; 3];
    for (s, name) in spacing
        .iter_mut()
        .zip(["x spacing", "y spacing", "z spacing"])
    {
        *s = c.number(name)?;
    }
    for name in ["unit type", "data origin", "data model"] {
        c.number::<i64>(name)?;
    }
    let compressed = match c.number::<i64>("compression")? {
        0 => false,
        1 => true,
        k => {
            return Err(ReadError::new(
                path,
                ErrorKind::Unsupported(format!("compression type {k} (only 0 and 1)")),
            ))
        }
    };
    Ok(Header {
        dims,
        spacing,
        compressed,
    })
}

/// Largest output of one run-length pair: a count byte of 127 and the byte it repeats.
const MAX_RUN: u64 = 127;

/// Most bytes `encoded` run-length bytes can decode to: every byte pair a run of 127.
fn max_rle_output(encoded: u64) -> u64 {
    (encoded / 2).saturating_mul(MAX_RUN)
}

/// An [`ErrorKind::Undeliverable`] unless `encoded` run-length bytes can decode to
/// `declared` voxels.
fn check_deliverable(path: &Path, declared: u64, encoded: u64) -> Result<()> {
    let max = max_rle_output(encoded);
    if declared > max {
        return Err(ReadError::new(
            path,
            ErrorKind::Undeliverable {
                declared,
                available: encoded,
                max,
                how: "a run-length byte pair expands to at most 127 bytes",
            },
        ));
    }
    Ok(())
}

/// Skips the icon (`icon_w icon_h X` and three planes of `icon_w icon_h` bytes).
fn skip_icon(c: &mut Cursor<'_>) -> Result<()> {
    let icon_w: u64 = c.number("icon width")?;
    let icon_h: u64 = c.number("icon height")?;
    c.marker("the icon size")?;
    let icon = icon_w
        .checked_mul(icon_h)
        .and_then(|n| n.checked_mul(3))
        .ok_or_else(|| header_err(c.path, "icon size overflows"))?;
    c.take(icon)?;
    Ok(())
}

/// Decodes the run-length slices of `h` into a buffer that grows slice by slice; each slice
/// is checked against the bytes that encode it before it is allocated.
fn decode_slices(c: &mut Cursor<'_>, h: &Header) -> Result<Vec<u8>> {
    let path = c.path;
    let plane = h.dims[0] * h.dims[1];
    let mut voxels = Vec::new();
    for z in 0..h.dims[2] {
        let size: u64 = c.number("compressed slice size")?;
        c.marker("a compressed slice size")?;
        let encoded = c.take(size)?;
        check_deliverable(path, plane as u64, size)?;
        let start = voxels.len();
        voxels.resize(start + plane, 0);
        decode_rle(encoded, &mut voxels[start..])
            .map_err(|why| ReadError::new(path, ErrorKind::Invalid(format!("slice {z}: {why}"))))?;
    }
    Ok(voxels)
}

/// Reads an SLC file into an 8-bit grid.
///
/// The declared volume is bounded by what the file can deliver before anything is
/// allocated: raw slices need one byte per voxel, run-length slices at least two bytes per
/// 127 voxels ([`ErrorKind::Undeliverable`] otherwise), and run-length output grows slice by
/// slice as it is decoded.
pub fn read(path: &Path) -> Result<Grid> {
    let limit = volux_core::limits::memory_limit();
    let bytes = read_regular(path, limit)?;
    let mut c = Cursor {
        path,
        bytes: &bytes,
        at: 0,
    };
    let h = read_header(&mut c)?;
    skip_icon(&mut c)?;
    let count = (h.dims[0] * h.dims[1]) as u64 * h.dims[2] as u64;
    let left = bytes.len().saturating_sub(c.at) as u64;
    if h.compressed {
        check_deliverable(path, count, left)?;
    } else {
        // Raw slices end the file: a short one is refused before allocating.
        c.ensure(count)?;
    }
    volux_core::limits::check_alloc("data", count, 1).map_err(|e| ReadError::new(path, e))?;
    let data = if h.compressed {
        raw::decode(path, ElemType::U8, &decode_slices(&mut c, &h)?, true)?
    } else {
        raw::decode(path, ElemType::U8, c.take(count)?, true)?
    };
    raw::make_grid(path, h.dims, h.spacing, [0.0; 3], data, Vec::new())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An SLC file of `dims` with a 2 x 1 icon, its slices raw or run-length encoded.
    fn slc(dims: [usize; 3], compression: u8, slices: &[Vec<u8>]) -> Vec<u8> {
        let mut out = format!(
            "11111\n{} {} {} 8\n1.0 1.0 2.5\n1 6 0 {compression}\n2 1 X",
            dims[0], dims[1], dims[2]
        )
        .into_bytes();
        out.extend_from_slice(&[9; 6]);
        for s in slices {
            if compression == 1 {
                out.extend_from_slice(format!("{} X", s.len()).as_bytes());
            }
            out.extend_from_slice(s);
        }
        out
    }

    fn write(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("volux-slc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn run_lengths_decode_literal_and_repeated_runs() {
        let mut out = [0u8; 6];
        decode_rle(&[0x83, 1, 2, 3, 0x03, 7, 0], &mut out).unwrap();
        assert_eq!(out, [1, 2, 3, 7, 7, 7]);
        // The slice may end without a terminator.
        decode_rle(&[0x06, 4], &mut out).unwrap();
        assert_eq!(out, [4; 6]);
    }

    #[test]
    fn bad_run_lengths_are_errors() {
        let mut out = [0u8; 4];
        assert!(decode_rle(&[0x05, 1, 0], &mut out)
            .unwrap_err()
            .contains("exceed"));
        assert!(decode_rle(&[0x84, 1, 2], &mut out)
            .unwrap_err()
            .contains("short"));
        assert!(decode_rle(&[0x04], &mut out)
            .unwrap_err()
            .contains("no value"));
        assert!(decode_rle(&[0x02, 1, 0], &mut out)
            .unwrap_err()
            .contains("2 of 4"));
    }

    #[test]
    fn raw_and_compressed_files_read_alike() {
        let dims = [3, 2, 2];
        let slices = [vec![1, 2, 3, 4, 5, 6], vec![0, 0, 0, 0, 9, 9]];
        let raw = write("raw.slc", &slc(dims, 0, &slices));
        let rle = write(
            "rle.slc",
            &slc(
                dims,
                1,
                &[vec![0x86, 1, 2, 3, 4, 5, 6, 0], vec![0x04, 0, 0x02, 9, 0]],
            ),
        );
        for p in [raw, rle] {
            let g = read(&p).unwrap();
            assert_eq!(g.dims(), dims);
            assert_eq!(g.spacing().z, 2.5);
            assert_eq!(g.scalar_type().name(), "uint8");
            assert_eq!(g.value(2, 1, 0), 6.0);
            assert_eq!(g.value(1, 0, 1), 0.0);
            assert_eq!(g.value(1, 1, 1), 9.0);
            assert!(is_slc(&std::fs::read(&p).unwrap()));
        }
    }

    #[test]
    fn bad_files_are_errors_naming_the_file() {
        let dims = [2, 2, 2];
        let ok = slc(dims, 0, &[vec![1; 4], vec![2; 4]]);
        let cases: Vec<(&str, Vec<u8>, &str)> = vec![
            ("short.slc", ok[..ok.len() - 1].to_vec(), "truncated"),
            (
                "bits.slc",
                slc(dims, 0, &[]).replace_first(b" 8\n", b" 16\n"),
                "16 bits",
            ),
            ("comp.slc", slc(dims, 2, &[]), "compression type 2"),
            ("dims.slc", slc([0, 2, 2], 0, &[]), "dims"),
            ("magic.slc", b"11112\n2 2 2 8\n".to_vec(), "magic"),
            ("header.slc", b"11111\n2 2".to_vec(), "no z size"),
            (
                "overrun.slc",
                slc(dims, 1, &[vec![0x05, 1, 0], vec![0x04, 1, 0]]),
                "slice 0: runs exceed",
            ),
        ];
        for (name, bytes, expect) in cases {
            let p = write(name, &bytes);
            let e = read(&p).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains(expect), "{name}: {e}");
        }
    }

    #[test]
    fn detection_finds_slc_by_magic_but_not_in_raw_data() {
        let bytes = slc([2, 1, 1], 0, &[vec![1, 2]]);
        let p = write("volume.dat", &bytes);
        assert_eq!(
            crate::detect::detect(&p).unwrap(),
            crate::detect::Format::Slc
        );
        // Raw data that happens to start with the magic number stays raw.
        let p = write("data.raw", &bytes);
        assert_eq!(
            crate::detect::detect(&p).unwrap(),
            crate::detect::Format::RawJson
        );
    }

    #[test]
    fn a_tiny_file_cannot_claim_a_huge_volume() {
        // 2048^3 voxels (8 GiB) declared by a few hundred bytes of run-length slices: refused
        // by the size bound before anything is allocated.
        let bytes = slc([2048, 2048, 2048], 1, &vec![vec![0x7f, 1, 0]; 20]);
        let p = write("huge.slc", &bytes);
        let e = read(&p).unwrap_err();
        assert!(
            matches!(
                e.kind,
                ErrorKind::Undeliverable {
                    declared: 8589934592,
                    ..
                }
            ),
            "{e}"
        );
        let msg = e.to_string();
        assert!(
            msg.contains("huge.slc") && msg.contains("at most 127 bytes"),
            "{msg}"
        );
        // A single slice that claims more than its bytes can hold is refused the same way.
        let bytes = slc([2048, 2048, 1], 1, &[vec![0x7f, 1, 0]]);
        let bytes = [bytes, vec![0; 200_000]].concat();
        let e = read(&write("slice.slc", &bytes)).unwrap_err();
        assert!(
            matches!(
                e.kind,
                ErrorKind::Undeliverable {
                    declared: 4194304,
                    available: 3,
                    ..
                }
            ),
            "{e}"
        );
        // Raw slices need one byte per voxel.
        let bytes = slc([2048, 2048, 2048], 0, &[vec![1; 100]]);
        let e = read(&write("rawhuge.slc", &bytes)).unwrap_err();
        assert!(
            matches!(e.kind, ErrorKind::Truncated { found: 100, .. }),
            "{e}"
        );
    }

    #[test]
    fn special_files_are_refused() {
        use crate::util::hostile::*;
        let dir = tempfile::tempdir().unwrap();
        let zero = zero_link(dir.path(), "zero.slc");
        assert_refused(read(&zero), "zero.slc", "(a character device)");
        assert_refused(read(&link_loop(dir.path(), "l.slc")), "l.slc", "loop");
        if let Some(f) = fifo(dir.path(), "f.slc") {
            assert_refused(read(&f), "f.slc", "(a FIFO)");
            assert_refused(crate::load(&f, &Default::default()), "f.slc", "(a FIFO)");
        }
    }

    trait ReplaceFirst {
        fn replace_first(self, from: &[u8], to: &[u8]) -> Vec<u8>;
    }

    impl ReplaceFirst for Vec<u8> {
        fn replace_first(self, from: &[u8], to: &[u8]) -> Vec<u8> {
            let i = self.windows(from.len()).position(|w| w == from).unwrap();
            [&self[..i], to, &self[i + from.len()..]].concat()
        }
    }
}
