//! Grid ray casting on the GPU ([`GpuGridRenderer`]): the grid resident in a 3D texture, one
//! compute invocation per pixel (`raycast.wgsl`), the image read back.
use std::collections::HashMap;
use std::sync::{mpsc, Arc};
use std::time::Instant;

use volux_core::image::Image;
use volux_core::Grid;
use volux_render::frame::{Frame, FrameStats, MethodStats, Rebuilt, RenderStats};
use volux_render::integrate::Integrator;
use volux_render::macrocell::MacrocellGrid;
use volux_render::raycast::{Placement, RenderOptions};
use volux_render::renderer::Renderer;
use volux_render::sampling::{Reconstruction, Trilinear};
use volux_render::scene::{GridRaycast, Method, Scene, Volume};
use volux_render::shading::GradientVolume;
use volux_render::tiles::Control;
use volux_render::{check_image_size, RenderError};
use wgpu::util::DeviceExt;

use crate::context::GpuContext;
use crate::error::GpuError;
use crate::params::{flags, frame_data, Drawn, Params};
use crate::resources::{no_gradients, upload_gradients, words_buffer, MaskBits};
use crate::tables::{TableKey, Tables};

const WORKGROUP: u32 = 8;

/// A frame's pixels and each pixel's sample count.
pub(crate) type Readback = (Vec<[f32; 4]>, Vec<u32>);

/// Grid ray casting on the GPU: Riemann sums with step-corrected opacity and
/// pre-integration, Blinn-Phong shading, isosurfaces, maximum intensity projection, clip
/// planes, the sculpt mask, empty-space skipping and early ray termination (see the crate
/// docs for what it refuses). The grid is uploaded once, as `f32` (undefined and infinite
/// values as NaN, drawn as empty medium as on the CPU).
pub struct GpuGridRenderer {
    ctx: Arc<GpuContext>,
    grid: Arc<Grid>,
    volume: wgpu::TextureView,
    /// The pipelines compiled so far, by the features they draw and their mode.
    pipelines: HashMap<u32, wgpu::ComputePipeline>,
    /// The min/max of each macrocell (from the data, built once).
    macrocells: MacrocellGrid,
    /// The last frame's classification, kept while the TF and the step stay.
    tables: Option<Tables>,
    /// The gradient volume and its world units per count, uploaded on the first shaded
    /// frame (`None` inside when it is over the memory budget: gradients on the fly).
    gradients: Option<Option<(wgpu::TextureView, [f32; 3])>>,
    /// Bound where a frame uses no gradient volume or no mask.
    no_gradients: wgpu::TextureView,
    no_mask: wgpu::Buffer,
    /// The sculpt mask's bits, for the mask (by address) of one generation.
    mask: Option<(usize, MaskBits)>,
}

/// The most isovalues the shader composites.
pub const MAX_ISOVALUES: usize = 8;

impl GpuGridRenderer {
    /// Uploads `grid` to the device of `ctx`; an error when it is over the device's 3D
    /// texture size.
    pub fn new(ctx: Arc<GpuContext>, grid: Arc<Grid>) -> Result<Self, GpuError> {
        let limits = ctx.limits();
        let dims = grid.dims();
        let side = limits.max_texture_dimension_3d as usize;
        if dims.iter().any(|&n| n > side) {
            return Err(GpuError::OverLimit {
                what: format!("a grid of {}x{}x{}", dims[0], dims[1], dims[2]),
                limit: format!("3D textures up to {side} per side"),
            });
        }
        let volume = ctx.checked(|| upload(&ctx, &grid))??;
        let macrocells =
            volux_core::with_samples!(grid.samples(), |s| MacrocellGrid::build(s, grid.dims()));
        let no_gradients = ctx.checked(|| no_gradients(&ctx))?;
        let no_mask = words_buffer(&ctx.device, "no sculpt mask", &[u32::MAX]);
        Ok(Self {
            ctx,
            grid,
            volume,
            pipelines: HashMap::new(),
            macrocells,
            tables: None,
            gradients: None,
            no_gradients,
            no_mask,
            mask: None,
        })
    }

