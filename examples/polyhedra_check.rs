//! The `N_c` grid against the exact polyhedral overlap (`OverlapSettings::with_exact_polyhedra`)
//! on random box pairs: random aspect ratios and orientations, depths set so the exact overlap
//! volume is (1–10 % of the smaller box's size)³ × 8 × its volume. Prints, per sub-cell `N_c`,
//! the median, 90th percentile and worst relative volume error of a first touch and of a
//! persistent contact (three evaluations, each seeded with the last box), and how many
//! overlapping pairs the grid reported apart.
//!
//! `cargo run --release --example polyhedra_check -- --cases 300` (`--worst 0.3` also prints
//! each pair whose error exceeds 30 %, with the exact and the grid's boxes).

mod common;

use discrete_contact::compute_overlap;
use discrete_contact::prelude::*;

/// xorshift64: a fixed, portable sequence of cases.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A uniformly random rotation (Shoemake's method).
    fn rotation(&mut self) -> Rotation {
        let (u1, u2, u3) = (self.next(), self.next(), self.next());
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        let t = std::f64::consts::TAU;
        Rotation::from_xyzw(a * (t * u2).sin(), a * (t * u2).cos(), b * (t * u3).sin(), b * (t * u3).cos()).normalize()
    }

    fn half_extents(&mut self) -> Vector {
        Vector::new(0.2 + 0.3 * self.next(), 0.2 + 0.3 * self.next(), 0.2 + 0.3 * self.next())
    }
}

/// Median, 90th percentile and worst of the magnitudes.
fn spread(errors: &[f64]) -> (f64, f64, f64) {
    let mut e: Vec<f64> = errors.iter().map(|x| x.abs()).collect();
    e.sort_by(f64::total_cmp);
    (e[e.len() / 2], e[e.len() * 9 / 10], e[e.len() - 1])
}

fn main() {
    let args = common::Args::from_env(include_str!("polyhedra_check.rs"));
    let cases = args.number("--cases", 300.0);
    if !(cases >= 1.0) {
        eprintln!("--cases: needs at least 1 pair, got {cases}");
        std::process::exit(2);
    }
    let cases = cases as usize;
    let worst = args.number("--worst", f64::INFINITY);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let n_cs = [4usize, 8, 16];
    let exact = OverlapSettings::new(8, IntegrationMode::Subcell).unwrap().with_exact_polyhedra(true);
    let (mut first, mut persistent, mut missed) = (vec![vec![]; n_cs.len()], vec![vec![]; n_cs.len()], vec![0usize; n_cs.len()]);
    for case in 0..cases {
        let (ha, hb) = (rng.half_extents(), rng.half_extents());
        let (a, b) = (ConvexShape::cuboid(ha).unwrap(), ConvexShape::cuboid(hb).unwrap());
        let pa = Pose::from_parts(Vector::ZERO, rng.rotation());
        let rb = rng.rotation();
        let dir = Vector::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5).normalize();
        let target = (0.01 + 0.09 * rng.next()).powi(3) * 8.0 * ha.element_product().min(hb.element_product());
        let at = |s: f64| Pose::from_parts(dir * s, rb);
        let volume = |s: f64| compute_overlap(&a, &pa, &b, &at(s), &exact, None).unwrap().map_or(0.0, |g| g.volume);
        // Bisection on the centre distance for the target volume.
        let (mut lo, mut hi) = (0.0, 2.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if volume(mid) > target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let pb = at(lo);
        let reference = compute_overlap(&a, &pa, &b, &pb, &exact, None).unwrap().expect("overlaps at the bisected depth");
        for (k, &n_c) in n_cs.iter().enumerate() {
            let settings = OverlapSettings::new(n_c, IntegrationMode::Subcell).unwrap();
            let Some(g) = compute_overlap(&a, &pa, &b, &pb, &settings, None).unwrap() else {
                missed[k] += 1;
                first[k].push(1.0);
                persistent[k].push(1.0);
                continue;
            };
            let mut seeded = g.clone();
            for _ in 0..3 {
                match compute_overlap(&a, &pa, &b, &pb, &settings, Some(&seeded.corrected_box)).unwrap() {
                    Some(next) => seeded = next,
                    None => {
                        seeded.volume = 0.0;
                        break;
                    }
                }
            }
            let (e_first, e_seeded) = ((g.volume - reference.volume) / reference.volume, (seeded.volume - reference.volume) / reference.volume);
            first[k].push(e_first);
            persistent[k].push(e_seeded);
            if e_first.abs().max(e_seeded.abs()) > worst {
                let r = &reference.corrected_box;
                println!("case {case} N_c = {n_c}: exact V = {:.3e}, first {:.3e}, persistent {:.3e}", reference.volume, g.volume, seeded.volume);
                println!("  exact box {:?} .. {:?}\n  first box {:?} .. {:?}", r.mins, r.maxs, g.corrected_box.mins, g.corrected_box.maxs);
            }
        }
    }
    println!("{cases} box pairs, sub-cell volume error against the exact polyhedron:");
    println!("{:>5} {:>30} {:>30} {:>7}", "N_c", "first touch: median p90 worst", "persistent: median p90 worst", "missed");
    for (k, n_c) in n_cs.iter().enumerate() {
        let (f, p) = (spread(&first[k]), spread(&persistent[k]));
        println!("{n_c:>5} {:>10.4} {:>9.4} {:>9.4} {:>10.4} {:>9.4} {:>9.4} {:>7}", f.0, f.1, f.2, p.0, p.1, p.2, missed[k]);
    }
}
