//! The uniform block of the PT shaders ([`ViewParams`], `View` in `classify.wgsl` and
//! `draw.wgsl`): the camera, the sizes, the classification table's domain, the isosurfaces
//! with their lighting and the clipping planes.
use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use volux_core::camera::Projection;
use volux_core::voi::ClipPlane;
use volux_core::Camera;
use volux_render::backend_kit::NEAR_FRACTION;
use volux_render::isosurface::Isovalue;
use volux_render::shading::{BlinnPhong, Light};

/// The most isovalues the shaders draw (the uniform block holds them).
pub(crate) const MAX_ISOSURFACES: usize = 16;
/// The most clipping planes the shaders trim to.
pub(crate) const MAX_PLANES: usize = 8;

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
    /// Isovalues, planes, headlight (1) or directional light (0), unused.
    extra: [u32; 4],
    /// Ambient, diffuse, specular, shininess.
    shade: [f32; 4],
    /// Unit direction towards the light (world), minimum gradient.
    light: [f32; 4],
    /// Per isovalue `(value, 0, 0, 0)` and its RGBA.
    isos: [[f32; 4]; 2 * MAX_ISOSURFACES],
    /// Per plane `(normal, distance of the eye)` and `(normal . right, . up, . forward, 0)`.
    planes: [[f32; 4]; 2 * MAX_PLANES],
}

fn v4(v: DVec3) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, 0.0]
}

/// What the shaders know of the TF besides their buffers.
#[derive(Clone, Copy)]
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

/// The isosurfaces (sorted by value, at most [`MAX_ISOSURFACES`]), their lighting and the
/// clipping planes (at most [`MAX_PLANES`]) of a frame.
pub(crate) struct Extras<'a> {
    pub(crate) isosurfaces: &'a [Isovalue],
    pub(crate) lighting: BlinnPhong,
    pub(crate) planes: &'a [ClipPlane],
}

impl ViewParams {
    /// The block for `camera`, a `width x height` image, a mesh of `tets` and `vertices`.
    pub(crate) fn new(
        camera: &Camera,
        (width, height): (usize, usize),
        (tets, vertices): (usize, usize),
        tf: &TfShape,
        extras: &Extras<'_>,
    ) -> Self {
        let (r, u, f) = camera.basis();
        let (perspective, scale) = match camera.projection {
            Projection::Perspective { fov_y_deg } => (1, (fov_y_deg.to_radians() * 0.5).tan()),
            Projection::Orthographic { height } => (0, height * 0.5),
        };
        let near = (camera.target - camera.eye).length() * NEAR_FRACTION;
        let lit = extras.lighting;
        let (light, headlight) = match lit.light {
            Light::Headlight => ([0.0; 3], 1),
            Light::Direction(d) => (d.normalize_or_zero().to_array(), 0),
        };
        let isos = &extras.isosurfaces[..extras.isosurfaces.len().min(MAX_ISOSURFACES)];
        let planes = &extras.planes[..extras.planes.len().min(MAX_PLANES)];
        let mut iso_rows = [[0.0f32; 4]; 2 * MAX_ISOSURFACES];
        for (k, iso) in isos.iter().enumerate() {
            iso_rows[2 * k] = [iso.value, 0.0, 0.0, 0.0];
            iso_rows[2 * k + 1] = iso.rgba;
        }
        // Distances relative to the eye, in f64: no cancellation in the shaders.
        let mut plane_rows = [[0.0f32; 4]; 2 * MAX_PLANES];
        for (k, p) in planes.iter().enumerate() {
            let n = p.normal;
            let mut a = v4(n);
            a[3] = p.distance(camera.eye) as f32;
            plane_rows[2 * k] = a;
            plane_rows[2 * k + 1] = [n.dot(r) as f32, n.dot(u) as f32, n.dot(f) as f32, 0.0];
        }
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
            extra: [isos.len() as u32, planes.len() as u32, headlight, 0],
            shade: [lit.ambient, lit.diffuse, lit.specular, lit.shininess],
            light: [light[0], light[1], light[2], lit.min_gradient],
            isos: iso_rows,
            planes: plane_rows,
        }
    }
}
