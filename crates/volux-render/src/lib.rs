//! # volux-render
//!
//! The rendering engine of Volux. Front ends (the CLI, the viewer, benchmarks) build a
//! [`Scene`](scene::Scene) and call one [`Renderer`](engine::Renderer) made for their
//! [`Volume`](scene::Volume) by [`create_renderer`](engine::create_renderer); the renderers
//! share the pipeline's stages, one module each:
//! **data** → **field sampling** → **classification** → **integration** → **traversal** →
//! **compositing** → **image**.
//!
//! ```
//! use volux_core::{image::PngOptions, synth, CameraSpec};
//! use volux_render::{engine::create_renderer, scene::{Scene, Volume}, tiles::Control};
//!
//! let volume = Volume::from(synth::marschner_lobb(64)?);
//! let camera = CameraSpec { azimuth: Some(30.0), ..Default::default() }.resolve(&volume.bounds())?;
//! let scene = Scene::new(camera, 256, 256, volume.preset_tf("auto")?);
//! let frame = create_renderer(&volume, &scene.method)?.render(&scene, &Control::default())?;
//! frame.image.write_png(&std::env::temp_dir().join("volux-quick-start.png"), &PngOptions::default())?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## The engine API
//!
//! - [`scene`]: what to render: the volume, the view, the appearance, the method, with
//!   units and defaults stated once;
//! - [`engine`]: the [`Renderer`](engine::Renderer) trait, frames and their figures, and the
//!   choice of renderer for a volume and a method;
//! - [`renderer`]: the trait every renderer implements; [`frame`]: frames and their figures
//!   (the common ones and each method's own); [`error`]: the renderers' errors;
//! - [`tiles`]: the one tile driver (parallel tiles, cancellation, progress) every renderer
//!   runs on, and [`Control`](tiles::Control).
//! - [`framing`]: what a scene makes visible (the box a camera frames, or why nothing
//!   shows), and a camera fitted to a box.
//! - [`backend_kit`]: the engine's parts a rendering backend (the GPU's) reuses, listed in
//!   one place: ray set-up, tables, lattices.
//! - [`device`]: the interface of a rendering device besides the CPU engine (the GPU
//!   backend), injected by a front end that was built with one.
//!
//! ## Shared stages
//!
//! - [`sampling`]: field reconstruction (trilinear and tricubic sampling of native-type
//!   grids, lane-wise);
//! - [`classify`]: classification, lookup tables built from a transfer function;
//!   [`data_colour`]: RGB volumes drawn in their own colour, opacity from luminance;
//! - [`integrate`]: the optical model and its integrators (Riemann, trapezoid, Simpson,
//!   adaptive Simpson of seed `001`, pre-integration, and the linear-segment rules of the
//!   tetrahedral renderers: average, ψ, exact);
//! - [`composite`]: the front-to-back *under* operator, `f32` and `f64`;
//! - [`shading`]: gradients and Blinn-Phong lighting; [`isosurface`]: isovalue crossings;
//!   [`mip`]: maximum intensity projection;
//! - [`macrocell`] and [`intervals`]: empty-space skipping, the interval iterator a ray
//!   samples, and the seam bricked grids plug into;
//! - [`geometry`]: the exact orientation predicate and canonical face planes of meshes.
//!
//! ## Traversals (the renderers)
//!
//! - [`raycast`]: image-order ray casting of regular grids (seed `001`);
//! - [`pt`]: Projected Tetrahedra, cell projection of meshes (seeds `000` and `002`), with
//!   the brute-force per-pixel mesh reference;
//! - [`tetray`]: cell-to-cell ray casting of meshes;
//! - [`resample`]: meshes resampled onto a grid and ray cast.
//!
//! ## Sculpting (seed `004`)
//!
//! - [`sculpt`]: the sculpt mask seen through field sampling (every grid integrator), picking
//!   the visible surface, label colouring, and the sculpt state (planes, eraser strokes, digs,
//!   measurement and label picks) with undo, redo and replayable steps.
//!
//! ## Volumes larger than memory (seed `003`)
//!
//! - [`bricked`]: a chunked pyramid rendered level by level through a bounded brick cache,
//!   sampled exactly across brick faces, equal to the in-core image.
//! - [`distributed`]: sort-last rendering on several ranks: a k-d split of the chunks into
//!   one convex region per rank, each rank's rays sampled only in its region on the global
//!   sample lattice, binary-swap compositing in visibility order over a message-passing
//!   trait (threads in tests, MPI in `volux-mpi`); equal to the single-process render.
//!
//! `docs/seeds.md` in the repository says which seed document each number names.
#![deny(missing_docs)]
// One `unsafe` block, proven by a benchmark: the lane sampler's unchecked corner loads
// (`sampling::Trilinear::interpolate4`, with the argument for their soundness).
#![deny(unsafe_code)]

pub mod backend_kit;
pub mod bricked;
pub mod classify;
#[cfg(test)]
mod clip_tests;
pub mod composite;
pub mod data_colour;
pub mod device;
pub mod distributed;
pub mod engine;
pub mod error;
pub mod frame;
pub mod framing;
pub mod geometry;
pub mod integrate;
pub mod intervals;
pub mod isosurface;
pub mod macrocell;
pub mod mip;
pub mod pt;
pub mod raycast;
pub mod renderer;
pub mod resample;
pub mod sampling;
pub mod scene;
pub mod sculpt;
pub mod shading;
pub mod tetray;
pub mod tiles;

pub use error::{
    check_image_size, EngineWords, Refusal, Remedy, RenderError, Setting, SettingError, Vocabulary,
    MAX_IMAGE_SIDE,
};
pub use raycast::{render_grid, RenderOptions, RenderStats};
