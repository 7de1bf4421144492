//! Static normal force against Hertz for the eight cases of Marquardt et al. Fig. 3, both integration
//! modes, N_c = 2…32: error against run time.
//!
//! Writes `target/validation/hertz_error.csv`, `hertz_force.csv` and `hertz_validation.png`.
//!
//! `cargo run --release --example hertz_validation -- --no-facet-bulge` runs the sub-cell
//! resolutions and their reference at N_c = 64 without the balls' facet layer
//! (`OverlapSettings::with_facet_bulge(false)`: second order).

#[path = "common/mod.rs"]
mod common;

use discrete_contact::{IntegrationMode, OverlapSettings};
use discrete_contact_validation::hertz::HertzCase;
use plotters::prelude::*;

const RESOLUTIONS: [usize; 5] = [2, 4, 8, 16, 32];
const MODES: [IntegrationMode; 2] = [IntegrationMode::Count, IntegrationMode::Subcell];
/// Reference resolution for the discretisation error (sub-cell).
const REFERENCE_N: usize = 64;

struct Run {
    case: usize,
    mode: IntegrationMode,
    n: usize,
    forces: Vec<f64>,
    rms_hertz: f64,
    rms_reference: f64,
    us_per_eval: f64,
}

fn rms(values: &[f64], reference: &[f64]) -> f64 {
    let s: f64 = values.iter().zip(reference).map(|(v, r)| ((v - r) / r).powi(2)).sum();
    (s / values.len() as f64).sqrt()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env(include_str!("hertz_validation.rs"));
    let bulge = !args.flag("--no-facet-bulge");
    let cases = HertzCase::all();
    let ds = HertzCase::indentations();
    let dir = common::output_dir();
    println!(
        "Hertz validation: E* = {:.4e} Pa, {} indentations up to {} m",
        HertzCase::effective_modulus(),
        ds.len(),
        ds[ds.len() - 1]
    );
    let mut runs = Vec::new();
    for (ci, case) in cases.iter().enumerate() {
        let analytic: Vec<f64> = ds.iter().map(|&d| case.analytic_force(d)).collect();
        let fine =
            OverlapSettings::new(REFERENCE_N, IntegrationMode::Subcell)?.with_facet_bulge(bulge);
        let reference: Vec<f64> =
            ds.iter().map(|&d| case.force(&fine, d)).collect::<Result<_, _>>()?;
        for mode in MODES {
            for n in RESOLUTIONS {
                let s = OverlapSettings::new(n, mode)?.with_facet_bulge(bulge);
                let forces: Vec<f64> =
                    ds.iter().map(|&d| case.force(&s, d)).collect::<Result<_, _>>()?;
                let us = common::time_us(40.0, || {
                    for &d in &ds {
                        std::hint::black_box(case.force(&s, d).unwrap());
                    }
                }) / ds.len() as f64;
                runs.push(Run {
                    case: ci,
                    mode,
                    n,
                    rms_hertz: rms(&forces, &analytic),
                    rms_reference: rms(&forces, &reference),
                    forces,
                    us_per_eval: us,
                });
            }
        }
        eprint!(".");
    }
    eprintln!();

    let mut err_rows = Vec::new();
    let mut force_rows = Vec::new();
    for r in &runs {
        let case = cases[r.case];
        err_rows.push(format!(
            "{},{},{},{:.6e},{:.3}",
            case.name(),
            r.mode.name(),
            r.n,
            r.rms_hertz,
            r.us_per_eval
        ));
        for (d, f) in ds.iter().zip(&r.forces) {
            force_rows.push(format!(
                "{},{},{},{:.6e},{:.6e},{:.6e}",
                case.name(),
                r.mode.name(),
                r.n,
                d,
                f,
                case.analytic_force(*d)
            ));
        }
    }
    common::write_csv(
        &dir.join("hertz_error.csv"),
        "case,mode,n_c,rms_rel_error,time_per_eval_us",
        &err_rows,
    );
    common::write_csv(
        &dir.join("hertz_force.csv"),
        "case,mode,n_c,indentation_m,force_n,analytic_n",
        &force_rows,
    );

    // Error against run time, per case and averaged.
    println!(
        "\n{:<22} {:>7} {:>4} {:>12} {:>12} {:>12}",
        "case", "mode", "N_c", "rms vs Hertz", "rms vs ref", "µs/eval"
    );
    for r in &runs {
        println!(
            "{:<22} {:>7} {:>4} {:>12.4e} {:>12.4e} {:>12.1}",
            cases[r.case].name(),
            r.mode.name(),
            r.n,
            r.rms_hertz,
            r.rms_reference,
            r.us_per_eval
        );
    }
    println!("\nMean over the eight cases (the Pareto view):");
    println!(
        "{:>7} {:>4} {:>14} {:>14} {:>12}",
        "mode", "N_c", "rms vs Hertz", "rms vs ref", "µs/eval"
    );
    let mut summary = Vec::new();
    for mode in MODES {
        for n in RESOLUTIONS {
            let sel: Vec<&Run> = runs.iter().filter(|r| r.mode == mode && r.n == n).collect();
            let m = sel.len() as f64;
            let (eh, er, t) = sel.iter().fold((0.0, 0.0, 0.0), |a, r| {
                (a.0 + r.rms_hertz / m, a.1 + r.rms_reference / m, a.2 + r.us_per_eval / m)
            });
            println!("{:>7} {:>4} {:>14.4e} {:>14.4e} {:>12.1}", mode.name(), n, eh, er, t);
            summary.push((mode, n, eh, er, t));
        }
    }
    println!("\nExperimental order of convergence (least squares over N_c = 8, 16, 32):");
    for mode in MODES {
        let pick = |f: fn(&(IntegrationMode, usize, f64, f64, f64)) -> f64| -> Vec<f64> {
            summary.iter().filter(|s| s.0 == mode && (8..=32).contains(&s.1)).map(f).collect()
        };
        let ns = pick(|s| s.1 as f64);
        println!(
            "  {:>7}: EOC vs Hertz {:.2}, EOC of the discretisation error (vs sub-cell N_c = {REFERENCE_N}) {:.2}",
            mode.name(),
            common::eoc(&ns, &pick(|s| s.2)),
            common::eoc(&ns, &pick(|s| s.3))
        );
    }
    let count16 = summary.iter().find(|s| s.0 == IntegrationMode::Count && s.1 == 16).unwrap();
    if let Some(best) = summary
        .iter()
        .filter(|s| s.0 == IntegrationMode::Subcell && s.2 <= count16.2)
        .min_by(|a, b| a.4.total_cmp(&b.4))
    {
        println!(
            "\nCheapest sub-cell setting at least as accurate as counting at N_c = 16 ({:.3e} in {:.0} µs): N_c = {} ({:.3e} in {:.0} µs, {:.1}x faster)",
            count16.2, count16.4, best.1, best.2, best.4, count16.4 / best.4
        );
    }

    plot(&dir.join("hertz_validation.png"), &cases, &ds, &runs, &summary)?;
    println!("\nwrote {}/hertz_error.csv, hertz_force.csv, hertz_validation.png", dir.display());
    Ok(())
}

