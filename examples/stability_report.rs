//! Runs the stability matrix (stiff materials, fast and slow impacts, restitution 0.1–1,
//! mass ratios, grazing hit, thin plate, resting contact, a refused step) in the rapier
//! pipeline and prints one row per case: outcome, error, sub-steps, wall time.

use discrete_contact::validation::stability::Case;
use rayon::prelude::*;

fn main() {
    let cases = Case::matrix();
    println!("{:<58} {:<10} {:>10} {:>9} {:>9}", "case", "outcome", "error", "substeps", "wall s");
    // Rows appear as cases finish (two at a time).
    let outcomes: Vec<_> = cases
        .par_iter()
        .map(|c| {
            let o = c.run();
            println!("{:<58} {:<10} {:>10.2e} {:>9} {:>9.2}", c.describe(), o.verdict, o.error, o.substeps, o.wall_time_s);
            o
        })
        .collect();
    let failed = outcomes.iter().filter(|o| o.verdict.starts_with("FAILED")).count();
    println!("\n{} cases, {} ok, {} refused with advice, {failed} failed", cases.len(), outcomes.iter().filter(|o| o.verdict == "ok").count(), outcomes.iter().filter(|o| o.verdict == "refused").count());
    if failed > 0 {
        std::process::exit(1);
    }
}
