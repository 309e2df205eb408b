//! Tetrahedral meshes with one scalar per vertex.
//!
//! Validation follows what the Projected Tetrahedra and tet ray-casting seeds need
//! (`000_...txt` ch. 3): indices in range, finite positions, positively oriented tets
//! (inverted ones are re-oriented by swapping two vertices), zero-volume tets counted; a mesh
//! with nothing to render (all vertices coinciding or in one axis plane, all tets degenerate)
//! is refused, so the error names the mesh rather than a later stage.
//! Face adjacency (the neighbour across each face) feeds MPVO sorting and cell-to-cell ray
//! traversal.
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::aabb::Aabb;
use crate::error::{Error, Result};
use crate::grid::{MAX_COORDINATE, MIN_SPACING};

/// Marks a face with no neighbour (a boundary face) in [`TetMesh::face_adjacency`].
pub const NO_NEIGHBOR: u32 = u32::MAX;

/// The faces of a tet as vertex slots, face `f` being opposite vertex `f`, each wound so its
/// normal points outward for a positively oriented tet.
pub const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// What validation found and repaired.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct MeshReport {
    /// Tets whose orientation was negative and were re-oriented.
    pub inverted_reoriented: usize,
    /// Tets with (near) zero volume, kept but reported; renderers discard them.
    pub degenerate: usize,
    /// Vertex scalars that were NaN/Inf and were replaced by the minimum.
    pub nonfinite_scalars: usize,
    /// Vertices that no tet uses.
    pub unused_vertices: usize,
}

/// A tetrahedral mesh: positions, one scalar per vertex, tets as four vertex indices.
#[derive(Clone, Debug)]
pub struct TetMesh {
    positions: Vec<Vec3>,
    scalars: Vec<f32>,
    tets: Vec<[u32; 4]>,
    range: [f64; 2],
    report: MeshReport,
    notes: Vec<String>,
}

/// Six times the signed volume of tet (a, b, c, d), in f64.
pub fn signed_volume6(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> f64 {
    let (a, b, c, d) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3(), d.as_dvec3());
    (b - a).cross(c - a).dot(d - a)
}

/// Errors on the first vertex whose position is not finite or beyond ±[`MAX_COORDINATE`].
fn check_positions(positions: &[Vec3]) -> Result<()> {
    let bad = |p: &Vec3| !p.is_finite() || f64::from(p.abs().max_element()) > MAX_COORDINATE;
    match positions.iter().position(bad) {
        None => Ok(()),
        Some(i) if !positions[i].is_finite() => Err(Error::InvalidMesh(format!(
            "vertex {i} has a non-finite position {}",
            positions[i]
        ))),
        Some(i) => Err(Error::InvalidMesh(format!(
            "vertex {i} at {} is beyond ±{MAX_COORDINATE:e}",
            positions[i]
        ))),
    }
}

/// The diagonal of the bounding box of `positions` (not empty, finite); errors when every
/// vertex coincides, the box is smaller than [`MIN_SPACING`] across (garbage such as floats
/// read in the wrong byte order) or flat (zero extent along an axis).
fn check_extent(positions: &[Vec3]) -> Result<f64> {
    let b = Aabb::from_points(positions.iter().map(|p| p.as_dvec3()))
        .ok_or_else(|| Error::InvalidMesh("no vertices".into()))?;
    let extent = b.max - b.min;
    if extent == DVec3::ZERO {
        return Err(Error::InvalidMesh(format!(
            "all {} vertices coincide at {}",
            positions.len(),
            b.min
        )));
    }
    if b.diagonal() < MIN_SPACING {
        return Err(Error::InvalidMesh(format!(
            "the mesh is only {:.3e} across (below {MIN_SPACING:e}): the positions are not usable coordinates",
            b.diagonal()
        )));
    }
    if let Some(axis) = (0..3).find(|&a| extent[a] == 0.0) {
        return Err(Error::InvalidMesh(format!(
            "the mesh is flat: every vertex has {} = {}, so every tet has zero volume",
            ["x", "y", "z"][axis],
            b.min[axis]
        )));
    }
    Ok(b.diagonal())
}

