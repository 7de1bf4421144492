//! An ordinary rapier scene for the drop-in demonstration and its benchmark: a bin (half-space
//! floor and four cuboid walls on a fixed body) filled from above with a mix of spheres,
//! cylinders, cubes and convex polyhedra, and a see-saw plank on a revolute joint in the middle
//! of the floor. Nothing in it knows about the discrete contact: the same world runs with
//! rapier's own contacts or with [`DiscreteContacts`].

use discrete_contact::rapier3d_f64::prelude::*;

use discrete_contact::error::Result;
use discrete_contact::material::{Friction, Material};
use discrete_contact::math::{Real, Vector};
use discrete_contact::overlap::{IntegrationMode, OverlapSettings};
use discrete_contact::rapier::{DiscreteContacts, StepPolicy};

/// Size of the bodies (m): spheres of this radius; the other shapes have similar volume.
pub const BODY_RADIUS: Real = 0.01;
/// Density of every body (kg/m³).
pub const DENSITY: Real = 1000.0;
/// Friction coefficient of rapier's own contacts (the discrete run sets its own law).
pub const RAPIER_FRICTION: Real = 0.4;
/// Restitution of rapier's own contacts.
pub const RAPIER_RESTITUTION: Real = 0.5;

/// Restitution of the discrete contacts.
pub const RESTITUTION: Real = 0.5;

/// The bodies' material for the discrete contacts: a rubber, E = 5 MPa, ν = 0.4.
pub fn rubber() -> Result<Material> {
    Material::new(5e6, 0.4)
}

/// The discrete contact the example and the benchmark add to the scene: sub-cell integration
/// at `n_c`, restitution [`RESTITUTION`], friction μ_s = 0.5, μ_k = 0.4 (v_s = 1 cm/s),
/// `substeps_per_contact` sub-steps per Hertz contact time, automatic sub-stepping. Hand it
/// the colliders with `handle_all(&mut world, rubber()?)`.
pub fn discrete_contacts(n_c: usize, substeps_per_contact: Real) -> Result<DiscreteContacts> {
    discrete_contacts_with(
        OverlapSettings::new(n_c, IntegrationMode::Subcell)?,
        substeps_per_contact,
    )
}

/// [`discrete_contacts`] with any overlap settings (the example's `--exact` adds the exact forms
/// for sphere and polyhedron pairs).
pub fn discrete_contacts_with(
    overlap: OverlapSettings,
    substeps_per_contact: Real,
) -> Result<DiscreteContacts> {
    Ok(DiscreteContacts::new(overlap, RESTITUTION)?
        .with_friction(Friction::new(0.5, 0.4, 0.01)?)
        .with_substeps_per_contact(substeps_per_contact)?
        .with_policy(StepPolicy::AutoSubstep { max_substeps: 1000 }))
}

/// The scene and the handles a report needs.
pub struct BinScene {
    /// The world, with gravity, `dt = 1/240 s`.
    pub world: PhysicsWorld,
    /// The falling bodies.
    pub bodies: Vec<RigidBodyHandle>,
    /// The see-saw plank on its revolute joint.
    pub plank: RigidBodyHandle,
    /// Half-width of the bin's square floor (m).
    pub half_width: Real,
}

/// A uniform sequence on [0, 1) from xorshift64 started at `seed`: portable and fixed, so a
/// scene is the same on every machine.
pub fn xorshift(mut seed: u64) -> impl FnMut() -> Real {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as Real / (1u64 << 53) as Real
    }
}

/// The scene's rock about its centre: twelve points in directions drawn from `random`, each at
/// 0.85–1.15 `r` (their convex hull is the rock).
pub fn rock_points(r: Real, random: &mut impl FnMut() -> Real) -> Vec<Vector> {
    (0..12)
        .map(|_| {
            let p = Vector::new(random() - 0.5, random() - 0.5, random() - 0.5);
            p.normalize_or(Vector::X) * r * (0.85 + 0.3 * random())
        })
        .collect()
}

/// A bin with `n` falling bodies, columns of six by six per layer, shapes cycling through
/// sphere, cylinder, cube and polyhedron, each slightly turned (deterministic).
pub fn bin_scene(n: usize) -> BinScene {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, -9.81, 0.0);
    world.integration_parameters.dt = 1.0 / 240.0;
    let r = BODY_RADIUS;
    let spacing = 2.7 * r;
    let per_row = 6;
    let half_width = 0.5 * spacing * per_row as Real + r;

    // The bin: floor and four walls on one fixed body.
    let bin = world.insert_body(RigidBodyBuilder::fixed());
    let rapier_material =
        |c: ColliderBuilder| c.friction(RAPIER_FRICTION).restitution(RAPIER_RESTITUTION);
    world.insert_collider(
        rapier_material(ColliderBuilder::new(SharedShape::halfspace(Vector::Y))),
        Some(bin),
    );
    let (t, h) = (0.01, 0.3);
    for (x, z, hx, hz) in [
        (half_width + t, 0.0, t, half_width + 2.0 * t),
        (-half_width - t, 0.0, t, half_width + 2.0 * t),
        (0.0, half_width + t, half_width, t),
        (0.0, -half_width - t, half_width, t),
    ] {
        world.insert_collider(
            rapier_material(ColliderBuilder::cuboid(hx, h, hz)).translation(Vector::new(x, h, z)),
            Some(bin),
        );
    }

    // The see-saw: a plank hinged about z at its middle, above the floor.
    let pivot = Vector::new(0.0, 0.025, 0.0);
    let plank = world.insert_body(RigidBodyBuilder::dynamic().translation(pivot));
    world.insert_collider(
        rapier_material(ColliderBuilder::cuboid(0.6 * half_width, 0.004, 0.4 * half_width))
            .density(DENSITY),
        Some(plank),
    );
    let anchor = world.insert_body(RigidBodyBuilder::fixed().translation(pivot));
    world.insert_impulse_joint(anchor, plank, RevoluteJointBuilder::new(Vector::Z));

    // The falling bodies.
    let mut bodies = Vec::with_capacity(n);
    let mut random = xorshift(0x2545_f491_4f6c_dd1d);
    for i in 0..n {
        let (layer, k) = (i / (per_row * per_row), i % (per_row * per_row));
        let x = -half_width + r + 0.5 * spacing + (k % per_row) as Real * spacing;
        let z = -half_width + r + 0.5 * spacing + (k / per_row) as Real * spacing;
        let y = 0.06 + layer as Real * spacing;
        let turn = Vector::new(random() - 0.5, random() - 0.5, random() - 0.5) * 2.0;
        let body = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(
                    x + 0.2 * r * (random() - 0.5),
                    y,
                    z + 0.2 * r * (random() - 0.5),
                ))
                .rotation(turn),
        );
        let collider = match i % 4 {
            0 => ColliderBuilder::ball(r),
            1 => ColliderBuilder::cylinder(0.8 * r, 0.9 * r),
            2 => ColliderBuilder::cuboid(0.8 * r, 0.8 * r, 0.8 * r),
            _ => {
                let points = rock_points(r, &mut random);
                ColliderBuilder::convex_hull(&points).unwrap_or_else(|| ColliderBuilder::ball(r))
            }
        };
        world.insert_collider(rapier_material(collider).density(DENSITY), Some(body));
        bodies.push(body);
    }
    BinScene { world, bodies, plank, half_width }
}

/// Kinetic energy (J) of the dynamic bodies, rotation included.
pub fn kinetic_energy(world: &PhysicsWorld) -> Real {
    world.bodies.iter().filter(|(_, rb)| rb.is_dynamic()).map(|(_, rb)| rb.kinetic_energy()).sum()
}
