//! The state adaptive Simpson (`001_...txt` ch. 4, Algorithms 3 and 4) carries along one
//! ray between two steps, so that a ray can be integrated piece by piece and still take the
//! very steps, with the very decisions, of the whole ray integrated at once: its position,
//! the step the control proposes and its streak of successes, the lookahead on a hidden
//! peak, the optical depth and transmittance, the colour, the error and the sample count,
//! and the sample at the position (the next step's first point). A distributed render hands
//! it from region to region in visibility order (seed `003`'s blocks, made exact).
//!
//! [`F64Ray`] is the state of the f64 integrator
//! ([`adaptive_simpson_resume`](super::adaptive_simpson_resume)), [`LaneRay`]
//! that of one slot of the f32 lanes ([`AdaptiveLanes`](super::lanes::AdaptiveLanes));
//! [`RayState`] is a pixel's ray, whichever integrator the ray caster gives it.
use crate::integrate::medium::Medium;

/// The step control of one integral between two steps (`StepSize` of the f64 integrator).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepState {
    /// The step proposed.
    pub h: f64,
    /// Consecutive successes.
    pub successes: u32,
    /// The length of a hidden peak's quarter to step next (0: none).
    pub peak_ahead: f64,
}

/// The f64 integrator's ray between two steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct F64Ray {
    /// Where the next step starts.
    pub t: f64,
    /// The sample at `t`.
    pub first: Medium,
    /// The step control (coupled), or the inner integral's (decoupled).
    pub inner: StepState,
    /// The outer integral's step control (decoupled; unused when coupled).
    pub outer: StepState,
    /// Colour so far.
    pub color: [f64; 3],
    /// Optical depth so far, and `exp(-depth)`.
    pub depth: f64,
    /// Transmittance.
    pub trans: f64,
    /// Samples taken.
    pub samples: u64,
    /// Estimated error so far.
    pub error: f64,
    /// Whether a step missed the tolerance (accepted at `hmin`).
    pub missed: bool,
}

/// One slot of the f32 lanes between two rounds, the next step proposed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LaneRay {
    /// Where the next step starts.
    pub t: f32,
    /// The end of the ray (f32).
    pub t_end: f32,
    /// The next step, and whether it ends the ray.
    pub h: f32,
    /// Whether the next step ends the ray.
    pub to_end: bool,
    /// The step the control proposes, and its consecutive successes.
    pub step_h: f32,
    /// Consecutive successes.
    pub successes: u32,
    /// How many of the next step's points are new.
    pub new_points: u64,
    /// The length of a hidden peak's quarter to step next (0: none).
    pub peak_ahead: f32,
    /// Allowed error per unit length.
    pub tol_per_length: f32,
    /// The sample at `t`: colour, extinction, value, breakpoint counts.
    pub rgb0: [f32; 3],
    /// Extinction at `t`.
    pub tau0: f32,
    /// Value at `t`.
    pub value0: f32,
    /// Breakpoints at or below the value at `t`.
    pub at_or_below0: f32,
    /// Breakpoints below the value at `t`.
    pub below0: f32,
    /// Optical depth so far.
    pub depth: f32,
    /// Transmittance.
    pub trans: f32,
    /// Colour so far.
    pub color: [f32; 3],
    /// Estimated error so far.
    pub error: f32,
    /// Whether a step missed the tolerance.
    pub missed: bool,
    /// Samples taken.
    pub samples: u64,
}

/// A pixel's ray in a piecewise integration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum RayState {
    /// Not begun: the first piece that holds the ray's entry starts it.
    #[default]
    Start,
    /// Begun, in the f64 integrator.
    F64(F64Ray),
    /// Begun, in the f32 lanes.
    Lanes(LaneRay),
    /// Finished (the ray's end reached, or opaque): its premultiplied RGBA.
    Done([f32; 4]),
}

impl RayState {
    /// The pixel of a ray no later piece continues: a finished ray's colour, nothing for a
    /// ray never begun (it missed the volume), or the colour so far.
    pub fn rgba(&self) -> [f32; 4] {
        let from = |c: [f64; 3], depth: f64| [c[0], c[1], c[2], 1.0 - (-depth).exp()];
        let v = match self {
            RayState::Start => return [0.0; 4],
            RayState::Done(rgba) => return *rgba,
            RayState::F64(s) => from(s.color, s.depth),
            RayState::Lanes(s) => from(s.color.map(f64::from), f64::from(s.depth)),
        };
        v.map(|v| v as f32)
    }
}
