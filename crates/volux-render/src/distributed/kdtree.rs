//! The k-d split of a level's chunk grid into convex regions, one per rank ([`KdSplit`]):
//! boxes of whole chunks, balanced by chunk count, for any number of ranks; the part of a
//! ray inside a region ([`KdSplit::clip_ray`], an exact partition of the ray); and the
//! regions' visibility order for a viewpoint ([`KdSplit::visibility_order`]).
use glam::DVec3;
use volux_core::bricked::ChunkLayout;
use volux_core::camera::{Camera, Projection};

use super::error::DistributedError;
use crate::raycast::Placement;

/// A box of chunks, `lo` included and `hi` excluded (chunk coordinates).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChunkBox {
    /// The first chunk along each axis.
    pub lo: [usize; 3],
    /// One past the last chunk along each axis.
    pub hi: [usize; 3],
}

impl ChunkBox {
    /// The number of chunks in the box.
    pub fn count(&self) -> usize {
        (0..3).map(|a| self.hi[a] - self.lo[a]).product()
    }

    /// Whether chunk `c` lies in the box.
    pub fn contains(&self, c: [usize; 3]) -> bool {
        (0..3).all(|a| self.lo[a] <= c[a] && c[a] < self.hi[a])
    }

    /// Whether chunk `c` lies in the box grown by one chunk on every side (a face, edge or
    /// corner neighbour, or the box's own): the chunks a region's rays may read.
    pub fn near(&self, c: [usize; 3]) -> bool {
        (0..3).all(|a| self.lo[a] <= c[a] + 1 && c[a] <= self.hi[a])
    }
}

/// A node of the split: a region, or a plane between two subtrees.
#[derive(Clone, Debug)]
enum Node {
    Leaf(usize),
    Split {
        axis: usize,
        /// The plane, in voxel coordinates (a chunk boundary).
        plane: f64,
        low: Box<Node>,
        high: Box<Node>,
    },
}

/// Where rays come from: a perspective eye, or the direction of parallel rays, in voxel
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewPoint {
    /// Rays leave this point.
    Eye(DVec3),
    /// Parallel rays of this direction.
    Direction(DVec3),
}

impl ViewPoint {
    /// The viewpoint of `camera` in the voxel coordinates of `place`.
    pub fn of(camera: &Camera, place: &Placement) -> Self {
        let to_voxel = |p: DVec3| (place.point_to_local(p) - place.origin) / place.spacing;
        match camera.projection {
            Projection::Perspective { .. } => ViewPoint::Eye(to_voxel(camera.eye)),
            Projection::Orthographic { .. } => ViewPoint::Direction(
                place.vector_to_local(camera.target - camera.eye) / place.spacing,
            ),
        }
    }
}

/// A k-d split of a chunk grid into convex boxes of chunks, one per rank, balanced by chunk
/// count: each node cuts its box across its longest side (in samples) at the chunk boundary
/// that best divides the chunks in proportion to the ranks on either side (`n / 2` and
/// `n - n / 2`), so any number of ranks works. A region owns the samples `[lo, hi)` of its
/// chunks along each axis; its rays read its chunks and their neighbours across its faces
/// (trilinear cells and steps that straddle a face).
#[derive(Clone, Debug)]
pub struct KdSplit {
    regions: Vec<ChunkBox>,
    root: Node,
    chunks: [usize; 3],
    chunk: [usize; 3],
}

impl KdSplit {
    /// The split of `layout`'s chunks into `ranks` regions; an error when there are fewer
    /// chunks than ranks (or no rank).
    pub fn new(layout: &ChunkLayout, ranks: usize) -> Result<Self, DistributedError> {
        let chunks = layout.chunks_per_axis();
        let count = layout.chunk_count();
        if ranks == 0 || ranks > count {
            return Err(DistributedError::Split {
                ranks,
                chunks: count,
            });
        }
        let mut regions = Vec::with_capacity(ranks);
        let all = ChunkBox {
            lo: [0; 3],
            hi: chunks,
        };
        let root = split(all, ranks, layout, &mut regions).ok_or(DistributedError::Split {
            ranks,
            chunks: count,
        })?;
        Ok(Self {
            regions,
            root,
            chunks,
            chunk: layout.chunk,
        })
    }

    /// The regions, region `r` for rank `r`.
    pub fn regions(&self) -> &[ChunkBox] {
        &self.regions
    }

    /// The number of regions.
    pub fn len(&self) -> usize {
        self.regions.len()
    }

    /// Whether there is no region (never: a split has at least one).
    pub fn is_empty(&self) -> bool {
        self.regions.is_empty()
    }

    /// Chunks per axis of the split grid.
    pub fn chunks_per_axis(&self) -> [usize; 3] {
        self.chunks
    }

    /// Samples per chunk along each axis.
    pub fn chunk_shape(&self) -> [usize; 3] {
        self.chunk
    }

    /// The region holding chunk `c`.
    pub fn region_of(&self, c: [usize; 3]) -> Option<usize> {
        self.regions.iter().position(|b| b.contains(c))
    }

