//! Which floating-point precision the drop-in needs: sphere–wall impacts of the stability
//! matrix with the body's state held in f64 (rapier3d-f64, what this crate uses) or rounded to
//! f32 after every sub-step — what rapier3d (f32) would store — with the scene at the origin or
//! shifted 1 m and 10 m away from it.
//!
//! A sub-step moves a body by `v Δt_sub`; once that is below the spacing of its coordinates
//! (1.2e-7 m at 1 m in f32) the body's position stops changing. The f32 drop-in refuses such a
//! step ([`Error::PrecisionTooLow`](discrete_contact::Error::PrecisionTooLow)) rather than
//! stall.

use discrete_contact::error::Result;
use discrete_contact::math::Real;

/// One impact: a 1 cm steel sphere (7800 kg/m³, ν = 0.3, e = 0.85) hitting a half-space head-on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Impact {
    /// Young's modulus of sphere and wall (Pa).
    pub youngs: Real,
    /// Impact speed (m/s).
    pub speed: Real,
    /// Distance of the scene from the origin along each axis (m).
    pub offset: Real,
}

/// How an impact ended with the state in one precision.
#[derive(Clone, Debug, PartialEq)]
pub enum Ending {
    /// Rebounded: `|e_measured / e - 1|`.
    Rebound(Real),
    /// The sphere never reached the wall: its sub-step displacement rounds away.
    Stuck,
    /// The drop-in refused the step: its precision cannot resolve the impact.
    Refused,
}

impl Impact {
    /// The cases of the report: E ∈ {1e6, 5e8, 2e11} Pa × v ∈ {0.01, 1} m/s × offset ∈ {0, 1,
    /// 10} m.
    pub fn cases() -> Vec<Impact> {
        let mut v = Vec::new();
        for youngs in [1e6, 5e8, 2e11] {
            for speed in [0.01, 1.0] {
                for offset in [0.0, 1.0, 10.0] {
                    v.push(Impact { youngs, speed, offset });
                }
            }
        }
        v
    }

    /// Runs the impact with rapier3d-f64 (`f32 = false`) or rapier3d (`f32 = true`). The step
    /// is a 40th of the sphere's Hertz contact time (within the drop-in's advice, which takes
    /// the bounding sphere's radius, here r), one sub-step per step.
    pub fn run(&self, f32: bool) -> Result<Ending> {
        if f32 {
            in_f32::run::run(self)
        } else {
            in_f64::run::run(self)
        }
    }
}

/// The impact in rapier3d (f32).
mod in_f32;
/// The impact in rapier3d-f64.
mod in_f64;
