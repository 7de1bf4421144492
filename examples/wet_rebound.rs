//! A steel sphere falling through glycerol–water onto the floor of a closed box and bouncing
//! (Marquardt et al. §5, the experiment of Li 2010): rapier body, HLBM fluid and discrete contact
//! four-way coupled. Runs each release gap at two resolutions with the contact, and at the
//! finer one without it (no rebound — the paper's point).
//!
//! ```text
//! cargo run --release --example wet_rebound              # Δx = 0.6 and 0.3 mm (the paper's; hours)
//! cargo run --release --example wet_rebound -- --quick   # Δx = 1.0 and 0.75 mm (a few minutes)
//! ```
//! Options (defaults: Li 2010): `--dx 0.6,0.3` (mm), `--h0 5.5,19.6,35.7` (mm), `--radius 4.75`
//! (mm), `--rho-p 7780`, `--rho-f 1230` (kg/m³), `--mu 0.0502` (Pa s), `--box 42,42,50` (mm),
//! `--e-dry 0.97`, `--youngs-scale 1` (both Young's moduli times this: a softer, longer
//! contact), `--nc 16`, `--t-end 0.25` (s), `--dt-us` (fluid step; default keeps the
//! paper's τ = 7.3), `--vtk-every-ms` (ParaView snapshots), `--no-compare` (skip the runs
//! without contact), `--checkpoint-every N` (save each run every N steps to
//! `target/validation/checkpoints/`) and `--resume` (go on from those files after a stop, with
//! bit-identical results), `--forcing-momentum` (the fluid's force on the sphere as the EDM
//! forcing's momentum instead of Wen et al.'s link-wise momentum exchange; see
//! `hlbm::ForceMethod`), `--no-facet-bulge` (the contact's overlap without the sphere's facet
//! layer: second order, `OverlapSettings::with_facet_bulge(false)`).
//!
//! The wet contact is the film model (`--lubrication`, the default): the liquid film's force
//! below the gap the lattice resolves (see `discrete_contact::lubrication`), a virtual mass
//! lent to the sphere over each fluid step (see
//! `discrete_contact::coupling::FluidSettings::with_virtual_mass`) and no enlargement, with
//! `--film-cutoff 1.2` (in Δx), `--film-min-gap-um 16` (roughness, µm) and `--virtual-mass 0.8`
//! (its coefficient `C_V`). `--enlargement-model` runs Marquardt et al.'s model instead: the
//! contact starts at a gap of `--enlargement 0.143` Δx, which stands for the film, and no
//! virtual mass. (`--virtual-mass` and `--enlargement` override either model's.) The film model
//! is the default because it follows e/e_dry(St) within 0.1 from St ≈ 20 to ≈ 950 at 10 and 16
//! nodes across the diameter, where the enlargement rebounds too high at low Stokes numbers
//! and stays near 0.8 above St ≈ 200 (`docs/wet.md`).
//! `--nodes-per-d 10,16` sets the resolutions as lattice nodes across the diameter instead of
//! `--dx`.
//!
//! `--st-sweep` runs e/e_dry against the Stokes number instead: nine experiments from St ≈ 3 to
//! ≈ 900 in the Li box (the sphere's density, the liquid's viscosity and the release gap
//! varied; [`SWEEP`]), each at every `--nodes-per-d` resolution (default 10 and 16 nodes
//! across the diameter) with the enlargement model and again with the film model, and writes
//! `wet_rebound_st.csv` (the summary's columns) and `wet_rebound_st.png` beside Legendre et
//! al.'s correlation; `--sweep-series film` or `enlargement` runs one of the two series.
//!
//! Writes `target/validation/wet_rebound.csv` (`h0_mm,dx_mm,rho_p_kg_m3,mu_pa_s,film,t_s,gap_mm,vz_m_s`,
//! with contact), `wet_rebound_no_contact.csv` (same columns), `wet_rebound_summary.csv` (one
//! row per run: impact, speeds, St, e/e_dry, Legendre's value, wall time) and
//! `wet_rebound.png`.

#[path = "common/mod.rs"]
mod common;

use std::time::Instant;

use discrete_contact::coupling::{ForceMethod, FILM_CUTOFF};
use discrete_contact::material::Material;
use discrete_contact::math::Vector;
use discrete_contact_validation::wet_rebound::{ReboundRun, Trajectory, WetRebound};
use plotters::prelude::*;

/// One run's settings (lengths in mm) beyond the Li (2010) case.
#[derive(Clone, Copy, Debug)]
struct Job {
    h0: f64,
    dx: f64,
    rho_p: f64,
    mu: f64,
    contact: bool,
    film: bool,
}

