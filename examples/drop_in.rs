//! The drop-in: an ordinary rapier scene — a bin filled with a few hundred spheres, cylinders,
//! cubes and convex polyhedra falling onto a see-saw plank on a revolute joint — run twice:
//! with rapier's own contacts, and with the discrete overlap-volume contact added by the few
//! lines marked in the validation crate's `drop_in::run`. Prints kinetic energy, largest overlap and wall time as the pile
//! settles, and writes `target/validation/drop_in.csv`.
//!
//! `cargo run --release --example drop_in [-- --bodies 180 --seconds 1.0 --nc 4 --per-contact 6 --reuse 0.25]`
//! (about a minute on 2 cores; the run time grows with bodies × seconds). `--exact` computes
//! the sphere pairs (and spheres on the floor) in closed form and the pairs of cubes, convex
//! polyhedra, walls and the plank as exact polyhedra; the rest (cylinders, sphere–box) on the
//! grid. `--reuse f` sets the geometry reuse (0: every contact evaluated in full on every
//! sub-step). `--f32` runs the same scene in rapier3d (f32) with the f32 drop-in, and writes
//! `drop_in_f32.csv`. `--length-unit m` sets rapier's `length_unit` in both runs (default 1 m,
//! as an untuned scene has it; rapier advises the bodies' size, here 0.02 m, which takes its
//! broad-phase pairs from ~14 000 to ~950). `--no-facet-bulge` integrates the balls' contacts
//! without their facet layer (second order, `OverlapSettings::with_facet_bulge(false)`).

#[path = "common/mod.rs"]
mod common;

use discrete_contact_validation::drop_in::{self, Options, Summary, BODY_RADIUS};

/// Reporting interval (s of simulated time).
const REPORT_EVERY: f64 = 0.1;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env(include_str!("drop_in.rs"));
    let f32 = args.flag("--f32");
    let options = Options {
        bodies: args.number("--bodies", 180.0) as usize,
        seconds: args.number("--seconds", 1.0),
        per_contact: args.number("--per-contact", 6.0),
        n_c: args.number("--nc", 4.0) as usize,
        exact: args.flag("--exact"),
        facet_bulge: !args.flag("--no-facet-bulge"),
        reuse: discrete_contact::contact::check_reuse(
            args.number("--reuse", discrete_contact::contact::GEOMETRY_REUSE),
        )
        .unwrap_or_else(|e| {
            eprintln!("--reuse: {e}");
            std::process::exit(2);
        }),
        length_unit: args.number("--length-unit", 1.0),
    };
    if !(options.length_unit > 0.0 && options.length_unit.is_finite()) {
        eprintln!("--length-unit: must be a length > 0 (m), got {}", options.length_unit);
        std::process::exit(2);
    }
    println!("rapier build: {}", if f32 { "rapier3d (f32)" } else { "rapier3d-f64" });
    let run = if f32 { drop_in::f32::run } else { drop_in::run };
    let Summary {
        rapier_ke,
        rapier_penetration,
        rapier_wall,
        ke,
        max_indentation,
        substeps,
        evaluations,
        refreshes,
        wall,
        rows,
        ..
    } = run(&options, REPORT_EVERY)?;
    let name = if f32 { "drop_in_f32.csv" } else { "drop_in.csv" };
    let path = common::output_dir().join(name);
    common::write_csv(&path, "t_s,kinetic_energy_j,contacts,substeps_per_step,full_evaluations_per_contact_step,max_indentation_m,wall_time_s", &rows);

    let (n, seconds) = (options.bodies, options.seconds);
    println!("\nsummary ({n} bodies, {seconds} s simulated):");
    println!("  rapier's contacts:   KE {rapier_ke:.3e} J, largest penetration {:.2} mm, wall {rapier_wall:.2} s", rapier_penetration * 1e3);
    println!(
        "  discrete contacts:   KE {ke:.3e} J, largest overlap {:.3} mm ({:.1} % of the radius), {substeps} sub-steps, wall {wall:.2} s",
        max_indentation * 1e3,
        100.0 * max_indentation / BODY_RADIUS
    );
    let full = refreshes.total();
    println!(
        "  contact evaluations: {evaluations}, of them full {full} ({:.1} %)",
        100.0 * full as f64 / evaluations.max(1) as f64
    );
    println!("  full evaluations by cause: {refreshes}");
    println!("  wall-time ratio discrete / rapier: {:.0}", wall / rapier_wall);
    println!("wrote {}", path.display());
    Ok(())
}
