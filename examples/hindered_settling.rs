//! Hindered settling of spheres and cubes in a triply periodic box (Marquardt, Hafen & Krause §5): rapier
//! bodies, the HLBM fluid and periodic discrete contacts four-way coupled. Compares the mean
//! settling velocity with Richardson–Zaki and Garside–Al-Dibouni, with and without contacts.
//!
//! ```text
//! cargo run --release --example hindered_settling -- --quick      # minutes: D = 6 Δx, box 8 D, Ar = 1000
//! cargo run --release --example hindered_settling                 # Marquardt, Hafen & Krause: D = 9 Δx, box 15 D (hours)
//! cargo run --release --example hindered_settling -- --peer-case  # seconds per step on the OpenLB case
//! ```
//! Options: `--phi 0.1,0.2,0.3`, `--ar 500,1000,2000`, `--shapes sphere,cube` (cubes at the
//! first Ar only), `--nodes-per-d 9`, `--box-d 15` (box edge in D), `--duration 200` (in D/U,
//! U the Stokes velocity), `--tau 0.55`, `--no-compare` (skip the runs without contacts),
//! `--peer-steps 100`, `--youngs` (Pa; 5 kPa, 50 kPa with `--quick`), `--nc 8` (sub-cell
//! cells across a contact's overlap, in every run including the peer case and the
//! performance table), `--forcing-momentum` (the fluid's force on the particles as the EDM
//! forcing's momentum instead of the link-wise momentum exchange; every run),
//! `--closed-form-spheres` (sphere pairs' overlaps in closed form instead of on the grid),
//! `--exact-polyhedra` (cube pairs' overlaps as the exact clipped polyhedron); the contact's
//! settings in every run: `--smoothing 0.5` (the `d_B` band's width, Δx), the wet contact
//! model — the film model of `wet_rebound` (`--lubrication`, the default: the liquid film
//! below 1.2 Δx with `--film-min-gap-um 16`, a virtual mass `--virtual-mass 0.8` lent to each
//! particle over a fluid step, and no enlargement; `--film-shear` adds the film's sliding and
//! rolling terms) or the seed's enlargement model (`--enlargement-model`: the contact starts
//! at a gap of `--enlargement 0.2` Δx, split over the pair; the peer case's default, as in
//! the reference code) —, `--restitution 0.926`, `--friction-scale 1` (multiplies
//! μ_s = 0.32 and μ_k = 0.16; 0 turns friction off), `--balance lattice|column|fluid` (where
//! the balance force acts: every node, each particle receiving its nodes' share (default);
//! each particle receiving exactly `ρ_f V a`, as from a closed column's pressure gradient; the
//! fluid alone, as in the reference code's example).
//!
//! `--perf-table` times `--perf-steps` (default 600) steps at φ = 10, 20, 30 % with and
//! without contacts in an 8 D and a 15 D box at the quick resolution (D = 6 Δx, E = 50 kPa):
//! MLUPs, seconds per 1000 steps and the time split, in `hindered_settling_perf.csv`
//! (`--perf-box-d 15` and `--perf-phi 0.3` pick cases, `--perf-shape cube` times cubes).
//!
//! Long runs: `--checkpoint-every N` saves each case every N steps (and when it ends) to
//! `target/validation/checkpoints/`; after a stop, the same command with `--resume` goes on
//! from there with bit-identical results (finished cases are not run again). A checkpoint
//! holds the whole lattice: ~150 bytes per node (375 MB at 135³).
//!
//! Writes `target/validation/hindered_settling.csv`
//! (`shape,phi,ar,n_particles,v_mean_over_vs,richardson_zaki,garside_al_dibouni,with_contacts,balance,wall_time_s,mlups`),
//! `hindered_settling_series.csv` (⟨v⟩/v_s over time), `hindered_settling.png`, and for the
//! peer case `hindered_settling_peer.csv`.

#[path = "common/mod.rs"]
mod common;

use std::time::Instant;

use std::path::PathBuf;

use discrete_contact::coupling::ForceMethod;
use discrete_contact_validation::hindered_settling::{
    Balance, HinderedSettling, ParticleShape, SettlingResult, SettlingRun,
};
use discrete_contact_validation::wet_rebound::FILM_MIN_GAP;
use plotters::prelude::*;

/// One finished run.
struct Run {
    case: HinderedSettling,
    result: SettlingResult,
}

