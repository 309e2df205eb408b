//! The optical model and its integrators.
//!
//! Emission-absorption (`001_...txt` ch. 2, eq. 2.13): along a ray, colour
//! `C = int_0^D c(s(t)) tau(s(t)) T(t) dt` with transparency `T(t) = exp(-int_0^t tau)` (the
//! *inner* integral) and opacity `A = 1 - T(D)`; the colour integral is the *outer* one.
//! Colours are premultiplied; compositing is front to back.
//!
//! Every integrator sees the ray only through a [`RayMedium`]: the classified medium at
//! distance `t`. Traversals (grid ray casting, tet ray casting) supply it, so one
//! implementation of each rule serves all renderers.
//!
//! - [`riemann`]: left Riemann sum with step-corrected opacity (eq. 2.14), order 1;
//! - [`fixed::trapezoid`], [`fixed::simpson`]: fixed-step rules, orders 2 and 4;
//! - [`adaptive::adaptive_simpson`]: the iterative adaptive Simpson of Algorithms 3 and 4,
//!   coupled or decoupled step control, error estimated per channel R, G, B, A.
use crate::classify::Classified;

pub mod adaptive;
pub mod fixed;

pub use adaptive::{adaptive_simpson, AdaptiveParams, StepControl};
pub use fixed::{simpson, trapezoid};

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

/// The medium along one ray, as the integrators see it.
pub trait RayMedium {
    /// Colour (linear RGB) and extinction per world unit at distance `t` along the ray.
    fn at(&mut self, t: f64) -> Medium;
}

/// Colour and extinction at one point of a ray, in f64 for the accurate integrators.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Medium {
    /// Linear RGB emission.
    pub rgb: [f64; 3],
    /// Extinction per world unit.
    pub tau: f64,
}

impl<F: FnMut(f64) -> Medium> RayMedium for F {
    fn at(&mut self, t: f64) -> Medium {
        self(t)
    }
}

/// The result of integrating one ray.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayIntegral {
    /// Premultiplied RGBA.
    pub rgba: [f64; 4],
    /// Samples of the medium taken.
    pub samples: u64,
    /// Estimated absolute error (largest channel), where the integrator estimates it.
    pub error: f64,
    /// Whether some step was accepted only because it reached `hmin` (tolerance not met).
    pub tolerance_missed: bool,
}

impl RayIntegral {
    pub(crate) fn from_parts(c: [f64; 3], depth: f64, samples: u64) -> Self {
        Self {
            rgba: [c[0], c[1], c[2], 1.0 - (-depth).exp()],
            samples,
            ..Default::default()
        }
    }
}

/// Left Riemann sum with step-corrected opacity over `[t0, t1]` with step `h` (eq. 2.14):
/// samples at `t0 + i h`, the last step shortened to end at `t1`. Order 1.
pub fn riemann(m: &mut impl RayMedium, t0: f64, t1: f64, h: f64) -> RayIntegral {
    let (mut c, mut trans, mut n) = ([0.0; 3], 1.0f64, 0u64);
    let mut t = t0;
    while t < t1 {
        let len = h.min(t1 - t);
        let s = m.at(t);
        n += 1;
        let a = 1.0 - (-s.tau * len).exp();
        for (ck, rk) in c.iter_mut().zip(s.rgb) {
            *ck += trans * a * rk;
        }
        trans *= 1.0 - a;
        t += h;
    }
    RayIntegral {
        rgba: [c[0], c[1], c[2], 1.0 - trans],
        samples: n,
        ..Default::default()
    }
}

#[cfg(test)]
pub(crate) mod tests;
