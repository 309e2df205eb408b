//! OFF tetrahedral meshes in the HAVS layout (Callahan et al., "Hardware-Assisted Visibility
//! Sorting", and `/work/shared/data/README.md`):
//!
//! ```text
//! [OFF]                 optional keyword line
//! n_verts n_tets [0]    counts (a third count, as in surface OFF, is ignored)
//! x y z s               n_verts lines: position and scalar
//! i j k l               n_tets lines, 0-based (a leading `4`, as in surface OFF, is accepted)
//! ```
//!
//! Blank lines and `#` comments are skipped; gzip is detected by its magic bytes
//! (`flate2`). OFF declares no byte size, so gzip is inflated into a growing buffer capped at
//! [`MAX_GZ_RATIO`] times the compressed size and at the memory limit: OFF text compresses
//! about 4:1 (the shared meshes: 4.1 to 4.4), so 64:1 leaves a wide margin for valid meshes
//! while a decompression bomb (deflate reaches 1032:1) stops early with an error. Parsing is a hand-written tokenizer over the bytes (integers parsed by hand,
//! floats by the standard library) because the benchmark meshes have over half a million tets:
//! no parser crate is needed for a format this small. Counts are checked against the bytes
//! actually present before anything is reserved, and every syntax error names its line.
use std::path::Path;

use glam::Vec3;
use volux_core::limits::{check_alloc, memory_limit};

/// Most bytes a gzip OFF file may inflate to, per compressed byte (see the module docs).
pub const MAX_GZ_RATIO: u64 = 64;
use volux_core::TetMesh;

use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::util::{open_gz_input, read_to_limit};

/// Shortest possible vertex or tet line: 4 one-character tokens, 3 separators, a newline.
const MIN_LINE_BYTES: u64 = 8;

/// Reads an OFF tetrahedral mesh (plain or gzip).
pub fn read(path: &Path) -> Result<TetMesh> {
    let bytes = read_text(path)?;
    parse(&bytes)
        .map_err(|m| ReadError::new(path, ErrorKind::Invalid(m)))
        .and_then(|(p, s, t, notes)| {
            let mut mesh = TetMesh::new(p, s, t).map_err(|e| ReadError::new(path, e))?;
            for n in notes {
                mesh = mesh.with_note(n);
            }
            Ok(mesh)
        })
}

/// The bytes of the file, inflated when gzip: plain files up to their length, gzip up to
/// [`MAX_GZ_RATIO`] times the compressed size; both within the memory limit.
fn read_text(path: &Path) -> Result<Vec<u8>> {
    let input = open_gz_input(path)?;
    let memory = memory_limit();
    if !input.gzip {
        check_alloc("OFF file", input.file_len, 1).map_err(|e| ReadError::new(path, e))?;
        return read_to_limit(path, input.reader, input.file_len, "the file", || {
            "it grew while being read".into()
        });
    }
    let ratio_cap = input.file_len.saturating_mul(MAX_GZ_RATIO);
    let limit = ratio_cap.min(memory);
    read_to_limit(path, input.reader, limit, "gzip data", || {
        if ratio_cap <= memory {
            format!(
                "{MAX_GZ_RATIO} times its {} compressed bytes; OFF text compresses about 4:1, \
                 so this looks like a decompression bomb",
                input.file_len
            )
        } else {
            "the memory limit".into()
        }
    })
}

/// Positions, scalars, tets and notes.
type Parsed = (Vec<Vec3>, Vec<f32>, Vec<[u32; 4]>, Vec<String>);

/// Non-blank, non-comment lines with their 1-based numbers.
struct Lines<'a> {
    rest: &'a [u8],
    number: usize,
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);
    fn next(&mut self) -> Option<Self::Item> {
        while !self.rest.is_empty() {
            let end = self
                .rest
                .iter()
                .position(|&b| b == b'\n')
                .unwrap_or(self.rest.len());
            let line = &self.rest[..end];
            self.rest = self.rest.get(end + 1..).unwrap_or(&[]);
            self.number += 1;
            let line = match line.iter().position(|&b| b == b'#') {
                Some(h) => &line[..h],
                None => line,
            };
            if line.iter().any(|b| !b.is_ascii_whitespace()) {
                return Some((self.number, line));
            }
        }
        None
    }
}

