//! The stability matrix of the drop-in (issue: stiff materials, fast impacts, grazing hits,
//! extreme mass ratios, thin plates, resting contact, a box on a ramp and a stack of boxes with
//! friction): each case either ends physically right or is refused with the time-step message —
//! never NaN or an explosion.

use std::time::Instant;

use discrete_contact::rapier3d_f64::prelude::{
    ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle, SharedShape,
};

use discrete_contact::error::{Error, Result};
use discrete_contact::material::{effective_modulus, Material};
use discrete_contact::math::{Pose, Real, Rotation, Vector};
use discrete_contact::overlap::{IntegrationMode, OverlapSettings};
use discrete_contact::rapier::{DiscreteContacts, StepPolicy};

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
    /// It was refused with advice (`TimeStepTooLarge`, `ContactTooSoft`), as it should be.
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

    /// Runs the case.
    pub fn run(&self) -> Outcome {
        let start = Instant::now();
        let result = self.run_inner();
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
            (_, Err(e)) => Outcome {
                verdict: Verdict::Failed(e.to_string()),
                error: Real::NAN,
                substeps: 0,
                wall_time_s,
            },
        }
    }

    fn run_inner(&self) -> Result<(Verdict, Real, usize)> {
        let r = RADIUS;
        let settings = OverlapSettings::new(4, IntegrationMode::Subcell)?;
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::ZERO;
        world.integration_parameters.dt = 1e-4;
        let wall = world.insert_body(RigidBodyBuilder::fixed());
        world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(wall));
        let sphere =
            |world: &mut PhysicsWorld, y: Real, v: Vector, density: Real| -> RigidBodyHandle {
                let b = world.insert_body(
                    RigidBodyBuilder::dynamic()
                        .translation(Vector::new(0.0, y, 0.0))
                        .linvel(v)
                        .can_sleep(false),
                );
                world.insert_collider(ColliderBuilder::ball(r).density(density), Some(b));
                b
            };
        let (e, youngs, policy) = match *self {
            Case::NormalImpact { youngs, restitution, .. } => {
                (restitution, youngs, StepPolicy::AutoSubstep { max_substeps: 100_000 })
            }
            Case::RefusedStep => (0.85, 2e11, StepPolicy::Fixed { substeps: 1 }),
            _ => (0.85, 5e8, StepPolicy::AutoSubstep { max_substeps: 100_000 }),
        };
        let mut contacts = DiscreteContacts::new(settings, e)?.with_policy(policy);
        let speed_in = match *self {
            Case::NormalImpact { speed, .. } => speed,
            Case::RefusedStep => 30.0,
            _ => 1.0,
        };
        // (body, normal along which the rebound is measured, approach speed along it)
        let (body, normal, v_n) = match *self {
            Case::NormalImpact { .. } | Case::RefusedStep => (
                sphere(&mut world, r + 1e-6, Vector::new(0.0, -speed_in, 0.0), 7800.0),
                Vector::Y,
                speed_in,
            ),
            Case::Grazing => {
                let a = 89f64.to_radians();
                let v = Vector::new(a.sin(), -a.cos(), 0.0);
                (sphere(&mut world, r + 1e-7, v, 7800.0), Vector::Y, a.cos())
            }
            Case::MassRatio { ratio } => {
                // Free space: B at rest far from the wall, A coming at 1 m/s along -x.
                let b = world.insert_body(
                    RigidBodyBuilder::dynamic()
                        .translation(Vector::new(0.0, 1.0, 0.0))
                        .can_sleep(false),
                );
                world.insert_collider(ColliderBuilder::ball(r).density(7800.0), Some(b));
                let a = world.insert_body(
                    RigidBodyBuilder::dynamic()
                        .translation(Vector::new(2.0 * r + 1e-6, 1.0, 0.0))
                        .linvel(Vector::new(-1.0, 0.0, 0.0))
                        .can_sleep(false),
                );
                world.insert_collider(ColliderBuilder::ball(r).density(7800.0 * ratio), Some(a));
                contacts.handle_all(&mut world, Material::new(youngs, 0.3)?)?;
                return Self::two_body(&mut world, &mut contacts, a, b, e);
            }
            Case::ThinPlate => {
                let b = world.insert_body(
                    RigidBodyBuilder::dynamic()
                        .pose(Pose::from_parts(
                            Vector::new(0.0, 0.0005 + 1e-6, 0.0),
                            Rotation::IDENTITY,
                        ))
                        .linvel(Vector::new(0.0, -1.0, 0.0))
                        .can_sleep(false),
                );
                world.insert_collider(
                    ColliderBuilder::cuboid(0.025, 0.0005, 0.025).density(2700.0),
                    Some(b),
                );
                (b, Vector::Y, 1.0)
            }
            Case::Resting { steps, dt } => {
                world.gravity = Vector::new(0.0, -9.81, 0.0);
                world.integration_parameters.dt = dt;
                let b = sphere(&mut world, r, Vector::ZERO, 7800.0);
                // The contact law's own rest, to a nanometre: every sub-step evaluated in full.
                // Geometry reuse re-anchors the force at each full evaluation, a jump of the
                // grid's noise that a frictionless ball does not damp out at this level.
                let mut contacts = contacts.with_geometry_reuse(0.0)?;
                let material = Material::new(5e8, 0.3)?;
                contacts.handle_all(&mut world, material)?;
                return Self::resting(
                    &mut world,
                    &mut contacts,
                    b,
                    steps,
                    effective_modulus(&material, &material),
                );
            }
            Case::Ramp { seconds } => return Self::boxes(seconds, true),
            Case::Pyramid { seconds } => return Self::boxes(seconds, false),
        };
        contacts.handle_all(&mut world, Material::new(youngs, 0.3)?)?;
        let ke0 = 0.5 * world.bodies[body].mass() * speed_in * speed_in;
        let mut touched = false;
        let mut substeps = 0;
        let mut lowest = Real::INFINITY;
        // Long enough for the slowest, softest contact to end.
        for _ in 0..200_000 {
            let s = contacts.step(&mut world)?;
            substeps = substeps.max(s.substeps);
            let rb = &world.bodies[body];
            lowest = lowest.min(rb.translation().y);
            if !rb.translation().is_finite() {
                return Ok((Verdict::Failed("non-finite state".into()), Real::NAN, substeps));
            }
            // A stiff contact can begin and end within one step: its depth tells it was there.
            touched |= s.max_indentation > 0.0 || s.contacts > 0;
            if touched && s.contacts == 0 {
                break;
            }
        }
        let rb = &world.bodies[body];
        let ke1 = 0.5 * rb.mass() * rb.linvel().length_squared()
            + 0.5 * rb.angvel().dot(rb.angvel()) * rb.mass() * r * r * 0.4;
        let e_meas = rb.linvel().dot(normal) / v_n;
        if !touched {
            return Ok((Verdict::Failed("no contact".into()), Real::NAN, substeps));
        }
        if lowest < 0.0 {
            return Ok((
                Verdict::Failed(format!("tunnelled (centre at {lowest:e} m)")),
                Real::NAN,
                substeps,
            ));
        }
        // Sub-stepped symplectic Euler errs by O(Δt_c / t_H) per contact: with >= 30 sub-steps
        // an elastic rebound comes out up to ~0.6 % fast; more than 1 % is a failure.
        if ke1 > ke0 * (1.0 + 1e-2) {
            return Ok((
                Verdict::Failed(format!("energy created ({:.3}×)", ke1 / ke0)),
                Real::NAN,
                substeps,
            ));
        }
        let err = (e_meas / e - 1.0).abs();
        let verdict =
            if err <= 0.05 { Verdict::Ok } else { Verdict::Failed(format!("e = {e_meas:.4}")) };
        Ok((verdict, err, substeps))
    }

    fn two_body(
        world: &mut PhysicsWorld,
        contacts: &mut DiscreteContacts,
        a: RigidBodyHandle,
        b: RigidBodyHandle,
        e: Real,
    ) -> Result<(Verdict, Real, usize)> {
        let p0 = world.bodies[a].mass() * world.bodies[a].linvel()
            + world.bodies[b].mass() * world.bodies[b].linvel();
        let mut touched = false;
        let mut substeps = 0;
        for _ in 0..200_000 {
            let s = contacts.step(world)?;
            substeps = substeps.max(s.substeps);
            touched |= s.max_indentation > 0.0 || s.contacts > 0;
            if touched && s.contacts == 0 {
                break;
            }
        }
        let (ra, rb) = (&world.bodies[a], &world.bodies[b]);
        let p1 = ra.mass() * ra.linvel() + rb.mass() * rb.linvel();
        let e_meas = (rb.linvel().x - ra.linvel().x) / 1.0;
        if (p1 - p0).length() > 1e-9 * p0.length() {
            return Ok((Verdict::Failed(format!("momentum {p0:?} → {p1:?}")), Real::NAN, substeps));
        }
        let err = (-e_meas / e - 1.0).abs();
        Ok((
            if err <= 0.05 { Verdict::Ok } else { Verdict::Failed(format!("e = {:.4}", -e_meas)) },
            err,
            substeps,
        ))
    }

    /// The ramp (`ramp`) or the pyramid, left standing for `seconds` at 240 steps per second
    /// under gravity; the error is the watched box's displacement from 0.5 s (once it has
    /// settled into its contacts) to the end.
    fn boxes(seconds: Real, ramp: bool) -> Result<(Verdict, Real, usize)> {
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = 1.0 / 240.0;
        let h = 0.5 * BOX;
        let fixed = world.insert_body(RigidBodyBuilder::fixed());
        let add_box = |world: &mut PhysicsWorld, pose: Pose| -> RigidBodyHandle {
            let b = world.insert_body(RigidBodyBuilder::dynamic().pose(pose).can_sleep(false));
            world.insert_collider(ColliderBuilder::cuboid(h, h, h).density(1000.0), Some(b));
            b
        };
        let watched = if ramp {
            let tilt = Rotation::from_rotation_z(20f64.to_radians());
            world.insert_collider(
                ColliderBuilder::cuboid(1.0, 0.1, 0.5)
                    .position(Pose::from_parts(Vector::ZERO, tilt)),
                Some(fixed),
            );
            add_box(&mut world, Pose::from_parts(tilt * Vector::new(0.0, 0.1 + h, 0.0), tilt))
        } else {
            world.insert_collider(
                ColliderBuilder::new(SharedShape::halfspace(Vector::Y)),
                Some(fixed),
            );
            let mut top = None;
            for row in 0..4 {
                for i in 0..4 - row {
                    let x = (i as Real - 0.5 * (3 - row) as Real) * (BOX + 1e-3);
                    top = Some(add_box(
                        &mut world,
                        Pose::from_translation(Vector::new(x, h + row as Real * BOX, 0.0)),
                    ));
                }
            }
            top.expect("four rows")
        };
        let mut contacts =
            DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell)?, 0.5)?
                .with_friction(discrete_contact::material::Friction::new(0.5, 0.4, 0.01)?)
                .with_policy(StepPolicy::AutoSubstep { max_substeps: 1000 });
        contacts.handle_all(&mut world, Material::new(1e7, 0.45)?)?;
        let steps = (seconds * 240.0).round() as usize;
        let (mut substeps, mut settled) = (0, None);
        for k in 0..steps {
            substeps = substeps.max(contacts.step(&mut world)?.substeps);
            if k + 1 == 120 {
                settled = Some(world.bodies[watched].translation());
            }
        }
        let at = world.bodies[watched].translation();
        if !at.is_finite() {
            return Ok((Verdict::Failed("non-finite state".into()), Real::NAN, substeps));
        }
        let drift = (at - settled.unwrap_or(at)).length();
        // Held: creeping below 1 mm/s after settling. Nassauer & Kuna's slip-speed law fails it
        // on the ramp (about 7 mm/s); rapier's own contacts hold the ramp's box to 0.03 mm/s.
        let creep = drift / (seconds - 0.5);
        let verdict = if creep < 1e-3 {
            Verdict::Ok
        } else {
            Verdict::Failed(format!("creeps {creep:e} m/s"))
        };
        Ok((verdict, drift, substeps))
    }

    /// The sphere `b` (`e_star` against the floor) left resting for `steps` steps.
    fn resting(
        world: &mut PhysicsWorld,
        contacts: &mut DiscreteContacts,
        b: RigidBodyHandle,
        steps: usize,
        e_star: Real,
    ) -> Result<(Verdict, Real, usize)> {
        let mut substeps = 0;
        let mut y_half = 0.0;
        let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
        for k in 0..steps {
            let s = contacts.step(world)?;
            substeps = substeps.max(s.substeps);
            let y = world.bodies[b].translation().y;
            if k == steps / 2 {
                y_half = y;
            }
            if k >= steps / 2 {
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        let rb = &world.bodies[b];
        let drift = (rb.translation().y - y_half).abs().max(hi - lo).max(rb.translation().x.abs());
        // The static Hertz indentation under the sphere's weight, d = (3 m g / (4 E* √R))^(2/3).
        let r = RADIUS;
        let d_hertz = (3.0 * rb.mass() * world.gravity.length() / (4.0 * e_star * Real::sqrt(r)))
            .powf(2.0 / 3.0);
        let d = r - rb.translation().y;
        // Tolerances: drift or jitter over the second half below 1 % of the static indentation
        // (1.3 µm here), the indentation itself within 5 % of Hertz (sub-cell N_c = 4 errs by
        // ~3 % on a sphere), and at rest.
        let ok = drift < 0.01 * d_hertz
            && (d / d_hertz - 1.0).abs() < 0.05
            && rb.linvel().length() < 1e-6;
        let verdict = if ok {
            Verdict::Ok
        } else {
            Verdict::Failed(format!(
                "drift {drift:e} m, indentation {d:e} m (Hertz {d_hertz:e}), |v| {:e}",
                rb.linvel().length()
            ))
        };
        Ok((verdict, drift, substeps))
    }
}
