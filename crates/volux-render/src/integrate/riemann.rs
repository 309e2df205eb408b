//! The left Riemann sum with step-corrected opacity (seed `001`, eq. 2.14).
use super::medium::{RayIntegral, RayMedium};
use crate::classify::Classified;
use crate::composite::RayAccumulator;

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
