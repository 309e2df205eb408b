//! Compositing: the front-to-back *under* operator on premultiplied RGBA, in `f32` (fragment
//! lists) and `f64` (rays, references and accurate integrators), the one place every renderer
//! composites.
//!
//! A ray's sum is kept in `f64` ([`RayAccumulator`], [`under_if64`]) though its samples'
//! colours are `f32`: a chain of hundreds of `f32` *under* steps drifts by about 1e-6 (each
//! step rounds to half an ulp of 1), and the same ray composited in pieces (bricks, ranks,
//! `003`) drifts differently; in `f64` both are the exact sum of the same `f32` terms to
//! well below an `f32` ulp.
//!
//! A ray (or a pixel's list of fragments) is accumulated front to back: what lies behind is
//! weighted by the transparency `1 - A` left in front of it,
//! `C += (1 - A) c`, `A += (1 - A) a` (premultiplied `c`). It is the seeds' back-to-front
//! *over* operator taken in the reverse order (seed `000` §4.3, seed `001` eq. 2.14), chosen
//! so that a ray or pixel can stop once it is opaque (early termination).

/// Composites `rgba` (premultiplied) behind `acc` (front-to-back *under*), `f32`.
#[inline(always)]
pub fn under(acc: &mut [f32; 4], rgba: [f32; 4]) {
    let w = 1.0 - acc[3];
    acc[0] += w * rgba[0];
    acc[1] += w * rgba[1];
    acc[2] += w * rgba[2];
    acc[3] += w * rgba[3];
}

/// [`under`] when `defined`; nothing otherwise (an undefined sample is empty medium). Written
/// without a branch for the lane loops.
#[inline(always)]
pub fn under_if(acc: &mut [f32; 4], rgba: [f32; 4], defined: bool) {
    let w = if defined { 1.0 - acc[3] } else { 0.0 };
    for c in 0..4 {
        acc[c] += w * rgba[c];
    }
}

/// [`under_if`] into an `f64` sum: the `f32` entry `rgba` composited when `defined`.
#[inline(always)]
pub fn under_if64(acc: &mut [f64; 4], rgba: [f32; 4], defined: bool) {
    let w = if defined { 1.0 - acc[3] } else { 0.0 };
    for c in 0..4 {
        acc[c] += w * f64::from(rgba[c]);
    }
}

/// Composites `rgba` (premultiplied) behind `acc` (front-to-back *under*), `f64`.
#[inline(always)]
pub fn under64(acc: &mut [f64; 4], rgba: [f64; 4]) {
    let w = 1.0 - acc[3];
    for c in 0..4 {
        acc[c] += w * rgba[c];
    }
}

/// Front-to-back composite of `pieces` (premultiplied, front first), `f64`.
pub fn composite64(pieces: impl IntoIterator<Item = [f64; 4]>) -> [f64; 4] {
    let mut acc = [0.0; 4];
    for p in pieces {
        under64(&mut acc, p);
    }
    acc
}

/// Premultiplied RGBA accumulated front to back along a ray, in `f64` (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayAccumulator {
    /// Premultiplied colour and opacity so far.
    pub rgba: [f64; 4],
}

impl RayAccumulator {
    /// Composites a segment of opacity `alpha` and (not premultiplied) colour `rgb` behind
    /// what is accumulated (front-to-back *under*).
    #[inline]
    pub fn under(&mut self, rgb: [f32; 3], alpha: f32) {
        let w = (1.0 - self.rgba[3]) * f64::from(alpha);
        self.rgba[0] += w * f64::from(rgb[0]);
        self.rgba[1] += w * f64::from(rgb[1]);
        self.rgba[2] += w * f64::from(rgb[2]);
        self.rgba[3] += w;
    }

    /// Accumulated opacity.
    #[inline]
    pub fn alpha(&self) -> f64 {
        self.rgba[3]
    }

    /// The sum as an image's `f32` pixel.
    #[inline]
    pub fn pixel(&self) -> [f32; 4] {
        self.rgba.map(|v| v as f32)
    }
}

/// Composites under `acc` a pre-integrated segment of premultiplied RGBA `e` (for the table's
/// length) that covers the fraction `frac` of that length: the opacity of a shortened segment
/// is `1 - (1 - alpha)^frac` (its optical depth scaled), its colour scaled with it.
#[inline]
pub fn under_partial(acc: &mut RayAccumulator, e: [f32; 4], frac: f32) {
    let alpha = if frac < 0.999_999 {
        1.0 - (1.0 - e[3]).max(0.0).powf(frac)
    } else {
        e[3]
    };
    let scale = if e[3] > 0.0 { alpha / e[3] } else { frac };
    let w = 1.0 - acc.rgba[3];
    for (a, ec) in acc.rgba.iter_mut().zip(&e[..3]) {
        *a += w * f64::from(ec * scale);
    }
    acc.rgba[3] += w * f64::from(alpha);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn under_is_over_in_reverse_order() {
        let layers = [
            [0.2, 0.1, 0.0, 0.3],
            [0.0, 0.4, 0.1, 0.5],
            [0.6, 0.6, 0.6, 0.9],
        ];
        let front_to_back = composite64(layers);
        // Back to front with "over": C = c + (1 - a) C.
        let mut back_to_front = [0.0f64; 4];
        for l in layers.iter().rev() {
            for c in 0..4 {
                back_to_front[c] = l[c] + (1.0 - l[3]) * back_to_front[c];
            }
        }
        for c in 0..4 {
            assert!((front_to_back[c] - back_to_front[c]).abs() < 1e-12);
        }
        let mut acc = [0.0f32; 4];
        for l in layers {
            under(&mut acc, l.map(|v| v as f32));
        }
        for c in 0..4 {
            assert!((f64::from(acc[c]) - front_to_back[c]).abs() < 1e-6);
        }
    }

    #[test]
    fn undefined_samples_add_nothing() {
        let mut acc = [0.1, 0.2, 0.3, 0.4];
        under_if(&mut acc, [1.0; 4], false);
        assert_eq!(acc, [0.1, 0.2, 0.3, 0.4]);
        under_if(&mut acc, [0.5; 4], true);
        assert!((acc[3] - 0.7).abs() < 1e-6);
    }

    #[test]
    fn a_partial_segment_scales_its_optical_depth() {
        // Half of a segment of opacity 0.75 has opacity 0.5.
        let mut acc = RayAccumulator::default();
        under_partial(&mut acc, [0.75, 0.0, 0.0, 0.75], 0.5);
        assert!((acc.rgba[3] - 0.5).abs() < 1e-6 && (acc.rgba[0] - 0.5).abs() < 1e-6);
        let mut whole = RayAccumulator::default();
        under_partial(&mut whole, [0.75, 0.0, 0.0, 0.75], 1.0);
        assert_eq!(whole.pixel(), [0.75, 0.0, 0.0, 0.75]);
    }
}
