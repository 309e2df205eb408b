//! A rendering device besides the CPU engine (the GPU backend of `volux-gpu`), injected by a
//! front end (VTK's injected algorithms, OSPRay's devices): the engine and the application
//! layer know the interface, and only a front end built with the GPU hands one over, so a
//! build without it carries none of its dependencies.
use crate::error::RenderError;
use crate::renderer::Renderer;
use crate::scene::{Method, Scene, Volume};

/// A device that draws some scenes (the GPU), opened on first use.
pub trait GpuDevice: Send {
    /// `Ok` when the device draws `scene` on `volume` and is open; `auto`: also refuses an
    /// adapter slower than the CPU engine (a software rasterizer) unless the method is one
    /// only the device draws. The error says why.
    fn draws(&mut self, volume: &Volume, scene: &Scene, auto: bool) -> Result<(), RenderError>;

    /// A renderer of `method` (resolved) for `volume` on the device, and the adapter's name.
    fn renderer(
        &mut self,
        volume: &Volume,
        method: &Method,
    ) -> Result<(Box<dyn Renderer>, String), RenderError>;

    /// The adapters the device could open, preferred first.
    fn adapters(&self) -> Vec<String>;
}
