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
use volux_core::Image;

use crate::pt::reference::MeshReference;
use crate::pt::{PtRenderer, PtStats};
use crate::raycast::{GridRenderer, RenderStats};
use crate::resample::ResampleRenderer;
use crate::scene::{Method, Scene, Volume};
use crate::tetray::{TetRayCaster, TetRayStats};
use crate::tiles::Control;
use crate::RenderError;

/// A renderer of one volume: turns scenes into frames, keeping its caches between calls.
pub trait Renderer: Send {
    /// The method's short name (`raycast`, `pt`, `tet-raycast`, `resample`).
    fn name(&self) -> &'static str;

    /// Renders `scene`, which must name this renderer's method or [`Method::Auto`];
    /// `control` cancels it and receives its progress.
    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError>;

    /// Renders `scene` at `1 / divisor` of its resolution: the quick first pass of
    /// progressive refinement (a viewer shows it while the camera moves).
    fn render_preview(
        &mut self,
        scene: &Scene,
        control: &Control,
        divisor: usize,
    ) -> Result<Frame, RenderError> {
        let mut small = scene.clone();
        small.view = scene.view.reduced(divisor);
        self.render(&small, control)
    }
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Premultiplied linear RGBA.
    pub image: Image,
    /// Estimated absolute integration error per pixel (largest channel), row-major, where the
    /// method estimates it (adaptive Simpson; 0 elsewhere); `None` for methods that do not.
    pub error_map: Option<Vec<f32>>,
    /// What the frame did.
    pub stats: FrameStats,
}

/// Figures of a frame: the common ones, and the method's own.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameStats {
    /// Wall time of the frame in milliseconds.
    pub ms: f64,
    /// Pixels rendered.
    pub pixels: usize,
    /// Which caches the frame rebuilt.
    pub rebuilt: Rebuilt,
    /// The method's own figures.
    pub method: MethodStats,
}

/// Which derived data a frame had to build (the rest came from the renderer's caches).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Rebuilt {
    /// Data structures of the volume (macrocells, gradients, adjacency, ray-caster planes
    /// and hierarchy, a resampled grid): built once per volume, or per setting they need.
    pub data: bool,
    /// Classification: what depends on the transfer function and the isovalues.
    pub classification: bool,
    /// View: what depends on the camera and the image size.
    pub view: bool,
}

impl Rebuilt {
    /// Everything rebuilt (a renderer without caches for that stage).
    pub const ALL: Self = Self {
        data: true,
        classification: true,
        view: true,
    };
}

/// The figures only one method has.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum MethodStats {
    /// Grid ray casting (also of a resampled mesh).
    GridRaycast(RenderStats),
    /// Projected Tetrahedra.
    ProjectedTetrahedra(PtStats),
    /// Tetrahedral ray casting.
    TetRaycast(TetRayStats),
    /// The brute-force mesh reference (no figures of its own).
    MeshReference,
}

/// The renderer of `method` for `volume` (resolving [`Method::Auto`]); errors when the
/// method does not apply to the volume. Nothing heavy is built until the first frame, except
/// the tet ray caster's planes and hierarchy.
pub fn create_renderer(volume: &Volume, method: &Method) -> Result<Box<dyn Renderer>, RenderError> {
    let method = method.resolve(volume)?;
    Ok(match (method, volume) {
        (Method::GridRaycast(_), Volume::Grid(g)) => Box::new(GridRenderer::new(g.clone())),
        (Method::ProjectedTetrahedra(_), Volume::Mesh(m)) => Box::new(PtRenderer::new(m.clone())),
        (Method::TetRaycast(_), Volume::Mesh(m)) => Box::new(TetRayCaster::new(m.clone())),
        (Method::Resample { .. }, Volume::Mesh(m)) => Box::new(ResampleRenderer::new(m.clone())),
        (Method::MeshReference, Volume::Mesh(m)) => Box::new(MeshReference::new(m.clone())),
        (m, v) => {
            return Err(RenderError::InvalidOptions(format!(
                "no renderer for {} of a {}",
                m.name(),
                v.kind()
            )))
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

/// The error of a renderer handed a scene for another method.
pub(crate) fn wrong_method(renderer: &'static str, method: &Method) -> RenderError {
    RenderError::InvalidOptions(format!(
        "the '{renderer}' renderer cannot draw method '{}': create a renderer for it",
        method.name()
    ))
}

/// A frame from an image, the error map where the method estimates one, and the figures.
pub(crate) fn frame(
    image: Image,
    error_map: Option<Vec<f32>>,
    started: std::time::Instant,
    rebuilt: Rebuilt,
    method: MethodStats,
) -> Frame {
    let pixels = image.width() * image.height();
    Frame {
        image,
        error_map,
        stats: FrameStats {
            ms: started.elapsed().as_secs_f64() * 1e3,
            pixels,
            rebuilt,
            method,
        },
    }
}
