//! Memory bandwidth of this machine (STREAM-like copy, triad and in-place update in this
//! binary), the roofline of a D3Q19 f64 update (304 B per node, at the in-place bandwidth: the
//! A-A sweep rewrites the lines it reads), and the kernel's MLUPs on 64³ and 128³ periodic
//! boxes with 1 and 2 threads, plain fluid and with 20 % of the nodes covered by particles
//! (their forces by momentum exchange and, printed only, by the forcing momentum and by the
//! exchange with the spheres moving) — with f64 populations, then with f32 storage
//! ([`hlbm::Storage::F32`], 152 B per update).
//!
//! Writes `target/validation/lbm_throughput.csv` (f64) and `lbm_throughput_f32.csv`.

use std::time::Instant;

use hlbm::{ForceMethod, Lattice, Storage};
use rayon::prelude::*;

/// Bytes a D3Q19 f64 node update moves in the A-A pattern: 19 reads + 19 writes.
const BYTES_PER_UPDATE: f64 = 19.0 * 2.0 * 8.0;

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool")
}

/// Bandwidth runs per thread count.
const RUNS: usize = 7;

/// Median bandwidths (GB/s) over `RUNS` runs, bytes counted as STREAM does.
struct Bandwidth {
    /// `a = b` (16 B/element).
    copy: f64,
    /// `a = b + s c` (24 B/element; the store to `a` also reads `a`'s lines first — the
    /// write-allocate STREAM does not count — so the memory moves 32 B).
    triad: f64,
    /// `a = a + s b` in place (24 B/element, all of it moved: `a`'s lines are read anyway).
    /// The A-A sweep reads and writes each population's own lines in the same way, so this is
    /// its ceiling.
    update: f64,
}

/// Medians, not best runs: on a shared machine single runs now and then read far above what
/// the memory sustains (up to 70 GB/s seen where the median is 45), and one such run would move
/// every percentage below.
fn bandwidth(threads: usize) -> Bandwidth {
    let n = 1 << 25; // 3 × 256 MiB, far beyond any cache
    let (mut a, b, c) = (vec![0.0f64; n], vec![1.0f64; n], vec![2.0f64; n]);
    let chunk = n / 64;
    pool(threads).install(|| {
        let (mut copies, mut triads, mut updates) = (Vec::new(), Vec::new(), Vec::new());
        let rate = |bytes: f64, t: Instant| bytes * n as f64 / t.elapsed().as_secs_f64() / 1e9;
        for _ in 0..RUNS {
            let t = Instant::now();
            a.par_chunks_mut(chunk)
                .zip(b.par_chunks(chunk))
                .for_each(|(a, b)| a.copy_from_slice(b));
            copies.push(rate(16.0, t));
            let t = Instant::now();
            a.par_chunks_mut(chunk).zip(b.par_chunks(chunk).zip(c.par_chunks(chunk))).for_each(
                |(a, (b, c))| {
                    for i in 0..a.len() {
                        a[i] = b[i] + 3.0 * c[i];
                    }
                },
            );
            triads.push(rate(24.0, t));
            let t = Instant::now();
            a.par_chunks_mut(chunk).zip(b.par_chunks(chunk)).for_each(|(a, b)| {
                for i in 0..a.len() {
                    a[i] += 1e-9 * b[i];
                }
            });
            updates.push(rate(24.0, t));
        }
        std::hint::black_box(&a);
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[RUNS / 2]
        };
        Bandwidth {
            copy: median(&mut copies),
            triad: median(&mut triads),
            update: median(&mut updates),
        }
    })
}

/// Covers about `fraction` of the nodes with spheres of radius 4 moving slowly, their centres
/// `shift` cells along x from the grid's.
fn add_particles(lat: &mut Lattice, fraction: f64, shift: f64) -> usize {
    let [nx, ny, nz] = lat.dims();
    let r = 4.0;
    // d_B > 0 reaches half a cell beyond the surface.
    let sphere = 4.0 / 3.0 * std::f64::consts::PI * (r + 0.5f64).powi(3);
    let spacing = (sphere / fraction).cbrt();
    let mut id = 0;
    lat.particles_mut().clear();
    let mut z = spacing / 2.0;
    while z < nz as f64 {
        let mut y = spacing / 2.0;
        while y < ny as f64 {
            let mut x = spacing / 2.0;
            while x < nx as f64 {
                lat.particles_mut()
                    .add_sphere([x + shift, y, z], r, 1.0, [1e-3, 0.0, 0.0], id)
                    .expect("a sphere inside the lattice");
                id += 1;
                x += spacing;
            }
            y += spacing;
        }
        z += spacing;
    }
    lat.particles().len()
}

