//! Williams' MPVO: face constraints and their topological sort (Williams 1992, the exact
//! alternative named in seed `000_...txt` §4.2).
use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::Vec3;
use rayon::prelude::*;
use volux_core::mesh::{FACES, NO_NEIGHBOR};
use volux_core::TetMesh;

use super::radix::{centroid_keys, centroid_order};
use super::view::{SortError, SortView};

/// Relative tolerance below which the eye counts as lying in a face plane (see
/// [`face_precedence`]).
const PLANE_TOL: f64 = 1e-12;
/// Marks a tet already emitted in the in-degree array of the topological sort.
const DONE: u8 = 0x80;

/// Which of the two cells sharing a face must be composited first (front to back).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Precedence {
    /// No constraint: a boundary face, or the eye (or, for parallel views, the view
    /// direction) lies in the face plane, where either order is correct.
    Free,
    /// The neighbour across the face is in front: it comes first.
    NeighbourFirst,
    /// The tet itself is in front: it comes before its neighbour.
    TetFirst,
}

impl Precedence {
    /// The same relation seen from the other cell.
    pub fn flip(self) -> Self {
        match self {
            Self::Free => Self::Free,
            Self::NeighbourFirst => Self::TetFirst,
            Self::TetFirst => Self::NeighbourFirst,
        }
    }
}

/// The MPVO relation across face `face` (opposite vertex `face`, [`FACES`]) of the tet with
/// vertices `tet`: for a perspective view the cell on the eye's side of the face plane is in
/// front, for a parallel view the cell the view direction leaves from (the outward normal
/// `n` of the tet's face has the neighbour in front when `n . (eye - a) > 0`, resp.
/// `n . forward < 0`; Williams 1992).
///
/// The plane is computed in `f64` from the face's three vertices sorted by index, so the two
/// cells sharing a face evaluate bit-identical numbers and always get opposite answers. When
/// `|n . w| <= 1e-12 |e1| |e2| |w|` (`e1`, `e2` the edges of the canonical face, `w` the
/// vector to the eye or the view direction), far above the rounding error of the expression,
/// the eye is taken to lie in the plane and the pair is [`Precedence::Free`]: every ray
/// through the face then grazes it and both orders composite the same image. Degenerate faces
/// (`n = 0`) are free too.
pub fn face_precedence(
    positions: &[Vec3],
    tet: &[u32; 4],
    face: usize,
    view: &SortView,
) -> Precedence {
    let mut v = FACES[face].map(|s| tet[s]);
    let mut odd = false;
    if v[0] > v[1] {
        v.swap(0, 1);
        odd = !odd;
    }
    if v[1] > v[2] {
        v.swap(1, 2);
        odd = !odd;
    }
    if v[0] > v[1] {
        v.swap(0, 1);
        odd = !odd;
    }
    let p = v.map(|i| positions[i as usize].as_dvec3());
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let w = if view.perspective {
        view.eye - p[0]
    } else {
        -view.forward
    };
    let s = e1.cross(e2).dot(w);
    let tol2 =
        PLANE_TOL * PLANE_TOL * e1.length_squared() * e2.length_squared() * w.length_squared();
    // Also free when `s` is NaN (a non-finite eye).
    if s.is_nan() || s * s <= tol2 {
        return Precedence::Free;
    }
    // The canonical order has the outward winding when the sorting permutation is even.
    if (s > 0.0) != odd {
        Precedence::NeighbourFirst
    } else {
        Precedence::TetFirst
    }
}

/// The MPVO constraints of a whole mesh for one view: for every tet and face, whether the
/// neighbour across it comes first, comes after, or is unconstrained. Four bits per tet for
/// each direction (a `u8` per tet), computed in parallel.
///
/// Each interior face is decided once, by the cell of smaller id ([`face_precedence`] on its
/// face), and both cells read that decision, so the constraints are antisymmetric even for an
/// adjacency that does not come from shared vertex triples. Discarded cells stay in the graph,
/// so constraints that pass through them still hold transitively among the kept cells.
#[derive(Clone, Debug)]
pub struct FaceOrder<'a> {
    adjacency: &'a [[u32; 4]],
    /// Low nibble: bit `f` set when the neighbour across `f` comes after the tet; high
    /// nibble: bit `f` set when it comes before.
    masks: Vec<u8>,
}

