//! The drop-in for rapier scenes built on `rapier3d` (f32; feature `rapier-f32`): rapier's
//! default build, the one `bevy_rapier3d` uses. The same API as [`crate::rapier`]'s for
//! `rapier3d-f64`, from the same source; the contact model computes in f64 and the drop-in
//! converts poses, velocities, masses and forces at rapier's boundary. Each handled
//! collider's shape is widened to its f64 parry twin ([`widen_f32`](crate::shape::widen_f32))
//! once, when handed over: the SDF and the exact distances that decide which pairs need an
//! evaluation come from it: parry's f32 distance between centimetre bodies can be off by more
//! than the gap it decides on, and a pair it calls apart sinks into itself unseen.
//!
//! **Precision.** With body positions in f32, a coordinate `x` moves only in steps of about
//! `|x| · 1.2e-7`. A stiff, slow contact far from the origin indents by a few such steps per
//! sub-step, or by none: the body would stall or its force would come in quanta. Before every
//! step the drop-in checks each pair it resolves: when the indentation that the pair's
//! approach makes in one sub-step is below [`PRECISION_SPACINGS`] spacings of the bodies'
//! coordinates, the step is refused with [`Error::PrecisionTooLow`](crate::Error::PrecisionTooLow),
//! naming the pair, its distance from the origin, the indentation per sub-step and what would
//! work (the scene nearer the origin, a softer material, or the f64 build). The f64 build makes
//! the same check; its spacing is 5 × 10⁸ times finer.
//!
//! ```
//! use discrete_contact::{IntegrationMode, Material, OverlapSettings};
//! use discrete_contact::rapier_f32::{DiscreteContacts, StepPolicy};
//! use rapier3d::prelude::*;
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

use rapier3d as engine;

// The drop-in's one source, compiled once per rapier build on purpose.
#[allow(clippy::duplicate_mod)]
#[path = "drop_in/mod.rs"]
mod drop_in;
pub use drop_in::*;

/// Rapier's numbers (f32) and the contact model's (f64): widened exactly, narrowed to the
/// nearest f32.
mod boundary {
    use super::engine::math as e;
    use crate::math as c;

    /// The spacing of rapier's numbers relative to their size (the unit round-off's double).
    pub(super) const EPSILON: c::Real = e::Real::EPSILON as c::Real;

    /// The name of rapier's numbers, for messages.
    pub(super) const PRECISION: &str = "f32";

    /// Rapier's scalar as the model's.
    pub(super) fn real(x: e::Real) -> c::Real {
        x.into()
    }
    /// The model's scalar as rapier's.
    pub(super) fn engine_real(x: c::Real) -> e::Real {
        x as e::Real
    }
    /// Rapier's vector as the model's.
    pub(super) fn vector(v: e::Vector) -> c::Vector {
        v.into()
    }
    /// The model's vector as rapier's.
    pub(super) fn engine_vector(v: c::Vector) -> e::Vector {
        v.as_vec3()
    }
    /// Rapier's pose as the model's.
    pub(super) fn pose(p: &e::Pose) -> c::Pose {
        c::Pose::from_parts(p.translation.into(), p.rotation.as_dquat())
    }
    /// The model's pose as rapier's.
    pub(super) fn engine_pose(p: &c::Pose) -> e::Pose {
        e::Pose::from_parts(p.translation.as_vec3(), p.rotation.as_quat())
    }
    /// A rapier collider's shape as f64 parry's: its numbers widened
    /// ([`widen_f32`](crate::shape::widen_f32)).
    pub(super) fn query_shape(
        co: &super::engine::prelude::Collider,
    ) -> crate::Result<parry3d_f64::shape::SharedShape> {
        crate::shape::widen_f32(co.shape())
    }
}
