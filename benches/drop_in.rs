//! One full step (dt = 1/240 s, with its contact sub-steps) of the `drop_in` example's scene:
//! 108 bodies (three layers) after the first has landed (0.2 s simulated), with the discrete
//! contact (with its default geometry reuse, and evaluating every contact in full) and, for
//! scale, with rapier's own contacts. Iterations advance the scene.

use criterion::{criterion_group, criterion_main, Criterion};
use discrete_contact_validation::drop_in::{self, bin_scene};

const BODIES: usize = 108;
const WARM_STEPS: usize = 48;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("drop_in_step");
    group
        .sample_size(10)
        .measurement_time(std::time::Duration::from_secs(10))
        .warm_up_time(std::time::Duration::from_millis(500));

    let mut scene = bin_scene(BODIES);
    for _ in 0..WARM_STEPS {
        scene.world.step();
    }
    group.bench_function("rapier_contacts", |b| b.iter(|| scene.world.step()));

    let mut scene = bin_scene(BODIES);
    let mut contacts = drop_in::discrete_contacts(4, 6.0).unwrap();
    contacts.handle_all(&mut scene.world, drop_in::rubber().unwrap()).unwrap();
    for _ in 0..WARM_STEPS {
        contacts.step(&mut scene.world).unwrap();
    }
    eprintln!("{} contacts alive after {WARM_STEPS} steps", contacts.contact_count());
    group.bench_function("discrete_contacts_nc4", |b| {
        b.iter(|| contacts.step(&mut scene.world).unwrap())
    });

    // The same without geometry reuse: every live contact integrated in full on every sub-step.
    let mut scene = bin_scene(BODIES);
    let mut contacts =
        drop_in::discrete_contacts(4, 6.0).unwrap().with_geometry_reuse(0.0).unwrap();
    contacts.handle_all(&mut scene.world, drop_in::rubber().unwrap()).unwrap();
    for _ in 0..WARM_STEPS {
        contacts.step(&mut scene.world).unwrap();
    }
    group.bench_function("discrete_contacts_nc4_full_evaluations", |b| {
        b.iter(|| contacts.step(&mut scene.world).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
