//! The brick pool's renderer ([`GpuPoolRenderer`]; see the `pool` module docs): the
//! frame's rounds of dispatches and brick loads, the tables, the bricks' value ranges.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use volux_core::image::Image;
use volux_render::backend_kit::ClassifyTable;
use volux_render::backend_kit::MacrocellGrid;
use volux_render::backend_kit::{Placement, RenderOptions};
use volux_render::frame::{Frame, FrameStats, MethodStats, Rebuilt, RenderStats};
use volux_render::integrate::Integrator;
use volux_render::renderer::Renderer;
use volux_render::sampling::Reconstruction;
use volux_render::scene::{GridRaycast, Method, Scene};
use volux_render::tiles::Control;
use volux_render::{check_image_size, Refusal, Remedy, RenderError};
use wgpu::util::DeviceExt;

use super::slots::{bricks_per_axis, PoolOptions, Slots};
use super::source::PoolSource;
use crate::context::GpuContext;
use crate::error::GpuError;
use crate::grid::{map, readback, Readback};
use crate::params::{flags, frame_data, Drawn, Params};
use crate::tables::{TableKey, Tables};

/// What the last frame did: dispatches, bricks uploaded, bricks resident.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PoolStats {
    /// Dispatches until no ray asked for a brick.
    pub rounds: usize,
    /// Bricks written to the atlas.
    pub uploads: usize,
    /// Slots in the atlas.
    pub capacity: usize,
    /// Bricks of the grid.
    pub bricks: usize,
    /// Bricks the TF leaves transparent (never loaded).
    pub empty: usize,
}

/// Grid ray casting through a brick pool (see the module documentation).
pub struct GpuPoolRenderer {
    ctx: Arc<GpuContext>,
    source: PoolSource,
    place: Placement,
    range: [f64; 2],
    slots: Slots,
    /// Each brick's value range (from the macrocells), when known.
    ranges: Option<MacrocellGrid>,
    /// The empty flags of the last TF, per brick.
    empty: Option<(volux_core::TransferFunction, Vec<bool>)>,
    tables: Option<Tables>,
    pipelines: HashMap<u32, wgpu::ComputePipeline>,
    stats: PoolStats,
}

/// The most dispatches of one frame (each loads at least one brick a waiting ray needs, so
/// a frame takes at most about as many as the bricks its rays cross).
const MAX_ROUNDS: usize = 1 << 16;

impl GpuPoolRenderer {
    /// A pool for `source` laid out by `options` on the device of `ctx`: the atlas is
    /// allocated (errors name the limit when not even one brick fits) and the bricks' value
    /// ranges found (a pass over a grid in memory; a bricked volume's recorded chunk ranges).
    pub fn new(
        ctx: Arc<GpuContext>,
        source: PoolSource,
        options: PoolOptions,
    ) -> Result<Self, GpuError> {
        if options.brick == 0 || !options.brick.is_multiple_of(MacrocellGrid::BLOCK) {
            return Err(GpuError::Failed(format!(
                "bricks of {} cells: the side must be a positive multiple of {}",
                options.brick,
                MacrocellGrid::BLOCK
            )));
        }
        let place = source.placement()?;
        let slots = Slots::new(&ctx, place.dims, options)?;
        let ranges = brick_ranges(&source, place.dims, options.brick);
        Ok(Self {
            range: source.range(),
            ctx,
            source,
            place,
            slots,
            ranges,
            empty: None,
            tables: None,
            pipelines: HashMap::new(),
            stats: PoolStats::default(),
        })
    }

    /// What the last frame did.
    pub fn stats(&self) -> PoolStats {
        self.stats
    }

    /// Whether the pool draws `scene`: `Err` names what it does not draw.
    pub fn supports(scene: &Scene) -> Result<(), Refusal> {
        let settings = match scene.method {
            Method::GridRaycast(s) => s,
            Method::Auto => GridRaycast::default(),
            ref m => {
                return Err(Refusal::new(
                    "the GPU brick pool",
                    format!("does not draw '{}'", m.name()),
                    None,
                ))
            }
        };
        let a = &scene.appearance;
        let refused = if !matches!(settings.integrator, Integrator::Riemann { .. }) {
            Some(format!("the {} integrator", settings.integrator.name()))
        } else if settings.reconstruction != Reconstruction::Trilinear {
            Some("tricubic reconstruction".into())
        } else if a.shade_volume {
            Some("volume shading".into())
        } else if !a.isosurfaces.is_empty() {
            Some("isosurfaces".into())
        } else if a.mip {
            Some("maximum intensity projection".into())
        } else if scene.mask.is_some() {
            Some("a sculpt mask".into())
        } else if scene.labels.is_some() {
            Some("region labels".into())
        } else {
            None
        };
        match refused {
            Some(what) => Err(Refusal::new(
                "the GPU brick pool",
                format!("does not draw {what} yet"),
                Some(Remedy::CpuBackend),
            )),
            None => Ok(()),
        }
    }
}

