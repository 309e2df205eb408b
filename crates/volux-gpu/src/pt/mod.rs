//! Projected Tetrahedra on the GPU ([`GpuPtRenderer`]): the seeds' two-pass pipeline (seed
//! `000` chapter 4, figure 4.1; seed `002` section 4) on one device, drawing the picture of
//! the CPU's `volux_render::pt::PtRenderer`:
//!
//! 1. **first pass** (`classify.wgsl`, `000` §4.1, `002` §4.1): every mesh vertex projected
//!    and snapped to the CPU's 1/256 pixel grid, then per tetrahedron the discard of cells
//!    whose value range has zero extinction and that no isovalue crosses (`002` §4.5, the
//!    CPU's kept set), the culling of cells with all four vertices outside one clipping
//!    plane (`004` ch. 4), the four orientation tests (exact, in emulated 64-bit integers on
//!    the grid), the 81-entry ternary truth table (the CPU's `TERNARY_TABLE`, uploaded), the
//!    thick vertex with its front and back depth, scalar and (with isosurfaces) gradient
//!    (perspective-correct as `pt::project`) and the centroid's depth key;
//! 2. **visibility order** (`sort.wgsl`, `000` §4.2): a stable radix sort of the keys,
//!    the CPU's centroid order (distance from the eye under perspective); with
//!    `SortMode::Exact` the CPU's MPVO order instead (`volux_render::pt::sort::mpvo_order`
//!    of every cell, the face adjacency built once), uploaded as the draw order. The CPU
//!    draws non-convex meshes or cyclic views per pixel in that mode; the GPU draws the
//!    MPVO order (cycles broken) there too;
//! 3. **second pass** (`draw.wgsl`, `000` §4.3, `002` §4.3-4.4): the fans (1 to 4
//!    triangles around the thick vertex) rasterized by the hardware in the sorted order,
//!    the vertex shader pulling the classified cells, `(s_f, s_b)`, depths and gradients
//!    interpolated perspective-correctly front and back apart; with clipping planes each
//!    fragment's segment is trimmed to its pixel's depth window inside the planes (computed
//!    in the fragment shader from the pixel's ray and the planes' distances to the eye; the
//!    scalars and gradients interpolated at the trimmed ends, a fragment outside discarded,
//!    as `pt::clip`); the fragment is coloured with the average rule or the ψ table (cut at
//!    the TF's breakpoints, as the CPU) and, with isosurfaces (`002` §4.6), cut at the
//!    isovalues crossed between `s_f` and `s_b` (located on the linear segment, at most 8,
//!    as `integrate::fragment`), the volume pieces and the surfaces (lit two-sided
//!    Blinn-Phong with the scene's `appearance.lighting` and the interpolated gradient)
//!    composited in depth order inside the fragment; the fragments are composited front to
//!    back with premultiplied "under" (blend factors `1 - dst.a` and 1, the CPU's operator
//!    and order) into an `rgba32float` target (`rgba16float` where the adapter cannot blend
//!    `f32`).
//!
//! The isovalues (at most [`MAX_ISOSURFACES`](view::MAX_ISOSURFACES)) and the planes (at
//! most [`MAX_PLANES`](view::MAX_PLANES)) ride in the uniform block; the vertex gradients
//! ([`TetMesh::vertex_gradients`], as the CPU) are uploaded with the first isosurface.
//!
//! **Between frames** (`frame.rs`, the update step of `000` §4.2 and `002` §4.5): the mesh
//! (positions with the scalars, cells, gradients) and the ψ table stay on the device; the
//! TF's buffers are rebuilt when the TF changes, the kept set (the `keep` pass: one flag per
//! cell and their count, `PtStats::tets_kept`) when the TF's zero set or the isovalues
//! change; projection, classification and sort run when the camera, the image size, the
//! planes, the kept set or the need for gradients change. The cells hold no TF-dependent
//! data (the average rule's linear piece is found in the vertex shader), so a TF change
//! with the same zero set only redraws the fans. The frame's `Rebuilt` says which ran:
//! `data` (ψ table, gradients), `classification` (TF buffers or kept set), `view` (first
//! pass and sort).
//!
//! Not drawn yet, and refused by name ([`GpuPtRenderer::supports`]): the exact and adaptive
//! Simpson colours, the sculpt mask, region labels, and
//! more isovalues or planes than the uniform block holds. Early termination is not done:
//! the "under" blend still shades and composites every fragment (a fragment shader cannot
//! read the target's opacity; stopping a pixel would take, e.g., drawing the order in
//! chunks and, between chunks, marking opaque pixels in a stencil or depth buffer that
//! the next chunks test, or a compute rasterizer), so where the CPU stops a pixel at
//! opacity `e` the GPU pixel differs by at most `1 - e`. `PtStats` reports `tets_kept`; the drawn,
//! degenerate, clipped and culled counts and the fragment count are not counted on the
//! device (zero).
mod draw;
mod frame;
mod layout;
mod sort;
mod state;
mod tables;
mod view;

