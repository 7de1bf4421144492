//! Runs the stability matrix (stiff materials, fast and slow impacts, restitution 0.1–1,
//! mass ratios, grazing hit, thin plate, resting contact, a refused step, a box on a ramp and a
//! ten-box pyramid with friction) in the rapier pipeline and prints one row per case: outcome, error, sub-steps, wall time.
//!
//! Then the precision table: the sphere–wall impacts in rapier3d-f64 and in rapier3d (f32),
//! near the origin and 1 m and 10 m away.
//!
//! `cargo run --release --example stability_report -- resting` runs only the matrix cases whose
//! description contains the given text (`-- precision`: only the precision table); `-- --f32`
//! runs the matrix with the f32 drop-in (rapier3d) instead of the f64 one.

use discrete_contact_validation::precision::{Ending, Impact};
use discrete_contact_validation::stability::{Case, Verdict};
use rayon::prelude::*;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let f32 = args.iter().any(|a| a == "--f32");
    let filter = args.into_iter().find(|a| a != "--f32").unwrap_or_default();
    println!("drop-in: {}", if f32 { "rapier3d (f32)" } else { "rapier3d-f64" });
    let cases: Vec<Case> =
        Case::matrix().into_iter().filter(|c| c.describe().contains(&filter)).collect();
    println!("{:<58} {:<10} {:>10} {:>9} {:>9}", "case", "outcome", "error", "substeps", "wall s");
    // Rows appear as cases finish (two at a time).
    let outcomes: Vec<_> = cases
        .par_iter()
        .map(|c| {
            let o = c.run_in(f32);
            println!(
                "{:<58} {:<10} {:>10.2e} {:>9} {:>9.2}",
                c.describe(),
                o.verdict,
                o.error,
                o.substeps,
                o.wall_time_s
            );
            o
        })
        .collect();
    let failed = outcomes.iter().filter(|o| matches!(o.verdict, Verdict::Failed(_))).count();
    println!(
        "\n{} cases, {} ok, {} refused with advice, {failed} failed",
        cases.len(),
        outcomes.iter().filter(|o| o.verdict == Verdict::Ok).count(),
        outcomes.iter().filter(|o| o.verdict == Verdict::Refused).count()
    );
    if filter.is_empty() || filter == "precision" {
        precision_table();
    }
    if failed > 0 {
        std::process::exit(1);
    }
}

/// Restitution error |e_meas/e - 1| with the state in f64 and in f32, per impact.
fn precision_table() {
    println!("\nPrecision (e = 0.85, one sub-step = t_H/40): |e_meas/e - 1| with rapier3d-f64 / rapier3d (f32)");
    println!("{:>8} {:>6} {:>9} {:>12} {:>12}", "E (Pa)", "v (m/s)", "offset (m)", "f64", "f32");
    let show = |r: discrete_contact::Result<Ending>| match r {
        Ok(Ending::Rebound(err)) => format!("{err:.2e}"),
        Ok(Ending::Stuck) => "stuck".into(),
        Ok(Ending::Refused) => "refused".into(),
        Err(e) => format!("error: {e}"),
    };
    let rows: Vec<String> = Impact::cases()
        .par_iter()
        .map(|c| {
            format!(
                "{:>8.0e} {:>7} {:>10} {:>12} {:>12}",
                c.youngs,
                c.speed,
                c.offset,
                show(c.run(false)),
                show(c.run(true))
            )
        })
        .collect();
    rows.iter().for_each(|r| println!("{r}"));
}
