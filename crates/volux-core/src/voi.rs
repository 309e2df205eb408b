//! The convex volume of interest (VOI) of seed `004_...txt` ch. 4: a convex polyhedron kept as
//! a planar graph (vertices and faces with ordered vertex loops, the edges shared by two
//! faces), starting as the data's bounding box and cut by planes (sec. 4.3.2, "recorte do
//! poliedro de amostragem"): each cut keeps the half-space `n . x + d >= 0` and adds one face,
//! the cap, whose loop follows the cut edges of the faces it crosses (the order the seed's
//! Weighted Sweep Graph gives the polygon of a cut, sec. 4.2.2).
//!
//! Degenerate cuts have defined results: a plane through a vertex, along an edge or along a
//! face that removes nothing leaves the VOI unchanged ([`Cut::Unchanged`]); a plane that would
//! leave nothing, or only a face, an edge or a point, is refused with
//! [`Error::EmptyVolumeOfInterest`] and leaves the VOI as it was.
use std::collections::HashMap;

use glam::DVec3;

use crate::aabb::Aabb;
use crate::error::{Error, Result};

/// A clipping plane: the half-space `normal . x + offset >= 0` is kept (world units; the
/// normal has unit length).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClipPlane {
    /// Unit normal, pointing into the kept half-space.
    pub normal: DVec3,
    /// Offset: the plane is `normal . x + offset = 0`.
    pub offset: f64,
}

impl ClipPlane {
    /// The plane `a x + b y + c z + d = 0` keeping `a x + b y + c z + d >= 0` (the CLI's
    /// `--clip-plane A,B,C,D`), scaled to a unit normal. Errors when a coefficient is not
    /// finite or the normal is (numerically) zero.
    pub fn new(a: f64, b: f64, c: f64, d: f64) -> Result<Self> {
        let n = DVec3::new(a, b, c);
        let len = n.length();
        let usable = [a, b, c, d].iter().all(|v| v.is_finite()) && len.is_finite() && len > 1e-300;
        if !usable {
            return Err(Error::InvalidClipPlane(format!(
                "{a},{b},{c},{d}: the normal (A,B,C) must be finite and non-zero, D finite"
            )));
        }
        Ok(Self {
            normal: n / len,
            offset: d / len,
        })
    }

    /// Checks a plane built field by field (e.g. read from a session file): finite, with a
    /// unit normal.
    pub fn check(&self) -> Result<()> {
        let (n, d) = (self.normal, self.offset);
        Self::new(n.x, n.y, n.z, d)?;
        if (n.length() - 1.0).abs() > 1e-6 {
            return Err(Error::InvalidClipPlane(format!(
                "{n:?}, {d}: the normal must have unit length"
            )));
        }
        Ok(())
    }

    /// Signed distance of `p` from the plane, positive on the kept side.
    pub fn distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p) + self.offset
    }
}

/// The part of `[t0, t1]` where the ray `origin + t dir` is on the kept side of every plane
/// (the slab test of a box, generalised to any convex set of half-spaces); `None` when no
/// interval of positive length is left.
pub fn clip_by_planes<'a>(
    planes: impl IntoIterator<Item = &'a ClipPlane>,
    origin: DVec3,
    dir: DVec3,
    (mut t0, mut t1): (f64, f64),
) -> Option<(f64, f64)> {
    for p in planes {
        let (d0, rate) = (p.distance(origin), p.normal.dot(dir));
        if rate > 0.0 {
            t0 = t0.max(-d0 / rate);
        } else if rate < 0.0 {
            t1 = t1.min(-d0 / rate);
        } else if d0 < 0.0 {
            return None;
        }
    }
    (t1 > t0).then_some((t0, t1))
}

/// One face of the VOI: its plane (normal pointing inside) and its vertex loop, counter-
/// clockwise seen from outside.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// The face's plane; the VOI lies on its kept side.
    pub plane: ClipPlane,
    /// Indices into [`ConvexVoi::vertices`], counter-clockwise seen from outside.
    pub vertices: Vec<u32>,
}

