//! Coupled adaptive Simpson (`001_...txt` Algorithm 3) for [`RAYS`] rays at once, in f32
//! lanes: the fast path of traversals that can sample several rays together.
//!
//! The step control is the one of [`adaptive`](super): five points per step, the error
//! estimate `(S2 - S1) / 15` per channel R, G, B, A, the tolerance scaled with the step, a
//! failed step halved, the step doubled after two consecutive successes, `hmin`/`hmax`, steps
//! refined where the transfer function hides a peak between two samples. What differs is the
//! arithmetic:
//!
//! - each round takes the four new points `t + k h / 4` (`k = 1..4`) of every ray's step in
//!   one [`LANES`](crate::sampling::LANES)-lane call of the sampler, lane `(k - 1) RAYS + r`
//!   holding ray `r`'s point `k`, so that one point of all rays is one contiguous group;
//! - the rules, the error estimates and the step decisions are computed for all rays together
//!   in f32, the transmittance by a polynomial `exp` over the lanes ([`exp_lanes`]);
//! - a halved step takes its four points again, although two are known: the lanes are there
//!   anyway (the round's sampler call has sixteen), and a uniform round keeps every operation
//!   lane-wise. The same positions give the same values; [`RayIntegral::samples`] counts
//!   distinct points, as the f64 integrator does.
//!
//! f32 rounding of a step's sums is about 1e-7 of the step's integral, far below the error
//! allowed per step for tolerances of [`AdaptiveLanes::MIN_TOL`] and above; the f64 integrator
//! serves smaller tolerances and the reference.
use super::{
    standard_factor, standard_growth, AdaptiveParams, StepControl, PEAK_NEAR_HMIN, SAFETY,
};
use crate::integrate::medium::RayIntegral;

/// Rays integrated together.
pub const RAYS: usize = 4;

/// Lanes of a round: four new points per ray.
pub const LANES: usize = 4 * RAYS;

/// The classified samples of one round: lane `(k - 1) RAYS + r` is ray `r`'s point `k`.
#[derive(Clone, Copy, Debug, Default)]
pub struct LaneMedia {
    /// Linear RGB emission per lane.
    pub rgb: [[f32; LANES]; 3],
    /// Extinction per world unit per lane (0 where the field is undefined).
    pub tau: [f32; LANES],
    /// The scalar value classified (0 where undefined), for the hidden-peak test.
    pub value: [f32; LANES],
    /// The number of transfer-function breakpoints at or below the value, or a lower bound
    /// (a table-based traversal reads bounds from
    /// [`BreakpointRanks`](crate::classify::BreakpointRanks)).
    pub breakpoints_at_or_below: [f32; LANES],
    /// The number of breakpoints strictly below the value, or an upper bound.
    pub breakpoints_below: [f32; LANES],
}

/// Where a ray stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// No ray in this slot.
    Idle,
    /// Between intervals: the caller enters the next one or finishes the ray.
    NeedsSpan,
    /// The next round samples the first point of the interval just entered.
    Entering,
    /// The next round samples the current step's points.
    Stepping,
    /// Stopped before a step starting at or past the ray's stop
    /// ([`AdaptiveLanes::stop_at`]): the caller exports its state.
    Paused,
}

