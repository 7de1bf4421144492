//! The lattice kernel: one block collision (in cache), and full steps of periodic boxes with
//! and without particle nodes (spheres of radius 4 covering ~20 % of the nodes, their forces
//! measured by the forcing momentum and by the momentum exchange), on 1 and 2 threads; and the
//! plain fluid with f32 population storage. Criterion reports time per step; MLUPs = cells /
//! time. The spheres stay where they are, so the exchange finds its links once (the `moving`
//! row of `lbm_throughput` times them found again every step).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use hlbm::d3q19::{collide, LANES, Q, W};
use hlbm::{ForceMethod, Lattice, Storage};

fn block(c: &mut Criterion) {
    let mut blk = [[0.0f64; LANES]; Q];
    for i in 0..Q {
        for l in 0..LANES {
            blk[i][l] = W[i] * (1.0 + 1e-3 * l as f64);
        }
    }
    let du = [[1e-4; LANES]; 3];
    let mut g = c.benchmark_group("collide_block");
    g.throughput(Throughput::Elements(LANES as u64));
    g.bench_function("plain", |b| {
        b.iter(|| collide(std::hint::black_box(&mut blk), 1.0 / 0.6, None))
    });
    g.bench_function("forced", |b| {
        b.iter(|| collide(std::hint::black_box(&mut blk), 1.0 / 0.6, Some(&du)))
    });
    g.finish();
}

fn covered(lat: &mut Lattice) {
    let [nx, ny, nz] = lat.dims();
    // Spheres of radius 4 on a 12-cell grid: ~20 % particle nodes.
    let centres = |n: usize| (0..n / 12).map(|i| 12.0 * i as f64 + 6.3);
    let mut id = 0;
    for cz in centres(nz) {
        for cy in centres(ny) {
            for cx in centres(nx) {
                lat.particles_mut()
                    .add_sphere([cx, cy, cz], 4.0, 1.0, [1e-3, 0.0, 0.0], id)
                    .expect("a sphere inside the lattice");
                id += 1;
            }
        }
    }
}

fn steps(c: &mut Criterion) {
    let mut g = c.benchmark_group("lattice_step");
    g.sample_size(10).measurement_time(std::time::Duration::from_secs(3));
    for n in [64usize, 128] {
        g.throughput(Throughput::Elements((n * n * n) as u64));
        for threads in [1usize, 2] {
            let cases = [
                ("fluid", None, Storage::F64),
                ("forcing", Some(ForceMethod::Forcing), Storage::F64),
                ("exchange", Some(ForceMethod::MomentumExchange), Storage::F64),
                ("fluid_f32", None, Storage::F32),
            ];
            for (name, method, storage) in cases {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let mut lat = Lattice::new(n, n, n, 0.6).unwrap();
                lat.set_storage(storage);
                if let Some(method) = method {
                    lat.set_force_method(method);
                    covered(&mut lat);
                }
                let id = format!("{n}^3/{threads}t/{name}");
                g.bench_function(BenchmarkId::from_parameter(id), |b| {
                    b.iter(|| pool.install(|| lat.step().unwrap()))
                });
            }
        }
    }
    g.finish();
}

criterion_group!(benches, block, steps);
criterion_main!(benches);