/// What a cut did to the VOI.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cut {
    /// The plane removed nothing (every vertex on its kept side or on it).
    Unchanged,
    /// The plane removed part of the VOI and added a face.
    Cut,
}

/// A convex polyhedron: the volume of interest (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct ConvexVoi {
    vertices: Vec<DVec3>,
    faces: Vec<Face>,
    /// Distances below this count as on a plane (a fixed fraction of the starting box's
    /// diagonal, so that results do not depend on where the data sits in the world).
    eps: f64,
}

/// The unit cube's faces: the axis, the side (0 low, 1 high) and the loop of corner indices
/// (bit 0 x, bit 1 y, bit 2 z), counter-clockwise seen from outside.
const BOX_FACES: [(usize, usize, [u32; 4]); 6] = [
    (0, 0, [0, 4, 6, 2]),
    (0, 1, [1, 3, 7, 5]),
    (1, 0, [0, 1, 5, 4]),
    (1, 1, [2, 6, 7, 3]),
    (2, 0, [0, 2, 3, 1]),
    (2, 1, [4, 5, 7, 6]),
];

impl ConvexVoi {
    /// The box `bounds` as a VOI. Errors when the box is not finite or is flat in some axis.
    pub fn from_aabb(bounds: &Aabb) -> Result<Self> {
        let size = bounds.max - bounds.min;
        if !(bounds.min.is_finite() && bounds.max.is_finite()) || size.min_element() <= 0.0 {
            return Err(Error::EmptyVolumeOfInterest(format!(
                "the box {:?} to {:?} has no volume",
                bounds.min, bounds.max
            )));
        }
        let vertices = (0..8)
            .map(|i| {
                let pick = |bit: u32, a: f64, b: f64| if i & bit != 0 { b } else { a };
                DVec3::new(
                    pick(1, bounds.min.x, bounds.max.x),
                    pick(2, bounds.min.y, bounds.max.y),
                    pick(4, bounds.min.z, bounds.max.z),
                )
            })
            .collect();
        let faces = BOX_FACES
            .iter()
            .map(|&(axis, side, ring)| {
                let mut normal = DVec3::ZERO;
                normal[axis] = if side == 0 { 1.0 } else { -1.0 };
                let at = if side == 0 {
                    bounds.min[axis]
                } else {
                    bounds.max[axis]
                };
                let offset = if side == 0 { -at } else { at };
                Face {
                    plane: ClipPlane { normal, offset },
                    vertices: ring.to_vec(),
                }
            })
            .collect();
        Ok(Self {
            vertices,
            faces,
            eps: 1e-9 * size.length(),
        })
    }

    /// The vertices.
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// The faces.
    pub fn faces(&self) -> &[Face] {
        &self.faces
    }

    /// The number of edges (each shared by two faces).
    pub fn edge_count(&self) -> usize {
        self.faces.iter().map(|f| f.vertices.len()).sum::<usize>() / 2
    }

    /// The planes that bound the VOI (one per face), for clipping rays and segments.
    pub fn planes(&self) -> impl Iterator<Item = &ClipPlane> {
        self.faces.iter().map(|f| &f.plane)
    }

    /// Whether `p` lies inside or on the VOI.
    pub fn contains(&self, p: DVec3) -> bool {
        self.planes().all(|pl| pl.distance(p) >= -self.eps)
    }

    /// The parameter interval of the segment `origin + t dir`, `t` in `[t0, t1]`, that lies
    /// inside the VOI; `None` when the segment misses it.
    pub fn clip_segment(&self, origin: DVec3, dir: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        clip_by_planes(self.planes(), origin, dir, (t0, t1))
    }

