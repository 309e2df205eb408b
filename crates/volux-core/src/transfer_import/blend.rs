//! The blend of two VTK transfer-function nodes, shared by the opacity curve
//! ([`super::vtk_piecewise_value`]) and the colour spaces.

/// How VTK blends two nodes at position `s` of their segment (after the midpoint shift),
/// by the left node's sharpness (`vtkPiecewiseFunction::GetTable`, and the same in
/// `vtkColorTransferFunction`): a step above 0.99, linear below 0.01, otherwise a Hermite
/// curve of `s` sharpened by the power `1 + 10 sharpness` with both slopes
/// `(1 - sharpness) (right - left)`.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Blend {
    /// The left value before the middle, the right one from it.
    Step {
        /// Whether the right value applies.
        right: bool,
    },
    /// Linear at `s`.
    Linear {
        /// Position in the segment.
        s: f64,
    },
    /// Hermite at the sharpened `s`.
    Hermite {
        /// The sharpened position.
        s: f64,
        /// The Hermite basis h1..h4 at `s`.
        h: [f64; 4],
        /// `1 - sharpness`.
        slope: f64,
    },
}

impl Blend {
    /// The blend at position `s` for the left node's `sharpness`.
    pub(crate) fn new(s: f64, sharpness: f64) -> Self {
        if sharpness > 0.99 {
            return Self::Step { right: s >= 0.5 };
        }
        if sharpness < 0.01 {
            return Self::Linear { s };
        }
        let p = 1.0 + 10.0 * sharpness;
        let s = if s < 0.5 {
            0.5 * (s * 2.0).powf(p)
        } else if s > 0.5 {
            1.0 - 0.5 * ((1.0 - s) * 2.0).powf(p)
        } else {
            s
        };
        let (ss, sss) = (s * s, s * s * s);
        let h = [
            2.0 * sss - 3.0 * ss + 1.0,
            -2.0 * sss + 3.0 * ss,
            sss - 2.0 * ss + s,
            sss - ss,
        ];
        Self::Hermite {
            s,
            h,
            slope: 1.0 - sharpness,
        }
    }

    /// The position a colour space interpolates at (the sharpened one for Hermite).
    pub(crate) fn position(&self) -> f64 {
        match *self {
            Self::Step { right } => f64::from(u8::from(right)),
            Self::Linear { s } | Self::Hermite { s, .. } => s,
        }
    }

    /// The blend of the left value `p` and the right value `q` (unclamped).
    pub(crate) fn mix(&self, p: f64, q: f64) -> f64 {
        match *self {
            Self::Step { right } => {
                if right {
                    q
                } else {
                    p
                }
            }
            Self::Linear { s } => (1.0 - s) * p + s * q,
            Self::Hermite { h, slope, .. } => {
                let t = slope * (q - p);
                h[0] * p + h[1] * q + h[2] * t + h[3] * t
            }
        }
    }
}
