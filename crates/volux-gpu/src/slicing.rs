//! Texture slicing on the GPU ([`GpuSlicingRenderer`], seed `004` ch. 3): the grid resident
//! in a 3D texture (§3.3, the initialisation stage), the slice polygons of the volume of
//! interest rebuilt per frame on the host ([`crate::slices`], the update stage), rasterized
//! and blended back to front by the render pipeline (`slicing.wgsl`, the drawing stage), the
//! image read back.
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use volux_core::image::Image;
use volux_core::Grid;
use volux_render::backend_kit::{local_clip_planes, Placement, RenderOptions};
use volux_render::frame::{Frame, FrameStats, MethodStats, Rebuilt, RenderStats};
use volux_render::integrate::Integrator;
use volux_render::renderer::Renderer;
use volux_render::scene::{GridRaycast, Method, Scene, SlicingSettings};
use volux_render::tiles::Control;
use volux_render::{Refusal, Remedy, RenderError};
use wgpu::util::DeviceExt;

use crate::context::GpuContext;
use crate::error::GpuError;
use crate::params::{flags, frame_data, Drawn, Params};
use crate::resident::Resident;
use crate::slices::{slice_triangles, Sweep};
use crate::target::{read_target, target};

/// Texture slicing of a grid (`--method slicing`): view-aligned slices `step` voxels apart
/// through the grid's box cut by the clip planes, composited back to front with
/// premultiplied "over" blending into an `Rgba32Float` target (`Rgba16Float` where the
/// adapter cannot blend `f32`: [`GpuSlicingRenderer::target_format`]). Each fragment samples
/// the grid trilinearly, classifies with the ray caster's slab table (opacity corrected for
/// the distance between slices along its ray), hides what the sculpt mask hides, and is lit
/// with Blinn-Phong from the gradient volume when the volume is shaded.
///
/// Back to front, nothing is terminated early: the scene's early termination does not
/// apply (the ray caster's pictures differ by at most `1 -` the threshold where it stops).
/// Maximum intensity projection, isosurfaces and region labels are refused by name
/// ([`GpuSlicingRenderer::supports`]).
pub struct GpuSlicingRenderer {
    res: Resident,
    /// The pipelines compiled so far, by the features they draw (`field.wgsl`'s flags).
    pipelines: HashMap<u32, wgpu::RenderPipeline>,
    format: wgpu::TextureFormat,
}

impl GpuSlicingRenderer {
    /// Uploads `grid` to the device of `ctx`; an error when it is over the device's 3D
    /// texture size.
    pub fn new(ctx: Arc<GpuContext>, grid: Arc<Grid>) -> Result<Self, GpuError> {
        let format = if ctx.blends_f32() {
            wgpu::TextureFormat::Rgba32Float
        } else {
            wgpu::TextureFormat::Rgba16Float
        };
        let res = Resident::new(ctx, grid)?;
        Ok(Self {
            res,
            pipelines: HashMap::new(),
            format,
        })
    }

    /// The format slices are blended in: `Rgba32Float`, or `Rgba16Float` where the adapter
    /// cannot blend `f32`.
    pub fn target_format(&self) -> wgpu::TextureFormat {
        self.format
    }

    /// The adapter this renderer draws on.
    pub fn context(&self) -> &GpuContext {
        &self.res.ctx
    }

    /// Whether texture slicing draws `scene`: `Err` says what it does not draw.
    pub fn supports(scene: &Scene) -> Result<(), Refusal> {
        let Method::Slicing(_) = scene.method else {
            return Err(Refusal::new(
                "texture slicing",
                format!("draws the slicing method, not '{}'", scene.method.name()),
                Some(Remedy::Method("slicing")),
            ));
        };
        let a = &scene.appearance;
        let refused = if a.mip {
            Some("maximum intensity projection")
        } else if !a.isosurfaces.is_empty() {
            Some("isosurfaces")
        } else if scene.labels.is_some() {
            Some("region labels")
        } else {
            None
        };
        match refused {
            Some(what) => Err(Refusal::new(
                "texture slicing",
                format!("does not draw {what}"),
                Some(Remedy::Method("raycast")),
            )),
            None => Ok(()),
        }
    }

