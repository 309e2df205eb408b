//! PLOT3D whole-grid, single-block, binary files without Fortran record markers (the layout of
//! the NASA Blunt Fin and LOx Post data; NASA PLOT3D User's Manual, TM-101067, ch. 8, and
//! `vtkMultiBlockPLOT3DReader`):
//!
//! * xyz: `nx ny nz` (int32), then X, Y, Z (float32, `nx*ny*nz` each, i fastest), then
//!   optionally IBLANK (int32, `nx*ny*nz`), detected from the file size;
//! * q: `nx ny nz`, then `fsmach alpha re time` (float32), then 5 variables (density,
//!   x/y/z momentum, stagnation energy).
//!
//! Both files may also start with a block count of 1 (multi-block layout with one block; more
//! blocks are refused as unsupported). The byte order and layout are detected per file from
//! the header integers: big-endian (as written by the original workstations) is tried first,
//! then little-endian, each without then with a block count, and the first reading whose dims
//! explain the file size exactly wins; when none does, the first whose data fits is used and
//! the trailing bytes are noted (the NASA Blunt Fin q file has 484). Coordinates that are not
//! finite, coincide, lie in a plane or make only degenerate tets (what a wrong byte order
//! gives) are refused with the byte order and dims the grid was read with. The curvilinear grid becomes 5 tets per cell with
//! [`volux_core::tetrahedralize::curvilinear_to_tets`].
//!
//! IBLANK is reported, not applied: the reference tet meshes of these benchmarks keep every
//! cell (LOx Post: 513,375 tets = 5 x 37 x 75 x 37, although 4,332 points have IBLANK = -1),
//! so no cell is dropped. No crate is used: the format is a few arrays of fixed-size numbers.
use std::path::{Path, PathBuf};

use glam::Vec3;
use volux_core::tetrahedralize::curvilinear_to_tets;
use volux_core::TetMesh;

use crate::error::ErrorKind;

use crate::error::ReadError;

use crate::error::Result;
use crate::util::read_regular;

/// The names of the q variables, in file order, then the derived one.
pub const VARIABLES: [&str; 6] = [
    "density",
    "momentum-x",
    "momentum-y",
    "momentum-z",
    "energy",
    "velocity-magnitude",
];

/// Reads a PLOT3D xyz file (and its q file) into a tet mesh with one q variable per vertex.
///
/// `q_file` defaults to the xyz name with `xyz` replaced by `q`; `q_variable` is one of
/// [`VARIABLES`] or an index `0`..`4` (default `density`).
pub fn read(path: &Path, q_file: Option<&Path>, q_variable: Option<&str>) -> Result<TetMesh> {
    let var = variable(q_variable).map_err(|m| ReadError::new(path, ErrorKind::Invalid(m)))?;
    let q_path = match q_file {
        Some(q) => q.to_path_buf(),
        None => default_q(path)?,
    };
    let xyz = read_xyz(path)?;
    let q = read_q(&q_path, xyz.dims)?;
    let scalars = q.variable(var);
    let mut notes = xyz.notes;
    notes.extend(q.notes);
    notes.push(format!(
        "q file {}: fsmach {}, alpha {}, re {}, time {}; scalar: {}",
        q_path.display(),
        q.header[0],
        q.header[1],
        q.header[2],
        q.header[3],
        VARIABLES[var]
    ));
    let (dims, little) = (xyz.dims, xyz.little);
    let mut mesh = curvilinear_to_tets(dims, xyz.positions, scalars, None)
        .map_err(|e| ReadError::new(path, mesh_context(e, dims, little)))?;
    for n in notes {
        mesh = mesh.with_note(n);
    }
    Ok(mesh)
}

/// Adds to a mesh error (non-finite, coinciding or flat points, all tets degenerate: what a
/// wrong byte order or a file that is not a PLOT3D grid gives) how the grid was read.
fn mesh_context(e: volux_core::Error, dims: [usize; 3], little: bool) -> volux_core::Error {
    match e {
        volux_core::Error::InvalidMesh(m) => volux_core::Error::InvalidMesh(format!(
            "{m} (the grid was read as {} {}x{}x{}: is it a PLOT3D grid in that byte order?)",
            order(little),
            dims[0],
            dims[1],
            dims[2]
        )),
        e => e,
    }
}

/// The name of a byte order.
fn order(little: bool) -> &'static str {
    if little {
        "little-endian"
    } else {
        "big-endian"
    }
}

