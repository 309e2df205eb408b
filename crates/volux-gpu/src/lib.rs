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
//! - [`GpuPtRenderer`]: Projected Tetrahedra of a tetrahedral mesh (seed `000` chapters 4-5,
//!   seed `002` section 4): classification by the ternary truth table and the thick vertex
//!   in a compute shader, a GPU radix sort of centroid depths, the fans rasterized by the
//!   hardware and coloured with the average or ψ rule, lit isosurfaces inside the fragments
//!   and clip planes (cells culled, fragments trimmed to each pixel's window), composited
//!   front to back ("under" blending, no early termination); the kept set, the TF's tables
//!   and the sorted cells cached between frames and rebuilt only when what they depend on
//!   changes;
//! - [`GpuSlicingRenderer`]: texture slicing of a grid (seed `004` ch. 3, `--method
//!   slicing`): view-aligned slices of the volume of interest (the box cut by the clip
//!   planes, `004` §4.3.2, swept as in §4.2.2) rasterized and blended back to front ("over",
//!   eq. 3.2) into an `f32` target, each fragment classified with the ray caster's tables
//!   (opacity corrected for the slice distance along its ray), the sculpt mask and shading
//!   per fragment; maximum intensity projection, isosurfaces and labels are refused;
//! - [`GpuPoolRenderer`]: grids larger than the device's memory or texture limits through a
//!   brick pool (seed `003` done in one pass): bricks in the slots of a 3D texture atlas
//!   with a page table, loaded as rays ask for them, opacity carried across bricks and
//!   dispatches, transparent bricks never loaded; [`GpuBrickedRenderer`] draws a bricked
//!   volume (an OME-Zarr store) through a pool of the level each frame needs;
//! - [`renderer_for`] and [`supports`]: the renderer a front end gets for a volume, and
//!   whether a scene is drawn.
//!
//! What the shaders do not draw is refused with a
//! [`RenderError`](volux_render::RenderError) that names it (each renderer's `supports`);
//! a front end with `--backend auto` then renders on the CPU.
#![deny(missing_docs)]
#![forbid(unsafe_code)]
mod context;
mod device;
mod error;
mod grid;
mod params;
mod pool;
mod pt;
mod resident;
mod resources;
mod select;
mod slices;
mod slicing;
mod tables;
mod target;

pub use context::{adapters, quiet_headless_vulkan, AdapterSummary, GpuContext};
pub use device::LazyGpu;
pub use error::GpuError;
pub use grid::{GpuGridRenderer, MAX_ISOVALUES};
pub use pool::{GpuBrickedRenderer, GpuPoolRenderer, PoolOptions, PoolSource, PoolStats};
pub use pt::GpuPtRenderer;
pub use select::{auto_draws, renderer_for, supports};
pub use slicing::GpuSlicingRenderer;
