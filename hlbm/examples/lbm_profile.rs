//! Single-thread profile target: 96³ periodic box, plain fluid, `STEPS` steps (env), for perf.
fn main() {
    let steps: usize = std::env::var("STEPS").ok().and_then(|s| s.parse().ok()).unwrap_or(40);
    let particles = std::env::var("PARTICLES").is_ok();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| {
        let mut lat = hlbm::Lattice::new(96, 96, 96, 0.6).unwrap();
        if particles {
            for z in 0..96 {
                for y in 0..96 {
                    for x in (0..96).step_by(5) {
                        lat.particles.add(x, y, z, 0.5, [1e-3, 0.0, 0.0], [0.0; 3], (x / 20) as u32);
                    }
                }
            }
        }
        let t = std::time::Instant::now();
        lat.run(steps).unwrap();
        let s = t.elapsed().as_secs_f64();
        println!("{:.1} MLUPs", 96f64.powi(3) * steps as f64 / s / 1e6);
    });
}