/// Coupled adaptive Simpson over [`RAYS`] rays, each over disjoint ordered intervals, driven
/// by a traversal: [`AdaptiveLanes::start`] a ray in a slot and [`AdaptiveLanes::enter`] its
/// intervals while [`AdaptiveLanes::needs_span`]; each round, sample the
/// [`AdaptiveLanes::distances`] and hand the classified samples to
/// [`AdaptiveLanes::supply`]. The same rules and decisions as
/// [`adaptive_simpson_intervals`](super::adaptive_simpson_intervals) with coupled control,
/// in f32.
pub struct AdaptiveLanes {
    h0: f32,
    hmin: f32,
    hmax: f32,
    /// Quarters hiding a peak up to this long are searched by `hmin` steps
    /// ([`PEAK_NEAR_HMIN`] `hmin`).
    peak_near_hmin: f32,
    /// Steps at or below this are accepted whatever their error.
    hmin_accept: f32,
    /// Optical depth at which the early-termination opacity is reached.
    depth_stop: f32,
    tol: f32,
    phase: [Phase; RAYS],
    /// Start of the current step, end of the current interval, the step, and whether it ends
    /// the interval.
    t: [f32; RAYS],
    t_end: [f32; RAYS],
    h: [f32; RAYS],
    to_end: [bool; RAYS],
    /// Where the ray pauses: before a step starting at or past it (infinite: never).
    t_stop: [f64; RAYS],
    /// Whether steps are sized by the error-per-step controller
    /// ([`standard_factor`](super::adaptive::standard_factor)) rather than Algorithm 3.
    standard: bool,
    /// The step the control proposes, and its consecutive successes.
    step_h: [f32; RAYS],
    successes: [u32; RAYS],
    /// How many of the current step's four points are new (the others were sampled before).
    new_points: [u64; RAYS],
    /// Where the step proposed ends at the quarter of a refused step that hid a peak: that
    /// quarter's length, the step after it (0: none).
    peak_ahead: [f32; RAYS],
    /// Whether the ray has integrated an interval (the next one follows a gap).
    after_gap: [bool; RAYS],
    /// Allowed error per unit length.
    tol_per_length: [f32; RAYS],
    /// The sample at the start of the step, and its breakpoint counts.
    rgb0: [[f32; RAYS]; 3],
    tau0: [f32; RAYS],
    value0: [f32; RAYS],
    at_or_below0: [f32; RAYS],
    below0: [f32; RAYS],
    /// The integrals so far: optical depth, transmittance `exp(-depth)`, colour, error.
    depth: [f32; RAYS],
    trans: [f32; RAYS],
    color: [[f32; RAYS]; 3],
    error: [f32; RAYS],
    missed: [bool; RAYS],
    samples: [u64; RAYS],
}

/// A step's rules for all rays (point 0 is the step's start, 4 its end).
struct Rules {
    depth_end: [f32; RAYS],
    trans_end: [f32; RAYS],
    color: [[f32; RAYS]; 3],
    /// Largest error estimate of R, G, B and A.
    error: [f32; RAYS],
}

impl AdaptiveLanes {
    /// The smallest tolerance this f32 integrator accepts (see the module docs).
    pub const MIN_TOL: f64 = 1e-3;

    /// Lanes for the parameters `p` (world units, coupled control).
    pub fn new(p: &AdaptiveParams) -> Self {
        let a = p.early_termination.map_or(2.0, |a| a.min(1.0));
        Self {
            h0: p.h0 as f32,
            hmin: p.hmin as f32,
            hmax: p.hmax as f32,
            peak_near_hmin: (PEAK_NEAR_HMIN * p.hmin) as f32,
            hmin_accept: (p.hmin * (1.0 + 1e-6)) as f32,
            depth_stop: if a < 1.0 {
                -((1.0 - a).ln()) as f32
            } else {
                f32::INFINITY
            },
            tol: (SAFETY * p.tol) as f32,
            phase: [Phase::Idle; RAYS],
            t: [0.0; RAYS],
            t_end: [0.0; RAYS],
            h: [0.0; RAYS],
            to_end: [false; RAYS],
            t_stop: [f64::INFINITY; RAYS],
            standard: p.control == StepControl::CoupledStandard,
            step_h: [0.0; RAYS],
            successes: [0; RAYS],
            new_points: [4; RAYS],
            peak_ahead: [0.0; RAYS],
            after_gap: [false; RAYS],
            tol_per_length: [0.0; RAYS],
            rgb0: [[0.0; RAYS]; 3],
            tau0: [0.0; RAYS],
            value0: [0.0; RAYS],
            at_or_below0: [0.0; RAYS],
            below0: [0.0; RAYS],
            depth: [0.0; RAYS],
            trans: [1.0; RAYS],
            color: [[0.0; RAYS]; 3],
            error: [0.0; RAYS],
            missed: [false; RAYS],
            samples: [0; RAYS],
        }
    }

    /// Starts a ray in slot `r` whose intervals have total length `len` (the tolerance is
    /// shared over it); it then needs its first interval.
    pub fn start(&mut self, r: usize, len: f64) {
        self.phase[r] = Phase::NeedsSpan;
        self.after_gap[r] = false;
        self.t_stop[r] = f64::INFINITY;
        self.tol_per_length[r] = if len > 0.0 {
            (f64::from(self.tol) / len) as f32
        } else {
            0.0
        };
        self.depth[r] = 0.0;
        self.trans[r] = 1.0;
        for c in 0..3 {
            self.color[c][r] = 0.0;
        }
        self.error[r] = 0.0;
        self.missed[r] = false;
        self.samples[r] = 0;
    }

