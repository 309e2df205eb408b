//! Options and results of the grid ray caster.
use std::sync::Arc;

use glam::{DMat3, DVec3};
use volux_core::sculpt::SculptMask;

use crate::data_colour::DataColour;
use crate::sculpt::labels::LabelVolume;
use volux_core::voi::ClipPlane;
use volux_core::{Camera, Grid, Image, TransferFunction};

use crate::error::{Refusal, RenderError};
use crate::frame::RenderStats;
use crate::integrate::integrator::Integrator;
use crate::isosurface::Isosurfaces;
use crate::sampling::Reconstruction;
use crate::scene::{GridRaycast, Scene, DEFAULT_EARLY_TERMINATION};
use crate::shading::blinn_phong::BlinnPhong;
use crate::tiles::Control;

/// What to render and how.
#[derive(Clone)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// The camera.
    pub camera: Camera,
    /// The transfer function (resolved against the data range by the renderer).
    pub tf: TransferFunction,
    /// How rays are integrated (steps in voxel units of the smallest spacing).
    pub integrator: Integrator,
    /// Stop a ray once its opacity reaches this value; `None` integrates to the end
    /// (reference mode).
    pub early_termination: Option<f32>,
    /// Skip macrocells whose extinction is zero, when enough of them are empty for it to pay
    /// (never changes the image).
    pub empty_space_skipping: bool,
    /// Offset each ray's first Riemann sample by a per-pixel pseudo-random fraction of the
    /// step, trading wood-grain artifacts for fine noise (deterministic per pixel).
    pub jitter: bool,
    /// Reconstruction filter of grids (trilinear, or tricubic Catmull-Rom / B-spline).
    pub reconstruction: Reconstruction,
    /// Blinn-Phong gradient shading of the volume samples and isosurfaces (`None`: emission
    /// only).
    pub shading: Option<BlinnPhong>,
    /// Lighting of the isosurfaces when `shading` is `None` (`None`: unlit, their own colour).
    pub iso_lighting: Option<BlinnPhong>,
    /// Isosurfaces composited with the volume (Riemann integrator).
    pub isosurfaces: Isosurfaces,
    /// Maximum intensity projection instead of compositing: each pixel shows the TF colour of
    /// the largest value along its ray.
    pub mip: bool,
    /// World-space clipping planes: rays sample only where every plane keeps them
    /// (`normal . x + offset >= 0`).
    pub clip_planes: Vec<ClipPlane>,
    /// The sculpt mask: samples it hides are skipped (seed `004` sec. 4.4).
    pub mask: Option<Arc<SculptMask>>,
    /// Region labels drawn in their colours (seed `004` sec. 6.2; rays then go one by one).
    pub labels: Option<Arc<LabelVolume>>,
    /// An RGB grid's own colour in place of the TF's ([`crate::data_colour`]; rays then go
    /// one by one). Labels, where there are some, are drawn over it.
    pub data_colour: Option<Arc<DataColour>>,
    /// Cancellation and progress.
    pub control: Control,
}

impl RenderOptions {
    /// The options of `scene` drawn with `settings` (the scene's method resolved to grid ray
    /// casting): isosurfaces lit with the scene's lighting, the volume too when
    /// `shade_volume`; no early termination for the reference integrator.
    pub fn from_scene(scene: &Scene, settings: &GridRaycast, control: &Control) -> Self {
        let a = &scene.appearance;
        Self {
            width: scene.view.width,
            height: scene.view.height,
            camera: scene.view.camera,
            tf: a.effective_tf(),
            integrator: settings.integrator,
            early_termination: match settings.integrator {
                Integrator::Reference => None,
                _ => scene.early_termination,
            },
            empty_space_skipping: true,
            jitter: settings.jitter,
            reconstruction: settings.reconstruction,
            shading: a.shade_volume.then_some(a.lighting),
            iso_lighting: Some(a.lighting),
            isosurfaces: a.isosurfaces.clone(),
            mip: a.mip,
            clip_planes: scene.clip_planes.clone(),
            mask: scene.mask.clone(),
            labels: scene.labels.clone(),
            data_colour: None,
            control: control.clone(),
        }
    }

