//! # volux-render
//!
//! The rendering stages of the Volux pipeline, one module each, shared by every traversal:
//!
//! - [`sampling`]: field reconstruction (trilinear sampling of native-type grids);
//! - [`classify`]: classification, a lookup table built from a [`TransferFunction`];
//! - [`integrate`]: the optical model and its integrators (Riemann sum with step-corrected
//!   opacity, `001_...txt` eq. 2.14);
//! - [`raycast`]: image-order traversal of regular grids, front-to-back compositing;
//! - [`resample`]: tetrahedral meshes resampled onto a grid (the simple correct path for
//!   meshes until cell projection lands).
//!
//! [`TransferFunction`]: volux_core::TransferFunction
#![deny(missing_docs)]
// One `unsafe` block, proven by a benchmark: the lane sampler's unchecked corner loads
// (`sampling::Trilinear::interpolate4`, with the argument for their soundness).
#![deny(unsafe_code)]

pub mod classify;
pub mod composite;
pub mod engine;
pub mod geometry;
pub mod integrate;
pub mod intervals;
pub mod isosurface;
pub mod macrocell;
pub mod mip;
pub mod pt;
pub mod raycast;
pub mod resample;
pub mod sampling;
pub mod scene;
pub mod shading;
pub mod tetray;
pub mod tiles;

pub use raycast::{render_grid, RenderOptions, RenderStats};

/// Errors of the renderers.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The render was cancelled through its cancellation flag.
    #[error("render cancelled")]
    Cancelled,
    /// Options that cannot be used (zero image size, non-positive step...).
    #[error("invalid render options: {0}")]
    InvalidOptions(String),
    /// An error of the data model.
    #[error("{0}")]
    Data(#[from] volux_core::Error),
}

/// Largest image side accepted by the renderers.
pub const MAX_IMAGE_SIDE: usize = 1 << 15;

/// Checks an image size: both sides between 1 and [`MAX_IMAGE_SIDE`].
pub fn check_image_size(width: usize, height: usize) -> Result<(), RenderError> {
    if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(RenderError::InvalidOptions(format!(
            "image size {width}x{height} must be between 1 and {MAX_IMAGE_SIDE}"
        )));
    }
    Ok(())
}
