//! The drop-in: an ordinary rapier scene — a bin filled with a few hundred spheres, cylinders,
//! cubes and convex polyhedra falling onto a see-saw plank on a revolute joint — run twice:
//! with rapier's own contacts, and with the discrete overlap-volume contact added by the few
//! lines marked below. Prints kinetic energy, largest overlap and wall time as the pile
//! settles, and writes `target/validation/drop_in.csv`.
//!
//! `cargo run --release --example drop_in [-- --bodies 180 --seconds 1.0 --nc 4 --per-contact 6 --reuse 0.25]`
//! (about four minutes on 2 cores; the run time grows with bodies × seconds). `--exact` computes
//! the sphere pairs (and spheres on the floor) in closed form and the pairs of cubes, convex
//! polyhedra, walls and the plank as exact polyhedra; the rest (cylinders, sphere–box) on the
//! grid. `--reuse f` sets the geometry reuse (0: every contact evaluated in full on every
//! sub-step).

#[path = "common/mod.rs"]
mod common;

use std::time::Instant;

use discrete_contact_validation::drop_in::{
    self, bin_scene, kinetic_energy, BinScene, BODY_RADIUS,
};

/// Reporting interval (s of simulated time).
const REPORT_EVERY: f64 = 0.1;

/// Largest penetration among rapier's own contact points (m).
fn rapier_penetration(world: &discrete_contact::rapier3d_f64::prelude::PhysicsWorld) -> f64 {
    world
        .narrow_phase
        .contact_pairs()
        .flat_map(|p| p.manifolds().iter())
        .flat_map(|m| m.points.iter())
        .map(|p| -p.dist)
        .fold(0.0, f64::max)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env(include_str!("drop_in.rs"));
    let n = args.number("--bodies", 180.0) as usize;
    let seconds = args.number("--seconds", 1.0);
    let per_contact = args.number("--per-contact", 6.0);
    let n_c = args.number("--nc", 4.0) as usize;
    let exact = args.flag("--exact");
    let reuse = discrete_contact::contact::check_reuse(
        args.number("--reuse", discrete_contact::contact::GEOMETRY_REUSE),
    )
    .unwrap_or_else(|e| {
        eprintln!("--reuse: {e}");
        std::process::exit(2);
    });

    // 1. The scene with rapier's own contacts.
    let BinScene { mut world, .. } = bin_scene(n);
    let dt = world.integration_parameters.dt;
    let steps = (seconds / dt).round() as usize;
    let every = (REPORT_EVERY / dt).round() as usize;
    println!("{n} bodies (radius {BODY_RADIUS} m) and a see-saw on a revolute joint, dt = {dt:.5} s, {seconds} s simulated");
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

    // 2. The same scene with the discrete contact: these lines are the drop-in (the settings,
    //    rubber E = 5 MPa, e = 0.5, friction 0.5/0.4, are in the validation crate's `drop_in`).
    let BinScene { mut world, .. } = bin_scene(n);
    let overlap =
        discrete_contact::OverlapSettings::new(n_c, discrete_contact::IntegrationMode::Subcell)?;
    let mut contacts = drop_in::discrete_contacts_with(
        overlap.with_closed_form_spheres(exact).with_exact_polyhedra(exact),
        per_contact,
    )?
    .with_geometry_reuse(reuse)?;
    let handled = contacts.handle_all(&mut world, drop_in::rubber()?)?;
    // (then `contacts.step(&mut world)?` where the loop had `world.step()`)

    let forms = if exact { ", exact forms where they exist" } else { "" };
    println!("\ndiscrete contacts ({handled} colliders handled, sub-cell N_c = {n_c}{forms}, rubber E = 5 MPa, e = 0.5, μ = 0.5/0.4, {per_contact} sub-steps per contact time, geometry reuse {reuse}):");
    println!(
        "{:>6} {:>12} {:>9} {:>9} {:>10} {:>14} {:>8}",
        "t (s)", "KE (J)", "contacts", "sub/step", "full/c/step", "max overlap", "wall (s)"
    );
    let start = Instant::now();
    let (mut max_ind, mut max_sub, mut total_sub): (f64, usize, usize) = (0.0, 0, 0);
    // Full evaluations and contact-steps (a contact alive at a step's end) since the last row, and in all.
    let (mut full, mut contact_steps, mut all_full, mut all_evaluations) =
        (0usize, 0usize, 0usize, 0usize);
    let mut rows = Vec::new();
    for s in 1..=steps {
        let st = contacts.step(&mut world)?;
        max_ind = max_ind.max(st.max_indentation);
        max_sub = max_sub.max(st.substeps);
        total_sub += st.substeps;
        full += st.full_evaluations;
        contact_steps += st.contacts;
        all_full += st.full_evaluations;
        all_evaluations += st.evaluations;
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
    let wall = start.elapsed().as_secs_f64();
    let ke = kinetic_energy(&world);
    let path = common::output_dir().join("drop_in.csv");
    common::write_csv(&path, "t_s,kinetic_energy_j,contacts,substeps_per_step,full_evaluations_per_contact_step,max_indentation_m,wall_time_s", &rows);

    println!("\nsummary ({n} bodies, {seconds} s simulated):");
    println!("  rapier's contacts:   KE {rapier_ke:.3e} J, largest penetration {:.2} mm, wall {rapier_wall:.2} s", max_pen * 1e3);
    println!(
        "  discrete contacts:   KE {ke:.3e} J, largest overlap {:.3} mm ({:.1} % of the radius), {total_sub} sub-steps, wall {wall:.2} s",
        max_ind * 1e3,
        100.0 * max_ind / BODY_RADIUS
    );
    println!(
        "  contact evaluations: {all_evaluations}, of them full {all_full} ({:.1} %)",
        100.0 * all_full as f64 / all_evaluations.max(1) as f64
    );
    println!("  wall-time ratio discrete / rapier: {:.0}", wall / rapier_wall);
    println!("wrote {}", path.display());
    Ok(())
}
