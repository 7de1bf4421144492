//! # discrete-contact
//!
//! Discrete overlap-volume contacts (Nassauer & Kuna 2013, as discretised in Marquardt et al.) for
//! arbitrarily shaped convex rigid bodies given as signed distance functions.
//!
//! Data flows one way: body pose → [`shape`] (SDF) → [`overlap`] (volume, contact point,
//! normal, indentation) → [`force`] (normal force with restitution damping, friction,
//! torques; the history-dependent tangential spring in [`tangential`]) → body. [`contact`]
//! keeps what a contact remembers between sub-steps.
//!
//! ```
//! use discrete_contact::prelude::*;
//!
//! let ball = ConvexShape::ball(0.01)?;                       // 1 cm sphere
//! let floor = ConvexShape::half_space(Vector::Y)?;           // the plane y = 0
//! let steel = Material::new(200e9, 0.3)?;
//! let model = ContactModel::new(
//!     PairParameters::new(&steel, &steel, 0.9)?,
//!     OverlapSettings::new(8, IntegrationMode::Subcell)?,
//! );
//! let a = BodyState::at_rest(&ball, Pose::from_translation(Vector::new(0.0, 0.01 - 1e-5, 0.0)))
//!     .moving(Vector::new(0.0, -1.0, 0.0), Vector::ZERO);
//! let b = BodyState::at_rest(&floor, Pose::IDENTITY);
//! let mut state = None;
//! let out = model.evaluate(&a, &b, &mut state)?.expect("they overlap");
//! assert!(out.force.force_on_a.y > 0.0);                    // pushes the ball up
//! # Ok::<(), discrete_contact::Error>(())
//! ```
//!
//! ## Cargo features
//! - `rapier` (default): the drop-in for rapier3d-f64 scenes ([`rapier`] module).
//! - `rapier-f32`: the same drop-in for rapier3d (f32) scenes, rapier's default build and the
//!   one `bevy_rapier3d` uses (`rapier_f32` module); the contact arithmetic stays in f64, poses,
//!   velocities and forces are converted at rapier's boundary. With `default-features = false`
//!   a dry f32 build compiles neither f64 rapier nor the lattice.
//! - `parallel` (default): a step's contacts are evaluated on all cores (rayon); forces are
//!   summed in a fixed order, so results do not depend on the thread count.
//! - `fluid`: wet runs — the `coupling` module (rapier bodies four-way coupled with the
//!   bundled HLBM lattice crate, re-exported as `hlbm`); implies `rapier`. A dry build never
//!   compiles the lattice.
//! - `checkpoint` (default): serde for every state type (this crate's, rapier's world, the
//!   lattice) and the [`checkpoint`] module — save a run, resume it bit-identically.
//!
//! Every file the crate writes goes through [`io`]: complete or not at all.
//!
//! ## Stiff contacts at rapier's step
//! The drop-in takes every contact that is not an impact implicitly (`Integration::Implicit`,
//! the default): bodies resting on each other, rolling or sliding are solved at whatever step
//! rapier is given — one convex problem per island of touching bodies, the Nassauer–Kuna law
//! taken where the step leaves each contact — so a stack of steel boxes stands at 60 Hz.
//! Impacts keep the sub-steps their restitution needs, each group of bodies they set moving
//! sub-stepped on its own. Every step checks itself afterwards (overlaps within their limit,
//! no energy created) and is redone in more sub-steps or refused with
//! [`Error::StepRejected`]; it never returns `Ok` for a world that blew up.
//! `Integration::Explicit` integrates every contact in sub-steps of the stiffest one's period
//! (every force history resolved in time, at a cost growing as `√E`).
//!
//! **f32 scenes**: in f32 a coordinate moves in steps of about `|x| · 1.2e-7` (0.12 µm at
//! 1 m). A stiff slow impact resolved in sub-steps of microseconds may move a body by less
//! than that per step; rather than let it stall, the f32 drop-in refuses such a step with
//! [`Error::PrecisionTooLow`] — the scene nearer the origin, a softer material or the f64
//! build serves it.
//!
//! ## Errors
//! Every fallible call returns [`Error`]; its variants are the catalogue:
//! - [`Error::InvalidParameter`] — a scalar outside its range (`E > 0`, `0 <= ν <= 0.5`,
//!   `0 < e <= 1`, `μ_s >= μ_k >= 0`, `v_s > 0`, `N_c >= 1`, positive finite sizes); the message
//!   names the parameter and the range. Fix the input.
//! - [`Error::InvalidArgument`] — an argument that is not a number and not what the call
//!   accepts (a collider handle of another world, a collider without a dynamic body for the
//!   fluid, contacts whose periodic box is not the fluid's, a saved run of another case).
//! - [`Error::UnsupportedShape`] — a parry shape with no convex SDF (compounds, polylines;
//!   meshes and height fields outside the drop-in's walls), or a mesh with no solid side;
//!   decompose it into convex pieces or pass a custom SDF.
//! - [`Error::NonFinite`] — a NaN/infinite pose, velocity or vertex; usually a blown-up
//!   simulation upstream: reduce the time step.
//! - [`Error::UnboundedOverlap`] — both bodies unbounded (two half-spaces); such a pair has no
//!   contact to compute.
//! - [`Error::TimeStepTooLarge`] — (rapier drop-in) a step cannot give a contact 30 sub-steps
//!   (or the number set with `with_substeps_per_contact`) within its Hertz contact time, or
//!   too few within a live contact's own or its tangential spring's half-period (see
//!   `DiscreteContacts::substeps`), under the chosen policy; the message names the pair, the
//!   recommended step and the sub-steps needed. Lower `dt` or allow more sub-steps.
//! - [`Error::ContactTooSoft`] — (rapier drop-in) Hertz puts an impact's indentation beyond
//!   the limit (half the smaller body's smallest half-extent by default): the bodies would
//!   pass through each other. Use a stiffer material or a lower speed; deliberately softened
//!   materials raise the limit with `DiscreteContacts::with_indentation_limit`.
//! - [`Error::PrecisionTooLow`] — (rapier drop-in) a moving pair whose approach in one
//!   (sub-)step is under two spacings of its coordinates (f32 far from the origin): the body
//!   would stall. The message names the pair, the distance from the origin and what would
//!   work.
//! - [`Error::StepRejected`] — (rapier drop-in) a step whose outcome failed its own check (a
//!   contact deeper than its bodies can hold, energy created, an implicit solve without a
//!   solution) and could not be redone in more sub-steps; the message names the pair, the
//!   step and what went wrong, and the world is left as it was before the step. Lower `dt`,
//!   use a softer material or slower bodies, or allow more sub-steps.
//! - [`Error::InvalidParameter`] with `periodic box size` — a periodic box shorter than twice a
//!   pair's reach (two bounding diameters plus the contact margin): a body would meet two
//!   images of another. Enlarge the box.
//! - [`Error::Io`] — a file could not be created, written, renamed or read; the message names
//!   the path and the system's reason (missing folder, no permission, disk full). A failed
//!   write leaves the previous file in place.
//! - `Error::Checkpoint` — (feature `checkpoint`) a file that cannot be resumed, with its
//!   `CheckpointProblem`: `NotACheckpoint` (wrong path), `FormatVersion` / `WrittenBy`
//!   (written by another version: resume with that version), `Kind` (holds another kind of
//!   run), `Length` / `Checksum` (truncated or altered: use an earlier checkpoint), `Decode`
//!   (the payload is not the state asked for, or a parameter in it fails its constructor's
//!   check — the message names it and its range), `Encode` (the state holds something that cannot
//!   be saved: a `ConvexShape::Custom` closure). The validation runs also refuse a checkpoint of
//!   another case, with `InvalidArgument` named `case`.
//! - `Error::Fluid` — (feature `fluid`) the lattice refused a parameter (e.g. `τ <= 1/2`: raise
//!   `Δt` or `ν`, or lower `Δx`), blew up (the message names the step and the node: lower the
//!   lattice velocity with a smaller `Δt`, or raise `τ`), or could not write a file.
//!
//! ## Periodic boxes
//! [`periodic::PeriodicBox`] given to `DiscreteContacts::with_periodic` (from
//! `Fluid::periodic_box` in a wet run) makes contacts act through periodic faces and moves
//! bodies that leave the box back into it; a scene without it pays nothing for periodicity.

