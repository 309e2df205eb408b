//! Fragment colour models for cell projection (Projected Tetrahedra): the Shirley-Tuchman
//! average and Moreland-Angel partial pre-integration with the `psi` table.
//!
//! A PT rasterizer knows per fragment the scalar where the ray enters the cell (`s_f`), where
//! it leaves it (`s_b`) and the thickness `l` (world units) in between, the scalar linear
//! along the ray. Both models turn these into premultiplied RGBA for front-to-back
//! compositing, using the transfer function only at `s_f` and `s_b`
//! ([`CellClassifier::lookup`]: colour `c` and extinction `tau` per world unit). The exact
//! answer, for any TF, is [`SegmentIntegrator::integrate`](super::segment::SegmentIntegrator::integrate).
//!
//! # Shirley-Tuchman average ([`average_fragment`])
//!
//! Thesis `000_...txt`, section 2.3, eqs. 2.2 and 2.3 (after Shirley and Tuchman 1990):
//!
//! ```text
//! C = (C(s_f) + C(s_b)) / 2                       (2.2)
//! alpha = 1 - exp(-l (tau(s_f) + tau(s_b)) / 2)   (2.3)
//! ```
//!
//! composited as `C_new = alpha C + (1 - alpha) C_old` (eq. 2.4), i.e. premultiplied
//! `[alpha C, alpha]`. The opacity is exact when `tau` is linear along the segment (the
//! trapezoid gives the optical depth of a linear function exactly); the colour is not: with
//! `dc = c_b - c_f`, `dtau = tau_b - tau_f`, the exact colour is
//! `l (c_f tau_f + (c_f dtau + tau_f dc) / 2 + dc dtau / 3) + O(l^2)` and eq. 2.2 puts
//! `dc dtau / 4` in place of `dc dtau / 3`, so the error is `-l dc dtau / 12 + O(l^2)`
//! (tested), and `O(1)` for thick cells, where the exact colour tends to the front colour
//! while eq. 2.2 keeps the mean (measured up to `0.24` on linear TFs). For a constant medium
//! (`s_f == s_b`) it is exact.
//!
//! # Partial pre-integration ([`psi_fragment`])
//!
//! Moreland and Angel 2004 ("A fast high accuracy volume renderer for unstructured data"):
//! integrate exactly assuming colour and extinction *linear along the segment*,
//! `c(t) = c_f + (c_b - c_f) t / l`, `tau(t) = tau_f + (tau_b - tau_f) t / l`, which is exact
//! when the TF is linear between `s_f` and `s_b`. Derivation, front to back with the
//! transparency `T(t) = exp(-int_0^t tau)` seen from the front (`T(0) = 1`):
//!
//! ```text
//! C = int_0^l c(t) tau(t) T(t) dt          and   tau T = -dT/dt, so by parts
//!   = [-c T]_0^l + int_0^l c'(t) T(t) dt
//!   = c_f - c_b zeta + (c_b - c_f) psi
//!   = c_f (1 - psi) + c_b (psi - zeta),          A = 1 - zeta,
//! zeta = T(l) = exp(-l (tau_f + tau_b) / 2),
//! psi  = (1/l) int_0^l T dt = int_0^1 exp(-(a x + (b - a) x^2 / 2)) dx,  a = tau_f l, b = tau_b l.
//! ```
//!
//! `psi` is the mean transparency of the segment, so `zeta <= psi <= 1` and both colour
//! weights are non-negative and sum to `A`: the fragment colour `C / A` is a convex
//! combination of `c_f` and `c_b`. The front colour carries `1 - psi`, the back colour
//! `psi - zeta`; an optically thick cell (`psi -> 0`) shows its front colour, a thin one a
//! mix weighted about 2:1 towards the front. `psi` depends on the thicknesses `a`, `b` only,
//! not on the TF, so it is tabulated once ([`PsiTable`]); it is not symmetric (`a` is the
//! front). Checked numerically: [`psi_segment`] (this formula in f64 with [`psi_exact`])
//! equals [`SegmentIntegrator::integrate`](super::segment::SegmentIntegrator::integrate)
//! to `6.7e-16` on 400 random segments of TFs linear between `s_f` and `s_b` (thicknesses up
//! to 1000); [`psi_fragment`] (f32, tables) to `8.0e-7`.
//!
//! When TF breakpoints lie between `s_f` and `s_b` the model sees only the end values and
//! misses what happens in between (e.g. a peak): over 249 random segments of random
//! piecewise-linear TFs with breakpoints inside, [`psi_fragment`] is off by `0.089` on average
//! and `0.74` at worst (the average model by `0.14` and `0.64`); splitting the segment at the
//! breakpoints and compositing [`psi_segment`] pieces brings it back to `4e-10`.
//!
//! ## `psi_exact`
//!
//! 8-point Gauss-Legendre on sub-intervals over which the depth grows by at most 2 and its
//! quadratic part `|b - a| h^2 / 2` by at most `1/2` (Gaussian-like integrands need the
//! latter), stopped at depth 60. Measured: `2.1e-15` relative error (splitting identity, over
//! thicknesses up to `1e9`), `6.6e-16` against the closed form `(1 - exp(-a)) / a` of constant
//! extinction over `1e-12 ..= 1e12`, and within `2e-13` of a `2e5`-step Simpson rule (its own
//! error) for thicknesses up to `1e3`. A closed form exists (`erf` for `b > a`, Dawson's
//! function for `b < a`) but needs special functions std lacks and suffers cancellation.
//!
//! ## The table
//!
//! Moreland and Angel index the table by `gamma = tau l / (tau l + 1)` on both axes
//! ([`gamma`], [`PsiTable::psi`]). Uniform nodes in `gamma` interpolate badly near
//! `gamma_b -> 1`, where `psi ~ sqrt(pi (1 - gamma_b) / 2)` has an infinite slope: measured
//! maximum bilinear error `2.0e-2`, `1.4e-2`, `9.8e-3` for `n = 256, 512, 1024` nodes per axis
//! (it decreases only like `sqrt(1 / n)`). The nodes here are uniform in
//! `v = 1 - sqrt(1 - gamma) = 1 - 1 / sqrt(1 + tau l)` instead, in which `psi` is linear
//! near that edge: maximum errors `4.9e-4`, `2.4e-4`, `1.2e-4` (order 1, the worst cells where
//! both thicknesses exceed 500 and `psi < 2e-3`). Chosen: `n = 512` (1 MiB of f32), with
//! measured errors (tests, against [`psi_exact`]):
//!
//! | where | max abs error of `psi` |
//! |---|---|
//! | nodes | `3.2e-7` (f32 rounding of the inputs) |
//! | 511^2 cell centres | `2.3e-4`; `3.3e-6` where both thicknesses `<= 100` |
//! | `1e5` random points, thickness log-uniform in `[1e-4, 1e6]` | `2.3e-4`; `3.2e-6` where `<= 100` |
//! | [`PsiTable::psi`] at random `gamma <= 0.999` | `3.7e-6` |
//!
//! The table stores `1 - psi`, the front colour's weight, so that thin cells keep their
//! relative precision; still, bilinear interpolation from the zero at the origin leaves a
//! relative error of `2.3e-3` in `1 - psi` for cells with `a + b < 0.1`. The fragment path
//! therefore uses the Taylor series of `1 - psi` when `a + b < 1/8` (measured `2.6e-7`
//! relative) and the table above. Building the table takes about 0.1 s (2 shared cores).
//!
//! # Per-fragment front end
//!
//! [`CellClassifier`] tabulates `[r, g, b, tau]` at 4096 values over the data range and all
//! breakpoints, interpolated linearly: exact (to f32) between breakpoints, and within
//! `h |slope jump| / 4` (`h` the entry spacing) in an interval containing a breakpoint. For a
//! TF with kinks of extinction slope up to `0.75` per value unit over a range of 100 the
//! measured error is `4.6e-3` in `tau` (bound `4.6e-3`) and `2.2e-4` in colour. Where the
//! values of a cell's fragments all lie in a range without breakpoints (its vertex range),
//! [`CellClassifier::linear_on`] gives the TF there as one [`LinearPiece`] instead, exact to
//! f32 (measured `1.7e-7` on random TFs) and cheaper than the table: PT shades such cells
//! with it, without lookups or breakpoint search.
//! [`average_fragment`] and [`psi_fragment`] are f32, allocation-free and written without
//! data-dependent branches apart from the input check and the choice between the thin-cell
//! series and the table (a branch: neighbouring fragments have similar thicknesses, so it is
//! predicted well, and thin cells skip the table's square roots, division and loads); the
//! opacity uses a range-reduced `1 - exp(-d)` with `7.3e-8` relative error (measured over
//! `d` in `[1e-30, 8e20]`). Measured cost (release, the ignored test `psi_fragment_timing`,
//! one core of a shared 2-core AMD EPYC VM at 2.6 GHz, 2^20 fragments): [`psi_fragment`]
//! 36 ns per call on coherent inputs (slowly varying, as in rasterization) and 40 ns on
//! random ones (43 and 46 ns when both were evaluated and one selected);
//! [`average_fragment`] 18 and 20 ns.
use rayon::prelude::*;
use volux_core::TransferFunction;

