//! The optical model and its integrators.
//!
//! Emission-absorption (`001_...txt` ch. 2): along a ray, colour
//! `C = int c(s(t)) tau(s(t)) T(t) dt` with transparency `T(t) = exp(-int_0^t tau)`, and
//! opacity `A = 1 - T(end)`. Colours are premultiplied, compositing is front to back.
use crate::classify::Classified;

/// Premultiplied RGBA accumulated front to back along a ray.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayAccumulator {
    /// Premultiplied colour and opacity so far.
    pub rgba: [f32; 4],
}

impl RayAccumulator {
    /// Composites a segment of opacity `alpha` and colour `rgb` behind what is accumulated
    /// (front-to-back "under" operator).
    #[inline]
    pub fn under(&mut self, rgb: [f32; 3], alpha: f32) {
        let w = (1.0 - self.rgba[3]) * alpha;
        self.rgba[0] += w * rgb[0];
        self.rgba[1] += w * rgb[1];
        self.rgba[2] += w * rgb[2];
        self.rgba[3] += w;
    }

    /// Accumulated opacity.
    #[inline]
    pub fn alpha(&self) -> f32 {
        self.rgba[3]
    }
}

/// One step of the Riemann sum (`001_...txt` eq. 2.14) with step-corrected opacity: a sample
/// classified as `c` stands for a slab of length `h` (world units) of constant extinction, so
/// its opacity is `1 - exp(-tau h)` and images do not change with `h` except by the
/// integration error.
#[inline]
pub fn riemann_step(acc: &mut RayAccumulator, c: Classified, h: f32) {
    if c.tau > 0.0 {
        acc.under(c.rgb, 1.0 - (-c.tau * h).exp());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Constant colour and extinction: the integral is exactly `c (1 - exp(-tau L))` and the
    /// step-corrected Riemann sum reproduces it for any step.
    #[test]
    fn constant_medium_is_exact_for_any_step() {
        let (tau, len) = (0.7f32, 3.0f32);
        for n in [1, 3, 10, 100] {
            let h = len / n as f32;
            let mut acc = RayAccumulator::default();
            for _ in 0..n {
                riemann_step(
                    &mut acc,
                    Classified {
                        rgb: [1.0, 0.5, 0.0],
                        tau,
                    },
                    h,
                );
            }
            let exact = 1.0 - (-tau * len).exp();
            assert!((acc.alpha() - exact).abs() < 1e-5, "n={n}");
            assert!((acc.rgba[1] - 0.5 * exact).abs() < 1e-5);
        }
    }
}
