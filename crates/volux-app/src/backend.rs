//! Where frames are rendered (OSPRay's device role): the CPU engine, or the GPU backend
//! (`volux-gpu`, behind the `gpu` feature) when there is an adapter and it draws the scene.
//!
//! - [`Backend::Cpu`] never opens a device;
//! - [`Backend::Gpu`] insists: what the GPU cannot draw is an error that says why;
//! - [`Backend::Auto`] draws on a hardware adapter when the GPU backend draws the scene's
//!   method and features, else on the CPU, and says why ([`Placement::cpu_because`]). A
//!   software adapter (llvmpipe, lavapipe: wgpu's device type `Cpu`) is never preferred to
//!   the CPU engine, which is faster on the same cores, unless the method is GPU-only
//!   (texture slicing), whose refusal by the GPU is then the answer
//!   ([`volux_gpu::auto_draws`]).
//!
//! Every front end renders through a [`RendererFactory`], which keeps the device once opened.
use serde::{Deserialize, Serialize};
use volux_render::engine::{create_renderer, Renderer};
use volux_render::scene::{Method, Scene, Volume};
use volux_render::RenderError;

use crate::error::AppError;
use crate::words::WordError;

/// Whether this build has the GPU backend (the `gpu` feature).
pub const GPU_BUILT: bool = cfg!(feature = "gpu");

/// Where frames are rendered. The default is the CPU engine, the reference (a library
/// caller that names no backend gets the same pixels everywhere); the CLI and the viewer
/// default to `auto`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// The GPU where a hardware adapter draws the scene, else the CPU.
    Auto,
    /// The CPU engine (the reference: deterministic, and no device opened).
    #[default]
    Cpu,
    /// The GPU backend, or an error saying why not.
    Gpu,
}

impl Backend {
    /// The names front ends offer, in this order.
    pub const NAMES: [&'static str; 3] = ["auto", "cpu", "gpu"];

    /// Parses a backend's name: `auto`, `cpu` or `gpu`.
    pub fn parse(text: &str) -> Result<Self, WordError> {
        match text.trim() {
            "auto" => Ok(Self::Auto),
            "cpu" => Ok(Self::Cpu),
            "gpu" => Ok(Self::Gpu),
            _ => Err(WordError::NotABackend {
                given: text.to_string(),
            }),
        }
    }

    /// The backend's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Cpu => "cpu",
            Self::Gpu => "gpu",
        }
    }
}

impl std::str::FromStr for Backend {
    type Err = WordError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::parse(s)
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

/// Where a frame is drawn, and why not on the GPU when `auto` chose the CPU.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Placement {
    /// On the GPU.
    pub on_gpu: bool,
    /// Why `auto` renders on the CPU in a build with the GPU backend (no adapter, a
    /// software adapter, a feature the GPU does not draw); `None` otherwise.
    pub cpu_because: Option<String>,
}

/// A renderer and the device it draws on.
pub struct Opened {
    /// The renderer.
    pub renderer: Box<dyn Renderer>,
    /// Where it draws.
    pub device: Device,
    /// Why `auto` chose the CPU ([`Placement::cpu_because`]).
    pub cpu_because: Option<String>,
}

/// Makes renderers on a [`Backend`]: keeps the GPU device once opened (or why it could not
/// be), so a front end that renders many frames opens it once.
pub struct RendererFactory {
    backend: Backend,
    gpu: gpu::Lazy,
}

impl RendererFactory {
    /// A factory for `backend`; no device is opened yet.
    pub fn new(backend: Backend) -> Self {
        Self {
            backend,
            gpu: gpu::Lazy::new(),
        }
    }

    /// The backend it renders on.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// Where the frame of `scene` (its method resolved) on `volume` is drawn; an error when
    /// the backend is `gpu` (or the method is GPU-only) and the GPU cannot draw it.
    pub fn place(&mut self, volume: &Volume, scene: &Scene) -> Result<Placement, AppError> {
        let gpu = |on_gpu| Placement {
            on_gpu,
            cpu_because: None,
        };
        match self.backend {
            Backend::Cpu => Ok(gpu(false)),
            // Only the GPU draws a GPU-only method: why it cannot is the answer.
            Backend::Gpu => self.gpu.draws(volume, scene, false).map(|()| gpu(true)),
            Backend::Auto if scene.method.gpu_only() => {
                self.gpu.draws(volume, scene, false).map(|()| gpu(true))
            }
            Backend::Auto => match self.gpu.draws(volume, scene, true) {
                Ok(()) => Ok(gpu(true)),
                Err(AppError::GpuNotBuilt) => Ok(gpu(false)),
                Err(why) => Ok(Placement {
                    on_gpu: false,
                    cpu_because: Some(why.to_string()),
                }),
            },
        }
    }

    /// A renderer of `method` (resolved) for `volume`, on the GPU or the CPU.
    pub fn make(
        &mut self,
        volume: &Volume,
        method: &Method,
        on_gpu: bool,
    ) -> Result<(Box<dyn Renderer>, Device), AppError> {
        if on_gpu {
            return self.gpu.renderer(volume, method);
        }
        Ok((create_renderer(volume, method)?, Device::Cpu))
    }

    /// The renderer of `scene` on `volume`: [`RendererFactory::place`], then
    /// [`RendererFactory::make`] with the scene's method.
    pub fn open(&mut self, volume: &Volume, scene: &Scene) -> Result<Opened, AppError> {
        let placement = self.place(volume, scene)?;
        let (renderer, device) = self.make(volume, &scene.method, placement.on_gpu)?;
        Ok(Opened {
            renderer,
            device,
            cpu_because: placement.cpu_because,
        })
    }
}

