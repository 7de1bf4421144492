//! A fixed contact-evaluation loop for profiling (`perf record`, `valgrind --tool=callgrind`):
//! one of the `contact` bench's pairs, sub-cell integration, evaluated again and again as a
//! persistent contact (seeded with its last box) or as a first touch.
//!
//! `cargo run --release --example contact_profile -- --pair sphere_sphere --n-c 4 --iterations 2000`
//! (`--pair sphere_sphere|cylinder_plane|cylinder_cylinder|cube_cube|hull_hull|capsule_cylinder`, `--first` for first touches, `--exact-polyhedra` for the exact form of polyhedral pairs, `--no-facet-bulge` without smooth bodies' facet layers, `--enlargement E` for a contact enlargement of `E` m on each body). Prints the mean time per
//! evaluation and the result, so two builds can be compared on the same output.

mod common;
#[path = "../benches/common/pairs.rs"]
mod pairs;

use pairs::pairs;

use discrete_contact::prelude::*;

fn main() {
    let args = common::Args::from_env(include_str!("contact_profile.rs"));
    let pair = args.value("--pair").unwrap_or("sphere_sphere").to_string();
    let n_c = args.number("--n-c", 4.0) as usize;
    let iterations = args.number("--iterations", 2000.0) as usize;
    let first = args.flag("--first");
    let names = pairs().iter().map(|p| p.0).collect::<Vec<_>>().join(", ");
    let Some((_, sa, pa, sb, pb)) = pairs().into_iter().find(|p| p.0 == pair) else {
        eprintln!("unknown --pair {pair}: one of {names}");
        std::process::exit(2);
    };
    let settings = OverlapSettings::new(n_c, IntegrationMode::Subcell)
        .unwrap_or_else(|e| {
            eprintln!("--n-c: {e}");
            std::process::exit(2);
        })
        .with_exact_polyhedra(args.flag("--exact-polyhedra"))
        .with_facet_bulge(!args.flag("--no-facet-bulge"));
    let eps = args.number("--enlargement", 0.0);
    let settings = settings.with_enlargement(eps, eps).unwrap_or_else(|e| {
        eprintln!("--enlargement: {e}");
        std::process::exit(2);
    });
    let m = Material::new(5e8, 0.35).unwrap();
    let params = PairParameters::new(&m, &m, 0.85).unwrap();
    let model = ContactModel::new(params, settings);
    let a = BodyState::at_rest(&sa, pa).moving(Vector::new(0.0, -1.0, 0.0), Vector::ZERO);
    let b = BodyState::at_rest(&sb, pb);
    let mut state = None;
    let out = model.evaluate(&a, &b, &mut state).unwrap().expect("the pair overlaps");
    let clock = std::time::Instant::now();
    let mut sum = 0.0;
    for _ in 0..iterations {
        let mut s = if first { None } else { state };
        sum += model.evaluate(&a, &b, &mut s).unwrap().map_or(0.0, |o| o.force.normal_force);
    }
    let us = clock.elapsed().as_secs_f64() / iterations.max(1) as f64 * 1e6;
    let kind = if first { "first touch" } else { "persistent" };
    println!("{pair} N_c = {n_c} {kind}: {us:.2} µs per evaluation; V = {:.6e} m³, F_n = {:.6e} N (first), mean F_n {:.6e} N", out.geometry.volume, out.force.normal_force, sum / iterations.max(1) as f64);
}
