//! The bin scene and its run in one rapier build: its parent module names the rapier crate
//! `engine` and the drop-in `drop_in`. Written once for both builds, so conversions between
//! the scene's f64 constants and rapier's numbers are identities in the f64 build.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use std::time::Instant;

use super::drop_in::{DiscreteContacts, StepPolicy};
use super::engine::math::{Real, Vector};
use super::engine::prelude::*;

use super::super::{
    rock_points, rubber, xorshift, Options, Summary, BODY_RADIUS, DENSITY, RAPIER_FRICTION,
    RAPIER_RESTITUTION, RESTITUTION,
};
use discrete_contact::error::Result;
use discrete_contact::material::Friction;
use discrete_contact::overlap::{IntegrationMode, OverlapSettings};

/// The discrete contact the example and the benchmark add to the scene: sub-cell integration
/// at `n_c`, restitution [`RESTITUTION`], friction μ_s = 0.5, μ_k = 0.4 (v_s = 1 cm/s),
/// `substeps_per_contact` sub-steps per Hertz contact time, automatic sub-stepping. Hand it
/// the colliders with `handle_all(&mut world, rubber()?)`.
pub fn discrete_contacts(n_c: usize, substeps_per_contact: f64) -> Result<DiscreteContacts> {
    discrete_contacts_with(
        OverlapSettings::new(n_c, IntegrationMode::Subcell)?,
        substeps_per_contact,
    )
}

/// [`discrete_contacts`] with any overlap settings (the example's `--exact` adds the exact forms
/// for sphere and polyhedron pairs).
pub fn discrete_contacts_with(
    overlap: OverlapSettings,
    substeps_per_contact: f64,
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
    pub half_width: f64,
}

/// The four cuboid walls of a square bin about the vertical axis through the origin: inner
/// faces `half_width` from it (m), `thickness` thick, standing on `y = 0` to `2 height`, the
/// corners closed.
pub fn bin_walls(half_width: f64, thickness: f64, height: f64) -> [ColliderBuilder; 4] {
    let (w, t) = (half_width, thickness);
    [
        (w + t, 0.0, t, w + 2.0 * t),
        (-w - t, 0.0, t, w + 2.0 * t),
        (0.0, w + t, w, t),
        (0.0, -w - t, w, t),
    ]
    .map(|(x, z, hx, hz)| {
        ColliderBuilder::cuboid(hx as Real, height as Real, hz as Real).translation(Vector::new(
            x as Real,
            height as Real,
            z as Real,
        ))
    })
}