/// OpenLB 1.9 on this kind of machine (2 cores, 2 MPI ranks), the peer case, MLUPs:
/// (φ, with contacts, without).
const OPENLB: [(f64, f64, f64); 2] = [(0.15, 2.95, 3.4), (0.30, 1.25, 2.6)];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env(include_str!("hindered_settling.rs"));
    let dir = common::output_dir();
    if args.flag("--peer-case") {
        return peer_case(&args, &dir);
    }
    if args.flag("--perf-table") {
        return perf_table(&args, &dir);
    }
    let quick = args.flag("--quick");
    let phis = args.list("--phi", &[0.1, 0.2, 0.3]);
    let ars = args.list("--ar", if quick { &[1000.0] } else { &[500.0, 1000.0, 2000.0] });
    let shapes: Vec<ParticleShape> = args
        .value("--shapes")
        .unwrap_or("sphere,cube")
        .split(',')
        .map(|s| shape_named("--shapes", s))
        .collect();
    let case_for =
        |shape, phi, ar, contacts| -> Result<HinderedSettling, discrete_contact::Error> {
            let mut c = seed_case(&args, shape, phi, ar, args.film_model()?)?;
            c.nodes_per_diameter = args.number("--nodes-per-d", if quick { 6.0 } else { 9.0 });
            let box_d = args.number("--box-d", if quick { 8.0 } else { 15.0 });
            c.box_nodes = (box_d * c.nodes_per_diameter).round() as usize;
            c.duration = args.number("--duration", if quick { 100.0 } else { 200.0 });
            c.tau = args.number("--tau", c.tau);
            // At D = 6 Δx particles meet at up to ~0.8 m/s, where Hertz puts the seed's 5 kPa
            // indentation past a radius (refused); quick mode stiffens them tenfold.
            let e = args.number("--youngs", if quick { 5e4 } else { c.material.youngs_modulus() });
            c.material = discrete_contact::Material::new(e, c.material.poisson_ratio())?;
            c.contacts = contacts;
            Ok(c)
        };
    let mut jobs = Vec::new();
    for &ar in &ars {
        for &phi in &phis {
            for &shape in &shapes {
                if shape == ParticleShape::Sphere || ar == ars[0] {
                    jobs.push((shape, phi, ar, true));
                }
            }
            if !args.flag("--no-compare") && shapes.contains(&ParticleShape::Sphere) {
                jobs.push((ParticleShape::Sphere, phi, ar, false));
            }
        }
    }
    let c0 = case_for(ParticleShape::Sphere, phis[0], ars[0], true)?;
    println!(
        "D = {} mm = {} Δx, box {} Δx ({:.1} D), ρ_p/ρ_f = {}, τ = {}, e = {}, μ_s/μ_k = {}/{}, E = {} Pa, N_c = {}, enlargement {} Δx, smoothing {} Δx, C_V = {}, film minimum gap {:?} m, film shear {}, run {} D/U, balance {}",
        c0.diameter * 1e3,
        c0.nodes_per_diameter,
        c0.box_nodes,
        c0.box_nodes as f64 / c0.nodes_per_diameter,
        c0.density_ratio,
        c0.tau,
        c0.restitution,
        c0.friction.static_coefficient,
        c0.friction.kinetic_coefficient,
        c0.material.youngs_modulus(),
        c0.n_c,
        c0.enlargement_cells,
        c0.smoothing_cells,
        c0.virtual_mass,
        c0.film_min_gap,
        c0.film_shear,
        c0.duration,
        c0.balance.name()
    );

    let checkpoints = common::Checkpoints::from_args(&args, &dir);
    let mut runs = Vec::new();
    for (shape, phi, ar, contacts) in jobs {
        let case = case_for(shape, phi, ar, contacts)?;
        println!(
            "\n{} φ = {phi}, Ar = {ar}, {} particles, {}: ν = {:.3e} m²/s, Δt = {:.2e} s, {} steps, v_s = {:.4} m/s (Re = {:.1})",
            shape.name(),
            case.particle_count(),
            if contacts { "with contacts" } else { "no contacts" },
            case.viscosity(),
            case.dt(),
            case.steps(),
            case.terminal_velocity(),
            case.reynolds()
        );
        let result = run_with_progress(&case, &checkpoints)?;
        println!(
            "  ⟨v⟩/v_s = {:.3} (Richardson–Zaki {:.3}, Garside–Al-Dibouni {:.3}); {:.1} s, {:.1} MLUPs; time in lattice {:.0} %, mapping {:.0} %, bodies + contacts {:.0} %; at most {} contacts; momentum balance {:+.1} % of the net weight",
            result.v_mean_over_vs,
            case.richardson_zaki(),
            case.garside_al_dibouni(),
            result.wall_time,
            result.mlups(),
            100.0 * result.seconds.lattice / result.wall_time,
            100.0 * result.seconds.mapping / result.wall_time,
            100.0 * result.seconds.bodies / result.wall_time,
            result.max_contacts,
            100.0 * result.momentum_imbalance
        );
        if result.momentum_imbalance.abs() > 0.05 {
            println!(
                "  WARNING: a net force of {:.0} % of the bodies' net weight on the suspension — the coupling loses or makes momentum",
                100.0 * result.momentum_imbalance
            );
        }
        runs.push(Run { case, result });
    }

    let rows: Vec<String> = runs
        .iter()
        .map(|r| {
            format!(
                "{},{},{},{},{:.4},{:.4},{:.4},{},{},{:.2},{:.2}",
                r.case.shape.name(),
                r.case.volume_fraction,
                r.case.archimedes,
                r.result.particles,
                r.result.v_mean_over_vs,
                r.case.richardson_zaki(),
                r.case.garside_al_dibouni(),
                r.case.contacts,
                r.case.balance.name(),
                r.result.wall_time,
                r.result.mlups()
            )
        })
        .collect();
    common::write_csv(
        &dir.join("hindered_settling.csv"),
        "shape,phi,ar,n_particles,v_mean_over_vs,richardson_zaki,garside_al_dibouni,with_contacts,balance,wall_time_s,mlups",
        &rows,
    );
    let series: Vec<String> = runs
        .iter()
        .flat_map(|r| {
            r.result.samples.iter().map(move |(t, v)| {
                format!(
                    "{},{},{},{},{},{:.5},{:.4}",
                    r.case.shape.name(),
                    r.case.volume_fraction,
                    r.case.archimedes,
                    r.case.contacts,
                    r.case.balance.name(),
                    t,
                    v
                )
            })
        })
        .collect();
    common::write_csv(
        &dir.join("hindered_settling_series.csv"),
        "shape,phi,ar,with_contacts,balance,t_s,v_over_vs",
        &series,
    );

    println!(
        "\n{:>7} {:>5} {:>6} {:>5} {:>8} {:>8} {:>8} {:>9} {:>8} {:>7}",
        "shape", "phi", "Ar", "N", "<v>/v_s", "R-Z", "G-AD", "contacts", "wall s", "MLUPs"
    );
    for r in &runs {
        println!(
            "{:>7} {:>5} {:>6} {:>5} {:>8.3} {:>8.3} {:>8.3} {:>9} {:>8.1} {:>7.1}",
            r.case.shape.name(),
            r.case.volume_fraction,
            r.case.archimedes,
            r.result.particles,
            r.result.v_mean_over_vs,
            r.case.richardson_zaki(),
            r.case.garside_al_dibouni(),
            r.case.contacts,
            r.result.wall_time,
            r.result.mlups()
        );
    }
    // Cubes against spheres at equal φ and Ar.
    for c in runs.iter().filter(|r| r.case.shape == ParticleShape::Cube) {
        if let Some(s) = runs.iter().find(|r| {
            r.case.shape == ParticleShape::Sphere
                && r.case.contacts
                && r.case.volume_fraction == c.case.volume_fraction
                && r.case.archimedes == c.case.archimedes
        }) {
            println!(
                "cubes at φ = {}, Ar = {}: {:.1} % slower than spheres (Marquardt, Hafen & Krause: 13 % at low φ to 26 % at high φ)",
                c.case.volume_fraction,
                c.case.archimedes,
                100.0 * (1.0 - c.result.v_mean_over_vs / s.result.v_mean_over_vs)
            );
        }
    }
    plot(&dir.join("hindered_settling.png"), &runs)?;
    println!(
        "\nwrote {}/hindered_settling.csv, hindered_settling_series.csv, hindered_settling.png",
        dir.display()
    );
    Ok(())
}