/// The Stokes-number sweep: (sphere density kg/m³, viscosity Pa s, release gap mm) in the Li
/// box with Li's sphere radius and liquid density — glass, alumina, steel (Li's three gaps) and
/// tungsten carbide, in liquids from 0.1 down to 0.0125 Pa s. The time step follows the
/// spacing as in Li's case, so τ scales with the viscosity (≈ 2–15).
const SWEEP: [(f64, f64, f64); 9] = [
    (2500.0, 0.1, 19.6),
    (2500.0, 0.0502, 19.6),
    (4000.0, 0.0502, 19.6),
    (7780.0, 0.0502, 5.5),
    (7780.0, 0.0502, 19.6),
    (7780.0, 0.0502, 35.7),
    (15600.0, 0.0502, 35.7),
    (15600.0, 0.025, 35.7),
    (15600.0, 0.0125, 35.7),
];

/// One finished run.
struct Run {
    job: Job,
    case: WetRebound,
    traj: Trajectory,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env(include_str!("wet_rebound.rs"));
    let quick = args.flag("--quick");
    let sweep = args.flag("--st-sweep");
    let radius_mm = args.number("--radius", 4.75);
    let dxs = if sweep || args.value("--nodes-per-d").is_some() {
        let nodes = args.list("--nodes-per-d", &[10.0, 16.0]);
        nodes.iter().map(|n| 2.0 * radius_mm / n).collect()
    } else {
        args.list("--dx", if quick { &[1.0, 0.75] } else { &[0.6, 0.3] })
    };
    let h0s = args.list("--h0", &[5.5, 19.6, 35.7]);
    let bx = args.list("--box", &[42.0, 42.0, 50.0]);
    let vtk_every = args
        .value("--vtk-every-ms")
        .map(|v| v.parse::<f64>().expect("--vtk-every-ms: a number") * 1e-3);
    let li = WetRebound::li_2010(h0s[0] * 1e-3, dxs[0] * 1e-3);
    let case_for = |j: &Job| -> WetRebound {
        let mut c = WetRebound::li_2010(j.h0 * 1e-3, j.dx * 1e-3);
        c.radius = radius_mm * 1e-3;
        c.particle_density = j.rho_p;
        c.fluid_density = args.number("--rho-f", c.fluid_density);
        c.viscosity = j.mu;
        c.box_size = Vector::new(bx[0], bx[1], bx[2]) * 1e-3;
        c.dry_restitution = args.number("--e-dry", c.dry_restitution);
        c.n_c = args.number("--nc", c.n_c as f64) as usize;
        c.facet_bulge = !args.flag("--no-facet-bulge");
        let soften = args.number("--youngs-scale", 1.0);
        for m in [&mut c.sphere_material, &mut c.wall_material] {
            *m = Material::new(m.youngs_modulus() * soften, m.poisson_ratio())
                .expect("--youngs-scale: a positive factor");
        }
        c.end_time = args.number("--t-end", c.end_time);
        if let Some(dt) = args.value("--dt-us") {
            c.dt = dt.parse::<f64>().expect("--dt-us: a number") * 1e-6;
        }
        c.contact = j.contact;
        // The film model (film, virtual mass, no enlargement) or the enlargement model.
        if j.film {
            c = c.with_film_model();
            c.film_cutoff = Some(args.number("--film-cutoff", FILM_CUTOFF) * c.dx);
            c.film_min_gap = args.number("--film-min-gap-um", c.film_min_gap * 1e6) * 1e-6;
        }
        if let Some(e) = args.value("--enlargement") {
            c.enlargement = e.parse::<f64>().expect("--enlargement: a number") * c.dx;
        }
        c.virtual_mass = args.number("--virtual-mass", c.virtual_mass);
        if args.flag("--forcing-momentum") {
            c.force_method = ForceMethod::Forcing;
        }
        c
    };

