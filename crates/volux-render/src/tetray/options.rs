//! The options of a tetrahedral ray casting frame.
use volux_core::camera::Camera;
use volux_core::transfer::TransferFunction;
use volux_core::voi::ClipPlane;

use crate::error::{RenderError, Setting, SettingError};
use crate::integrate::segment::SegmentRule;
use crate::isosurface::Isosurfaces;
use crate::scene::{check_early_termination, Scene};
use crate::shading::BlinnPhong;
use crate::tiles::Control;

/// Options of a ray-cast frame.
#[derive(Clone, Debug)]
pub(crate) struct TetRayOptions {
    /// Image width (1 to 32768).
    pub width: usize,
    /// Image height (1 to 32768).
    pub height: usize,
    /// The camera.
    pub camera: Camera,
    /// The transfer function (resolved against the mesh's range by the renderer).
    pub tf: TransferFunction,
    /// Ray colour.
    pub color: SegmentRule,
    /// Isosurfaces (seed `002` §4.6), drawn where a segment's linear scalar crosses them, with
    /// the fragment colour of the projection renderer
    /// ([`FragmentShader::fragment`](crate::integrate::fragment::FragmentShader::fragment)).
    pub isosurfaces: Isosurfaces,
    /// Lighting of the isosurfaces (normals interpolated from the vertex gradients).
    pub shading: BlinnPhong,
    /// Maximum intensity projection: each pixel shows the TF colour, opaque, of the largest
    /// scalar along its ray (the largest segment end point: the field is linear per cell);
    /// the colour mode, isosurfaces and early termination are ignored.
    pub mip: bool,
    /// Stop a ray once its opacity reaches this (`None`: never).
    pub early_termination: Option<f32>,
    /// Empty-space skipping (per-segment colours only; default on): the walk leaves out the
    /// cells whose value range has zero extinction and no isovalue, jumping over runs of
    /// them through a hierarchy of the other cells (the `skip` module). The image is the same
    /// up to the choice among cells tied at an edge or vertex; `false` walks every cell.
    pub skip_empty: bool,
    /// World-space clipping planes (`normal . x + offset >= 0` kept): every segment is
    /// trimmed exactly to the part of its ray the planes keep (seed `004` ch. 4).
    pub clip_planes: Vec<ClipPlane>,
    /// Cancellation and progress.
    pub control: Control,
}

impl TetRayOptions {
    /// 512 x 512, exact colour, no isosurfaces, default lighting, early termination at
    /// [`DEFAULT_EARLY_TERMINATION`](crate::scene::DEFAULT_EARLY_TERMINATION) (the engine's default colour is ψ: [`crate::scene`]).
    #[cfg(test)]
    pub fn new(camera: Camera, tf: TransferFunction) -> Self {
        Self {
            width: 512,
            height: 512,
            camera,
            tf,
            color: SegmentRule::Exact,
            isosurfaces: Isosurfaces::default(),
            shading: BlinnPhong::default(),
            mip: false,
            early_termination: Some(crate::scene::DEFAULT_EARLY_TERMINATION),
            skip_empty: true,
            clip_planes: Vec::new(),
            control: Control::default(),
        }
    }

    pub(super) fn validate(&self) -> Result<(), RenderError> {
        crate::error::check_image_size(self.width, self.height)?;
        check_early_termination(self.early_termination)?;
        if let SegmentRule::AdaptiveSimpson(p) = &self.color {
            for (setting, v) in [
                (Setting::Tolerance, p.tol),
                (Setting::FirstStep, p.h0),
                (Setting::MinStep, p.hmin),
                (Setting::MaxStep, p.hmax),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(SettingError::new(setting, v, "positive and finite").into());
                }
            }
            if p.hmin > p.hmax {
                return Err(SettingError::new(
                    Setting::MinStep,
                    p.hmin,
                    format!("at most the largest step, {}", p.hmax),
                )
                .into());
            }
        }
        self.shading.validate()?;
        self.camera.validate()?;
        self.tf.validate()?;
        Ok(())
    }
}

impl TetRayOptions {
    /// The options of `scene` drawn with `rule`, whose adaptive steps are in units of
    /// `unit_length` world units (the mesh's [`Volume::unit_length`](crate::scene::Volume::unit_length)).
    pub fn from_scene(
        scene: &Scene,
        rule: SegmentRule,
        unit_length: f64,
        control: &Control,
    ) -> Self {
        let a = &scene.appearance;
        Self {
            width: scene.view.width,
            height: scene.view.height,
            camera: scene.view.camera,
            tf: a.effective_tf(),
            color: rule.scaled(unit_length),
            isosurfaces: a.isosurfaces.clone(),
            shading: a.lighting,
            mip: a.mip,
            early_termination: scene.early_termination,
            skip_empty: true,
            clip_planes: scene.clip_planes.clone(),
            control: control.clone(),
        }
    }
}