/// Splits a line into at most 8 whitespace-separated tokens; returns how many there were.
fn tokens<'a>(line: &'a [u8], out: &mut [&'a [u8]; 8]) -> usize {
    let mut n = 0;
    for t in line
        .split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
    {
        if n < out.len() {
            out[n] = t;
        }
        n += 1;
    }
    n
}

fn parse_u64(t: &[u8]) -> Option<u64> {
    if t.is_empty() || t.len() > 19 {
        return None;
    }
    t.iter().try_fold(0u64, |acc, &b| {
        b.is_ascii_digit().then(|| acc * 10 + (b - b'0') as u64)
    })
}

fn parse_f32(t: &[u8]) -> Option<f32> {
    std::str::from_utf8(t).ok()?.parse().ok()
}

fn show(t: &[u8]) -> String {
    String::from_utf8_lossy(&t[..t.len().min(40)]).into_owned()
}

/// Parses the whole file content.
fn parse(bytes: &[u8]) -> std::result::Result<Parsed, String> {
    let mut lines = Lines {
        rest: bytes,
        number: 0,
    };
    let (nv, nt, line) = counts(&mut lines)?;
    let need = (nv + nt).saturating_mul(MIN_LINE_BYTES);
    if need > bytes.len() as u64 {
        return Err(format!(
            "line {line}: the counts ({nv} vertices, {nt} tets) need at least {need} bytes, but the file holds {}",
            bytes.len()
        ));
    }
    check_alloc("vertices", nv, 16).map_err(|e| e.to_string())?;
    check_alloc("tets", nt, 16).map_err(|e| e.to_string())?;
    let (positions, scalars) = vertices(&mut lines, nv as usize)?;
    let tets = tets(&mut lines, nt as usize, nv)?;
    let mut notes = Vec::new();
    let extra = lines.count();
    if extra > 0 {
        notes.push(format!("{extra} lines after the last tet ignored"));
    }
    Ok((positions, scalars, tets, notes))
}

/// The count line (after an optional `OFF` keyword): vertices, tets, its line number.
fn counts(lines: &mut Lines) -> std::result::Result<(u64, u64, usize), String> {
    let mut tok = [&[][..]; 8];
    let Some((mut no, mut line)) = lines.next() else {
        return Err("empty file: no 'n_verts n_tets' line".into());
    };
    if tokens(line, &mut tok) == 1 && tok[0].eq_ignore_ascii_case(b"OFF") {
        (no, line) = lines
            .next()
            .ok_or("the file ends after the OFF keyword, before 'n_verts n_tets'")?;
    }
    let n = tokens(line, &mut tok);
    if !(2..=3).contains(&n) {
        return Err(format!(
            "line {no}: expected 'n_verts n_tets', found {n} values"
        ));
    }
    let count = |t: &[u8]| {
        parse_u64(t)
            .filter(|&c| c < u32::MAX as u64)
            .ok_or_else(|| {
                format!(
                    "line {no}: '{}' is not a count (a non-negative integer below 2^32)",
                    show(t)
                )
            })
    };
    Ok((count(tok[0])?, count(tok[1])?, no))
}

fn vertices(lines: &mut Lines, nv: usize) -> std::result::Result<(Vec<Vec3>, Vec<f32>), String> {
    let mut tok = [&[][..]; 8];
    let mut positions = Vec::with_capacity(nv);
    let mut scalars = Vec::with_capacity(nv);
    for i in 0..nv {
        let (no, line) = lines
            .next()
            .ok_or_else(|| format!("truncated: the file ends after {i} of {nv} vertex lines"))?;
        let n = tokens(line, &mut tok);
        if n != 4 {
            return Err(format!(
                "line {no}: vertex {i} has {n} values, expected 4 (x y z scalar)"
            ));
        }
        let mut v = [0f32; 4];
        for (k, t) in tok[..4].iter().enumerate() {
            v[k] =
                parse_f32(t).ok_or_else(|| format!("line {no}: '{}' is not a number", show(t)))?;
        }
        positions.push(Vec3::new(v[0], v[1], v[2]));
        scalars.push(v[3]);
    }
    Ok((positions, scalars))
}