/// Index of the variable (0..=4 from the file, 5 = velocity magnitude).
fn variable(name: Option<&str>) -> std::result::Result<usize, String> {
    let name = name.unwrap_or("density").trim().to_ascii_lowercase();
    if let Ok(i) = name.parse::<usize>() {
        if i < 5 {
            return Ok(i);
        }
    }
    let alias = match name.as_str() {
        "rho" => "density",
        "rhou" | "momentum_x" | "x-momentum" => "momentum-x",
        "rhov" | "momentum_y" | "y-momentum" => "momentum-y",
        "rhow" | "momentum_z" | "z-momentum" => "momentum-z",
        "e" | "stagnation-energy" => "energy",
        "velocity_magnitude" | "velmag" | "speed" => "velocity-magnitude",
        n => n,
    };
    VARIABLES.iter().position(|v| *v == alias).ok_or_else(|| {
        format!(
            "unknown q variable '{name}' (known: {}, or an index 0..4)",
            VARIABLES.join(", ")
        )
    })
}

/// The xyz file name with its last `xyz` replaced by `q`.
fn default_q(path: &Path) -> Result<PathBuf> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    match lower.rfind("xyz") {
        Some(i) => Ok(path.with_file_name(format!("{}q{}", &name[..i], &name[i + 3..]))),
        None => Err(ReadError::new(
            path,
            ErrorKind::Invalid(
                "cannot derive the q file name (no 'xyz' in the file name): give the q file".into(),
            ),
        )),
    }
}

/// A parsed header: dims, byte order, offset of the data, and whether the file size is
/// explained exactly by the layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Header {
    dims: [usize; 3],
    little: bool,
    data_at: usize,
    exact: bool,
}

/// The data a file may hold after its header, in 4-byte values, for `n` points: the exact
/// sizes of its layouts (xyz: with or without IBLANK) and the least it must hold.
#[derive(Clone, Copy, Debug)]
struct Layout {
    exact: [u64; 2],
    min: u64,
}

impl Layout {
    /// An xyz file: X, Y, Z, and optionally IBLANK.
    fn xyz(n: u64) -> Self {
        let xyz = n.saturating_mul(3);
        Layout {
            exact: [xyz, n.saturating_mul(4)],
            min: xyz,
        }
    }
    /// A q file: 4 header floats and 5 variables.
    fn q(n: u64) -> Self {
        let q = n.saturating_mul(5).saturating_add(4);
        Layout {
            exact: [q, q],
            min: q,
        }
    }
}

fn int(bytes: &[u8], at: usize, little: bool) -> Option<i64> {
    let b: [u8; 4] = bytes.get(at..at + 4)?.try_into().ok()?;
    Some(if little {
        i32::from_le_bytes(b)
    } else {
        i32::from_be_bytes(b)
    } as i64)
}

/// The header read with byte order `little`, with (`blocks`) or without a leading block count
/// of 1, if its dims are valid and their data fits in the file.
fn candidate(
    bytes: &[u8],
    little: bool,
    blocks: bool,
    layout: fn(u64) -> Layout,
) -> Option<Header> {
    if blocks && int(bytes, 0, little) != Some(1) {
        return None;
    }
    let at = if blocks { 4 } else { 0 };
    let d = [0, 1, 2].map(|k| int(bytes, at + 4 * k, little).unwrap_or(0));
    let (dims, n) = volux_core::limits::checked_dims(d).ok()?;
    let data_at = at + 12;
    let avail = bytes.len().checked_sub(data_at)? as u64;
    let l = layout(n);
    let fits = |values: u64| values.checked_mul(4);
    if fits(l.min)? > avail {
        return None;
    }
    Some(Header {
        dims,
        little,
        data_at,
        exact: l.exact.iter().any(|&v| fits(v) == Some(avail)),
    })
}

/// The plausible readings of a header, in the order tried: big-endian first (the original
/// workstations), then little-endian, each without then with a block count of 1.
fn candidates(bytes: &[u8], layout: fn(u64) -> Layout) -> Vec<Header> {
    [(false, false), (false, true), (true, false), (true, true)]
        .into_iter()
        .filter_map(|(little, blocks)| candidate(bytes, little, blocks, layout))
        .collect()
}