/// A bin with `n` falling bodies, columns of six by six per layer, shapes cycling through
/// sphere, cylinder, cube and polyhedron, each slightly turned (deterministic).
pub fn bin_scene(n: usize) -> BinScene {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, -9.81, 0.0);
    world.integration_parameters.dt = 1.0 / 240.0;
    // Positions and sizes in f64, each rounded once to rapier's numbers.
    let v = |x: f64, y: f64, z: f64| Vector::new(x as Real, y as Real, z as Real);
    let r = BODY_RADIUS;
    let spacing = 2.7 * r;
    let per_row = 6;
    let half_width = 0.5 * spacing * per_row as f64 + r;

    // The bin: floor and four walls on one fixed body.
    let bin = world.insert_body(RigidBodyBuilder::fixed());
    let rapier_material = |c: ColliderBuilder| {
        c.friction(RAPIER_FRICTION as Real).restitution(RAPIER_RESTITUTION as Real)
    };
    world.insert_collider(
        rapier_material(ColliderBuilder::new(SharedShape::halfspace(Vector::Y))),
        Some(bin),
    );
    for wall in bin_walls(half_width, 0.01, 0.3) {
        world.insert_collider(rapier_material(wall), Some(bin));
    }

    // The see-saw: a plank hinged about z at its middle, above the floor.
    let pivot = v(0.0, 0.025, 0.0);
    let plank = world.insert_body(RigidBodyBuilder::dynamic().translation(pivot));
    world.insert_collider(
        rapier_material(ColliderBuilder::cuboid(
            (0.6 * half_width) as Real,
            0.004,
            (0.4 * half_width) as Real,
        ))
        .density(DENSITY as Real),
        Some(plank),
    );
    let anchor = world.insert_body(RigidBodyBuilder::fixed().translation(pivot));
    world.insert_impulse_joint(anchor, plank, RevoluteJointBuilder::new(Vector::Z));

    // The falling bodies.
    let mut bodies = Vec::with_capacity(n);
    let mut random = xorshift(0x2545_f491_4f6c_dd1d);
    for i in 0..n {
        let (layer, k) = (i / (per_row * per_row), i % (per_row * per_row));
        let x = -half_width + r + 0.5 * spacing + (k % per_row) as f64 * spacing;
        let z = -half_width + r + 0.5 * spacing + (k / per_row) as f64 * spacing;
        let y = 0.06 + layer as f64 * spacing;
        let turn = v(random() - 0.5, random() - 0.5, random() - 0.5) * 2.0;
        let body = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(v(x + 0.2 * r * (random() - 0.5), y, z + 0.2 * r * (random() - 0.5)))
                .rotation(turn),
        );
        let rf = r as Real;
        let collider = match i % 4 {
            0 => ColliderBuilder::ball(rf),
            1 => ColliderBuilder::cylinder(0.8 * rf, 0.9 * rf),
            2 => ColliderBuilder::cuboid(0.8 * rf, 0.8 * rf, 0.8 * rf),
            _ => {
                let points: Vec<Vector> =
                    rock_points(r, &mut random).iter().map(|p| v(p.x, p.y, p.z)).collect();
                ColliderBuilder::convex_hull(&points).unwrap_or_else(|| ColliderBuilder::ball(rf))
            }
        };
        world.insert_collider(rapier_material(collider).density(DENSITY as Real), Some(body));
        bodies.push(body);
    }
    BinScene { world, bodies, plank, half_width }
}

/// Kinetic energy (J) of the dynamic bodies, rotation included.
pub fn kinetic_energy(world: &PhysicsWorld) -> f64 {
    world
        .bodies
        .iter()
        .filter(|(_, rb)| rb.is_dynamic())
        .map(|(_, rb)| rb.kinetic_energy() as f64)
        .sum()
}

/// Largest penetration among rapier's own contact points (m).
fn rapier_penetration(world: &PhysicsWorld) -> f64 {
    world
        .narrow_phase
        .contact_pairs()
        .flat_map(|p| p.manifolds().iter())
        .flat_map(|m| m.points.iter())
        .map(|p| -p.dist as f64)
        .fold(0.0, f64::max)
}

