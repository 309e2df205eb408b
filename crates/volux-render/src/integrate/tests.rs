//! One harness for every integrator: a medium with closed-form integrals (the field is linear
//! along the ray, s = t, with linear extinction tau = a s), the fitted order of convergence of
//! each fixed-step rule, and the error control of the adaptive one.
use super::*;
use crate::classify::Classified;
use crate::composite::RayAccumulator;

const L: f64 = 2.0;
const A: f64 = 1.5;

/// R = 1, G = s^2 / L^2, B = 0.5; tau = A s.
fn medium(t: f64) -> Medium {
    Medium {
        rgb: [1.0, t * t / (L * L), 0.5],
        tau: A * t,
        value: t,
    }
}

/// Closed form: with U = A L^2 / 2, alpha = 1 - e^-U, R = alpha, B = alpha / 2,
/// G = 2 / (A L^2) (1 - (1 + U) e^-U).
fn exact() -> [f64; 4] {
    let u = A * L * L / 2.0;
    let alpha = 1.0 - (-u).exp();
    let g = 2.0 / (A * L * L) * (1.0 - (1.0 + u) * (-u).exp());
    [alpha, g, 0.5 * alpha, alpha]
}

fn max_err(r: &RayIntegral) -> f64 {
    let e = exact();
    (0..4).map(|c| (r.rgba[c] - e[c]).abs()).fold(0.0, f64::max)
}

/// Least-squares slope of log(error) against log(h).
fn fitted_order(rule: impl Fn(f64) -> RayIntegral) -> f64 {
    let pts: Vec<(f64, f64)> = [8.0, 16.0, 32.0, 64.0, 128.0]
        .iter()
        .map(|n| {
            let h = L / n;
            (h.ln(), max_err(&rule(h)).ln())
        })
        .collect();
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let num: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let den: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    num / den
}

#[test]
fn riemann_converges_with_order_one() {
    let k = fitted_order(|h| riemann(&mut medium, 0.0, L, h));
    assert!((0.8..1.3).contains(&k), "Riemann order {k}");
}

#[test]
fn trapezoid_converges_with_order_two() {
    let k = fitted_order(|h| trapezoid(&mut medium, 0.0, L, h));
    assert!((1.8..2.3).contains(&k), "trapezoid order {k}");
}

#[test]
fn simpson_converges_with_order_four() {
    let k = fitted_order(|h| simpson(&mut medium, 0.0, L, h));
    assert!((3.6..4.5).contains(&k), "Simpson order {k}");
}

fn params(tol: f64, control: StepControl) -> AdaptiveParams {
    AdaptiveParams {
        tol,
        h0: 0.5,
        hmin: 1e-4,
        hmax: 1.0,
        control,
        early_termination: None,
    }
}

/// Every step control: the seed's coupled and decoupled, and the error-per-step controller.
const CONTROLS: [StepControl; 3] = [
    StepControl::Coupled,
    StepControl::Decoupled,
    StepControl::CoupledStandard,
];

#[test]
fn adaptive_simpson_meets_its_tolerance() {
    for control in CONTROLS {
        let mut last_samples = u64::MAX;
        for tol in [1e-2, 1e-3, 1e-4, 1e-6] {
            let r = adaptive_simpson(&mut medium, 0.0, L, &params(tol, control));
            let err = max_err(&r);
            assert!(err <= tol, "{control:?} tol {tol}: error {err}");
            assert!(!r.tolerance_missed);
            assert!(r.error <= tol * 1.0001, "estimate {} over tol", r.error);
            assert!(r.samples >= 5);
            // Tighter tolerances cost more samples.
            assert!(last_samples == u64::MAX || r.samples >= last_samples);
            last_samples = r.samples;
        }
    }
}

/// A sharp feature (a narrow extinction spike) that a coarse fixed step misses: the adaptive
/// method still meets its tolerance against a very fine Simpson reference.
#[test]
fn adaptive_simpson_resolves_a_spike() {
    let spike = |t: f64| Medium {
        rgb: [1.0, t / L, 0.2],
        tau: 20.0 * (-((t - 1.3) / 0.02).powi(2)).exp() + 0.1,
        value: t,
    };
    let reference = simpson(&mut { spike }, 0.0, L, 1e-5);
    for control in CONTROLS {
        let r = adaptive_simpson(&mut { spike }, 0.0, L, &params(1e-3, control));
        let err = (0..4)
            .map(|c| (r.rgba[c] - reference.rgba[c]).abs())
            .fold(0.0, f64::max);
        assert!(err <= 1e-3, "{control:?}: {err}");
        assert!(r.samples < 2000, "{control:?}: {} samples", r.samples);
    }
}

#[test]
fn hmin_accepts_and_reports() {
    let mut p = params(1e-12, StepControl::Coupled);
    p.hmin = 0.25;
    let r = adaptive_simpson(&mut medium, 0.0, L, &p);
    assert!(r.tolerance_missed);
    assert!(r.samples <= 4 * 8 + 1 + 8, "{} samples", r.samples);
}

#[test]
fn empty_ray_is_transparent() {
    for control in CONTROLS {
        let r = adaptive_simpson(
            &mut |_t: f64| Medium::default(),
            0.0,
            5.0,
            &params(1e-3, control),
        );
        assert_eq!(r.rgba, [0.0; 4]);
        let r = adaptive_simpson(&mut medium, 1.0, 1.0, &params(1e-3, control));
        assert_eq!(r.rgba, [0.0; 4]);
    }
}

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
        let exact = 1.0 - (-f64::from(tau * len)).exp();
        assert!((acc.alpha() - exact).abs() < 1e-6, "n={n}");
        assert!((acc.rgba[1] - 0.5 * exact).abs() < 1e-6);
    }
}