    /// The volume enclosed (the divergence theorem over the faces' fans).
    pub fn volume(&self) -> f64 {
        let c = self.centroid();
        let mut v = 0.0;
        for f in &self.faces {
            let p = |k: usize| self.vertices[f.vertices[k] as usize] - c;
            for k in 1..f.vertices.len() - 1 {
                v += p(0).dot(p(k).cross(p(k + 1)));
            }
        }
        v / 6.0
    }

    /// The mean of the vertices (a point inside the VOI).
    pub fn centroid(&self) -> DVec3 {
        self.vertices.iter().sum::<DVec3>() / self.vertices.len() as f64
    }

    /// Cuts the VOI by `plane`, keeping its kept side (sec. 4.3.2). On error the VOI is left
    /// unchanged.
    pub fn cut(&mut self, plane: &ClipPlane) -> Result<Cut> {
        let (dist, side) = self.classify(plane);
        if !side.contains(&Side::Out) {
            return Ok(Cut::Unchanged);
        }
        if !side.contains(&Side::In) {
            return Err(Error::EmptyVolumeOfInterest(
                "the plane would remove the whole volume of interest".into(),
            ));
        }
        let cutter = Cutter::new(&self.vertices, &dist, &side);
        let (vertices, faces) = cutter.run(&self.faces, plane)?;
        (self.vertices, self.faces) = (vertices, faces);
        Ok(Cut::Cut)
    }
}

/// The most slices [`ConvexVoi::sweep`] returns.
pub const MAX_SWEEP_SLICES: usize = 1 << 20;

impl ConvexVoi {
    /// The polygons where the planes `k . x = d` cut the VOI, for `d` from the lowest vertex
    /// weight `k . v` up in steps of `step` (the slices of slice-based rendering, sec. 4.2.2):
    /// each polygon counter-clockwise about `-k`, an empty one where a plane only touches the
    /// VOI. As with the seed's Weighted Sweep Graph, the support edges (the edges the planes
    /// cross) change only at events, the vertex weights: they are found once per interval
    /// between events and each slice interpolates along them. Errors when `k` is zero or not
    /// finite, `step` is not positive, or more than [`MAX_SWEEP_SLICES`] slices would result.
    pub fn sweep(&self, k: DVec3, step: f64) -> Result<Vec<Vec<DVec3>>> {
        let dir = ClipPlane::new(k.x, k.y, k.z, 0.0)?.normal;
        let weights: Vec<f64> = self.vertices.iter().map(|&v| dir.dot(v)).collect();
        let mut events = weights.clone();
        events.sort_by(f64::total_cmp);
        events.dedup_by(|a, b| *a - *b <= self.eps);
        let (lo, hi) = (events[0], events[events.len() - 1]);
        let count = ((hi - lo) / step).floor() + 1.0;
        let usable = step > 0.0 && count <= MAX_SWEEP_SLICES as f64;
        if !usable {
            return Err(Error::InvalidSweep(format!(
                "step {step}: must be > 0 and give at most {MAX_SWEEP_SLICES} slices"
            )));
        }
        let mut out = Vec::with_capacity(count as usize);
        let mut interval = 0;
        let mut support: Option<Vec<(u32, u32)>> = None;
        for i in 0..count as usize {
            let d = lo + i as f64 * step;
            while interval + 1 < events.len() && d >= events[interval + 1] {
                (interval, support) = (interval + 1, None);
            }
            if interval + 1 >= events.len() || d <= events[interval] + self.eps {
                // On an event: the plane passes through vertices; cut it directly.
                out.push(self.section(&ClipPlane {
                    normal: dir,
                    offset: -d,
                }));
                continue;
            }
            let mid = 0.5 * (events[interval] + events[interval + 1]);
            let edges = support.get_or_insert_with(|| {
                self.support_edges(&ClipPlane {
                    normal: dir,
                    offset: -mid,
                })
            });
            out.push(self.interpolate(edges, &weights, d));
        }
        Ok(out)
    }

