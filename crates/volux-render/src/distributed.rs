//! Sort-last distributed rendering (seed `003`'s blocks, on several processes, done exactly):
//! a level's chunk grid is cut by a k-d split into convex boxes of chunks, one per rank
//! ([`kdtree`]); each rank ray casts only the part of every ray inside its box, on the
//! *global* sample lattice, so that every sample of the single-process render is taken by
//! exactly one rank ([`region`]); the partial images (premultiplied RGBA, no background)
//! are composited front to back in the view's visibility order of the boxes by binary swap,
//! with the ranks beyond a power of two folded into partners first as IceT does ([`swap`]),
//! over a small message-passing trait ([`exchange`]) that runs over threads in tests and
//! over MPI in the `volux-mpi` crate. Rank 0 ends with the whole image.
//!
//! Seed `003` merges its blocks' images with the opacity reset at every block boundary, so
//! its bricked picture differs from the whole one; here a rank's partial image is the exact
//! integral of its part of the ray, and the *under* operator composites the parts, so the
//! picture equals the single-process render (within float rounding: 1e-6 per channel,
//! tested for 1 to 5 ranks, and 3e-7 on rays of about 600 samples, whose sums are kept in
//! `f64`: [`crate::composite`]). Early ray termination is off (but for adaptive Simpson, below):
//! a rank behind another cannot know that the rays it samples are already opaque in front. Isosurfaces too: the step from
//! a region's last sample to the next region's first belongs to the front region, which
//! finds and refines the crossings in it exactly as one process does.
//!
//! Adaptive Simpson (`001_...txt` ch. 4, Algorithms 3 and 4) is exact too, bit for bit and
//! with early termination, by another schedule: its step, its streak of successes, its
//! lookahead and its decisions depend on the whole ray so far, so instead of integrating
//! their pieces alone and compositing, the ranks pass the rays' states along the visibility
//! order, band by band as a wavefront, each taking the steps that start in its region
//! ([`pipeline`], the states as messages: [`states`]).
//!
//! Maximum intensity projection is exact too, by another reduction: each rank keeps per
//! pixel the largest sample of its part of the ray's lattice, its index and its refined
//! peak, and the ranks keep the largest (the earlier on ties) by the same binary swap
//! ([`mip`], [`part`]).
//!
//! The job every rank renders: [`job`]. Read counts per rank: [`reads`]; a bricked level rendered by region:
//! [`render_cache_region`](crate::bricked::render_cache_region). Errors: [`error`].

pub mod error;
pub mod exchange;
pub mod job;
pub mod kdtree;
pub mod mip;
pub mod part;
pub mod pipeline;
pub mod reads;
pub mod region;
pub mod states;
pub mod swap;
#[cfg(test)]
mod tests;
