//! Regular and curvilinear grids split into conforming tetrahedra.
//!
//! Each hexahedral cell becomes 5 tets: a central tet on the four corners whose global index
//! parity `(i + j + k) % 2` is even, and one corner tet at each odd corner. Because the choice
//! depends on the global parity, the pattern mirrors on alternating cells and every face
//! diagonal is shared by the two cells that meet there, so the mesh conforms (as the seeds do
//! for the Blunt Fin and LOx Post meshes, `000_...txt` ch. 5).
use glam::Vec3;

use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::limits::{check_alloc, check_alloc_within, count_of, memory_budget};
use crate::mesh::{signed_volume6, TetMesh};

/// Offsets of the 8 corners of a cell, corner `c` at `(c & 1, (c >> 1) & 1, (c >> 2) & 1)`.
const CORNERS: [[usize; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [0, 1, 0],
    [1, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [0, 1, 1],
    [1, 1, 1],
];

/// The 5 tets of a cell as corner numbers, for a cell whose corner 0 has even global parity.
const EVEN_CELL: [[usize; 4]; 5] = [
    [0, 3, 5, 6],
    [1, 0, 3, 5],
    [2, 0, 3, 6],
    [4, 0, 5, 6],
    [7, 3, 5, 6],
];
/// The mirrored pattern, for a cell whose corner 0 has odd global parity.
const ODD_CELL: [[usize; 4]; 5] = [
    [1, 2, 4, 7],
    [0, 1, 2, 4],
    [3, 1, 2, 7],
    [5, 1, 4, 7],
    [6, 2, 4, 7],
];

/// Tets of a structured lattice of `cells` cells, vertex `(i, j, k)` numbered by
/// `vertex(i, j, k)`; cells for which `keep(i, j, k)` is false are skipped. Orientation is
/// fixed later from the positions.
pub fn lattice_tets(
    cells: [usize; 3],
    vertex: impl Fn(usize, usize, usize) -> u32,
    keep: impl Fn(usize, usize, usize) -> bool,
) -> Vec<[u32; 4]> {
    let mut tets = Vec::with_capacity(cells[0] * cells[1] * cells[2] * 5);
    for k in 0..cells[2] {
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                if !keep(i, j, k) {
                    continue;
                }
                let ids = CORNERS.map(|c| vertex(i + c[0], j + c[1], k + c[2]));
                let pattern = if (i + j + k) % 2 == 0 {
                    &EVEN_CELL
                } else {
                    &ODD_CELL
                };
                tets.extend(pattern.iter().map(|t| t.map(|c| ids[c])));
            }
        }
    }
    tets
}

/// Swaps two vertices of every negatively oriented tet so all are positive.
pub fn orient_positive(positions: &[Vec3], tets: &mut [[u32; 4]]) {
    for t in tets {
        let p = t.map(|v| positions[v as usize]);
        if signed_volume6(p[0], p[1], p[2], p[3]) < 0.0 {
            t.swap(2, 3);
        }
    }
}

/// A curvilinear (structured) grid of `dims` points, x fastest, into 5 tets per cell.
/// `blank`, when given, marks points to leave out (PLOT3D IBLANK = 0): cells touching one are
/// skipped.
pub fn curvilinear_to_tets(
    dims: [usize; 3],
    positions: Vec<Vec3>,
    scalars: Vec<f32>,
    blank: Option<&[bool]>,
) -> Result<TetMesh> {
    let n = dims[0] * dims[1] * dims[2];
    if dims.iter().any(|&d| d < 2) {
        return Err(Error::InvalidDims {
            dims: dims.map(|d| d as i64),
            reason: "need at least 2 points along each axis to make cells".into(),
        });
    }
    if positions.len() != n || scalars.len() != n || blank.is_some_and(|b| b.len() != n) {
        return Err(Error::SizeMismatch {
            expected: n as u64,
            actual: positions.len().min(scalars.len()) as u64,
        });
    }
    let cells = dims.map(|d| d - 1);
    check_alloc("the tets", count_of(&cells).saturating_mul(5), TET_BYTES)?;
    let id = |i: usize, j: usize, k: usize| (i + dims[0] * (j + dims[1] * k)) as u32;
    let keep = |i: usize, j: usize, k: usize| {
        blank.is_none_or(|b| {
            CORNERS
                .iter()
                .all(|c| !b[id(i + c[0], j + c[1], k + c[2]) as usize])
        })
    };
    let mut tets = lattice_tets(cells, id, keep);
    orient_positive(&positions, &mut tets);
    TetMesh::new(positions, scalars, tets)
}

