//! The GPU backend of Volux, through `wgpu` (Vulkan, Metal, DX12, GL): the same pictures as
//! the CPU engine, behind the engine's [`Renderer`](volux_render::renderer::Renderer) trait.
//!
//! - [`GpuContext`]: an adapter and its device, chosen once ([`adapters`] lists them);
//! - [`GpuGridRenderer`]: grid ray casting in a compute shader (seed `001`'s Riemann sum with
//!   step-corrected opacity, `003`'s GPU ray casting without its per-block opacity reset),
//!   one thread per pixel, rays generated in the shader from the camera, clipped to the box
//!   and the clip planes, the same sample lattice and classification table as the CPU lanes,
//!   `f32` accumulation (not `004`'s 8-bit buffers, section 6.1), early ray termination,
//!   and maximum intensity projection (the largest lattice sample refined by a parabola and
//!   polished, as `volux_render::mip`);
//! - [`GpuPtRenderer`]: Projected Tetrahedra of a tetrahedral mesh (seed `000` chapters 4-5,
//!   seed `002` section 4): classification by the ternary truth table and the thick vertex
//!   in a compute shader, a GPU radix sort of centroid depths, the fans rasterized by the
//!   hardware and coloured with the average or ψ rule, composited back to front.
//!
//! What the shader does not draw yet (shading, isosurfaces, the other integrators, the
//! sculpt mask, region labels, jitter, tricubic reconstruction, bricked grids) is refused
//! with a [`RenderError`](volux_render::RenderError) that says so; a front end with
//! `--backend auto` then renders on the CPU ([`GpuGridRenderer::supports`]).
mod context;
mod error;
mod grid;
mod params;
mod pt;
mod tables;

pub use context::{adapters, AdapterSummary, GpuContext};
pub use error::GpuError;
pub use grid::GpuGridRenderer;
pub use pt::GpuPtRenderer;
