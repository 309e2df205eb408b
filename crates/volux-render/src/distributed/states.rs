//! Ray states as messages of `f32` ([`encode`], [`decode`]), the words of the pipeline of
//! adaptive Simpson (seed `003`'s blocks, made exact; the state is that of `001_...txt`
//! ch. 4's integrator). A state is a tag word and its fields, each `f64` or `u64` as two
//! words of its bits, each `f32` as itself, each `u32` or flag as one word of its bits:
//! bit for bit what the sender had.
use super::error::DistributedError;
use crate::integrate::adaptive::state::{F64Ray, LaneRay, RayState, StepState};
use crate::integrate::Medium;

const START: u32 = 0;
const F64: u32 = 1;
const LANES: u32 = 2;
const DONE: u32 = 3;

/// The words of `states`, after `out`'s.
pub fn encode(states: &[RayState], out: &mut Vec<f32>) {
    let mut w = Words(out);
    for s in states {
        match s {
            RayState::Start => w.u32(START),
            RayState::F64(s) => {
                w.u32(F64);
                w.f64ray(s);
            }
            RayState::Lanes(s) => {
                w.u32(LANES);
                w.lane(s);
            }
            RayState::Done(rgba) => {
                w.u32(DONE);
                rgba.iter().for_each(|&v| w.f32(v));
            }
        }
    }
}

/// `n` states from `words` ([`encode`]'s), which must hold exactly them.
pub fn decode(words: &[f32], n: usize) -> Result<Vec<RayState>, DistributedError> {
    let mut r = Reader { words, at: 0 };
    let out = (0..n).map(|_| r.state()).collect::<Result<Vec<_>, _>>()?;
    if r.at != words.len() {
        return Err(bad("words left after the states"));
    }
    Ok(out)
}

fn bad(what: &str) -> DistributedError {
    DistributedError::Exchange(format!("a message of ray states: {what}"))
}

struct Words<'a>(&'a mut Vec<f32>);

impl Words<'_> {
    fn f32(&mut self, v: f32) {
        self.0.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.0.push(f32::from_bits(v));
    }
    fn u64(&mut self, v: u64) {
        self.u32((v >> 32) as u32);
        self.u32(v as u32);
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn step(&mut self, s: &StepState) {
        self.f64(s.h);
        self.u32(s.successes);
        self.f64(s.peak_ahead);
    }
    fn f64ray(&mut self, s: &F64Ray) {
        self.f64(s.t);
        s.first.rgb.iter().for_each(|&c| self.f64(c));
        self.f64(s.first.tau);
        self.f64(s.first.value);
        self.step(&s.inner);
        self.step(&s.outer);
        s.color.iter().for_each(|&c| self.f64(c));
        self.f64(s.depth);
        self.f64(s.trans);
        self.u64(s.samples);
        self.f64(s.error);
        self.u32(u32::from(s.missed));
    }
    fn lane(&mut self, s: &LaneRay) {
        for v in [s.t, s.t_end, s.h, s.step_h, s.peak_ahead, s.tol_per_length] {
            self.f32(v);
        }
        self.u32(u32::from(s.to_end));
        self.u32(s.successes);
        self.u64(s.new_points);
        s.rgb0.iter().for_each(|&c| self.f32(c));
        for v in [s.tau0, s.value0, s.at_or_below0, s.below0, s.depth, s.trans] {
            self.f32(v);
        }
        s.color.iter().for_each(|&c| self.f32(c));
        self.f32(s.error);
        self.u32(u32::from(s.missed));
        self.u64(s.samples);
    }
}

struct Reader<'a> {
    words: &'a [f32],
    at: usize,
}

impl Reader<'_> {
    fn u32(&mut self) -> Result<u32, DistributedError> {
        let v = self.words.get(self.at).ok_or_else(|| bad("too short"))?;
        self.at += 1;
        Ok(v.to_bits())
    }
    fn f32(&mut self) -> Result<f32, DistributedError> {
        self.u32().map(f32::from_bits)
    }
    fn u64(&mut self) -> Result<u64, DistributedError> {
        Ok((u64::from(self.u32()?) << 32) | u64::from(self.u32()?))
    }
    fn f64(&mut self) -> Result<f64, DistributedError> {
        self.u64().map(f64::from_bits)
    }
    fn flag(&mut self) -> Result<bool, DistributedError> {
        Ok(self.u32()? != 0)
    }
    fn f32s<const N: usize>(&mut self) -> Result<[f32; N], DistributedError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f32()?;
        }
        Ok(out)
    }
    fn f64s<const N: usize>(&mut self) -> Result<[f64; N], DistributedError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64()?;
        }
        Ok(out)
    }
    fn step(&mut self) -> Result<StepState, DistributedError> {
        Ok(StepState {
            h: self.f64()?,
            successes: self.u32()?,
            peak_ahead: self.f64()?,
        })
    }
    fn state(&mut self) -> Result<RayState, DistributedError> {
        Ok(match self.u32()? {
            START => RayState::Start,
            F64 => RayState::F64(self.f64ray()?),
            LANES => RayState::Lanes(self.lane()?),
            DONE => RayState::Done(self.f32s()?),
            tag => return Err(bad(&format!("unknown tag {tag}"))),
        })
    }
    fn f64ray(&mut self) -> Result<F64Ray, DistributedError> {
        let t = self.f64()?;
        let [r, g, b, tau, value] = self.f64s()?;
        let first = Medium {
            rgb: [r, g, b],
            tau,
            value,
        };
        Ok(F64Ray {
            t,
            first,
            inner: self.step()?,
            outer: self.step()?,
            color: self.f64s()?,
            depth: self.f64()?,
            trans: self.f64()?,
            samples: self.u64()?,
            error: self.f64()?,
            missed: self.flag()?,
        })
    }
    fn lane(&mut self) -> Result<LaneRay, DistributedError> {
        let [t, t_end, h, step_h, peak_ahead, tol_per_length] = self.f32s()?;
        let (to_end, successes, new_points) = (self.flag()?, self.u32()?, self.u64()?);
        let rgb0 = self.f32s()?;
        let [tau0, value0, at_or_below0, below0, depth, trans] = self.f32s()?;
        Ok(LaneRay {
            t,
            t_end,
            h,
            to_end,
            step_h,
            successes,
            new_points,
            peak_ahead,
            tol_per_length,
            rgb0,
            tau0,
            value0,
            at_or_below0,
            below0,
            depth,
            trans,
            color: self.f32s()?,
            error: self.f32()?,
            missed: self.flag()?,
            samples: self.u64()?,
        })
    }
}
