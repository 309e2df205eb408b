//! `--backend`: the renderer a command renders with, opened by the application layer's
//! [`RendererFactory`] (the CPU engine, or the GPU device this module hands over in a build
//! with the `gpu` feature), and `volux info --gpu`. This module only phrases the choice for
//! the terminal.
use volux_app::{AppError, Backend, Device, RendererFactory};
use volux_render::device::GpuDevice;
use volux_render::renderer::Renderer;
use volux_render::scene::{Scene, Volume};

use super::common::CmdError;

/// How to get the GPU backend, for a build without it.
const HOW_TO_BUILD: &str =
    "this volux was built without the GPU backend (cargo build --release -p volux-cli --features gpu)";

/// The GPU device of a build with the `gpu` feature.
pub fn gpu_device() -> Option<Box<dyn GpuDevice>> {
    #[cfg(feature = "gpu")]
    return Some(Box::new(volux_gpu::LazyGpu::new()));
    #[cfg(not(feature = "gpu"))]
    None
}

/// The command line's words for the application layer's errors on backends.
fn phrased(e: AppError) -> CmdError {
    match e {
        AppError::GpuNotBuilt => HOW_TO_BUILD.into(),
        other => other.into(),
    }
}

/// The renderer of `scene` on `volume` for `backend`; says on stderr which device it chose,
/// and why `auto` chose the CPU in a build with the GPU backend.
pub fn renderer(
    volume: &Volume,
    scene: &Scene,
    backend: Backend,
) -> Result<Box<dyn Renderer>, CmdError> {
    let opened = RendererFactory::new(backend, gpu_device())
        .open(volume, scene)
        .map_err(phrased)?;
    match (&opened.device, &opened.cpu_because) {
        (Device::Gpu(adapter), _) => eprintln!("volux: rendering on the GPU: {adapter}"),
        (Device::Cpu, Some(why)) => eprintln!("volux: rendering on the CPU: {why}"),
        (Device::Cpu, None) => {}
    }
    Ok(opened.renderer)
}

/// `volux info --gpu`: the adapters, preferred first.
pub fn list_adapters(json: bool) -> Result<(), CmdError> {
    let adapters = RendererFactory::new(Backend::Gpu, gpu_device())
        .adapters()
        .map_err(phrased)?;
    if json {
        outln!("{}", serde_json::to_string(&adapters)?)?;
    } else if adapters.is_empty() {
        outln!("no GPU adapter (install a Vulkan driver, e.g. mesa-vulkan-drivers)")?;
    } else {
        for (i, a) in adapters.iter().enumerate() {
            let first = if i == 0 {
                "  (--backend gpu uses it)"
            } else {
                ""
            };
            outln!("{i}: {a}{first}")?;
        }
    }
    Ok(())
}