use std::sync::Arc;
use std::time::Instant;

use volux_core::{Image, TetMesh};
use volux_render::backend_kit::PsiTable;
use volux_render::frame::{Frame, FrameStats, MethodStats, PtStats, Rebuilt};
use volux_render::integrate::SegmentRule;
use volux_render::renderer::Renderer;
use volux_render::scene::{Method, PtSettings, Scene, SortMode};
use volux_render::tiles::Control;
use volux_render::{check_image_size, Refusal, Remedy, RenderError};
use wgpu::util::DeviceExt;

use crate::context::GpuContext;
use crate::error::GpuError;
use layout::{CELL_BYTES, VERTICES_PER_CELL};
use sort::RadixSort;
use state::Caches;

/// The mesh on the device.
struct MeshBuffers {
    /// `(x, y, z, scalar)` per vertex.
    positions: wgpu::Buffer,
    tets: wgpu::Buffer,
    /// The vertex gradients ([`TetMesh::vertex_gradients`]), uploaded with the first
    /// isosurface; one zero element before.
    gradients: Option<wgpu::Buffer>,
    no_gradients: wgpu::Buffer,
}

/// Projected Tetrahedra on the GPU (see the module docs): the mesh uploaded once, the ψ
/// table when first needed.
pub struct GpuPtRenderer {
    ctx: Arc<GpuContext>,
    mesh: Arc<TetMesh>,
    data: MeshBuffers,
    table: wgpu::Buffer,
    classify: [wgpu::ComputePipeline; 3],
    sort: RadixSort,
    draw: wgpu::RenderPipeline,
    format: wgpu::TextureFormat,
    psi: Option<wgpu::TextureView>,
    tiny_psi: wgpu::TextureView,
    caches: Caches,
}

impl GpuPtRenderer {
    /// Uploads `mesh` to the device of `ctx`; an error naming the limit when its buffers are
    /// over the device's.
    pub fn new(ctx: Arc<GpuContext>, mesh: Arc<TetMesh>) -> Result<Self, GpuError> {
        check_limits(&ctx.limits(), &mesh)?;
        let device = &ctx.device;
        let built = ctx.checked(|| {
            let format = draw::target_format(ctx.blend_f32);
            let tiny = PsiTable::with_size(2);
            (
                upload(device, &mesh),
                storage(device, "ternary table", &tables::packed_table()),
                draw::classify_pipelines(device),
                RadixSort::new(device),
                draw::draw_pipeline(device, format),
                format,
                tables::psi_texture(device, &ctx.queue, &tiny),
            )
        })?;
        let (data, table, classify, sort, draw, format, tiny_psi) = built;
        Ok(Self {
            ctx,
            mesh,
            data,
            table,
            classify,
            sort,
            draw,
            format,
            psi: None,
            tiny_psi,
            caches: Caches::default(),
        })
    }

    /// The target format: `Rgba32Float` where the adapter blends `f32`, else `Rgba16Float`.
    pub fn target_format(&self) -> wgpu::TextureFormat {
        self.format
    }

    /// Whether the shaders draw `scene` (a Projected Tetrahedra scene): `Err` names what they
    /// do not draw, for a front end to fall back to the CPU or to say so.
    pub fn supports(scene: &Scene) -> Result<(), Refusal> {
        let settings = match scene.method {
            Method::ProjectedTetrahedra(s) => s,
            Method::Auto => PtSettings::default(),
            ref m => {
                return Err(Refusal::new(
                    "the GPU Projected Tetrahedra renderer",
                    format!("does not draw '{}'", m.name()),
                    None,
                ))
            }
        };
        let refused = match settings.color {
            SegmentRule::Average | SegmentRule::Psi => None,
            ref c => Some(format!("the {} fragment colour", c.name())),
        }
        .or_else(|| {
            let n = scene.appearance.isosurfaces.as_slice().len();
            (n > view::MAX_ISOSURFACES)
                .then(|| format!("{n} isosurfaces (at most {})", view::MAX_ISOSURFACES))
        })
        .or_else(|| {
            let n = scene.clip_planes.len();
            (n > view::MAX_PLANES)
                .then(|| format!("{n} clip planes (at most {})", view::MAX_PLANES))
        })
        .or_else(|| scene.mask.is_some().then(|| "a sculpt mask".into()))
        .or_else(|| scene.labels.is_some().then(|| "region labels".into()));
        match refused {
            Some(what) => Err(Refusal::new(
                "the GPU backend",
                format!("does not draw {what} with Projected Tetrahedra yet"),
                Some(Remedy::CpuBackend),
            )),
            None => Ok(()),
        }
    }

    /// The adapter this renderer draws on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }
}