impl<'a> FaceOrder<'a> {
    /// The constraints of `mesh` under `view`, `adjacency` as [`TetMesh::face_adjacency`]
    /// returns it. Errors when `adjacency` has the wrong length, names a tet out of range, or
    /// is not symmetric (the first offending tet in id order is reported).
    pub fn new(
        mesh: &TetMesh,
        adjacency: &'a [[u32; 4]],
        view: &SortView,
    ) -> Result<Self, SortError> {
        let tets = mesh.tets();
        let n = tets.len();
        if adjacency.len() != n {
            return Err(SortError::LengthMismatch {
                what: "adjacency",
                actual: adjacency.len(),
                tets: n,
            });
        }
        let pos = mesh.positions();
        let decide = |t: usize| -> Result<u8, SortError> {
            let mut mask = 0u8;
            for f in 0..4 {
                let u = adjacency[t][f];
                if u == NO_NEIGHBOR || u as usize == t {
                    continue;
                }
                if u as usize >= n {
                    return Err(SortError::NeighbourOutOfRange {
                        tet: t as u32,
                        face: f as u8,
                        neighbour: u,
                    });
                }
                let Some(g) = adjacency[u as usize].iter().position(|&x| x as usize == t) else {
                    return Err(SortError::AsymmetricAdjacency {
                        tet: t as u32,
                        face: f as u8,
                        neighbour: u,
                    });
                };
                let p = if t < u as usize {
                    face_precedence(pos, &tets[t], f, view)
                } else {
                    face_precedence(pos, &tets[u as usize], g, view).flip()
                };
                mask |= match p {
                    Precedence::Free => 0,
                    Precedence::TetFirst => 1 << f,
                    Precedence::NeighbourFirst => 0x10 << f,
                };
            }
            Ok(mask)
        };
        // 0xFF (every face both before and after) cannot be a real mask: it flags an error,
        // recomputed below in id order so the error reported is deterministic.
        let mut masks = Vec::with_capacity(n);
        (0..n)
            .into_par_iter()
            .map(|t| decide(t).unwrap_or(0xFF))
            .collect_into_vec(&mut masks);
        if masks.par_iter().any(|&m| m == 0xFF) {
            let first = masks.iter().position(|&m| m == 0xFF).expect("flagged");
            return Err(decide(first).expect_err("flagged tet fails again"));
        }
        Ok(Self { adjacency, masks })
    }

    /// Number of tets.
    pub fn len(&self) -> usize {
        self.masks.len()
    }

    /// Whether the mesh has no tets.
    pub fn is_empty(&self) -> bool {
        self.masks.is_empty()
    }

    /// The relation across face `face` of tet `tet`.
    pub fn precedence(&self, tet: u32, face: usize) -> Precedence {
        let m = self.masks[tet as usize];
        if m & (1 << face) != 0 {
            Precedence::TetFirst
        } else if m & (0x10 << face) != 0 {
            Precedence::NeighbourFirst
        } else {
            Precedence::Free
        }
    }

    /// Number of neighbours that must come before `tet` (its in-degree in the MPVO graph).
    pub fn in_degree(&self, tet: u32) -> u32 {
        (self.masks[tet as usize] >> 4).count_ones()
    }

    /// Number of constrained face pairs (edges of the MPVO graph).
    pub fn constraints(&self) -> u64 {
        self.masks
            .par_iter()
            .map(|m| u64::from((m & 0xF).count_ones()))
            .sum()
    }

