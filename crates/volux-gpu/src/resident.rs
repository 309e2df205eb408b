//! What a grid renderer keeps on the device between frames ([`Resident`]): the grid as a 3D
//! texture, its macrocells, the classification tables while the TF and the step stay, the
//! gradient volume and the sculpt mask's bits; shared by the ray caster and texture slicing.
use std::sync::Arc;

use volux_core::Grid;
use volux_render::backend_kit::GradientVolume;
use volux_render::backend_kit::MacrocellGrid;
use volux_render::backend_kit::RenderOptions;
use volux_render::backend_kit::Trilinear;
use volux_render::integrate::Integrator;

use crate::context::GpuContext;
use crate::error::GpuError;
use crate::params::flags;
use crate::resources::{no_gradients, upload_gradients, words_buffer, MaskBits};
use crate::tables::{TableKey, Tables};

/// A grid on the device and what was derived from it (see the module docs).
pub(crate) struct Resident {
    pub(crate) ctx: Arc<GpuContext>,
    pub(crate) grid: Arc<Grid>,
    pub(crate) volume: wgpu::TextureView,
    /// The min/max of each macrocell (from the data, built once).
    pub(crate) macrocells: MacrocellGrid,
    /// The last frame's classification, kept while the TF and the step stay.
    pub(crate) tables: Option<Tables>,
    /// The gradient volume and its world units per count, uploaded on the first shaded
    /// frame (`None` inside when it is over the memory budget: gradients on the fly).
    gradients: Option<Option<(wgpu::TextureView, [f32; 3])>>,
    /// Bound where a frame uses no gradient volume or no mask.
    no_gradients: wgpu::TextureView,
    no_mask: wgpu::Buffer,
    /// The sculpt mask's bits, for the mask (by address) of one generation.
    mask: Option<(usize, MaskBits)>,
}

impl Resident {
    /// Uploads `grid` to the device of `ctx`; an error when it is over the device's 3D
    /// texture size.
    pub(crate) fn new(ctx: Arc<GpuContext>, grid: Arc<Grid>) -> Result<Self, GpuError> {
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
            macrocells,
            tables: None,
            gradients: None,
            no_gradients,
            no_mask,
            mask: None,
        })
    }

    /// Device memory held, in bytes: the grid (4 per voxel), the gradient volume once shaded
    /// (8 per voxel), the tables and the mask's bits.
    pub(crate) fn device_bytes(&self) -> u64 {
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

    /// The gradient volume when `flags` use it, else the one-texel stand-in.
    pub(crate) fn gradients_view(&self, flags: u32) -> &wgpu::TextureView {
        match &self.gradients {
            Some(Some((view, _))) if flags & flags::GRADIENT_VOLUME != 0 => view,
            _ => &self.no_gradients,
        }
    }

    /// The sculpt mask's bits when `flags` use them, else the stand-in.
    pub(crate) fn mask_buffer(&self, flags: u32) -> &wgpu::Buffer {
        match &self.mask {
            Some((_, bits)) if flags & flags::MASK != 0 => &bits.buffer,
            _ => &self.no_mask,
        }
    }

    /// Rebuilds the tables unless they are those of `opts` at step `h`; whether it did.
    pub(crate) fn classify(&mut self, opts: &RenderOptions, h: f64) -> Result<bool, GpuError> {
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
    pub(crate) fn prepare_gradients(
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
    pub(crate) fn prepare_mask(
        &mut self,
        opts: &RenderOptions,
        flags: &mut u32,
    ) -> Result<(), GpuError> {
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
