//! Maximum intensity projection (MIP): the largest field value along a ray.
//!
//! MIP is the classic alternative to the emission-absorption model of the seed `001_...txt`
//! for angiography-like data: each pixel shows the maximum of the field along its ray, with
//! no classification of opacity. [`max_along`] samples the ray at a fixed step and refines the
//! maximum between samples:
//!
//! 1. a parabola through the largest sample and its two neighbours ([`parabolic_peak`])
//!    locates the peak (its vertex) and estimates its value: the value error drops from
//!    `O(h^2)` (nearest sample) to `O(h^4)`;
//! 2. one more field sample at the vertex *polishes* the value: the field there is a true
//!    value, off the peak only by the square of the vertex's small location error.
//!
//! On a Gaussian bump with step 0.5 voxel, over all sub-step peak positions, the worst value
//! errors relative to the peak height are (nearest sample / parabola / polished): sigma 1
//! voxel: 3e-2 / 4e-3 / 2e-5; sigma 1.5: 1.4e-2 / 8e-4 / 2e-6. The cost is one extra sample
//! per ray. The result is never below the largest lattice sample.

/// Vertex of the parabola through `(-h, y0)`, `(0, y1)`, `(h, y2)`, where `y1` is the largest
/// of the three: returns (offset from the middle sample in `[-h/2, h/2]`, value `>= y1`).
///
/// `offset = h (y0 - y2) / (2 (y0 - 2 y1 + y2))` and
/// `value = y1 - (y2 - y0)^2 / (8 (y0 - 2 y1 + y2))`. A flat triple (zero curvature), a
/// middle sample that is not the largest, or non-finite inputs give `(0, y1)`.
pub fn parabolic_peak(y0: f32, y1: f32, y2: f32, h: f64) -> (f64, f32) {
    let (a, b, c) = (y0 as f64, y1 as f64, y2 as f64);
    let curv = a - 2.0 * b + c;
    if !(a <= b && c <= b && curv < 0.0 && h.is_finite()) {
        return (0.0, y1);
    }
    let offset = (h * (a - c) / (2.0 * curv)).clamp(-0.5 * h.abs(), 0.5 * h.abs());
    let value = b - (c - a) * (c - a) / (8.0 * curv);
    let value = value as f32;
    if offset.is_finite() && value.is_finite() {
        (offset, value.max(y1))
    } else {
        (0.0, y1)
    }
}

/// The maximum of `sample` along `[t0, t1]` and where it is: samples at `t0 + i step` for
/// `t0 + i step <= t1` (a fixed lattice, so skipping empty space elsewhere does not move
/// them), then refines the largest with [`parabolic_peak`] when both neighbours are defined.
///
/// `sample` returns `None` where the field is undefined; non-finite values count as
/// undefined. The first of equal maxima wins. Returns `None` when no sample is defined, or
/// when `t0`, `t1` or `step` are not finite, `step <= 0` or `t1 < t0`. The cost is one call
/// per lattice point: the caller chooses a step that keeps that bounded.
pub fn max_along<F: FnMut(f64) -> Option<f32>>(
    t0: f64,
    t1: f64,
    step: f64,
    mut sample: F,
) -> Option<(f32, f64)> {
    if !(t0.is_finite() && t1.is_finite() && step.is_finite() && step > 0.0 && t1 >= t0) {
        return None;
    }
    // (value, t, previous sample, next sample, waiting for the next sample)
    let mut best: Option<(f32, f64, Option<f32>, Option<f32>)> = None;
    let mut waiting = false;
    let mut prev: Option<f32> = None;
    let mut i = 0u64;
    loop {
        let t = t0 + step * i as f64;
        if t > t1 {
            break;
        }
        let v = sample(t).filter(|v| v.is_finite());
        if waiting {
            if let Some(b) = best.as_mut() {
                b.3 = v;
            }
            waiting = false;
        }
        if let Some(v) = v {
            if !matches!(best, Some(b) if b.0 >= v) {
                best = Some((v, t, prev, None));
                waiting = true;
            }
        }
        prev = v;
        i += 1;
    }
    let (v, t, y0, y2) = best?;
    Some(refine_peak((v, t), (y0, y2), step, sample))
}

