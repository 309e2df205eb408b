//! Out-of-core rendering of bricked volumes (seed `003`, volumes larger than memory, done
//! exactly): a level of a [`Multiscale`](volux_core::bricked::Multiscale) pyramid is read
//! chunk by chunk into a [`BrickCache`] bounded by a byte budget (least recently used chunks
//! evicted), and sampled as a [`Field`](crate::sampling::Field) on the global sample lattice,
//! exact across brick faces; rays walk the volume front to back in one pass, so accumulated
//! opacity and early termination carry across bricks (the seed's merge reset opacity at
//! every block boundary). At full resolution the image equals the in-core image of the same
//! data (tested for every integrator, with budgets that force evictions within a frame).
//! [`BrickedVolume`] holds the pyramid and chooses the level ([`Lod`]);
//! [`render_cache_region`] renders one rank's region of a distributed render
//! ([`crate::distributed`]).

mod cache;
mod field;
#[cfg(test)]
pub(crate) mod fixtures;
mod memo;
mod prefetch;
mod region;
mod render;
#[cfg(test)]
mod tests;
pub mod volume;

pub use cache::{Brick, BrickCache, CacheStats};
pub use region::{level_placement, render_cache_frame, render_cache_region};
pub use render::{render_level, BrickedRenderer};
pub use volume::{BrickedVolume, Lod, StoreStatistics};