/// Runs the scene twice as [`Options`] says — with rapier's own contacts, then with the
/// discrete contact added by the few lines marked below — printing a row every
/// `report_every` s of simulated time.
pub fn run(options: &Options, report_every: f64) -> Result<Summary> {
    let Options { bodies: n, seconds, per_contact, n_c, exact, facet_bulge, reuse, length_unit } =
        *options;
    let scene = || {
        let mut scene = bin_scene(n);
        scene.world.integration_parameters.length_unit = length_unit as Real;
        scene
    };
    // 1. The scene with rapier's own contacts.
    let BinScene { mut world, .. } = scene();
    let dt = world.integration_parameters.dt as f64;
    let steps = (seconds / dt).round() as usize;
    let every = (report_every / dt).round() as usize;
    println!("{n} bodies (radius {BODY_RADIUS} m) and a see-saw on a revolute joint, dt = {dt:.5} s, {seconds} s simulated, rapier's length unit {length_unit} m");
    println!("\nrapier's own contacts:");
    println!("{:>6} {:>12} {:>14} {:>8}", "t (s)", "KE (J)", "penetration", "wall (s)");
    let start = Instant::now();
    let mut max_pen: f64 = 0.0;
    for s in 1..=steps {
        world.step();
        max_pen = max_pen.max(rapier_penetration(&world));
        if s % every == 0 {
            println!(
                "{:>6.2} {:>12.4e} {:>11.2} mm {:>8.2}",
                s as f64 * dt,
                kinetic_energy(&world),
                max_pen * 1e3,
                start.elapsed().as_secs_f64()
            );
        }
    }
    let rapier_wall = start.elapsed().as_secs_f64();
    let rapier_ke = kinetic_energy(&world);

    // 2. The same scene with the discrete contact: these lines are the drop-in (rubber
    //    E = 5 MPa, e = 0.5, friction 0.5/0.4).
    let BinScene { mut world, .. } = scene();
    let overlap =
        OverlapSettings::new(n_c, IntegrationMode::Subcell)?.with_facet_bulge(facet_bulge);
    let mut contacts = discrete_contacts_with(
        overlap.with_closed_form_spheres(exact).with_exact_polyhedra(exact),
        per_contact,
    )?
    .with_geometry_reuse(reuse)?;
    let left = contacts.handle_all(&mut world, rubber()?)?;
    let handled = world.colliders.len() - left.len();
    // (then `contacts.step(&mut world)?` where the loop had `world.step()`)

    let forms = match (exact, facet_bulge) {
        (true, _) => ", exact forms where they exist",
        (false, false) => ", no facet layer",
        (false, true) => "",
    };
    println!("\ndiscrete contacts ({handled} colliders handled, sub-cell N_c = {n_c}{forms}, rubber E = 5 MPa, e = 0.5, μ = 0.5/0.4, {per_contact} sub-steps per contact time, geometry reuse {reuse}):");
    println!(
        "{:>6} {:>12} {:>9} {:>9} {:>10} {:>14} {:>8}",
        "t (s)", "KE (J)", "contacts", "sub/step", "full/c/step", "max overlap", "wall (s)"
    );
    let start = Instant::now();
    let (mut max_ind, mut max_sub, mut total_sub): (f64, usize, usize) = (0.0, 0, 0);
    // Full evaluations and contact-steps (a contact alive at a step's end) since the last row;
    // evaluations, and full ones by cause, in all.
    let (mut full, mut contact_steps, mut all_evaluations) = (0usize, 0usize, 0usize);
    let mut refreshes = discrete_contact::contact::Refreshes::default();
    let mut rows = Vec::new();
    for s in 1..=steps {
        let st = contacts.step(&mut world)?;
        max_ind = max_ind.max(st.max_indentation);
        max_sub = max_sub.max(st.substeps);
        total_sub += st.substeps;
        full += st.full_evaluations();
        contact_steps += st.contacts;
        all_evaluations += st.evaluations;
        refreshes += st.refreshes;
        if s % every == 0 {
            let (t, ke, wall) =
                (s as f64 * dt, kinetic_energy(&world), start.elapsed().as_secs_f64());
            let per_contact_step = full as f64 / contact_steps.max(1) as f64;
            println!(
                "{t:>6.2} {ke:>12.4e} {:>9} {:>9} {per_contact_step:>11.2} {:>11.3} mm {wall:>8.2}",
                st.contacts,
                max_sub,
                max_ind * 1e3
            );
            rows.push(format!(
                "{t},{ke},{},{max_sub},{per_contact_step},{max_ind},{wall}",
                st.contacts
            ));
            (max_sub, full, contact_steps) = (0, 0, 0);
        }
    }
    Ok(Summary {
        rapier_ke,
        rapier_penetration: max_pen,
        rapier_wall,
        handled,
        ke: kinetic_energy(&world),
        max_indentation: max_ind,
        substeps: total_sub,
        evaluations: all_evaluations,
        refreshes,
        wall: start.elapsed().as_secs_f64(),
        rows,
    })
}