/// The largest lattice sample `(v, t)` refined with its neighbours `y0` (at `t - step`) and
/// `y2` (at `t + step`), where both are defined: the vertex of their parabola
/// ([`parabolic_peak`]), polished by one more `sample` there (the second step of
/// [`max_along`], for traversals that scan the lattice themselves).
pub fn refine_peak<F: FnMut(f64) -> Option<f32>>(
    (v, t): (f32, f64),
    (y0, y2): (Option<f32>, Option<f32>),
    step: f64,
    mut sample: F,
) -> (f32, f64) {
    match (y0, y2) {
        (Some(y0), Some(y2)) => {
            let (dt, peak) = parabolic_peak(y0, v, y2, step);
            if dt == 0.0 {
                return (peak, t);
            }
            // Polish: the field at the vertex, a true value of the field near the peak (the
            // vertex is off by O(h^3), so this is off by O(h^6)); the parabola's own value
            // where the field is undefined there.
            let ts = t + dt;
            match sample(ts).filter(|s| s.is_finite()) {
                Some(s) if s >= v => (s, ts),
                Some(_) => (v, t),
                None => (peak, ts),
            }
        }
        _ => (v, t),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refined_maximum_of_a_bump_is_within_1e3() {
        // Gaussian bumps of height 2 and widths 1 and 1.5 voxel, and a Lorentzian, at many
        // sub-step positions, step 0.5.
        type Bump = Box<dyn Fn(f64) -> f64>;
        let bumps: [(f64, Bump); 3] = [
            (1.0, Box::new(|x: f64| 2.0 * (-x * x / 2.0).exp())),
            (1.5, Box::new(|x: f64| 2.0 * (-x * x / 4.5).exp())),
            (1.5, Box::new(|x: f64| 2.0 / (1.0 + x * x / 2.25))),
        ];
        for k in 0..50 {
            let centre = 3.0 + 0.01 * k as f64;
            for (width, f) in &bumps {
                let bump = |t: f64| Some(f(t - centre) as f32);
                let (v, t) = max_along(0.0, 8.0, 0.5, bump).unwrap();
                assert!(
                    (v - 2.0).abs() < 1e-3,
                    "centre {centre} width {width}: max {v}"
                );
                assert!((t - centre).abs() < 0.05, "centre {centre}: at {t}");
                // The nearest sample alone is worse when the peak is between samples.
                let raw = (0..=16)
                    .map(|i| f(i as f64 * 0.5 - centre) as f32)
                    .fold(f32::MIN, f32::max);
                assert!((v - 2.0).abs() <= (raw - 2.0).abs() + 1e-6);
            }
            // The parabola alone (no polish) on the width-1.5 Gaussian of height 1.
            let g = |x: f64| (-(x - centre).powi(2) / 4.5).exp() as f32;
            let m = (2.0 * centre).round();
            let (y0, y1, y2) = (g(0.5 * (m - 1.0)), g(0.5 * m), g(0.5 * (m + 1.0)));
            let (_, p) = parabolic_peak(y0, y1, y2, 0.5);
            assert!((p - 1.0).abs() < 1e-3, "parabola at {centre}: {p}");
        }
    }

    #[test]
    fn parabola_is_exact_for_quadratics() {
        let q = |x: f64| (5.0 - 3.0 * (x - 0.2) * (x - 0.2)) as f32;
        let (dx, v) = parabolic_peak(q(-1.0), q(0.0), q(1.0), 1.0);
        assert!(
            (dx - 0.2).abs() < 1e-6 && (v - 5.0).abs() < 1e-6,
            "{dx} {v}"
        );
        assert_eq!(parabolic_peak(1.0, 1.0, 1.0, 0.5), (0.0, 1.0));
        assert_eq!(parabolic_peak(2.0, 1.0, 0.0, 0.5), (0.0, 1.0));
        assert_eq!(parabolic_peak(f32::NAN, 1.0, 0.0, 0.5), (0.0, 1.0));
    }

    #[test]
    fn edges_undefined_samples_and_bad_input() {
        // Maximum at the last sample: no neighbour after it, no refinement.
        assert_eq!(
            max_along(0.0, 2.0, 0.5, |t| Some(t as f32)),
            Some((2.0, 2.0))
        );
        // Maximum next to an undefined sample: kept as sampled.
        let s = |t: f64| {
            if t > 1.2 {
                None
            } else {
                Some(-(t - 1.3).abs() as f32)
            }
        };
        assert_eq!(max_along(0.0, 2.0, 0.5, s), Some((-0.3, 1.0)));
        assert_eq!(max_along(0.0, 2.0, 0.5, |_| None), None);
        assert_eq!(max_along(0.0, 2.0, 0.5, |_| Some(f32::NAN)), None);
        assert_eq!(max_along(0.0, 2.0, 0.0, |_| Some(1.0)), None);
        assert_eq!(max_along(0.0, f64::NAN, 0.5, |_| Some(1.0)), None);
        assert_eq!(max_along(2.0, 1.0, 0.5, |_| Some(1.0)), None);
        assert_eq!(max_along(1.0, 1.0, 0.5, |_| Some(1.0)), Some((1.0, 1.0)));
    }
}