    let finest = dxs.iter().cloned().fold(f64::INFINITY, f64::min);
    let mut jobs: Vec<Job> = Vec::new();
    if sweep {
        let series: &[bool] = match args.value("--sweep-series") {
            None => &[false, true],
            Some("film") => &[true],
            Some("enlargement") => &[false],
            Some(_) => {
                return Err(discrete_contact::Error::InvalidArgument {
                    name: "--sweep-series",
                    allowed: "film or enlargement",
                }
                .into())
            }
        };
        for &dx in &dxs {
            for &film in series {
                for &(rho_p, mu, h0) in &SWEEP {
                    jobs.push(Job { h0, dx, rho_p, mu, contact: true, film });
                }
            }
        }
    } else {
        let rho_p = args.number("--rho-p", li.particle_density);
        let mu = args.number("--mu", li.viscosity);
        let film = args.film_model()?;
        for &dx in &dxs {
            for &h0 in &h0s {
                jobs.push(Job { h0, dx, rho_p, mu, contact: true, film });
            }
        }
        if !args.flag("--no-compare") {
            for &h0 in &h0s {
                jobs.push(Job { h0, dx: finest, rho_p, mu, contact: false, film: false });
            }
        }
    }
    let c0 = case_for(&jobs[0]);
    println!(
        "sphere R = {} mm in ρ_f = {} kg/m³; box {:?} mm; e_dry = {}, N_c = {}",
        c0.radius * 1e3,
        c0.fluid_density,
        bx,
        c0.dry_restitution,
        c0.n_c
    );

    let dir = common::output_dir();
    let checkpoints = common::Checkpoints::from_args(&args, &dir);
    let mut runs = Vec::new();
    for job in jobs {
        let Job { h0, dx, rho_p, mu, contact, film } = job;
        let case = case_for(&job);
        let settings = format!(
            "ρ_p = {rho_p} kg/m³, μ = {mu} Pa s, h0 = {h0} mm, Δx = {dx:.4} mm ({:.1} nodes across), Δt = {:.2} µs, {}, enlargement {:.3} Δx, C_V = {}",
            2.0 * case.radius / case.dx,
            case.dt * 1e6,
            match (contact, film) {
                (false, _) => "no contact",
                (true, false) => "with contact",
                (true, true) => "with contact and film",
            },
            case.enlargement / case.dx,
            case.virtual_mass
        );
        println!("\n{settings}");
        let start = Instant::now();
        let mut last_print = 0.0;
        let mut next_vtk = 0.0;
        let steps_max = (case.end_time / case.dt).ceil();
        let path = checkpoints.file(&format!(
            "wet_rebound_h{h0}_dx{dx}_rho{rho_p}_mu{mu}_{}{}",
            if contact { "contact" } else { "no_contact" },
            if film { "_film" } else { "" }
        ));
        let mut run = if checkpoints.resumable(&path) {
            let run = ReboundRun::load(&path, &case)?;
            println!("  resumed from {} at step {}", path.display(), run.trajectory().steps);
            run
        } else {
            ReboundRun::new(&case)?
        };
        let first = run.trajectory().steps;
        while !run.is_done() {
            run.step()?;
            if checkpoints.due(run.trajectory().steps, run.is_done()) {
                run.save(&path)?;
            }
            let (tr, fluid) = (run.trajectory(), run.fluid());
            let el = start.elapsed().as_secs_f64();
            let t = tr.steps as f64 * case.dt;
            if el - last_print > 5.0 {
                last_print = el;
                let done = (tr.steps - first) as f64;
                let mlups = done * tr.cells as f64 / el / 1e6;
                let eta = el * ((steps_max - first as f64) / done - 1.0);
                let gap = tr.samples.last().map_or(0.0, |s| s.1);
                println!(
                    "  step {:>6}  t = {:.4} s  gap = {:>7.3} mm  {:>6.1} MLUPs  ETA ≤ {:.0} s",
                    tr.steps,
                    t,
                    gap * 1e3,
                    mlups,
                    eta
                );
            }
            if let Some(every) = vtk_every {
                if t >= next_vtk {
                    next_vtk += every;
                    let path = dir.join(format!("wet_rebound_h{h0}_dx{dx}_{:06}.vtk", tr.steps));
                    if let Err(e) = fluid.write_vtk(&path) {
                        eprintln!("VTK: {e}");
                    }
                }
            }
        }
        let traj = run.finish();
        report(&case, &traj);
        runs.push(Run { job, case, traj });
    }

    // Gap over time, one row per 0.1 ms at least (every step is finer than 0.5 ms).
    for (contact, name) in [(true, "wet_rebound.csv"), (false, "wet_rebound_no_contact.csv")] {
        let mut rows = Vec::new();
        for r in runs.iter().filter(|r| r.job.contact == contact) {
            let Job { h0, dx, rho_p, mu, film, .. } = r.job;
            let mut last = f64::NEG_INFINITY;
            for &(t, gap, vz) in &r.traj.samples {
                if t - last >= 1e-4 - 1e-12 {
                    rows.push(format!(
                        "{h0},{dx},{rho_p},{mu},{film},{t:.6},{:.5},{vz:.5}",
                        gap * 1e3
                    ));
                    last = t;
                }
            }
        }
        if !rows.is_empty() {
            common::write_csv(
                &dir.join(name),
                "h0_mm,dx_mm,rho_p_kg_m3,mu_pa_s,film,t_s,gap_mm,vz_m_s",
                &rows,
            );
        }
    }

