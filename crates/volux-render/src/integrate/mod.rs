//! The optical model and its integrators.
//!
//! Emission-absorption (`001_...txt` ch. 2, eq. 2.13): along a ray, colour
//! `C = int_0^D c(s(t)) tau(s(t)) T(t) dt` with transparency `T(t) = exp(-int_0^t tau)` (the
//! *inner* integral) and opacity `A = 1 - T(D)`; the colour integral is the *outer* one.
//! Colours are premultiplied; compositing is front to back.
//!
//! Every integrator sees the ray only through a [`RayMedium`]: the classified medium at
//! distance `t`. Traversals (grid ray casting, tet ray casting) supply it, so one
//! implementation of each rule serves all renderers.
//!
//! - [`Integrator`]: the choice of rule of the grid ray caster;
//! - [`medium`]: the medium along a ray as the rules see it, and what a ray's integral holds;
//! - [`riemann`](mod@riemann): left Riemann sum with step-corrected opacity (eq. 2.14), order 1;
//! - [`fixed::trapezoid`], [`fixed::simpson`]: fixed-step rules, orders 2 and 4;
//! - [`adaptive`]: adaptive Simpson (seed `001` ch. 4), all in one folder:
//!   [`adaptive::adaptive_simpson`], the iterative rule of Algorithms 3 and 4, coupled or
//!   decoupled step control, error estimated per channel R, G, B, A, in f64;
//!   [`adaptive::step`], its parameters and step control (the seed's, or the error-per-step
//!   controller), shared with the lanes; [`adaptive::state`], what a ray carries between two
//!   steps, to integrate it piece by piece with the steps of the whole (a distributed
//!   render's regions); [`adaptive::lanes::AdaptiveLanes`], the same coupled control for four
//!   rays at once in f32 lanes, the fast path of renderers that sample several rays together.
//!   The ray caster's adaptive lane stream, which feeds it, is a traversal
//!   (`raycast::adaptive_stream`);
//! - [`segment`]: the colour of a segment along which the scalar is linear ([`SegmentRule`]:
//!   average, ψ, exact, adaptive), the one segment integrator of the tetrahedral renderers;
//! - [`fragment`]: a segment's colour by its rule, cut at the isosurfaces it crosses (the
//!   fragment of Projected Tetrahedra, the segment of the tet ray caster);
//! - [`psi`]: partial pre-integration (the ψ table, the TF lookup of cells, average and ψ
//!   fragment colours);
//! - [`preintegrated`]: the grid's pre-integration table over (front, back) values.
pub mod adaptive;
pub mod fixed;
pub mod fragment;
pub mod integrator;
pub mod medium;
pub mod preintegrated;
pub mod psi;
pub mod riemann;
pub mod segment;

pub use adaptive::{
    adaptive_simpson, adaptive_simpson_intervals, adaptive_simpson_pieces, AdaptiveParams,
    StepControl,
};
pub use fixed::{fixed_intervals, simpson, trapezoid, FixedRule};
pub use integrator::Integrator;
pub use medium::{hides_breakpoints, hides_breakpoints_along, Medium, RayIntegral, RayMedium};
pub use riemann::{riemann, riemann_step};
pub use segment::{SegmentIntegrator, SegmentRule};

#[cfg(test)]
pub(crate) mod tests;