    /// The regions front to back as seen from `view`: at each split the child on the
    /// viewer's side first (for parallel rays, the child the rays enter first). Boxes cut by
    /// planes are convex and the planes separate them, so every ray meets them in this
    /// order (perspective or parallel), whatever its direction.
    pub fn visibility_order(&self, view: ViewPoint) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.regions.len());
        order(&self.root, view, &mut out);
        out
    }

    /// The part of the voxel-space ray `o + t d`, `t` in `[t0, t1)`, inside `region`: the
    /// ray's interval cut at every plane on the way down the tree, the part before a plane
    /// going to the child the ray meets first. The parts of all regions partition
    /// `[t0, t1)` exactly (each cut is one `t` shared by both sides), so a sample lattice on
    /// the ray puts each sample in exactly one region (`t < cut` before, `t >= cut` after,
    /// as the ray caster compares). `None` when the ray misses it.
    pub fn clip_ray(
        &self,
        region: usize,
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
    ) -> Option<(f64, f64)> {
        let (mut a, mut b) = (t0, t1);
        let mut node = &self.root;
        loop {
            match node {
                Node::Leaf(r) => {
                    return (*r == region && a < b).then_some((a, b));
                }
                Node::Split {
                    axis,
                    plane,
                    low,
                    high,
                } => {
                    let goes_low = self.regions_under(low).contains(&region);
                    let (oa, da) = (o[*axis], d[*axis]);
                    if da == 0.0 {
                        // Parallel to the plane: the whole ray is on the side of its origin.
                        if (oa < *plane) != goes_low {
                            return None;
                        }
                    } else {
                        let cut = (*plane - oa) / da;
                        // The child the ray meets first: the low one when it moves up the axis.
                        let first_low = da > 0.0;
                        if goes_low == first_low {
                            b = b.min(cut);
                        } else {
                            a = a.max(cut);
                        }
                    }
                    if a >= b {
                        return None;
                    }
                    node = if goes_low { low } else { high };
                }
            }
        }
    }

    /// The regions in a subtree, as a range (regions are numbered in tree order).
    fn regions_under(&self, node: &Node) -> std::ops::Range<usize> {
        let (mut lo, mut hi) = (node, node);
        while let Node::Split { low, .. } = lo {
            lo = low;
        }
        while let Node::Split { high, .. } = hi {
            hi = high;
        }
        match (lo, hi) {
            (Node::Leaf(a), Node::Leaf(b)) => *a..*b + 1,
            _ => 0..0,
        }
    }
}

/// Splits `b` among `ranks` regions (numbered in tree order, appended to `out`); `None` when
/// no plane leaves every side at least one chunk per rank.
fn split(b: ChunkBox, ranks: usize, layout: &ChunkLayout, out: &mut Vec<ChunkBox>) -> Option<Node> {
    if ranks == 1 {
        out.push(b);
        return Some(Node::Leaf(out.len() - 1));
    }
    let (n_low, n_high) = (ranks / 2, ranks - ranks / 2);
    // Axes by their length in samples, longest first.
    let samples = |a: usize| {
        let (lo, hi) = (
            b.lo[a] * layout.chunk[a],
            (b.hi[a] * layout.chunk[a]).min(layout.dims[a]),
        );
        (hi - lo) as f64 * layout.spacing[a]
    };
    let mut axes = [0, 1, 2];
    axes.sort_by(|&x, &y| samples(y).total_cmp(&samples(x)));
    for axis in axes {
        let len = b.hi[axis] - b.lo[axis];
        if len < 2 {
            continue;
        }
        let cross = b.count() / len;
        // Chunks cut off the low end: at least n_low ranks' worth, leaving n_high's.
        let min_cut = n_low.div_ceil(cross).max(1);
        let max_cut = len - n_high.div_ceil(cross).max(1);
        if min_cut > max_cut {
            continue;
        }
        let ideal = (len as f64 * n_low as f64 / ranks as f64).round() as usize;
        let cut = ideal.clamp(min_cut, max_cut);
        let at = b.lo[axis] + cut;
        let (mut lb, mut hb) = (b, b);
        lb.hi[axis] = at;
        hb.lo[axis] = at;
        let low = split(lb, n_low, layout, out)?;
        let high = split(hb, n_high, layout, out)?;
        return Some(Node::Split {
            axis,
            plane: (at * layout.chunk[axis]) as f64,
            low: Box::new(low),
            high: Box::new(high),
        });
    }
    None
}

/// Appends the leaves of `node` front to back as seen from `view`.
fn order(node: &Node, view: ViewPoint, out: &mut Vec<usize>) {
    match node {
        Node::Leaf(r) => out.push(*r),
        Node::Split {
            axis,
            plane,
            low,
            high,
        } => {
            let low_first = match view {
                ViewPoint::Eye(e) => e[*axis] < *plane,
                ViewPoint::Direction(d) => d[*axis] >= 0.0,
            };
            let (first, second) = if low_first { (low, high) } else { (high, low) };
            order(first, view, out);
            order(second, view, out);
        }
    }
}