impl Renderer for GpuPoolRenderer {
    fn name(&self) -> &'static str {
        "raycast"
    }

    fn render(&mut self, scene: &Scene, control: &Control) -> Result<Frame, RenderError> {
        let started = Instant::now();
        Self::supports(scene)?;
        let settings = match scene.method {
            Method::GridRaycast(s) => s,
            _ => GridRaycast::default(),
        };
        let opts = RenderOptions::from_scene(scene, &settings, control);
        check_image_size(opts.width, opts.height)?;
        let ctx = self.ctx.clone();
        let ((rgba, samples), classified) = ctx.checked(|| self.frame(&opts, control))??;
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

/// The per-frame buffers of the rays' state.
struct RayState {
    acc: wgpu::Buffer,
    index: wgpu::Buffer,
    samples: wgpu::Buffer,
    requests: wgpu::Buffer,
}

impl GpuPoolRenderer {
    /// Renders `opts` in rounds until no ray waits for a brick; the pixels, each pixel's
    /// samples, and whether the classification was rebuilt.
    fn frame(
        &mut self,
        opts: &RenderOptions,
        control: &Control,
    ) -> Result<(Readback, bool), GpuError> {
        let Integrator::Riemann { step } = opts.integrator else {
            return Err(GpuError::Failed("the pool draws Riemann sums only".into()));
        };
        let h = step * self.place.spacing.min_element();
        let classified = self.classify(opts, h)?;
        let pipeline = self.pipeline(if opts.jitter { flags::JITTER } else { 0 })?;
        let Some(tables) = &self.tables else {
            return Err(GpuError::Failed("no classification tables".into()));
        };
        let device = &self.ctx.device;
        let drawn = Drawn {
            tables,
            to_world: [0.0; 3],
            cells: [1, 1, 1],
            planes: opts.clip_planes.len(),
        };
        let params = Params::new(opts, &self.place, h, &drawn);
        let uniform = |label: &str, bytes: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            })
        };
        let params = uniform("params", bytemuck::bytes_of(&params));
        let layout = uniform("pool", bytemuck::cast_slice(&self.slots.layout()));
        let frame = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("clip planes"),
            contents: bytemuck::cast_slice(&frame_data(opts, &self.place)),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let pixels = (opts.width * opts.height) as u64;
        let state = self.ray_state(pixels)?;
        let empty = self.empty.as_ref().map(|(_, e)| e.as_slice());
        self.stats = PoolStats {
            capacity: self.slots.capacity(),
            bricks: self.slots.bricks(),
            empty: empty.map_or(0, |e| e.iter().filter(|&&x| x).count()),
            ..PoolStats::default()
        };
        loop {
            if control.is_cancelled() {
                return Err(GpuError::Failed("cancelled".into()));
            }
            if self.stats.rounds == MAX_ROUNDS {
                return Err(GpuError::Failed(format!(
                    "the brick pool did not finish the frame in {MAX_ROUNDS} rounds"
                )));
            }
            let page = self
                .slots
                .page(self.empty.as_ref().map(|(_, e)| e.as_slice()));
            let page = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("page table"),
                contents: bytemuck::cast_slice(&page),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let entries = [
                (0, params.as_entire_binding()),
                (1, wgpu::BindingResource::TextureView(self.slots.view())),
                (2, tables.lut.as_entire_binding()),
                (3, layout.as_entire_binding()),
                (4, frame.as_entire_binding()),
                (5, page.as_entire_binding()),
                (6, state.requests.as_entire_binding()),
                (7, state.acc.as_entire_binding()),
                (8, state.index.as_entire_binding()),
                (9, state.samples.as_entire_binding()),
            ]
            .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource });
            let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("pool"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            });
            let mut encoder = device.create_command_encoder(&Default::default());
            encoder.clear_buffer(&state.requests, 0, None);
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(
                    (opts.width as u32).div_ceil(8),
                    (opts.height as u32).div_ceil(8),
                    1,
                );
            }
            let size = state.requests.size();
            let asked = readback(device, &mut encoder, &state.requests, size);
            self.ctx.queue.submit([encoder.finish()]);
            let asked: Vec<u32> = bytemuck::cast_slice(&map(device, &asked)?).to_vec();
            self.stats.rounds += 1;
            let wanted: Vec<usize> = (0..asked.len()).filter(|&b| asked[b] != 0).collect();
            if wanted.is_empty() {
                break;
            }
            self.stats.uploads += self.slots.load(&self.ctx, &self.source, &wanted)?;
        }
        let mut encoder = device.create_command_encoder(&Default::default());
        let rgba = readback(device, &mut encoder, &state.acc, pixels * 16);
        let counts = readback(device, &mut encoder, &state.samples, pixels * 4);
        self.ctx.queue.submit([encoder.finish()]);
        let rgba: Vec<[f32; 4]> = bytemuck::cast_slice(&map(device, &rgba)?).to_vec();
        let counts: Vec<u32> = bytemuck::cast_slice(&map(device, &counts)?).to_vec();
        Ok(((rgba, counts), classified))
    }

    /// Zeroed ray state for `pixels` rays and the request flags; an error when the image is
    /// over the device's storage buffers.
    fn ray_state(&self, pixels: u64) -> Result<RayState, GpuError> {
        let limits = self.ctx.limits();
        let most = u64::from(limits.max_storage_buffer_binding_size).min(limits.max_buffer_size);
        if pixels * 16 > most {
            return Err(GpuError::OverLimit {
                what: format!("an image of {pixels} pixels"),
                limit: format!("storage buffers up to {most} bytes"),
            });
        }
        let zeroed = |label: &str, size: u64| {
            self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        Ok(RayState {
            acc: zeroed("ray opacity", pixels * 16),
            index: zeroed("ray sample index", pixels * 4),
            samples: zeroed("ray samples", pixels * 4),
            requests: zeroed("brick requests", 4 * self.slots.bricks() as u64),
        })
    }

    /// Rebuilds the tables and the bricks' empty flags unless they are those of `opts` at
    /// step `h`; whether it did.
    fn classify(&mut self, opts: &RenderOptions, h: f64) -> Result<bool, GpuError> {
        let key = TableKey {
            tf: opts.tf.clone(),
            h,
            isovalues: Vec::new(),
            preintegrated: false,
        };
        if self.tables.as_ref().is_some_and(|t| t.is_for(&key)) {
            return Ok(false);
        }
        let one = MacrocellGrid::from_ranges([1; 3], [1; 3], vec![[0.0, 0.0]])
            .ok_or_else(|| GpuError::Failed("a one-cell macrocell grid".into()))?;
        self.tables = Some(Tables::new(&self.ctx.device, key, self.range, &one)?);
        self.empty = self.ranges.as_ref().map(|r| {
            let table = ClassifyTable::new(&opts.tf, self.range, ClassifyTable::DEFAULT_SIZE);
            (opts.tf.clone(), r.empty_flags(&table, &[]))
        });
        Ok(true)
    }

    /// The pipeline of the flags (jitter), compiled on first use.
    fn pipeline(&mut self, flags: u32) -> Result<wgpu::ComputePipeline, GpuError> {
        if let Some(p) = self.pipelines.get(&flags) {
            return Ok(p.clone());
        }
        let device = &self.ctx.device;
        let p = self.ctx.checked(|| {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("pool.wgsl"),
                source: wgpu::ShaderSource::Wgsl(
                    concat!(include_str!("../common.wgsl"), include_str!("../pool.wgsl")).into(),
                ),
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("pool"),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &[("FLAGS", f64::from(flags))],
                    ..Default::default()
                },
                cache: None,
            })
        })?;
        self.pipelines.insert(flags, p.clone());
        Ok(p)
    }
}

