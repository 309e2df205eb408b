//! The step control of adaptive Simpson (`001_...txt` ch. 4, Algorithm 3): the parameters, a
//! step's five samples (`Probe`), and the bookkeeping of the step size (`StepSize`): the
//! seed's halving and doubling, or the error-per-step controller ([`standard_factor`]). The
//! rules and the integration loops are in [`adaptive`](super); the f32 lanes
//! ([`lanes`](super::lanes)) follow the same decisions.
use super::state::StepState;
use crate::integrate::medium::{Medium, RayMedium};

/// How the steps of the inner and outer integrals are controlled (`001_...txt` sec. 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum StepControl {
    /// One step for both integrals.
    Coupled,
    /// The outer step is controlled on its own within each inner step.
    Decoupled,
    /// One step for both integrals, sized by the error-per-step controller
    /// ([`standard_factor`]) instead of the seed's halving and doubling (Algorithm 3).
    #[serde(rename = "coupled-standard")]
    CoupledStandard,
}

impl StepControl {
    /// Whether one step serves both integrals.
    pub fn is_coupled(self) -> bool {
        self != StepControl::Decoupled
    }
}

/// Safety factor of the error-per-step controller: the next step aims at `0.9^4`, about
/// two thirds, of the allowed error rather than at the limit, so that few steps fail.
const CONTROLLER_SAFETY: f64 = 0.9;

/// Bounds on the factor by which the error-per-step controller changes the step.
const CONTROLLER_FACTOR: [f64; 2] = [0.2, 5.0];

/// `tol / err` at and beyond which the controller's factor is its upper bound:
/// `(5 / 0.9)^4`.
const FACTOR_HI_RATIO: f64 = 952.598_689_224_203_4;

/// `tol / err` at and below which the controller's factor is its lower bound:
/// `(0.2 / 0.9)^4`.
const FACTOR_LO_RATIO: f64 = 0.002_438_652_644_413_961_8;

/// The error-per-step controller (Hairer, Norsett and Wanner, *Solving ODEs I*, sec. II.4),
/// the alternative to the seed's Algorithm 3 (`001_...txt` ch. 4): the next step is the last
/// one times `0.9 (tol / err)^(1/4)`, clamped to `[0.2, 5]`. Simpson's error estimate over a
/// step of length `h` is `O(h^5)` and the tolerance allowed is proportional to `h` (`eps h /
/// L`), so their ratio goes as `h^4`: the fourth root makes the next step meet the tolerance
/// with the safety margin where the error behaves asymptotically. Two square roots, no `powf`.
/// A zero error gives the largest growth.
pub fn standard_factor(err: f64, tol: f64) -> f64 {
    let [lo, hi] = CONTROLLER_FACTOR;
    // The clamps without the roots: most steps of smooth or empty stretches have errors far
    // below the tolerance, and two roots and a division cost more than the rest of a step's
    // bookkeeping.
    if err * FACTOR_HI_RATIO < tol {
        return hi;
    }
    if err * FACTOR_LO_RATIO > tol {
        return lo;
    }
    let f = CONTROLLER_SAFETY * (tol / err).sqrt().sqrt();
    // Selects: NaN (0 / 0) goes to the largest growth.
    let f = if f > lo { f } else { lo };
    if f < hi {
        f
    } else {
        hi
    }
}

/// Parameters of [`adaptive_simpson`](super::adaptive_simpson); lengths in world units.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptiveParams {
    /// Absolute error tolerance per channel for the whole ray.
    pub tol: f64,
    /// Initial step.
    pub h0: f64,
    /// Smallest step; accepted whatever its error.
    pub hmin: f64,
    /// Largest step.
    pub hmax: f64,
    /// Coupled or decoupled control.
    pub control: StepControl,
    /// Stop once opacity reaches this value (`None`: integrate to the end).
    pub early_termination: Option<f64>,
}

