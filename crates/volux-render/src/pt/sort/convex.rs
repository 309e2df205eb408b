//! Convexity of a tetrahedral mesh: whether MPVO alone is an exact visibility order (Williams
//! 1992; seed `000_...txt` §4.2 names MPVO as the exact alternative to the centroid sort).
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use volux_core::TetMesh;

/// Relative tolerance of the dihedral test: a boundary edge is concave when the far vertex of
/// one face lies more than `1e-6 |d - a|` (plus the `f32` rounding of the coordinates)
/// outside the plane of the other face, so coplanar faces pass.
const DIHEDRAL_TOL: f64 = 1e-6;

/// What the convexity test found on the boundary surface of a mesh.
///
/// The mesh is convex when its boundary is one closed, consistently oriented, edge-manifold
/// surface of the topology of a sphere (Euler characteristic 2) that is locally convex at
/// every edge; a connected closed surface locally convex everywhere bounds a convex body, so
/// the local dihedral tests imply global convexity. Several components (an inner cavity, two
/// separate pieces), non-manifold edges or a handle (a torus) make it non-convex.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Convexity {
    /// Boundary triangles.
    pub boundary_faces: usize,
    /// Connected components of the boundary (faces connected through shared edges).
    pub components: usize,
    /// Boundary edges not shared by exactly two faces of opposite winding.
    pub nonmanifold_edges: usize,
    /// Manifold boundary edges whose dihedral angle is reflex (beyond the tolerance).
    pub concave_edges: usize,
    /// `V - E + F` of the boundary surface (2 for a sphere).
    pub euler_characteristic: i64,
}

impl Convexity {
    /// The convexity report of `mesh` (from [`TetMesh::boundary_faces`]).
    pub fn of_mesh(mesh: &TetMesh) -> Self {
        Self::of_boundary(mesh.positions(), &mesh.boundary_faces())
    }

    /// The convexity report of a boundary surface given as outward-wound triangles.
    pub fn of_boundary(positions: &[Vec3], faces: &[[u32; 3]]) -> Self {
        let mut report = Self {
            boundary_faces: faces.len(),
            ..Self::default()
        };
        if faces.is_empty() {
            return report;
        }
        // Directed edges (a -> b) as (undirected key, face * 2 + [a > b]).
        let mut edges: Vec<(u64, u32)> = faces
            .par_iter()
            .enumerate()
            .flat_map_iter(|(i, f)| {
                (0..3).map(move |k| {
                    let (a, b) = (f[k], f[(k + 1) % 3]);
                    let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                    (key, (i as u32) * 2 + u32::from(a > b))
                })
            })
            .collect();
        edges.par_sort_unstable();

        let scale = positions
            .iter()
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        let quantum = 4.0 * f64::from(f32::EPSILON) * f64::from(scale);
        let p = |v: u32| positions[v as usize].as_dvec3();
        let far = |face: u32, key: u64| {
            let (a, b) = ((key >> 32) as u32, key as u32);
            *faces[face as usize]
                .iter()
                .find(|&&v| v != a && v != b)
                .unwrap_or(&a)
        };
        // Distance of `d` outside the plane of face `f`, minus the tolerance.
        let outside = |f: u32, d: u32| {
            let [a, b, c] = faces[f as usize].map(p);
            let n = (b - a).cross(c - a);
            let len = n.length();
            if len == 0.0 {
                return f64::NEG_INFINITY;
            }
            let w: DVec3 = p(d) - a;
            n.dot(w) / len - (DIHEDRAL_TOL * w.length() + quantum)
        };

        let mut parent: Vec<u32> = (0..faces.len() as u32).collect();
        let mut undirected = 0i64;
        let mut i = 0;
        while i < edges.len() {
            let mut j = i + 1;
            while j < edges.len() && edges[j].0 == edges[i].0 {
                j += 1;
            }
            undirected += 1;
            let group = &edges[i..j];
            for e in &group[1..] {
                union(&mut parent, group[0].1 >> 1, e.1 >> 1);
            }
            if group.len() != 2 || (group[0].1 & 1) == (group[1].1 & 1) {
                report.nonmanifold_edges += 1;
            } else {
                let key = group[0].0;
                let (f, g) = (group[0].1 >> 1, group[1].1 >> 1);
                if outside(f, far(g, key)) > 0.0 || outside(g, far(f, key)) > 0.0 {
                    report.concave_edges += 1;
                }
            }
            i = j;
        }
        report.components = (0..parent.len() as u32)
            .filter(|&f| find(&mut parent, f) == f)
            .count();
        let mut used = vec![false; positions.len()];
        for &v in faces.iter().flatten() {
            used[v as usize] = true;
        }
        let vertices = used.iter().filter(|&&u| u).count() as i64;
        report.euler_characteristic = vertices - undirected + faces.len() as i64;
        report
    }

    /// Whether the boundary is a single closed locally convex surface of genus 0, i.e. the
    /// mesh is convex and MPVO alone orders it exactly.
    pub fn is_convex(&self) -> bool {
        self.boundary_faces > 0
            && self.components == 1
            && self.nonmanifold_edges == 0
            && self.concave_edges == 0
            && self.euler_characteristic == 2
    }
}

/// Whether `mesh` is convex ([`Convexity::of_mesh`] and [`Convexity::is_convex`]): when it is
/// not, the renderer needs a per-pixel fragment sort on top of MPVO.
pub fn is_convex(mesh: &TetMesh) -> bool {
    Convexity::of_mesh(mesh).is_convex()
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let up = parent[parent[x as usize] as usize];
        parent[x as usize] = up;
        x = up;
    }
    x
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        // The smaller root wins, so the structure does not depend on the visiting order.
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi as usize] = lo;
    }
}
