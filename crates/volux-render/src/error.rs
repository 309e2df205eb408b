//! The errors of the renderers, and the image size they accept.

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
    /// A rendering backend (the GPU) failed or cannot draw the scene: no adapter, a device
    /// limit, out of device memory, a lost device.
    #[error("{0}")]
    Backend(String),
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
