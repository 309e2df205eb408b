//! What the ray casting shader reads besides the volume: the camera and grid in one uniform
//! block ([`Params`]), the classification tables and the clip planes.
use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use volux_core::camera::Projection;
use volux_render::raycast::{local_clip_planes, Placement, RenderOptions};

use crate::tables::Tables;

/// The shader's `Params` (`raycast.wgsl`), field for field.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct Params {
    eye: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    forward: [f32; 4],
    origin: [f32; 4],
    inv_spacing: [f32; 4],
    dims: [u32; 4],
    size: [u32; 4],
    lens: [f32; 4],
    mode: [u32; 4],
}

fn v4(v: DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

impl Params {
    /// The parameters of `opts` on the grid at `place`, with the step `h` (world units), the
    /// tables' domain, and `planes` clip planes.
    pub(crate) fn new(
        opts: &RenderOptions,
        place: &Placement,
        h: f64,
        tables: &Tables,
        planes: usize,
    ) -> Self {
        let cam = &opts.camera;
        let (r, u, f) = cam.basis();
        let (projection, lens) = match cam.projection {
            Projection::Perspective { fov_y_deg } => (0, (fov_y_deg.to_radians() * 0.5).tan()),
            Projection::Orthographic { height } => (1, height),
        };
        let (lo, scale) = tables.domain;
        let stop = opts.early_termination.unwrap_or(2.0);
        let [nx, ny, nz] = place.dims.map(|n| n as u32);
        Self {
            eye: v4(place.point_to_local(cam.eye), 0.0),
            right: v4(place.vector_to_local(r), 0.0),
            up: v4(place.vector_to_local(u), 0.0),
            forward: v4(place.vector_to_local(f), 0.0),
            origin: v4(place.origin, h as f32),
            inv_spacing: v4(place.spacing.recip(), stop),
            dims: [nx, ny, nz, planes as u32],
            size: [
                opts.width as u32,
                opts.height as u32,
                projection,
                tables.entries as u32,
            ],
            lens: [
                lens as f32,
                (opts.width as f64 / opts.height as f64) as f32,
                lo,
                scale,
            ],
            mode: [u32::from(opts.mip), 0, 0, 0],
        }
    }
}

/// The clip planes of `opts` in the grid's local frame ([`local_clip_planes`]),
/// `[nx, ny, nz, offset]` each, and one unused plane when there are none (a storage buffer is
/// never empty).
pub(crate) fn local_planes(opts: &RenderOptions, place: &Placement) -> Vec<[f32; 4]> {
    let mut out: Vec<[f32; 4]> = local_clip_planes(place, &opts.clip_planes)
        .iter()
        .map(|p| v4(p.normal, p.offset as f32))
        .collect();
    if out.is_empty() {
        out.push([0.0; 4]);
    }
    out
}
