//! Which floating-point precision the drop-in needs: sphere–wall impacts of the stability
//! matrix with the body's state held in f64 (rapier3d-f64, what this crate uses) or rounded to
//! f32 after every sub-step — what rapier3d (f32) would store — with the scene at the origin or
//! shifted 1 m and 10 m away from it.
//!
//! The emulation keeps the contact arithmetic in f64, so it shows the least f32 would cost:
//! a sub-step moves a body by `v Δt_sub`, and once that is below the f32 spacing of its
//! coordinates (1.2e-7 m at 1 m) the body's position stops changing.

use discrete_contact::rapier3d_f64::prelude::{
    ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle, SharedShape,
};

use crate::stability::RADIUS;
use discrete_contact::error::Result;
use discrete_contact::material::{effective_modulus, hertz_contact_time, Material};
use discrete_contact::math::{Pose, Real, Rotation, Vector};
use discrete_contact::overlap::{IntegrationMode, OverlapSettings};
use discrete_contact::rapier::{DiscreteContacts, StepPolicy};

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

    /// Runs the impact with the state in f64 (`f32_state = false`) or rounded to f32 after every
    /// sub-step. The step is a 40th of the sphere's Hertz contact time (within the drop-in's
    /// advice, which takes the bounding sphere's radius, here r), one sub-step per step.
    pub fn run(&self, f32_state: bool) -> Result<Ending> {
        let (r, e, density) = (RADIUS, 0.85, 7800.0);
        let material = Material::new(self.youngs, 0.3)?;
        // Rapier computes the mass only at the first step; the step is needed before that.
        let mass = density * 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
        let t_h = hertz_contact_time(mass, r, effective_modulus(&material, &material), self.speed);
        let dt = t_h / 40.0;
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::ZERO;
        world.integration_parameters.dt = dt;
        let o = Vector::splat(self.offset);
        let wall = world.insert_body(RigidBodyBuilder::fixed().translation(o));
        world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(wall));
        // Four sub-steps of flight before the touch.
        let start = o + Vector::new(0.0, r + 4.0 * self.speed * dt, 0.0);
        let ball = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(start)
                .linvel(Vector::new(0.0, -self.speed, 0.0))
                .can_sleep(false),
        );
        world.insert_collider(ColliderBuilder::ball(r).density(density), Some(ball));
        let settings = OverlapSettings::new(4, IntegrationMode::Subcell)?;
        let mut contacts =
            DiscreteContacts::new(settings, e)?.with_policy(StepPolicy::Fixed { substeps: 1 });
        contacts.handle_all(&mut world, material)?;
        if f32_state {
            round_to_f32(&mut world, ball);
        }
        let mut touched = false;
        // The contact lasts ~40 steps; a sphere that has not come back within 100 times that
        // stands still.
        for _ in 0..4000 {
            let s = contacts.step(&mut world)?;
            if f32_state {
                round_to_f32(&mut world, ball);
            }
            touched |= s.max_indentation > 0.0 || s.contacts > 0;
            if touched && s.contacts == 0 {
                let v = world.bodies[ball].linvel().y;
                return Ok(Ending::Rebound((v / self.speed / e - 1.0).abs()));
            }
        }
        Ok(Ending::Stuck)
    }
}

/// Rounds a body's pose and velocities to f32 (as rapier3d would store them), and moves its
/// colliders along.
fn round_to_f32(world: &mut PhysicsWorld, h: RigidBodyHandle) {
    let f = |x: Real| x as f32 as Real;
    let v3 = |v: Vector| Vector::new(f(v.x), f(v.y), f(v.z));
    let rb = &mut world.bodies[h];
    let p = *rb.position();
    let q = p.rotation;
    let pose =
        Pose::from_parts(v3(p.translation), Rotation::from_xyzw(f(q.x), f(q.y), f(q.z), f(q.w)));
    rb.set_position(pose, false);
    let (linvel, angvel) = (v3(rb.linvel()), v3(rb.angvel()));
    rb.set_linvel(linvel, false);
    rb.set_angvel(angvel, false);
    let colliders = rb.colliders().to_vec();
    for c in colliders {
        let co = &mut world.colliders[c];
        let local = co.position_wrt_parent().copied().unwrap_or(Pose::IDENTITY);
        co.set_position(pose * local);
    }
}