    /// Whether the shader draws `scene` (a grid ray casting scene): `Err` says what it does
    /// not draw yet, for a front end to fall back to the CPU or to say so.
    pub fn supports(scene: &Scene) -> Result<(), String> {
        let settings = match scene.method {
            Method::GridRaycast(s) => s,
            Method::Auto => GridRaycast::default(),
            ref m => return Err(format!("the GPU backend does not draw '{}'", m.name())),
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
            Some(what) => Err(format!(
                "the GPU backend does not draw {what} yet (use --backend cpu)"
            )),
            None => Ok(()),
        }
    }

    /// The adapter this renderer draws on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Device memory held between frames, in bytes: the grid (4 per voxel), the gradient
    /// volume once shaded (8 per voxel), the tables and the mask's bits. A frame adds its
    /// image and sample counts twice (20 bytes per pixel on the device, as much to read
    /// back).
    pub fn device_bytes(&self) -> u64 {
        let voxels = self.grid.dims().iter().map(|&n| n as u64).product::<u64>();
        let gradients = match self.gradients {
            Some(Some(_)) => 8 * voxels,
            _ => 0,
        };
        let tables = self
            .tables
            .as_ref()
            .map_or(0, |t| t.lut.size() + t.cells.size() + t.preint.size());
        let mask = self.mask.as_ref().map_or(0, |(_, m)| m.buffer.size());
        4 * voxels + gradients + tables + mask
    }