#![warn(missing_docs)]

/// Deserializes a parameter type from its fields through its constructor (feature
/// `checkpoint`), so values read from a file pass the same checks as values given in code.
macro_rules! deserialize_checked {
    ($ty:ident via $shadow:ident { $($(#[$m:meta])* $field:ident: $fty:ty),* $(,)? } => |$f:ident| $check:expr) => {
        #[doc = concat!("A [`", stringify!($ty), "`] as read from a file, checked before use.")]
        #[cfg(feature = "checkpoint")]
        #[derive(serde::Deserialize)]
        struct $shadow {
            $($(#[$m])* $field: $fty),*
        }

        #[cfg(feature = "checkpoint")]
        impl TryFrom<$shadow> for $ty {
            type Error = crate::Error;
            fn try_from($f: $shadow) -> crate::Result<Self> {
                crate::checkpoint::checked($check)
            }
        }
    };
}

#[cfg(feature = "checkpoint")]
pub mod checkpoint;
pub mod contact;
#[cfg(feature = "fluid")]
pub mod coupling;
pub mod error;
pub mod force;
#[cfg_attr(not(any(feature = "rapier", feature = "rapier-f32")), allow(dead_code))]
mod implicit;
pub mod io;
pub mod lubrication;
pub mod material;
pub mod overlap;
pub mod periodic;
#[cfg(feature = "rapier")]
pub mod rapier;
#[cfg(feature = "rapier-f32")]
pub mod rapier_f32;
pub mod shape;
#[cfg(any(feature = "rapier", feature = "rapier-f32"))]
mod substep;
pub mod tangential;

/// The README's example, compiled and run as a doc test.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

pub use contact::{BodyState, ContactModel, ContactOutput, ContactState};
pub use error::{Error, Result};
pub use force::{
    contact_force, contact_force_with_history, normal_force, BodyKinematics, ContactForce,
};
pub use material::{
    damping_from_restitution, effective_modulus, hertz_contact_time, hertz_max_indentation,
    Friction, Material, PairParameters, StiffnessFactor,
};
pub use overlap::{compute_overlap, IntegrationMode, OverlapGeometry, OverlapSettings};
pub use shape::{ConvexShape, MeshSdf, Sdf};
pub use tangential::TangentialLaw;

/// The math types of parry/rapier (f64): `Real`, `Vector` (glam `DVec3`), `Pose`, `Rotation`.
pub mod math {
    pub use parry3d_f64::math::{Matrix, Pose, Real, Rotation, Vector};
}

/// Re-export of the parry version the shapes come from.
pub use parry3d_f64;

/// The rapier version the drop-in works with (f64).
#[cfg(feature = "rapier")]
pub use rapier3d_f64;

/// The rapier version the f32 drop-in works with.
#[cfg(feature = "rapier-f32")]
pub use rapier3d;

/// The bundled homogenized lattice Boltzmann crate (feature `fluid`; a dry build never
/// compiles it).
#[cfg(feature = "fluid")]
pub use hlbm;

/// Everything a typical user needs.
pub mod prelude {
    pub use crate::math::{Pose, Real, Rotation, Vector};
    pub use crate::{
        BodyKinematics, BodyState, ContactModel, ConvexShape, Friction, IntegrationMode, Material,
        OverlapSettings, PairParameters, Sdf, StiffnessFactor, TangentialLaw,
    };
}
