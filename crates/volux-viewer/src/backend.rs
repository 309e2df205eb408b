//! Where the viewer's frames are rendered: the CPU engine, or the GPU backend (`volux-gpu`,
//! behind the default `gpu` feature) when there is an adapter and it draws the scene.
//!
//! `volux-view --backend auto` (the default) renders a frame on the GPU when a hardware
//! adapter exists and the GPU backend draws the scene's method and features
//! ([`volux_gpu::auto_draws`]: a software adapter such as llvmpipe only for GPU-only
//! methods), else on the CPU;
//! `gpu` insists (the view shows why a scene cannot be drawn there); `cpu` never opens a
//! device. Every frame says which it was drawn on ([`Device`]).
use volux_render::engine::{create_renderer, Renderer};
use volux_render::scene::{Method, Scene, Volume};
use volux_render::session::SessionBackend;
use volux_render::RenderError;

/// Which renderer the viewer asks for (`--backend`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    /// The GPU where it draws the scene, else the CPU.
    Auto,
    /// The CPU engine (the library's default: deterministic, and no device opened).
    #[default]
    Cpu,
    /// The GPU backend, or an error saying why not.
    Gpu,
}

impl Backend {
    /// Parses `auto`, `cpu` or `gpu`.
    pub fn parse(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Self::Auto),
            "cpu" => Ok(Self::Cpu),
            "gpu" => Ok(Self::Gpu),
            _ => Err(format!("--backend '{s}': expected auto, cpu or gpu")),
        }
    }
}

impl From<Backend> for SessionBackend {
    fn from(b: Backend) -> Self {
        match b {
            Backend::Auto => Self::Auto,
            Backend::Cpu => Self::Cpu,
            Backend::Gpu => Self::Gpu,
        }
    }
}

/// What drew a frame: the CPU engine, or the GPU adapter named.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Device {
    /// The CPU engine.
    #[default]
    Cpu,
    /// The GPU backend on this adapter (its name, API and kind).
    Gpu(String),
}

impl std::fmt::Display for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Cpu => write!(f, "CPU"),
            Self::Gpu(adapter) => write!(f, "GPU: {adapter}"),
        }
    }
}

/// Makes the renderers of the render thread: keeps the GPU device once opened (or why it
/// could not be).
pub(crate) struct Factory {
    backend: Backend,
    gpu: gpu::Lazy,
}

impl Factory {
    pub(crate) fn new(backend: Backend) -> Self {
        Self {
            backend,
            gpu: gpu::Lazy::new(),
        }
    }

    /// Whether the frame of `scene` (its method resolved) on `volume` is drawn on the GPU;
    /// an error when the backend is `gpu` and it cannot be.
    pub(crate) fn on_gpu(&mut self, volume: &Volume, scene: &Scene) -> Result<bool, RenderError> {
        match self.backend {
            Backend::Cpu => Ok(false),
            // Only the GPU draws a GPU-only method: why it cannot is the answer.
            Backend::Auto if scene.method.gpu_only() => {
                self.gpu.draws(volume, scene, false).map(|()| true)
            }
            Backend::Auto => Ok(self.gpu.draws(volume, scene, true).is_ok()),
            Backend::Gpu => self.gpu.draws(volume, scene, false).map(|()| true),
        }
    }

    /// A renderer of `method` (resolved) for `volume`, on the GPU or the CPU.
    pub(crate) fn make(
        &mut self,
        volume: &Volume,
        method: &Method,
        on_gpu: bool,
    ) -> Result<(Box<dyn Renderer>, Device), RenderError> {
        if on_gpu {
            return self.gpu.renderer(volume, method);
        }
        Ok((create_renderer(volume, method)?, Device::Cpu))
    }
}

#[cfg(feature = "gpu")]
mod gpu {
    use std::sync::Arc;

    use volux_gpu::GpuContext;
    use volux_render::engine::Renderer;
    use volux_render::scene::{Method, Scene, Volume};
    use volux_render::RenderError;

    use super::Device;

    /// The device, opened on first use (or why it could not be).
    pub(super) struct Lazy(Option<Result<Arc<GpuContext>, String>>);

    impl Lazy {
        pub(super) fn new() -> Self {
            Self(None)
        }

        fn context(&mut self) -> Result<Arc<GpuContext>, RenderError> {
            let opened = self
                .0
                .get_or_insert_with(|| GpuContext::new().map(Arc::new).map_err(|e| e.to_string()));
            opened.clone().map_err(RenderError::Backend)
        }

        /// `Ok` when the GPU backend draws `scene` on `volume` and a device is open; `auto`
        /// applies the rule of [`volux_gpu::auto_draws`] (no software adapter unless the
        /// method is GPU-only).
        pub(super) fn draws(
            &mut self,
            volume: &Volume,
            scene: &Scene,
            auto: bool,
        ) -> Result<(), RenderError> {
            volux_gpu::supports(volume, scene).map_err(RenderError::Backend)?;
            let ctx = self.context()?;
            if auto {
                volux_gpu::auto_draws(&ctx, volume, scene).map_err(RenderError::Backend)?;
            }
            Ok(())
        }

        pub(super) fn renderer(
            &mut self,
            volume: &Volume,
            method: &Method,
        ) -> Result<(Box<dyn Renderer>, Device), RenderError> {
            let ctx = self.context()?;
            let device = Device::Gpu(ctx.adapter().to_string());
            Ok((volux_gpu::renderer_for(ctx, volume, method)?, device))
        }
    }
}

#[cfg(not(feature = "gpu"))]
mod gpu {
    use volux_render::engine::Renderer;
    use volux_render::scene::{Method, Scene, Volume};
    use volux_render::RenderError;

    use super::Device;

    const NOT_BUILT: &str =
        "this volux-view was built without the GPU backend (build it with --features gpu)";

    pub(super) struct Lazy;

    impl Lazy {
        pub(super) fn new() -> Self {
            Self
        }
    }

    impl Lazy {
        pub(super) fn draws(&mut self, _: &Volume, _: &Scene, _: bool) -> Result<(), RenderError> {
            Err(RenderError::Backend(NOT_BUILT.into()))
        }

        pub(super) fn renderer(
            &mut self,
            _: &Volume,
            _: &Method,
        ) -> Result<(Box<dyn Renderer>, Device), RenderError> {
            Err(RenderError::Backend(NOT_BUILT.into()))
        }
    }
}