    /// The ray caster's options for `scene`, with its Riemann step.
    fn render_options(scene: &Scene, control: &Control) -> Result<RenderOptions, RenderError> {
        scene.validate()?;
        Self::supports(scene)?;
        let Method::Slicing(SlicingSettings { step }) = scene.method else {
            return Err(RenderError::Internal("not a slicing scene".into()));
        };
        let integrator = Integrator::Riemann { step };
        integrator.validate()?;
        let settings = GridRaycast {
            integrator,
            ..GridRaycast::default()
        };
        Ok(RenderOptions::from_scene(scene, &settings, control))
    }
}

impl Renderer for GpuSlicingRenderer {
    fn name(&self) -> &'static str {
        "slicing"
    }

    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError> {
        let started = Instant::now();
        let opts = Self::render_options(scene, control)?;
        if control.is_cancelled() {
            return Err(RenderError::Cancelled);
        }
        let ctx = self.res.ctx.clone();
        let (rgba, classified) = ctx.checked(|| self.draw(&opts))??;
        let rebuilt = Rebuilt {
            data: false,
            classification: classified,
            view: true,
        };
        let rays = rgba.iter().filter(|p| p[3] > 0.0).count() as u64;
        let image = Image::from_pixels(opts.width, opts.height, rgba)?;
        let seconds = started.elapsed().as_secs_f64();
        Ok(Frame {
            image,
            error_map: None,
            stats: FrameStats {
                ms: seconds * 1e3,
                pixels: opts.width * opts.height,
                rebuilt,
                // Fragments are not counted: `samples` stays 0.
                method: MethodStats::GridRaycast(RenderStats {
                    rays,
                    samples: 0,
                    seconds,
                    rays_over_tolerance: 0,
                    rebuilt,
                }),
            },
        })
    }
}

impl GpuSlicingRenderer {
    /// Draws the slices of `opts`: the pixels, and whether the tables were rebuilt.
    fn draw(&mut self, opts: &RenderOptions) -> Result<(Vec<[f32; 4]>, bool), GpuError> {
        let Integrator::Riemann { step } = opts.integrator else {
            return Err(GpuError::Failed("slicing takes a Riemann step".into()));
        };
        let place = Placement::of(&self.res.grid);
        let h = step * place.spacing.min_element();
        let stale = self.res.classify(opts, h)?;
        let mut flags = 0;
        let to_world = self.res.prepare_gradients(opts, &mut flags)?;
        self.res.prepare_mask(opts, &mut flags)?;
        flags |= flags::cuts(opts, flags);
        let pipeline = self.pipeline(flags)?;
        let Some(tables) = &self.res.tables else {
            return Err(GpuError::Failed("no classification tables".into()));
        };
        let drawn = Drawn {
            tables,
            to_world,
            cells: self.res.macrocells.counts(),
            planes: opts.clip_planes.len(),
        };
        let params = Params::new(opts, &place, h, &drawn);
        let (_, _, forward) = opts.camera.basis();
        let sweep = Sweep {
            eye: place.point_to_local(opts.camera.eye),
            forward: place.vector_to_local(forward).normalize(),
            h,
        };
        let planes = local_clip_planes(&place, &opts.clip_planes);
        let vertices = slice_triangles(&place, &planes, &sweep)?;
        let bind = self.bind_group(
            &pipeline,
            &params,
            &frame_data(opts, &place),
            (flags, &tables.lut),
        );
        let rgba = self.rasterize(opts, (&pipeline, &bind), &vertices)?;
        Ok((rgba, stale))
    }