/// A case's checkpoint file (the file also holds the whole case and refuses another).
fn checkpoint_path(checkpoints: &common::Checkpoints, case: &HinderedSettling) -> PathBuf {
    let contacts = if case.contacts { "contacts" } else { "no_contacts" };
    checkpoints.file(&format!(
        "hindered_settling_{}_phi{}_ar{}_{contacts}",
        case.shape.name(),
        case.volume_fraction,
        case.archimedes
    ))
}

/// Runs a case (from its checkpoint with `--resume`) with a progress line every 5 s.
fn run_with_progress(
    case: &HinderedSettling,
    checkpoints: &common::Checkpoints,
) -> Result<SettlingResult, discrete_contact::Error> {
    let path = checkpoint_path(checkpoints, case);
    let mut run = if checkpoints.resumable(&path) {
        let run = SettlingRun::load(&path, case)?;
        println!("  resumed from {} at step {}", path.display(), run.steps_done());
        run
    } else {
        SettlingRun::new(case)?
    };
    let start = Instant::now();
    let (first, steps) = (run.steps_done(), case.steps());
    let mut last = 0.0;
    let cells = (case.box_nodes as f64).powi(3);
    while !run.is_done() {
        let report = run.step()?;
        let step = run.steps_done();
        if checkpoints.due(step, run.is_done()) {
            let saving = Instant::now();
            run.save(&path)?;
            println!(
                "  step {step:>6}: saved {} ({:.1} s)",
                path.display(),
                saving.elapsed().as_secs_f64()
            );
        }
        let el = start.elapsed().as_secs_f64();
        if el - last > 5.0 {
            last = el;
            let contacts = report.contacts.map_or(0, |c| c.contacts);
            let done = (step - first) as f64;
            println!(
                "  step {step:>6}/{steps}  ⟨v⟩/v_s = {:.3}  {contacts} contacts  {:.1} MLUPs  ETA {:.0} s",
                run.latest(),
                done * cells / el / 1e6,
                el * ((steps - first) as f64 / done - 1.0)
            );
        }
    }
    Ok(run.finish())
}

