//! Where frames are rendered (OSPRay's device role): the CPU engine, or the GPU backend
//! (`volux-gpu`, in front ends built with it) when there is an adapter and it draws the
//! scene.
//!
//! - [`Backend::Cpu`] never opens a device;
//! - [`Backend::Gpu`] insists: what the GPU cannot draw is an error that says why;
//! - [`Backend::Auto`] draws on a hardware adapter when the GPU backend draws the scene's
//!   method and features, else on the CPU, and says why ([`Placement::cpu_because`]). A
//!   software adapter (llvmpipe, lavapipe: wgpu's device type `Cpu`) is never preferred to
//!   the CPU engine, which is faster on the same cores, unless the method is GPU-only
//!   (texture slicing), whose refusal by the GPU is then the answer (`volux_gpu::auto_draws`).
//!
//! Every front end renders through a [`RendererFactory`], given the GPU device
//! ([`GpuDevice`]) when the front end was built with one: the application layer itself
//! carries no GPU dependency, so a front end built without the GPU has none.
use serde::{Deserialize, Serialize};
use volux_render::device::GpuDevice;
use volux_render::engine::{create_renderer, Renderer};
use volux_render::scene::{Method, Scene, Volume};
use volux_render::RenderError;

use crate::error::AppError;
use crate::words::WordError;

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

/// Makes renderers on a [`Backend`], on the CPU engine or on the GPU device the front end
/// hands over (`volux_gpu::LazyGpu` in a build with the GPU backend; `None` otherwise), which
/// is kept once opened, so a front end that renders many frames opens it once.
pub struct RendererFactory {
    backend: Backend,
    gpu: Option<Box<dyn GpuDevice>>,
}

impl RendererFactory {
    /// A factory for `backend` with the front end's GPU device, if it was built with one; no
    /// device is opened yet.
    pub fn new(backend: Backend, gpu: Option<Box<dyn GpuDevice>>) -> Self {
        Self { backend, gpu }
    }

    /// The backend it renders on.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The GPU device, or [`AppError::GpuNotBuilt`].
    fn gpu(&mut self) -> Result<&mut Box<dyn GpuDevice>, AppError> {
        self.gpu.as_mut().ok_or(AppError::GpuNotBuilt)
    }

    /// Where the frame of `scene` (its method resolved) on `volume` is drawn; an error when
    /// the backend is `gpu` (or the method is GPU-only) and the GPU cannot draw it.
    pub fn place(&mut self, volume: &Volume, scene: &Scene) -> Result<Placement, AppError> {
        let placed = |on_gpu| Placement {
            on_gpu,
            cpu_because: None,
        };
        let insist = self.backend == Backend::Gpu || scene.method.gpu_only();
        if self.backend == Backend::Cpu {
            return Ok(placed(false));
        }
        if insist {
            // Only the GPU draws a GPU-only method: why it cannot is the answer.
            self.gpu()?.draws(volume, scene, false)?;
            return Ok(placed(true));
        }
        let Some(gpu) = self.gpu.as_mut() else {
            // A build without the GPU: there was no choice to explain.
            return Ok(placed(false));
        };
        Ok(match gpu.draws(volume, scene, true) {
            Ok(()) => placed(true),
            Err(why) => Placement {
                on_gpu: false,
                cpu_because: Some(reason_only(&why)),
            },
        })
    }