type Summary = (IntegrationMode, usize, f64, f64, f64);

fn plot(
    path: &std::path::Path,
    cases: &[HertzCase],
    ds: &[f64],
    runs: &[Run],
    summary: &[Summary],
) -> Result<(), Box<dyn std::error::Error>> {
    common::png(path, (1800, 1350), |root| {
        let (top, bottom) = root.split_vertically(820);
        let panels = top.split_evenly((2, 4));
        let shown = [
            (IntegrationMode::Count, 4, RED),
            (IntegrationMode::Count, 8, MAGENTA),
            (IntegrationMode::Count, 16, BLUE),
            (IntegrationMode::Subcell, 4, GREEN),
            (IntegrationMode::Subcell, 8, BLACK),
        ];
        for (ci, (case, area)) in cases.iter().zip(panels.iter()).enumerate() {
            let fmax = case.analytic_force(ds[ds.len() - 1]) * 1.15 / 1e3;
            let mut ch = ChartBuilder::on(area)
                .caption(case.name(), ("sans-serif", 18))
                .margin(8)
                .x_label_area_size(32)
                .y_label_area_size(52)
                .build_cartesian_2d(0.0..ds[ds.len() - 1] * 1e3 * 1.02, 0.0..fmax)?;
            ch.configure_mesh()
                .x_desc("d (mm)")
                .y_desc("F_n (kN)")
                .label_style(("sans-serif", 12))
                .draw()?;
            let line: Vec<(f64, f64)> = (0..=100)
                .map(|i| ds[ds.len() - 1] * i as f64 / 100.0)
                .map(|d| (d * 1e3, case.analytic_force(d) / 1e3))
                .collect();
            ch.draw_series(LineSeries::new(line, BLACK.stroke_width(2)))?
                .label("analytic")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLACK));
            for (mode, n, color) in shown {
                let r = runs.iter().find(|r| r.case == ci && r.mode == mode && r.n == n).unwrap();
                let pts = ds.iter().zip(&r.forces).map(|(d, f)| (d * 1e3, f / 1e3));
                let s = ch.draw_series(pts.map(|p| {
                    if mode == IntegrationMode::Count {
                        Cross::new(p, 4, color.stroke_width(1)).into_dyn()
                    } else {
                        Circle::new(p, 3, color.filled()).into_dyn()
                    }
                }))?;
                if ci == 0 {
                    s.label(format!("{} N_c={n}", mode.name()))
                        .legend(move |(x, y)| Circle::new((x + 8, y), 3, color.filled()));
                }
            }
            if ci == 0 {
                common::legend(&mut ch, SeriesLabelPosition::UpperLeft, 11)?;
            }
        }
        let (tmin, tmax) =
            summary.iter().fold((f64::MAX, 0.0f64), |a, s| (a.0.min(s.4), a.1.max(s.4)));
        let (emin, emax) = summary
            .iter()
            .fold((f64::MAX, 0.0f64), |a, s| (a.0.min(s.2.min(s.3)), a.1.max(s.2.max(s.3))));
        let mut ch = ChartBuilder::on(&bottom)
            .caption(
                "Mean RMS relative error against time per contact evaluation (8 cases)",
                ("sans-serif", 22),
            )
            .margin(20)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (tmin * 0.7..tmax * 1.4).log_scale(),
                (emin * 0.5..emax * 2.0).log_scale(),
            )?;
        ch.configure_mesh()
            .x_desc("time per evaluation (µs)")
            .y_desc("RMS relative error")
            .label_style(("sans-serif", 14))
            .draw()?;
        for (mode, color) in [(IntegrationMode::Count, RED), (IntegrationMode::Subcell, BLUE)] {
            let pts: Vec<(f64, f64)> =
                summary.iter().filter(|s| s.0 == mode).map(|s| (s.4, s.2)).collect();
            ch.draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
                .label(format!("{} vs Hertz", mode.name()))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2))
                });
            ch.draw_series(pts.iter().zip(RESOLUTIONS).map(|(p, n)| {
                EmptyElement::at(*p)
                    + Circle::new((0, 0), 4, color.filled())
                    + Text::new(format!("N_c={n}"), (6, -14), ("sans-serif", 13))
            }))?;
            let refpts: Vec<(f64, f64)> =
                summary.iter().filter(|s| s.0 == mode).map(|s| (s.4, s.3)).collect();
            ch.draw_series(LineSeries::new(refpts, color.mix(0.5).stroke_width(1)))?
                .label(format!("{} discretisation error", mode.name()))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.mix(0.5)));
        }
        common::legend(&mut ch, SeriesLabelPosition::UpperRight, 14)?;
        Ok(())
    })
}
