//! A bounding volume hierarchy over a set of cells, for the ray's entry into the mesh
//! (Garrity's boundary-face entry, seed `000` §2.4).
//!
//! The primitives are the cells owning boundary faces (each cell once, however many of its
//! faces lie on the boundary) and the other cells with a vertex on the boundary, boxed by the
//! cell's bounding box: a query returns the nearest cell whose reference clip
//! ([`Geometry::clip`]) reaches past a given `t`. That is the cell entered through the
//! nearest boundary face beyond `t` — also when the ray enters exactly through a boundary
//! edge or vertex and continues in a cell touching the boundary only there (the tie rule may
//! give the ray to it rather than to the face owners; such a cell has a boundary vertex) —
//! and it also finds a boundary cell the ray is already inside (the walk's fallback). The
//! same structure, built per frame over the cells around the eye (or across an orthographic
//! camera's eye plane), starts rays whose origin lies inside the mesh.
//!
//! Nodes are a flat array (children of an inner node are adjacent), built by median split of
//! the primitives' centroids on the widest axis, at most [`LEAF`] primitives per leaf; boxes
//! are padded by a small multiple of the mesh size so that rays lying in a box face are
//! never rejected, and stored as `f32` rounded outward (the slab test is in `f64`). Each
//! primitive's own box is kept too and tested before its clip. Traversal is nearest child
//! first, children culled before they are pushed, with pruning against the best hit (which
//! a caller may seed with a candidate, e.g. the neighbouring ray's answer).
use glam::DVec3;

use super::geom::{Clip, Geometry};

/// Most primitives in a leaf.
pub(crate) const LEAF: usize = 4;

/// A node: its box (`f32`, rounded outward from the `f64` box), then either two children at
/// `first`, `first + 1` (`count == 0`) or `count` primitives from `first` in the primitive
/// array.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: [f32; 3],
    hi: [f32; 3],
    first: u32,
    count: u32,
}

/// `v` rounded to an `f32` no larger than it.
fn f32_down(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) > v {
        f.next_down()
    } else {
        f
    }
}

/// `v` rounded to an `f32` no smaller than it.
fn f32_up(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) < v {
        f.next_up()
    } else {
        f
    }
}

impl Node {
    const EMPTY: Node = Node {
        lo: [0.0; 3],
        hi: [0.0; 3],
        first: 0,
        count: 0,
    };

    /// The parameters `(near, far)` where the ray `o + t d` (`inv = 1 / d`) enters and leaves
    /// the box, in `f64`.
    #[inline(always)]
    fn slab(&self, o: DVec3, inv: DVec3) -> (f64, f64) {
        let lo = DVec3::new(self.lo[0].into(), self.lo[1].into(), self.lo[2].into());
        let hi = DVec3::new(self.hi[0].into(), self.hi[1].into(), self.hi[2].into());
        let a = (lo - o) * inv;
        let b = (hi - o) * inv;
        // f64::min/max ignore a NaN (0 * inf: the origin on a padded face, parallel).
        let near = a.x.min(b.x).max(a.y.min(b.y)).max(a.z.min(b.z));
        let far = a.x.max(b.x).min(a.y.max(b.y)).min(a.z.max(b.z));
        (near, far)
    }
}

/// Whether a box the ray crosses over `(near, far)` may hold a hit past `t_lo` starting no
/// later than `best_key` (kept when a comparison is NaN).
#[inline(always)]
fn may_hold((near, far): (f64, f64), t_lo: f64, best_key: f64) -> bool {
    !(far < t_lo || near > far || near > best_key)
}

/// The largest distance from `from` to a corner of `node`'s box.
#[inline]
fn far_corner(node: &Node, from: DVec3) -> f64 {
    let lo = DVec3::from_array(node.lo.map(f64::from)) - from;
    let hi = DVec3::from_array(node.hi.map(f64::from)) - from;
    lo.abs().max(hi.abs()).length()
}

/// The hierarchy.
#[derive(Clone, Debug, Default)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    prims: Vec<u32>,
    /// The padded box of each primitive (as a node without children), tested before its
    /// clip.
    prim_boxes: Vec<Node>,
}