    /// A renderer of `method` (resolved) for `volume`, on the GPU or the CPU.
    pub fn make(
        &mut self,
        volume: &Volume,
        method: &Method,
        on_gpu: bool,
    ) -> Result<(Box<dyn Renderer>, Device), AppError> {
        if on_gpu {
            let (renderer, adapter) = self.gpu()?.renderer(volume, method)?;
            return Ok((renderer, Device::Gpu(adapter)));
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

    /// The adapters the GPU device can open, preferred first.
    pub fn adapters(&self) -> Result<Vec<String>, AppError> {
        let gpu = self.gpu.as_ref().ok_or(AppError::GpuNotBuilt)?;
        Ok(gpu.adapters())
    }
}

/// Why the GPU does not draw a scene, without the way out the engine offers (the CPU
/// engine, which `auto` takes anyway).
fn reason_only(why: &RenderError) -> String {
    match why {
        RenderError::Refused(r) => format!("{} {}", r.by, r.refuses),
        RenderError::Backend { reason, .. } => reason.clone(),
        other => other.to_string(),
    }
}

impl From<AppError> for RenderError {
    /// The engine's error as it was; the application's errors as a backend's reason (for a
    /// render thread that reports [`RenderError`]s).
    fn from(e: AppError) -> Self {
        match e {
            AppError::Render(r) => r,
            other => RenderError::backend(other.to_string()),
        }
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
        let mut factory = RendererFactory::new(Backend::Cpu, None);
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

    /// Without a GPU device, `auto` renders on the CPU without a reason (there was no
    /// choice) and `gpu` is refused as not built.
    #[test]
    fn a_build_without_the_gpu_refuses_it_by_name() {
        let volume = Volume::from(synth::marschner_lobb(8).unwrap());
        let scene = scene_on(&volume);
        let auto = RendererFactory::new(Backend::Auto, None)
            .place(&volume, &scene)
            .unwrap();
        assert_eq!(
            auto,
            Placement {
                on_gpu: false,
                cpu_because: None
            }
        );
        let mut gpu = RendererFactory::new(Backend::Gpu, None);
        assert!(matches!(
            gpu.place(&volume, &scene),
            Err(AppError::GpuNotBuilt)
        ));
        assert!(matches!(gpu.adapters(), Err(AppError::GpuNotBuilt)));
    }

    /// A device that draws everything, on a hardware or a software adapter; it counts the
    /// times it was asked.
    struct FakeGpu {
        software: bool,
        asked: std::sync::Arc<std::sync::atomic::AtomicUsize>,
    }

    impl GpuDevice for FakeGpu {
        fn draws(&mut self, _: &Volume, scene: &Scene, auto: bool) -> Result<(), RenderError> {
            self.asked
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            if auto && self.software && !scene.method.gpu_only() {
                // As the GPU refuses a scene: with the CPU engine as the way out, which
                // `auto`'s reason leaves out (it takes it).
                return Err(volux_render::Refusal::new(
                    "the fake adapter",
                    "is a software rasterizer",
                    Some(volux_render::Remedy::CpuBackend),
                )
                .into());
            }
            Ok(())
        }

        fn renderer(
            &mut self,
            volume: &Volume,
            method: &Method,
        ) -> Result<(Box<dyn Renderer>, String), RenderError> {
            Ok((create_renderer(volume, method)?, "fake".into()))
        }

        fn adapters(&self) -> Vec<String> {
            vec!["fake".into()]
        }
    }

    /// `auto` takes a hardware device, says why it keeps to the CPU on a software one, and
    /// insists on the device for a GPU-only method; `cpu` never asks the device.
    #[test]
    fn auto_prefers_hardware_and_says_why_not() {
        let volume = Volume::from(synth::marschner_lobb(8).unwrap());
        let scene = scene_on(&volume);
        let asked = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let device = |software| -> Option<Box<dyn GpuDevice>> {
            Some(Box::new(FakeGpu {
                software,
                asked: asked.clone(),
            }))
        };
        let hardware = RendererFactory::new(Backend::Auto, device(false))
            .open(&volume, &scene)
            .unwrap();
        assert_eq!(hardware.device, Device::Gpu("fake".into()));
        let software = RendererFactory::new(Backend::Auto, device(true))
            .place(&volume, &scene)
            .unwrap();
        assert!(!software.on_gpu);
        assert_eq!(
            software.cpu_because.as_deref(),
            Some("the fake adapter is a software rasterizer")
        );
        let mut slicing = scene.clone();
        slicing.method = Method::Slicing(Default::default());
        let placed = RendererFactory::new(Backend::Auto, device(true))
            .place(&volume, &slicing)
            .unwrap();
        assert!(placed.on_gpu, "a GPU-only method goes to the GPU");
        let before = asked.load(std::sync::atomic::Ordering::Relaxed);
        let cpu = RendererFactory::new(Backend::Cpu, device(false))
            .place(&volume, &scene)
            .unwrap();
        assert!(!cpu.on_gpu);
        assert_eq!(asked.load(std::sync::atomic::Ordering::Relaxed), before);
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
