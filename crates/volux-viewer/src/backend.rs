//! Where the viewer's frames are rendered: the application layer's backends
//! ([`volux_app::backend`]: the CPU engine, or the GPU backend behind the default `gpu`
//! feature when there is an adapter and it draws the scene).
//!
//! `volux-view --backend auto` (the default) renders a frame on the GPU when a hardware
//! adapter exists and the GPU backend draws the scene's method and features (a software
//! adapter such as llvmpipe only for GPU-only methods), else on the CPU; `gpu` insists (the
//! view shows why a scene cannot be drawn there); `cpu` never opens a device. Every frame
//! says which it was drawn on ([`Device`]). The render thread opens its renderers through
//! one [`volux_app::RendererFactory`].
pub use volux_app::backend::{Backend, Device};
use volux_render::device::GpuDevice;

/// The GPU device of a build with the `gpu` feature (the default), for the render thread's
/// [`volux_app::RendererFactory`].
pub fn gpu_device() -> Option<Box<dyn GpuDevice>> {
    #[cfg(feature = "gpu")]
    return Some(Box::new(volux_gpu::LazyGpu::new()));
    #[cfg(not(feature = "gpu"))]
    None
}
