//! The `N_c` grid against the exact polyhedral overlap (`OverlapSettings::with_exact_polyhedra`)
//! on random pairs — boxes of random aspect ratio and twelve-point convex hulls, random
//! orientations, depths set so the exact overlap volume is (1–10 % of the smaller body's
//! size)³ × 8 × its volume (the pairs of the `polyhedra_grid` test). Prints, per mode and
//! `N_c`, the median, 90th percentile and worst relative volume error of a first touch and of
//! a persistent contact (three evaluations, each seeded with the last box), the median and
//! worst contact-point error per the overlap's size, and how many overlapping pairs the grid
//! reported apart.
//!
//! `cargo run --release --example polyhedra_check -- --cases 2000` (`--worst 0.1` also prints
//! each pair whose volume error exceeds 10 %).

mod common;
#[path = "../tests/common/polyhedra.rs"]
mod polyhedra;

use discrete_contact::compute_overlap;
use discrete_contact::prelude::*;

/// Median, 90th percentile and worst of the magnitudes.
fn spread(errors: &[f64]) -> (f64, f64, f64) {
    let mut e: Vec<f64> = errors.iter().map(|x| x.abs()).collect();
    e.sort_by(f64::total_cmp);
    (e[e.len() / 2], e[e.len() * 9 / 10], e[e.len() - 1])
}

fn main() {
    let args = common::Args::from_env(include_str!("polyhedra_check.rs"));
    let cases = args.number("--cases", 2000.0);
    if !(cases >= 1.0) {
        eprintln!("--cases: needs at least 1 pair, got {cases}");
        std::process::exit(2);
    }
    let cases = cases as usize;
    let worst = args.number("--worst", f64::INFINITY);
    let mut rng = polyhedra::Rng(0x9E37_79B9_7F4A_7C15);
    let settings: Vec<(IntegrationMode, usize)> =
        [IntegrationMode::Subcell, IntegrationMode::Count]
            .into_iter()
            .flat_map(|m| [4usize, 8, 16].map(|n| (m, n)))
            .collect();
    let k = settings.len();
    let (mut first, mut persistent, mut point, mut missed) =
        (vec![vec![]; k], vec![vec![]; k], vec![vec![]; k], vec![0usize; k]);
    for case_index in 0..cases {
        let case = polyhedra::case(&mut rng, case_index);
        for (j, &(mode, n_c)) in settings.iter().enumerate() {
            // The grid itself (sub-cell mode would otherwise clip these pairs exactly).
            let s = OverlapSettings::new(n_c, mode).unwrap().with_polyhedra_on_grid(true);
            let eval = |previous: Option<&parry3d_f64::bounding_volume::Aabb>| {
                compute_overlap(&case.a, &case.pose_a, &case.b, &case.pose_b, &s, previous).unwrap()
            };
            let Some(g) = eval(None) else {
                missed[j] += 1;
                first[j].push(1.0);
                persistent[j].push(1.0);
                point[j].push(1.0);
                continue;
            };
            let mut seeded = g.clone();
            for _ in 0..3 {
                match eval(Some(&seeded.corrected_box)) {
                    Some(next) => seeded = next,
                    None => {
                        seeded.volume = 0.0;
                        break;
                    }
                }
            }
            let (e_first, e_point) = polyhedra::errors(&case, &g);
            let e_seeded = polyhedra::errors(&case, &seeded).0;
            first[j].push(e_first);
            persistent[j].push(e_seeded);
            point[j].push(e_point);
            if e_first.abs().max(e_seeded.abs()) > worst {
                let kind = if case_index % 2 == 0 { "boxes" } else { "hulls" };
                println!("case {case_index} ({kind}) {mode:?} N_c = {n_c}: exact V = {:.3e}, first {:.3e}, persistent {:.3e}", case.exact.volume, g.volume, seeded.volume);
            }
        }
    }
    println!("{cases} pairs (half boxes, half hulls), error against the exact polyhedron:");
    println!(
        "{:>8} {:>4} {:>30} {:>30} {:>20} {:>7}",
        "mode",
        "N_c",
        "volume, first: median p90 worst",
        "persistent: median p90 worst",
        "point: median worst",
        "missed"
    );
    for (j, (mode, n_c)) in settings.iter().enumerate() {
        let (f, p, c) = (spread(&first[j]), spread(&persistent[j]), spread(&point[j]));
        let mode = format!("{mode:?}").to_lowercase();
        println!("{mode:>8} {n_c:>4} {:>10.4} {:>9.4} {:>9.4} {:>10.4} {:>9.4} {:>9.4} {:>10.4} {:>9.4} {:>7}", f.0, f.1, f.2, p.0, p.1, p.2, c.0, c.2, missed[j]);
    }
}
