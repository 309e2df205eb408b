//! A lane's ray taken out of the lanes between two rounds and put back later, possibly into
//! another slot of other lanes ([`LaneRay`]): a distributed render integrates each region's
//! piece of a ray and hands the state on (`001_...txt` ch. 4, Algorithm 3, with its step,
//! streak of successes, lookahead and transmittance carried across).
use super::{AdaptiveLanes, Phase};
use crate::integrate::adaptive::state::LaneRay;

impl AdaptiveLanes {
    /// The state of the ray in slot `r`, paused ([`AdaptiveLanes::is_paused`]): its next
    /// step proposed, not sampled.
    pub fn export(&self, r: usize) -> LaneRay {
        LaneRay {
            t: self.t[r],
            t_end: self.t_end[r],
            h: self.h[r],
            to_end: self.to_end[r],
            step_h: self.step_h[r],
            successes: self.successes[r],
            new_points: self.new_points[r],
            peak_ahead: self.peak_ahead[r],
            tol_per_length: self.tol_per_length[r],
            rgb0: [0, 1, 2].map(|c| self.rgb0[c][r]),
            tau0: self.tau0[r],
            value0: self.value0[r],
            at_or_below0: self.at_or_below0[r],
            below0: self.below0[r],
            depth: self.depth[r],
            trans: self.trans[r],
            color: [0, 1, 2].map(|c| self.color[c][r]),
            error: self.error[r],
            missed: self.missed[r],
            samples: self.samples[r],
        }
    }

    /// Puts the ray `s` (from [`AdaptiveLanes::export`]) into slot `r`, to take its next
    /// step in the next round and pause before a step starting at or past `t_stop`.
    pub fn import(&mut self, r: usize, s: &LaneRay, t_stop: f64) {
        self.phase[r] = Phase::Stepping;
        self.after_gap[r] = true;
        self.t_stop[r] = t_stop;
        (self.t[r], self.t_end[r], self.h[r]) = (s.t, s.t_end, s.h);
        (self.to_end[r], self.step_h[r]) = (s.to_end, s.step_h);
        (self.successes[r], self.new_points[r]) = (s.successes, s.new_points);
        (self.peak_ahead[r], self.tol_per_length[r]) = (s.peak_ahead, s.tol_per_length);
        for c in 0..3 {
            self.rgb0[c][r] = s.rgb0[c];
            self.color[c][r] = s.color[c];
        }
        (self.tau0[r], self.value0[r]) = (s.tau0, s.value0);
        (self.at_or_below0[r], self.below0[r]) = (s.at_or_below0, s.below0);
        (self.depth[r], self.trans[r]) = (s.depth, s.trans);
        (self.error[r], self.missed[r], self.samples[r]) = (s.error, s.missed, s.samples);
    }
}
