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
//! `--e-dry 0.97`, `--nc 16`, `--t-end 0.25` (s), `--dt-us` (fluid step; default keeps the
//! paper's τ = 7.3), `--vtk-every-ms` (ParaView snapshots), `--no-compare` (skip the runs
//! without contact), `--checkpoint-every N` (save each run every N steps to
//! `target/validation/checkpoints/`) and `--resume` (go on from those files after a stop, with
//! bit-identical results), `--forcing-momentum` (the fluid's force on the sphere as the EDM
//! forcing's momentum instead of Wen et al.'s link-wise momentum exchange; see
//! `hlbm::ForceMethod`), `--enlargement 0.143` (contact enlargement, in Δx), `--lubrication`
//! (the liquid film's force below the gap the lattice resolves, see
//! `discrete_contact::lubrication`) with `--film-cutoff 1.2` (in Δx) and
//! `--film-min-gap-um 16` (roughness, µm).
//!
//! Writes `target/validation/wet_rebound.csv` (`h0_mm,dx_mm,t_s,gap_mm`, with contact),
//! `wet_rebound_no_contact.csv` (same columns), `wet_rebound_summary.csv` and
//! `wet_rebound.png`.

#[path = "common/mod.rs"]
mod common;

use std::time::Instant;

use discrete_contact::coupling::{ForceMethod, FILM_CUTOFF};
use discrete_contact::math::Vector;
use discrete_contact_validation::wet_rebound::{ReboundRun, Trajectory, WetRebound};
use plotters::prelude::*;

/// One finished run.
struct Run {
    h0: f64,
    dx: f64,
    contact: bool,
    case: WetRebound,
    traj: Trajectory,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env(include_str!("wet_rebound.rs"));
    let quick = args.flag("--quick");
    let dxs = args.list("--dx", if quick { &[1.0, 0.75] } else { &[0.6, 0.3] });
    let h0s = args.list("--h0", &[5.5, 19.6, 35.7]);
    let bx = args.list("--box", &[42.0, 42.0, 50.0]);
    let vtk_every = args
        .value("--vtk-every-ms")
        .map(|v| v.parse::<f64>().expect("--vtk-every-ms: a number") * 1e-3);
    let case_for = |h0_mm: f64, dx_mm: f64, contact: bool| -> WetRebound {
        let mut c = WetRebound::li_2010(h0_mm * 1e-3, dx_mm * 1e-3);
        c.radius = args.number("--radius", 4.75) * 1e-3;
        c.particle_density = args.number("--rho-p", c.particle_density);
        c.fluid_density = args.number("--rho-f", c.fluid_density);
        c.viscosity = args.number("--mu", c.viscosity);
        c.box_size = Vector::new(bx[0], bx[1], bx[2]) * 1e-3;
        c.dry_restitution = args.number("--e-dry", c.dry_restitution);
        c.n_c = args.number("--nc", c.n_c as f64) as usize;
        c.end_time = args.number("--t-end", c.end_time);
        if let Some(dt) = args.value("--dt-us") {
            c.dt = dt.parse::<f64>().expect("--dt-us: a number") * 1e-6;
        }
        c.contact = contact;
        c.enlargement = args.number("--enlargement", 1.0 / 7.0) * c.dx;
        if args.flag("--lubrication") {
            c.film_cutoff = Some(args.number("--film-cutoff", FILM_CUTOFF) * c.dx);
            c.film_min_gap = args.number("--film-min-gap-um", c.film_min_gap * 1e6) * 1e-6;
        }
        if args.flag("--forcing-momentum") {
            c.force_method = ForceMethod::Forcing;
        }
        c
    };

    let c0 = case_for(h0s[0], dxs[0], true);
    println!(
        "sphere R = {} mm, ρ_p = {} kg/m³ in ρ_f = {} kg/m³, μ = {} Pa s; box {:?} mm; e_dry = {}, N_c = {}",
        c0.radius * 1e3,
        c0.particle_density,
        c0.fluid_density,
        c0.viscosity,
        bx,
        c0.dry_restitution,
        c0.n_c
    );
    let finest = dxs.iter().cloned().fold(f64::INFINITY, f64::min);
    let mut jobs: Vec<(f64, f64, bool)> = Vec::new();
    for &dx in &dxs {
        for &h0 in &h0s {
            jobs.push((h0, dx, true));
        }
    }
    if !args.flag("--no-compare") {
        for &h0 in &h0s {
            jobs.push((h0, finest, false));
        }
    }