use super::segment::{GL_W, GL_X};

pub mod lanes;

/// Default [`PsiTable`] resolution (nodes per axis).
pub const PSI_TABLE_SIZE: usize = 512;

/// Largest accepted [`PsiTable`] resolution (`4096^2` f32 nodes: 64 MiB).
pub const MAX_PSI_TABLE_SIZE: usize = 4096;

/// Largest optical-depth increase per Gauss-Legendre sub-interval in [`psi_exact`].
const DEPTH_STEP: f64 = 2.0;

/// Largest `|k| h^2` (the quadratic part of the depth) per sub-interval in [`psi_exact`]:
/// Gaussian-like integrands need shorter sub-intervals than exponential ones (with `|k| h^2`
/// up to 2 the 8-point rule is off by `1e-12`, measured).
const QUADRATIC_STEP: f64 = 0.5;

/// [`psi_exact`] stops integrating once the transparency is below `exp(-60)`.
const MAX_DEPTH: f64 = 60.0;

/// Safety bound on the sub-intervals of [`psi_exact`] (about `MAX_DEPTH / DEPTH_STEP + 1`
/// are needed).
const MAX_SUBINTERVALS: usize = 1 << 12;

/// Optical thicknesses above this are clamped by [`gamma`] (keeps `t / (t + 1)` from becoming
/// `inf / inf`).
const MAX_F32_DEPTH: f32 = 1e30;