/// Each brick's value range as a macrocell grid of bricks (the union of the ranges of the
/// macrocells or chunks it overlaps), or `None` when the source records none.
fn brick_ranges(source: &PoolSource, dims: [usize; 3], side: usize) -> Option<MacrocellGrid> {
    let cells = match source {
        PoolSource::Grid(g) => {
            volux_core::with_samples!(g.samples(), |s| MacrocellGrid::build(s, g.dims()))
        }
        PoolSource::Level(v, level) => v.chunk_cells(*level)?.clone(),
    };
    let bricks = bricks_per_axis(dims, side);
    let (counts, block) = (cells.counts(), cells.block());
    let mut ranges = Vec::with_capacity(bricks.iter().product());
    for bz in 0..bricks[2] {
        for by in 0..bricks[1] {
            for bx in 0..bricks[0] {
                let b = [bx, by, bz];
                let span = |a: usize| {
                    let first = (b[a] * side / block[a]).min(counts[a] - 1);
                    let last = (((b[a] + 1) * side - 1) / block[a]).min(counts[a] - 1);
                    first..=last
                };
                let mut r = [f32::INFINITY, f32::NEG_INFINITY];
                for k in span(2) {
                    for j in span(1) {
                        for i in span(0) {
                            let m = cells.ranges()[i + counts[0] * (j + counts[1] * k)];
                            r = [r[0].min(m[0]), r[1].max(m[1])];
                        }
                    }
                }
                ranges.push(r);
            }
        }
    }
    MacrocellGrid::from_ranges(bricks, [side; 3], ranges)
}