    /// The polygon where `plane` cuts the VOI (empty when it only touches it or misses it).
    pub fn section(&self, plane: &ClipPlane) -> Vec<DVec3> {
        let mut voi = self.clone();
        match voi.cut(plane) {
            // A cut's cap is its last face.
            Ok(Cut::Cut) => voi.faces.last().map_or(vec![], |cap| {
                cap.vertices
                    .iter()
                    .map(|&v| voi.vertices[v as usize])
                    .collect()
            }),
            _ => vec![],
        }
    }

    /// The support edges of the plane `plane`, in the order of its polygon.
    fn support_edges(&self, plane: &ClipPlane) -> Vec<(u32, u32)> {
        let (dist, side) = self.classify(plane);
        Cutter::new(&self.vertices, &dist, &side)
            .support_edges(&self.faces)
            .unwrap_or_default()
    }

    /// Each vertex's signed distance from `plane` and its side.
    fn classify(&self, plane: &ClipPlane) -> (Vec<f64>, Vec<Side>) {
        let dist: Vec<f64> = self.vertices.iter().map(|&v| plane.distance(v)).collect();
        let side = dist.iter().map(|&d| Side::of(d, self.eps)).collect();
        (dist, side)
    }

    /// The points at weight `d` along the support edges `edges`.
    fn interpolate(&self, edges: &[(u32, u32)], weights: &[f64], d: f64) -> Vec<DVec3> {
        edges
            .iter()
            .map(|&(a, b)| {
                let (pa, pb) = (self.vertices[a as usize], self.vertices[b as usize]);
                let (wa, wb) = (weights[a as usize], weights[b as usize]);
                pa + (pb - pa) * ((d - wa) / (wb - wa))
            })
            .collect()
    }
}

/// Where a vertex lies against the cutting plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    In,
    On,
    Out,
}

impl Side {
    fn of(d: f64, eps: f64) -> Self {
        if d > eps {
            Side::In
        } else if d < -eps {
            Side::Out
        } else {
            Side::On
        }
    }
}

/// One cut in progress: the kept vertices renumbered, and the new vertices on cut edges.
struct Cutter<'a> {
    old: &'a [DVec3],
    dist: &'a [f64],
    side: &'a [Side],
    /// New index of each old vertex (`u32::MAX` for removed ones).
    remap: Vec<u32>,
    vertices: Vec<DVec3>,
    /// Whether each new vertex lies on the cutting plane.
    on_plane: Vec<bool>,
    /// The new vertex on each cut edge, by the edge's (smaller, larger) old indices.
    on_edge: HashMap<(u32, u32), u32>,
}

impl<'a> Cutter<'a> {
    fn new(old: &'a [DVec3], dist: &'a [f64], side: &'a [Side]) -> Self {
        let (mut remap, mut vertices, mut on_plane) = (vec![u32::MAX; old.len()], vec![], vec![]);
        for (i, &s) in side.iter().enumerate() {
            if s != Side::Out {
                remap[i] = vertices.len() as u32;
                vertices.push(old[i]);
                on_plane.push(s == Side::On);
            }
        }
        Self {
            old,
            dist,
            side,
            remap,
            vertices,
            on_plane,
            on_edge: HashMap::new(),
        }
    }

    /// The new vertex where the edge `a`-`b` (one in, one out) crosses the plane.
    fn crossing(&mut self, a: u32, b: u32) -> u32 {
        let key = (a.min(b), a.max(b));
        if let Some(&v) = self.on_edge.get(&key) {
            return v;
        }
        let (pa, pb) = (self.old[key.0 as usize], self.old[key.1 as usize]);
        let (da, db) = (self.dist[key.0 as usize], self.dist[key.1 as usize]);
        let v = self.vertices.len() as u32;
        self.vertices.push(pa + (pb - pa) * (da / (da - db)));
        self.on_plane.push(true);
        self.on_edge.insert(key, v);
        v
    }