/// Below this sum of the end thicknesses `a + b` the fragment's `1 - psi` comes from its
/// Taylor series ([`one_minus_psi_series`]) instead of the table.
const THIN: f32 = 0.125;

/// The length `h` over which the depth `d h + k h^2` grows by `delta` (infinite when it
/// never does), the smaller positive root computed without cancellation.
#[inline]
fn step_for_depth(d: f64, k: f64, delta: f64) -> f64 {
    let disc = d * d + 4.0 * k * delta;
    if disc.is_nan() || disc < 0.0 {
        return f64::INFINITY;
    }
    let den = d + disc.sqrt();
    if den > 0.0 {
        2.0 * delta / den
    } else {
        f64::INFINITY
    }
}

/// The `psi` function of partial pre-integration: the mean transparency
/// `psi(a, b) = int_0^1 exp(-(a x + (b - a) x^2 / 2)) dx` of a segment whose extinction goes
/// linearly from `tau_f` to `tau_b`, given its optical thicknesses `a = tau_l_f = tau_f l` and
/// `b = tau_l_b = tau_b l` (see the module documentation). Not symmetric: `a` is the front.
///
/// Accurate to about `1e-15` relative (8-point Gauss-Legendre on sub-intervals over which the
/// depth grows by at most 2, the integral stopped at depth 60; measured in the tests).
/// Negative thicknesses are read as 0 (`psi(0, 0) = 1`), an infinite one gives 0, NaN gives
/// NaN.
pub fn psi_exact(tau_l_f: f64, tau_l_b: f64) -> f64 {
    if tau_l_f.is_nan() || tau_l_b.is_nan() {
        return f64::NAN;
    }
    let (a, b) = (tau_l_f.max(0.0), tau_l_b.max(0.0));
    if a == f64::INFINITY || b == f64::INFINITY {
        // Infinite extinction everywhere past the front point.
        return 0.0;
    }
    if a == 0.0 && b == 0.0 {
        return 1.0;
    }
    // q(x) = a x + k x^2, q'(x) = a + (b - a) x >= 0 on [0, 1].
    let k = 0.5 * (b - a);
    let (mut x0, mut q0, mut sum) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..MAX_SUBINTERVALS {
        let d = (a + (b - a) * x0).max(0.0);
        let rest = 1.0 - x0;
        let h = step_for_depth(d, k, DEPTH_STEP).min((QUADRATIC_STEP / k.abs()).sqrt());
        let last = h.is_nan() || h >= rest || x0 + h <= x0;
        let h = if last { rest } else { h };
        let half = 0.5 * h;
        let f = |u: f64| (-(d * u + k * u * u)).exp();
        let mut s = 0.0;
        for (x, w) in GL_X.iter().zip(GL_W) {
            s += w * (f(half * (1.0 - x)) + f(half * (1.0 + x)));
        }
        sum += (-q0).exp() * half * s;
        q0 += d * h + k * h * h;
        x0 += h;
        if last || q0 > MAX_DEPTH {
            break;
        }
    }
    sum
}

/// Moreland and Angel's exact premultiplied RGBA `[C_r, C_g, C_b, A]` of a segment of length
/// `l` whose colour goes linearly from `c_f` to `c_b` and extinction (per world unit) from
/// `tau_f` to `tau_b`: `C = c_f (1 - psi) + c_b (psi - zeta)`, `A = 1 - zeta` (see the module
/// documentation), in f64 with [`psi_exact`]. Transparent black when an argument is not
/// finite or `l <= 0`; negative extinction is read as 0.
pub fn psi_segment(c_f: [f64; 3], tau_f: f64, c_b: [f64; 3], tau_b: f64, l: f64) -> [f64; 4] {
    let finite = c_f.iter().chain(&c_b).all(|v| v.is_finite())
        && tau_f.is_finite()
        && tau_b.is_finite()
        && l.is_finite();
    if !(finite && l > 0.0) {
        return [0.0; 4];
    }
    let (a, b) = (tau_f.max(0.0) * l, tau_b.max(0.0) * l);
    let alpha = -(-0.5 * (a + b)).exp_m1();
    let w = (1.0 - psi_exact(a, b)).clamp(0.0, alpha);
    let wb = alpha - w;
    [
        c_f[0] * w + c_b[0] * wb,
        c_f[1] * w + c_b[1] * wb,
        c_f[2] * w + c_b[2] * wb,
        alpha,
    ]
}

