//! Classification by the data's own colour: an RGB grid ([`volux_core::color::Rgb`]:
//! cryosections, histology, secondary captures) is drawn in the colour its voxels carry, with
//! the opacity the transfer function gives its luminance (the grid's scalar). This is VTK's
//! "dependent components" mode for three-component volumes (`vtkVolumeProperty::
//! IndependentComponentsOff`): the colour comes from the data, the opacity from one scalar.
//!
//! The channels are interpolated trilinearly at the sample, as the scalar is, in the file's
//! encoding (sRGB, as photographs and secondary captures are stored), then scaled to 0..1 by
//! the type's full scale and turned to linear light, the space the compositing works in (the
//! image is encoded back to sRGB when written). Grid ray casting takes these rays one by one,
//! as it does for region labels; shading lights the data's colour as it lights the TF's.
use std::sync::Arc;

use glam::Vec3;
use volux_core::color::Rgb;
use volux_core::image::srgb_to_linear;
use volux_core::Grid;

/// An RGB grid's colour, ready to be sampled along rays (voxel coordinates).
#[derive(Clone, Debug)]
pub struct DataColour {
    rgb: Arc<Rgb>,
    dims: [usize; 3],
    full_scale: f32,
}

impl DataColour {
    /// The colour of `grid`, `None` when it has none.
    pub fn of(grid: &Grid) -> Option<Self> {
        let rgb = grid.color_shared()?;
        let full_scale = rgb.full_scale() as f32;
        Some(Self {
            rgb,
            dims: grid.dims(),
            full_scale,
        })
    }

    /// The grid dims the colour belongs to.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The linear RGB colour at voxel position `p` (clamped to the grid), trilinearly
    /// interpolated.
    pub fn colour_at(&self, p: Vec3) -> [f32; 3] {
        let [nx, ny, nz] = self.dims;
        let axis = |x: f32, n: usize| {
            let x = x.clamp(0.0, (n - 1) as f32);
            let i = (x.floor() as usize).min(n.saturating_sub(2));
            let f = if n > 1 { x - i as f32 } else { 0.0 };
            (i, (i + 1).min(n - 1), f)
        };
        let (x0, x1, fx) = axis(p.x, nx);
        let (y0, y1, fy) = axis(p.y, ny);
        let (z0, z1, fz) = axis(p.z, nz);
        let idx = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        let corners = [
            (idx(x0, y0, z0), (1.0 - fx) * (1.0 - fy) * (1.0 - fz)),
            (idx(x1, y0, z0), fx * (1.0 - fy) * (1.0 - fz)),
            (idx(x0, y1, z0), (1.0 - fx) * fy * (1.0 - fz)),
            (idx(x1, y1, z0), fx * fy * (1.0 - fz)),
            (idx(x0, y0, z1), (1.0 - fx) * (1.0 - fy) * fz),
            (idx(x1, y0, z1), fx * (1.0 - fy) * fz),
            (idx(x0, y1, z1), (1.0 - fx) * fy * fz),
            (idx(x1, y1, z1), fx * fy * fz),
        ];
        let mut out = [0.0f32; 3];
        for (c, ch) in self.rgb.channels().iter().enumerate() {
            let v: f32 = corners.iter().map(|&(i, w)| w * ch.get_f32(i)).sum();
            out[c] = srgb_to_linear((v / self.full_scale).clamp(0.0, 1.0));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::{Buffer, Samples};

    fn rgb_grid() -> Grid {
        // 2 x 1 x 1: red then blue.
        let ch = |v: [u8; 2]| Samples::U8(Buffer::owned(v.to_vec()));
        let rgb = Rgb::new([ch([255, 0]), ch([0, 0]), ch([0, 255])]).unwrap();
        Grid::from_rgb([2, 1, 1], [1.0; 3], [0.0; 3], rgb).unwrap()
    }

    #[test]
    fn colours_are_interpolated_then_made_linear() {
        let c = DataColour::of(&rgb_grid()).unwrap();
        assert_eq!(c.colour_at(Vec3::ZERO), [1.0, 0.0, 0.0]);
        assert_eq!(c.colour_at(Vec3::new(1.0, 0.0, 0.0)), [0.0, 0.0, 1.0]);
        let mid = c.colour_at(Vec3::new(0.5, 0.0, 0.0));
        let half = srgb_to_linear(0.5);
        assert!((mid[0] - half).abs() < 1e-6 && (mid[2] - half).abs() < 1e-6);
        // Outside the grid, the nearest edge.
        assert_eq!(c.colour_at(Vec3::new(-3.0, 2.0, 9.0)), [1.0, 0.0, 0.0]);
    }

    #[test]
    fn a_scalar_grid_has_no_data_colour() {
        let g = Grid::new(
            [1, 1, 1],
            [1.0; 3],
            [0.0; 3],
            Samples::U8(Buffer::owned(vec![1])),
        )
        .unwrap();
        assert!(DataColour::of(&g).is_none());
    }
}