/// The particle shape an option names; any other name stops the example with the option's name.
fn shape_named(option: &str, name: &str) -> ParticleShape {
    match name.trim() {
        "sphere" => ParticleShape::Sphere,
        "cube" => ParticleShape::Cube,
        other => panic!("{option}: sphere or cube, not {other}"),
    }
}

/// Seed 002's case with the options every run takes (`--nc`), with the film model (`film`)
/// or the enlargement model.
fn seed_case(
    args: &common::Args,
    shape: ParticleShape,
    phi: f64,
    ar: f64,
    film: bool,
) -> Result<HinderedSettling, discrete_contact::Error> {
    let mut c = HinderedSettling::seed_002(shape, phi, ar)?;
    c.n_c = args.number("--nc", c.n_c as f64) as usize;
    if args.flag("--forcing-momentum") {
        c.force_method = ForceMethod::Forcing;
    }
    c.closed_form_spheres = args.flag("--closed-form-spheres");
    c.exact_polyhedra = args.flag("--exact-polyhedra");
    c.smoothing_cells = args.number("--smoothing", c.smoothing_cells);
    // The film model (film, virtual mass, no enlargement) or the enlargement model.
    if film {
        c = c.with_film_model();
        c.film_min_gap = Some(args.number("--film-min-gap-um", FILM_MIN_GAP * 1e6) * 1e-6);
        c.film_shear = args.flag("--film-shear");
    } else if args.flag("--film-shear") {
        return Err(discrete_contact::Error::InvalidArgument {
            name: "--film-shear",
            allowed: "only with the film model (the film it adds to)",
        });
    }
    c.enlargement_cells = args.number("--enlargement", c.enlargement_cells);
    c.virtual_mass = args.number("--virtual-mass", c.virtual_mass);
    c.restitution = args.number("--restitution", c.restitution);
    if let Some(name) = args.value("--balance") {
        c.balance = Balance::named(name).ok_or(discrete_contact::Error::InvalidArgument {
            name: "--balance",
            allowed: "lattice, column or fluid",
        })?;
    }
    let f = args.number("--friction-scale", 1.0);
    c.friction = discrete_contact::Friction::new(
        f * c.friction.static_coefficient,
        f * c.friction.kinetic_coefficient,
        c.friction.transition_speed,
    )?;
    Ok(c)
}