/// The Shirley-Tuchman average (thesis `000_...txt` section 2.3, eqs. 2.2 and 2.3) in f64:
/// colour `(c_f + c_b) / 2`, opacity `A = 1 - exp(-l (tau_f + tau_b) / 2)`, returned
/// premultiplied as `[A C_r, A C_g, A C_b, A]`. Transparent black when an argument is not
/// finite or `l <= 0`; negative extinction is read as 0.
pub fn average_segment(c_f: [f64; 3], tau_f: f64, c_b: [f64; 3], tau_b: f64, l: f64) -> [f64; 4] {
    let finite = c_f.iter().chain(&c_b).all(|v| v.is_finite())
        && tau_f.is_finite()
        && tau_b.is_finite()
        && l.is_finite();
    if !(finite && l > 0.0) {
        return [0.0; 4];
    }
    let alpha = -(-0.5 * l * (tau_f.max(0.0) + tau_b.max(0.0))).exp_m1();
    let m = 0.5 * alpha;
    [
        (c_f[0] + c_b[0]) * m,
        (c_f[1] + c_b[1]) * m,
        (c_f[2] + c_b[2]) * m,
        alpha,
    ]
}

/// `x` clamped to `[lo, hi]`, NaN mapped to `lo` (unlike `f32::clamp`, which keeps NaN).
#[inline(always)]
fn clamp_or_lo(x: f32, lo: f32, hi: f32) -> f32 {
    if x > lo {
        x.min(hi)
    } else {
        lo
    }
}

/// The normalized optical thickness `gamma = tau l / (tau l + 1)` in `[0, 1]` that indexes
/// the `psi` table (Moreland and Angel); `gamma = 1` for infinite thickness, 0 for negative
/// or NaN.
#[inline]
pub fn gamma(tau_l: f32) -> f32 {
    let t = clamp_or_lo(tau_l, 0.0, MAX_F32_DEPTH);
    t / (t + 1.0)
}

/// Thicknesses above this are clamped when mapped to table coordinates: `v` is then within
/// `3.2e-8` of 1, which rounds to 1 in f32.
const MAX_COORD_DEPTH: f32 = 1e15;

/// Table coordinates `v = 1 - sqrt(1 - gamma) = 1 - 1 / sqrt(1 + tau l)` of two optical
/// thicknesses, as `tau l / (r (r + 1))` with `r = sqrt(1 + tau l)` (no cancellation) and one
/// division for both; NaN and negative give 0, infinite gives 1.
#[inline(always)]
fn coords_of_depths(tau_l_f: f32, tau_l_b: f32) -> (f32, f32) {
    let (tf, tb) = (
        clamp_or_lo(tau_l_f, 0.0, MAX_COORD_DEPTH),
        clamp_or_lo(tau_l_b, 0.0, MAX_COORD_DEPTH),
    );
    let (rf, rb) = ((1.0 + tf).sqrt(), (1.0 + tb).sqrt());
    let (pf, pb) = (rf * (rf + 1.0), rb * (rb + 1.0));
    let inv = 1.0 / (pf * pb);
    (tf * pb * inv, tb * pf * inv)
}

/// Table coordinate of a normalized thickness `gamma` (see [`coords_of_depths`]); NaN stays NaN.
#[inline]
fn coord_of_gamma(gamma: f32) -> f32 {
    let g = gamma.clamp(0.0, 1.0);
    g / (1.0 + (1.0 - g).sqrt())
}

/// `1 - exp(-d)` in f32 for `d >= 0` (NaN and negative read as 0), branch-free and with full
/// relative precision for thin cells, where `1 - exp(-d)` in f32 would lose the leading
/// digits. Range reduction `d = k ln 2 + r`, `|r| <= ln 2 / 2`, then
/// `1 - exp(-d) = (1 - 2^-k) - 2^-k expm1(-r)` with `expm1` by its degree-7 Taylor polynomial
/// (truncation below `6e-9` relative). Measured against f64 `expm1` (tests): at most `7.3e-8`
/// relative error over `d` in `[1e-30, 8e20]`. A series-or-`exp` branch mispredicts on mixed
/// fragments (measured +12 ns per fragment on random inputs) and f64 `exp` costs +5 ns.
#[inline(always)]
fn opacity(d: f32) -> f32 {
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    // Above 87, exp(-d) < 2^-125: opaque to f32 precision.
    let d = clamp_or_lo(d, 0.0, 87.0);
    let k = (d * std::f32::consts::LOG2_E + 0.5) as i32;
    let kf = k as f32;
    let x = -((d - kf * LN2_HI) - kf * LN2_LO);
    // Estrin's scheme (shorter dependency chain than Horner's).
    let (x2, x4) = (x * x, x * x * x * x);
    let p01 = 0.5 + x * (1.0 / 6.0);
    let p23 = 1.0 / 24.0 + x * (1.0 / 120.0);
    let p45 = 1.0 / 720.0 + x * (1.0 / 5040.0);
    let em = x + x2 * (p01 + x2 * p23 + x4 * p45);
    let scale = f32::from_bits(((127 - k) as u32) << 23);
    (1.0 - scale) - scale * em
}

