//! The GPU backend as the engine's injected device ([`volux_render::device::GpuDevice`]):
//! the context opened on first use (or why it could not be), then kept, so that a front end
//! rendering many frames opens it once.
use std::sync::Arc;

use volux_render::device::GpuDevice;
use volux_render::renderer::Renderer;
use volux_render::scene::{Method, Scene, Volume};
use volux_render::RenderError;

use crate::context::GpuContext;
use crate::select::{auto_draws, renderer_for, supports};

/// The GPU device of a front end, opened on first use.
#[derive(Default)]
pub struct LazyGpu(Option<Result<Arc<GpuContext>, String>>);

impl LazyGpu {
    /// A device not opened yet.
    pub fn new() -> Self {
        Self(None)
    }

    fn context(&mut self) -> Result<Arc<GpuContext>, RenderError> {
        let opened = self
            .0
            .get_or_insert_with(|| GpuContext::new().map(Arc::new).map_err(|e| e.to_string()));
        opened.clone().map_err(RenderError::backend)
    }
}

impl GpuDevice for LazyGpu {
    fn draws(&mut self, volume: &Volume, scene: &Scene, auto: bool) -> Result<(), RenderError> {
        supports(volume, scene)?;
        let ctx = self.context()?;
        if auto {
            auto_draws(&ctx, volume, scene)?;
        }
        Ok(())
    }

    fn renderer(
        &mut self,
        volume: &Volume,
        method: &Method,
    ) -> Result<(Box<dyn Renderer>, String), RenderError> {
        let ctx = self.context()?;
        let adapter = ctx.adapter().to_string();
        Ok((renderer_for(ctx, volume, method)?, adapter))
    }

    fn adapters(&self) -> Vec<String> {
        crate::context::adapters()
            .iter()
            .map(|a| a.to_string())
            .collect()
    }
}
