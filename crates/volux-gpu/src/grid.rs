//! Grid ray casting on the GPU ([`GpuGridRenderer`]): the grid resident in a 3D texture, one
//! compute invocation per pixel (`raycast.wgsl`), the image read back.
use std::collections::HashMap;
use std::sync::{mpsc, Arc};
use std::time::Instant;

use volux_core::image::Image;
use volux_core::Grid;
use volux_render::backend_kit::{Placement, RenderOptions};
use volux_render::frame::{Frame, FrameStats, MethodStats, Rebuilt, RenderStats};
use volux_render::integrate::Integrator;
use volux_render::renderer::Renderer;
use volux_render::sampling::Reconstruction;
use volux_render::scene::{GridRaycast, Method, Scene, Volume};
use volux_render::tiles::Control;
use volux_render::{check_image_size, Refusal, Remedy, RenderError};
use wgpu::util::DeviceExt;

use crate::context::GpuContext;
use crate::error::GpuError;
use crate::params::{flags, frame_data, Drawn, Params};
use crate::resident::Resident;

const WORKGROUP: u32 = 8;

/// A frame's pixels and each pixel's sample count.
pub(crate) type Readback = (Vec<[f32; 4]>, Vec<u32>);

/// Grid ray casting on the GPU: Riemann sums with step-corrected opacity and
/// pre-integration, Blinn-Phong shading, isosurfaces, maximum intensity projection, clip
/// planes, the sculpt mask, empty-space skipping and early ray termination (see the crate
/// docs for what it refuses). The grid is uploaded once, as `f32` (undefined and infinite
/// values as NaN, drawn as empty medium as on the CPU).
pub struct GpuGridRenderer {
    res: Resident,
    /// The pipelines compiled so far, by the features they draw and their mode.
    pipelines: HashMap<u32, wgpu::ComputePipeline>,
}

/// The most isovalues the shader composites.
pub const MAX_ISOVALUES: usize = 8;

impl GpuGridRenderer {
    /// Uploads `grid` to the device of `ctx`; an error when it is over the device's 3D
    /// texture size.
    pub fn new(ctx: Arc<GpuContext>, grid: Arc<Grid>) -> Result<Self, GpuError> {
        let res = Resident::new(ctx, grid)?;
        Ok(Self {
            res,
            pipelines: HashMap::new(),
        })
    }

    /// Whether the shader draws `scene` (a grid ray casting scene): `Err` says what it does
    /// not draw yet, for a front end to fall back to the CPU or to say so.
    pub fn supports(scene: &Scene) -> Result<(), Refusal> {
        let settings = match scene.method {
            Method::GridRaycast(s) => s,
            Method::Auto => GridRaycast::default(),
            ref m => {
                return Err(Refusal::new(
                    "the GPU grid renderer",
                    format!("does not draw '{}'", m.name()),
                    None,
                ))
            }
        };
        let a = &scene.appearance;
        let drawn = matches!(
            settings.integrator,
            Integrator::Riemann { .. } | Integrator::Preintegrated { .. }
        );
        let refused = if !drawn {
            Some(format!("the {} integrator", settings.integrator.name()))
        } else if settings.reconstruction != Reconstruction::Trilinear {
            Some("tricubic reconstruction".into())
        } else if a.isosurfaces.len() > MAX_ISOVALUES {
            Some(format!(
                "more than {MAX_ISOVALUES} isosurfaces ({})",
                a.isosurfaces.len()
            ))
        } else if scene.labels.is_some() {
            Some("region labels".into())
        } else {
            None
        };
        match refused {
            Some(what) => Err(Refusal::new(
                "the GPU backend",
                format!("does not draw {what} yet"),
                Some(Remedy::CpuBackend),
            )),
            None => Ok(()),
        }
    }

    /// The adapter this renderer draws on.
    pub fn context(&self) -> &GpuContext {
        &self.res.ctx
    }