    /// The face's loop clipped to the kept side (Sutherland-Hodgman on a convex polygon).
    fn clip_loop(&mut self, ring: &[u32]) -> Vec<u32> {
        let mut out = Vec::with_capacity(ring.len() + 1);
        for (k, &a) in ring.iter().enumerate() {
            let b = ring[(k + 1) % ring.len()];
            let (sa, sb) = (self.side[a as usize], self.side[b as usize]);
            if sa != Side::Out {
                out.push(self.remap[a as usize]);
            }
            if (sa == Side::In && sb == Side::Out) || (sa == Side::Out && sb == Side::In) {
                out.push(self.crossing(a, b));
            }
        }
        out
    }

    /// The kept faces, and the cap's edges (each the reverse of a kept face's edge on the
    /// plane), start -> end.
    fn clip_faces(&mut self, faces: &[Face]) -> (Vec<Face>, HashMap<u32, u32>) {
        let mut kept = Vec::with_capacity(faces.len() + 1);
        let mut cap_next = HashMap::new();
        for f in faces {
            let ring = self.clip_loop(&f.vertices);
            if ring.len() < 3 {
                continue;
            }
            for (k, &p) in ring.iter().enumerate() {
                let q = ring[(k + 1) % ring.len()];
                if self.on_plane[p as usize] && self.on_plane[q as usize] {
                    cap_next.insert(q, p);
                }
            }
            kept.push(Face {
                plane: f.plane,
                vertices: ring,
            });
        }
        (kept, cap_next)
    }

    /// The kept faces and the cap; the vertices compacted to those the faces use.
    fn run(mut self, faces: &[Face], plane: &ClipPlane) -> Result<(Vec<DVec3>, Vec<Face>)> {
        let (mut kept, cap_next) = self.clip_faces(faces);
        let cap = chain(&cap_next)?;
        kept.push(Face {
            plane: *plane,
            vertices: cap,
        });
        Ok(compact(self.vertices, kept))
    }

    /// The old edges under the cap's vertices, in the cap's order, when every cap vertex is
    /// a crossing (no old vertex on the plane).
    fn support_edges(mut self, faces: &[Face]) -> Option<Vec<(u32, u32)>> {
        let (_, cap_next) = self.clip_faces(faces);
        let cap = chain(&cap_next).ok()?;
        let by_vertex: HashMap<u32, (u32, u32)> =
            self.on_edge.iter().map(|(&e, &v)| (v, e)).collect();
        cap.iter().map(|v| by_vertex.get(v).copied()).collect()
    }
}

/// The cap's loop from its edges (start -> end), or an error if they do not form one loop.
fn chain(next: &HashMap<u32, u32>) -> Result<Vec<u32>> {
    let broken = || {
        Error::EmptyVolumeOfInterest("the cut leaves no volume (its cap is not a polygon)".into())
    };
    let &start = next.keys().min().ok_or_else(broken)?;
    let mut ring = vec![start];
    let mut at = start;
    loop {
        at = *next.get(&at).ok_or_else(broken)?;
        if at == start {
            break;
        }
        if ring.len() >= next.len() {
            return Err(broken());
        }
        ring.push(at);
    }
    if ring.len() < 3 || ring.len() != next.len() {
        return Err(broken());
    }
    Ok(ring)
}

/// Drops vertices no face uses and renumbers the loops.
fn compact(vertices: Vec<DVec3>, mut faces: Vec<Face>) -> (Vec<DVec3>, Vec<Face>) {
    let mut remap = vec![u32::MAX; vertices.len()];
    let mut out = Vec::with_capacity(vertices.len());
    for f in &mut faces {
        for v in &mut f.vertices {
            let r = &mut remap[*v as usize];
            if *r == u32::MAX {
                *r = out.len() as u32;
                out.push(vertices[*v as usize]);
            }
            *v = *r;
        }
    }
    (out, faces)
}

#[cfg(test)]
#[path = "voi/tests.rs"]
mod tests;