/// The peer case (Marquardt, Hafen & Krause's study as in its authors' public example): 15 D box, D = 9 Δx,
/// φ = 15 % and 30 %, with and without contacts, `--peer-steps` steps each; seconds per step
/// and MLUPs beside OpenLB 1.9's on this kind of machine.
fn peer_case(args: &common::Args, dir: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    let steps = args.number("--peer-steps", 100.0) as u64;
    // The reference code's model unless the film model is asked for.
    let film = args.flag("--lubrication");
    let mut rows = Vec::new();
    println!(
        "{:>5} {:>6} {:>9} {:>8} {:>9} {:>8} {:>10} {:>8}",
        "phi", "N", "contacts", "s/step", "MLUPs", "OpenLB", "speed-up", "<v>/v_s"
    );
    for (phi, openlb_with, openlb_without) in OPENLB {
        for contacts in [true, false] {
            let mut case = seed_case(args, ParticleShape::Sphere, phi, 1000.0, film)?;
            case.contacts = contacts;
            case.duration = steps as f64 * case.dt() * case.stokes_velocity() / case.diameter;
            let r = run_with_progress(&case, &common::Checkpoints::default())?;
            let openlb = if contacts { openlb_with } else { openlb_without };
            println!(
                "{:>5} {:>6} {:>9} {:>8.3} {:>9.2} {:>8.2} {:>9.1}× {:>8.3}   (lattice {:.0} %, mapping {:.0} %, bodies + contacts {:.0} %)",
                phi,
                r.particles,
                contacts,
                r.seconds_per_step(),
                r.mlups(),
                openlb,
                r.mlups() / openlb,
                r.v_mean_over_vs,
                100.0 * r.seconds.lattice / r.wall_time,
                100.0 * r.seconds.mapping / r.wall_time,
                100.0 * r.seconds.bodies / r.wall_time
            );
            rows.push(format!(
                "{},{},{},{},{},{:.4},{:.3},{:.3},{:.4},{:.4},{:.4}",
                phi,
                r.particles,
                contacts,
                r.cells,
                r.steps,
                r.seconds_per_step(),
                r.mlups(),
                openlb,
                r.seconds.lattice / r.steps as f64,
                r.seconds.mapping / r.steps as f64,
                r.seconds.bodies / r.steps as f64
            ));
        }
    }
    common::write_csv(
        &dir.join("hindered_settling_peer.csv"),
        "phi,n_particles,with_contacts,cells,steps,s_per_step,mlups,openlb_mlups,lattice_s_per_step,mapping_s_per_step,bodies_s_per_step",
        &rows,
    );
    println!("wrote {}/hindered_settling_peer.csv", dir.display());
    Ok(())
}

/// MLUPs and seconds per 1000 steps with and without contacts at φ = 10, 20, 30 % for two
/// box sizes (quick resolution), from rest: the contacts form during the run.
fn perf_table(
    args: &common::Args,
    dir: &std::path::Path,
) -> Result<(), Box<dyn std::error::Error>> {
    let steps = args.number("--perf-steps", 600.0) as u64;
    let film = args.film_model()?;
    let shape = shape_named("--perf-shape", args.value("--perf-shape").unwrap_or("sphere"));
    let mut rows = Vec::new();
    println!(
        "{:>5} {:>6} {:>5} {:>9} {:>8} {:>10} {:>9} {:>9} {:>10}",
        "box_D", "nodes", "phi", "contacts", "N", "s/1000", "MLUPs", "contacts%", "max_contacts"
    );
    for box_d in args.list("--perf-box-d", &[8.0, 15.0]) {
        for &phi in &args.list("--perf-phi", &[0.1, 0.2, 0.3]) {
            for contacts in [true, false] {
                let mut case = seed_case(args, shape, phi, 1000.0, film)?;
                case.nodes_per_diameter = 6.0;
                case.box_nodes = (box_d * case.nodes_per_diameter) as usize;
                case.material =
                    discrete_contact::Material::new(5e4, case.material.poisson_ratio())?;
                case.contacts = contacts;
                case.duration = steps as f64 * case.dt() * case.stokes_velocity() / case.diameter;
                let r = run_with_progress(&case, &common::Checkpoints::default())?;
                let share = 100.0 * r.seconds.bodies / r.wall_time;
                println!(
                    "{:>5} {:>6} {:>5} {:>9} {:>8} {:>10.1} {:>9.2} {:>9.0} {:>10}",
                    box_d,
                    case.box_nodes,
                    phi,
                    contacts,
                    r.particles,
                    1000.0 * r.seconds_per_step(),
                    r.mlups(),
                    share,
                    r.max_contacts
                );
                rows.push(format!(
                    "{},{},{},{},{},{},{:.3},{:.3},{:.1},{}",
                    box_d,
                    case.box_nodes,
                    phi,
                    contacts,
                    r.particles,
                    r.steps,
                    1000.0 * r.seconds_per_step(),
                    r.mlups(),
                    share,
                    r.max_contacts
                ));
            }
        }
    }
    common::write_csv(
        &dir.join("hindered_settling_perf.csv"),
        "box_d,box_nodes,phi,with_contacts,n_particles,steps,s_per_1000_steps,mlups,bodies_percent,max_contacts",
        &rows,
    );
    println!("wrote {}/hindered_settling_perf.csv", dir.display());
    Ok(())
}