    /// Device memory held between frames, in bytes: the grid (4 per voxel), the gradient
    /// volume once shaded (8 per voxel), the tables and the mask's bits. A frame adds its
    /// image and sample counts twice (20 bytes per pixel on the device, as much to read
    /// back).
    pub fn device_bytes(&self) -> u64 {
        self.res.device_bytes()
    }

    fn render_options(
        &self,
        scene: &Scene,
        control: &Control,
    ) -> Result<RenderOptions, RenderError> {
        let volume = Volume::Grid(self.res.grid.clone());
        let settings = match scene.method.resolve(&volume)? {
            Method::GridRaycast(s) => s,
            m => {
                return Err(Refusal::new(
                    "the GPU grid renderer",
                    format!("cannot draw method '{}'", m.name()),
                    None,
                )
                .into())
            }
        };
        Self::supports(scene)?;
        let opts = RenderOptions::from_scene(scene, &settings, control);
        check_image_size(opts.width, opts.height)?;
        Ok(opts)
    }
}

impl Renderer for GpuGridRenderer {
    fn name(&self) -> &'static str {
        "raycast"
    }

    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError> {
        let started = Instant::now();
        let opts = self.render_options(scene, control)?;
        if control.is_cancelled() {
            return Err(RenderError::Cancelled);
        }
        let ctx = self.res.ctx.clone();
        let ((rgba, samples), classified) = ctx.checked(|| self.dispatch(&opts))??;
        let rebuilt = Rebuilt {
            data: false,
            classification: classified,
            view: true,
        };
        let image = Image::from_pixels(opts.width, opts.height, rgba)?;
        let seconds = started.elapsed().as_secs_f64();
        let rays = samples.iter().filter(|&&n| n > 0).count() as u64;
        Ok(Frame {
            image,
            error_map: None,
            stats: FrameStats {
                ms: seconds * 1e3,
                pixels: opts.width * opts.height,
                rebuilt,
                method: MethodStats::GridRaycast(RenderStats {
                    rays,
                    samples: samples.iter().map(|&n| u64::from(n)).sum(),
                    seconds,
                    rays_over_tolerance: 0,
                    rebuilt,
                }),
            },
        })
    }
}

impl GpuGridRenderer {
    /// Runs the shader for `opts`: the pixels and each pixel's sample count, and whether the
    /// classification tables were rebuilt.
    fn dispatch(&mut self, opts: &RenderOptions) -> Result<(Readback, bool), GpuError> {
        let (Integrator::Riemann { step } | Integrator::Preintegrated { step }) = opts.integrator
        else {
            return Err(GpuError::Failed(
                "only Riemann sums and pre-integration are drawn".into(),
            ));
        };
        let pixels = (opts.width * opts.height) as u64;
        let bytes = pixels * 16;
        self.check_buffer(bytes, opts)?;
        let place = Placement::of(&self.res.grid);
        let h = step * place.spacing.min_element();
        let stale = self.res.classify(opts, h)?;
        let mut flags = flags::SKIP;
        let to_world = self.res.prepare_gradients(opts, &mut flags)?;
        self.res.prepare_mask(opts, &mut flags)?;
        flags |= flags::cuts(opts, flags);
        if opts.jitter {
            flags |= flags::JITTER;
        }
        if !opts.isosurfaces.is_empty() {
            flags |= flags::ISOSURFACES;
            if opts.iso_lighting.is_some() || opts.shading.is_some() {
                flags |= flags::ISO_LIT;
            }
        }
        let mode = match opts.integrator {
            _ if opts.mip => 1,
            Integrator::Preintegrated { .. } => 2,
            _ => 0,
        };
        let pipeline = self.pipeline(flags, mode)?;
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
        let device = &self.res.ctx.device;
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let frame = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("clip planes and isovalues"),
            contents: bytemuck::cast_slice(&frame_data(opts, &place)),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let output = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let (rgba_buf, count_buf) = (output("rgba", bytes), output("samples", pixels * 4));
        let gradients = self.res.gradients_view(flags);
        let mask = self.res.mask_buffer(flags);
        let entries = [
            (0, uniform.as_entire_binding()),
            (1, wgpu::BindingResource::TextureView(&self.res.volume)),
            (2, tables.lut.as_entire_binding()),
            (3, tables.preint.as_entire_binding()),
            (4, frame.as_entire_binding()),
            (5, tables.cells.as_entire_binding()),
            (6, mask.as_entire_binding()),
            (7, wgpu::BindingResource::TextureView(gradients)),
            (8, rgba_buf.as_entire_binding()),
            (9, count_buf.as_entire_binding()),
        ]
        .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("raycast"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(
                (opts.width as u32).div_ceil(WORKGROUP),
                (opts.height as u32).div_ceil(WORKGROUP),
                1,
            );
        }
        let rgba_read = readback(device, &mut encoder, &rgba_buf, bytes);
        let count_read = readback(device, &mut encoder, &count_buf, pixels * 4);
        self.res.ctx.queue.submit([encoder.finish()]);
        let rgba: Vec<[f32; 4]> = bytemuck::cast_slice(&map(device, &rgba_read)?).to_vec();
        let counts: Vec<u32> = bytemuck::cast_slice(&map(device, &count_read)?).to_vec();
        Ok(((rgba, counts), stale))
    }