/// `1 - psi(a, b)` for thin segments (`a + b < THIN`) by the Taylor series
/// `1 - psi = I1 - I2 / 2 + I3 / 6 - I4 / 24 + ...` with `In = int_0^1 q(x)^n dx`,
/// `q = a x + k x^2`, `k = (b - a) / 2`; the first omitted term is below `((a + b) / 2)^5 / 120`,
/// i.e. `1.3e-7` relative to `1 - psi >= (a + b) / 6`.
#[inline(always)]
fn one_minus_psi_series(a: f32, b: f32) -> f32 {
    const THIRD: f32 = 1.0 / 3.0;
    const SEVENTH: f32 = 1.0 / 7.0;
    const NINTH: f32 = 1.0 / 9.0;
    const SIXTH: f32 = 1.0 / 6.0;
    const TWENTY_FOURTH: f32 = 1.0 / 24.0;
    let k = 0.5 * (b - a);
    let (a2, k2, ak) = (a * a, k * k, a * k);
    let i1 = 0.5 * a + THIRD * k;
    let i2 = THIRD * a2 + 0.5 * ak + 0.2 * k2;
    let i3 = a2 * (0.25 * a + 0.6 * k) + k2 * (0.5 * a + SEVENTH * k);
    let i4 =
        a2 * (0.2 * a2 + 2.0 * THIRD * a * k + 6.0 * SEVENTH * k2) + k2 * (0.5 * ak + NINTH * k2);
    i1 - 0.5 * i2 + SIXTH * i3 - TWENTY_FOURTH * i4
}

/// Moreland and Angel's `psi` table: `1 - psi` sampled on an `n x n` grid over the front and
/// back optical thicknesses, independent of the transfer function, with bilinear lookups
/// (see the module documentation for the node placement and its measured error).
#[derive(Clone, Debug, PartialEq)]
pub struct PsiTable {
    /// Row-major `1 - psi`: node `(i, j)` at `i * n + j`, `i` the front, `j` the back.
    one_minus_psi: Vec<f32>,
    n: usize,
}

impl Default for PsiTable {
    fn default() -> Self {
        Self::new()
    }
}

impl PsiTable {
    /// The table with [`PSI_TABLE_SIZE`] nodes per axis (about 0.1 s on 2 cores; build it
    /// once and share it).
    pub fn new() -> Self {
        Self::with_size(PSI_TABLE_SIZE)
    }

    /// The table with `n` nodes per axis, `n` clamped to `2..=MAX_PSI_TABLE_SIZE`; rows are
    /// computed in parallel.
    pub fn with_size(n: usize) -> Self {
        let n = n.clamp(2, MAX_PSI_TABLE_SIZE);
        let depth = |i: usize| {
            // v = 1 - 1 / sqrt(1 + tau l)  <=>  tau l = 1 / (1 - v)^2 - 1.
            let v = i as f64 / (n - 1) as f64;
            if i + 1 == n {
                f64::INFINITY
            } else {
                let r = 1.0 - v;
                (1.0 - r * r) / (r * r)
            }
        };
        let depths: Vec<f64> = (0..n).map(depth).collect();
        let mut one_minus_psi = vec![0.0f32; n * n];
        one_minus_psi
            .par_chunks_mut(n)
            .enumerate()
            .for_each(|(i, row)| {
                for (j, e) in row.iter_mut().enumerate() {
                    *e = (1.0 - psi_exact(depths[i], depths[j])) as f32;
                }
            });
        Self { one_minus_psi, n }
    }

    /// Nodes per axis.
    pub fn size(&self) -> usize {
        self.n
    }

    /// The tabulated `1 - psi`, row `i` (front thickness node) after row, `size()` entries a
    /// row: what a GPU backend uploads to draw the same ψ colours.
    pub fn values(&self) -> &[f32] {
        &self.one_minus_psi
    }

    /// `psi` at normalized front and back thicknesses `gamma_f`, `gamma_b` (see [`gamma`]),
    /// clamped to `[0, 1]`, interpolated bilinearly. NaN gives NaN; never panics.
    #[inline]
    pub fn psi(&self, gamma_f: f32, gamma_b: f32) -> f32 {
        1.0 - self.bilinear(coord_of_gamma(gamma_f), coord_of_gamma(gamma_b))
    }

    /// `psi` at front and back optical thicknesses `tau_f l`, `tau_b l` (negative or NaN read
    /// as 0).
    #[inline]
    pub fn psi_of_depths(&self, tau_l_f: f32, tau_l_b: f32) -> f32 {
        1.0 - self.one_minus_psi_of_depths(tau_l_f, tau_l_b)
    }

    /// `1 - psi` at front and back optical thicknesses (stored directly so that thin cells,
    /// where `psi` is close to 1, keep their relative precision).
    #[inline(always)]
    fn one_minus_psi_of_depths(&self, tau_l_f: f32, tau_l_b: f32) -> f32 {
        let (vf, vb) = coords_of_depths(tau_l_f, tau_l_b);
        self.bilinear(vf, vb)
    }

