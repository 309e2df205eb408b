//! Fixed-step trapezoid and Simpson rules for the inner and outer integrals
//! (`001_...txt` eqs. 2.15 to 2.17, with the same rule for both integrals).
use super::medium::{Medium, RayIntegral, RayMedium};

/// Colour integrand `c tau T` at a sample with optical depth `depth`.
#[inline]
pub(crate) fn integrand(s: &Medium, depth: f64) -> [f64; 3] {
    let w = s.tau * (-depth).exp();
    [s.rgb[0] * w, s.rgb[1] * w, s.rgb[2] * w]
}

/// Trapezoid rule with step `h` (last step shortened): order 2.
pub fn trapezoid(m: &mut impl RayMedium, t0: f64, t1: f64, h: f64) -> RayIntegral {
    fixed_intervals(
        m,
        &[(t0, t1)],
        (t0, t1),
        h,
        FixedRule::Trapezoid,
        f64::INFINITY,
    )
}

/// Simpson's rule with step `h` (samples at each step's ends and middle): order 4.
pub fn simpson(m: &mut impl RayMedium, t0: f64, t1: f64, h: f64) -> RayIntegral {
    fixed_intervals(
        m,
        &[(t0, t1)],
        (t0, t1),
        h,
        FixedRule::Simpson,
        f64::INFINITY,
    )
}

/// Which fixed-step rule integrates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FixedRule {
    /// Two samples per step.
    Trapezoid,
    /// Three samples per step (ends and middle).
    Simpson,
}

/// A fixed-step rule over the ray `[t0, t1]` on the steps `[t0 + i h, t0 + (i + 1) h]` (the
/// last one shortened) that overlap the ordered, disjoint `spans`; steps outside them lie in
/// transparent space (no extinction, so no colour and no depth) and are skipped, which changes
/// nothing. Stops once the optical depth reaches `stop_depth` (early ray termination).
pub fn fixed_intervals(
    m: &mut impl RayMedium,
    spans: &[(f64, f64)],
    (t0, t1): (f64, f64),
    h: f64,
    rule: FixedRule,
    stop_depth: f64,
) -> RayIntegral {
    let (mut c, mut depth, mut n) = ([0.0; 3], 0.0, 0u64);
    // Steps before this one are integrated (a step may straddle two spans).
    let mut next = 0u64;
    for &(a, b) in spans {
        let mut i = (((a - t0) / h).floor().max(0.0) as u64).max(next);
        let mut start: Option<(Medium, [f64; 3])> = None;
        loop {
            let t = t0 + h * i as f64;
            if t >= b || t >= t1 {
                break;
            }
            let len = h.min(t1 - t);
            let (s0, g0) = start.unwrap_or_else(|| {
                n += 1;
                let s = m.at(t);
                (s, integrand(&s, depth))
            });
            let (s1, g1) = match rule {
                FixedRule::Trapezoid => {
                    let s1 = m.at(t + len);
                    n += 1;
                    let d1 = depth + 0.5 * len * (s0.tau + s1.tau);
                    let g1 = integrand(&s1, d1);
                    for k in 0..3 {
                        c[k] += 0.5 * len * (g0[k] + g1[k]);
                    }
                    depth = d1;
                    (s1, g1)
                }
                FixedRule::Simpson => {
                    let (sm, s1) = (m.at(t + 0.5 * len), m.at(t + len));
                    n += 2;
                    let (dm, d1) = simpson_depths(depth, len, [s0.tau, sm.tau, s1.tau]);
                    let (gm, g1) = (integrand(&sm, dm), integrand(&s1, d1));
                    for k in 0..3 {
                        c[k] += len / 6.0 * (g0[k] + 4.0 * gm[k] + g1[k]);
                    }
                    depth = d1;
                    (s1, g1)
                }
            };
            start = Some((s1, g1));
            i += 1;
            next = i;
            if depth >= stop_depth {
                return RayIntegral::from_parts(c, depth, n);
            }
        }
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
