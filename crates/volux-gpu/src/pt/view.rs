//! The uniform block of the PT shaders ([`ViewParams`], `View` in `classify.wgsl` and
//! `draw.wgsl`): the camera, the sizes and the classification table's domain.
use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use volux_core::camera::Projection;
use volux_core::Camera;
use volux_render::pt::project::NEAR_FRACTION;

/// The shaders' `View`, field for field.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct ViewParams {
    eye: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    forward: [f32; 4],
    size: [u32; 4],
    mode: [u32; 4],
    lens: [f32; 4],
    table: [f32; 4],
}

fn v4(v: DVec3) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, 0.0]
}

/// What the shaders know of the TF besides their buffers.
pub(crate) struct TfShape {
    /// Finite breakpoints.
    pub(crate) knots: u32,
    /// Entries of the classifier's table, its value at entry 0 and entries per value unit.
    pub(crate) entries: u32,
    pub(crate) lo: f32,
    pub(crate) scale: f32,
    /// ψ table nodes per axis.
    pub(crate) psi_nodes: u32,
    /// 1: ψ, 0: average.
    pub(crate) psi: bool,
}

impl ViewParams {
    /// The block for `camera`, a `width x height` image, a mesh of `tets` and `vertices`.
    pub(crate) fn new(
        camera: &Camera,
        (width, height): (usize, usize),
        (tets, vertices): (usize, usize),
        tf: &TfShape,
    ) -> Self {
        let (r, u, f) = camera.basis();
        let (perspective, scale) = match camera.projection {
            Projection::Perspective { fov_y_deg } => (1, (fov_y_deg.to_radians() * 0.5).tan()),
            Projection::Orthographic { height } => (0, height * 0.5),
        };
        let near = (camera.target - camera.eye).length() * NEAR_FRACTION;
        Self {
            eye: v4(camera.eye),
            right: v4(r),
            up: v4(u),
            forward: v4(f),
            size: [width as u32, height as u32, tets as u32, vertices as u32],
            mode: [perspective, tf.knots, tf.entries, u32::from(tf.psi)],
            lens: [
                scale as f32,
                (width as f64 / height as f64) as f32,
                near as f32,
                tf.lo,
            ],
            table: [
                tf.scale,
                tf.entries.saturating_sub(1) as f32,
                tf.psi_nodes as f32,
                0.0,
            ],
        }
    }
}