/// Five samples over a candidate step `[t, t + h]` at `t + k h / 4`.
pub(super) struct Probe {
    pub(super) t: f64,
    pub(super) h: f64,
    pub(super) s: [Medium; 5],
    /// Bit `k` set: sample `k` is known.
    pub(super) known: u8,
}

impl Probe {
    pub(super) fn new(t: f64, h: f64, first: Medium) -> Self {
        Self {
            t,
            h,
            s: [first; 5],
            known: 1,
        }
    }

    /// Samples the missing points (all five are then in `s`), counting new samples into `n`.
    #[inline]
    pub(super) fn fill(&mut self, m: &mut impl RayMedium, n: &mut u64) {
        if self.known == 1 {
            // A fresh step: its four new samples together.
            let [a, b, c, d] = m.at4(std::array::from_fn(|k| {
                self.t + self.h * (k + 1) as f64 / 4.0
            }));
            self.s = [self.s[0], a, b, c, d];
            self.known = 0x1f;
            *n += 4;
            return;
        }
        for k in 1..5 {
            if self.known & (1 << k) == 0 {
                self.s[k] = m.at(self.t + self.h * k as f64 / 4.0);
                *n += 1;
            }
        }
        self.known = 0x1f;
    }

    /// Starts the step `[t, t + h]` from the known sample `first` (in place: no copy of the
    /// five samples).
    #[inline]
    pub(super) fn restart(&mut self, t: f64, h: f64, first: Medium) {
        (self.t, self.h, self.s[0], self.known) = (t, h, first, 1);
    }

    /// Shortens the step to its first `quarters` quarters (1 to 3), keeping the samples that
    /// fall on the shorter step's points.
    pub(super) fn keep_quarters(&mut self, quarters: usize) {
        if quarters == 2 {
            return self.halve();
        }
        self.h *= quarters as f64 * 0.25;
        self.s[4] = self.s[quarters];
        self.known = 0b10001;
    }

    /// Halves the step, keeping the samples of the first half.
    pub(super) fn halve(&mut self) {
        self.h *= 0.5;
        self.s = [self.s[0], self.s[0], self.s[1], self.s[1], self.s[2]];
        self.known = 0b10101;
    }
}

/// Step-size bookkeeping shared by both controls: the seed's doubling after two consecutive
/// successes and halving on failure (Algorithm 3), or the error-per-step controller
/// ([`standard_factor`]) when `standard`.
pub(super) struct StepSize {
    pub(super) h: f64,
    successes: u32,
    pub(super) standard: bool,
    hmin: f64,
    /// Where the step proposed ends at the quarter of a refused step that hid a peak: that
    /// quarter's length, the step after it (0: none).
    peak_ahead: f64,
}

impl StepSize {
    /// The step `taken` was accepted with the error `err` where `tol` was allowed.
    pub(super) fn success(&mut self, taken: f64, hmax: f64, err: f64, tol: f64) {
        self.successes += 1;
        if self.peak_ahead > 0.0 {
            // The step ended where a hidden peak's quarter begins: that quarter next.
            (self.h, self.peak_ahead) = (self.peak_step(self.peak_ahead), 0.0);
        } else if self.standard {
            let next = taken * standard_growth(err, tol, self.successes);
            // A step shortened to end its interval does not shrink the proposal.
            let next = if taken < self.h {
                next.max(self.h)
            } else {
                next
            };
            self.h = next.min(hmax);
        } else if taken >= self.h && self.successes >= 2 {
            self.h = (2.0 * self.h).min(hmax);
        }
    }

    /// The step `taken` failed with the error `err` where `tol` was allowed (or hides a peak,
    /// `blind`); true when the next try is its first half (whose samples are known).
    pub(super) fn failure(&mut self, taken: f64, err: f64, tol: f64, blind: bool) -> bool {
        self.successes = 0;
        if self.standard && !blind {
            self.h = taken * standard_factor(err, tol);
            false
        } else {
            self.h = taken * 0.5;
            true
        }
    }

