//! Fixed-step trapezoid and Simpson rules for the inner and outer integrals
//! (`001_...txt` eqs. 2.15 to 2.17, with the same rule for both integrals).
use super::{Medium, RayIntegral, RayMedium};

/// Colour integrand `c tau T` at a sample with optical depth `depth`.
#[inline]
pub(crate) fn integrand(s: &Medium, depth: f64) -> [f64; 3] {
    let w = s.tau * (-depth).exp();
    [s.rgb[0] * w, s.rgb[1] * w, s.rgb[2] * w]
}

/// Trapezoid rule with step `h` (last step shortened): order 2.
pub fn trapezoid(m: &mut impl RayMedium, t0: f64, t1: f64, h: f64) -> RayIntegral {
    let (mut c, mut depth) = ([0.0; 3], 0.0);
    let mut s0 = m.at(t0);
    let mut g0 = integrand(&s0, 0.0);
    let mut n = 1;
    let mut t = t0;
    while t < t1 {
        let len = h.min(t1 - t);
        let s1 = m.at(t + len);
        n += 1;
        let d1 = depth + 0.5 * len * (s0.tau + s1.tau);
        let g1 = integrand(&s1, d1);
        for k in 0..3 {
            c[k] += 0.5 * len * (g0[k] + g1[k]);
        }
        (s0, g0, depth) = (s1, g1, d1);
        t += len;
    }
    RayIntegral::from_parts(c, depth, n)
}

/// Optical depths at `t + h/2` and `t + h` from extinctions at `t`, `t + h/2`, `t + h`:
/// the half-interval quadratic rule `H/12 (5 a + 8 b - c)` and Simpson's rule.
#[inline]
pub(crate) fn simpson_depths(depth: f64, h: f64, tau: [f64; 3]) -> (f64, f64) {
    let mid = depth + h / 24.0 * (5.0 * tau[0] + 8.0 * tau[1] - tau[2]);
    let end = depth + h / 6.0 * (tau[0] + 4.0 * tau[1] + tau[2]);
    (mid, end)
}

/// Simpson's rule with step `h` (samples at each step's ends and middle): order 4.
pub fn simpson(m: &mut impl RayMedium, t0: f64, t1: f64, h: f64) -> RayIntegral {
    let (mut c, mut depth) = ([0.0; 3], 0.0);
    let mut s0 = m.at(t0);
    let mut g0 = integrand(&s0, 0.0);
    let mut n = 1;
    let mut t = t0;
    while t < t1 {
        let len = h.min(t1 - t);
        let (sm, s1) = (m.at(t + 0.5 * len), m.at(t + len));
        n += 2;
        let (dm, d1) = simpson_depths(depth, len, [s0.tau, sm.tau, s1.tau]);
        let (gm, g1) = (integrand(&sm, dm), integrand(&s1, d1));
        for k in 0..3 {
            c[k] += len / 6.0 * (g0[k] + 4.0 * gm[k] + g1[k]);
        }
        (s0, g0, depth) = (s1, g1, d1);
        t += len;
    }
    RayIntegral::from_parts(c, depth, n)
}
