//! The Volux binary tetrahedral-mesh format (`.vtet`), defined here.
//!
//! All values are little-endian, with no padding:
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `VOLUXTET` |
//! | 4 | `u32` version, 1 |
//! | 8 | `u64` n_vertices |
//! | 8 | `u64` n_tets |
//! | 12 * n_vertices | `f32` x, y, z per vertex |
//! | 4 * n_vertices | `f32` scalar per vertex |
//! | 16 * n_tets | `u32` four 0-based vertex indices per tet |
//! | 8 | `u64` FNV-1a 64 checksum of the three arrays above (the payload) |
//!
//! The reader checks that the file length is exactly what the counts require before allocating,
//! then the checksum; [`TetMesh::new`] rejects invalid meshes (out-of-range indices, empty
//! meshes, non-finite positions) and reports repairs. No crate is needed: the layout is fixed.
use std::io::Write;
use std::path::Path;

use glam::Vec3;
use volux_core::TetMesh;

use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::error::WriteError;
use crate::util::{
    file_len, header_err, open_regular, read_exact_checked, write_chunked, Progress, PROGRESS_STEP,
};

/// Magic bytes of the format.
pub const MAGIC: &[u8] = b"VOLUXTET";

/// The format version this module reads and writes.
pub const VERSION: u32 = 1;

/// Bytes before the payload: magic, version, two counts.
const HEADER_BYTES: u64 = 8 + 4 + 8 + 8;

/// Initial state of the FNV-1a 64-bit hash.
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// FNV-1a 64-bit hash of `bytes`.
fn fnv1a(bytes: &[u8]) -> u64 {
    fnv1a_update(FNV_OFFSET, bytes)
}

