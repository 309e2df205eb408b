//! Ray casting of tetrahedral meshes by cell-to-cell traversal (issue 5): Garrity's
//! boundary-face entry, Bunyk et al.'s and Weiler et al.'s (HARC) walk from cell to cell
//! through face adjacency (seed `000` §2.4), with the segment colours of the projection
//! renderer (exact pre-integration, or partial pre-integration ψ of seed `000` §2.3, applied to cells in §2.6), the
//! adaptive Simpson rule of seed `001` ch. 4 along the whole ray, isosurfaces (seed `002`
//! §4.6) and maximum intensity projection (`pixel.rs`).
//!
//! Per pixel, the ray through the pixel centre ([`Camera::ray`](volux_core::Camera::ray)):
//!
//! 1. **enters** the mesh through the nearest boundary face, found in a bounding volume
//!    hierarchy over the cells owning boundary faces (`bvh.rs`); a camera inside the mesh
//!    starts from a per-frame hierarchy over the cells around the eye;
//! 2. **walks** ([`walk`]): in the current cell the ray is clipped against the four face
//!    planes (the canonical planes of [`crate::pt::reference`], so both cells of a face agree
//!    bit for bit on where the ray crosses it, and a ray in a face plane belongs to exactly
//!    one of them), giving the exit face, the exit parameter and the scalar at entry and exit
//!    (from the cell's linear field, in `f64`); the segment `(s_in, s_out, length)` is
//!    integrated and composited front to back (*under* operator, optional early
//!    termination), and the walk steps to the neighbour across the exit face. Leaving
//!    through a boundary face, the hierarchy is queried again past the exit (a re-entry of a
//!    non-convex mesh or a mesh with gaps). Rays through vertices and edges are continued by
//!    a local search around the exit point; the walk provably never loops (the ray parameter
//!    strictly increases with every segment) and a step bound backs that up;
//! 3. tiles of [`TILE`](crate::tiles::TILE) pixels a side are rendered in parallel by the
//!    tile driver ([`crate::tiles`]); each pixel depends only
//!    on its own ray, so the image is deterministic.
//!
//! The result equals the brute-force reference [`MeshReference`](crate::pt::reference::MeshReference) in exact colour
//! mode: the crossing parameters are bit-identical to the reference's, and in the tests
//! (`tests.rs`: `smooth_tets(3000)` from five cameras including orthographic and inside the
//! mesh, `torus_tets(24)` with re-entries, a mesh with gaps, an axis-aligned lattice whose
//! pixel rays run through vertices, along edges and in faces) the `f32` images are equal to
//! the reference's, with no abandoned ray. ψ colour differs from exact by `3.4e-4` on average
//! (`3.8e-2` at most) with the test TF.
//!
//! Measured (ignored test `timing_512_smooth_200k`, release, 2 shared and loaded cores):
//! 512 x 512 of `smooth_tets(200_000)` (196 520 cells, 36 segments per ray) in about 770 ms
//! exact and 580 ms ψ (0.26 and 0.34 M tets/s), the walk alone about 75 ns per segment on
//! one thread; building the caster takes about 90 ms and its structures are 151 bytes per
//! tet (face planes 40 bytes per face, cell-to-face table, adjacency, cell fields, boundary
//! hierarchy).
//!
//! **Empty-space skipping** (`skip.rs`, per-segment colours only,
//! `skip_empty`, on by default): per TF and set of isovalues, the cells whose
//! vertex value range has zero extinction (exactly, for the exact integrator's linear pieces
//! and the ψ/average lookup table) and holds no isovalue colour as transparent black, so
//! they are left out: the walk (`Walker::trace_visible` in `walk`)
//! steps across faces while the neighbour is visible and otherwise asks a hierarchy over the
//! visible cells for the first one past the exit (which also covers entries, boundary exits,
//! re-entries and edge or vertex exits). Compositing a transparent segment changes nothing,
//! so the image is the one of the full walk (equal in the tests, bit for bit on the bench
//! meshes); the statistics then count the visible cells' segments only, with the jumps over
//! invisible runs as `skips`. With more than 90 % of the cells visible the full walk is used.
//! The first visible cell of each ray is found per tile, not per ray (`first.rs`): once per
//! frame the visible cells are projected to pixel rectangles and binned to tiles, and each
//! tile clips its cells, near to far, against the rays of their rectangles, keeping per pixel
//! the hit that starts first: the hierarchy's answer, exactly, for a fraction of the cost;
//! rays that meet no visible cell are not walked (a frame with a visible cell across a
//! perspective eye's plane queries the hierarchy per ray instead). The farthest box corner
//! of a tile's cells bounds how far its rays may meet a visible cell, so an invisible
//! neighbour is walked through (up to 16 cells, without segments) until a visible cell or
//! that bound, and the hierarchy is asked only past longer invisible runs, boundary exits and
//! edge or vertex exits: the query after a ray's last visible cell, which used to be most of
//! the queries, is mostly gone.
//! On the issue-17 workload (`tets_200k`, the 37-knot TF, 512 x 512) 28 % of the segments
//! are visible; the walk used to make about 1.3 hierarchy queries per ray (the entry, a few
//! jumps, the last exit), of which the entry is now found per tile.
//!
//! **Adaptive Simpson** ([`SegmentRule::AdaptiveSimpson`](crate::integrate::SegmentRule::AdaptiveSimpson), seed `001` ch. 4): the walked
//! segments of a ray form the medium (scalar linear per segment, exact TF classification,
//! TF breakpoints inside a step reported as hidden features, gaps empty) and the whole ray
//! is integrated across cell boundaries, with a per-pixel error estimate
//! ([`TetRayRendered::error_map`]) and the rays over tolerance counted. In the tests, at
//! `tol = 1e-3` (steps in units of `diagonal / 256`: `h0 = 2`, `hmin = 1e-3`, `hmax = 4`)
//! no pixel of 64 x 64 differs from the exact colour by more than the tolerance
//! (`smooth_tets(3000)`: max `1.6e-4`, 52 samples per ray; `torus_tets(24)`: max `6.4e-4`),
//! and no ray is over tolerance.
//!
//! **Isosurfaces** (seed `002` §4.6) use the fragment shader PT uses too
//! ([`crate::integrate::fragment`]), with
//! normals interpolated from the vertex gradients at the segment's end points (barycentric):
//! PT with exact order and colour and this caster agree to `3e-5` on average per channel.
//! **MIP** shows the TF colour of the largest segment end point, opaque.
//!
mod bvh;
mod first;
mod geom;
mod options;
mod pixel;
pub mod render;
mod skip;
mod tables;
pub mod walk;

pub use crate::frame::TetRayStats;
#[cfg(test)]
pub(crate) use options::TetRayOptions;
pub use render::{TetRayCaster, TetRayRendered, TracedRay};
pub use walk::{WalkOutcome, WalkSegment};

#[cfg(test)]
mod tests;
