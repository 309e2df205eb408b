//! Colour volumes: the red, green and blue samples of an RGB grid (cryosection and histology
//! stacks, secondary captures, ultrasound, DICOM PALETTE COLOR after its lookup table, NIfTI
//! `RGB24`, TIFF RGB), kept beside the scalar that classification, measurement and the
//! histogram use. That scalar is the luminance (ITK's and Rec. 709's weights, 0.2125 R +
//! 0.7154 G + 0.0721 B, rounded to the channels' type), as VTK's dependent components give
//! opacity from the colour's intensity; a reader asked for one channel (`component`) makes a
//! scalar grid of it instead.
use crate::error::{Error, Result};
use crate::samples::{Buffer, Samples, ScalarType};

/// Luminance weights of red, green and blue (Rec. 709, as ITK's `RGBPixel::GetLuminance`).
pub const LUMINANCE: [f64; 3] = [0.2125, 0.7154, 0.0721];

/// The colour channels of an RGB grid, one sample per voxel each, x fastest, of one type.
#[derive(Clone, Debug)]
pub struct Rgb {
    channels: [Samples; 3],
}

impl Rgb {
    /// Colour from red, green and blue samples of the same length and type.
    pub fn new(channels: [Samples; 3]) -> Result<Self> {
        let [r, g, b] = &channels;
        if g.len() != r.len() || b.len() != r.len() {
            return Err(Error::SizeMismatch {
                expected: r.len() as u64,
                actual: g.len().min(b.len()) as u64,
            });
        }
        if g.scalar_type() != r.scalar_type() || b.scalar_type() != r.scalar_type() {
            return Err(Error::InvalidGeometry(format!(
                "colour channels of different types ({}, {}, {})",
                r.scalar_type().name(),
                g.scalar_type().name(),
                b.scalar_type().name()
            )));
        }
        Ok(Self { channels })
    }

    /// Red, green and blue.
    pub fn channels(&self) -> &[Samples; 3] {
        &self.channels
    }

    /// The channels' type.
    pub fn scalar_type(&self) -> ScalarType {
        self.channels[0].scalar_type()
    }

    /// Voxels.
    pub fn len(&self) -> usize {
        self.channels[0].len()
    }

    /// Whether there are no voxels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The value that means full intensity: 255 for `u8`, 65535 for `u16`, 32767 for `i16`,
    /// and the largest value present for `f32`.
    pub fn full_scale(&self) -> f64 {
        match self.scalar_type() {
            ScalarType::U8 => 255.0,
            ScalarType::U16 => 65535.0,
            ScalarType::I16 => 32767.0,
            ScalarType::F32 => {
                let mut hi = 0.0f64;
                for c in &self.channels {
                    for i in 0..c.len() {
                        hi = hi.max(f64::from(c.get_f32(i)));
                    }
                }
                if hi > 0.0 {
                    hi
                } else {
                    1.0
                }
            }
        }
    }

    /// The colour of voxel `i`, each channel scaled to 0..1 by `full_scale`.
    #[inline]
    pub fn rgb(&self, i: usize, full_scale: f32) -> [f32; 3] {
        let s = 1.0 / full_scale;
        [
            (self.channels[0].get_f32(i) * s).clamp(0.0, 1.0),
            (self.channels[1].get_f32(i) * s).clamp(0.0, 1.0),
            (self.channels[2].get_f32(i) * s).clamp(0.0, 1.0),
        ]
    }

    /// The luminance of every voxel, in the channels' type (rounded for integers).
    pub fn luminance(&self) -> Samples {
        let n = self.len();
        let [r, g, b] = &self.channels;
        let lum = |i: usize| {
            LUMINANCE[0] * f64::from(r.get_f32(i))
                + LUMINANCE[1] * f64::from(g.get_f32(i))
                + LUMINANCE[2] * f64::from(b.get_f32(i))
        };
        match self.scalar_type() {
            ScalarType::U8 => Samples::U8(Buffer::owned(
                (0..n)
                    .map(|i| lum(i).round().clamp(0.0, 255.0) as u8)
                    .collect(),
            )),
            ScalarType::U16 => Samples::U16(Buffer::owned(
                (0..n)
                    .map(|i| lum(i).round().clamp(0.0, 65535.0) as u16)
                    .collect(),
            )),
            ScalarType::I16 => Samples::I16(Buffer::owned(
                (0..n)
                    .map(|i| lum(i).round().clamp(-32768.0, 32767.0) as i16)
                    .collect(),
            )),
            ScalarType::F32 => Samples::F32(Buffer::owned((0..n).map(|i| lum(i) as f32).collect())),
        }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        3 * self.len() * self.scalar_type().size()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u8s(v: &[u8]) -> Samples {
        Samples::U8(Buffer::owned(v.to_vec()))
    }

    #[test]
    fn luminance_weighs_green_most_and_white_stays_white() {
        let rgb = Rgb::new([
            u8s(&[255, 255, 0, 0]),
            u8s(&[255, 0, 255, 0]),
            u8s(&[255, 0, 0, 255]),
        ])
        .unwrap();
        let Samples::U8(l) = rgb.luminance() else {
            panic!("u8 channels give u8 luminance")
        };
        assert_eq!(l.as_slice(), &[255, 54, 182, 18]);
        assert_eq!(rgb.rgb(1, 255.0), [1.0, 0.0, 0.0]);
    }

    #[test]
    fn channels_of_different_lengths_or_types_are_refused() {
        assert!(Rgb::new([u8s(&[1, 2]), u8s(&[1]), u8s(&[1, 2])]).is_err());
        let u16s = Samples::U16(Buffer::owned(vec![1u16, 2]));
        assert!(Rgb::new([u8s(&[1, 2]), u16s, u8s(&[1, 2])]).is_err());
    }
}
