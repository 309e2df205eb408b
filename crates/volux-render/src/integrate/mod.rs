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
//!   coupled or decoupled step control, error estimated per channel R, G, B, A, in f64;
//! - [`adaptive_lanes::AdaptiveLanes`]: the same coupled control for four rays at once in f32
//!   lanes, the fast path of renderers that sample several rays together;
//! - [`segment`]: the colour of a segment along which the scalar is linear ([`SegmentRule`]:
//!   average, ψ, exact, adaptive), the one segment integrator of the tetrahedral renderers;
//! - [`psi`]: partial pre-integration (the ψ table, the TF lookup of cells, average and ψ
//!   fragment colours);
//! - [`preintegrated`]: the grid's pre-integration table over (front, back) values.
use crate::classify::Classified;
use crate::composite::RayAccumulator;

pub mod adaptive;
pub mod adaptive_lanes;
pub mod fixed;
pub mod preintegrated;
pub mod psi;
pub mod segment;

pub use adaptive::{
    adaptive_simpson, adaptive_simpson_intervals, adaptive_simpson_pieces, AdaptiveParams,
    StepControl,
};
pub use fixed::{fixed_intervals, simpson, trapezoid, FixedRule};
pub use segment::{SegmentIntegrator, SegmentRule};

/// How rays are integrated; lengths are in voxel units (of the smallest grid spacing), as in
/// the seed, and converted to world units by the traversal.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Integrator {
    /// Left Riemann sum with step-corrected opacity.
    Riemann {
        /// Step.
        step: f64,
    },
    /// Fixed-step trapezoid rule.
    Trapezoid {
        /// Step.
        step: f64,
    },
    /// Fixed-step Simpson rule.
    Simpson {
        /// Step.
        step: f64,
    },
    /// Iterative adaptive Simpson with error control.
    AdaptiveSimpson(AdaptiveParams),
    /// Pre-integrated classification: each step's colour and opacity looked up in a table
    /// over (front value, back value), exact for a linear field within the step.
    Preintegrated {
        /// Step.
        step: f64,
    },
    /// The f64 ground truth: adaptive Simpson at a tolerance of 1e-7, exact classification,
    /// f64 reconstruction, and steps that never straddle a voxel boundary (where the
    /// trilinear field has a kink), so the result is accurate to about 1e-6.
    Reference,
}

impl Integrator {
    /// The adaptive parameters of the reference integrator (voxel units).
    pub const REFERENCE: AdaptiveParams = AdaptiveParams {
        tol: 1e-7,
        h0: 0.25,
        hmin: 1e-5,
        hmax: 0.5,
        control: StepControl::Coupled,
        early_termination: None,
    };

    /// The CLI name.
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Riemann { .. } => "riemann",
            Integrator::Trapezoid { .. } => "trapezoid",
            Integrator::Simpson { .. } => "simpson",
            Integrator::AdaptiveSimpson(p) if p.control == StepControl::Coupled => {
                "adaptive-coupled"
            }
            Integrator::AdaptiveSimpson(_) => "adaptive-decoupled",
            Integrator::Preintegrated { .. } => "preintegrated",
            Integrator::Reference => "reference",
        }
    }

    /// Checks steps and tolerances.
    pub fn validate(&self) -> Result<(), String> {
        let pos = |name: &str, v: f64| {
            if v.is_finite() && v >= 1e-6 {
                Ok(())
            } else {
                Err(format!("{name} {v} must be >= 1e-6"))
            }
        };
        match self {
            Integrator::Riemann { step }
            | Integrator::Trapezoid { step }
            | Integrator::Simpson { step }
            | Integrator::Preintegrated { step } => pos("step", *step),
            Integrator::AdaptiveSimpson(p) => {
                pos("h0", p.h0)?;
                pos("hmin", p.hmin)?;
                pos("hmax", p.hmax)?;
                if !(p.tol.is_finite() && p.tol > 0.0) {
                    return Err(format!("tolerance {} must be > 0", p.tol));
                }
                if p.hmin > p.hmax {
                    return Err(format!("hmin {} must not exceed hmax {}", p.hmin, p.hmax));
                }
                Ok(())
            }
            Integrator::Reference => Ok(()),
        }
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

    /// The medium at four distances; media that can compute them together (lane-wise
    /// reconstruction) override it.
    fn at4(&mut self, t: [f64; 4]) -> [Medium; 4] {
        t.map(|t| self.at(t))
    }

    /// Whether the classification may vary in a way samples at scalar values `a` and `b`
    /// cannot see (e.g. a transfer-function peak lies strictly between them). Adaptive
    /// integration refines such steps down to `hmin` instead of trusting its error estimate.
    fn hides_features(&self, _a: f64, _b: f64) -> bool {
        false
    }

    /// Whether [`RayMedium::hides_features`] holds between any two neighbouring samples of
    /// `values` (in ray order); media override it to answer for all pairs at once.
    fn hides_features_along(&self, values: &[f64; 5]) -> bool {
        values.windows(2).any(|w| self.hides_features(w[0], w[1]))
    }
}

/// Whether two or more of the sorted `breakpoints` lie strictly between `a` and `b`: the
/// piecewise-linear classification then has a peak or valley no sample shows.
pub fn hides_breakpoints(breakpoints: &[f64], a: f64, b: f64) -> bool {
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    // Adaptive integration asks this for every pair of neighbouring samples: for the few
    // breakpoints of a usual TF, branch-free counts beat a binary search's mispredictions.
    let (first, last) = if breakpoints.len() <= 32 {
        breakpoints.iter().fold((0, 0), |(f, l), &x| {
            (f + usize::from(x <= lo), l + usize::from(x < hi))
        })
    } else {
        (
            breakpoints.partition_point(|&x| x <= lo),
            breakpoints.partition_point(|&x| x < hi),
        )
    };
    last >= first + 2
}

/// [`hides_breakpoints`] for every pair of neighbouring `values`: each value's rank among
/// the breakpoints is counted once rather than once per pair it belongs to.
pub fn hides_breakpoints_along<const N: usize>(breakpoints: &[f64], values: &[f64; N]) -> bool {
    if breakpoints.len() < 2 {
        return false;
    }
    if breakpoints.len() > 32 {
        return values
            .windows(2)
            .any(|w| hides_breakpoints(breakpoints, w[0], w[1]));
    }
    // Breakpoints at or below each value, and strictly below it.
    let (mut at_or_below, mut below) = ([0usize; N], [0usize; N]);
    for &x in breakpoints {
        for k in 0..N {
            at_or_below[k] += usize::from(x <= values[k]);
            below[k] += usize::from(x < values[k]);
        }
    }
    (1..N).any(|k| {
        let (lo, hi) = if values[k - 1] <= values[k] {
            (k - 1, k)
        } else {
            (k, k - 1)
        };
        below[hi] >= at_or_below[lo] + 2
    })
}

/// Colour and extinction at one point of a ray, in f64 for the accurate integrators.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Medium {
    /// Linear RGB emission.
    pub rgb: [f64; 3],
    /// Extinction per world unit.
    pub tau: f64,
    /// The scalar value classified (for [`RayMedium::hides_features`]); 0 when unknown.
    pub value: f64,
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
