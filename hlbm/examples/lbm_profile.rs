//! Single-thread profile target: 96³ periodic box, plain fluid, `STEPS` steps (env), for perf;
//! `PARTICLES=1` covers ~20 % of the nodes with spheres of radius 4, `MOVING=1` maps them again
//! before every step half a cell back and forth along x (every row's nodes change: the links
//! are found again each step; the mapping is not timed), `FORCING=1` measures their forces by
//! the forcing momentum instead of the momentum exchange, `STORAGE=f32` stores the populations
//! as f32.
fn main() {
    let steps: usize = std::env::var("STEPS").ok().and_then(|s| s.parse().ok()).unwrap_or(40);
    let particles = std::env::var("PARTICLES").is_ok();
    let moving = std::env::var("MOVING").is_ok();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| {
        let mut lat = hlbm::Lattice::new(96, 96, 96, 0.6).unwrap();
        if std::env::var("STORAGE").as_deref() == Ok("f32") {
            lat.set_storage(hlbm::Storage::F32);
        }
        if std::env::var("FORCING").is_ok() {
            lat.set_force_method(hlbm::ForceMethod::Forcing);
        }
        // Spheres of radius 4 on a 12-cell grid (~20 % of the nodes), `shift` cells along x.
        let place = |lat: &mut hlbm::Lattice, shift: f64| {
            lat.particles_mut().clear();
            for (id, c) in (0..512)
                .map(|k| [k % 8, (k / 8) % 8, k / 64].map(|i| 12.0 * i as f64 + 6.3))
                .enumerate()
            {
                lat.particles_mut()
                    .add_sphere([c[0] + shift, c[1], c[2]], 4.0, 1.0, [1e-3, 0.0, 0.0], id as u32)
                    .expect("a sphere inside the lattice");
            }
        };
        if particles {
            place(&mut lat, 0.0);
        }
        let mut timed = std::time::Duration::ZERO;
        for step in 0..steps {
            if particles && moving {
                place(&mut lat, 0.5 * (step % 2) as f64);
            }
            let t = std::time::Instant::now();
            lat.step().unwrap();
            timed += t.elapsed();
        }
        println!("{:.1} MLUPs", 96f64.powi(3) * steps as f64 / timed.as_secs_f64() / 1e6);
    });
}