    /// Empties slot `r`.
    pub fn idle(&mut self, r: usize) {
        self.phase[r] = Phase::Idle;
    }

    /// Whether the ray in slot `r` waits for its next interval (or to be finished).
    pub fn needs_span(&self, r: usize) -> bool {
        self.phase[r] == Phase::NeedsSpan
    }

    /// Pauses the ray in slot `r` before its first step that would start at or past `t`
    /// (a step starting before it is taken whole).
    pub fn stop_at(&mut self, r: usize, t: f64) {
        self.t_stop[r] = t;
    }

    /// Whether the ray in slot `r` has paused at its stop ([`AdaptiveLanes::stop_at`]).
    pub fn is_paused(&self, r: usize) -> bool {
        self.phase[r] == Phase::Paused
    }

    /// Whether the ray in slot `r` has reached the early-termination opacity.
    pub fn is_opaque(&self, r: usize) -> bool {
        self.depth[r] >= self.depth_stop
    }

    /// Whether some slot has a round to take.
    pub fn is_busy(&self) -> bool {
        self.phase
            .iter()
            .any(|&p| p == Phase::Entering || p == Phase::Stepping)
    }

    /// The ray in slot `r` enters the interval `[t0, t1]`; false (nothing entered) if it is
    /// empty in f32.
    pub fn enter(&mut self, r: usize, (t0, t1): (f64, f64)) -> bool {
        let (a, b) = (t0 as f32, t1 as f32);
        if b <= a {
            return false;
        }
        (self.phase[r], self.t[r], self.t_end[r]) = (Phase::Entering, a, b);
        // As the f64 integrator: `h0` on the first interval, `hmax` after a skipped gap.
        (self.step_h[r], self.successes[r]) = if self.after_gap[r] {
            (self.hmax, 2)
        } else {
            (self.h0, 0)
        };
        self.after_gap[r] = true;
        true
    }

    /// The distances to sample this round, lane `(k - 1) RAYS + r` for ray `r`'s point `k`
    /// (an entering ray asks for its interval's start in all its lanes; an idle slot for 0).
    pub fn distances(&self) -> [f32; LANES] {
        let mut out = [0.0; LANES];
        for k in 0..4 {
            for r in 0..RAYS {
                let along = if self.phase[r] == Phase::Stepping {
                    self.h[r] * (k + 1) as f32 * 0.25
                } else {
                    0.0
                };
                out[k * RAYS + r] = self.t[r] + along;
            }
        }
        out
    }

    /// Takes the round's samples at [`AdaptiveLanes::distances`]: entering rays keep their
    /// first sample, stepping rays accept their step (and propose the next) or halve it.
    pub fn supply(&mut self, m: &LaneMedia) {
        let rules = self.rules(m);
        let peaks = self.hides_peaks(m);
        for (r, &quarter) in peaks.iter().enumerate() {
            match self.phase[r] {
                Phase::Entering => {
                    self.keep_start(r, m, 0);
                    self.samples[r] += 1;
                    self.phase[r] = Phase::Stepping;
                    self.propose(r);
                }
                Phase::Stepping => self.judge(r, m, &rules, quarter),
                Phase::Idle | Phase::NeedsSpan | Phase::Paused => {}
            }
        }
    }

    /// The integral of the ray in slot `r` so far.
    pub fn result(&self, r: usize) -> RayIntegral {
        let c = [0, 1, 2].map(|c| f64::from(self.color[c][r]));
        let mut out = RayIntegral::from_parts(c, f64::from(self.depth[r]), self.samples[r]);
        out.error = f64::from(self.error[r]);
        out.tolerance_missed = self.missed[r];
        out
    }