    /// The pipeline drawing the features `flags` in `mode` (compiled on first use).
    fn pipeline(&mut self, flags: u32, mode: u32) -> Result<wgpu::ComputePipeline, GpuError> {
        let key = flags | mode << 16;
        if let Some(p) = self.pipelines.get(&key) {
            return Ok(p.clone());
        }
        let ctx = &self.res.ctx;
        let p = ctx.checked(|| pipeline(&ctx.device, flags, mode))?;
        self.pipelines.insert(key, p.clone());
        Ok(p)
    }

    /// An error when the image's `bytes` are over the device's storage buffers.
    fn check_buffer(&self, bytes: u64, opts: &RenderOptions) -> Result<(), GpuError> {
        let limits = self.res.ctx.limits();
        let most = u64::from(limits.max_storage_buffer_binding_size).min(limits.max_buffer_size);
        if bytes > most {
            return Err(GpuError::OverLimit {
                what: format!("an image of {}x{}", opts.width, opts.height),
                limit: format!("storage buffers up to {most} bytes"),
            });
        }
        Ok(())
    }
}

/// A buffer the copy of `src` lands in, to be mapped on the host.
pub(crate) fn readback(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    src: &wgpu::Buffer,
    size: u64,
) -> wgpu::Buffer {
    let dst = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_buffer_to_buffer(src, 0, &dst, 0, size);
    dst
}

/// The bytes of `buf` once the device is done with it.
pub(crate) fn map(device: &wgpu::Device, buf: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let slice = buf.slice(..);
    let (tx, rx) = mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .map_err(|e| GpuError::Failed(e.to_string()))?;
    rx.recv()
        .map_err(|e| GpuError::Failed(e.to_string()))?
        .map_err(|e| GpuError::Failed(e.to_string()))?;
    let bytes = slice.get_mapped_range().to_vec();
    buf.unmap();
    Ok(bytes)
}

/// The ray casting pipeline (`raycast.wgsl`) of the features `flags` in `mode`.
fn pipeline(device: &wgpu::Device, flags: u32, mode: u32) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("raycast.wgsl"),
        source: wgpu::ShaderSource::Wgsl(
            concat!(
                include_str!("common.wgsl"),
                include_str!("field.wgsl"),
                include_str!("raycast.wgsl")
            )
            .into(),
        ),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("raycast"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: &[("FLAGS", f64::from(flags)), ("MODE", f64::from(mode))],
            ..Default::default()
        },
        cache: None,
    })
}
