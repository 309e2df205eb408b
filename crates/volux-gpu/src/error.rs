//! The errors of the GPU backend.
use volux_render::{Remedy, RenderError};

/// What can go wrong on the GPU.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GpuError {
    /// No adapter (no GPU, no Vulkan/Metal/DX12/GL driver, no software rasterizer).
    #[error("no GPU adapter found (install a Vulkan driver, e.g. mesa-vulkan-drivers)")]
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
    #[error("{what} is over the GPU's limit ({limit})")]
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
        let remedy = match e {
            GpuError::NoAdapter | GpuError::OverLimit { .. } => Some(Remedy::CpuBackend),
            GpuError::Device { .. } | GpuError::Failed(_) => None,
        };
        RenderError::Backend {
            reason: e.to_string(),
            remedy,
        }
    }
}
