//! The second pass's pipelines and target (seed `000` §4.3, seed `002` §4.3-4.4): the
//! first pass in compute (`classify.wgsl`), the fans through the hardware rasterizer
//! (`draw.wgsl`) into a float target with premultiplied front-to-back "under" blending.
use crate::error::GpuError;
use crate::grid::{map, readback};

/// The render target's format: `rgba32float` where the adapter blends it (its
/// adapter-specific format features say `BLENDABLE`), `rgba16float` otherwise.
pub(crate) fn target_format(blend_f32: bool) -> wgpu::TextureFormat {
    if blend_f32 {
        wgpu::TextureFormat::Rgba32Float
    } else {
        wgpu::TextureFormat::Rgba16Float
    }
}

/// The first pass: vertex projection, per-tetrahedron classification, and the kept set.
pub(crate) fn classify_pipelines(device: &wgpu::Device) -> [wgpu::ComputePipeline; 3] {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("classify.wgsl"),
        source: wgpu::ShaderSource::Wgsl(include_str!("classify.wgsl").into()),
    });
    ["project", "classify", "keep"].map(|entry| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: None,
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    })
}

/// The fan pipeline: no culling, no depth, the fans drawn front to back with premultiplied
/// "under" (`dst + (1 - dst.a) src`, the CPU's compositing operator and order).
pub(crate) fn draw_pipeline(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("draw.wgsl"),
        source: wgpu::ShaderSource::Wgsl(include_str!("draw.wgsl").into()),
    });
    let under = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::OneMinusDstAlpha,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("pt fans"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: Some(wgpu::BlendState {
                    color: under,
                    alpha: under,
                }),
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview: None,
        cache: None,
    })
}

/// A cleared `width x height` target of `format`.
pub(crate) fn target(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    (width, height): (u32, u32),
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("pt image"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// Bytes per texel of the target.
fn texel_bytes(format: wgpu::TextureFormat) -> u32 {
    if format == wgpu::TextureFormat::Rgba32Float {
        16
    } else {
        8
    }
}

/// Records the copy of `texture` into a buffer to map (rows padded to 256 bytes); returns
/// the buffer and the padded row length.
pub(crate) fn copy_out(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
) -> (wgpu::Buffer, u32) {
    let size = texture.size();
    let row = texel_bytes(texture.format()) * size.width;
    let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let bytes = u64::from(padded) * u64::from(size.height);
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("pt image copy"),
        size: bytes,
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(size.height),
            },
        },
        size,
    );
    (readback(device, encoder, &staging, bytes), padded)
}

/// The pixels of a mapped target copy, as `f32` RGBA.
pub(crate) fn pixels(
    device: &wgpu::Device,
    buf: &wgpu::Buffer,
    format: wgpu::TextureFormat,
    (width, height, padded): (u32, u32, u32),
) -> Result<Vec<[f32; 4]>, GpuError> {
    let bytes = map(device, buf)?;
    let row = (texel_bytes(format) * width) as usize;
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height as usize {
        let start = y * padded as usize;
        let line = bytes
            .get(start..start + row)
            .ok_or_else(|| GpuError::Failed("short image readback".into()))?;
        if format == wgpu::TextureFormat::Rgba32Float {
            out.extend(bytemuck::pod_collect_to_vec::<u8, [f32; 4]>(line));
        } else {
            let halves = bytemuck::pod_collect_to_vec::<u8, [u16; 4]>(line);
            out.extend(halves.iter().map(|h| h.map(half_to_f32)));
        }
    }
    Ok(out)
}

/// An IEEE half as `f32`.
fn half_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((h >> 10) & 0x1f);
    let frac = f32::from(h & 0x3ff);
    match exp {
        0 => sign * frac * 2f32.powi(-24),
        31 if frac == 0.0 => sign * f32::INFINITY,
        31 => f32::NAN,
        _ => sign * (1.0 + frac / 1024.0) * 2f32.powi(exp - 15),
    }
}
