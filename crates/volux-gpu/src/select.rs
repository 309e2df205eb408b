//! The GPU renderer of a volume, as front ends ask for one ([`renderer_for`]): texture
//! slicing when asked; grids ray cast in a whole 3D texture, or through the brick pool when they are over the device's limits;
//! meshes with Projected Tetrahedra; bricked volumes through a pool of the level each frame
//! needs. [`supports`] says beforehand whether a scene is drawn.
use std::sync::Arc;

use volux_render::renderer::Renderer;
use volux_render::scene::{Method, Scene, Volume};
use volux_render::{Refusal, Remedy};

use crate::context::GpuContext;
use crate::error::GpuError;
use crate::grid::GpuGridRenderer;
use crate::pool::{GpuBrickedRenderer, GpuPoolRenderer, PoolOptions, PoolSource};
use crate::pt::GpuPtRenderer;
use crate::slicing::GpuSlicingRenderer;

/// `Ok` when the GPU backend draws `scene` of `volume`, else what it does not draw. (A grid
/// over the device's texture limits is drawn through the brick pool, which draws less: its
/// refusal comes with the frame.)
pub fn supports(volume: &Volume, scene: &Scene) -> Result<(), Refusal> {
    if let Volume::Grid(g) = volume {
        if g.color().is_some() && scene.appearance.data_colour && !scene.appearance.mip {
            return Err(Refusal::new(
                "the GPU backend",
                "does not draw an RGB grid in its own colour yet",
                Some(Remedy::CpuBackend),
            ));
        }
    }
    match volume {
        Volume::Grid(_) if matches!(scene.method, Method::Slicing(_)) => {
            GpuSlicingRenderer::supports(scene)
        }
        Volume::Grid(_) => GpuGridRenderer::supports(scene),
        Volume::Mesh(_) => GpuPtRenderer::supports(scene),
        Volume::Bricked(..) => GpuPoolRenderer::supports(scene),
        _ => Err(Refusal::new(
            "the GPU backend",
            format!("does not draw a {}", volume.kind()),
            Some(Remedy::CpuBackend),
        )),
    }
}

/// `Ok` when `--backend auto` draws `scene` of `volume` on the device of `ctx`, else why the
/// CPU engine draws it: what [`supports`] refuses, or a software adapter (llvmpipe: device
/// type `Cpu`), which is never preferred to the CPU engine (it was 3.6x-19x slower on the CT
/// head and the Blunt Fin) unless the method is GPU-only ([`Method::gpu_only`]). One rule
/// for every front end.
pub fn auto_draws(ctx: &GpuContext, volume: &Volume, scene: &Scene) -> Result<(), Refusal> {
    supports(volume, scene)?;
    let adapter = ctx.adapter();
    if adapter.is_software() && !scene.method.gpu_only() {
        return Err(Refusal::new(
            format!("the GPU adapter {adapter}"),
            "is a software rasterizer, slower than the CPU engine (the GPU backend asked for by \
             name uses it anyway)",
            None,
        ));
    }
    Ok(())
}

/// The GPU renderer of `method` for `volume` on the device of `ctx`: texture slicing for
/// `--method slicing`, else ray casting or PT; a grid over the device's 3D texture or buffer
/// limits, or one whose upload runs out of device memory, is ray cast through the brick
/// pool.
pub fn renderer_for(
    ctx: Arc<GpuContext>,
    volume: &Volume,
    method: &Method,
) -> Result<Box<dyn Renderer>, GpuError> {
    Ok(match volume {
        Volume::Grid(g) if matches!(method, Method::Slicing(_)) => {
            Box::new(GpuSlicingRenderer::new(ctx, g.clone())?)
        }
        Volume::Grid(g) => match GpuGridRenderer::new(ctx.clone(), g.clone()) {
            Ok(r) => Box::new(r),
            Err(GpuError::OverLimit { .. } | GpuError::Failed(_)) => Box::new(
                GpuPoolRenderer::new(ctx, PoolSource::Grid(g.clone()), PoolOptions::default())?,
            ),
            Err(e) => return Err(e),
        },
        Volume::Mesh(m) => Box::new(GpuPtRenderer::new(ctx, m.clone())?),
        Volume::Bricked(v, lod) => Box::new(GpuBrickedRenderer::new(
            ctx,
            v.clone(),
            *lod,
            PoolOptions::default(),
        )),
        _ => {
            return Err(GpuError::Failed(format!(
                "the GPU backend does not draw a {}",
                volume.kind()
            )))
        }
    })
}