    // Restitution against the Stokes number, error against cost.
    println!("\nEffective restitution (speeds at a gap of 5 % of D) against Legendre et al. (2006), e/e_dry = exp(-35/St):");
    println!(
        "{:>7} {:>7} {:>6} {:>6} {:>9} {:>9} {:>9} {:>9} {:>7} {:>8} {:>8} {:>8} {:>8} {:>9}",
        "rho_p",
        "mu",
        "h0",
        "dx",
        "t_imp",
        "U_in",
        "U_out",
        "h_reb",
        "St",
        "e/e_dry",
        "Legendre",
        "error",
        "wall s",
        "contact"
    );
    let mut summary = Vec::new();
    for r in &runs {
        let level = r.case.measuring_gap();
        let (u_in, u_out) = r.traj.speeds_at(level).unwrap_or((f64::NAN, f64::NAN));
        let st = r.case.stokes_number(u_in);
        let ratio = u_out / u_in / r.case.dry_restitution;
        let legendre = if st > 10.0 { r.case.legendre_ratio(u_in) } else { 0.0 };
        let t_imp = r.traj.impact.map_or(f64::NAN, |i| i.0);
        let h_reb = r.traj.rebound_height.unwrap_or(0.0);
        println!(
            "{:>7} {:>7} {:>6} {:>6.3} {:>9.4} {:>9.4} {:>9.4} {:>6.3} mm {:>7.1} {:>8.3} {:>8.3} {:>+8.3} {:>8.1} {:>9}",
            r.job.rho_p,
            r.job.mu,
            r.job.h0,
            r.job.dx,
            t_imp,
            u_in,
            u_out,
            h_reb * 1e3,
            st,
            ratio,
            legendre,
            ratio - legendre,
            r.traj.wall_time,
            match (r.job.contact, r.job.film) {
                (false, _) => "no",
                (true, false) => "yes",
                (true, true) => "film",
            }
        );
        summary.push(format!(
            "{},{},{},{},{},{},{:.6},{:.5},{:.5},{:.5},{:.2},{:.4},{:.4},{:.2},{},{}",
            r.job.h0,
            r.job.dx,
            r.job.rho_p,
            r.job.mu,
            r.job.contact,
            r.job.film,
            t_imp,
            u_in,
            u_out,
            h_reb * 1e3,
            st,
            ratio,
            legendre,
            r.traj.wall_time,
            r.traj.steps,
            r.traj.cells
        ));
    }
    common::write_csv(
        &dir.join(if sweep { "wet_rebound_st.csv" } else { "wet_rebound_summary.csv" }),
        "h0_mm,dx_mm,rho_p_kg_m3,mu_pa_s,contact,film,t_impact_s,u_in_m_s,u_out_m_s,rebound_height_mm,stokes,e_over_e_dry,legendre,wall_time_s,steps,cells",
        &summary,
    );
    if sweep {
        plot_st(&dir.join("wet_rebound_st.png"), &runs)?;
        println!(
            "\nwrote {}/wet_rebound.csv, wet_rebound_st.csv, wet_rebound_st.png",
            dir.display()
        );
    } else {
        plot(&dir.join("wet_rebound.png"), &runs, finest)?;
        println!("\nwrote {}/wet_rebound.csv, wet_rebound_no_contact.csv, wet_rebound_summary.csv, wet_rebound.png", dir.display());
    }
    Ok(())
}

/// One run's key numbers.
fn report(case: &WetRebound, t: &Trajectory) {
    let level = case.measuring_gap();
    match (t.impact, t.speeds_at(level)) {
        (Some((ti, u_contact)), Some((u_in, u_out))) => println!(
            "  impact at {ti:.4} s, {u_contact:.3} m/s at the contact ({u_in:.3} m/s at a gap of {:.2} mm), rebound {u_out:.3} m/s, height {:.3} mm, St = {:.1}, {} steps in {:.1} s",
            level * 1e3,
            t.rebound_height.unwrap_or(0.0) * 1e3,
            case.stokes_number(u_in),
            t.steps,
            t.wall_time
        ),
        _ => println!("  no impact; smallest gap {:.3} mm; {} steps in {:.1} s", t.min_gap * 1e3, t.steps, t.wall_time),
    }
}

