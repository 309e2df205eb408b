//! The errors of the GPU backend.
use volux_render::RenderError;

/// What can go wrong on the GPU.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GpuError {
    /// No adapter (no GPU, no Vulkan/Metal/DX12/GL driver, no software rasterizer).
    #[error("no GPU adapter found (install a Vulkan driver, e.g. mesa-vulkan-drivers, or use --backend cpu)")]
    NoAdapter,
    /// The adapter refused to open a device.
    #[error("the GPU adapter '{adapter}' refused a device: {reason}")]
    Device {
        /// The adapter's name.
        adapter: String,
        /// Why.
        reason: String,
    },
    /// The data or the image is over a limit of the device.
    #[error("{what} is over the GPU's limit ({limit}); use --backend cpu")]
    OverLimit {
        /// What is too large, with its size.
        what: String,
        /// The device's limit.
        limit: String,
    },
    /// The device failed while rendering (out of memory, lost device, validation).
    #[error("the GPU failed: {0}")]
    Failed(String),
}

impl From<GpuError> for RenderError {
    fn from(e: GpuError) -> Self {
        RenderError::Backend(e.to_string())
    }
}
