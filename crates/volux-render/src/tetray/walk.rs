//! The cell-to-cell walk of one ray (Garrity; Bunyk et al.; Weiler et al.'s HARC, seed `000`
//! §2.4): enter through the nearest boundary face, then repeatedly clip the ray against the
//! current cell, emit the segment `(s_in, s_out, length)` and step to the neighbour across
//! the exit face; at a boundary exit, look the next entry up in the boundary hierarchy (a
//! re-entry of a non-convex mesh).
//!
//! # Robustness
//!
//! Each cell's interval is the reference's clip (`Geometry::clip`): shared faces give
//! bit-identical crossing parameters in both cells, and a ray in a face plane is claimed by
//! exactly one of them. Every emitted segment has positive length and starts where the
//! previous one ended (or later), so the current parameter `t` strictly increases and no cell
//! is emitted twice: the walk cannot loop. When the neighbour across the exit face does not
//! continue the ray (it left through an edge or a vertex, so the chosen exit face was one of
//! several; or it runs in a face plane the tie rule gives to another cell), a **local
//! search** visits the cells around the exit point (breadth first across faces, only cells
//! containing the point up to a tolerance, at most `LOCAL_SEARCH` of them) and continues in
//! the one whose clip starts first past `t`. Only when that finds nothing is the boundary
//! hierarchy queried from `t`: a true exit from the mesh (counted as a re-entry when the
//! hierarchy finds more of the mesh), or, on a non-manifold mesh, a lost walk (counted as a
//! recovery). A step bound (`4 n + 64` cells) backs all this up; a ray that reaches it is
//! abandoned (counted) with what it composited so far.
use glam::DVec3;
use volux_core::mesh::NO_NEIGHBOR;

use super::bvh::{Bvh, Hit};
use super::geom::Geometry;
use super::skip::Visibility;

/// Most cells the local search around an edge or vertex visits.
pub(crate) const LOCAL_SEARCH: usize = 512;

/// Most invisible cells [`Walker::trace_visible`] walks through before it asks the hierarchy
/// of visible cells for the next one: short invisible runs (and the last run up to the ray's
/// reach) are cheaper to walk than to query.
pub(crate) const INVISIBLE_RUN: usize = 16;

/// One segment of a ray in one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkSegment {
    /// Entry parameter.
    pub t_in: f64,
    /// Exit parameter (`> t_in`).
    pub t_out: f64,
    /// Scalar at the entry.
    pub s_in: f64,
    /// Scalar at the exit.
    pub s_out: f64,
    /// The cell.
    pub tet: u32,
}

/// What happened to one ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WalkOutcome {
    /// Segments emitted.
    pub segments: u64,
    /// Entries found by the boundary hierarchy after a boundary exit.
    pub reentries: u64,
    /// Walks that lost the cell-to-cell path and were resumed by the hierarchy.
    pub recovered: u64,
    /// Local searches around an edge or vertex, where the neighbour across the exit face did
    /// not continue the ray (boundary exits are not counted).
    pub local_searches: u64,
    /// Whether the step bound stopped the ray.
    pub abandoned: bool,
    /// Jumps over runs of invisible cells through the hierarchy of visible cells
    /// (`Walker::trace_visible` only).
    pub skips: u64,
}

/// Where a ray's walk over the visible cells starts ([`Walker::trace_visible`]).
pub(crate) struct VisibleRay<'v> {
    /// The visible cells.
    pub vis: &'v Visibility,
    /// The ray parameter past which no visible cell is met (the tile's reach,
    /// [`super::first`], or infinity).
    pub t_limit: f64,
    /// The ray's first visible cell from `t = 0` ([`Walker::first_visible`], or per tile in
    /// [`super::first`]), `None` when it meets none.
    pub first: Option<Hit>,
}

/// Reusable buffers of the local search.
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    visited: Vec<u32>,
    queue: Vec<u32>,
    /// The first visible cell of the previous ray ([`Walker::trace_visible`]): neighbouring
    /// rays mostly start in the same cell, and the hierarchy prunes against it.
    first: Option<u32>,
}

/// A ray tracer over one mesh's geometry.
pub(crate) struct Walker<'a> {
    pub geo: &'a Geometry,
    pub boundary: &'a Bvh,
    /// Cells around the ray origins (camera inside the mesh), or an empty hierarchy.
    pub start: &'a Bvh,
    pub max_steps: usize,
}