/// Finds the header for `layout`: the first plausible reading whose layout explains the file
/// size exactly; else, when the file is exactly a multi-block file of several blocks,
/// [`ErrorKind::Unsupported`]; else the first reading into which the data fits (the trailing
/// bytes are noted by the caller); else a header error.
fn header(bytes: &[u8], layout: fn(u64) -> Layout) -> std::result::Result<Header, ErrorKind> {
    let all = candidates(bytes, layout);
    if let Some(h) = all.iter().find(|h| h.exact) {
        return Ok(*h);
    }
    if let Some(m) = multi_block(bytes, layout) {
        return Err(ErrorKind::Unsupported(m));
    }
    if let Some(h) = all.first() {
        return Ok(*h);
    }
    let show = |l| [0, 4, 8].map(|a| int(bytes, a, l));
    Err(ErrorKind::Header(format!(
        "no plausible header: the first ints read {:?} (big-endian) / {:?} (little-endian), which are not dims whose data fits in the {} bytes of the file (or the file has Fortran record markers, which are not supported)",
        show(false),
        show(true),
        bytes.len()
    )))
}

/// Most blocks a file is checked for in [`multi_block`].
const MAX_BLOCKS: i64 = 4096;

/// A message when the file is a multi-block file of more than one block (which this reader
/// does not read): a block count, the dims of each block, then data of exactly their size.
fn multi_block(bytes: &[u8], layout: fn(u64) -> Layout) -> Option<String> {
    [false, true].into_iter().find_map(|little| {
        let blocks = int(bytes, 0, little).filter(|b| (2..=MAX_BLOCKS).contains(b))?;
        let mut values = [0u64; 2];
        for b in 0..blocks as usize {
            let d = [0, 1, 2].map(|k| int(bytes, 4 + 12 * b + 4 * k, little).unwrap_or(0));
            let (_, n) = volux_core::limits::checked_dims(d).ok()?;
            let l = layout(n);
            values = [0, 1].map(|i| values[i].saturating_add(l.exact[i]));
        }
        let data = (bytes.len() as u64).checked_sub(4 + 12 * blocks as u64)?;
        values
            .iter()
            .any(|v| v.checked_mul(4) == Some(data))
            .then(|| {
                format!(
                    "a multi-block PLOT3D file with {blocks} blocks ({}); Volux reads one block",
                    if little {
                        "little-endian"
                    } else {
                        "big-endian"
                    }
                )
            })
    })
}

fn floats(bytes: &[u8], at: usize, n: usize, little: bool) -> Vec<f32> {
    bytes
        .get(at..at + 4 * n)
        .unwrap_or(&[])
        .chunks_exact(4)
        .map(|c| {
            let b = [c[0], c[1], c[2], c[3]];
            if little {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            }
        })
        .collect()
}

/// The whole file, if it is a regular file ([`read_regular`]: FIFOs and devices are refused
/// before opening) that fits in memory.
fn read_file(path: &Path) -> Result<Vec<u8>> {
    read_regular(path, u64::MAX)
}

fn trailing_note(what: &str, extra: usize) -> Option<String> {
    (extra > 0).then(|| format!("{what}: {extra} trailing bytes after the data ignored"))
}

/// The grid: dims, byte order, positions, notes.
struct Xyz {
    dims: [usize; 3],
    /// Little-endian (else big-endian).
    little: bool,
    positions: Vec<Vec3>,
    notes: Vec<String>,
}

fn read_xyz(path: &Path) -> Result<Xyz> {
    let bytes = read_file(path)?;
    let h = header(&bytes, Layout::xyz).map_err(|k| ReadError::new(path, k))?;
    let n = h.dims.iter().product::<usize>();
    let [x, y, z] = [0, 1, 2].map(|k| floats(&bytes, h.data_at + 4 * k * n, n, h.little));
    let positions: Vec<Vec3> = (0..n).map(|i| Vec3::new(x[i], y[i], z[i])).collect();
    let rest = bytes.len() - h.data_at - 12 * n;
    let mut notes = vec![format!(
        "PLOT3D {} grid {}x{}x{}",
        order(h.little),
        h.dims[0],
        h.dims[1],
        h.dims[2]
    )];
    if rest >= 4 * n {
        let at = h.data_at + 12 * n;
        let blanked = (0..n)
            .filter(|&i| int(&bytes, at + 4 * i, h.little) != Some(1))
            .count();
        notes.push(format!(
            "IBLANK present: {blanked} of {n} points have IBLANK != 1; all cells kept"
        ));
        notes.extend(trailing_note("xyz", rest - 4 * n));
    } else {
        notes.extend(trailing_note("xyz", rest));
    }
    Ok(Xyz {
        dims: h.dims,
        little: h.little,
        positions,
        notes,
    })
}

