//! [`Integrator`]: how a grid ray caster integrates each ray.
use super::adaptive::{AdaptiveParams, StepControl};
use crate::error::{Setting, SettingError};

/// How rays are integrated; lengths are in voxel units (of the smallest grid spacing), as in
/// the seed, and converted to world units by the traversal.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Integrator {
    /// Left Riemann sum with step-corrected opacity.
    Riemann {
        /// Step.
        step: f64,
    },
    /// Fixed-step trapezoid rule.
    Trapezoid {
        /// Step.
        step: f64,
    },
    /// Fixed-step Simpson rule.
    Simpson {
        /// Step.
        step: f64,
    },
    /// Iterative adaptive Simpson with error control.
    AdaptiveSimpson(AdaptiveParams),
    /// Pre-integrated classification: each step's colour and opacity looked up in a table
    /// over (front value, back value), exact for a linear field within the step.
    Preintegrated {
        /// Step.
        step: f64,
    },
    /// The f64 ground truth: adaptive Simpson at a tolerance of 1e-7, exact classification,
    /// f64 reconstruction, and steps that never straddle a voxel boundary (where the
    /// trilinear field has a kink), so the result is accurate to about 1e-6.
    Reference,
}

impl Integrator {
    /// The adaptive parameters of the reference integrator (voxel units).
    pub const REFERENCE: AdaptiveParams = AdaptiveParams {
        tol: 1e-7,
        h0: 0.25,
        hmin: 1e-5,
        hmax: 0.5,
        control: StepControl::Coupled,
        early_termination: None,
    };

    /// The CLI name.
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Riemann { .. } => "riemann",
            Integrator::Trapezoid { .. } => "trapezoid",
            Integrator::Simpson { .. } => "simpson",
            Integrator::AdaptiveSimpson(p) if p.control == StepControl::Coupled => {
                "adaptive-coupled"
            }
            Integrator::AdaptiveSimpson(p) if p.control == StepControl::CoupledStandard => {
                "adaptive-standard"
            }
            Integrator::AdaptiveSimpson(_) => "adaptive-decoupled",
            Integrator::Preintegrated { .. } => "preintegrated",
            Integrator::Reference => "reference",
        }
    }

    /// Checks steps and tolerances.
    pub fn validate(&self) -> Result<(), SettingError> {
        let pos = |setting: Setting, v: f64| {
            if v.is_finite() && v >= 1e-6 {
                Ok(())
            } else {
                Err(SettingError::new(setting, v, ">= 1e-6"))
            }
        };
        match self {
            Integrator::Riemann { step }
            | Integrator::Trapezoid { step }
            | Integrator::Simpson { step }
            | Integrator::Preintegrated { step } => pos(Setting::Step, *step),
            Integrator::AdaptiveSimpson(p) => {
                pos(Setting::FirstStep, p.h0)?;
                pos(Setting::MinStep, p.hmin)?;
                pos(Setting::MaxStep, p.hmax)?;
                if !(p.tol.is_finite() && p.tol > 0.0) {
                    return Err(SettingError::new(Setting::Tolerance, p.tol, "> 0"));
                }
                if p.hmin > p.hmax {
                    return Err(SettingError::new(
                        Setting::MinStep,
                        p.hmin,
                        format!("at most the largest step, {}", p.hmax),
                    ));
                }
                Ok(())
            }
            Integrator::Reference => Ok(()),
        }
    }
}
