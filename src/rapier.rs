//! The drop-in for rapier scenes built on `rapier3d-f64` (feature `rapier`, on by default).
//! Scenes on `rapier3d` (f32) use the same drop-in from module `rapier_f32` (feature
//! `rapier-f32`).
//!
//! A user keeps their [`PhysicsWorld`](rapier3d_f64::prelude::PhysicsWorld) — bodies,
//! colliders, joints, gravity, their own hooks and event handlers — and replaces
//! `world.step()` by [`DiscreteContacts::step`]. For every pair of *handled* colliders that
//! rapier's broad phase reports, rapier's own contact response is switched off (a physics
//! hook returns `None`), and the discrete overlap-volume force is applied instead, with
//! contact sub-steps: each sub-step is one rapier step of `dt / n` with
//! one solver iteration, forces computed from the poses at its start (a leapfrog). Everything
//! else rapier does — joints, gravity, contacts of unhandled pairs, events — keeps working,
//! and rapier's pair rules hold for handled pairs too: collision and solver groups, active
//! collision types, sensors, disabled colliders, joints with contacts disabled, and the user's
//! `filter_contact_pair` hook on colliders that asked for it before they were handed over.
//! Handled pairs report rapier's collision events themselves (`Started` and `Stopped`, a
//! removed collider's with `REMOVED`, through [`DiscreteContacts::step_with_events`], without
//! a `ContactPair`, which only rapier can build); their contact-force events are read after
//! the step from [`DiscreteContacts::contact_force_events`], and what each live contact
//! carried over the last step — point, normal, indentation, force — from
//! [`DiscreteContacts::contacts`] ([`ParaViewSeries`] writes them and the bodies for
//! ParaView). Bodies and colliders may be removed between steps:
//! their contacts end at the next step.
//!
//! **Small bodies**: rapier sizes its broad-phase margins by
//! `integration_parameters.length_unit` (1 m by default). For millimetre bodies set it to their
//! size — left at 1 m, 1934 settling 3 mm spheres were all paired with each other (1.9 million
//! pairs, seconds per step); at 3 mm the step takes a millisecond.
//!
//! ```
//! use discrete_contact::prelude::*;
//! use discrete_contact::rapier::{DiscreteContacts, StepPolicy};
//! use rapier3d_f64::prelude::*;
//! # use discrete_contact::math::Vector;
//! let mut world = PhysicsWorld::new();
//! let floor = world.insert_body(RigidBodyBuilder::fixed());
//! world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(floor));
//! let ball = world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 0.0105, 0.0)));
//! world.insert_collider(ColliderBuilder::ball(0.01).density(7800.0), Some(ball));
//! world.integration_parameters.dt = 1e-4;
//!
//! let steel = Material::new(2e11, 0.3)?;
//! let mut contacts = DiscreteContacts::new(OverlapSettings::new(6, IntegrationMode::Subcell)?, 0.9)?
//!     .with_policy(StepPolicy::AutoSubstep { max_substeps: 1000 });
//! contacts.handle_all(&mut world, steel)?;        // every convex collider
//! for _ in 0..100 {
//!     contacts.step(&mut world)?;                 // instead of world.step()
//! }
//! assert!(world.bodies[ball].translation().y > 0.009); // resting on the floor, not through it
//! # Ok::<(), discrete_contact::Error>(())
//! ```

use rapier3d_f64 as engine;

// The drop-in's one source, compiled once per rapier build on purpose.
#[allow(clippy::duplicate_mod)]
#[path = "drop_in/mod.rs"]
mod drop_in;
pub use drop_in::*;

/// Rapier's numbers and the contact model's: both f64 here, so every conversion is the identity.
mod boundary {
    use super::engine::math as e;
    use crate::math as c;

    /// The spacing of rapier's numbers relative to their size (the unit round-off's double).
    pub(super) const EPSILON: c::Real = e::Real::EPSILON;

    /// The name of rapier's numbers, for messages.
    pub(super) const PRECISION: &str = "f64";

    /// Rapier's scalar as the model's.
    pub(super) fn real(x: e::Real) -> c::Real {
        x
    }
    /// The model's scalar as rapier's.
    pub(super) fn engine_real(x: c::Real) -> e::Real {
        x
    }
    /// Rapier's vector as the model's.
    pub(super) fn vector(v: e::Vector) -> c::Vector {
        v
    }
    /// The model's vector as rapier's.
    pub(super) fn engine_vector(v: c::Vector) -> e::Vector {
        v
    }
    /// Rapier's pose as the model's.
    pub(super) fn pose(p: &e::Pose) -> c::Pose {
        *p
    }
    /// The model's pose as rapier's.
    pub(super) fn engine_pose(p: &c::Pose) -> e::Pose {
        *p
    }
    /// A rapier collider's shape as f64 parry's: rapier's own.
    pub(super) fn query_shape(
        co: &super::engine::prelude::Collider,
    ) -> crate::Result<parry3d_f64::shape::SharedShape> {
        Ok(co.shared_shape().clone())
    }
}