/// Gap over time like Marquardt et al.'s Fig. 7: finest resolution solid, coarser thin, no contact
/// dashed.
fn plot(
    path: &std::path::Path,
    runs: &[Run],
    finest: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    common::png(path, (1100, 700), |root| {
        let t_max =
            runs.iter().flat_map(|r| r.traj.samples.last()).map(|s| s.0).fold(0.0, f64::max);
        let h_max = runs.iter().map(|r| r.job.h0).fold(0.0, f64::max) * 1.05;
        let mut ch = ChartBuilder::on(root)
            .caption("Sphere rebound in glycerol–water (Li 2010 setup)", ("sans-serif", 24))
            .margin(14)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_max, -1.0..h_max)?;
        ch.configure_mesh()
            .x_desc("t (s)")
            .y_desc("gap h (mm)")
            .label_style(("sans-serif", 15))
            .draw()?;
        let colours = [RED, BLUE, GREEN, MAGENTA, CYAN, BLACK];
        let mut h0s: Vec<f64> = runs.iter().map(|r| r.job.h0).collect();
        h0s.dedup();
        for r in runs {
            let k = h0s.iter().position(|&h| h == r.job.h0).unwrap_or(0);
            let colour = colours[k % colours.len()];
            let pts: Vec<(f64, f64)> = r.traj.samples.iter().map(|s| (s.0, s.1 * 1e3)).collect();
            let label = format!(
                "h0 = {} mm, Δx = {} mm{}",
                r.job.h0,
                r.job.dx,
                if r.job.contact { "" } else { ", no contact" }
            );
            let style = if r.job.contact && r.job.dx == finest {
                colour.stroke_width(2)
            } else {
                colour.mix(0.5).stroke_width(1)
            };
            if r.job.contact {
                ch.draw_series(LineSeries::new(pts, style))?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], style));
            } else {
                ch.draw_series(DashedLineSeries::new(pts, 6, 4, style))?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], style));
            }
        }
        common::legend(&mut ch, SeriesLabelPosition::UpperRight, 13)?;
        Ok(())
    })
}

/// e/e_dry against the Stokes number, one series per resolution (the finest filled) and per film
/// setting, beside Legendre et al.'s correlation (zero below St = 10: no rebound).
fn plot_st(path: &std::path::Path, runs: &[Run]) -> Result<(), Box<dyn std::error::Error>> {
    common::png(path, (1000, 650), |root| {
        let mut ch = ChartBuilder::on(root)
            .caption("Wet restitution against the Stokes number", ("sans-serif", 24))
            .margin(14)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d((1.0..2000.0).log_scale(), 0.0..1.1)?;
        ch.configure_mesh()
            .x_desc("St = (ρ_p + ρ_f/2) U D / 9μ")
            .y_desc("e / e_dry")
            .label_style(("sans-serif", 15))
            .draw()?;
        let curve = (0..=330).map(|k| {
            let st = 10f64.powf(k as f64 / 100.0);
            (st, if st > 10.0 { (-35.0 / st).exp() } else { 0.0 })
        });
        ch.draw_series(LineSeries::new(curve, BLACK.stroke_width(2)))?
            .label("Legendre et al. (2006), exp(−35/St)")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], BLACK.stroke_width(2)));
        let mut dxs: Vec<f64> = runs.iter().map(|r| r.job.dx).collect();
        dxs.sort_by(f64::total_cmp);
        dxs.dedup();
        for (k, &dx) in dxs.iter().enumerate() {
            for film in [false, true] {
                let colour = if film { BLUE } else { RED };
                // Finest (smallest Δx, first after sorting) filled.
                let filled = k == 0;
                let mut nodes = 0.0;
                let pts: Vec<(f64, f64)> = runs
                    .iter()
                    .filter(|r| r.job.dx == dx && r.job.film == film && r.job.contact)
                    .filter_map(|r| {
                        nodes = 2.0 * r.case.radius / r.case.dx;
                        let (u_in, u_out) = r.traj.speeds_at(r.case.measuring_gap())?;
                        let e = u_out / u_in / r.case.dry_restitution;
                        Some((r.case.stokes_number(u_in), e))
                            .filter(|p| p.0.is_finite() && p.1.is_finite())
                    })
                    .collect();
                if pts.is_empty() {
                    continue;
                }
                let style = if filled { colour.filled() } else { colour.stroke_width(2) };
                let label = format!(
                    "D = {nodes:.0} Δx, {}",
                    if film { "liquid film and virtual mass" } else { "enlargement Δx/7" }
                );
                ch.draw_series(pts.into_iter().map(move |p| Circle::new(p, 5, style)))?
                    .label(label)
                    .legend(move |(x, y)| Circle::new((x + 9, y), 5, style));
            }
        }
        common::legend(&mut ch, SeriesLabelPosition::UpperLeft, 14)?;
        Ok(())
    })
}