/// A hit of [`Bvh::nearest`]: the tet and its clip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hit {
    pub tet: u32,
    pub clip: Clip,
}

impl Hit {
    /// The hit's start beyond `t_lo`.
    #[inline]
    pub fn key(&self, t_lo: f64) -> f64 {
        self.clip.t_in.max(t_lo)
    }

    /// Whether `self` starts before `other` (ties by tet index).
    pub fn before(&self, other: &Hit, t_lo: f64) -> bool {
        let (a, b) = (self.key(t_lo), other.key(t_lo));
        a < b || (a == b && self.tet < other.tet)
    }
}

impl Bvh {
    /// Builds the hierarchy over the cells `tets`, boxed by `boxes` and padded by `pad`.
    pub fn build(tets: Vec<u32>, boxes: impl Fn(u32) -> (DVec3, DVec3), pad: f64) -> Self {
        let mut prims = tets;
        if prims.is_empty() {
            return Self::default();
        }
        let bounds: Vec<(DVec3, DVec3)> = prims
            .iter()
            .map(|&t| {
                let (lo, hi) = boxes(t);
                (lo - DVec3::splat(pad), hi + DVec3::splat(pad))
            })
            .collect();
        // Work on (prim, box index) pairs; boxes are indexed by position in the input.
        let mut items: Vec<(u32, u32)> = prims
            .iter()
            .enumerate()
            .map(|(i, &t)| (t, i as u32))
            .collect();
        let mut nodes = Vec::with_capacity(2 * items.len() / LEAF + 2);
        nodes.push(Node::EMPTY);
        let mut stack = vec![(0usize, 0usize, items.len())];
        while let Some((node, begin, end)) = stack.pop() {
            let slice = &mut items[begin..end];
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            let (mut clo, mut chi) = (lo, hi);
            for &(_, b) in slice.iter() {
                let (a, z) = bounds[b as usize];
                lo = lo.min(a);
                hi = hi.max(z);
                let c = (a + z) * 0.5;
                clo = clo.min(c);
                chi = chi.max(c);
            }
            nodes[node].lo = lo.to_array().map(f32_down);
            nodes[node].hi = hi.to_array().map(f32_up);
            let ext = chi - clo;
            if slice.len() <= LEAF || ext.max_element() <= 0.0 {
                nodes[node].first = begin as u32;
                nodes[node].count = slice.len() as u32;
                continue;
            }
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = slice.len() / 2;
            let centre = |b: u32| {
                let (a, z) = bounds[b as usize];
                (a[axis] + z[axis]) * 0.5
            };
            slice.select_nth_unstable_by(mid, |x, y| {
                centre(x.1).total_cmp(&centre(y.1)).then(x.0.cmp(&y.0))
            });
            let left = nodes.len();
            nodes.extend([Node::EMPTY; 2]);
            nodes[node].first = left as u32;
            stack.push((left + 1, begin + mid, end));
            stack.push((left, begin, begin + mid));
        }
        let prim_boxes = items
            .iter()
            .map(|&(_, b)| {
                let (lo, hi) = bounds[b as usize];
                Node {
                    lo: lo.to_array().map(f32_down),
                    hi: hi.to_array().map(f32_up),
                    ..Node::EMPTY
                }
            })
            .collect();
        prims = items.into_iter().map(|(t, _)| t).collect();
        Self {
            nodes,
            prims,
            prim_boxes,
        }
    }

    /// Peak bytes per cell while [`Bvh::build`] builds: the cell list, its padded box, the
    /// (cell, box) pairs, its box in the hierarchy and the nodes (at most two per leaf).
    pub fn build_bytes_per_cell() -> u64 {
        let node = std::mem::size_of::<Node>();
        (4 + std::mem::size_of::<(DVec3, DVec3)>() + 8 + node + (2 * node).div_ceil(LEAF)) as u64
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.prims.len()
    }