    /// Bilinear interpolation of the stored `1 - psi` at table coordinates in `[0, 1]`.
    #[inline(always)]
    fn bilinear(&self, vf: f32, vb: f32) -> f32 {
        let last = (self.n - 1) as f32;
        let pos = |v: f32| {
            let x = v.clamp(0.0, 1.0) * last;
            let i = (x as usize).min(self.n - 2);
            (i, x - i as f32)
        };
        let ((i, fi), (j, fj)) = (pos(vf), pos(vb));
        let r0 = i * self.n + j;
        let r1 = r0 + self.n;
        let t = &self.one_minus_psi;
        let (e00, e01, e10, e11) = (t[r0], t[r0 + 1], t[r1], t[r1 + 1]);
        let a = e00 + (e01 - e00) * fj;
        let b = e10 + (e11 - e10) * fj;
        a + (b - a) * fi
    }
}

/// The transfer function on an interval without breakpoints: `[r, g, b, tau]` linear in the
/// value (see [`CellClassifier::linear_on`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearPiece {
    origin: f32,
    at_origin: [f32; 4],
    slope: [f32; 4],
}

impl LinearPiece {
    /// `(origin, value at origin, slope)`: the piece is `at_origin + slope (s - origin)`,
    /// for code that evaluates it a channel at a time.
    #[inline(always)]
    pub fn coefficients(&self) -> (f32, [f32; 4], [f32; 4]) {
        (self.origin, self.at_origin, self.slope)
    }

    /// `[r, g, b, tau]` at value `s` (extrapolated linearly outside the piece).
    #[inline(always)]
    pub fn at(&self, s: f32) -> [f32; 4] {
        let d = s - self.origin;
        let (a, k) = (self.at_origin, self.slope);
        [
            a[0] + k[0] * d,
            a[1] + k[1] * d,
            a[2] + k[2] * d,
            a[3] + k[3] * d,
        ]
    }
}

/// Per-TF lookup of colour and extinction by scalar, one table shared by the cell colour
/// models: `[r, g, b, tau]` (linear RGB, extinction per world unit) at `N` evenly spaced values
/// over a domain covering the data range and every TF breakpoint (as
/// [`ClassifyTable`](crate::classify::ClassifyTable) does), interpolated linearly (see the
/// module documentation for its measured error).
#[derive(Clone, Debug)]
pub struct CellClassifier {
    entries: Vec<[f32; 4]>,
    /// The TF's finite breakpoints (f32, sorted): the TF is linear between consecutive ones
    /// and constant outside them.
    knots: Vec<f32>,
    /// `pieces[k]`: the TF on `[knots[k - 1], knots[k]]` (unbounded at the ends), exactly.
    pieces: Vec<LinearPiece>,
    /// `opaque_prefix[i]`: number of entries before `i` with non-zero extinction.
    opaque_prefix: Vec<u32>,
    lo: f32,
    scale: f32,
    /// `N - 1` as f32: the largest table coordinate.
    last: f32,
}

impl CellClassifier {
    /// Default number of entries.
    pub const DEFAULT_SIZE: usize = 4096;

    /// Tabulates `tf` (resolved; an unresolved one is resolved on `range`) over `range` and
    /// its breakpoints with [`CellClassifier::DEFAULT_SIZE`] entries.
    pub fn new(tf: &TransferFunction, range: [f64; 2]) -> Self {
        Self::with_size(tf, range, Self::DEFAULT_SIZE)
    }