fn tets(lines: &mut Lines, nt: usize, nv: u64) -> std::result::Result<Vec<[u32; 4]>, String> {
    let mut tok = [&[][..]; 8];
    let mut tets = Vec::with_capacity(nt);
    for i in 0..nt {
        let (no, line) = lines
            .next()
            .ok_or_else(|| format!("truncated: the file ends after {i} of {nt} tet lines"))?;
        let n = tokens(line, &mut tok);
        let ids = match n {
            4 => &tok[..4],
            5 if tok[0] == b"4" => &tok[1..5],
            _ => {
                return Err(format!(
                    "line {no}: tet {i} has {n} values, expected 4 vertex indices"
                ))
            }
        };
        let mut t = [0u32; 4];
        for (k, s) in ids.iter().enumerate() {
            let v = parse_u64(s)
                .ok_or_else(|| format!("line {no}: '{}' is not a vertex index", show(s)))?;
            if v >= nv {
                return Err(format!(
                    "line {no}: tet {i} uses vertex {v}, but there are {nv} vertices"
                ));
            }
            t[k] = v as u32;
        }
        tets.push(t);
    }
    Ok(tets)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_with_comments_and_keyword() {
        let text = b"# c\nOFF\n4 1\n0 0 0 1\n1 0 0 2 # x\n\n0 1 0 3\n0 0 1 4\n4 0 1 2 3\n";
        let (p, s, t, notes) = parse(text).unwrap();
        assert_eq!(p.len(), 4);
        assert_eq!(s, vec![1.0, 2.0, 3.0, 4.0]);
        assert_eq!(t, vec![[0, 1, 2, 3]]);
        assert!(notes.is_empty());
    }

    #[test]
    fn special_files_are_refused() {
        use crate::util::hostile::*;
        let dir = tempfile::tempdir().unwrap();
        assert_refused(
            read(&zero_link(dir.path(), "z.off")),
            "z.off",
            "(a character device)",
        );
        assert_refused(read(&link_loop(dir.path(), "l.off")), "l.off", "loop");
        if let Some(f) = fifo(dir.path(), "f.off.gz") {
            assert_refused(read(&f), "f.off.gz", "(a FIFO)");
        }
    }

    #[test]
    fn gzip_bombs_stop_at_the_ratio_cap() {
        use std::io::Write as _;
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bomb.off.gz");
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        enc.write_all(b"4 1\n").unwrap();
        enc.write_all(&vec![b' '; 256 << 20]).unwrap();
        let gz = enc.finish().unwrap();
        std::fs::write(&p, &gz).unwrap();
        let e = read(&p).unwrap_err();
        let limit = gz.len() as u64 * MAX_GZ_RATIO;
        assert!(
            matches!(e.kind, ErrorKind::Inflates { limit: l, .. } if l == limit),
            "{e}"
        );
        assert!(e.to_string().contains("decompression bomb"), "{e}");
    }

    #[test]
    fn errors_name_lines() {
        let e = parse(b"4 1\n0 0 0 1\n1 0 x 2\n0 1 0 3\n0 0 1 4\n0 1 2 3\n").unwrap_err();
        assert!(e.contains("line 3"), "{e}");
        let e = parse(b"4 1\n0 0 0 1\n1 0 0 2\n0 1 0 3\n0 0 1 4\n0 1 2 4\n").unwrap_err();
        assert!(e.contains("line 6") && e.contains("vertex 4"), "{e}");
        let e = parse(b"4000000000 1\n0 0 0 1\n").unwrap_err();
        assert!(e.contains("bytes"), "{e}");
    }
}
