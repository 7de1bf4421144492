//! Stiff contacts at rapier's step: scenes built as rapier's own examples build them, each run
//! with rapier's own contacts and with the discrete contact, at several Young's moduli.
//!
//! `cargo run --release --example stacks`

use clap::Parser;
use discrete_contact::rapier::Integration;
use discrete_contact_validation::stacks::{self, Outcome, Scene};

/// The scene suite: pyramids of 10 and 55 boxes, a tower of planks, a wall of bricks, spheres
/// poured into a box and the drop-in's bin, each with rapier's own contacts (rapier's
/// `length_unit` at the bodies' size) and with the discrete contact.
#[derive(Parser)]
struct Options {
    /// Young's moduli to run (Pa), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1e6, 1e7, 1e9, 2e11])]
    youngs: Vec<f64>,
    /// Simulated time per run (s).
    #[arg(long, default_value_t = 2.0)]
    seconds: f64,
    /// Only the scenes whose names contain this.
    #[arg(long)]
    only: Option<String>,
    /// Geometry reuse fraction of the discrete contact (0: every evaluation in full).
    #[arg(long, default_value_t = discrete_contact::contact::GEOMETRY_REUSE)]
    reuse: f64,
    /// A pyramid with this many boxes in its lowest row instead of the suite.
    #[arg(long)]
    base: Option<usize>,
    /// Print every step's statistics of the discrete runs.
    #[arg(long)]
    trace: bool,
    /// Most sub-steps per step before a step is refused.
    #[arg(long, default_value_t = 10_000)]
    max_substeps: usize,
    /// Every contact explicit, in sub-steps of its own stiffness (`Integration::Explicit`),
    /// instead of the default implicit step of resting contacts.
    #[arg(long)]
    explicit: bool,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let options = Options::parse();
    let scenes = [
        Scene::Pyramid { base: 4 },
        Scene::Pyramid { base: 10 },
        Scene::PlankTower { layers: 8 },
        Scene::BrickWall { rows: 6, per_row: 5 },
        Scene::Pour { spheres: 1000 },
        Scene::Bin { bodies: 180 },
    ];
    println!(
        "{:<28} {:>8} {:>10} {:>12} {:>11} {:>9} {:>9} {:>8}  outcome",
        "scene", "E (Pa)", "rapier (s)", "discrete (s)", "ratio", "sub/step", "KE (J)", "d (µm)"
    );
    let scenes = match options.base {
        Some(base) => vec![Scene::Pyramid { base }],
        None => scenes.to_vec(),
    };
    for scene in scenes {
        if options.only.as_ref().is_some_and(|o| !scene.name().contains(o.as_str())) {
            continue;
        }
        let rapier = stacks::run_rapier(scene, options.seconds);
        println!(
            "{:<28} {:>8} {:>10.3} {:>12} {:>11} {:>9} {:>9.2e} {:>8.1}  rapier: {:?}",
            scene.name(),
            "-",
            rapier.wall,
            "-",
            "-",
            1,
            rapier.kinetic_energy,
            rapier.max_indentation * 1e6,
            rapier.outcome
        );
        for &e in &options.youngs {
            let integration =
                if options.explicit { Integration::Explicit } else { Integration::Implicit };
            let contacts = stacks::discrete_contacts(options.max_substeps)?
                .with_geometry_reuse(options.reuse)?
                .with_integration(integration);
            let run = stacks::run_discrete(scene, options.seconds, e, contacts, options.trace)?;
            let outcome = match &run.outcome {
                Outcome::Stands => "stands".to_string(),
                Outcome::Refused(m) => format!("refused: {m}"),
                Outcome::Fails(m) => format!("FAILS: {m}"),
            };
            println!(
                "{:<28} {:>8.0e} {:>10.3} {:>12.3} {:>10.1}× {:>9.1} {:>9.2e} {:>8.1}  {outcome} ({} steps)",
                scene.name(),
                e,
                rapier.wall,
                run.wall,
                run.wall / rapier.wall * rapier.steps as f64 / run.steps.max(1) as f64,
                run.substeps_per_step,
                run.kinetic_energy,
                run.max_indentation * 1e6,
                run.steps
            );
        }
    }
    Ok(())
}
