//! Projected Tetrahedra (PT): object-order rendering of tetrahedral meshes by cell projection.
//!
//! PT (Shirley and Tuchman, 1990) projects every tetrahedron onto the image plane, splits
//! its projected silhouette into 1 to 4 triangles that share one *thick vertex* (the
//! projection of the longest ray segment through the cell, of length `l`, entered with the
//! scalar `s_f` and left with `s_b`), and composites the triangles in visibility order. The
//! other projected vertices are *thin*: the ray covers no distance there, so their opacity is
//! zero; the rasterizer interpolates `(s_f, s_b, l)` between the thick vertex and the thin
//! ones, and each fragment gets the colour and opacity of a ray segment through a
//! homogeneous slab (seed `000_afff90a9230f72b1.txt`, chapter 3 and figures 3.1 to 3.3;
//! seed `002_e36188f6c4fef36d.txt`, section 3).
//!
//! # The two-pass pipeline of the seeds
//!
//! The seeds' GPU realization (thesis `000`, chapter 4, figure 4.1; paper `002`, section 4)
//! has two passes with a CPU step between them:
//!
//! 1. **First pass, per tetrahedron** (`000` §4.1, `002` §4.1): read the four vertices,
//!    compute the centroid depth `z_c`, project the vertices, compute four orientation tests
//!    on the projection and look the resulting ternary code up in the *ternary truth table*
//!    (`000` figure 4.3, table 4.1, eq. 4.1; `002` figure 4), compute the thick vertex and its
//!    properties `s_f`, `s_b`, `l` (and, in `002`, the front and back gradients).
//! 2. **Sorting and arrays** (`000` §4.2, `002` §4.2): sort the cells by centroid depth
//!    (bucket sort while the view moves, merge sort for still frames; both approximate: exact
//!    visibility order needs MPVO-like methods) and fill the fan arrays: five vertices per
//!    tetrahedron (the four originals plus the thick vertex), six fan indices and a count.
//! 3. **Second pass, per fragment** (`000` §4.3, `002` §4.3 and §4.4): rasterize the fans,
//!    look `s_f` and `s_b` up in the transfer function, compute the opacity from `l` (average
//!    extinction, or the partial pre-integration `ψ` table of Moreland and Angel) and
//!    composite back to front.
//!
//! # What is here
//!
//! - [`classify`]: the per-tetrahedron classification of step 1: an exact orientation
//!   predicate, the 81-entry ternary truth table (derived, not transcribed, and checked
//!   against brute-force geometry for every entry), and [`classify::classify`], which turns
//!   four projected vertices into a class, a triangle fan and a thick vertex;
//! - [`project`]: vertex projection per view (snapped to a sub-pixel grid so that shared
//!   faces rasterize identically) and the thick vertex's front and back depth, scalar and
//!   gradient, perspective-correct;
//! - [`sort`]: visibility order: centroid radix sort, MPVO, violation counts, convexity;
//! - [`raster`]: screen tiles, binning in drawing order, scanline rasterization with exact
//!   fixed-point edge functions and the top-left rule;
//! - the colour of a fragment (average, ψ, exact) with isosurfaces is
//!   [`crate::integrate::fragment`], shared with the tet ray caster;
//! - [`shade`]: the second pass on lanes: a cell's fragments in a tile gathered, then
//!   interpolated and coloured several at a time;
//! - [`render`]: [`PtRenderer`], the stages wired together with the caches of the update step
//!   (discard, per-tetrahedron pass, order, bins), parallel over tiles and deterministic;
//! - [`clip`]: clipping planes (seed `004` sec. 4): each pixel's depth window, fragments
//!   trimmed to it, cells wholly outside a plane culled;
//! - [`reference`](mod@reference): a brute-force per-pixel ray/tetrahedron integrator, the independent
//!   reference of the tests.

pub mod classify;
pub mod clip;
pub mod planes;
pub mod project;
pub mod raster;
pub mod reference;
pub mod render;
pub mod setup;
pub mod shade;
pub mod sort;

pub use crate::frame::PtStats;
pub use crate::scene::SortMode;
#[cfg(test)]
pub(crate) use render::PtOptions;
pub use render::PtRenderer;