    /// The number of constrained face pairs whose two cells both appear in `order` (a front
    /// to back list of distinct tet ids, possibly a subset) in the wrong relative order. Pairs
    /// with a cell missing from `order` are not counted.
    ///
    /// # Panics
    ///
    /// If an id of `order` is not a tet.
    pub fn count_violations(&self, order: &[u32]) -> u64 {
        let mut at = vec![u32::MAX; self.masks.len()];
        for (i, &t) in order.iter().enumerate() {
            at[t as usize] = i as u32;
        }
        order
            .par_iter()
            .enumerate()
            .map(|(i, &t)| {
                let before = self.masks[t as usize] >> 4;
                (0..4)
                    .filter(|&f| before & (1 << f) != 0)
                    .filter(|&f| {
                        let j = at[self.adjacency[t as usize][f] as usize];
                        j != u32::MAX && j as usize > i
                    })
                    .count() as u64
            })
            .sum()
    }
}

/// The result of [`mpvo`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MpvoResult {
    /// The kept tets, front to back.
    pub order: Vec<u32>,
    /// Constrained face pairs (edges of the MPVO graph), over the whole mesh.
    pub constraints: u64,
    /// Tets forced out while the graph had no cell free of constraints (each one breaks at
    /// least one cycle); 0 for an acyclic graph, when the order satisfies every constraint.
    pub cycles_broken: u64,
    /// Tets that became free only after the centroid scan had passed them, i.e. that MPVO
    /// moved behind cells of larger centroid depth: a measure of how far the exact order is
    /// from the centroid order.
    pub reordered: u64,
}

/// [`mpvo`] returning only the order.
pub fn mpvo_order(
    mesh: &TetMesh,
    adjacency: &[[u32; 4]],
    view: &SortView,
    kept: Option<&[u32]>,
) -> Result<Vec<u32>, SortError> {
    mpvo(mesh, adjacency, view, kept).map(|r| r.order)
}

/// Williams' MPVO front to back: builds the face constraints ([`FaceOrder`]) and the centroid
/// depths ([`centroid_keys`]) and runs [`mpvo_with`]. `kept`, when given, lists the tets to
/// draw (in any order); the others still constrain the order but are left out of it.
pub fn mpvo(
    mesh: &TetMesh,
    adjacency: &[[u32; 4]],
    view: &SortView,
    kept: Option<&[u32]>,
) -> Result<MpvoResult, SortError> {
    let (faces, depths) = rayon::join(
        || FaceOrder::new(mesh, adjacency, view),
        || centroid_keys(mesh, view),
    );
    mpvo_with(&faces?, &depths, kept)
}