/// MLUPs of `n³` with `threads` threads, timed over at least 1.5 s. `moving`: the spheres are
/// mapped again before every step, half a cell back and forth along x, so the rows' nodes
/// change and the links are found again (the mapping itself not timed).
fn mlups(
    n: usize,
    threads: usize,
    particles: bool,
    moving: bool,
    method: ForceMethod,
    storage: Storage,
) -> (f64, f64) {
    pool(threads).install(|| {
        let mut lat = Lattice::new(n, n, n, 0.6).expect("lattice");
        lat.set_storage(storage);
        lat.set_force_method(method);
        let covered = if particles {
            add_particles(&mut lat, 0.2, 0.0) as f64 / lat.cells() as f64
        } else {
            0.0
        };
        lat.run(4).expect("warm-up");
        let mut timed = 0.0;
        let mut steps = 0;
        while steps < 4 || timed < 1.5 || steps % 2 == 1 {
            if moving {
                add_particles(&mut lat, 0.2, 0.5 * (steps % 2) as f64);
            }
            let t = Instant::now();
            lat.step().expect("stable");
            timed += t.elapsed().as_secs_f64();
            steps += 1;
        }
        (lat.cells() as f64 * steps as f64 / timed / 1e6, covered)
    })
}

fn main() {
    let threads_max = std::thread::available_parallelism().map_or(1, |n| n.get()).min(2);
    println!("Memory bandwidth (median of {RUNS}, 3 × 256 MiB arrays):");
    let (mut roof, mut triad) = (0.0f64, 0.0f64);
    for t in 1..=threads_max {
        let bw = bandwidth(t);
        println!(
            "  {t} thread(s): copy {:.1} GB/s, triad {:.1} GB/s, in-place update {:.1} GB/s",
            bw.copy, bw.triad, bw.update
        );
        roof = roof.max(bw.update);
        triad = triad.max(bw.triad);
    }
    let roofline = roof * 1e9 / BYTES_PER_UPDATE / 1e6;
    println!("Roofline: {roof:.1} GB/s (in-place update) / {BYTES_PER_UPDATE} B per node update = {roofline:.1} MLUPs (f64)");
    println!("  (from the triad, which also pays a write-allocate the A-A sweep does not: {:.1} MLUPs)\n", triad * 1e9 / BYTES_PER_UPDATE / 1e6);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("target")
        .join("validation");
    std::fs::create_dir_all(&dir).expect("output folder");
    // f64 populations (the default, `lbm_throughput.csv`), then f32 storage at half the bytes
    // per update (`lbm_throughput_f32.csv`, same columns).
    for (storage, bytes, file) in [
        (Storage::F64, BYTES_PER_UPDATE, "lbm_throughput.csv"),
        (Storage::F32, BYTES_PER_UPDATE / 2.0, "lbm_throughput_f32.csv"),
    ] {
        let roofline = roof * 1e9 / bytes / 1e6;
        println!(
            "{storage:?} populations: roofline {roofline:.1} MLUPs ({bytes} B per node update)"
        );
        println!(
            "{:>6} {:>8} {:>10} {:>9} {:>8} {:>10}",
            "grid", "threads", "particles", "covered", "MLUPs", "% roofline"
        );
        let mut rows = Vec::new();
        for n in [64, 128] {
            for t in 1..=threads_max {
                // Plain fluid, then particles with their forces by momentum exchange (the
                // default, in the CSV), by the forcing momentum and by the exchange with the
                // spheres moving (both printed only).
                let cases = [
                    ("no", false, false, ForceMethod::MomentumExchange),
                    ("exchange", true, false, ForceMethod::MomentumExchange),
                    ("forcing", true, false, ForceMethod::Forcing),
                    ("moving", true, true, ForceMethod::MomentumExchange),
                ];
                for (name, particles, moving, method) in cases {
                    let (m, covered) = mlups(n, t, particles, moving, method, storage);
                    println!(
                        "{:>5}³ {t:>8} {name:>10} {:>8.1}% {m:>8.1} {:>9.0}%",
                        n,
                        covered * 100.0,
                        100.0 * m / roofline
                    );
                    if name == "no" || name == "exchange" {
                        rows.push(format!(
                            "{n}^3,{t},{},{m:.2},{roofline:.2}",
                            if particles { 0.2 } else { 0.0 }
                        ));
                    }
                }
            }
        }
        let path = dir.join(file);
        let csv = std::iter::once("grid,threads,particles,mlups,roofline_mlups".to_string())
            .chain(rows)
            .map(|r| r + "\n")
            .collect::<String>();
        std::fs::write(&path, csv).expect("csv");
        println!("wrote {}\n", path.display());
    }
}