/// The solution: header floats, the 5 variables, notes.
struct Q {
    header: [f32; 4],
    vars: Vec<Vec<f32>>,
    notes: Vec<String>,
}

impl Q {
    fn variable(&self, v: usize) -> Vec<f32> {
        if v < 5 {
            return self.vars[v].clone();
        }
        let [d, mx, my, mz] = [0, 1, 2, 3].map(|k| &self.vars[k]);
        (0..d.len())
            .map(|i| (mx[i] * mx[i] + my[i] * my[i] + mz[i] * mz[i]).sqrt() / d[i])
            .collect()
    }
}

fn read_q(path: &Path, dims: [usize; 3]) -> Result<Q> {
    let bytes = read_file(path)?;
    let h = header(&bytes, Layout::q).map_err(|k| ReadError::new(path, k))?;
    if h.dims != dims {
        return Err(ReadError::new(
            path,
            ErrorKind::Header(format!(
                "q dims {:?} differ from the xyz dims {dims:?}",
                h.dims
            )),
        ));
    }
    let n = dims.iter().product::<usize>();
    let head = floats(&bytes, h.data_at, 4, h.little);
    let header = [0, 1, 2, 3].map(|k| head.get(k).copied().unwrap_or(0.0));
    let at = h.data_at + 16;
    let vars = (0..5)
        .map(|k| floats(&bytes, at + 4 * k * n, n, h.little))
        .collect();
    let notes = trailing_note("q", bytes.len() - at - 20 * n)
        .into_iter()
        .collect();
    Ok(Q {
        header,
        vars,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variable_names() {
        assert_eq!(variable(None).unwrap(), 0);
        assert_eq!(variable(Some("4")).unwrap(), 4);
        assert_eq!(variable(Some("Velocity-Magnitude")).unwrap(), 5);
        let e = variable(Some("pressure")).unwrap_err();
        assert!(e.contains("density") && e.contains("energy"), "{e}");
        assert!(variable(Some("5")).is_err());
    }

    /// Writes ints in the byte order `little`.
    fn ints(little: bool, v: &[i32]) -> Vec<u8> {
        v.iter()
            .flat_map(|&v| {
                if little {
                    v.to_le_bytes()
                } else {
                    v.to_be_bytes()
                }
            })
            .collect()
    }

    /// The reading that explains the file size exactly wins over one tried earlier whose data
    /// merely fits. (Between byte orders this needs dims of 256 or more on every axis, since
    /// a small int read in the other order is huge; a block count of 1 read as a dim is the
    /// ambiguity small files have.) The data here is zeros: only the header is parsed.
    #[test]
    fn exact_reading_wins_over_order_of_trial() {
        let mut le = ints(true, &[65536, 1, 1]);
        le.resize(12 + 12 * 65536, 0);
        let h = header(&le, Layout::xyz).unwrap();
        assert!(h.little && h.exact && h.dims == [65536, 1, 1], "{h:?}");
        // A block count of 1 read as a dim: the exact block reading wins.
        let mut be = ints(false, &[1, 1, 256, 256]);
        be.resize(16 + 16 * 65536, 0);
        let h = header(&be, Layout::xyz).unwrap();
        assert!(!h.little && h.exact && h.data_at == 16, "{h:?}");
        assert_eq!(h.dims, [1, 256, 256]);
        // Nothing exact: the first reading that fits, trailing bytes and all.
        be.push(0);
        let h = header(&be, Layout::xyz).unwrap();
        assert!(
            !h.exact && h.data_at == 12 && h.dims == [1, 1, 256],
            "{h:?}"
        );
    }

    /// A multi-block file of 2 blocks is recognised (both byte orders), not read as one block.
    #[test]
    fn multi_block_files_are_unsupported() {
        for little in [false, true] {
            let mut b = ints(little, &[2, 2, 2, 2, 3, 2, 2]);
            b.resize(b.len() + 4 * 3 * (8 + 12), 0);
            let e = header(&b, Layout::xyz).unwrap_err();
            assert!(matches!(e, ErrorKind::Unsupported(_)), "{e}");
            assert!(e.to_string().contains("2 blocks"), "{e}");
        }
    }

    #[test]
    fn q_name_from_xyz_name() {
        let q = default_q(Path::new("/d/bluntfinxyz.bin")).unwrap();
        assert_eq!(q, Path::new("/d/bluntfinq.bin"));
        assert!(default_q(Path::new("/d/grid.bin")).is_err());
    }
}
