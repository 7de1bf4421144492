//! One impact in one rapier build: its parent module names the rapier crate `engine` and the
//! drop-in `drop_in`. Written once for both builds, so conversions between the case's f64 and
//! rapier's numbers are identities in the f64 build.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use super::drop_in::{DiscreteContacts, StepPolicy};
use super::engine::math::{Real, Vector};
use super::engine::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, SharedShape};

use super::super::{Ending, Impact};
use crate::stability::RADIUS;
use discrete_contact::error::{Error, Result};
use discrete_contact::material::{effective_modulus, hertz_contact_time, Material};
use discrete_contact::overlap::{IntegrationMode, OverlapSettings};

/// Runs `impact` (see [`Impact::run`]).
pub(crate) fn run(impact: &Impact) -> Result<Ending> {
    let (r, e, density) = (RADIUS, 0.85, 7800.0);
    let material = Material::new(impact.youngs, 0.3)?;
    // Rapier computes the mass only at the first step; the step is needed before that.
    let mass = density * 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let t_h = hertz_contact_time(mass, r, effective_modulus(&material, &material), impact.speed);
    let dt = t_h / 40.0;
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    world.integration_parameters.dt = dt as Real;
    let o = Vector::splat(impact.offset as Real);
    let wall = world.insert_body(RigidBodyBuilder::fixed().translation(o));
    world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(wall));
    // Four sub-steps of flight before the touch.
    let start = o + Vector::new(0.0, (r + 4.0 * impact.speed * dt) as Real, 0.0);
    let ball = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(start)
            .linvel(Vector::new(0.0, -impact.speed as Real, 0.0))
            .can_sleep(false),
    );
    world.insert_collider(ColliderBuilder::ball(r as Real).density(density as Real), Some(ball));
    let settings = OverlapSettings::new(4, IntegrationMode::Subcell)?;
    let mut contacts =
        DiscreteContacts::new(settings, e)?.with_policy(StepPolicy::Fixed { substeps: 1 });
    contacts.handle_all(&mut world, material)?;
    let mut touched = false;
    // The contact lasts ~40 steps; a sphere that has not come back within 100 times that
    // stands still.
    for _ in 0..4000 {
        let s = match contacts.step(&mut world) {
            Err(Error::PrecisionTooLow { .. }) => return Ok(Ending::Refused),
            other => other?,
        };
        touched |= s.max_indentation > 0.0 || s.contacts > 0;
        if touched && s.contacts == 0 {
            let v = world.bodies[ball].linvel().y as f64;
            return Ok(Ending::Rebound((v / impact.speed / e - 1.0).abs()));
        }
    }
    Ok(Ending::Stuck)
}