/// The adapters the GPU backend can open, preferred first (name, API, kind, driver).
pub fn adapters() -> Result<Vec<String>, AppError> {
    gpu::adapters()
}

impl From<AppError> for RenderError {
    /// The engine's error as it was; the application's errors as a backend's reason (for a
    /// render thread that reports [`RenderError`]s).
    fn from(e: AppError) -> Self {
        match e {
            AppError::Render(r) => r,
            other => RenderError::Backend(other.to_string()),
        }
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
    use crate::error::AppError;

    /// The device, opened on first use (or why it could not be).
    pub(super) struct Lazy(Option<Result<Arc<GpuContext>, String>>);

    impl Lazy {
        pub(super) fn new() -> Self {
            Self(None)
        }

        fn context(&mut self) -> Result<Arc<GpuContext>, AppError> {
            let opened = self
                .0
                .get_or_insert_with(|| GpuContext::new().map(Arc::new).map_err(|e| e.to_string()));
            Ok(opened.clone().map_err(RenderError::Backend)?)
        }

        /// `Ok` when the GPU backend draws `scene` on `volume` and a device is open; `auto`
        /// applies the rule of [`volux_gpu::auto_draws`] (no software adapter unless the
        /// method is GPU-only).
        pub(super) fn draws(
            &mut self,
            volume: &Volume,
            scene: &Scene,
            auto: bool,
        ) -> Result<(), AppError> {
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
        ) -> Result<(Box<dyn Renderer>, Device), AppError> {
            let ctx = self.context()?;
            let device = Device::Gpu(ctx.adapter().to_string());
            let renderer =
                volux_gpu::renderer_for(ctx, volume, method).map_err(RenderError::from)?;
            Ok((renderer, device))
        }
    }

    pub(super) fn adapters() -> Result<Vec<String>, AppError> {
        Ok(volux_gpu::adapters()
            .iter()
            .map(|a| a.to_string())
            .collect())
    }
}

#[cfg(not(feature = "gpu"))]
mod gpu {
    use volux_render::engine::Renderer;
    use volux_render::scene::{Method, Scene, Volume};

    use super::Device;
    use crate::error::AppError;

    pub(super) struct Lazy;

    impl Lazy {
        pub(super) fn new() -> Self {
            Self
        }

        pub(super) fn draws(&mut self, _: &Volume, _: &Scene, _: bool) -> Result<(), AppError> {
            Err(AppError::GpuNotBuilt)
        }

        pub(super) fn renderer(
            &mut self,
            _: &Volume,
            _: &Method,
        ) -> Result<(Box<dyn Renderer>, Device), AppError> {
            Err(AppError::GpuNotBuilt)
        }
    }

    pub(super) fn adapters() -> Result<Vec<String>, AppError> {
        Err(AppError::GpuNotBuilt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::{synth, CameraSpec, TransferFunction};

    fn scene_on(volume: &Volume) -> Scene {
        let camera = CameraSpec::default().resolve(&volume.bounds()).unwrap();
        let tf = TransferFunction::from_json(
            r#"{"color": [[0, 1, 1, 1]], "extinction": [[0, 0], [1, 4]]}"#,
        )
        .unwrap();
        Scene::new(camera, 16, 12, tf)
    }

    /// The CPU backend opens the engine's renderer, which draws the CPU engine's picture.
    #[test]
    fn the_cpu_backend_never_opens_a_device() {
        let volume = Volume::from(synth::marschner_lobb(12).unwrap());
        let scene = scene_on(&volume);
        let mut factory = RendererFactory::new(Backend::Cpu);
        let mut opened = factory.open(&volume, &scene).unwrap();
        assert_eq!(opened.device, Device::Cpu);
        assert_eq!(opened.cpu_because, None);
        let control = volux_render::tiles::Control::default();
        let a = opened.renderer.render(&scene, &control).unwrap();
        let b = create_renderer(&volume, &scene.method)
            .unwrap()
            .render(&scene, &control)
            .unwrap();
        assert_eq!(a.image, b.image);
    }

    /// Without the GPU backend, `auto` renders on the CPU without a reason (there was no
    /// choice) and `gpu` is refused as not built.
    #[cfg(not(feature = "gpu"))]
    #[test]
    fn a_build_without_the_gpu_refuses_it_by_name() {
        let volume = Volume::from(synth::marschner_lobb(8).unwrap());
        let scene = scene_on(&volume);
        let auto = RendererFactory::new(Backend::Auto)
            .place(&volume, &scene)
            .unwrap();
        assert_eq!(
            auto,
            Placement {
                on_gpu: false,
                cpu_because: None
            }
        );
        let gpu = RendererFactory::new(Backend::Gpu).place(&volume, &scene);
        assert!(matches!(gpu, Err(AppError::GpuNotBuilt)));
        assert!(matches!(adapters(), Err(AppError::GpuNotBuilt)));
    }

    #[test]
    fn backends_read_and_write_their_names() {
        for name in Backend::NAMES {
            let b: Backend = name.parse().unwrap();
            assert_eq!(b.name(), name);
            assert_eq!(serde_json::to_string(&b).unwrap(), format!("\"{name}\""));
        }
        assert!(matches!(
            Backend::parse("vulkan"),
            Err(WordError::NotABackend { .. })
        ));
    }
}
