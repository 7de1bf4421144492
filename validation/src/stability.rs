//! The stability matrix of the drop-in (issue: stiff materials, fast impacts, grazing hits,
//! extreme mass ratios, thin plates, resting contact, a box on a ramp and a stack of boxes with
//! friction): each case either ends physically right or is refused with the time-step message —
//! never NaN or an explosion.

use std::time::Instant;

use discrete_contact::error::Error;
use discrete_contact::math::Real;

/// Radius of every sphere of the matrix (m).
pub(crate) const RADIUS: Real = 0.005;

/// One case of the matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Case {
    /// A 1 cm steel-density sphere hitting a wall head-on.
    NormalImpact {
        /// Young's modulus of both (Pa).
        youngs: Real,
        /// Impact speed (m/s).
        speed: Real,
        /// Restitution.
        restitution: Real,
    },
    /// Two equal spheres head-on, A `ratio` times denser than B, 1 m/s, e = 0.85.
    MassRatio {
        /// m_A / m_B.
        ratio: Real,
    },
    /// A sphere hitting the wall 89° off its normal at 1 m/s.
    Grazing,
    /// A 50 × 50 × 1 mm plate falling flat onto the wall at 1 m/s, e = 0.85.
    ThinPlate,
    /// A sphere resting on the wall under gravity for `steps` steps of `dt`.
    Resting {
        /// Steps to run.
        steps: usize,
        /// Time step (s).
        dt: Real,
    },
    /// A stiff fast impact with a fixed, too coarse sub-step: must be refused.
    RefusedStep,
    /// A 10 cm rubber-like box (E = 10 MPa, ν = 0.45, e = 0.5) resting on a fixed ramp (a
    /// cuboid) tilted 20°, μ_s = 0.5, μ_k = 0.4 (tan 20° < μ_s: it must stay), for `seconds`.
    Ramp {
        /// Simulated time (s).
        seconds: Real,
    },
    /// Ten such boxes stacked 4-3-2-1 on the floor (1 mm gaps within a row), for `seconds`.
    Pyramid {
        /// Simulated time (s).
        seconds: Real,
    },
}

/// Side of the ramp's and the pyramid's boxes (m).
const BOX: Real = 0.1;

/// What a case's run says of it.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// It ended right (within the case's tolerance).
    Ok,
    /// It was refused with advice (`TimeStepTooLarge`, `ContactTooSoft`, `PrecisionTooLow`),
    /// as it should be.
    Refused,
    /// It went wrong; why.
    Failed(String),
}

impl core::fmt::Display for Verdict {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Verdict::Ok => f.pad("ok"),
            Verdict::Refused => f.pad("refused"),
            Verdict::Failed(why) => f.pad(&format!("FAILED: {why}")),
        }
    }
}

/// How a case ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// Whether it ended right, was refused, or failed.
    pub verdict: Verdict,
    /// The measured error (meaning per case, see [`Case::describe`]).
    pub error: Real,
    /// Largest number of sub-steps of any step.
    pub substeps: usize,
    /// Wall time (s).
    pub wall_time_s: Real,
}

impl Case {
    /// The matrix of the report.
    pub fn matrix() -> Vec<Case> {
        let mut v = Vec::new();
        for youngs in [1e6, 5e8, 2e11] {
            for speed in [0.01, 1.0, 30.0] {
                for restitution in [0.1, 0.85, 1.0] {
                    v.push(Case::NormalImpact { youngs, speed, restitution });
                }
            }
        }
        v.extend([
            Case::MassRatio { ratio: 1.0 },
            Case::MassRatio { ratio: 1000.0 },
            Case::Grazing,
            Case::ThinPlate,
        ]);
        v.extend([Case::Resting { steps: 100_000, dt: 1e-4 }, Case::RefusedStep]);
        v.extend([
            Case::Ramp { seconds: 2.0 },
            Case::Ramp { seconds: 10.0 },
            Case::Pyramid { seconds: 2.0 },
            Case::Pyramid { seconds: 10.0 },
        ]);
        v
    }

    /// A line naming the case and what its error measures.
    pub fn describe(&self) -> String {
        match self {
            Case::NormalImpact { youngs, speed, restitution } => {
                format!("sphere–wall E={youngs:.0e} v={speed} e={restitution} (|e_meas/e - 1|)")
            }
            Case::MassRatio { ratio } => format!("sphere–sphere m_A/m_B={ratio} (|e_meas/e - 1|)"),
            Case::Grazing => "grazing hit 89° (|e_n/e - 1|)".into(),
            Case::ThinPlate => "thin plate 50:50:1 flat (|e_meas/e - 1|)".into(),
            Case::Resting { steps, dt } => {
                format!("resting sphere {steps} steps of {dt:e} s (drift m; indentation vs Hertz)")
            }
            Case::RefusedStep => "E=2e11 v=30 with 1 fixed sub-step (must refuse)".into(),
            Case::Ramp { seconds } => format!("box on a 20° ramp μ_s=0.5, {seconds} s (drift m)"),
            Case::Pyramid { seconds } => format!("10-box pyramid, {seconds} s (top box drift m)"),
        }
    }

    /// Runs the case with rapier3d-f64.
    pub fn run(&self) -> Outcome {
        self.run_in(false)
    }

    /// Runs the case with rapier3d-f64 (`f32 = false`) or rapier3d (`f32 = true`).
    pub fn run_in(&self, f32: bool) -> Outcome {
        let start = Instant::now();
        let result = if f32 { in_f32::run::run(self) } else { in_f64::run::run(self) };
        let wall_time_s = start.elapsed().as_secs_f64();
        match (self, result) {
            (Case::RefusedStep, Err(Error::TimeStepTooLarge { substeps_needed, .. })) => Outcome {
                verdict: Verdict::Refused,
                error: 0.0,
                substeps: substeps_needed,
                wall_time_s,
            },
            (Case::RefusedStep, other) => Outcome {
                verdict: Verdict::Failed(format!("not refused ({other:?})")),
                error: Real::NAN,
                substeps: 0,
                wall_time_s,
            },
            (_, Ok((verdict, error, substeps))) => {
                Outcome { verdict, error, substeps, wall_time_s }
            }
            (_, Err(Error::TimeStepTooLarge { substeps_needed, .. })) => Outcome {
                verdict: Verdict::Refused,
                error: 0.0,
                substeps: substeps_needed,
                wall_time_s,
            },
            (_, Err(Error::ContactTooSoft { indentation, .. })) => {
                Outcome { verdict: Verdict::Refused, error: indentation, substeps: 0, wall_time_s }
            }
            (_, Err(Error::PrecisionTooLow { indentation, .. })) => {
                Outcome { verdict: Verdict::Refused, error: indentation, substeps: 0, wall_time_s }
            }
            (_, Err(e)) => Outcome {
                verdict: Verdict::Failed(e.to_string()),
                error: Real::NAN,
                substeps: 0,
                wall_time_s,
            },
        }
    }
}

/// The cases in rapier3d (f32).
mod in_f32;
/// The cases in rapier3d-f64.
mod in_f64;
