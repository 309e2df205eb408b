//! Canonical face planes of tetrahedra: the one geometry the mesh reference and the tet ray
//! caster share, so that both cells of a face, and both renderers, compute bit-identical
//! crossings.
//!
//! # Ties: rays in face planes
//!
//! A ray may lie exactly in the plane of a face (axis-aligned lattices seen along an axis).
//! To count such a ray exactly once, each face plane is computed *canonically* from its three
//! vertices sorted lexicographically by position ([`lex_cmp`]), so the two cells sharing a
//! face see exactly opposite normals and offsets; a ray lying in a plane (`n . d = 0` and
//! `n . (o - a) = 0` exactly) is then decided as if its origin were shifted by the
//! infinitesimal vector `eps (1, delta, delta^2)` (simulation of simplicity, [`lex_negative`]):
//! it is inside the half-space when the first non-zero component of the outward normal is
//! negative. Because that is one consistent perturbation of the ray for all faces, a ray
//! along a shared face or a shared edge is claimed by exactly one of the cells around it.
//! Crossings of a shared face give bit-identical `t` in both cells, since `t = -num / den`
//! with both negated.
use glam::DVec3;
use volux_core::mesh::FACES;

/// A cell whose volume is at most this times the cube of its longest edge (times 6) counts
/// as degenerate and is skipped.
pub const DEGENERATE_VOLUME: f64 = 1e-12;

/// Where a ray crosses one tetrahedron: parameters (world distances along the unit
/// direction, `0 <= t_in < t_out`) and the linearly interpolated scalar at both ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TetCrossing {
    /// Entry parameter (clipped to 0 when the origin is inside).
    pub t_in: f64,
    /// Exit parameter.
    pub t_out: f64,
    /// Scalar at the entry point.
    pub s_in: f64,
    /// Scalar at the exit point.
    pub s_out: f64,
}

impl TetCrossing {
    /// Length of the segment, `t_out - t_in` (world units for a unit direction).
    pub fn length(&self) -> f64 {
        self.t_out - self.t_in
    }
}

/// The four face planes of a non-degenerate tetrahedron, canonical (see the module
/// documentation), with outward normals.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TetPlanes {
    /// Outward (not unit) normal of face `f`, the face opposite vertex `f`.
    n: [DVec3; 4],
    /// The lexicographically smallest vertex of face `f`.
    a: [DVec3; 4],
    /// `n[f] . (p[f] - a[f])`, negative: the signed height of the opposite vertex.
    h_opp: [f64; 4],
    /// Vertex scalars.
    s: [f64; 4],
}

/// Lexicographic order of points (how a face's vertices are sorted before its plane is
/// computed, so that neighbouring cells compute the bit-identical plane).
pub fn lex_cmp(a: &DVec3, b: &DVec3) -> std::cmp::Ordering {
    a.x.total_cmp(&b.x)
        .then(a.y.total_cmp(&b.y))
        .then(a.z.total_cmp(&b.z))
}

/// Whether the first non-zero component of `n` is negative: the sign of `n . (1, d, d^2)`
/// for an infinitesimal `d > 0`.
pub fn lex_negative(n: DVec3) -> bool {
    if n.x != 0.0 {
        n.x < 0.0
    } else if n.y != 0.0 {
        n.y < 0.0
    } else {
        n.z < 0.0
    }
}

/// Six times the signed volume of the cell `p`, or `None` when the cell is degenerate (volume
/// at most [`DEGENERATE_VOLUME`] times the cube of its longest edge) or not finite. One test
/// for the reference and the tet ray caster, so both skip the same cells.
pub fn cell_volume6(p: [DVec3; 4]) -> Option<f64> {
    let vol6 = (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]);
    let mut edge2 = 0.0f64;
    for i in 0..4 {
        for j in i + 1..4 {
            edge2 = edge2.max(p[i].distance_squared(p[j]));
        }
    }
    let bound = DEGENERATE_VOLUME * edge2 * edge2.sqrt();
    (vol6.is_finite() && bound.is_finite() && vol6.abs() > bound).then_some(vol6)
}

impl TetPlanes {
    /// `None` for a degenerate cell or non-finite input.
    pub(crate) fn new(p: [DVec3; 4], s: [f64; 4]) -> Option<Self> {
        if !(p.iter().all(|v| v.is_finite()) && s.iter().all(|v| v.is_finite())) {
            return None;
        }
        cell_volume6(p)?;
        let mut planes = Self {
            n: [DVec3::ZERO; 4],
            a: [DVec3::ZERO; 4],
            h_opp: [0.0; 4],
            s,
        };
        for (f, slots) in FACES.iter().enumerate() {
            let mut v = slots.map(|i| p[i]);
            v.sort_by(lex_cmp);
            let nc = (v[1] - v[0]).cross(v[2] - v[0]);
            let h = nc.dot(p[f] - v[0]);
            if !(h != 0.0 && h.is_finite()) {
                return None;
            }
            let (n, h) = if h > 0.0 { (-nc, -h) } else { (nc, h) };
            planes.n[f] = n;
            planes.a[f] = v[0];
            planes.h_opp[f] = h;
        }
        Some(planes)
    }

    /// Clips the ray `origin + t dir`, `t >= 0`, against the cell.
    pub(crate) fn clip(&self, origin: DVec3, dir: DVec3) -> Option<TetCrossing> {
        let mut t_in = 0.0f64;
        let mut t_out = f64::INFINITY;
        let mut num = [0.0; 4];
        let mut den = [0.0; 4];
        for f in 0..4 {
            num[f] = self.n[f].dot(origin - self.a[f]);
            den[f] = self.n[f].dot(dir);
            if den[f] < 0.0 {
                t_in = t_in.max(-num[f] / den[f]);
            } else if den[f] > 0.0 {
                t_out = t_out.min(-num[f] / den[f]);
            } else {
                // Parallel to the plane (or NaN): all inside or all outside; a ray in the
                // plane itself is decided by the tie rule.
                let inside = num[f] < 0.0 || (num[f] == 0.0 && lex_negative(self.n[f]));
                if den[f].is_nan() || !inside {
                    return None;
                }
            }
        }
        if !(t_out > t_in && t_out.is_finite()) {
            return None;
        }
        let scalar = |t: f64| {
            let (mut w, mut acc) = (0.0, 0.0);
            for f in 0..4 {
                let l = ((num[f] + t * den[f]) / self.h_opp[f]).max(0.0);
                w += l;
                acc += l * self.s[f];
            }
            if w > 0.0 {
                acc / w
            } else {
                self.s.iter().sum::<f64>() * 0.25
            }
        };
        Some(TetCrossing {
            t_in,
            t_out,
            s_in: scalar(t_in),
            s_out: scalar(t_out),
        })
    }
}

/// Intersects the ray `origin + t dir`, `t >= 0`, with the tetrahedron of corners `p` and
/// vertex scalars `s` (any orientation). Returns `None` when the ray misses it, touches it
/// only in a point (a vertex, or an edge crossed transversally), or when the cell is
/// degenerate or an input is not finite. A ray lying in a face plane is decided by the
/// tie rule of the module documentation. `t` is in units of `|dir|`; for a unit direction it
/// is a world distance.
pub fn ray_tet_intersection(
    p: [DVec3; 4],
    s: [f64; 4],
    origin: DVec3,
    dir: DVec3,
) -> Option<TetCrossing> {
    TetPlanes::new(p, s)?.clip(origin, dir)
}
