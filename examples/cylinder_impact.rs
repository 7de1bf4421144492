//! Oblique cylinder–wall impact (Marquardt et al. Fig. 6, Park 2003) in the rapier pipeline:
//! θ = 0°…90° in 5° steps, N_c ∈ {2, 4, 8, 16}, both integration modes.
//!
//! Writes `target/validation/cylinder_impact.csv` and `cylinder_impact.png`, and prints the
//! error against run time.
//!
//! `cargo run --release --example cylinder_impact [-- --reuse 0.25]`: `--reuse f` sets the
//! geometry reuse (0: the contact evaluated in full on every sub-step).

#[path = "common/mod.rs"]
mod common;

use discrete_contact::{IntegrationMode, OverlapSettings};
use discrete_contact_validation::cylinder_impact::{park, simulate_with_reuse};
use plotters::prelude::*;
use rayon::prelude::*;

const RESOLUTIONS: [usize; 4] = [2, 4, 8, 16];
const MODES: [IntegrationMode; 2] = [IntegrationMode::Count, IntegrationMode::Subcell];

struct Row {
    theta: f64,
    n: usize,
    mode: IntegrationMode,
    v: f64,
    w: f64,
    time: f64,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env(include_str!("cylinder_impact.rs"));
    let reuse = discrete_contact::contact::check_reuse(
        args.number("--reuse", discrete_contact::contact::GEOMETRY_REUSE),
    )
    .unwrap_or_else(|e| {
        eprintln!("--reuse: {e}");
        std::process::exit(2);
    });
    let thetas: Vec<f64> = (0..=18).map(|i| 5.0 * i as f64).collect();
    let mut jobs = Vec::new();
    for mode in MODES {
        for n in RESOLUTIONS {
            for &t in &thetas {
                jobs.push((t, n, mode));
            }
        }
    }
    eprintln!("{} impacts on {} threads …", jobs.len(), rayon::current_num_threads());
    let rows: Vec<Row> = jobs
        .par_iter()
        .map(|&(theta, n, mode)| {
            let r =
                simulate_with_reuse(theta, OverlapSettings::new(n, mode).expect("valid"), reuse)
                    .expect("impact runs");
            Row { theta, n, mode, v: r.v_ratio, w: r.omega_r_ratio, time: r.wall_time_s }
        })
        .collect();
    let dir = common::output_dir();
    let csv: Vec<String> = rows
        .iter()
        .map(|r| {
            let (pv, pw) = park(r.theta);
            format!(
                "{},{},{},{:.6},{:.6},{:.6},{:.6},{:.4}",
                r.theta,
                r.n,
                r.mode.name(),
                r.v,
                r.w,
                pv,
                pw,
                r.time
            )
        })
        .collect();
    common::write_csv(
        &dir.join("cylinder_impact.csv"),
        "theta_deg,n_c,mode,v_ratio,omega_r_ratio,v_ratio_analytic,omega_r_ratio_analytic,wall_time_s",
        &csv,
    );
    println!("Error against Park (2003) for 10° <= θ <= 80°, and run time per impact (geometry reuse {reuse}):");
    println!(
        "{:>7} {:>4} {:>12} {:>12} {:>12}",
        "mode", "N_c", "max |Δv/v|", "max |ΔRω/v|", "s/impact"
    );
    for mode in MODES {
        for n in RESOLUTIONS {
            let sel: Vec<&Row> = rows.iter().filter(|r| r.mode == mode && r.n == n).collect();
            let inner = sel.iter().filter(|r| (10.0..=80.0).contains(&r.theta));
            let (ev, ew) = inner.fold((0.0f64, 0.0f64), |a, r| {
                let (pv, pw) = park(r.theta);
                (a.0.max((r.v - pv).abs()), a.1.max((r.w - pw).abs()))
            });
            let t = sel.iter().map(|r| r.time).sum::<f64>() / sel.len() as f64;
            println!("{:>7} {n:>4} {ev:>12.4} {ew:>12.4} {t:>12.2}", mode.name());
        }
    }
    plot(&dir.join("cylinder_impact.png"), &rows)?;
    println!("\nwrote {}/cylinder_impact.csv, cylinder_impact.png", dir.display());
    Ok(())
}

fn plot(path: &std::path::Path, rows: &[Row]) -> Result<(), Box<dyn std::error::Error>> {
    common::png(path, (1400, 600), |root| {
        let panels = root.split_evenly((1, 2));
        for (k, area) in panels.iter().enumerate() {
            let (title, range) =
                if k == 0 { ("rebound speed v+/v", -0.6..1.5) } else { ("R ω+/v", -1.8..1.8) };
            let mut ch = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 22))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(55)
                .build_cartesian_2d(0.0..90.0, range)?;
            ch.configure_mesh()
                .x_desc("impact angle θ (°)")
                .label_style(("sans-serif", 14))
                .draw()?;
            let exact: Vec<(f64, f64)> = (1..900)
                .map(|i| i as f64 / 10.0)
                .map(|t| (t, if k == 0 { park(t).0 } else { park(t).1 }))
                .collect();
            ch.draw_series(LineSeries::new(exact, BLACK.stroke_width(2)))?
                .label("Park (2003)")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLACK));
            for (mode, n, color) in [
                (IntegrationMode::Count, 4, RED),
                (IntegrationMode::Count, 16, MAGENTA),
                (IntegrationMode::Subcell, 4, GREEN),
                (IntegrationMode::Subcell, 8, BLUE),
            ] {
                let pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| r.mode == mode && r.n == n)
                    .map(|r| (r.theta, if k == 0 { r.v } else { r.w }))
                    .collect();
                ch.draw_series(pts.iter().map(|p| Circle::new(*p, 4, color.filled())))?
                    .label(format!("{} N_c={n}", mode.name()))
                    .legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
            }
            common::legend(
                &mut ch,
                if k == 0 {
                    SeriesLabelPosition::UpperLeft
                } else {
                    SeriesLabelPosition::LowerLeft
                },
                13,
            )?;
        }
        Ok(())
    })
}