/// Checks the mesh's buffers against the device's limits.
fn check_limits(limits: &wgpu::Limits, mesh: &TetMesh) -> Result<(), GpuError> {
    let most = u64::from(limits.max_storage_buffer_binding_size).min(limits.max_buffer_size);
    let tets = mesh.tets().len() as u64;
    let largest = (tets * CELL_BYTES).max(16 * mesh.positions().len() as u64);
    if largest > most {
        return Err(GpuError::OverLimit {
            what: format!(
                "a mesh of {tets} tetrahedra and {} vertices ({largest} bytes in one buffer)",
                mesh.positions().len()
            ),
            limit: format!("storage buffers up to {most} bytes (max_storage_buffer_binding_size)"),
        });
    }
    if tets * VERTICES_PER_CELL > u64::from(u32::MAX) {
        return Err(GpuError::OverLimit {
            what: format!("a mesh of {tets} tetrahedra"),
            limit: format!("{} vertices a draw", u32::MAX),
        });
    }
    Ok(())
}

fn storage<T: bytemuck::Pod>(device: &wgpu::Device, label: &str, data: &[T]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(data),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// Positions (as `vec4`), scalars and cells; a dummy element where the mesh has none.
fn upload(device: &wgpu::Device, mesh: &TetMesh) -> MeshBuffers {
    let mut positions: Vec<[f32; 4]> = mesh
        .positions()
        .iter()
        .zip(mesh.scalars())
        .map(|(p, &s)| [p.x, p.y, p.z, s])
        .collect();
    positions.resize(positions.len().max(1), [0.0; 4]);
    let mut tets: Vec<[u32; 4]> = mesh.tets().to_vec();
    tets.resize(tets.len().max(1), [0; 4]);
    MeshBuffers {
        positions: storage(device, "positions", &positions),
        tets: storage(device, "tets", &tets),
        gradients: None,
        no_gradients: storage(device, "no gradients", &[[0.0f32; 4]]),
    }
}

/// The vertex gradients of `mesh` as `vec4`.
fn upload_gradients(device: &wgpu::Device, mesh: &TetMesh) -> wgpu::Buffer {
    let mut g: Vec<[f32; 4]> = mesh
        .vertex_gradients()
        .iter()
        .map(|g| [g.x, g.y, g.z, 0.0])
        .collect();
    g.resize(g.len().max(1), [0.0; 4]);
    storage(device, "vertex gradients", &g)
}

impl Renderer for GpuPtRenderer {
    fn name(&self) -> &'static str {
        "pt"
    }

    fn render(&mut self, scene: &Scene, _control: &Control) -> Result<Frame, RenderError> {
        let started = Instant::now();
        let settings = match scene.method {
            Method::ProjectedTetrahedra(s) => s,
            Method::Auto => PtSettings::default(),
            m => {
                return Err(Refusal::new(
                    "the GPU pt renderer",
                    format!("cannot draw method '{}'", m.name()),
                    None,
                )
                .into())
            }
        };
        scene.validate()?;
        Self::supports(scene)?;
        let (w, h) = (scene.view.width, scene.view.height);
        check_image_size(w, h)?;
        let psi = settings.color == SegmentRule::Psi;
        let mut data = false;
        if psi && self.psi.is_none() {
            let table = PsiTable::new();
            let view = self
                .ctx
                .checked(|| tables::psi_texture(&self.ctx.device, &self.ctx.queue, &table))?;
            self.psi = Some(view);
            data = true;
        }
        if !scene.appearance.isosurfaces.is_empty() && self.data.gradients.is_none() {
            let (device, mesh) = (&self.ctx.device, &self.mesh);
            let buffer = self.ctx.checked(|| upload_gradients(device, mesh))?;
            self.data.gradients = Some(buffer);
            data = true;
        }
        let tf = scene.appearance.effective_tf();
        let ctx = self.ctx.clone();
        let exact = settings.sort == SortMode::Exact;
        let report = match ctx.checked(|| self.frame(scene, &tf, psi, exact)) {
            Ok(Ok(r)) => r,
            Ok(Err(e)) | Err(e) => {
                // What the caches hold may be half built: start afresh next frame.
                self.caches = Caches::default();
                return Err(e.into());
            }
        };
        let rebuilt = Rebuilt {
            data,
            ..report.rebuilt
        };
        let image = Image::from_pixels(w, h, report.rgba)?;
        let seconds = started.elapsed().as_secs_f64();
        let stats = PtStats {
            tets: self.mesh.tets().len(),
            tets_kept: report.kept,
            seconds,
            rebuilt,
            ..Default::default()
        };
        Ok(Frame {
            image,
            error_map: None,
            stats: FrameStats {
                ms: seconds * 1e3,
                pixels: w * h,
                rebuilt,
                method: MethodStats::ProjectedTetrahedra(stats),
            },
        })
    }
}
