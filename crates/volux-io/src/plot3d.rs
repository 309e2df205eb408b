//! PLOT3D whole-grid, single-block, binary files without Fortran record markers (the layout of
//! the NASA Blunt Fin and LOx Post data; NASA PLOT3D User's Manual, TM-101067, ch. 8, and
//! `vtkMultiBlockPLOT3DReader`):
//!
//! * xyz: `nx ny nz` (int32), then X, Y, Z (float32, `nx*ny*nz` each, i fastest), then
//!   optionally IBLANK (int32, `nx*ny*nz`), detected from the file size;
//! * q: `nx ny nz`, then `fsmach alpha re time` (float32), then 5 variables (density,
//!   x/y/z momentum, stagnation energy).
//!
//! Both files may also start with a block count of 1 (multi-block layout with one block). The
//! byte order is detected per file from the plausibility of the header integers (big-endian,
//! as written by the original workstations, is tried first); trailing bytes are tolerated with
//! a note. The curvilinear grid becomes 5 tets per cell with
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
    let mut mesh = curvilinear_to_tets(xyz.dims, xyz.positions, scalars, None)
        .map_err(|e| ReadError::new(path, e))?;
    for n in notes {
        mesh = mesh.with_note(n);
    }
    Ok(mesh)
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

/// A parsed header: dims, byte order, offset of the data.
#[derive(Clone, Copy, Debug)]
struct Header {
    dims: [usize; 3],
    little: bool,
    data_at: usize,
}

fn int(bytes: &[u8], at: usize, little: bool) -> Option<i64> {
    let b: [u8; 4] = bytes.get(at..at + 4)?.try_into().ok()?;
    Some(if little {
        i32::from_le_bytes(b)
    } else {
        i32::from_be_bytes(b)
    } as i64)
}

/// Finds a plausible header: byte order (BE first) and optional block count of 1, such that
/// `min_values(n)` values of 4 bytes fit in the file after it.
fn header(bytes: &[u8], min_values: impl Fn(u64) -> u64) -> std::result::Result<Header, String> {
    for little in [false, true] {
        for blocks in [false, true] {
            if blocks && int(bytes, 0, little) != Some(1) {
                continue;
            }
            let at = if blocks { 4 } else { 0 };
            let d = [0, 1, 2].map(|k| int(bytes, at + 4 * k, little).unwrap_or(0));
            let Ok((dims, n)) = volux_core::limits::checked_dims(d) else {
                continue;
            };
            let data_at = at + 12;
            let need = min_values(n).saturating_mul(4);
            if need <= (bytes.len() - data_at.min(bytes.len())) as u64 {
                return Ok(Header {
                    dims,
                    little,
                    data_at,
                });
            }
        }
    }
    let show = |l| [0, 4, 8].map(|a| int(bytes, a, l));
    Err(format!(
        "no plausible header: the first ints read {:?} (big-endian) / {:?} (little-endian), which are not dims whose data fits in the {} bytes of the file (or the file has Fortran record markers, which are not supported)",
        show(false),
        show(true),
        bytes.len()
    ))
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

fn read_file(path: &Path) -> Result<Vec<u8>> {
    let len = std::fs::metadata(path)
        .map_err(|e| ReadError::new(path, e))?
        .len();
    volux_core::limits::check_alloc("PLOT3D file", len, 1).map_err(|e| ReadError::new(path, e))?;
    std::fs::read(path).map_err(|e| ReadError::new(path, e))
}

fn trailing_note(what: &str, extra: usize) -> Option<String> {
    (extra > 0).then(|| format!("{what}: {extra} trailing bytes after the data ignored"))
}

/// The grid: dims, positions, notes.
struct Xyz {
    dims: [usize; 3],
    positions: Vec<Vec3>,
    notes: Vec<String>,
}

fn read_xyz(path: &Path) -> Result<Xyz> {
    let bytes = read_file(path)?;
    let h = header(&bytes, |n| n.saturating_mul(3))
        .map_err(|m| ReadError::new(path, ErrorKind::Header(m)))?;
    let n = h.dims.iter().product::<usize>();
    let [x, y, z] = [0, 1, 2].map(|k| floats(&bytes, h.data_at + 4 * k * n, n, h.little));
    let positions: Vec<Vec3> = (0..n).map(|i| Vec3::new(x[i], y[i], z[i])).collect();
    let rest = bytes.len() - h.data_at - 12 * n;
    let mut notes = vec![format!(
        "PLOT3D {} grid {}x{}x{}",
        if h.little {
            "little-endian"
        } else {
            "big-endian"
        },
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
    let h = header(&bytes, |n| n.saturating_mul(5).saturating_add(4))
        .map_err(|m| ReadError::new(path, ErrorKind::Header(m)))?;
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

    #[test]
    fn q_name_from_xyz_name() {
        let q = default_q(Path::new("/d/bluntfinxyz.bin")).unwrap();
        assert_eq!(q, Path::new("/d/bluntfinq.bin"));
        assert!(default_q(Path::new("/d/grid.bin")).is_err());
    }
}