    /// Accepts or halves ray `r`'s step (Algorithm 3, lines 7-13).
    fn judge(&mut self, r: usize, m: &LaneMedia, rules: &Rules, quarter: u8) {
        let blind = quarter != 0;
        let h = self.h[r];
        let tol_h = self.tol_per_length[r] * h;
        let err = rules.error[r];
        self.samples[r] += self.new_points[r];
        if (err <= tol_h && !blind) || h <= self.hmin_accept {
            for c in 0..3 {
                self.color[c][r] += rules.color[c][r];
            }
            (self.depth[r], self.trans[r]) = (rules.depth_end[r], rules.trans_end[r]);
            self.error[r] += err;
            self.missed[r] |= err > tol_h;
            self.keep_start(r, m, 3);
            self.successes[r] += 1;
            self.grow(r, h, err, tol_h);
            if self.to_end[r] || self.is_opaque(r) {
                self.t[r] = self.t_end[r];
                self.phase[r] = Phase::NeedsSpan;
            } else {
                self.t[r] += h;
                self.propose(r);
                if f64::from(self.t[r]) >= self.t_stop[r] {
                    self.phase[r] = Phase::Paused;
                }
            }
        } else if self.standard && blind {
            self.before_peak(r, h, quarter);
        } else if self.standard && self.shrink(r, h, err, tol_h) {
            // The error-per-step controller proposed a shorter step from the same start.
        } else {
            (self.step_h[r], self.successes[r]) = (h * 0.5, 0);
            (self.h[r], self.to_end[r], self.new_points[r]) = (h * 0.5, false, 2);
        }
    }

    /// The error-per-step controller's next try after ray `r`'s step `h` failed with the error
    /// `err` (`tol` allowed): a new step from the same start, all its points new. False (and
    /// nothing changed) when the proposal is not shorter than `h`, which happens when the
    /// rest of the interval is a sliver over `hmin`: the step is then halved, as Algorithm 3.
    fn shrink(&mut self, r: usize, h: f32, err: f32, tol: f32) -> bool {
        let f = standard_factor(f64::from(err), f64::from(tol)) as f32;
        let next = (h * f).clamp(self.hmin, self.hmax);
        let room = self.t_end[r] - self.t[r];
        let sliver = 64.0 * f32::EPSILON * self.t_end[r].abs();
        if next >= h || next + sliver >= room {
            return false;
        }
        (self.step_h[r], self.successes[r]) = (h * f, 0);
        (self.h[r], self.to_end[r], self.new_points[r]) = (next, false, 4);
        true
    }

    /// The error-per-step controller's next try after ray `r`'s step `h` hid a peak of the
    /// transfer function in its quarter `quarter` (1 to 4): the quarters before it, whose
    /// samples showed none, as one step, then the quarter that hid the peak (see
    /// [`AdaptiveLanes::grow`]); a peak in the first quarter gets that quarter at once. Each
    /// refused step narrows where the peak lies fourfold, down to `hmin`, where halving
    /// (Algorithm 3) narrows it twofold. As the f64 integrator's `StepSize::before_peak`.
    fn before_peak(&mut self, r: usize, h: f32, quarter: u8) {
        let quarter_len = h * 0.25;
        let before = quarter_len * f32::from(quarter - 1);
        // The points of the refused step sampled again: the new end, and for half the step
        // its midpoint too.
        let (next, known, ahead) = if before > self.hmin {
            (before, if quarter == 3 { 2 } else { 1 }, quarter_len)
        } else if quarter_len > self.peak_near_hmin {
            (quarter_len, 1, 0.0)
        } else if self.hmin < h {
            (self.hmin, 0, 0.0)
        } else {
            (h * 0.5, 2, 0.0)
        };
        self.peak_ahead[r] = ahead;
        (self.step_h[r], self.successes[r]) = (next, 0);
        (self.h[r], self.to_end[r], self.new_points[r]) = (next, false, 4 - known);
    }

    /// The step proposed after ray `r`'s step `h` was accepted with the error `err` (`tol`
    /// allowed): doubled after two consecutive successes (Algorithm 3), or scaled by the
    /// error-per-step controller, as [`StepSize`](super::adaptive) in f64.
    fn grow(&mut self, r: usize, h: f32, err: f32, tol: f32) {
        let proposed = self.step_h[r];
        if self.peak_ahead[r] > 0.0 {
            // The step ended where a hidden peak's quarter begins: that quarter next.
            let quarter = self.peak_ahead[r];
            self.step_h[r] = if quarter > self.peak_near_hmin {
                quarter
            } else {
                self.hmin
            };
            self.peak_ahead[r] = 0.0;
        } else if self.standard {
            let f = standard_growth(f64::from(err), f64::from(tol), self.successes[r]) as f32;
            // A step shortened to end its interval does not shrink the proposal.
            let next = if h < proposed {
                (h * f).max(proposed)
            } else {
                h * f
            };
            self.step_h[r] = next.min(self.hmax);
        } else if h >= proposed && self.successes[r] >= 2 {
            self.step_h[r] = (2.0 * proposed).min(self.hmax);
        }
    }

