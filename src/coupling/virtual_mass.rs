//! The virtual mass: the fluid's added mass lent to a body over each fluid step.
//!
//! A lattice carries pressure at its sound speed, a few lattice spacings per step, so when a
//! contact turns a body round within a fluid step or two, the liquid's reaction to that turn
//! (its added mass, `≈ ρ_f V/2` for a sphere in open liquid, more near a wall) reaches the body
//! over the following steps, after the contact has let go, and is taken from the rebound. In a
//! liquid the added mass turns with the body during the contact: the contact pushes on both.
//!
//! As in the scheme of Schwarz, Kempe & Fröhlich (2015, J. Comput. Phys. 281, 591–613,
//! doi:10.1016/j.jcp.2014.10.039), the body is lent a virtual mass `m_v = C_V ρ_f V` for each
//! fluid step, and the momentum `m_v Δv` this takes from it is returned later. Theirs returns
//! it on the next step, with the previous step's acceleration, for a solver whose fluid
//! answers within a step; a lattice answers a sudden turn over the time its pressure takes to
//! cross the body (`τ = r √3 Δt/Δx`, several steps), and a contact lasts a few steps, so here
//! the momentum lent, `P`, comes back at the rate `P/τ`:
//!
//! `(m + m_v) Δv_n = F_n Δt + R_n`, `R_n = P_n min(1, Δt/τ)`, `P_{n+1} = P_n − R_n + m_v Δv_n`.
//!
//! Summed over steps, `m (v_N − v_0) = Σ F Δt − P_N`: the body's momentum is the forces'
//! impulse less what is still lent, so nothing is created or lost, and where the acceleration
//! is steady over `τ` the return equals the loan. Within a collision the contact turns
//! `m + m_v` round, and `m_v (1 + e) U` comes back to the body over `τ` while the lattice
//! takes its own reaction from it.
//!
//! Here the virtual mass is a point mass at the body's centre of mass (no rotational added
//! mass, as for a sphere in potential flow) added to rapier's mass properties for the step, the
//! body's gravity scale lowered by `m / (m + m_v)` so that its weight stays `m g`.

use rapier3d_f64::dynamics::{MassProperties, RigidBodyAdditionalMassProps};
use rapier3d_f64::prelude::{PhysicsWorld, RigidBodyHandle};

use crate::error::{Error, Result};
use crate::math::{Real, Vector};

/// What a body had before the virtual mass was lent to it, to give back after the step.
pub(super) struct Lent {
    body: RigidBodyHandle,
    additional: Option<RigidBodyAdditionalMassProps>,
    gravity_scale: Real,
    /// The velocity at the start of the step, `v_n` (m/s).
    start: Vector,
}

/// Whether `body` can take a virtual mass: not when its additional mass was set with
/// `set_additional_mass` (rapier scales its inertia with it; give it as
/// `set_additional_mass_properties` instead).
pub(super) fn check(world: &PhysicsWorld, body: RigidBodyHandle) -> Result<()> {
    match world
        .bodies
        .get(body)
        .and_then(|rb| rb.mass_properties().additional_local_mprops.as_deref())
    {
        Some(RigidBodyAdditionalMassProps::Mass(_)) => Err(Error::InvalidArgument {
            name: "additional mass of a body with a virtual mass",
            allowed: "mass properties (set_additional_mass_properties), not a bare mass",
        }),
        _ => Ok(()),
    }
}

/// Lends `body` ([`check`]ed) the virtual mass `m_v` (kg) for one step; returning the momentum
/// lent before ([`returned_share`]) is the caller's.
pub(super) fn lend(world: &mut PhysicsWorld, body: RigidBodyHandle, m_v: Real) -> Lent {
    let rb = &mut world.bodies[body];
    let additional = rb.mass_properties().additional_local_mprops.as_deref().copied();
    let point = MassProperties::new(rb.local_center_of_mass(), m_v, Vector::ZERO);
    let lent = match additional {
        Some(RigidBodyAdditionalMassProps::MassProps(p)) => p + point,
        _ => point,
    };
    let (mass, gravity_scale, start) = (rb.mass(), rb.gravity_scale(), rb.linvel());
    rb.set_additional_mass_properties(lent, false);
    rb.recompute_mass_properties_from_colliders(&world.colliders);
    rb.set_gravity_scale(gravity_scale * mass / (mass + m_v), false);
    Lent { body, additional, gravity_scale, start }
}

/// The share of the momentum still lent that a step of `dt` (s) returns to a body of volume
/// `volume` (m³) on a lattice of spacing `dx` (m): `Δt/τ`, at most 1, with `τ` the time the
/// lattice's pressure takes to cross the body's equivalent radius `r` at its sound speed
/// `Δx/(√3 Δt)` — over which the lattice delivers its own reaction to a sudden turn.
pub(super) fn returned_share(volume: Real, dx: Real, dt: Real) -> Real {
    let radius = (3.0 * volume / (4.0 * std::f64::consts::PI)).cbrt();
    let crossing = radius * 3.0_f64.sqrt() * dt / dx;
    (dt / crossing).min(1.0)
}

/// Gives back what [`lend`] took; returns the step's velocity change `v_{n+1} − v_n`.
pub(super) fn give_back(world: &mut PhysicsWorld, lent: Lent) -> Vector {
    let rb = &mut world.bodies[lent.body];
    let props = match lent.additional {
        None | Some(RigidBodyAdditionalMassProps::Mass(_)) => MassProperties::default(),
        Some(RigidBodyAdditionalMassProps::MassProps(p)) => p,
    };
    rb.set_additional_mass_properties(props, false);
    rb.recompute_mass_properties_from_colliders(&world.colliders);
    rb.set_gravity_scale(lent.gravity_scale, false);
    rb.linvel() - lent.start
}
