//! Per-mesh geometry of the ray caster: canonical face planes shared by the two cells of a
//! face, the face-to-face adjacency and the linear scalar field of every cell.
//!
//! The planes follow [`crate::geometry::planes`] exactly (as the mesh reference does): a face's plane is computed from its
//! three vertices sorted lexicographically by position, `n = (v1 - v0) x (v2 - v0)` in `f64`,
//! and each cell sees it with the sign that makes it point outward. Since a face's plane is
//! stored once and read by both of its cells with opposite signs, the numerators and
//! denominators of the crossing parameter `t = -num / den` are exactly negated between the
//! two cells, so both compute a bit-identical `t` (and bit-identical to the reference's): a
//! ray leaving one cell at `t` enters its neighbour at the same `t`, never earlier or later.
//! A ray lying in a face plane (`den == 0`, `num == 0`) is given to exactly one of the two
//! cells by the reference's tie rule (simulation of simplicity along `(1, d, d^2)`).
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use volux_core::mesh::{FACES, NO_NEIGHBOR};
use volux_core::TetMesh;

/// Marks a tet-face whose outward normal is the negated canonical normal.
pub(crate) const FLIP: u32 = 1 << 31;

/// A canonical face plane: normal of the lexicographically sorted vertices and the smallest
/// of them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FacePlane {
    pub n: DVec3,
    pub a: Vec3,
}

/// Where a ray crosses a cell (the reference's clip, plus the exit face).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Clip {
    pub t_in: f64,
    pub t_out: f64,
    pub exit: u8,
}

/// What the walk reads of one cell, in one 64-byte cache line (one memory access per cell
/// stepped into, besides its face planes).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Cell {
    /// Scalar field, `s(p) = g . p + c` as `[g.x, g.y, g.z, c]`; `g.x` is NaN for a skipped
    /// (degenerate or non-finite) cell.
    pub field: [f64; 4],
    /// Per face slot: index into `faces`, with [`FLIP`] set when the outward normal is `-n`.
    pub faces: [u32; 4],
    /// Neighbour across each face slot, or [`NO_NEIGHBOR`].
    pub adj: [u32; 4],
}

/// The per-mesh structures of the walk.
#[derive(Clone, Debug)]
pub(crate) struct Geometry {
    pub faces: Vec<FacePlane>,
    /// Per tet: its field, face planes and neighbours.
    pub cells: Vec<Cell>,
    /// Diagonal of the mesh's bounding box (tolerances are relative to it).
    pub scale: f64,
}

use crate::geometry::{cell_volume6, lex_cmp, lex_negative};