    /// The step that searches a quarter of length `quarter` hiding a peak: the quarter, or
    /// `hmin` once the quarter is within [`PEAK_NEAR_HMIN`] of it.
    fn peak_step(&self, quarter: f64) -> f64 {
        if quarter > PEAK_NEAR_HMIN * self.hmin {
            quarter
        } else {
            self.hmin
        }
    }

    /// The error-per-step controller's next try after `probe` hid a peak of the transfer
    /// function in its quarter `quarter` (1 to 4): the quarters before it, whose samples
    /// showed none, as one step, then the quarter that hid the peak ([`StepSize::peak_step`]);
    /// a peak in the first quarter gets that step at once. Each refused step narrows where the
    /// peak lies fourfold, down to `hmin`, where halving (Algorithm 3) narrows it twofold.
    pub(super) fn before_peak(&mut self, probe: &mut Probe, quarter: usize) {
        self.successes = 0;
        let quarter_len = probe.h * 0.25;
        let before = quarter_len * (quarter - 1) as f64;
        if before > self.hmin {
            (self.h, self.peak_ahead) = (before, quarter_len);
            probe.keep_quarters(quarter - 1);
        } else if self.peak_step(quarter_len) > self.hmin {
            (self.h, self.peak_ahead) = (quarter_len, 0.0);
            probe.keep_quarters(1);
        } else if self.hmin < probe.h {
            (self.h, self.peak_ahead) = (self.hmin, 0.0);
            let first = probe.s[0];
            probe.restart(probe.t, self.hmin, first);
        } else {
            self.h = probe.h * 0.5;
            probe.halve();
        }
    }

    /// The state to carry to a later piece of the ray ([`StepState`]).
    pub(super) fn state(&self) -> StepState {
        StepState {
            h: self.h,
            successes: self.successes,
            peak_ahead: self.peak_ahead,
        }
    }

    /// The control carried in `s`, with `p`'s kind and `hmin`.
    pub(super) fn resumed(p: &AdaptiveParams, s: &StepState) -> Self {
        Self {
            h: s.h,
            successes: s.successes,
            standard: p.control == StepControl::CoupledStandard,
            hmin: p.hmin,
            peak_ahead: s.peak_ahead,
        }
    }

    /// The control at the start of an interval: `h0` on the ray's first; `hmax` after a gap
    /// of empty space (skipped), as if the gap's steps had been taken (they all succeed, and
    /// grow to `hmax`), so that skipping changes the steps taken in occupied space as little
    /// as possible and does not restart the growth from `h0` at every occupied span.
    pub(super) fn start(p: &AdaptiveParams, after_gap: bool) -> Self {
        let standard = p.control == StepControl::CoupledStandard;
        if after_gap {
            Self {
                h: p.hmax,
                successes: 2,
                standard,
                hmin: p.hmin,
                peak_ahead: 0.0,
            }
        } else {
            Self {
                h: p.h0,
                successes: 0,
                standard,
                hmin: p.hmin,
                peak_ahead: 0.0,
            }
        }
    }
}

/// The growth factor of the error-per-step controller after an accepted step: at most 1 right
/// after a failure (`successes == 1`), so that a step that just failed is not retried longer.
pub fn standard_growth(err: f64, tol: f64, successes: u32) -> f64 {
    let f = standard_factor(err, tol);
    if successes <= 1 {
        f.min(1.0)
    } else {
        f
    }
}

/// A quarter of a step that hides a peak and is at most this many times `hmin` long is
/// searched by `hmin` steps at once: at the quarter's own spacing the peak would most likely
/// stay hidden (TF peaks are narrow), and the refused step costs more than the few `hmin`
/// steps the quarter holds. Measured on the phantom of `--suite targets` (hmin 0.4, hmax 4):
/// 3 % fewer steps than searching every quarter.
pub const PEAK_NEAR_HMIN: f64 = 4.0;