impl Walker<'_> {
    /// The first cell past `t_lo` of the boundary and start hierarchies.
    fn query(&self, o: DVec3, d: DVec3, t_lo: f64, with_start: bool) -> Option<Hit> {
        let a = self.boundary.nearest(self.geo, o, d, t_lo);
        let b = if with_start {
            self.start.nearest(self.geo, o, d, t_lo)
        } else {
            None
        };
        match (a, b) {
            (Some(a), Some(b)) => Some(if b.before(&a, t_lo) { b } else { a }),
            (a, b) => a.or(b),
        }
    }

    /// The cell continuing the ray at `t` near cell `from`, by breadth-first search over the
    /// cells containing the point `o + t d`; `None` when none reaches past `t`.
    fn local_search(
        &self,
        from: u32,
        o: DVec3,
        d: DVec3,
        t: f64,
        scratch: &mut Scratch,
    ) -> Option<Hit> {
        let geo = self.geo;
        let p = o + d * t;
        let tol = 1e-9 * geo.scale;
        scratch.visited.clear();
        scratch.queue.clear();
        scratch.visited.push(from);
        scratch.queue.push(from);
        let mut head = 0;
        let mut best: Option<Hit> = None;
        while head < scratch.queue.len() {
            let x = scratch.queue[head] as usize;
            head += 1;
            for y in geo.adj(x) {
                if y == NO_NEIGHBOR || scratch.visited.contains(&y) {
                    continue;
                }
                if scratch.visited.len() >= LOCAL_SEARCH {
                    break;
                }
                scratch.visited.push(y);
                if !geo.contains(y as usize, p, tol) {
                    continue;
                }
                scratch.queue.push(y);
                if let Some(clip) = geo.clip(y as usize, o, d) {
                    let hit = Hit { tet: y, clip };
                    if clip.t_out > t && best.is_none_or(|b| hit.before(&b, t)) {
                        best = Some(hit);
                    }
                }
            }
        }
        // A cell starting well past `t` is not a continuation; let the hierarchy decide.
        best.filter(|b| b.key(t) <= t + tol * (1.0 + d.length().recip()))
    }

    /// The segment of `hit` past `t` (the previous exit) on the ray `o + t d`.
    #[inline]
    fn segment(&self, hit: &Hit, o: DVec3, d: DVec3, t: f64) -> WalkSegment {
        let tet = hit.tet as usize;
        let (t0, t1) = (hit.clip.t_in.max(t), hit.clip.t_out);
        WalkSegment {
            t_in: t0,
            t_out: t1,
            s_in: self.geo.scalar(tet, o + d * t0),
            s_out: self.geo.scalar(tet, o + d * t1),
            tet: hit.tet,
        }
    }

    /// Walks the ray `o + t d`, `t >= 0`, through the visible cells of `start.vis` only
    /// ([`super::skip`]) from its first visible cell `start.first`, calling `sink` with each
    /// of their segments in front-to-back order until it returns `false` or no visible cell
    /// is left; no visible cell is met past `start.t_limit` (the ray's tile's reach,
    /// or infinity). The walk steps across the
    /// exit face while the neighbour is visible and continues the ray, and through up to
    /// [`INVISIBLE_RUN`] invisible cells (without segments) until it enters a visible one or
    /// passes `t_limit`; otherwise (a longer invisible run, a boundary exit, an exit through an
    /// edge or a vertex) the hierarchy of visible cells gives the first one past the exit.
    /// The segments are those of [`Walker::trace`] less the invisible cells' (up to the choice
    /// among cells tied at an edge or vertex, and the rounding of a segment's start there).
    /// Counted: visible cells reached past invisible ones as `skips`, past a boundary face as
    /// `reentries`, and visible neighbours that did not continue the ray as `local_searches`
    /// (resolved by the hierarchy here).
    pub fn trace_visible(
        &self,
        start: &VisibleRay<'_>,
        o: DVec3,
        d: DVec3,
        mut sink: impl FnMut(&WalkSegment) -> bool,
    ) -> WalkOutcome {
        let mut out = WalkOutcome::default();
        if !(o.is_finite() && d.is_finite()) || d == DVec3::ZERO {
            return out;
        }
        let (vis, t_limit) = (start.vis, start.t_limit);
        let geo = self.geo;
        let mut t = 0.0f64;
        let mut next = start.first;
        let mut steps = 0usize;
        while let Some(hit) = next {
            steps += 1;
            if steps > self.max_steps {
                out.abandoned = true;
                break;
            }
            let seg = self.segment(&hit, o, d, t);
            out.segments += 1;
            t = seg.t_out;
            // The neighbour is clipped before the segment is coloured: its cell record and
            // face planes load while the segment's integral is computed.
            let nb = geo.adj(hit.tet as usize)[hit.clip.exit as usize];
            let entered = if nb != NO_NEIGHBOR {
                self.enter_neighbour(nb, o, d, t)
            } else {
                None
            };
            if !sink(&seg) {
                break;
            }
            next = match entered {
                Some(h) if vis.is_visible(nb) => Some(h),
                Some(h) => self.cross_invisible(vis, h, t, t_limit, o, d, &mut out),
                None => {
                    if nb != NO_NEIGHBOR && vis.is_visible(nb) {
                        out.local_searches += 1;
                    }
                    self.jump(vis, nb == NO_NEIGHBOR, t, t_limit, o, d, &mut out)
                }
            };
        }
        out
    }

    /// The first visible cell of the ray `o + t d` from `t = 0` (before `t_limit`), from the
    /// hierarchy of visible cells, pruned against the previous ray's first cell (kept in
    /// `scratch`).
    pub fn first_visible(
        &self,
        vis: &Visibility,
        t_limit: f64,
        o: DVec3,
        d: DVec3,
        scratch: &mut Scratch,
    ) -> Option<Hit> {
        if !(o.is_finite() && d.is_finite()) || d == DVec3::ZERO {
            return None;
        }
        let geo = self.geo;
        let candidate = scratch
            .first
            .and_then(|c| geo.clip(c as usize, o, d).map(|clip| Hit { tet: c, clip }));
        let first = vis.bvh.nearest_from(geo, o, d, [0.0, t_limit], candidate);
        if let Some(h) = first {
            scratch.first = Some(h.tet);
        }
        first
    }

    /// The first visible cell past the invisible cell `hit` entered at `t`: found by walking
    /// through up to [`INVISIBLE_RUN`] invisible cells, `None` once the walk passes `t_limit`,
    /// otherwise from the hierarchy ([`Walker::jump`]).
    #[allow(clippy::too_many_arguments)]
    fn cross_invisible(
        &self,
        vis: &Visibility,
        mut hit: Hit,
        mut t: f64,
        t_limit: f64,
        o: DVec3,
        d: DVec3,
        out: &mut WalkOutcome,
    ) -> Option<Hit> {
        for _ in 0..INVISIBLE_RUN {
            if t >= t_limit {
                return None;
            }
            let t_out = hit.clip.t_out;
            let nb = self.geo.adj(hit.tet as usize)[hit.clip.exit as usize];
            if nb == NO_NEIGHBOR {
                return self.jump(vis, true, t_out, t_limit, o, d, out);
            }
            match self.enter_neighbour(nb, o, d, t_out) {
                Some(h) if vis.is_visible(nb) => {
                    out.skips += 1;
                    return Some(h);
                }
                Some(h) => (hit, t) = (h, t_out),
                None => return self.jump(vis, false, t_out, t_limit, o, d, out),
            }
        }
        self.jump(vis, false, t, t_limit, o, d, out)
    }

    /// The first visible cell past `t` before `t_limit` from the hierarchy, counted as a
    /// re-entry past a `boundary` exit and as a skip otherwise.
    #[allow(clippy::too_many_arguments)]
    fn jump(
        &self,
        vis: &Visibility,
        boundary: bool,
        t: f64,
        t_limit: f64,
        o: DVec3,
        d: DVec3,
        out: &mut WalkOutcome,
    ) -> Option<Hit> {
        if t >= t_limit {
            return None;
        }
        let next = vis.bvh.nearest_from(self.geo, o, d, [t, t_limit], None);
        if next.is_some() {
            if boundary {
                out.reentries += 1;
            } else {
                out.skips += 1;
            }
        }
        next
    }

    /// The neighbour `nb` entered through the exit face of `hit` at `t`, when the ray goes
    /// on in it (its entry parameter is `t`, bit for bit: [`Geometry::clip`]).
    #[inline(always)]
    fn enter_neighbour(&self, nb: u32, o: DVec3, d: DVec3, t: f64) -> Option<Hit> {
        let clip = self.geo.clip(nb as usize, o, d)?;
        (clip.t_out > t).then_some(Hit { tet: nb, clip })
    }

    /// Walks the ray `o + t d`, `t >= 0`, calling `sink` with each segment in front-to-back
    /// order until it returns `false` (early termination) or the ray leaves the mesh.
    pub fn trace(
        &self,
        o: DVec3,
        d: DVec3,
        scratch: &mut Scratch,
        mut sink: impl FnMut(&WalkSegment) -> bool,
    ) -> WalkOutcome {
        let mut out = WalkOutcome::default();
        if !(o.is_finite() && d.is_finite()) || d == DVec3::ZERO {
            return out;
        }
        let geo = self.geo;
        let mut t = 0.0f64;
        let mut next = self.query(o, d, 0.0, true);
        let mut steps = 0usize;
        while let Some(hit) = next {
            steps += 1;
            if steps > self.max_steps {
                out.abandoned = true;
                break;
            }
            let tet = hit.tet as usize;
            let seg = self.segment(&hit, o, d, t);
            out.segments += 1;
            if !sink(&seg) {
                break;
            }
            t = seg.t_out;
            let nb = geo.adj(tet)[hit.clip.exit as usize];
            if nb != NO_NEIGHBOR {
                if let Some(h) = self.enter_neighbour(nb, o, d, t) {
                    next = Some(h);
                    continue;
                }
                out.local_searches += 1;
            }
            next = self.local_search(hit.tet, o, d, t, scratch);
            if next.is_none() {
                next = self.query(o, d, t, false);
                if next.is_some() {
                    if nb == NO_NEIGHBOR {
                        out.reentries += 1;
                    } else {
                        out.recovered += 1;
                    }
                }
            }
        }
        out
    }
}