/// `a` when `c`, else `b`, by bit masks: no branch on `c`.
#[inline(always)]
fn pick(c: bool, a: f64, b: f64) -> f64 {
    let m = u64::from(c).wrapping_neg();
    f64::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// The linear field through four points, or `None` for a degenerate or non-finite cell.
fn cell_field(p: [DVec3; 4], s: [f64; 4]) -> Option<[f64; 4]> {
    if !s.iter().all(|v| v.is_finite()) {
        return None;
    }
    let (e1, e2, e3) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
    let vol6 = cell_volume6(p)?;
    // Solve [e1; e2; e3] g = ds by Cramer's rule (rows e_i): g = (ds1 (e2 x e3) + ds2 (e3 x
    // e1) + ds3 (e1 x e2)) / vol6.
    let (d1, d2, d3) = (s[1] - s[0], s[2] - s[0], s[3] - s[0]);
    let g = (e2.cross(e3) * d1 + e3.cross(e1) * d2 + e1.cross(e2) * d3) / vol6;
    let c = s[0] - g.dot(p[0]);
    (g.is_finite() && c.is_finite()).then_some([g.x, g.y, g.z, c])
}

impl Geometry {
    /// Builds the faces, adjacency and fields of `mesh` (`O(n log n)`, parallel).
    pub fn new(mesh: &TetMesh) -> Self {
        let pos = mesh.positions();
        let tets = mesh.tets();
        let mut keys: Vec<([u32; 3], u32)> = tets
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
        keys.par_sort_unstable();
        let mut cells = vec![
            Cell {
                field: [0.0; 4],
                faces: [0; 4],
                adj: [NO_NEIGHBOR; 4],
            };
            tets.len()
        ];
        let mut faces = Vec::with_capacity(tets.len() * 2 + 16);
        let mut i = 0;
        while i < keys.len() {
            let mut j = i + 1;
            while j < keys.len() && keys[j].0 == keys[i].0 {
                j += 1;
            }
            let id = faces.len() as u32;
            let mut v = keys[i].0.map(|k| pos[k as usize].as_dvec3());
            v.sort_by(lex_cmp);
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            faces.push(FacePlane {
                n,
                a: v[0].as_vec3(),
            });
            for &(_, code) in &keys[i..j] {
                let (t, f) = ((code >> 2) as usize, (code & 3) as usize);
                let opp = pos[tets[t][f] as usize].as_dvec3();
                let h = n.dot(opp - v[0]);
                cells[t].faces[f] = id | if h > 0.0 { FLIP } else { 0 };
            }
            if j - i >= 2 {
                let (a, b) = (keys[i].1, keys[i + 1].1);
                cells[(a >> 2) as usize].adj[(a & 3) as usize] = b >> 2;
                cells[(b >> 2) as usize].adj[(b & 3) as usize] = a >> 2;
            }
            i = j;
        }
        let scalars = mesh.scalars();
        cells.par_iter_mut().zip(tets).for_each(|(cell, tet)| {
            let p = tet.map(|v| pos[v as usize].as_dvec3());
            let s = tet.map(|v| scalars[v as usize] as f64);
            // A face plane through the opposite vertex makes the cell unusable too.
            cell.field = cell_field(p, s).unwrap_or([f64::NAN, 0.0, 0.0, 0.0]);
        });
        let mut geo = Self {
            faces,
            cells,
            scale: mesh.bounds().diagonal().max(f64::MIN_POSITIVE),
        };
        // The reference also rejects a cell when a face's height `h` is zero.
        for t in 0..tets.len() {
            for f in 0..4 {
                let (n, a) = geo.plane(t, f);
                let h = n.dot(pos[tets[t][f] as usize].as_dvec3() - a);
                if !(h < 0.0 && h.is_finite()) {
                    geo.cells[t].field[0] = f64::NAN;
                }
            }
        }
        geo
    }

    /// Outward normal and base point of face `f` of tet `t`.
    #[inline]
    pub fn plane(&self, t: usize, f: usize) -> (DVec3, DVec3) {
        let code = self.cells[t].faces[f];
        let pl = &self.faces[(code & !FLIP) as usize];
        let n = if code & FLIP != 0 { -pl.n } else { pl.n };
        (n, pl.a.as_dvec3())
    }

    /// The neighbours of tet `t` across its face slots ([`NO_NEIGHBOR`] for none).
    #[inline]
    pub fn adj(&self, t: usize) -> [u32; 4] {
        self.cells[t].adj
    }

    /// Whether tet `t` is rendered (not degenerate, finite scalars).
    #[inline]
    pub fn usable(&self, t: usize) -> bool {
        !self.cells[t].field[0].is_nan()
    }

    /// The reference's clip of the ray `o + t d`, `t >= 0`, against tet `t`, with the exit
    /// face (the first of the faces giving the smallest exit parameter). `None` when the ray
    /// misses the cell, touches it in a point or the cell is skipped.
    ///
    /// Entered from a neighbour, the entry face's parameter is the neighbour's exit
    /// parameter, bit for bit (the same plane read with the opposite sign, see the module
    /// documentation), so the walk needs no special case for it. The four faces are combined
    /// without branches on the signs of the ray's crossings (which a branch predictor cannot
    /// learn); a face parallel to the ray sends the cell to [`Geometry::clip_parallel`], the
    /// same clip with the parallel case.
    #[inline]
    pub fn clip(&self, t: usize, o: DVec3, d: DVec3) -> Option<Clip> {
        let cell = &self.cells[t];
        if cell.field[0].is_nan() {
            return None;
        }
        let mut t_in = 0.0f64;
        let mut t_out = f64::INFINITY;
        let mut exit = 0u8;
        let mut parallel = false;
        for (f, &code) in cell.faces.iter().enumerate() {
            let pl = &self.faces[(code & !FLIP) as usize];
            let sign = if code & FLIP != 0 { -1.0 } else { 1.0 };
            let num = pl.n.dot(o - pl.a.as_dvec3()) * sign;
            let den = pl.n.dot(d) * sign;
            let te = -num / den;
            t_in = t_in.max(pick(den < 0.0, te, f64::NEG_INFINITY));
            let leave = pick(den > 0.0, te, f64::INFINITY);
            exit = if leave < t_out { f as u8 } else { exit };
            t_out = t_out.min(leave);
            parallel |= !((den < 0.0) | (den > 0.0));
        }
        if parallel {
            return self.clip_parallel(t, o, d);
        }
        (t_out > t_in && t_out.is_finite()).then_some(Clip { t_in, t_out, exit })
    }

    /// [`Geometry::clip`] face by face, with the case of a ray parallel to a face plane
    /// (`den == 0`): inside when the ray is on the inner side, or in the plane and the tie
    /// rule gives it to this cell (simulation of simplicity, [`lex_negative`]).
    #[cold]
    #[inline(never)]
    fn clip_parallel(&self, t: usize, o: DVec3, d: DVec3) -> Option<Clip> {
        let mut t_in = 0.0f64;
        let mut t_out = f64::INFINITY;
        let mut exit = 0u8;
        for (f, &code) in self.cells[t].faces.iter().enumerate() {
            let pl = &self.faces[(code & !FLIP) as usize];
            let mut num = pl.n.dot(o - pl.a.as_dvec3());
            let mut den = pl.n.dot(d);
            if code & FLIP != 0 {
                num = -num;
                den = -den;
            }
            if den < 0.0 {
                t_in = t_in.max(-num / den);
            } else if den > 0.0 {
                let te = -num / den;
                if te < t_out {
                    t_out = te;
                    exit = f as u8;
                }
            } else {
                let n = if code & FLIP != 0 { -pl.n } else { pl.n };
                let inside = num < 0.0 || (num == 0.0 && lex_negative(n));
                if den.is_nan() || !inside {
                    return None;
                }
            }
        }
        (t_out > t_in && t_out.is_finite()).then_some(Clip { t_in, t_out, exit })
    }

    /// Whether point `p` lies in tet `t` up to `tol` (world units) from each face plane.
    #[inline]
    pub fn contains(&self, t: usize, p: DVec3, tol: f64) -> bool {
        (0..4).all(|f| {
            let (n, a) = self.plane(t, f);
            let len = n.length();
            n.dot(p - a) <= tol * len || len == 0.0
        })
    }

    /// The scalar of tet `t` at point `p`.
    #[inline]
    pub fn scalar(&self, t: usize, p: DVec3) -> f64 {
        let g = self.cells[t].field;
        g[0] * p.x + g[1] * p.y + g[2] * p.z + g[3]
    }

    /// Peak bytes per tet while [`Geometry::new`] builds: the four sorted face keys, the
    /// face table, the adjacency, the cell field and up to two face planes.
    pub fn build_bytes_per_tet() -> u64 {
        let keys = 4 * std::mem::size_of::<([u32; 3], u32)>();
        let planes = 2 * std::mem::size_of::<FacePlane>();
        (keys + std::mem::size_of::<Cell>() + planes) as u64
    }

    /// Bytes of these structures.
    pub fn bytes(&self) -> usize {
        self.faces.len() * std::mem::size_of::<FacePlane>()
            + self.cells.len() * std::mem::size_of::<Cell>()
    }
}
