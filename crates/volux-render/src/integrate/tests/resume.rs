//! Adaptive Simpson integrated piece by piece from the carried state
//! ([`adaptive_simpson_resume`](crate::integrate::adaptive::adaptive_simpson_resume)) equals
//! the whole ray bit for bit (`001_...txt` ch. 4): pieces cut anywhere, pieces thinner than a
//! step (jumped over, their state passed on unchanged), every step control, early
//! termination on and off.
use super::super::adaptive::{adaptive_simpson_resume, Resumed};
use super::super::*;

/// A smooth medium with a narrow extinction peak the samples can hide (value = t).
struct Bumpy;

impl RayMedium for Bumpy {
    fn at(&mut self, t: f64) -> Medium {
        let peak = (1.0 - ((t - 1.3) / 0.02).abs()).max(0.0) * 20.0;
        Medium {
            rgb: [1.0, (3.0 * t).sin().abs(), 0.5],
            tau: 0.4 + 0.3 * (5.0 * t).cos() + peak,
            value: t,
        }
    }
    fn hides_features(&self, a: f64, b: f64) -> bool {
        hides_breakpoints(&[1.28, 1.3, 1.32], a, b)
    }
}

/// The ray over `[0, 2]` cut at `cuts`, each piece resumed from where the last stopped (or
/// passed over when its next step starts past the piece): the integral, and how many
/// pieces were jumped over.
fn by_pieces(cuts: &[f64], p: &AdaptiveParams) -> (RayIntegral, usize) {
    let ends = (0.0, 2.0);
    let mut state = None;
    let mut jumped = 0;
    let mut bounds = vec![0.0];
    bounds.extend_from_slice(cuts);
    bounds.push(2.0);
    for w in bounds.windows(2) {
        let stop = w[1];
        if state.is_some_and(|s: super::super::adaptive::state::F64Ray| s.t >= stop) {
            jumped += 1;
            continue;
        }
        match adaptive_simpson_resume(&mut Bumpy, ends, stop, p, state.as_ref()) {
            Resumed::Paused(s) => state = Some(s),
            Resumed::Finished(r) => return (r, jumped),
        }
    }
    panic!("the last piece ends the ray");
}

#[test]
fn a_ray_resumed_piece_by_piece_equals_the_whole_ray_bit_for_bit() {
    let mut cuts = vec![0.1, 0.37, 0.370_001, 0.8, 1.299, 1.3, 1.301, 1.7];
    // Thin pieces a step jumps over.
    cuts.extend((0..40).map(|k| 1.75 + 0.005 * f64::from(k)));
    let mut jumped = 0;
    for control in [
        StepControl::Coupled,
        StepControl::Decoupled,
        StepControl::CoupledStandard,
    ] {
        for et in [None, Some(0.7)] {
            let p = AdaptiveParams {
                tol: 1e-4,
                h0: 0.05,
                hmin: 1e-3,
                hmax: 0.2,
                control,
                early_termination: et,
            };
            let whole = adaptive_simpson(&mut Bumpy, 0.0, 2.0, &p);
            let (pieces, j) = by_pieces(&cuts, &p);
            assert_eq!(pieces, whole, "{control:?}, early termination {et:?}");
            let (one, _) = by_pieces(&[], &p);
            assert_eq!(one, whole, "{control:?}: one piece");
            jumped += j;
        }
    }
    assert!(jumped > 0, "some thin piece was jumped over");
}