    fn render_options(
        &self,
        scene: &Scene,
        control: &Control,
    ) -> Result<RenderOptions, RenderError> {
        let volume = Volume::Grid(self.grid.clone());
        let settings = match scene.method.resolve(&volume)? {
            Method::GridRaycast(s) => s,
            m => {
                return Err(RenderError::InvalidOptions(format!(
                    "the GPU grid renderer cannot draw method '{}'",
                    m.name()
                )))
            }
        };
        Self::supports(scene).map_err(RenderError::Backend)?;
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
        let ctx = self.ctx.clone();
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
        let place = Placement::of(&self.grid);
        let h = step * place.spacing.min_element();
        let stale = self.classify(opts, h)?;
        let mut flags = flags::SKIP;
        let to_world = self.prepare_gradients(opts, &mut flags)?;
        self.prepare_mask(opts, &mut flags)?;
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
        let Some(tables) = &self.tables else {
            return Err(GpuError::Failed("no classification tables".into()));
        };
        let drawn = Drawn {
            tables,
            to_world,
            cells: self.macrocells.counts(),
            planes: opts.clip_planes.len(),
        };
        let params = Params::new(opts, &place, h, &drawn);
        let device = &self.ctx.device;
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
        let gradients = match &self.gradients {
            Some(Some((view, _))) if flags & flags::GRADIENT_VOLUME != 0 => view,
            _ => &self.no_gradients,
        };
        let mask = match &self.mask {
            Some((_, bits)) if flags & flags::MASK != 0 => &bits.buffer,
            _ => &self.no_mask,
        };
        let entries = [
            (0, uniform.as_entire_binding()),
            (1, wgpu::BindingResource::TextureView(&self.volume)),
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
        self.ctx.queue.submit([encoder.finish()]);
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
        let p = self
            .ctx
            .checked(|| pipeline(&self.ctx.device, flags, mode))?;
        self.pipelines.insert(key, p.clone());
        Ok(p)
    }

    /// An error when the image's `bytes` are over the device's storage buffers.
    fn check_buffer(&self, bytes: u64, opts: &RenderOptions) -> Result<(), GpuError> {
        let limits = self.ctx.limits();
        let most = u64::from(limits.max_storage_buffer_binding_size).min(limits.max_buffer_size);
        if bytes > most {
            return Err(GpuError::OverLimit {
                what: format!("an image of {}x{}", opts.width, opts.height),
                limit: format!("storage buffers up to {most} bytes"),
            });
        }
        Ok(())
    }

    /// Rebuilds the tables unless they are those of `opts` at step `h`; whether it did.
    fn classify(&mut self, opts: &RenderOptions, h: f64) -> Result<bool, GpuError> {
        let key = TableKey {
            tf: opts.tf.clone(),
            h,
            isovalues: opts
                .isosurfaces
                .as_slice()
                .iter()
                .map(|i| i.value)
                .collect(),
            preintegrated: matches!(opts.integrator, Integrator::Preintegrated { .. }),
        };
        if self.tables.as_ref().is_some_and(|t| t.is_for(&key)) {
            return Ok(false);
        }
        let range = self.grid.range();
        let tables = Tables::new(&self.ctx.device, key, range, &self.macrocells)?;
        self.tables = Some(tables);
        Ok(true)
    }

    /// The gradient volume's units per count when shaded samples use it (built and uploaded
    /// on the first shaded frame), setting the flags it needs.
    fn prepare_gradients(
        &mut self,
        opts: &RenderOptions,
        flags: &mut u32,
    ) -> Result<[f32; 3], GpuError> {
        if opts.shading.is_none() {
            return Ok([0.0; 3]);
        }
        *flags |= flags::SHADE;
        if self.gradients.is_none() {
            let g = &*self.grid;
            let built = volux_core::with_samples!(g.samples(), |s| GradientVolume::build(
                &Trilinear::new(s, g.dims()),
                g.spacing().as_vec3(),
                0
            ));
            let ctx = self.ctx.clone();
            self.gradients = Some(match built {
                Ok(volume) => Some(ctx.checked(|| upload_gradients(&ctx, &volume))?),
                Err(_) => None,
            });
        }
        match &self.gradients {
            Some(Some((_, to_world))) => {
                *flags |= flags::GRADIENT_VOLUME;
                Ok(*to_world)
            }
            _ => Ok([0.0; 3]),
        }
    }

    /// Uploads the scene's sculpt mask when it is new or has changed, setting its flag.
    fn prepare_mask(&mut self, opts: &RenderOptions, flags: &mut u32) -> Result<(), GpuError> {
        let Some(mask) = &opts.mask else {
            return Ok(());
        };
        if mask.dims() != self.grid.dims() {
            return Err(GpuError::Failed(format!(
                "the sculpt mask is {:?} voxels but the grid is {:?}",
                mask.dims(),
                self.grid.dims()
            )));
        }
        *flags |= flags::MASK;
        let address = Arc::as_ptr(mask) as usize;
        let current = self
            .mask
            .as_ref()
            .is_some_and(|(a, bits)| *a == address && bits.generation == mask.generation());
        if !current {
            let ctx = self.ctx.clone();
            self.mask = Some((address, ctx.checked(|| MaskBits::new(&ctx, mask))??));
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

/// The grid as an `r32float` 3D texture, non-finite values as NaN.
fn upload(ctx: &GpuContext, grid: &Grid) -> Result<wgpu::TextureView, GpuError> {
    let [nx, ny, nz] = grid.dims();
    let size = wgpu::Extent3d {
        width: nx as u32,
        height: ny as u32,
        depth_or_array_layers: nz as u32,
    };
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("volume"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    // A slab of z layers at a time, so that the f32 copy never holds the whole grid twice.
    let layer = nx * ny;
    let per_write = (16 << 20) / (4 * layer).max(1);
    let per_write = per_write.max(1);
    let samples = grid.samples();
    let mut z = 0;
    while z < nz {
        let n = per_write.min(nz - z);
        let values: Vec<f32> = (z * layer..(z + n) * layer)
            .map(|i| {
                let v = samples.get_f32(i);
                if v.is_finite() {
                    v
                } else {
                    f32::NAN
                }
            })
            .collect();
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: z as u32,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&values),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * nx as u32),
                rows_per_image: Some(ny as u32),
            },
            wgpu::Extent3d {
                depth_or_array_layers: n as u32,
                ..size
            },
        );
        z += n;
    }
    Ok(texture.create_view(&Default::default()))
}

/// The ray casting pipeline (`raycast.wgsl`) of the features `flags` in `mode`.
fn pipeline(device: &wgpu::Device, flags: u32, mode: u32) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("raycast.wgsl"),
        source: wgpu::ShaderSource::Wgsl(
            concat!(include_str!("common.wgsl"), include_str!("raycast.wgsl")).into(),
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
