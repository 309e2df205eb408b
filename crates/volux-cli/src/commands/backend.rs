//! `--backend`: the renderer a command renders with, on the CPU or the GPU (`volux-gpu`,
//! behind the `gpu` feature), and `volux info --gpu`.
use volux_render::engine::create_renderer;
use volux_render::renderer::Renderer;
use volux_render::scene::{Scene, Volume};

use super::common::CmdError;
use crate::cli::Backend;

/// The renderer of `scene` on `volume` for `backend`: `auto` takes a hardware GPU when it
/// draws the scene (`volux_gpu::auto_draws`: never a software adapter unless the method
/// is GPU-only) and says on stderr which it chose and why.
pub fn renderer(
    volume: &Volume,
    scene: &Scene,
    backend: Backend,
) -> Result<Box<dyn Renderer>, CmdError> {
    match backend {
        Backend::Cpu => Ok(create_renderer(volume, &scene.method)?),
        // Only the GPU draws a GPU-only method: its refusal is the answer, not a CPU render.
        Backend::Gpu => gpu::renderer(volume, scene, false),
        Backend::Auto if scene.method.gpu_only() => gpu::renderer(volume, scene, false),
        Backend::Auto => match gpu::renderer(volume, scene, true) {
            Ok(r) => Ok(r),
            Err(why) => {
                if gpu::BUILT {
                    eprintln!("volux: rendering on the CPU: {why}");
                }
                Ok(create_renderer(volume, &scene.method)?)
            }
        },
    }
}

/// `volux info --gpu`: the adapters, preferred first.
pub fn list_adapters(json: bool) -> Result<(), CmdError> {
    let adapters = gpu::adapters()?;
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

#[cfg(feature = "gpu")]
mod gpu {
    use std::sync::Arc;

    use volux_gpu::GpuContext;
    use volux_render::renderer::Renderer;
    use volux_render::scene::{Scene, Volume};
    use volux_render::RenderError;

    use crate::commands::common::CmdError;

    pub const BUILT: bool = true;

    /// The GPU renderer; `auto` applies the rule of [`volux_gpu::auto_draws`].
    pub fn renderer(
        volume: &Volume,
        scene: &Scene,
        auto: bool,
    ) -> Result<Box<dyn Renderer>, CmdError> {
        volux_gpu::supports(volume, scene).map_err(RenderError::Backend)?;
        let ctx = Arc::new(GpuContext::new().map_err(RenderError::from)?);
        if auto {
            volux_gpu::auto_draws(&ctx, volume, scene).map_err(RenderError::Backend)?;
        }
        eprintln!("volux: rendering on the GPU: {}", ctx.adapter());
        Ok(volux_gpu::renderer_for(ctx, volume, &scene.method).map_err(RenderError::from)?)
    }

    pub fn adapters() -> Result<Vec<String>, CmdError> {
        Ok(volux_gpu::adapters()
            .iter()
            .map(|a| a.to_string())
            .collect())
    }
}

#[cfg(not(feature = "gpu"))]
mod gpu {
    use volux_render::renderer::Renderer;
    use volux_render::scene::{Scene, Volume};

    use crate::commands::common::CmdError;

    pub const BUILT: bool = false;

    const NOT_BUILT: &str = "this volux was built without the GPU backend (cargo build --release -p volux-cli --features gpu)";

    pub fn renderer(_: &Volume, _: &Scene, _: bool) -> Result<Box<dyn Renderer>, CmdError> {
        Err(NOT_BUILT.into())
    }

    pub fn adapters() -> Result<Vec<String>, CmdError> {
        Err(NOT_BUILT.into())
    }
}