    /// As [`CellClassifier::new`] with `size` entries (clamped to `2..=2^24`). Non-finite
    /// range ends and control points are ignored, negative or non-finite extinction is read
    /// as 0 and non-finite colour as black, so lookups are always finite.
    pub fn with_size(tf: &TransferFunction, range: [f64; 2], size: usize) -> Self {
        let tf = tf.resolved(range);
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        let bp: Vec<f64> = tf
            .breakpoints()
            .into_iter()
            .filter(|x| x.is_finite())
            .collect();
        let ends = range.iter().copied().filter(|x| x.is_finite());
        let lo = ends
            .clone()
            .chain(bp.first().copied())
            .fold(f64::INFINITY, f64::min);
        let hi = ends
            .chain(bp.last().copied())
            .fold(f64::NEG_INFINITY, f64::max);
        let lo = if lo.is_finite() { lo } else { 0.0 };
        let hi = if hi > lo && (hi - lo).is_finite() {
            hi
        } else {
            lo + 1.0
        };
        let size = size.clamp(2, 1 << 24);
        let entries: Vec<[f32; 4]> = (0..size)
            .map(|i| {
                let s = lo + (hi - lo) * i as f64 / (size - 1) as f64;
                let c = if tf.color.is_empty() {
                    [0.0; 3]
                } else {
                    tf.color_at(s).map(finite)
                };
                let tau = if tf.extinction.is_empty() {
                    0.0
                } else {
                    finite(tf.tau_per_world(s)).max(0.0)
                };
                [
                    c[0] as f32,
                    c[1] as f32,
                    c[2] as f32,
                    (tau as f32).min(f32::MAX),
                ]
            })
            .collect();
        let mut opaque_prefix = Vec::with_capacity(size + 1);
        let mut count = 0u32;
        opaque_prefix.push(0);
        for e in &entries {
            count += u32::from(e[3] > 0.0);
            opaque_prefix.push(count);
        }
        let knots: Vec<f32> = bp.iter().map(|&k| k as f32).collect();
        let value = |s: f64| -> [f64; 4] {
            let c = if tf.color.is_empty() {
                [0.0; 3]
            } else {
                tf.color_at(s).map(finite)
            };
            let tau = if tf.extinction.is_empty() {
                0.0
            } else {
                finite(tf.tau_per_world(s)).max(0.0)
            };
            [c[0], c[1], c[2], tau]
        };
        let pieces = (0..=bp.len())
            .map(|k| {
                // Origin at the left knot (the first one for the unbounded left piece, which
                // is constant like the right one).
                let origin = knots
                    .get(k.saturating_sub(1))
                    .copied()
                    .filter(|x| x.is_finite())
                    .unwrap_or(0.0);
                if bp.is_empty() {
                    return LinearPiece {
                        origin,
                        at_origin: value(0.0).map(|v| v as f32),
                        slope: [0.0; 4],
                    };
                }
                // The line through the piece's values at its left end and its middle (the TF
                // may jump at a breakpoint: the value there is the right-hand one), constant
                // at the ends, evaluated at the f32 origin.
                let (left, right) = (bp[k.saturating_sub(1)], bp[k.min(bp.len() - 1)]);
                let mid = 0.5 * (left + right);
                let (a, b) = (value(left), value(mid));
                let slope = [0, 1, 2, 3].map(|c| {
                    let d = (b[c] - a[c]) / (mid - left);
                    if d.is_finite() {
                        d
                    } else {
                        0.0
                    }
                });
                let at = |c: usize| a[c] + slope[c] * (f64::from(origin) - left);
                LinearPiece {
                    origin,
                    at_origin: [0, 1, 2, 3].map(|c| (at(c) as f32).clamp(-f32::MAX, f32::MAX)),
                    slope: slope.map(|d| (d as f32).clamp(-f32::MAX, f32::MAX)),
                }
            })
            .collect();
        Self {
            entries,
            knots,
            pieces,
            opaque_prefix,
            lo: lo as f32,
            scale: ((size - 1) as f64 / (hi - lo)) as f32,
            last: (size - 1) as f32,
        }
    }

    /// The table of [`CellClassifier::lookup`]: its entries, the value at entry 0 and entries
    /// per value unit (what a GPU backend uploads to look values up the same way).
    pub fn table(&self) -> (&[[f32; 4]], f32, f32) {
        (&self.entries, self.lo, self.scale)
    }

    /// The value domain the table covers: `[min(range, breakpoints), max(range, breakpoints)]`.
    pub fn domain(&self) -> [f32; 2] {
        [self.lo, self.lo + self.last / self.scale]
    }

    /// `[r, g, b, tau]` at value `s`, clamped to the table's domain (NaN reads the first
    /// entry).
    #[inline(always)]
    pub fn lookup(&self, s: f32) -> [f32; 4] {
        // max/min rather than clamp: no run-time check of the bounds, and NaN maps to 0.
        let x = ((s - self.lo) * self.scale).max(0.0).min(self.last);
        let i = (x as usize).min(self.entries.len() - 2);
        let f = x - i as f32;
        let pair = &self.entries[i..i + 2];
        let (a, b) = (pair[0], pair[1]);
        [
            a[0] + (b[0] - a[0]) * f,
            a[1] + (b[1] - a[1]) * f,
            a[2] + (b[2] - a[2]) * f,
            a[3] + (b[3] - a[3]) * f,
        ]
    }

    /// The TF on `[lo, hi]` as one linear function, when no breakpoint lies strictly inside
    /// (`None` otherwise, or for NaN bounds). Its values are exact to f32 (the table's are
    /// only within `h |slope jump| / 4` next to a breakpoint), so per-fragment lookups of
    /// values in `[lo, hi]` (a cell's vertex range) can skip the table.
    #[inline]
    pub fn linear_on(&self, lo: f32, hi: f32) -> Option<&LinearPiece> {
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return None;
        }
        let k = self.knots.partition_point(|&x| x <= lo);
        if self.knots.get(k).is_some_and(|&x| x < hi) {
            return None;
        }
        self.pieces.get(k)
    }

    /// The breakpoints around the piece that [`CellClassifier::pieces_on`] gives first for
    /// ranges starting at `lo`: the last one `<= lo` and the first one `> lo` (infinite where
    /// there is none). Every range `[lo', hi']` with `below <= lo' <= hi' <= above` and
    /// `lo' < above` lies in that one piece.
    pub fn piece_bounds(&self, lo: f32) -> (f32, f32) {
        let first = self.knots.partition_point(|&x| x <= lo);
        let below = first
            .checked_sub(1)
            .map_or(f32::NEG_INFINITY, |i| self.knots[i]);
        let above = self.knots.get(first).copied().unwrap_or(f32::INFINITY);
        (below, above)
    }

    /// The TF on `[lo, hi]` piece by piece: the breakpoints strictly inside (sorted) and the
    /// linear pieces around and between them (one more than the breakpoints; the first
    /// holds `lo`, the last `hi`). `None` for NaN bounds or `lo > hi`. With no breakpoint
    /// inside, the one piece is [`CellClassifier::linear_on`]'s.
    #[inline]
    pub fn pieces_on(&self, lo: f32, hi: f32) -> Option<(&[f32], &[LinearPiece])> {
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return None;
        }
        let first = self.knots.partition_point(|&x| x <= lo);
        let last = self.knots.partition_point(|&x| x < hi).max(first);
        Some((
            self.knots.get(first..last)?,
            self.pieces.get(first..last + 1)?,
        ))
    }

    /// Whether the extinction is zero for every value in `[lo, hi]` (including the entries
    /// lookups there interpolate from): a cell whose vertex values span that range contributes
    /// nothing and need not be rasterized. NaN bounds give `false`.
    pub fn is_transparent(&self, lo: f32, hi: f32) -> bool {
        if lo.is_nan() || hi.is_nan() {
            return false;
        }
        let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
        let a = ((lo - self.lo) * self.scale).clamp(0.0, self.last).floor() as usize;
        let b = ((hi - self.lo) * self.scale).clamp(0.0, self.last).ceil() as usize;
        self.opaque_prefix[b + 1] == self.opaque_prefix[a]
    }
}

