//! What every rank of a distributed render needs to render its region, planned once (on
//! rank 0, from the scene) and sent to the others as JSON ([`RegionJob`]): the level, the
//! data range and the render options that matter for a bricked level.
use serde::{Deserialize, Serialize};
use volux_core::camera::Camera;
use volux_core::voi::ClipPlane;
use volux_core::TransferFunction;

use super::error::DistributedError;
use super::region::{is_pipelined, region_options};
use crate::integrate::integrator::Integrator;
use crate::isosurface::Isosurfaces;
use crate::raycast::RenderOptions;
use crate::sampling::Reconstruction;
use crate::scene::Scene;
use crate::shading::blinn_phong::BlinnPhong;

/// One distributed frame: the pyramid level rendered, the data range the transfer function
/// is placed on, and the options of the single-process render of the same scene (early
/// termination off, except for adaptive Simpson, whose state pipeline keeps it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionJob {
    /// The pyramid level.
    pub level: usize,
    /// The full level's data range (as the single-process render classifies over).
    pub range: [f64; 2],
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// The camera.
    pub camera: Camera,
    /// The transfer function (with the scene's opacity scale applied).
    pub tf: TransferFunction,
    /// The integrator.
    pub integrator: Integrator,
    /// Volume shading.
    pub shading: Option<BlinnPhong>,
    /// World clipping planes.
    pub clip_planes: Vec<ClipPlane>,
    /// Maximum intensity projection instead of compositing.
    #[serde(default)]
    pub mip: bool,
    /// Isosurfaces composited with the volume.
    #[serde(default)]
    pub isosurfaces: Isosurfaces,
    /// Lighting of the isosurfaces when `shading` is `None`.
    #[serde(default)]
    pub iso_lighting: Option<BlinnPhong>,
    /// The early-termination opacity (adaptive Simpson only: the other integrators'
    /// regions cannot know what lies in front of them).
    #[serde(default)]
    pub early_termination: Option<f32>,
}

impl RegionJob {
    /// The job of `scene` at `level` over `range`, as the single-process grid ray caster
    /// would render it; an error for what a split render cannot do exactly
    /// ([`region_options`]).
    pub fn from_scene(
        scene: &Scene,
        level: usize,
        range: [f64; 2],
    ) -> Result<Self, DistributedError> {
        let settings = crate::raycast::grid_settings(scene)?;
        let o = RenderOptions::from_scene(scene, &settings, &Default::default());
        if o.reconstruction != Reconstruction::Trilinear {
            return Err(DistributedError::Unsupported("cubic reconstruction".into()));
        }
        if o.integrator == Integrator::Reference {
            return Err(DistributedError::Unsupported(
                "the reference integrator (it integrates each ray whole); use adaptive-simpson"
                    .into(),
            ));
        }
        let o = region_options(&o)?;
        Ok(Self {
            level,
            range,
            width: o.width,
            height: o.height,
            camera: o.camera,
            tf: o.tf,
            integrator: o.integrator,
            shading: o.shading,
            clip_planes: o.clip_planes,
            mip: o.mip,
            isosurfaces: o.isosurfaces,
            iso_lighting: o.iso_lighting,
            early_termination: o.early_termination,
        })
    }

    /// The render options (early termination off but for adaptive Simpson).
    pub fn options(&self) -> RenderOptions {
        let mut o = RenderOptions::new(self.camera, self.tf.clone());
        (o.width, o.height) = (self.width, self.height);
        o.integrator = self.integrator;
        o.shading = self.shading;
        o.clip_planes = self.clip_planes.clone();
        o.mip = self.mip;
        o.isosurfaces = self.isosurfaces.clone();
        o.iso_lighting = self.iso_lighting;
        o.early_termination = self.early_termination.filter(|_| is_pipelined(&o));
        o
    }
}