    /// Ray `r`'s point `k` of this round becomes the start of its next step.
    fn keep_start(&mut self, r: usize, m: &LaneMedia, k: usize) {
        let l = k * RAYS + r;
        for c in 0..3 {
            self.rgb0[c][r] = m.rgb[c][l];
        }
        (self.tau0[r], self.value0[r]) = (m.tau[l], m.value[l]);
        self.at_or_below0[r] = m.breakpoints_at_or_below[l];
        self.below0[r] = m.breakpoints_below[l];
    }

    /// Ray `r`'s next step: the proposed one within `[hmin, hmax]`, shortened to the interval.
    /// A step that would leave a sliver of the order of the rounding of `t` goes to the end.
    fn propose(&mut self, r: usize) {
        let h = self.step_h[r].clamp(self.hmin, self.hmax);
        let room = self.t_end[r] - self.t[r];
        let sliver = 64.0 * f32::EPSILON * self.t_end[r].abs();
        (self.h[r], self.to_end[r]) = if h + sliver >= room {
            (room, true)
        } else {
            (h, false)
        };
        self.new_points[r] = 4;
    }

    /// Simpson's rule on each step and on its halves for the optical depth (inner integral)
    /// and the colour (outer integral), with their error estimates; the accepted values carry
    /// the estimate (Richardson, Algorithm 3 line 7).
    // Ray loops index several per-ray arrays at once: that is what vectorizes. No closures
    // or `map`s: they are not always inlined, and a call per element costs more than the sums.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn rules(&self, m: &LaneMedia) -> Rules {
        const FIFTEENTH: f32 = 1.0 / 15.0;
        // The five points of each ray's step, point-major: [k][r].
        let mut tau = [[0.0f32; RAYS]; 5];
        let mut rgb = [[[0.0f32; RAYS]; 5]; 3];
        tau[0] = self.tau0;
        for c in 0..3 {
            rgb[c][0] = self.rgb0[c];
        }
        for k in 1..5 {
            for r in 0..RAYS {
                tau[k][r] = m.tau[(k - 1) * RAYS + r];
                for c in 0..3 {
                    rgb[c][k][r] = m.rgb[c][(k - 1) * RAYS + r];
                }
            }
        }
        // Optical depth at the five points (quadratic through three points on each half) and
        // the depth's error estimate.
        let mut depth = [[0.0f32; RAYS]; 5];
        let mut err_depth = [0.0f32; RAYS];
        let (mut h6, mut h12) = ([0.0f32; RAYS], [0.0f32; RAYS]);
        for r in 0..RAYS {
            let h = self.h[r];
            (h6[r], h12[r]) = (h * (1.0 / 6.0), h * (1.0 / 12.0));
            let h48 = h * (1.0 / 48.0);
            let t = [tau[0][r], tau[1][r], tau[2][r], tau[3][r], tau[4][r]];
            let s1 = h6[r] * (t[0] + 4.0 * t[2] + t[4]);
            let s2 = h12[r] * (t[0] + 4.0 * t[1] + 2.0 * t[2] + 4.0 * t[3] + t[4]);
            err_depth[r] = (s2 - s1) * FIFTEENTH;
            let d0 = self.depth[r];
            let d2 = d0 + h12[r] * (t[0] + 4.0 * t[1] + t[2]);
            depth[0][r] = d0;
            depth[1][r] = d0 + h48 * (5.0 * t[0] + 8.0 * t[1] - t[2]);
            depth[2][r] = d2;
            depth[3][r] = d2 + h48 * (5.0 * t[2] + 8.0 * t[3] - t[4]);
            depth[4][r] = d0 + s2 + err_depth[r];
        }
        let mut x = [0.0f32; LANES];
        for k in 1..5 {
            for r in 0..RAYS {
                x[(k - 1) * RAYS + r] = -depth[k][r];
            }
        }
        exp_lanes(&mut x);
        // A step with no extinction keeps the carried transmittance exactly.
        let mut trans = [self.trans; 5];
        for r in 0..RAYS {
            let opaque = (tau[0][r] != 0.0)
                | (tau[1][r] != 0.0)
                | (tau[2][r] != 0.0)
                | (tau[3][r] != 0.0)
                | (tau[4][r] != 0.0);
            for k in 1..5 {
                let e = x[(k - 1) * RAYS + r];
                trans[k][r] = if opaque { e } else { self.trans[r] };
            }
        }
        let mut error = [0.0f32; RAYS];
        for r in 0..RAYS {
            error[r] = self.trans[r] * err_depth[r].abs();
        }
        let mut color = [[0.0f32; RAYS]; 3];
        for c in 0..3 {
            for r in 0..RAYS {
                let mut g = [0.0f32; 5];
                for k in 0..5 {
                    g[k] = rgb[c][k][r] * tau[k][r] * trans[k][r];
                }
                let c1 = h6[r] * (g[0] + 4.0 * g[2] + g[4]);
                let c2 = h12[r] * (g[0] + 4.0 * g[1] + 2.0 * g[2] + 4.0 * g[3] + g[4]);
                let e = (c2 - c1) * FIFTEENTH;
                color[c][r] = c2 + e;
                let e = e.abs();
                error[r] = if e > error[r] { e } else { error[r] };
            }
        }
        Rules {
            depth_end: depth[4],
            trans_end: trans[4],
            color,
            error,
        }
    }

    /// Per ray, the first quarter of its step (1 to 4; 0: none) where two or more breakpoints
    /// lie strictly between the values at its two ends: the transfer function then has
    /// a peak or valley no sample shows, and the step is refined down to `hmin` (as
    /// [`hides_breakpoints_along`](super::hides_breakpoints_along), from the counts of
    /// [`LaneMedia`]).
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn hides_peaks(&self, m: &LaneMedia) -> [u8; RAYS] {
        // Point-major over the five points: [k RAYS + r].
        let mut v = [0.0f32; LANES + RAYS];
        let (mut at_or_below, mut below) = ([0.0f32; LANES + RAYS], [0.0f32; LANES + RAYS]);
        v[..RAYS].copy_from_slice(&self.value0);
        at_or_below[..RAYS].copy_from_slice(&self.at_or_below0);
        below[..RAYS].copy_from_slice(&self.below0);
        v[RAYS..].copy_from_slice(&m.value);
        at_or_below[RAYS..].copy_from_slice(&m.breakpoints_at_or_below);
        below[RAYS..].copy_from_slice(&m.breakpoints_below);
        let mut out = [0u8; RAYS];
        for k in (1..5).rev() {
            for r in 0..RAYS {
                let (a, b) = ((k - 1) * RAYS + r, k * RAYS + r);
                let (lo, hi) = if v[a] <= v[b] { (a, b) } else { (b, a) };
                if below[hi] >= at_or_below[lo] + 2.0 {
                    out[r] = k as u8;
                }
            }
        }
        out
    }
}