/// Whether the per-fragment inputs are usable: finite values and a finite positive length.
#[inline(always)]
fn valid(s_f: f32, s_b: f32, l: f32) -> bool {
    s_f.is_finite() && s_b.is_finite() && l.is_finite() && l > 0.0
}

/// The Shirley-Tuchman fragment (eqs. 2.2 and 2.3) from classified front and back samples
/// `[r, g, b, tau]`: premultiplied `[A C_r, A C_g, A C_b, A]` with `C` the mean colour and
/// `A = 1 - exp(-l (tau_f + tau_b) / 2)`. Expects finite inputs and `l > 0` (see
/// [`average_fragment`] for the checked version).
#[inline(always)]
pub fn average_rgba(front: [f32; 4], back: [f32; 4], l: f32) -> [f32; 4] {
    let alpha = opacity(0.5 * l * (front[3] + back[3]));
    let m = 0.5 * alpha;
    [
        (front[0] + back[0]) * m,
        (front[1] + back[1]) * m,
        (front[2] + back[2]) * m,
        alpha,
    ]
}

/// The partial pre-integration fragment from classified front and back samples
/// `[r, g, b, tau]`: premultiplied `[C_r, C_g, C_b, A]` with `C = c_f (1 - psi) + c_b (psi -
/// zeta)`, `A = 1 - zeta`, `zeta = exp(-l (tau_f + tau_b) / 2)`, `psi` from `table`. Expects
/// finite inputs and `l > 0` (see [`psi_fragment`] for the checked version).
#[inline(always)]
pub fn psi_rgba(table: &PsiTable, front: [f32; 4], back: [f32; 4], l: f32) -> [f32; 4] {
    let (a, b) = ((front[3] * l).max(0.0), (back[3] * l).max(0.0));
    let alpha = opacity(0.5 * (a + b));
    // A branch: neighbouring fragments (rasterized or along a ray) have similar
    // thicknesses, so it is predicted well, and the table's square roots, division and
    // loads are skipped for thin cells (most of them in dense meshes).
    let w = if a + b < THIN {
        one_minus_psi_series(a, b)
    } else {
        table.one_minus_psi_of_depths(a, b)
    };
    // 1 - psi <= 1 - zeta: clamping keeps both weights non-negative despite table error.
    let w = clamp_or_lo(w, 0.0, alpha);
    let wb = alpha - w;
    [
        front[0] * w + back[0] * wb,
        front[1] * w + back[1] * wb,
        front[2] * w + back[2] * wb,
        alpha,
    ]
}

/// Shirley-Tuchman average fragment of a ray segment of length `l` (world units) from scalar
/// `s_f` (front) to `s_b` (back): premultiplied RGBA (see [`average_rgba`]). Transparent
/// black when an argument is not finite or `l <= 0`.
#[inline(always)]
pub fn average_fragment(cls: &CellClassifier, s_f: f32, s_b: f32, l: f32) -> [f32; 4] {
    if !valid(s_f, s_b, l) {
        return [0.0; 4];
    }
    average_rgba(cls.lookup(s_f), cls.lookup(s_b), l)
}

/// Partial pre-integration fragment of a ray segment of length `l` (world units) from scalar
/// `s_f` (front) to `s_b` (back): premultiplied RGBA (see [`psi_rgba`]), exact up to the
/// table errors when the TF is linear between `s_f` and `s_b`. Transparent black when an
/// argument is not finite or `l <= 0`.
#[inline(always)]
pub fn psi_fragment(cls: &CellClassifier, psi: &PsiTable, s_f: f32, s_b: f32, l: f32) -> [f32; 4] {
    if !valid(s_f, s_b, l) {
        return [0.0; 4];
    }
    psi_rgba(psi, cls.lookup(s_f), cls.lookup(s_b), l)
}

#[cfg(test)]
mod tests;