/// The FNV-1a 64-bit hash state `h` continued over `bytes`.
fn fnv1a_update(h: u64, bytes: &[u8]) -> u64 {
    bytes.iter().fold(h, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Reads the fixed-size header; returns (n_vertices, n_tets).
fn read_header(path: &Path, head: &[u8]) -> Result<(u64, u64)> {
    let magic_ok = head.get(..8) == Some(MAGIC);
    let word = |a: usize, b: usize| head.get(a..b).unwrap_or(&[]);
    if !magic_ok {
        return Err(header_err(
            path,
            "not a .vtet file: the magic bytes are not VOLUXTET",
        ));
    }
    let version = word(8, 12)
        .try_into()
        .map(u32::from_le_bytes)
        .map_err(|_| truncated(path, HEADER_BYTES, head.len() as u64))?;
    if version != VERSION {
        return Err(ReadError::new(
            path,
            ErrorKind::Unsupported(format!(
                ".vtet version {version} (this reader knows {VERSION})"
            )),
        ));
    }
    let count = |a, b| {
        word(a, b)
            .try_into()
            .map(u64::from_le_bytes)
            .map_err(|_| truncated(path, HEADER_BYTES, head.len() as u64))
    };
    Ok((count(12, 20)?, count(20, 28)?))
}

fn truncated(path: &Path, expected: u64, found: u64) -> ReadError {
    ReadError::new(path, ErrorKind::Truncated { expected, found })
}

/// The file length the counts require, or an error when it overflows.
fn expected_len(path: &Path, nv: u64, nt: u64) -> Result<u64> {
    nv.checked_mul(16)
        .and_then(|v| nt.checked_mul(16).and_then(|t| v.checked_add(t)))
        .and_then(|p| p.checked_add(HEADER_BYTES + 8))
        .ok_or_else(|| {
            header_err(
                path,
                format!("{nv} vertices and {nt} tets overflow the file size"),
            )
        })
}

/// Little-endian `f32` values of `bytes`.
fn f32s(bytes: &[u8]) -> impl Iterator<Item = f32> + '_ {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
}

/// Reads a `.vtet` mesh.
pub fn read(path: &Path) -> Result<TetMesh> {
    let file = open_regular(path)?;
    let len = file_len(path, &file)?;
    let mut file = std::io::BufReader::new(file);
    let head = read_exact_checked(path, &mut file, HEADER_BYTES.min(len))?;
    if (head.len() as u64) < HEADER_BYTES {
        if head.get(..8) != Some(MAGIC) {
            return Err(header_err(
                path,
                "not a .vtet file: the magic bytes are not VOLUXTET",
            ));
        }
        return Err(truncated(path, HEADER_BYTES, len));
    }
    let (nv, nt) = read_header(path, &head)?;
    let expected = expected_len(path, nv, nt)?;
    if len < expected {
        return Err(truncated(path, expected - HEADER_BYTES, len - HEADER_BYTES));
    }
    if len > expected {
        return Err(header_err(
            path,
            format!(
                "header/data size mismatch: {nv} vertices and {nt} tets need {expected} bytes, the file has {len}"
            ),
        ));
    }
    let body = read_exact_checked(path, &mut file, expected - HEADER_BYTES)?;
    decode(path, &body, nv as usize, nt as usize)
}

/// Verifies the checksum and builds the mesh from the payload + checksum bytes.
fn decode(path: &Path, body: &[u8], nv: usize, nt: usize) -> Result<TetMesh> {
    let (payload, sum) = body.split_at(body.len().saturating_sub(8));
    let stored = u64::from_le_bytes(sum.try_into().unwrap_or([0; 8]));
    if fnv1a(payload) != stored {
        return Err(ReadError::new(
            path,
            ErrorKind::Invalid("checksum mismatch: the file is corrupt".into()),
        ));
    }
    let (pos, rest) = payload.split_at(nv * 12);
    let (sca, idx) = rest.split_at(nv * 4);
    let p: Vec<f32> = f32s(pos).collect();
    let positions = p
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let scalars = f32s(sca).collect();
    let tets = idx
        .chunks_exact(16)
        .map(|c| {
            let u = |i: usize| u32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
            [u(0), u(4), u(8), u(12)]
        })
        .collect::<Vec<_>>();
    debug_assert_eq!(tets.len(), nt);
    TetMesh::new(positions, scalars, tets).map_err(|e| ReadError::new(path, e))
}

/// Bytes [`write()`] produces for `mesh` (header, arrays and checksum): the file's length, so a
/// caller can warn before writing a huge file.
pub fn encoded_size(mesh: &TetMesh) -> u64 {
    let (nv, nt) = (mesh.positions().len() as u64, mesh.tets().len() as u64);
    nv.saturating_mul(16)
        .saturating_add(nt.saturating_mul(16))
        .saturating_add(HEADER_BYTES + 8)
}

/// Writes `mesh` as a `.vtet` file (atomically: temporary name, then rename).
pub fn write(mesh: &TetMesh, path: &Path) -> Result<(), WriteError> {
    write_with_progress(mesh, path, &|_, _| {})
}

/// [`write()`], reporting `(bytes written, total bytes)` to `progress` as the file goes out:
/// once at the start, every few MiB, and at the end; the total is [`encoded_size`].
pub fn write_with_progress(
    mesh: &TetMesh,
    path: &Path,
    progress: &dyn Fn(u64, u64),
) -> Result<(), WriteError> {
    volux_core::image::write_atomically_with(path, |file| {
        let buffered = std::io::BufWriter::new(file);
        let mut out = Progress::new(buffered, encoded_size(mesh), PROGRESS_STEP, progress);
        write_mesh(&mut out, mesh)?;
        out.flush()
    })
    .map_err(|source| WriteError {
        path: path.to_path_buf(),
        source,
    })
}

/// Streams the header, the arrays and their checksum to `out`.
fn write_mesh(out: &mut impl Write, mesh: &TetMesh) -> std::io::Result<()> {
    let (nv, nt) = (mesh.positions().len() as u64, mesh.tets().len() as u64);
    out.write_all(MAGIC)?;
    out.write_all(&VERSION.to_le_bytes())?;
    out.write_all(&nv.to_le_bytes())?;
    out.write_all(&nt.to_le_bytes())?;
    let mut sum = FNV_OFFSET;
    let mut hash = |bytes: &[u8]| sum = fnv1a_update(sum, bytes);
    write_chunked(
        out,
        mesh.positions(),
        |p, o| p.to_array().iter().for_each(|c| o.extend(c.to_le_bytes())),
        &mut hash,
    )?;
    write_chunked(
        out,
        mesh.scalars(),
        |s, o| o.extend(s.to_le_bytes()),
        &mut hash,
    )?;
    write_chunked(
        out,
        mesh.tets(),
        |t, o| t.iter().for_each(|v| o.extend(v.to_le_bytes())),
        &mut hash,
    )?;
    out.write_all(&sum.to_le_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_refused() {
        use crate::util::hostile::*;
        let dir = tempfile::tempdir().unwrap();
        let zero = zero_link(dir.path(), "zm.vtet");
        assert_refused(read(&zero), "zm.vtet", "(a character device)");
        let looped = link_loop(dir.path(), "lm.vtet");
        assert_refused(read(&looped), "lm.vtet", "loop");
        if let Some(f) = fifo(dir.path(), "fm.vtet") {
            assert_refused(read(&f), "fm.vtet", "(a FIFO)");
        }
    }

    #[test]
    fn fnv1a_is_the_reference_hash_and_chains() {
        assert_eq!(fnv1a(b""), FNV_OFFSET);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
        assert_eq!(fnv1a_update(fnv1a(b"foo"), b"bar"), fnv1a(b"foobar"));
    }
}
