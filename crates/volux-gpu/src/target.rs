//! The render target texture slicing blends into ([`target`]), and its pixels read back as
//! `f32` ([`read_target`]; `Rgba16Float` widened on the host).
use crate::context::GpuContext;
use crate::error::GpuError;
use crate::grid::map;

/// A `w` x `h` colour target of `format`, copied out after drawing; an error when it is over
/// the device's 2D texture size.
pub(crate) fn target(
    ctx: &GpuContext,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
) -> Result<wgpu::Texture, GpuError> {
    let side = ctx.limits().max_texture_dimension_2d;
    if w > side || h > side {
        return Err(GpuError::OverLimit {
            what: format!("an image of {w}x{h}"),
            limit: format!("2D textures up to {side} per side"),
        });
    }
    Ok(ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("slicing target"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    }))
}

/// Submits `encoder` with a copy of `texture` (`Rgba32Float` or `Rgba16Float`) and returns
/// its pixels, rows top to bottom.
pub(crate) fn read_target(
    ctx: &GpuContext,
    mut encoder: wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    format: wgpu::TextureFormat,
) -> Result<Vec<[f32; 4]>, GpuError> {
    let (w, h) = (texture.width(), texture.height());
    let texel = if format == wgpu::TextureFormat::Rgba32Float {
        16
    } else {
        8
    };
    let row = (w * texel).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("slicing readback"),
        size: u64::from(row) * u64::from(h),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        texture.size(),
    );
    ctx.queue.submit([encoder.finish()]);
    let bytes = map(&ctx.device, &buffer)?;
    let used = (w * texel) as usize;
    let pixels = bytes
        .chunks_exact(row as usize)
        .flat_map(|r| r[..used].chunks_exact(texel as usize).map(pixel))
        .collect();
    Ok(pixels)
}

/// One texel's bytes as `f32` channels (four `f32`, or four `f16` widened).
fn pixel(texel: &[u8]) -> [f32; 4] {
    let width = texel.len() / 4;
    std::array::from_fn(|c| {
        let b = &texel[c * width..(c + 1) * width];
        match *b {
            [a0, a1, a2, a3] => f32::from_le_bytes([a0, a1, a2, a3]),
            [a0, a1] => f16_to_f32(u16::from_le_bytes([a0, a1])),
            _ => f32::NAN,
        }
    })
}

/// An IEEE half-precision number as `f32`.
fn f16_to_f32(bits: u16) -> f32 {
    let sign = if bits & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from((bits >> 10) & 0x1f);
    let mantissa = f32::from(bits & 0x3ff);
    sign * match exponent {
        0 => mantissa * 2f32.powi(-24),
        31 if mantissa == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        e => (1.0 + mantissa / 1024.0) * 2f32.powi(e - 15),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_widen_exactly() {
        for v in [0.0f32, 1.0, -2.5, 0.099975586, 65504.0, 2f32.powi(-24)] {
            let bits = half_bits(v);
            assert_eq!(f16_to_f32(bits), v, "{v}");
        }
        assert!(f16_to_f32(0x7e00).is_nan());
        assert_eq!(f16_to_f32(0x7c00), f32::INFINITY);
        assert_eq!(
            pixel(&[0, 0x3c, 0, 0xc0, 0, 0, 0, 0x38]),
            [1.0, -2.0, 0.0, 0.5]
        );
    }

    /// The half nearest `v` for the values above (normal or the smallest subnormal).
    fn half_bits(v: f32) -> u16 {
        (0..=0xffffu16)
            .filter(|&b| b & 0x7c00 != 0x7c00)
            .min_by(|&a, &b| {
                let (da, db) = ((f16_to_f32(a) - v).abs(), (f16_to_f32(b) - v).abs());
                da.total_cmp(&db)
            })
            .unwrap_or(0)
    }
}