/// `exp(x)` of every lane, in place, for `x <= 0` (the transmittance of an optical depth):
/// Cephes' `expf` (range reduction by `ln 2`, degree-5 polynomial), written without
/// float-to-int casts so that it runs lane-wise on baseline x86-64. Relative error below 3e-7
/// down to `exp(-80)`; below that (no visible light passes) the result is 0, so no subnormal
/// products slow the sums that follow.
#[allow(clippy::excessive_precision)]
pub fn exp_lanes<const N: usize>(x: &mut [f32; N]) {
    // 1.5 * 2^23: adding it rounds to an integer kept in the low mantissa bits.
    const ROUND: f32 = 12_582_912.0;
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    // ln 2 in two parts, the first exact in few bits.
    const LN2_HI: f32 = 0.693_359_375;
    const LN2_LO: f32 = -2.121_944_4e-4;
    for v in x.iter_mut() {
        let a = if *v > -80.0 { *v } else { -80.0 };
        let a = if a < 0.0 { a } else { 0.0 };
        let y = a * LOG2E + ROUND;
        let n = y - ROUND;
        let f = a - n * LN2_HI - n * LN2_LO;
        let mut p = 1.987_569_15e-4f32;
        p = p * f + 1.398_199_95e-3;
        p = p * f + 8.333_451_9e-3;
        p = p * f + 4.166_579_6e-2;
        p = p * f + 1.666_666_55e-1;
        p = p * f + 5.000_000_1e-1;
        let e = p * f * f + f + 1.0;
        // 2^n from the rounded integer's bits (n in [-116, 0]).
        let n_bits = y.to_bits().wrapping_sub(ROUND.to_bits());
        let scale = f32::from_bits(n_bits.wrapping_add(127) << 23);
        *v = if *v >= -80.0 { e * scale } else { 0.0 };
    }
}

mod resume;
#[cfg(test)]
mod tests;
