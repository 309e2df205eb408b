//! Image-order traversal of regular grids: one ray per pixel, exact ray/box entry and exit,
//! front-to-back compositing with early ray termination, parallel over square image tiles.
//!
//! Each ray is handed to one of the [`Integrator`](crate::integrate::Integrator)s of [`crate::integrate`] as a
//! [`RayMedium`](crate::integrate::RayMedium) (trilinear reconstruction of [`crate::sampling`], classification of
//! [`crate::classify`]); steps are given in voxel units (the smallest spacing), as in the seed
//! `001_...txt`. A tile takes one of these paths:
//!
//! - Riemann sums and pre-integration, emission only or shaded with the cached gradient
//!   volume: the lane stream (`raycast/stream.rs`), 16 rays advanced together;
//! - adaptive Simpson with coupled control, emission only or shaded with the cached gradient
//!   volume: `raycast/adaptive_stream.rs`, four rays' steps sampled and judged together in
//!   f32 lanes;
//! - maximum intensity projection: `raycast/mip_stream.rs`, 16 rays sampled together;
//! - everything else (isosurfaces, decoupled adaptive Simpson, trapezoid, Simpson, the
//!   reference): ray by ray.
//!
//! The paths compute the same sums (tested). Output does not depend on the number of threads:
//! every pixel is computed independently.

mod adaptive_stream;
pub(crate) mod cell_blocks;
pub mod clip;
mod context;
mod mask_tiles;
mod mip_stream;
pub mod options;
mod rays;
pub mod renderer;
mod resume;
mod stream;
#[cfg(test)]
mod tests;
mod traverse;

pub use crate::frame::RenderStats;
pub use clip::{ray_box, to_voxel, voxel_crossings};
pub(crate) use context::first_at_or_after;
pub use context::{cut_layer, local_clip_planes};
pub use options::{Placement, RenderOptions, Rendered};
pub(crate) use renderer::{grid_frame, grid_settings};
pub use renderer::{render_grid, GridRenderer};
pub(crate) use resume::with_band_caster;
pub use traverse::{render_field, render_field_in};