/// ⟨v⟩/v_s against φ with both correlations (Ar of the first run), with and without contacts.
fn plot(path: &std::path::Path, runs: &[Run]) -> Result<(), Box<dyn std::error::Error>> {
    common::png(path, (1000, 700), |root| {
        let mut ch = ChartBuilder::on(root)
            .caption("Hindered settling in a triply periodic box", ("sans-serif", 24))
            .margin(14)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..0.35, 0.0..1.0)?;
        ch.configure_mesh()
            .x_desc("φ")
            .y_desc("⟨v⟩ / v_s")
            .label_style(("sans-serif", 15))
            .draw()?;
        let mut ars: Vec<f64> = runs.iter().map(|r| r.case.archimedes).collect();
        ars.sort_by(f64::total_cmp);
        ars.dedup();
        let colours = [RED, BLUE, GREEN];
        for (k, &ar) in ars.iter().enumerate() {
            let colour = colours[k % colours.len()];
            let Some(any) = runs.iter().find(|r| r.case.archimedes == ar) else { continue };
            let curve = |f: &dyn Fn(&HinderedSettling) -> f64| -> Vec<(f64, f64)> {
                (0..=35)
                    .map(|i| {
                        let mut c = any.case.clone();
                        c.volume_fraction = i as f64 / 100.0;
                        (c.volume_fraction, f(&c))
                    })
                    .collect()
            };
            let rz = colour.mix(0.6).stroke_width(1);
            ch.draw_series(LineSeries::new(curve(&|c| c.richardson_zaki()), rz))?
                .label(format!("Richardson–Zaki, Ar = {ar}"))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], rz));
            ch.draw_series(DashedLineSeries::new(curve(&|c| c.garside_al_dibouni()), 6, 4, rz))?
                .label(format!("Garside–Al-Dibouni, Ar = {ar}"))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], rz));
            for (shape, contacts, label) in [
                (ParticleShape::Sphere, true, "spheres, contacts"),
                (ParticleShape::Sphere, false, "spheres, no contacts"),
                (ParticleShape::Cube, true, "cubes, contacts"),
            ] {
                let pts: Vec<(f64, f64)> = runs
                    .iter()
                    .filter(|r| {
                        r.case.archimedes == ar
                            && r.case.shape == shape
                            && r.case.contacts == contacts
                    })
                    .map(|r| (r.case.volume_fraction, r.result.v_mean_over_vs))
                    .collect();
                if pts.is_empty() {
                    continue;
                }
                let style = colour.filled();
                let label = format!("{label}, Ar = {ar}");
                match (shape, contacts) {
                    (ParticleShape::Sphere, true) => {
                        ch.draw_series(pts.iter().map(|&p| Circle::new(p, 6, style)))?
                            .label(label)
                            .legend(move |(x, y)| Circle::new((x + 9, y), 6, style));
                    }
                    (ParticleShape::Sphere, false) => {
                        let s = colour.stroke_width(2);
                        ch.draw_series(pts.iter().map(|&p| Circle::new(p, 6, s)))?
                            .label(label)
                            .legend(move |(x, y)| Circle::new((x + 9, y), 6, s));
                    }
                    (ParticleShape::Cube, _) => {
                        ch.draw_series(pts.iter().map(|&p| {
                            Rectangle::new(
                                [(p.0 - 0.004, p.1 - 0.012), (p.0 + 0.004, p.1 + 0.012)],
                                style,
                            )
                        }))?
                        .label(label)
                        .legend(move |(x, y)| {
                            Rectangle::new([(x + 4, y - 5), (x + 14, y + 5)], style)
                        });
                    }
                }
            }
        }
        common::legend(&mut ch, SeriesLabelPosition::UpperRight, 13)?;
        Ok(())
    })
}
