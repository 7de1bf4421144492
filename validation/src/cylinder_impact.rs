//! Oblique impact of a cylinder on a wall (Marquardt et al. §4.2, Park 2003), run in the
//! rapier pipeline through [`DiscreteContacts`].
//!
//! H = 5.3 mm, R = 4 mm, m = 3.1e-4 kg, I_xx = I_zz = 1.96566e-9 kg m² (about diameters),
//! 2.48e-9 kg m² about the axis; 1 m/s towards the wall; frictionless; e = 0.85;
//! E = 5e8 Pa, ν = 0.35 for both; Δt = 1.7e-6 s with 10 contact sub-steps.

use std::time::Instant;

use discrete_contact::rapier3d_f64::prelude::{
    ColliderBuilder, MassProperties, PhysicsWorld, RigidBodyBuilder, SharedShape,
};

use discrete_contact::error::Result;
use discrete_contact::material::Material;
use discrete_contact::math::{Pose, Real, Rotation, Vector};
use discrete_contact::overlap::OverlapSettings;
use discrete_contact::rapier::{DiscreteContacts, StepPolicy};

/// Cylinder height (m).
pub const HEIGHT: Real = 5.3e-3;
/// Cylinder radius (m).
pub const RADIUS: Real = 4e-3;
/// Mass (kg).
pub const MASS: Real = 3.1e-4;
/// Moment of inertia about a diameter (kg m²).
pub const INERTIA_DIAMETER: Real = 1.96566e-9;
/// Moment of inertia about the axis (kg m²).
pub const INERTIA_AXIS: Real = 2.48e-9;
/// Coefficient of restitution.
pub const RESTITUTION: Real = 0.85;
/// Time step (s).
pub const DT: Real = 1.7e-6;
/// Contact sub-steps per step.
pub const SUBSTEPS: usize = 10;

/// Park (2003): `(v⁺/v, R ω⁺/v)` for impact angle `theta_deg` between the flat face and the
/// wall; exactly 0° and 90° are face and line contacts without spin.
pub fn park(theta_deg: Real) -> (Real, Real) {
    if theta_deg <= 0.0 || theta_deg >= 90.0 {
        return (RESTITUTION, 0.0);
    }
    let r = (RADIUS * RADIUS + HEIGHT * HEIGHT / 4.0).sqrt();
    let alpha = (HEIGHT / (2.0 * RADIUS)).atan();
    let lever = r * (alpha + theta_deg.to_radians()).cos();
    let omega = MASS * (1.0 + RESTITUTION) * lever / (INERTIA_DIAMETER + MASS * lever * lever);
    (RESTITUTION - omega * lever, RADIUS * omega)
}

/// Result of one impact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rebound {
    /// Rebound speed of the centre / impact speed, away from the wall positive.
    pub v_ratio: Real,
    /// `R ω⁺ / v`, sign as in [`park`].
    pub omega_r_ratio: Real,
    /// Wall-clock time of the run (s).
    pub wall_time_s: Real,
}

/// Runs the impact at `theta_deg` and returns the state when the first contact ends, with the
/// drop-in's default geometry reuse ([`GEOMETRY_REUSE`](discrete_contact::contact::GEOMETRY_REUSE)).
pub fn simulate(theta_deg: Real, settings: OverlapSettings) -> Result<Rebound> {
    simulate_with_reuse(theta_deg, settings, discrete_contact::contact::GEOMETRY_REUSE)
}

/// [`simulate`] with geometry reuse at `reuse` (0: every sub-step evaluates the contact in
/// full; see [`DiscreteContacts::with_geometry_reuse`]).
pub fn simulate_with_reuse(
    theta_deg: Real,
    settings: OverlapSettings,
    reuse: Real,
) -> Result<Rebound> {
    let start = Instant::now();
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    world.integration_parameters.dt = DT;
    let wall = world.insert_body(RigidBodyBuilder::fixed());
    let wall_collider =
        world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(wall));
    // Axis (parry's y) tilted by θ about z: θ = 0 puts the flat face parallel to the wall.
    let theta = theta_deg.to_radians();
    let rotation = Rotation::from_rotation_z(theta);
    let lowest = HEIGHT / 2.0 * theta.cos() + RADIUS * theta.sin();
    let body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .pose(Pose::from_parts(Vector::new(0.0, lowest + 1e-7, 0.0), rotation))
            .linvel(Vector::new(0.0, -1.0, 0.0))
            .additional_mass_properties(MassProperties::new(
                Vector::ZERO,
                MASS,
                Vector::new(INERTIA_DIAMETER, INERTIA_AXIS, INERTIA_DIAMETER),
            ))
            .can_sleep(false),
    );
    let cyl = world
        .insert_collider(ColliderBuilder::cylinder(HEIGHT / 2.0, RADIUS).density(0.0), Some(body));
    let material = Material::new(5e8, 0.35)?;
    let mut contacts = DiscreteContacts::new(settings, RESTITUTION)?
        .with_policy(StepPolicy::Fixed { substeps: SUBSTEPS })
        .with_geometry_reuse(reuse)?;
    contacts.handle(&mut world, wall_collider, material)?;
    contacts.handle(&mut world, cyl, material)?;
    let mut touched = false;
    for _ in 0..20_000 {
        contacts.step(&mut world)?;
        let now = contacts.contact(cyl, wall_collider).is_some();
        if touched && !now {
            break;
        }
        touched |= now;
    }
    let rb = &world.bodies[body];
    // A rim point left of the centre (lever > 0) spins the cylinder about -z.
    Ok(Rebound {
        v_ratio: rb.linvel().y,
        omega_r_ratio: -RADIUS * rb.angvel().z,
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}
