//! What the ray casting shader reads besides the volume: the camera and grid in one uniform
//! block ([`Params`]) and the per-frame data (clip planes, isovalues).
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};
use volux_core::camera::Projection;
use volux_render::backend_kit::CutFaces;
use volux_render::backend_kit::{cut_layer, local_clip_planes, Placement, RenderOptions};
use volux_render::shading::Light;

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
    phong: [f32; 4],
    light: [f32; 4],
    gradient: [f32; 4],
    spacing: [f32; 4],
    cells: [u32; 4],
    extra: [f32; 4],
}

/// The shader's flags (`raycast.wgsl`).
pub(crate) mod flags {
    /// Volume samples are lit.
    pub(crate) const SHADE: u32 = 1;
    /// Gradients come from the gradient volume (else on the fly).
    pub(crate) const GRADIENT_VOLUME: u32 = 2;
    /// The sculpt mask hides samples.
    pub(crate) const MASK: u32 = 4;
    /// Empty macrocells are skipped.
    pub(crate) const SKIP: u32 = 8;
    /// Sample lattices are jittered per pixel.
    pub(crate) const JITTER: u32 = 16;
    /// Isosurfaces are lit.
    pub(crate) const ISO_LIT: u32 = 32;
    /// Isosurfaces are drawn.
    pub(crate) const ISOSURFACES: u32 = 64;
    /// The faces clip planes and the mask expose are lit with the cut's normal.
    pub(crate) const CUTS: u32 = 128;

    /// [`CUTS`] when `opts` lights volume samples (`flags` has [`SHADE`]) and something cuts
    /// the volume (a clip plane, or a sculpt mask: [`MASK`]), as
    /// [`CutFaces`](volux_render::shading::CutFaces) decides on the CPU.
    pub(crate) fn cuts(opts: &volux_render::raycast::RenderOptions, flags: u32) -> u32 {
        let cut = !opts.clip_planes.is_empty() || flags & MASK != 0;
        if flags & SHADE != 0 && cut {
            CUTS
        } else {
            0
        }
    }
}

/// What a frame draws besides the camera: the tables, the gradient volume's units per
/// count, the macrocells per axis, and the clip planes.
pub(crate) struct Drawn<'a> {
    pub(crate) tables: &'a Tables,
    pub(crate) to_world: [f32; 3],
    pub(crate) cells: [usize; 3],
    pub(crate) planes: usize,
}

fn v4(v: DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

impl Params {
    /// The parameters of `opts` on the grid at `place`, with the step `h` (world units) and
    /// what is `drawn`.
    pub(crate) fn new(opts: &RenderOptions, place: &Placement, h: f64, drawn: &Drawn) -> Self {
        let tables = drawn.tables;
        let cam = &opts.camera;
        let (r, u, f) = cam.basis();
        let (projection, lens) = match cam.projection {
            Projection::Perspective { fov_y_deg } => (0, (fov_y_deg.to_radians() * 0.5).tan()),
            Projection::Orthographic { height } => (1, height),
        };
        let (lo, scale) = tables.domain;
        let stop = opts.early_termination.unwrap_or(2.0);
        let [nx, ny, nz] = place.dims.map(|n| n as u32);
        let [cx, cy, cz] = drawn.cells.map(|n| n as u32);
        let (pre_lo, pre_scale, pre_n) = tables.preint_domain;
        let model = opts.shading.or(opts.iso_lighting).unwrap_or_default();
        let (light, headlight) = match model.light {
            Light::Headlight => (Vec3::ZERO, 1.0),
            Light::Direction(d) => (d.normalize_or_zero(), 0.0),
        };
        let [gx, gy, gz] = drawn.to_world;
        let isovalues = opts.isosurfaces.len() as u32;
        Self {
            eye: v4(place.point_to_local(cam.eye), 0.0),
            right: v4(place.vector_to_local(r), 0.0),
            up: v4(place.vector_to_local(u), 0.0),
            forward: v4(place.vector_to_local(f), 0.0),
            origin: v4(place.origin, h as f32),
            inv_spacing: v4(place.spacing.recip(), stop),
            dims: [nx, ny, nz, drawn.planes as u32],
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
            mode: [0, 0, 0, isovalues],
            phong: [
                model.ambient,
                model.diffuse,
                model.specular,
                model.shininess,
            ],
            light: [light.x, light.y, light.z, headlight],
            gradient: [gx, gy, gz, model.min_gradient],
            spacing: v4(place.spacing, pre_lo),
            cells: [cx, cy, cz, pre_n as u32],
            extra: [
                pre_scale,
                0.0,
                cut_layer(opts, place) as f32,
                CutFaces::strength(&model),
            ],
        }
    }
}

/// What the shader reads per frame: the clip planes of `opts` in the grid's local frame
/// ([`local_clip_planes`]), `[nx, ny, nz, offset]` each, then per isovalue `[value, 0, 0, 0]`
/// and its colour and opacity; one unused entry when there is nothing (a storage buffer is
/// never empty).
pub(crate) fn frame_data(opts: &RenderOptions, place: &Placement) -> Vec<[f32; 4]> {
    let mut out: Vec<[f32; 4]> = local_clip_planes(place, &opts.clip_planes)
        .iter()
        .map(|p| v4(p.normal, p.offset as f32))
        .collect();
    for iso in opts.isosurfaces.as_slice() {
        out.push([iso.value, 0.0, 0.0, 0.0]);
        out.push(iso.rgba);
    }
    if out.is_empty() {
        out.push([0.0; 4]);
    }
    out
}