impl TetMesh {
    /// Builds and validates a mesh. Errors on an empty mesh, a length mismatch, a non-finite
    /// or absurdly large position (beyond ±[`MAX_COORDINATE`]), an out-of-range index, a
    /// degenerate bounding box (all vertices coincide, or all lie in an axis plane) or tets
    /// that are all degenerate; repairs (and reports) inverted tets and non-finite scalars, and
    /// counts the degenerate tets of a mesh that has others.
    pub fn new(
        positions: Vec<Vec3>,
        mut scalars: Vec<f32>,
        mut tets: Vec<[u32; 4]>,
    ) -> Result<Self> {
        if positions.is_empty() || tets.is_empty() {
            return Err(Error::InvalidMesh(format!(
                "empty mesh ({} vertices, {} tets)",
                positions.len(),
                tets.len()
            )));
        }
        if positions.len() != scalars.len() {
            return Err(Error::InvalidMesh(format!(
                "{} vertices but {} scalars",
                positions.len(),
                scalars.len()
            )));
        }
        if positions.len() > u32::MAX as usize - 1 {
            return Err(Error::InvalidMesh("more than 2^32-2 vertices".into()));
        }
        check_positions(&positions)?;
        let n = positions.len() as u32;
        if let Some((t, tet)) = tets
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v >= n))
        {
            return Err(Error::InvalidMesh(format!(
                "tet {t} has vertex index out of range: {tet:?} (mesh has {n} vertices)"
            )));
        }
        let mut report = MeshReport::default();
        let (lo, hi) = scalars
            .iter()
            .filter(|v| v.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 0.0) };
        for s in scalars.iter_mut().filter(|s| !s.is_finite()) {
            *s = lo;
            report.nonfinite_scalars += 1;
        }
        let scale = check_extent(&positions)?;
        let eps = 1e-12 * scale.powi(3);
        let (inverted, degenerate) = tets
            .par_iter_mut()
            .map(|t| {
                let v = signed_volume6(
                    positions[t[0] as usize],
                    positions[t[1] as usize],
                    positions[t[2] as usize],
                    positions[t[3] as usize],
                );
                let degenerate = v.abs() <= eps
                    || t[0] == t[1]
                    || t[0] == t[2]
                    || t[0] == t[3]
                    || t[1] == t[2]
                    || t[1] == t[3]
                    || t[2] == t[3];
                if v < 0.0 && !degenerate {
                    t.swap(2, 3);
                    (1usize, 0usize)
                } else {
                    (0, degenerate as usize)
                }
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        if degenerate == tets.len() {
            return Err(Error::InvalidMesh(format!(
                "all {degenerate} tets are degenerate (zero volume or a repeated vertex): nothing to render"
            )));
        }
        report.inverted_reoriented = inverted;
        report.degenerate = degenerate;
        let mut used = vec![false; positions.len()];
        for t in &tets {
            for &v in t {
                used[v as usize] = true;
            }
        }
        report.unused_vertices = used.iter().filter(|u| !**u).count();
        Ok(Self {
            positions,
            scalars,
            tets,
            range: [lo as f64, hi as f64],
            report,
            notes: Vec::new(),
        })
    }

    /// Adds a note (e.g. "quadratic tets: corner nodes used") reported by `volux info`.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
    /// Notes on conversions made while loading.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }
    /// Vertex positions.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }
    /// One scalar per vertex.
    pub fn scalars(&self) -> &[f32] {
        &self.scalars
    }
    /// Tets as four vertex indices, positively oriented (unless degenerate).
    pub fn tets(&self) -> &[[u32; 4]] {
        &self.tets
    }
    /// `[min, max]` of the scalars.
    pub fn range(&self) -> [f64; 2] {
        self.range
    }
    /// What validation found.
    pub fn report(&self) -> &MeshReport {
        &self.report
    }
    /// World bounding box.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().map(|p| p.as_dvec3())).expect("mesh is not empty")
    }
    /// The four corner positions of tet `t`.
    pub fn tet_positions(&self, t: usize) -> [Vec3; 4] {
        self.tets[t].map(|v| self.positions[v as usize])
    }
    /// Bytes of the mesh itself (positions, scalars, tets) per tet.
    pub fn bytes_per_tet(&self) -> f64 {
        let bytes = self.positions.len() * (12 + 4) + self.tets.len() * 16;
        bytes as f64 / self.tets.len() as f64
    }

    /// For each tet and face `f` (opposite vertex `f`), the index of the tet across it, or
    /// [`NO_NEIGHBOR`]. Faces shared by more than two tets (non-manifold) keep the first pair.
    pub fn face_adjacency(&self) -> Vec<[u32; 4]> {
        let mut adj = vec![[NO_NEIGHBOR; 4]; self.tets.len()];
        let faces = self.sorted_faces();
        let mut i = 0;
        while i < faces.len() {
            let mut j = i + 1;
            while j < faces.len() && faces[j].0 == faces[i].0 {
                j += 1;
            }
            if j - i >= 2 {
                let (a, b) = (faces[i].1, faces[i + 1].1);
                adj[(a >> 2) as usize][(a & 3) as usize] = b >> 2;
                adj[(b >> 2) as usize][(b & 3) as usize] = a >> 2;
            }
            i = j;
        }
        adj
    }

    /// Boundary faces (faces owned by exactly one tet), wound outward.
    pub fn boundary_faces(&self) -> Vec<[u32; 3]> {
        let faces = self.sorted_faces();
        let mut out = Vec::new();
        let mut i = 0;
        while i < faces.len() {
            let mut j = i + 1;
            while j < faces.len() && faces[j].0 == faces[i].0 {
                j += 1;
            }
            if j - i == 1 {
                let code = faces[i].1;
                let tet = self.tets[(code >> 2) as usize];
                out.push(FACES[(code & 3) as usize].map(|s| tet[s]));
            }
            i = j;
        }
        out
    }

    /// (sorted vertex triple, tet*4 + face) for every face, sorted by triple.
    fn sorted_faces(&self) -> Vec<([u32; 3], u32)> {
        let mut faces: Vec<([u32; 3], u32)> = self
            .tets
            .par_iter()
            .enumerate()
            .flat_map_iter(|(t, tet)| {
                (0..4).map(move |f| {
                    let mut k = FACES[f].map(|s| tet[s]);
                    k.sort_unstable();
                    (k, (t as u32) * 4 + f as u32)
                })
            })
            .collect();
        faces.par_sort_unstable();
        faces
    }

    /// Per-vertex gradients: the volume-weighted average of the constant gradients of the tets
    /// around each vertex (degenerate tets ignored).
    pub fn vertex_gradients(&self) -> Vec<Vec3> {
        let mut acc = vec![(DVec3::ZERO, 0.0f64); self.positions.len()];
        for t in 0..self.tets.len() {
            if let Some((g, vol)) = self.tet_gradient(t) {
                for &v in &self.tets[t] {
                    let a = &mut acc[v as usize];
                    a.0 += g * vol;
                    a.1 += vol;
                }
            }
        }
        acc.into_iter()
            .map(|(g, w)| {
                if w > 0.0 {
                    (g / w).as_vec3()
                } else {
                    Vec3::ZERO
                }
            })
            .collect()
    }

    /// The constant gradient of the linear field in tet `t` and its volume; `None` if degenerate.
    pub fn tet_gradient(&self, t: usize) -> Option<(DVec3, f64)> {
        let p = self.tet_positions(t).map(|p| p.as_dvec3());
        let s = self.tets[t].map(|v| self.scalars[v as usize] as f64);
        let (e1, e2, e3) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
        let det = e1.cross(e2).dot(e3);
        if det.abs() < 1e-300 {
            return None;
        }
        let (d1, d2, d3) = (s[1] - s[0], s[2] - s[0], s[3] - s[0]);
        // Solve [e1; e2; e3] g = d by Cramer's rule with the cross-product inverse.
        let g = (e2.cross(e3) * d1 + e3.cross(e1) * d2 + e1.cross(e2) * d3) / det;
        Some((g, det.abs() / 6.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_tets() -> TetMesh {
        let p = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
        ];
        let s = p.iter().map(|p| 2.0 * p.x + 3.0 * p.y - p.z).collect();
        // second tet inverted on purpose
        TetMesh::new(p, s, vec![[0, 1, 2, 3], [1, 2, 4, 3]]).unwrap()
    }

    #[test]
    fn reorients_and_finds_adjacency() {
        let m = two_tets();
        assert_eq!(m.report().inverted_reoriented, 1);
        for t in 0..2 {
            let p = m.tet_positions(t);
            assert!(signed_volume6(p[0], p[1], p[2], p[3]) > 0.0);
        }
        let adj = m.face_adjacency();
        assert_eq!(adj[0].iter().filter(|&&n| n == 1).count(), 1);
        assert_eq!(adj[1].iter().filter(|&&n| n == 0).count(), 1);
        assert_eq!(m.boundary_faces().len(), 6);
    }

    #[test]
    fn gradient_of_linear_field_is_exact() {
        let m = two_tets();
        let (g, _) = m.tet_gradient(0).unwrap();
        assert!((g - DVec3::new(2.0, 3.0, -1.0)).length() < 1e-9);
        for g in m.vertex_gradients() {
            assert!((g.as_dvec3() - DVec3::new(2.0, 3.0, -1.0)).length() < 1e-5);
        }
    }

    #[test]
    fn boundary_faces_point_outward() {
        let m = two_tets();
        let c = m.bounds().center().as_vec3();
        for f in m.boundary_faces() {
            let [a, b, d] = f.map(|v| m.positions()[v as usize]);
            let n = (b - a).cross(d - a);
            assert!(n.dot((a + b + d) / 3.0 - c) > 0.0);
        }
    }

    #[test]
    fn rejects_bad_meshes() {
        let p = vec![Vec3::ZERO; 4];
        assert!(TetMesh::new(p.clone(), vec![0.0; 4], vec![]).is_err());
        assert!(TetMesh::new(p.clone(), vec![0.0; 4], vec![[0, 1, 2, 4]]).is_err());
        assert!(TetMesh::new(p.clone(), vec![0.0; 3], vec![[0, 1, 2, 3]]).is_err());
        let mut q = p.clone();
        q[0].x = f32::NAN;
        assert!(TetMesh::new(q, vec![0.0; 4], vec![[0, 1, 2, 3]]).is_err());
    }

    #[test]
    fn some_degenerate_tets_are_counted_not_refused() {
        let mut p = unit_tet();
        p.push(Vec3::new(0.5, 0.5, 0.0));
        let s = vec![0.0, f32::NAN, 1.0, 2.0, 3.0];
        // The second tet's four vertices lie in the plane z = 0; the third repeats a vertex.
        let m = TetMesh::new(p, s, vec![[0, 1, 2, 3], [0, 1, 2, 4], [0, 0, 1, 3]]).unwrap();
        assert_eq!(m.report().degenerate, 2);
        assert_eq!(m.report().nonfinite_scalars, 1);
    }

    fn unit_tet() -> Vec<Vec3> {
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]
    }

    /// The message of the mesh error for these positions and tets (scalars all 0).
    fn mesh_error(p: Vec<Vec3>, tets: Vec<[u32; 4]>) -> String {
        let n = p.len();
        match TetMesh::new(p, vec![0.0; n], tets) {
            Ok(_) => panic!("a mesh with nothing to render was accepted"),
            Err(e) => {
                assert!(matches!(e, Error::InvalidMesh(_)), "{e}");
                e.to_string()
            }
        }
    }

    #[test]
    fn meshes_with_nothing_to_render_are_refused() {
        let m = mesh_error(vec![Vec3::splat(2.5); 4], vec![[0, 1, 2, 3]]);
        assert!(
            m.contains("all 4 vertices coincide at [2.5, 2.5, 2.5]"),
            "{m}"
        );
        let mut flat = unit_tet();
        flat[3] = Vec3::new(0.3, 0.3, 0.0);
        let m = mesh_error(flat, vec![[0, 1, 2, 3]]);
        assert!(m.contains("flat") && m.contains("z = 0"), "{m}");
        // Coplanar in a slanted plane x + y + z = 1: every tet has zero volume.
        let slanted = vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(0.5, 0.25, 0.25)];
        let m = mesh_error(slanted, vec![[0, 1, 2, 3], [3, 2, 1, 0]]);
        assert!(m.contains("all 2 tets are degenerate"), "{m}");
        let m = mesh_error(unit_tet(), vec![[0, 1, 1, 3]]);
        assert!(m.contains("all 1 tets are degenerate"), "{m}");
        let tiny = unit_tet().into_iter().map(|p| p * 1e-35).collect();
        let m = mesh_error(tiny, vec![[0, 1, 2, 3]]);
        assert!(m.contains("only 1.732e-35 across"), "{m}");
        let mut huge = unit_tet();
        huge[2].y = 3e38;
        let m = mesh_error(huge, vec![[0, 1, 2, 3]]);
        assert!(m.contains("vertex 2") && m.contains("beyond"), "{m}");
        let mut inf = unit_tet();
        inf[1].z = f32::INFINITY;
        let m = mesh_error(inf, vec![[0, 1, 2, 3]]);
        assert!(m.contains("vertex 1 has a non-finite position"), "{m}");
        assert_eq!(m.lines().count(), 1);
    }
}
