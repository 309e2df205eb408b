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
use std::path::Path;

use glam::Vec3;
use volux_core::TetMesh;

use crate::error::ErrorKind;
use crate::error::ReadError;
use crate::error::Result;
use crate::error::WriteError;
use crate::util::{header_err, read_exact_checked};

/// Magic bytes of the format.
pub const MAGIC: &[u8] = b"VOLUXTET";

/// The format version this module reads and writes.
pub const VERSION: u32 = 1;

/// Bytes before the payload: magic, version, two counts.
const HEADER_BYTES: u64 = 8 + 4 + 8 + 8;

/// FNV-1a 64-bit hash of `bytes`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
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
    let len = std::fs::metadata(path)
        .map_err(|e| ReadError::new(path, e))?
        .len();
    let file = std::fs::File::open(path).map_err(|e| ReadError::new(path, e))?;
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

/// Writes `mesh` as a `.vtet` file (atomically: temporary name, then rename).
pub fn write(mesh: &TetMesh, path: &Path) -> Result<(), WriteError> {
    let werr = |source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    let (nv, nt) = (mesh.positions().len() as u64, mesh.tets().len() as u64);
    let total = nv
        .checked_mul(16)
        .and_then(|v| v.checked_add(nt.checked_mul(16)?))
        .and_then(|v| v.checked_add(HEADER_BYTES + 8))
        .unwrap_or(u64::MAX);
    volux_core::limits::check_alloc(".vtet output", total, 1).map_err(werr)?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&nv.to_le_bytes());
    out.extend_from_slice(&nt.to_le_bytes());
    let start = out.len();
    for p in mesh.positions() {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for s in mesh.scalars() {
        out.extend_from_slice(&s.to_le_bytes());
    }
    for t in mesh.tets() {
        for v in t {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    let sum = fnv1a(&out[start..]);
    out.extend_from_slice(&sum.to_le_bytes());
    volux_core::image::write_atomically(path, &out).map_err(werr)
}