/// Bytes of a mesh's vertices: a position (12 bytes) and a scalar (4), plus the flag
/// [`TetMesh::new`] keeps per vertex while it validates.
const VERTEX_BYTES: u64 = 12 + 4 + 1;
/// Bytes of one tet: four `u32` vertex indices.
const TET_BYTES: u64 = 16;

/// Bytes of the mesh [`grid_to_tets`] makes of a grid of `dims` samples (vertices and
/// 5 tets per cell), `u64::MAX` when the count overflows.
pub fn grid_mesh_bytes(dims: [usize; 3]) -> u64 {
    let vertices = count_of(&dims).saturating_mul(VERTEX_BYTES);
    let tets = count_of(&dims.map(|d| d.saturating_sub(1)))
        .saturating_mul(5)
        .saturating_mul(TET_BYTES);
    vertices.saturating_add(tets)
}

/// A regular grid into 5 tets per cell, vertices at the sample positions. The mesh is checked
/// against the process's memory budget before anything is allocated.
pub fn grid_to_tets(grid: &Grid) -> Result<TetMesh> {
    grid_to_tets_within(grid, memory_budget())
}

/// [`grid_to_tets`] with the memory budget given: [`Error::OverBudget`] when the mesh needs
/// more than `budget` bytes, [`Error::InvalidMesh`] when it has more vertices than `u32`
/// indices can number.
pub fn grid_to_tets_within(grid: &Grid, budget: u64) -> Result<TetMesh> {
    let d = grid.dims();
    check_alloc_within(
        budget,
        "the tetrahedral mesh of the grid",
        grid_mesh_bytes(d),
        1,
    )?;
    if grid.len() as u64 > u64::from(u32::MAX - 1) {
        return Err(Error::InvalidMesh(format!(
            "a grid of {} samples has more vertices than a mesh can index (2^32-2)",
            grid.len()
        )));
    }
    let mut positions = Vec::with_capacity(grid.len());
    for k in 0..d[2] {
        for j in 0..d[1] {
            for i in 0..d[0] {
                positions.push(grid.position(i, j, k).as_vec3());
            }
        }
    }
    let scalars = grid.to_f32_vec()?;
    curvilinear_to_tets(d, positions, scalars, None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Buffer, Samples};

    #[test]
    fn grid_to_tets_conforms_and_fills_volume() {
        let g = Grid::new(
            [4, 3, 5],
            [1.0, 2.0, 0.5],
            [0.0; 3],
            Samples::U8(Buffer::owned((0..60).map(|v| v as u8).collect())),
        )
        .unwrap();
        let m = grid_to_tets(&g).unwrap();
        assert_eq!(m.tets().len(), 3 * 2 * 4 * 5);
        assert_eq!(m.report().inverted_reoriented, 0);
        assert_eq!(m.report().degenerate, 0);
        let vol: f64 = (0..m.tets().len())
            .map(|t| {
                let p = m.tet_positions(t);
                signed_volume6(p[0], p[1], p[2], p[3]) / 6.0
            })
            .sum();
        assert!((vol - 3.0 * 4.0 * 2.0).abs() < 1e-4, "volume {vol}");
        // Conforming: boundary faces are exactly the 2 triangles of each outer cell face.
        let outer_quads = 2 * (3 * 2 + 3 * 4 + 2 * 4);
        assert_eq!(m.boundary_faces().len(), 2 * outer_quads);
    }

    /// A grid whose mesh exceeds the budget is refused before anything is allocated, with
    /// the size and the budget in the message.
    #[test]
    fn grid_over_budget_is_an_error_not_an_abort() {
        let g = Grid::new(
            [8, 8, 8],
            [1.0; 3],
            [0.0; 3],
            Samples::U8(Buffer::owned(vec![0; 512])),
        )
        .unwrap();
        let need = grid_mesh_bytes([8, 8, 8]);
        assert_eq!(need, 512 * 17 + 343 * 5 * 16);
        let e = grid_to_tets_within(&g, need - 1).unwrap_err();
        assert!(
            matches!(e, Error::OverBudget { bytes, .. } if bytes == need),
            "{e}"
        );
        assert!(
            e.to_string().starts_with(
                "the tetrahedral mesh of the grid needs 35.297 KiB, over the memory budget of \
                 35.296 KiB"
            ),
            "{e}"
        );
        assert!(grid_to_tets_within(&g, need).is_ok());
        // A 1024^3 grid (what a 1 MB .raw.gz can inflate to) needs about 33 GiB.
        assert!(grid_mesh_bytes([1024; 3]) > 32 << 30);
        assert_eq!(grid_mesh_bytes([usize::MAX, 2, 2]), u64::MAX);
    }
}
