//! What the ray casting shader reads besides the grid and the tables, uploaded once per
//! volume or per edit: the gradient volume ([`upload_gradients`]) and the sculpt mask's bits
//! ([`MaskBits`]).
use volux_core::sculpt::SculptMask;
use volux_render::backend_kit::GradientVolume;
use wgpu::util::DeviceExt;

use crate::context::GpuContext;
use crate::error::GpuError;

/// A 3D texture of `dims` texels of `format` (`bytes` per texel) holding `data`, written a
/// slab of z layers at a time.
pub(crate) fn texture_3d(
    ctx: &GpuContext,
    label: &str,
    dims: [usize; 3],
    format: wgpu::TextureFormat,
    bytes: usize,
    data: &[u8],
) -> wgpu::TextureView {
    let [nx, ny, nz] = dims;
    let size = wgpu::Extent3d {
        width: nx as u32,
        height: ny as u32,
        depth_or_array_layers: nz as u32,
    };
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let layer = nx * ny * bytes;
    let per_write = ((16 << 20) / layer.max(1)).max(1);
    let mut z = 0;
    while z < nz {
        let n = per_write.min(nz - z);
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
            &data[z * layer..(z + n) * layer],
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some((nx * bytes) as u32),
                rows_per_image: Some(ny as u32),
            },
            wgpu::Extent3d {
                depth_or_array_layers: n as u32,
                ..size
            },
        );
        z += n;
    }
    texture.create_view(&Default::default())
}

/// The gradient volume as an `rgba16sint` 3D texture (the CPU's quantized counts, 8 bytes per
/// voxel) and its world units per count.
pub(crate) fn upload_gradients(
    ctx: &GpuContext,
    gradients: &GradientVolume,
) -> (wgpu::TextureView, [f32; 3]) {
    let (data, to_world) = gradients.quantized();
    let view = texture_3d(
        ctx,
        "gradient volume",
        gradients.key().dims,
        wgpu::TextureFormat::Rgba16Sint,
        8,
        bytemuck::cast_slice(data),
    );
    (view, to_world.to_array())
}

/// A one-texel `rgba16sint` texture bound where there is no gradient volume.
pub(crate) fn no_gradients(ctx: &GpuContext) -> wgpu::TextureView {
    texture_3d(
        ctx,
        "no gradient volume",
        [1, 1, 1],
        wgpu::TextureFormat::Rgba16Sint,
        8,
        &[0; 8],
    )
}

/// The sculpt mask on the device: a bit per voxel, x fastest, for the mask of one generation.
pub(crate) struct MaskBits {
    pub(crate) generation: u64,
    pub(crate) buffer: wgpu::Buffer,
}

impl MaskBits {
    /// The bits of `mask`; an error when they are over the device's storage buffers.
    pub(crate) fn new(ctx: &GpuContext, mask: &SculptMask) -> Result<Self, GpuError> {
        let [nx, ny, nz] = mask.dims();
        let voxels = (nx * ny * nz) as u64;
        let words = voxels.div_ceil(32);
        let limits = ctx.limits();
        let most = u64::from(limits.max_storage_buffer_binding_size).min(limits.max_buffer_size);
        if words * 4 > most || voxels > u64::from(u32::MAX) {
            return Err(GpuError::OverLimit {
                what: format!("a sculpt mask of {nx}x{ny}x{nz} voxels"),
                limit: format!("storage buffers up to {most} bytes and 2^32 voxels"),
            });
        }
        let mut bits = vec![0u32; words as usize];
        let mut index = 0usize;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    if mask.voxel(i, j, k) {
                        bits[index >> 5] |= 1 << (index & 31);
                    }
                    index += 1;
                }
            }
        }
        Ok(Self {
            generation: mask.generation(),
            buffer: words_buffer(&ctx.device, "sculpt mask", &bits),
        })
    }
}

/// A storage buffer of `words`.
pub(crate) fn words_buffer(device: &wgpu::Device, label: &str, words: &[u32]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(words),
        usage: wgpu::BufferUsages::STORAGE,
    })
}
