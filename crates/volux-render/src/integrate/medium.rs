//! The medium along a ray as the integrators see it ([`RayMedium`]), and what integrating a
//! ray gives ([`RayIntegral`]).
/// The medium along one ray, as the integrators see it.
pub trait RayMedium {
    /// Colour (linear RGB) and extinction per world unit at distance `t` along the ray.
    fn at(&mut self, t: f64) -> Medium;

    /// The medium at four distances; media that can compute them together (lane-wise
    /// reconstruction) override it.
    fn at4(&mut self, t: [f64; 4]) -> [Medium; 4] {
        t.map(|t| self.at(t))
    }

    /// Whether the classification may vary in a way samples at scalar values `a` and `b`
    /// cannot see (e.g. a transfer-function peak lies strictly between them). Adaptive
    /// integration refines such steps down to `hmin` instead of trusting its error estimate.
    fn hides_features(&self, _a: f64, _b: f64) -> bool {
        false
    }

    /// Whether [`RayMedium::hides_features`] holds between any two neighbouring samples of
    /// `values` (in ray order); media override it to answer for all pairs at once.
    fn hides_features_along(&self, values: &[f64; 5]) -> bool {
        values.windows(2).any(|w| self.hides_features(w[0], w[1]))
    }

    /// The first pair of neighbouring samples of `values` between which
    /// [`RayMedium::hides_features`] holds, as the quarter of a five-point step it spans (1
    /// to 4), or 0 where none does.
    fn hidden_quarter(&self, values: &[f64; 5]) -> usize {
        if !self.hides_features_along(values) {
            return 0;
        }
        (1..5)
            .find(|&k| self.hides_features(values[k - 1], values[k]))
            .unwrap_or(4)
    }
}

/// Whether two or more of the sorted `breakpoints` lie strictly between `a` and `b`: the
/// piecewise-linear classification then has a peak or valley no sample shows.
pub fn hides_breakpoints(breakpoints: &[f64], a: f64, b: f64) -> bool {
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    // Adaptive integration asks this for every pair of neighbouring samples: for the few
    // breakpoints of a usual TF, branch-free counts beat a binary search's mispredictions.
    let (first, last) = if breakpoints.len() <= 32 {
        breakpoints.iter().fold((0, 0), |(f, l), &x| {
            (f + usize::from(x <= lo), l + usize::from(x < hi))
        })
    } else {
        (
            breakpoints.partition_point(|&x| x <= lo),
            breakpoints.partition_point(|&x| x < hi),
        )
    };
    last >= first + 2
}

/// [`hides_breakpoints`] for every pair of neighbouring `values`: each value's rank among
/// the breakpoints is counted once rather than once per pair it belongs to.
pub fn hides_breakpoints_along<const N: usize>(breakpoints: &[f64], values: &[f64; N]) -> bool {
    if breakpoints.len() < 2 {
        return false;
    }
    if breakpoints.len() > 32 {
        return values
            .windows(2)
            .any(|w| hides_breakpoints(breakpoints, w[0], w[1]));
    }
    // Breakpoints at or below each value, and strictly below it.
    let (mut at_or_below, mut below) = ([0usize; N], [0usize; N]);
    for &x in breakpoints {
        for k in 0..N {
            at_or_below[k] += usize::from(x <= values[k]);
            below[k] += usize::from(x < values[k]);
        }
    }
    (1..N).any(|k| {
        let (lo, hi) = if values[k - 1] <= values[k] {
            (k - 1, k)
        } else {
            (k, k - 1)
        };
        below[hi] >= at_or_below[lo] + 2
    })
}

/// Colour and extinction at one point of a ray, in f64 for the accurate integrators.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Medium {
    /// Linear RGB emission.
    pub rgb: [f64; 3],
    /// Extinction per world unit.
    pub tau: f64,
    /// The scalar value classified (for [`RayMedium::hides_features`]); 0 when unknown.
    pub value: f64,
}

impl<F: FnMut(f64) -> Medium> RayMedium for F {
    fn at(&mut self, t: f64) -> Medium {
        self(t)
    }
}

/// The result of integrating one ray.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayIntegral {
    /// Premultiplied RGBA.
    pub rgba: [f64; 4],
    /// Samples of the medium taken.
    pub samples: u64,
    /// Estimated absolute error (largest channel), where the integrator estimates it.
    pub error: f64,
    /// Whether some step was accepted only because it reached `hmin` (tolerance not met).
    pub tolerance_missed: bool,
}

impl RayIntegral {
    pub(crate) fn from_parts(c: [f64; 3], depth: f64, samples: u64) -> Self {
        Self {
            rgba: [c[0], c[1], c[2], 1.0 - (-depth).exp()],
            samples,
            ..Default::default()
        }
    }
}