/// The topological sort of MPVO (Kahn's algorithm) on precomputed constraints and centroid
/// depths (indexed by tet id).
///
/// **Tie-break by centroid depth.** Among the cells free of constraints the one of smallest
/// centroid depth is taken first (equal depths by id), so the result is the centroid order of
/// the seeds (`000` §4.2) corrected only where it breaks a face constraint. For convex meshes
/// any tie-break is exact; for non-convex ones, whose occlusions through empty space the face
/// graph does not see, the depth tie-break keeps distant parts apart where an id or FIFO
/// tie-break would interleave them arbitrarily. It costs O(n) plus a heap of only the
/// [`MpvoResult::reordered`] cells: a cursor walks the centroid order and takes the next free
/// cell; a cell freed after the cursor passed it has a smaller depth than any the cursor can
/// still reach, so it goes into a min-heap that is always served first.
///
/// **Cycles** (possible with perspective views of non-Delaunay meshes, or with broken
/// meshes) are broken, not reported as errors, so a renderer always gets an order: when no
/// cell is free, the remaining cell of smallest centroid depth is emitted regardless of its
/// constraints and [`MpvoResult::cycles_broken`] counts it.
///
/// Errors when `depths` has the wrong length or `kept` names a tet twice or out of range.
pub fn mpvo_with(
    faces: &FaceOrder<'_>,
    depths: &[f32],
    kept: Option<&[u32]>,
) -> Result<MpvoResult, SortError> {
    let n = faces.len();
    if depths.len() != n {
        return Err(SortError::LengthMismatch {
            what: "depths",
            actual: depths.len(),
            tets: n,
        });
    }
    let mut keep = vec![kept.is_none(); n];
    if let Some(kept) = kept {
        for &t in kept {
            let k = keep
                .get_mut(t as usize)
                .ok_or(SortError::KeptOutOfRange { id: t, tets: n })?;
            if *k {
                return Err(SortError::DuplicateKept(t));
            }
            *k = true;
        }
    }
    let all: Vec<u32> = (0..n as u32).collect();
    let sorted = centroid_order(depths, &all);
    drop(all);
    let mut rank = vec![0u32; n];
    for (r, &t) in sorted.iter().enumerate() {
        rank[t as usize] = r as u32;
    }
    // The graph renumbered by rank (centroid order), gathered in parallel, so the sequential
    // loop below walks its arrays nearly in memory order: for each rank the ranks of the
    // cells that come after it (u32::MAX for none) and its in-degree.
    let (succ, mut indeg): (Vec<[u32; 4]>, Vec<u8>) = sorted
        .par_iter()
        .map(|&t| {
            let m = faces.masks[t as usize];
            let a = &faces.adjacency[t as usize];
            let s = [0, 1, 2, 3].map(|f| {
                if m & (1 << f) != 0 {
                    rank[a[f] as usize]
                } else {
                    u32::MAX
                }
            });
            (s, (m >> 4).count_ones() as u8)
        })
        .unzip();
    drop(rank);

    let mut emitted: Vec<u32> = Vec::with_capacity(n);
    let mut heap: BinaryHeap<Reverse<u32>> = BinaryHeap::new();
    let (mut cursor, mut first_left) = (0usize, 0usize);
    let (mut cycles_broken, mut reordered) = (0u64, 0u64);
    while emitted.len() < n {
        let r = if let Some(Reverse(r)) = heap.pop() {
            r as usize
        } else {
            while cursor < n && indeg[cursor] != 0 {
                cursor += 1;
            }
            if cursor < n {
                cursor += 1;
                cursor - 1
            } else {
                // Every remaining cell waits on another: a cycle. Emit the nearest one.
                while indeg[first_left] & DONE != 0 {
                    first_left += 1;
                }
                cycles_broken += 1;
                first_left
            }
        };
        indeg[r] = DONE;
        emitted.push(r as u32);
        for &v in &succ[r] {
            if v == u32::MAX {
                continue;
            }
            let d = &mut indeg[v as usize];
            if *d & DONE != 0 {
                continue; // a cell forced out of a cycle
            }
            *d -= 1;
            if *d == 0 && (v as usize) < cursor {
                heap.push(Reverse(v));
                reordered += 1;
            }
        }
    }
    drop((succ, indeg));
    let order: Vec<u32> = emitted
        .par_iter()
        .map(|&r| sorted[r as usize])
        .filter(|&t| keep[t as usize])
        .collect();
    Ok(MpvoResult {
        order,
        constraints: faces.constraints(),
        cycles_broken,
        reordered,
    })
}

/// The number of interior face pairs whose relative order in `order` (front to back, distinct
/// ids, possibly a subset of the tets) contradicts the MPVO relation of `view`: how
/// `--stats` measures the ordering errors of the centroid sort. Builds a [`FaceOrder`]; use
/// [`FaceOrder::count_violations`] to count several orders under one view.
///
/// # Panics
///
/// If `adjacency` is not a valid face adjacency of `mesh` (as [`TetMesh::face_adjacency`]
/// returns it; see [`FaceOrder::new`] for the checks) or `order` names a tet out of range.
pub fn count_violations(
    order: &[u32],
    adjacency: &[[u32; 4]],
    mesh: &TetMesh,
    view: &SortView,
) -> u64 {
    match FaceOrder::new(mesh, adjacency, view) {
        Ok(faces) => faces.count_violations(order),
        Err(e) => panic!("count_violations: {e}"),
    }
}
