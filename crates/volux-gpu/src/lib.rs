//! The GPU backend of Volux, through `wgpu` (Vulkan, Metal, DX12, GL): the same pictures as
//! the CPU engine, behind the engine's [`Renderer`](volux_render::renderer::Renderer) trait.
//!
//! - [`GpuContext`]: an adapter and its device, chosen once ([`adapters`] lists them);
//! - [`GpuGridRenderer`]: grid ray casting in a compute shader, one thread per pixel, rays
//!   generated in the shader from the camera, clipped to the box and the clip planes (the
//!   volume of interest of seed `004`, ch. 4), the same sample lattice and classification
//!   tables as the CPU engine, `f32` accumulation (not `004`'s 8-bit buffers, section 6.1):
//!   seed `001`'s Riemann sum with step-corrected opacity and pre-integration (`000` §2.6,
//!   the 2D table), Blinn-Phong shading with the CPU's gradient volume (`002` §4.6),
//!   isosurfaces located by regula falsi and lit, maximum intensity projection (the largest
//!   lattice sample refined by a parabola and polished, as `volux_render::mip`), the sculpt
//!   mask (`004` §4.4.1, a bit per voxel, interpolated and thresholded at 0.5), empty-space
//!   skipping over the CPU's macrocells (samples never move), jitter and early ray
//!   termination; `003`'s GPU ray casting without its per-block opacity reset;
//! - [`GpuSlicingRenderer`]: texture slicing of a grid (seed `004` ch. 3, `--method
//!   slicing`): view-aligned slices of the volume of interest (the box cut by the clip
//!   planes, `004` §4.3.2, swept as in §4.2.2) rasterized and blended back to front ("over",
//!   eq. 3.2) into an `f32` target, each fragment classified with the ray caster's tables
//!   (opacity corrected for the slice distance along its ray), the sculpt mask and shading
//!   per fragment; maximum intensity projection, isosurfaces and labels are refused.
//!
//! What the ray casting shader does not draw (the trapezoid, Simpson, adaptive Simpson and reference
//! integrators, tricubic reconstruction, region labels, more than [`MAX_ISOVALUES`]
//! isosurfaces, bricked grids) is refused with a
//! [`RenderError`](volux_render::RenderError) that says so; a front end with
//! `--backend auto` then renders on the CPU ([`GpuGridRenderer::supports`]).
mod context;
mod error;
mod grid;
mod params;
mod resident;
mod resources;
mod slices;
mod slicing;
mod tables;
mod target;

pub use context::{adapters, AdapterSummary, GpuContext};
pub use error::GpuError;
pub use grid::{GpuGridRenderer, MAX_ISOVALUES};
pub use slicing::GpuSlicingRenderer;
