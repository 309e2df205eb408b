//! The brick pool ([`GpuPoolRenderer`]): grids larger than the device's memory or its 3D
//! texture limits, ray cast in one pass (seed `003` done properly). The grid is cut into
//! bricks of `B` cells per axis, `B + 1` samples with the shared faces, so that each
//! trilinear sample reads one brick; bricks live in the slots of one 3D texture atlas, a
//! page table maps bricks to slots, and a ray that reaches a brick that is not resident
//! saves its state (opacity so far, next sample index) and asks for it (`pool.wgsl`). The
//! host loads the asked bricks, evicting the longest-resident ones, and dispatches again
//! until no ray asks: the rays' front-to-back sums continue across bricks and rounds, with
//! no opacity reset (`003` reset it per brick and merged the pieces). Bricks the transfer
//! function leaves transparent are never loaded: rays skip them. Samples sit on the lattice
//! of [`GpuGridRenderer`](crate::GpuGridRenderer) and read the same values, so the
//! pictures are the same (tested).
//!
//! The pool draws the Riemann sum with step-corrected opacity, clip planes, jitter and
//! early ray termination; what else a scene asks for is refused by name
//! ([`GpuPoolRenderer::supports`]).
mod bricked;
mod renderer;
mod slots;
mod source;

pub use bricked::GpuBrickedRenderer;
pub use renderer::{GpuPoolRenderer, PoolStats};
pub use slots::PoolOptions;
pub use source::PoolSource;
