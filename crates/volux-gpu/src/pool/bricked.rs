//! A bricked volume on the GPU ([`GpuBrickedRenderer`]): each frame samples the level its
//! [`Lod`] picks (as the CPU's `BrickedRenderer`), through a brick pool of that level.
use std::sync::Arc;

use volux_render::bricked::{BrickedRenderer, BrickedVolume, Lod};
use volux_render::frame::Frame;
use volux_render::renderer::Renderer;
use volux_render::scene::Scene;
use volux_render::tiles::Control;
use volux_render::RenderError;

use super::renderer::GpuPoolRenderer;
use super::slots::PoolOptions;
use super::source::PoolSource;
use crate::context::GpuContext;

/// Grid ray casting of a bricked volume through a brick pool of the level each frame needs
/// (the pool is rebuilt when the level changes).
pub struct GpuBrickedRenderer {
    ctx: Arc<GpuContext>,
    volume: Arc<BrickedVolume>,
    levels: BrickedRenderer,
    options: PoolOptions,
    pool: Option<(usize, GpuPoolRenderer)>,
}

impl GpuBrickedRenderer {
    /// A renderer of `volume` choosing levels by `lod`, with pools laid out by `options`.
    pub fn new(
        ctx: Arc<GpuContext>,
        volume: Arc<BrickedVolume>,
        lod: Lod,
        options: PoolOptions,
    ) -> Self {
        Self {
            ctx,
            levels: BrickedRenderer::new(volume.clone(), lod),
            volume,
            options,
            pool: None,
        }
    }

    /// The pool of the last frame's level.
    pub fn pool(&self) -> Option<&GpuPoolRenderer> {
        self.pool.as_ref().map(|(_, p)| p)
    }
}

impl Renderer for GpuBrickedRenderer {
    fn name(&self) -> &'static str {
        "raycast"
    }

    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError> {
        GpuPoolRenderer::supports(scene)?;
        let level = self.levels.level_for(scene);
        if self.pool.as_ref().is_none_or(|(l, _)| *l != level) {
            self.pool = None;
            let source = PoolSource::Level(self.volume.clone(), level);
            let pool = GpuPoolRenderer::new(self.ctx.clone(), source, self.options)?;
            self.pool = Some((level, pool));
        }
        match &mut self.pool {
            Some((_, pool)) => pool.render(scene, control),
            None => Err(RenderError::Internal("no brick pool".into())),
        }
    }
}
