//! The trait every renderer implements: one call renders a [`Scene`] into a [`Frame`]
//! (OSPRay's `renderFrame`). [`crate::engine`] chooses the renderer for a volume.
use std::time::Instant;

use volux_core::image::Image;

use crate::error::{Refusal, RenderError};
use crate::frame::{Frame, FrameStats, MethodStats, Rebuilt};
use crate::scene::{Method, Scene};
use crate::tiles::Control;

/// A renderer of one volume: turns scenes into frames, keeping its caches between calls.
pub trait Renderer: Send {
    /// The method's short name ([`Method::name`]: `raycast`, `pt`, `tet-raycast`,
    /// `mesh-reference`, `resample`).
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

/// The error of a renderer handed a scene for another method.
pub(crate) fn wrong_method(renderer: &'static str, method: &Method) -> RenderError {
    Refusal::new(
        format!("the '{renderer}' renderer"),
        format!(
            "cannot draw method '{}': create a renderer for it",
            method.name()
        ),
        None,
    )
    .into()
}

/// Refuses a scene with a sculpt mask or region labels in a renderer of tetrahedra: both are
/// voxel layers of a grid (seed `004`), drawn by grid ray casting; a mesh is cut with planes.
pub(crate) fn no_voxel_layers(renderer: &'static str, scene: &Scene) -> Result<(), RenderError> {
    let layer = match (&scene.mask, &scene.labels) {
        (Some(_), _) => "a sculpt mask",
        (_, Some(_)) => "region labels",
        _ => return Ok(()),
    };
    Err(Refusal::new(
        format!("the '{renderer}' renderer"),
        format!(
            "draws tetrahedra and cannot apply {layer}: masks and labels apply to grids (ray cast the grid); cut a mesh with clip planes"
        ),
        None,
    )
    .into())
}

/// A frame from an image, the error map where the method estimates one, and the figures.
pub(crate) fn frame(
    image: Image,
    error_map: Option<Vec<f32>>,
    started: Instant,
    rebuilt: Rebuilt,
    method: MethodStats,
) -> Frame {
    let pixels = image.width() * image.height();
    // Diagnostics a method times apart are not part of the frame.
    let diagnostics = match &method {
        MethodStats::ProjectedTetrahedra(s) => s.diagnostics_s,
        _ => 0.0,
    };
    Frame {
        image,
        error_map,
        stats: FrameStats {
            ms: (started.elapsed().as_secs_f64() - diagnostics) * 1e3,
            pixels,
            rebuilt,
            method,
        },
    }
}