    /// Defaults: 512 x 512, Riemann with step 0.5 voxel, early termination at
    /// [`DEFAULT_EARLY_TERMINATION`] (the defaults of [`crate::scene`]).
    pub fn new(camera: Camera, tf: TransferFunction) -> Self {
        Self {
            width: 512,
            height: 512,
            camera,
            tf,
            integrator: Integrator::Riemann { step: 0.5 },
            early_termination: Some(DEFAULT_EARLY_TERMINATION),
            empty_space_skipping: true,
            jitter: false,
            reconstruction: Reconstruction::Trilinear,
            shading: None,
            iso_lighting: None,
            isosurfaces: Isosurfaces::default(),
            mip: false,
            clip_planes: Vec::new(),
            mask: None,
            labels: None,
            data_colour: None,
            control: Control::default(),
        }
    }

    pub(super) fn validate(&self) -> Result<(), RenderError> {
        crate::error::check_image_size(self.width, self.height)?;
        self.integrator.validate()?;
        if let Some(s) = &self.shading {
            s.validate()?;
        }
        if !self.isosurfaces.is_empty()
            && !self.mip
            && !matches!(self.integrator, Integrator::Riemann { .. })
        {
            return Err(Refusal::new(
                format!("the {} integrator", self.integrator.name()),
                "does not draw isosurfaces: the riemann integrator does",
                None,
            )
            .into());
        }
        self.tf.validate()?;
        self.camera.validate()?;
        Ok(())
    }
}

/// A rendered image with its figures and per-pixel estimated integration error.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image.
    pub image: Image,
    /// Figures of the render.
    pub stats: RenderStats,
    /// Estimated absolute error per pixel (largest channel; 0 where the integrator does not
    /// estimate it), row-major.
    pub error_map: Vec<f32>,
}

/// Placement of a field in the world: sample (i, j, k) at
/// `origin + direction * (spacing ∘ (i, j, k))` (LPS world, see [`volux_core::orientation`]).
///
/// Rays are traced in the grid's *local frame*: the world turned about `origin` by
/// `directionᵀ`, where the grid's box is axis-aligned (`[origin, origin + extent]`). The
/// direction is orthonormal, so distances (steps in world units, optical depths) are the same
/// in both frames.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// World position of sample (0, 0, 0).
    pub origin: DVec3,
    /// Distance between samples per axis.
    pub spacing: DVec3,
    /// Samples per axis.
    pub dims: [usize; 3],
    /// Unit world directions of the index axes (columns); identity for axis-aligned grids.
    pub direction: DMat3,
}

impl Placement {
    /// The placement of a grid.
    pub fn of(grid: &Grid) -> Self {
        Self {
            origin: grid.origin(),
            spacing: grid.spacing(),
            dims: grid.dims(),
            direction: grid.direction(),
        }
    }

    /// Whether the index axes are the world axes (no turn into the local frame).
    pub fn is_axis_aligned(&self) -> bool {
        self.direction == DMat3::IDENTITY
    }

    /// A world point in the local frame: `origin + directionᵀ (p - origin)` (the point itself
    /// when axis-aligned, bit for bit).
    pub fn point_to_local(&self, p: DVec3) -> DVec3 {
        if self.is_axis_aligned() {
            return p;
        }
        self.origin + self.direction.transpose() * (p - self.origin)
    }

    /// A world direction (ray direction, light direction) in the local frame:
    /// `directionᵀ v`.
    pub fn vector_to_local(&self, v: DVec3) -> DVec3 {
        if self.is_axis_aligned() {
            return v;
        }
        self.direction.transpose() * v
    }

    /// A local-frame vector (a gradient taken along the index axes) in the world: `direction v`.
    pub fn vector_to_world(&self, v: DVec3) -> DVec3 {
        if self.is_axis_aligned() {
            return v;
        }
        self.direction * v
    }
    pub(crate) fn extent(&self) -> DVec3 {
        DVec3::new(
            (self.dims[0].max(2) - 1) as f64,
            (self.dims[1].max(2) - 1) as f64,
            (self.dims[2].max(2) - 1) as f64,
        ) * self.spacing
    }
}