    let dir = common::output_dir();
    let checkpoints = common::Checkpoints::from_args(&args, &dir);
    let mut runs = Vec::new();
    for (h0, dx, contact) in jobs {
        let case = case_for(h0, dx, contact);
        let settings = format!(
            "h0 = {h0} mm, Δx = {dx} mm, Δt = {:.2} µs, {}",
            case.dt * 1e6,
            if contact { "with contact" } else { "no contact" }
        );
        println!("\n{settings}");
        let start = Instant::now();
        let mut last_print = 0.0;
        let mut next_vtk = 0.0;
        let steps_max = (case.end_time / case.dt).ceil();
        let path = checkpoints.file(&format!(
            "wet_rebound_h{h0}_dx{dx}_{}",
            if contact { "contact" } else { "no_contact" }
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
        runs.push(Run { h0, dx, contact, case, traj });
    }

    // Gap over time, one row per 0.1 ms at least (every step is finer than 0.5 ms).
    for (contact, name) in [(true, "wet_rebound.csv"), (false, "wet_rebound_no_contact.csv")] {
        let mut rows = Vec::new();
        for r in runs.iter().filter(|r| r.contact == contact) {
            let mut last = f64::NEG_INFINITY;
            for &(t, gap, _) in &r.traj.samples {
                if t - last >= 1e-4 - 1e-12 {
                    rows.push(format!("{},{},{:.6},{:.5}", r.h0, r.dx, t, gap * 1e3));
                    last = t;
                }
            }
        }
        if !rows.is_empty() {
            common::write_csv(&dir.join(name), "h0_mm,dx_mm,t_s,gap_mm", &rows);
        }
    }

    // Restitution against the Stokes number, error against cost.
    println!("\nEffective restitution (speeds at a gap of 5 % of D) against Legendre et al. (2006), e/e_dry = exp(-35/St):");
    println!(
        "{:>6} {:>6} {:>9} {:>9} {:>9} {:>9} {:>7} {:>8} {:>8} {:>8} {:>8} {:>9}",
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
            "{:>6} {:>6} {:>9.4} {:>9.4} {:>9.4} {:>6.3} mm {:>7.1} {:>8.3} {:>8.3} {:>+8.3} {:>8.1} {:>9}",
            r.h0,
            r.dx,
            t_imp,
            u_in,
            u_out,
            h_reb * 1e3,
            st,
            ratio,
            legendre,
            ratio - legendre,
            r.traj.wall_time,
            if r.contact { "yes" } else { "no" }
        );
        summary.push(format!(
            "{},{},{},{:.6},{:.5},{:.5},{:.5},{:.2},{:.4},{:.4},{:.2},{},{}",
            r.h0,
            r.dx,
            r.contact,
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
        &dir.join("wet_rebound_summary.csv"),
        "h0_mm,dx_mm,contact,t_impact_s,u_in_m_s,u_out_m_s,rebound_height_mm,stokes,e_over_e_dry,legendre,wall_time_s,steps,cells",
        &summary,
    );
    plot(&dir.join("wet_rebound.png"), &runs, finest)?;
    println!("\nwrote {}/wet_rebound.csv, wet_rebound_no_contact.csv, wet_rebound_summary.csv, wet_rebound.png", dir.display());
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
    common::register_fonts();
    discrete_contact::io::replace_atomically(
        path,
        |tmp: &std::path::Path| -> Result<(), Box<dyn std::error::Error>> {
            let root = BitMapBackend::new(tmp, (1100, 700)).into_drawing_area();
            root.fill(&WHITE)?;
            let t_max =
                runs.iter().flat_map(|r| r.traj.samples.last()).map(|s| s.0).fold(0.0, f64::max);
            let h_max = runs.iter().map(|r| r.h0).fold(0.0, f64::max) * 1.05;
            let mut ch = ChartBuilder::on(&root)
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
            let mut h0s: Vec<f64> = runs.iter().map(|r| r.h0).collect();
            h0s.dedup();
            for r in runs {
                let k = h0s.iter().position(|&h| h == r.h0).unwrap_or(0);
                let colour = colours[k % colours.len()];
                let pts: Vec<(f64, f64)> =
                    r.traj.samples.iter().map(|s| (s.0, s.1 * 1e3)).collect();
                let label = format!(
                    "h0 = {} mm, Δx = {} mm{}",
                    r.h0,
                    r.dx,
                    if r.contact { "" } else { ", no contact" }
                );
                let style = if r.contact && r.dx == finest {
                    colour.stroke_width(2)
                } else {
                    colour.mix(0.5).stroke_width(1)
                };
                if r.contact {
                    ch.draw_series(LineSeries::new(pts, style))?
                        .label(label)
                        .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], style));
                } else {
                    ch.draw_series(DashedLineSeries::new(pts, 6, 4, style))?
                        .label(label)
                        .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], style));
                }
            }
            ch.configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 13))
                .position(SeriesLabelPosition::UpperRight)
                .draw()?;
            root.present()?;
            Ok(())
        },
    )
}
