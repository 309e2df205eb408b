//! The lane integrator against the f64 adaptive integrator on media with closed forms, and its
//! `exp` against the library's.
use super::*;
use crate::integrate::adaptive::StepControl;
use crate::integrate::{adaptive_simpson_intervals, hides_breakpoints, Medium, RayMedium};

#[test]
fn exp_lanes_is_accurate_over_the_transmittance_range() {
    let mut worst = 0.0f64;
    for i in 0..=8000 {
        let x = -80.0 * f64::from(i) / 8000.0;
        let mut v = [x as f32; 4];
        exp_lanes(&mut v);
        let want = f64::from(x as f32).exp();
        worst = worst.max((f64::from(v[0]) - want).abs() / want);
    }
    assert!(worst < 3e-7, "relative error {worst}");
    let mut v = [0.0, -0.0, -80.5, f32::NAN, f32::NEG_INFINITY, -1e-30];
    exp_lanes(&mut v);
    assert_eq!(v, [1.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
}

/// Ray `r`'s medium: the linear field of the integrator tests (R = 1, G = s^2 / 4, B = 0.5,
/// tau = 1.5 s) with a green shifted by ray, plus narrow extinction peaks at [`PEAKS`] that
/// the breakpoints announce (one transfer function for all rays, as in a render).
struct Peaked(usize);

const PEAKS: [f64; 3] = [1.1, 1.35, 1.62];

fn breakpoints() -> Vec<f64> {
    PEAKS
        .iter()
        .flat_map(|&c| [c - 0.02, c, c + 0.02])
        .collect()
}

impl RayMedium for Peaked {
    fn at(&mut self, t: f64) -> Medium {
        let peak: f64 = PEAKS
            .iter()
            .map(|&c| (1.0 - ((t - c) / 0.02).abs()).max(0.0) * 40.0)
            .sum();
        let g = t + 0.1 * self.0 as f64;
        Medium {
            rgb: [1.0, g * g / 4.0, 0.5],
            tau: 1.5 * t + peak,
            value: t,
        }
    }
    fn hides_features(&self, a: f64, b: f64) -> bool {
        hides_breakpoints(&breakpoints(), a, b)
    }
}

/// The exact breakpoint counts of each lane's value.
fn count_breakpoints(m: &mut LaneMedia) {
    let bp = breakpoints();
    for l in 0..LANES {
        let v = f64::from(m.value[l]);
        m.breakpoints_at_or_below[l] = bp.partition_point(|&b| b <= v) as f32;
        m.breakpoints_below[l] = bp.partition_point(|&b| b < v) as f32;
    }
}

/// Integrates `rays` (intervals each) with the lanes, more rays than slots so slots are
/// refilled.
fn lanes(rays: &[Vec<(f64, f64)>], p: &AdaptiveParams) -> Vec<RayIntegral> {
    let mut lanes = AdaptiveLanes::new(p);
    let mut out = vec![RayIntegral::default(); rays.len()];
    // Slot r holds (ray index, next interval).
    let mut slots: [Option<(usize, usize)>; RAYS] = [None; RAYS];
    let mut queue = 0..rays.len();
    loop {
        for (r, slot) in slots.iter_mut().enumerate() {
            // Until the slot's ray has a round to take, or no ray is left.
            loop {
                if slot.is_none() {
                    let Some(i) = queue.next() else {
                        break;
                    };
                    let len = rays[i].iter().map(|(a, b)| (b - a).max(0.0)).sum();
                    lanes.start(r, len);
                    *slot = Some((i, 0));
                }
                let Some((i, next)) = slot.as_mut().filter(|_| lanes.needs_span(r)) else {
                    break;
                };
                let span = rays[*i].get(*next).copied();
                *next += 1;
                match span {
                    Some(s) if !lanes.is_opaque(r) => {
                        lanes.enter(r, s);
                    }
                    _ => {
                        out[*i] = lanes.result(r);
                        *slot = None;
                        lanes.idle(r);
                    }
                }
            }
        }
        if !lanes.is_busy() {
            break;
        }
        let ts = lanes.distances();
        let mut m = LaneMedia::default();
        for (l, &t) in ts.iter().enumerate() {
            let Some((i, _)) = slots[l % RAYS] else {
                continue;
            };
            let s = Peaked(i).at(f64::from(t));
            for c in 0..3 {
                m.rgb[c][l] = s.rgb[c] as f32;
            }
            (m.tau[l], m.value[l]) = (s.tau as f32, s.value as f32);
        }
        count_breakpoints(&mut m);
        lanes.supply(&m);
    }
    assert!(queue.next().is_none() && slots.iter().all(Option::is_none));
    out
}

/// Six rays (so slots are refilled): one whole interval, intervals with gaps and an empty
/// one, and two intervals meeting almost end to end.
fn gapped_rays() -> Vec<Vec<(f64, f64)>> {
    (0..6)
        .map(|r| match r % 3 {
            0 => vec![(0.0, 2.0)],
            1 => vec![(0.0, 0.4), (0.4, 0.4), (0.7, 1.6), (1.9, 2.0)],
            _ => vec![(0.3, 1.25), (1.3, 2.0)],
        })
        .collect()
}

/// The step limits of the [`gapped_rays`] tests, with tolerance `tol`, early termination
/// `stop` and the controller `control`.
fn gapped_params(tol: f64, stop: Option<f64>, control: StepControl) -> AdaptiveParams {
    AdaptiveParams {
        tol,
        h0: 0.1,
        hmin: 1e-3,
        hmax: 0.4,
        control,
        early_termination: stop,
    }
}

/// Six rays (so slots are refilled) over gaps, an empty interval and a hidden peak each, with
/// and without early termination: the same integrals as the f64 integrator to f32 rounding,
/// the same sample counts (the same step decisions).
#[test]
fn lanes_match_the_f64_coupled_integrator() {
    let rays = gapped_rays();
    for (tol, stop) in [(1e-3, None), (1e-2, None), (1e-3, Some(0.6))] {
        let p = gapped_params(tol, stop, StepControl::Coupled);
        let got = lanes(&rays, &p);
        for (r, spans) in rays.iter().enumerate() {
            let want = adaptive_simpson_intervals(&mut Peaked(r), spans, &p);
            let diff = (0..4)
                .map(|c| (got[r].rgba[c] - want.rgba[c]).abs())
                .fold(0.0, f64::max);
            assert!(diff < 2e-5, "ray {r} tol {tol} stop {stop:?}: {diff}");
            assert_eq!(
                got[r].samples, want.samples,
                "ray {r} tol {tol} {:?} {:?}",
                got[r], want
            );
            assert_eq!(got[r].tolerance_missed, want.tolerance_missed);
            assert!((got[r].error - want.error).abs() < 1e-6);
        }
    }
}

/// The error-per-step controller in lanes against the f64 integrator: its factors are
/// continuous in the error estimates (and a hidden peak and a failed error estimate are told
/// apart, which f32 values near a breakpoint may tell otherwise), so f32 rounding moves the
/// steps, and the integrals agree within the tolerance, not to f32 rounding; nor does the
/// controller take many more samples than Algorithm 3.
#[test]
fn standard_controller_lanes_meet_the_tolerance() {
    let rays = gapped_rays();
    for (tol, stop) in [(1e-3, None), (1e-2, None), (1e-3, Some(0.6))] {
        let p = gapped_params(tol, stop, StepControl::CoupledStandard);
        let seed = AdaptiveParams {
            control: StepControl::Coupled,
            ..p
        };
        let (got, seed_lanes) = (lanes(&rays, &p), lanes(&rays, &seed));
        for (r, spans) in rays.iter().enumerate() {
            let want = adaptive_simpson_intervals(&mut Peaked(r), spans, &p);
            let diff = (0..4)
                .map(|c| (got[r].rgba[c] - want.rgba[c]).abs())
                .fold(0.0, f64::max);
            // With early termination a ray stops at the end of the step that crosses the
            // opacity, wherever that step ends: both stop past it.
            match stop {
                None => assert!(diff < tol, "ray {r} tol {tol}: {diff}"),
                Some(a) => assert!(got[r].rgba[3] >= a.min(want.rgba[3]) - 1e-6),
            }
            let (a, b) = (got[r].samples, seed_lanes[r].samples);
            assert!(a <= b + b / 2, "ray {r} tol {tol}: {a} samples, seed {b}");
        }
    }
}