#[test]
fn hidden_breakpoints_are_detected() {
    let bp = [0.45, 0.5, 0.55];
    assert!(hides_breakpoints(&bp, 0.4, 0.6));
    assert!(hides_breakpoints(&bp, 0.6, 0.4));
    assert!(!hides_breakpoints(&bp, 0.4, 0.47));
    assert!(!hides_breakpoints(&bp, 0.45, 0.5));
    assert!(hides_breakpoints(&bp, 0.449, 0.501));
}

/// A medium whose extinction is a narrow TF peak that five samples can straddle: without the
/// breakpoint check the estimate is blind to it; with it, the step refines and the peak counts.
#[test]
fn adaptive_refines_across_hidden_tf_peaks() {
    struct Peak;
    impl RayMedium for Peak {
        fn at(&mut self, t: f64) -> Medium {
            // value = t; extinction peaks (tent) between 0.49 and 0.51.
            let tau = (1.0 - ((t - 0.5) / 0.01).abs()).max(0.0) * 50.0;
            Medium {
                rgb: [1.0; 3],
                tau,
                value: t,
            }
        }
        fn hides_features(&self, a: f64, b: f64) -> bool {
            hides_breakpoints(&[0.49, 0.5, 0.51], a, b)
        }
    }
    let exact = 1.0 - (-0.5f64).exp(); // depth = 50 * 0.01 = 0.5
    for control in [StepControl::Coupled, StepControl::CoupledStandard] {
        let mut p = params(1e-3, control);
        (p.h0, p.hmax, p.hmin) = (0.25, 0.25, 1e-4);
        let r = adaptive_simpson(&mut Peak, 0.0, 1.0, &p);
        assert!(
            (r.rgba[3] - exact).abs() < 1e-3,
            "{control:?}: alpha {} vs {exact}",
            r.rgba[3]
        );
    }
}

/// A uniform medium whose values cross three breakpoints near `C` (a transfer-function
/// feature the samples cannot see): no error estimate fails, so the steps refused are those
/// that hide the feature. Both controllers refine to `hmin` there and integrate exactly; the
/// error-per-step controller narrows where the feature lies fourfold per refused step (the
/// quarters before it as one step, then its quarter), Algorithm 3 twofold (halving), so it
/// takes fewer samples.
#[test]
fn the_standard_controller_goes_straight_to_a_hidden_peak() {
    const C: f64 = 0.613;
    struct Feature;
    impl RayMedium for Feature {
        fn at(&mut self, t: f64) -> Medium {
            Medium {
                rgb: [1.0; 3],
                tau: 0.5,
                value: t,
            }
        }
        fn hides_features(&self, a: f64, b: f64) -> bool {
            hides_breakpoints(&[C - 1e-4, C, C + 1e-4], a, b)
        }
    }
    let exact = 1.0 - (-1.0f64).exp();
    let samples = [StepControl::Coupled, StepControl::CoupledStandard].map(|control| {
        let mut p = params(1e-3, control);
        (p.h0, p.hmax, p.hmin) = (0.5, 1.0, 1e-3);
        let r = adaptive_simpson(&mut Feature, 0.0, 2.0, &p);
        assert!(
            (r.rgba[3] - exact).abs() < 1e-9,
            "{control:?}: {}",
            r.rgba[3]
        );
        r.samples
    });
    assert!(
        samples[1] * 4 < samples[0] * 3,
        "samples seed / standard {samples:?}"
    );
}

#[test]
fn breakpoints_along_samples_agree_with_each_pair() {
    let bp = [0.1, 0.2, 0.2, 0.45, 0.5, 0.55, 0.9];
    let mut seed = 7u32;
    let mut next = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        // Values on a coarse grid, so that some fall exactly on breakpoints.
        f64::from(seed >> 28) / 20.0
    };
    let mut hidden = 0;
    for _ in 0..4000 {
        let v: [f64; 5] = std::array::from_fn(|_| next());
        let pairwise = v.windows(2).any(|w| hides_breakpoints(&bp, w[0], w[1]));
        assert_eq!(hides_breakpoints_along(&bp, &v), pairwise, "{v:?}");
        hidden += usize::from(pairwise);
    }
    assert!((100..3900).contains(&hidden), "{hidden}");
    assert!(!hides_breakpoints_along(&[0.5], &[0.0, 1.0, 0.0, 1.0, 0.0]));
}

/// The error-per-step controller's factor: the safety margin at the tolerance, the fourth
/// root, the bounds, and the largest growth for a zero error.
#[test]
fn standard_factor_follows_the_fourth_root() {
    use super::adaptive::{standard_factor, standard_growth};
    assert!((standard_factor(1.0, 1.0) - 0.9).abs() < 1e-12);
    assert!((standard_factor(1.0, 16.0) - 1.8).abs() < 1e-12);
    assert_eq!(standard_factor(1.0, 1e9), 5.0);
    assert_eq!(standard_factor(1e9, 1.0), 0.2);
    assert_eq!(standard_factor(0.0, 1.0), 5.0);
    assert_eq!(standard_factor(f64::NAN, 1.0), 0.2);
    // Right after a failure the step does not grow.
    assert_eq!(standard_growth(0.0, 1.0, 1), 1.0);
    assert_eq!(standard_growth(0.0, 1.0, 2), 5.0);
}

mod resume;