    /// Bytes of the nodes and primitive list.
    pub fn bytes(&self) -> usize {
        (self.nodes.len() + self.prim_boxes.len()) * std::mem::size_of::<Node>()
            + self.prims.len() * 4
    }

    /// The cell whose clip reaches past `t_lo` and starts first (`max(t_in, t_lo)`, ties by
    /// index), or `None`.
    pub fn nearest(&self, geo: &Geometry, o: DVec3, d: DVec3, t_lo: f64) -> Option<Hit> {
        self.nearest_from(geo, o, d, [t_lo, f64::INFINITY], None)
    }

    /// [`Bvh::nearest`] past `t_lo` given a `candidate`, a hit of one of the primitives (e.g.
    /// the answer for a neighbouring ray, clipped with this one), and a bound `t_hi` known to
    /// be at or past the start of the answer, if there is one (e.g. a tile's reach): the
    /// answer is the same, but the traversal prunes against the candidate and the bound from
    /// the start.
    pub fn nearest_from(
        &self,
        geo: &Geometry,
        o: DVec3,
        d: DVec3,
        [t_lo, t_hi]: [f64; 2],
        candidate: Option<Hit>,
    ) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let inv = DVec3::ONE / d;
        let mut best = candidate.filter(|h| h.clip.t_out > t_lo);
        let mut best_key = best.map_or(t_hi, |h| h.key(t_lo).min(t_hi));
        // Nodes to visit, with the parameter where the ray enters their box.
        let mut stack: [(u32, f64); 64] = [(0, 0.0); 64];
        let root = self.nodes[0].slab(o, inv);
        if !may_hold(root, t_lo, best_key) {
            return best;
        }
        stack[0] = (0, root.0);
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let (index, near) = stack[sp];
            if near > best_key {
                continue;
            }
            let node = &self.nodes[index as usize];
            if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for (&t, b) in self.prims[range.clone()]
                    .iter()
                    .zip(&self.prim_boxes[range])
                {
                    if !may_hold(b.slab(o, inv), t_lo, best_key) {
                        continue;
                    }
                    if let Some(clip) = geo.clip(t as usize, o, d) {
                        if clip.t_out > t_lo {
                            let hit = Hit { tet: t, clip };
                            if best.is_none_or(|b| hit.before(&b, t_lo)) {
                                best_key = hit.key(t_lo);
                                best = Some(hit);
                            }
                        }
                    }
                }
                continue;
            }
            let (l, r) = (node.first, node.first + 1);
            let sl = self.nodes[l as usize].slab(o, inv);
            let sr = self.nodes[r as usize].slab(o, inv);
            let (hl, hr) = (may_hold(sl, t_lo, best_key), may_hold(sr, t_lo, best_key));
            if sp + 2 > stack.len() {
                // Unreachable for median splits (depth <= log2(n) + 1); stay correct anyway.
                return self.nearest_linear(geo, o, d, t_lo);
            }
            // Push the farther child first so the nearer one is visited first.
            let (first, second) = if sl.0 <= sr.0 {
                ((r, sr.0, hr), (l, sl.0, hl))
            } else {
                ((l, sl.0, hl), (r, sr.0, hr))
            };
            for (child, near, hit) in [first, second] {
                if hit {
                    stack[sp] = (child, near);
                    sp += 1;
                }
            }
        }
        best
    }

    /// Primitive `i` (hierarchy order).
    pub fn prim(&self, i: usize) -> u32 {
        self.prims[i]
    }

    /// The largest distance from `from` to a corner of primitive `i`'s padded box: every
    /// point of the cell lies at most this far from `from`.
    pub fn far_corner(&self, i: usize, from: DVec3) -> f64 {
        far_corner(&self.prim_boxes[i], from)
    }

    fn nearest_linear(&self, geo: &Geometry, o: DVec3, d: DVec3, t_lo: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for &t in &self.prims {
            if let Some(clip) = geo.clip(t as usize, o, d) {
                let hit = Hit { tet: t, clip };
                if clip.t_out > t_lo && best.is_none_or(|b| hit.before(&b, t_lo)) {
                    best = Some(hit);
                }
            }
        }
        best
    }
}
