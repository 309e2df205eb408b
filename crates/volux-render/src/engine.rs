//! One call renders a frame, whatever the volume and the method (OSPRay's
//! `renderFrame(renderer, camera, world)`; VTK's smart mapper): [`create_renderer`] picks the
//! renderer for a [`Volume`] and a [`Method`], and [`Renderer::render`] draws a [`Scene`]
//! into a [`Frame`]. The CLI, the viewer, benchmarks and tests all go through here.
//!
//! A renderer belongs to one volume and keeps what it derived from it between frames, keyed
//! on what it was derived from, so that an interactive front end can call it many times a
//! second: data structures (macrocells, gradients, face adjacency, the ray caster's planes
//! and hierarchy) are built once; a transfer-function change re-classifies (classification
//! tables, empty-space flags, the kept set of cells, pre-integration tables); a camera change
//! re-projects (PT's projection, order and bins; the ray caster's start cells); nothing else
//! is rebuilt. [`FrameStats::rebuilt`] says which of the three a frame paid for.
//!
//! Adding a renderer means implementing [`Renderer`] and naming it in [`create_renderer`].
//!
//! ```
//! use volux_core::{synth, CameraSpec};
//! use volux_render::engine::{create_renderer, Renderer};
//! use volux_render::scene::{Scene, Volume};
//! use volux_render::tiles::Control;
//!
//! let volume = Volume::from(synth::marschner_lobb(32)?);
//! let camera = CameraSpec::default().resolve(&volume.bounds())?;
//! let scene = Scene::new(camera, 64, 64, volume.preset_tf("auto")?);
//! let mut renderer = create_renderer(&volume, &scene.method)?;
//! let frame = renderer.render(&scene, &Control::default())?;
//! assert_eq!((frame.image.width(), frame.stats.pixels), (64, 64 * 64));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
use crate::bricked::BrickedRenderer;
use crate::error::{Refusal, Remedy, RenderError};
use crate::pt::reference::MeshReference;
use crate::pt::render::PtRenderer;
use crate::raycast::renderer::GridRenderer;
use crate::resample::ResampleRenderer;
use crate::scene::{Method, Scene, Volume};
use crate::tetray::render::TetRayCaster;
use crate::tiles::Control;

pub use crate::frame::{Frame, FrameStats, MethodStats, Rebuilt};
pub use crate::renderer::Renderer;

/// The renderer of `method` for `volume` (resolving [`Method::Auto`]); errors when the
/// method does not apply to the volume. Nothing heavy is built until the first frame, except
/// the tet ray caster's planes and hierarchy.
pub fn create_renderer(volume: &Volume, method: &Method) -> Result<Box<dyn Renderer>, RenderError> {
    let method = method.resolve(volume)?;
    Ok(match (method, volume) {
        (Method::GridRaycast(_), Volume::Grid(g)) => Box::new(GridRenderer::new(g.clone())),
        (Method::GridRaycast(_), Volume::Bricked(b, lod)) => {
            Box::new(BrickedRenderer::new(b.clone(), *lod))
        }
        (Method::ProjectedTetrahedra(_), Volume::Mesh(m)) => Box::new(PtRenderer::new(m.clone())),
        (Method::TetRaycast(_), Volume::Mesh(m)) => Box::new(TetRayCaster::new(m.clone())?),
        (Method::Resample { .. }, Volume::Mesh(m)) => Box::new(ResampleRenderer::new(m.clone())),
        (Method::MeshReference, Volume::Mesh(m)) => Box::new(MeshReference::new(m.clone())),
        (Method::Slicing(_), _) => {
            return Err(Refusal::new(
                "the CPU engine",
                "does not draw texture slicing, a GPU method",
                Some(Remedy::GpuBackend),
            )
            .into())
        }
        (m, v) => {
            return Err(Refusal::new(
                format!("the {} method", m.name()),
                format!("has no renderer for a {}", v.kind()),
                None,
            )
            .into())
        }
    })
}

/// Renders one frame of `scene` with a fresh renderer (a batch job: no cache survives).
pub fn render_once(
    volume: &Volume,
    scene: &Scene,
    control: &Control,
) -> Result<Frame, RenderError> {
    create_renderer(volume, &scene.method)?.render(scene, control)
}
