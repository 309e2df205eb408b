//! Sculpting a grid (seed `004_...txt` ch. 4-6): the [`SculptMask`] of removed voxels at the
//! data's full resolution, the regions the tools remove ([`region`]: the eraser's swept disc
//! on the screen, sec. 4.4, and the digger's ball, sec. 4.5) and the labelling of the visible
//! voxels from picked points ([`labels`], sec. 6.2): by the nearest point, as the seed does,
//! or by the region a point's visible voxels connect to (issue 41).
//!
//! The seed kept a 64³ mask in a texture, interpolated it and thresholded it at 0.5 (sec.
//! 4.4.1). Here the mask has one bit per voxel, stored sparsely in 8³ bricks (a brick wholly
//! kept or wholly removed takes no bits), and is sampled the same way: a point is visible when
//! the trilinear interpolation of the kept (1) and removed (0) voxels around it is at least
//! 0.5, so cut surfaces are smooth at any zoom. Per macrocell (the cells of
//! [`SculptMask::BLOCK`]³ voxels that empty-space skipping walks) the mask keeps whether it is
//! wholly visible, wholly removed or partly removed; each edit updates the macrocells of the
//! bricks it touched, never the whole grid.
//!
//! Picking the visible surface (the digger's centre, measurement, labelling seeds) needs the
//! classification and lives in the renderer (`volux_render::sculpt`).

mod cell_states;
mod cut;
mod grow;
#[cfg(test)]
mod label_tests;
pub mod labels;
mod mask;
pub mod region;
#[cfg(test)]
mod tests;

pub use labels::{label_regions, LabelSeed, RegionRule};
pub use mask::{MaskEdit, SculptMask};
pub use region::{Ball, Coverage, Region, ScreenStroke, VoxelFrame};