    /// The bindings of `slicing.wgsl` for a frame.
    fn bind_group(
        &self,
        pipeline: &wgpu::RenderPipeline,
        params: &Params,
        frame: &[[f32; 4]],
        (flags, lut): (u32, &wgpu::Buffer),
    ) -> wgpu::BindGroup {
        let device = &self.res.ctx.device;
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let uniform = init(
            "params",
            bytemuck::bytes_of(params),
            wgpu::BufferUsages::UNIFORM,
        );
        let planes = init(
            "clip planes",
            bytemuck::cast_slice(frame),
            wgpu::BufferUsages::STORAGE,
        );
        let entries = [
            (0, uniform.as_entire_binding()),
            (1, wgpu::BindingResource::TextureView(&self.res.volume)),
            (2, lut.as_entire_binding()),
            (3, planes.as_entire_binding()),
            (4, self.res.mask_buffer(flags).as_entire_binding()),
            (
                5,
                wgpu::BindingResource::TextureView(self.res.gradients_view(flags)),
            ),
        ]
        .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("slicing"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        })
    }

    /// Rasterizes the triangles `vertices` (back to front) into a cleared target and reads
    /// it back.
    fn rasterize(
        &self,
        opts: &RenderOptions,
        (pipeline, bind): (&wgpu::RenderPipeline, &wgpu::BindGroup),
        vertices: &[[f32; 3]],
    ) -> Result<Vec<[f32; 4]>, GpuError> {
        let ctx = &self.res.ctx;
        let (w, h) = (opts.width as u32, opts.height as u32);
        let texture = target(ctx, w, h, self.format)?;
        let view = texture.create_view(&Default::default());
        let bytes = std::mem::size_of_val(vertices) as u64;
        if bytes > ctx.limits().max_buffer_size {
            return Err(GpuError::OverLimit {
                what: format!("{} slice vertices", vertices.len()),
                limit: format!("buffers up to {} bytes", ctx.limits().max_buffer_size),
            });
        }
        let buffer = (!vertices.is_empty()).then(|| {
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("slices"),
                    contents: bytemuck::cast_slice(vertices),
                    usage: wgpu::BufferUsages::VERTEX,
                })
        });
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("slicing"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            if let Some(buffer) = &buffer {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind, &[]);
                pass.set_vertex_buffer(0, buffer.slice(..));
                pass.draw(0..vertices.len() as u32, 0..1);
            }
        }
        read_target(ctx, encoder, &texture, self.format)
    }
}

impl GpuSlicingRenderer {
    /// The pipeline drawing the features `flags` (compiled on first use).
    fn pipeline(&mut self, flags: u32) -> Result<wgpu::RenderPipeline, GpuError> {
        if let Some(p) = self.pipelines.get(&flags) {
            return Ok(p.clone());
        }
        let ctx = &self.res.ctx;
        let p = ctx.checked(|| pipeline(&ctx.device, self.format, flags))?;
        self.pipelines.insert(flags, p.clone());
        Ok(p)
    }
}

/// The slicing pipeline (`slicing.wgsl` after `common.wgsl` and `field.wgsl`) of the
/// features `flags`: triangles unculled, blended "over" with premultiplied colour (seed
/// `004` eq. 3.2).
fn pipeline(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    flags: u32,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("slicing.wgsl"),
        source: wgpu::ShaderSource::Wgsl(
            concat!(
                include_str!("common.wgsl"),
                include_str!("field.wgsl"),
                include_str!("slicing.wgsl")
            )
            .into(),
        ),
    });
    let constants = [("FLAGS", f64::from(flags))];
    let options = || wgpu::PipelineCompilationOptions {
        constants: &constants,
        ..Default::default()
    };
    let over = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
        operation: wgpu::BlendOperation::Add,
    };
    let attributes = wgpu::vertex_attr_array![0 => Float32x3];
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("slicing"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: options(),
            buffers: &[wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attributes,
            }],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: options(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: Some(wgpu::BlendState {
                    color: over,
                    alpha: over,
                }),
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        multiview: None,
        cache: None,
    })
}
