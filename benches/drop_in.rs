//! One full step (dt = 1/240 s, with its contact sub-steps) of the `drop_in` example's scene:
//! 108 bodies (three layers) after the first has landed (0.2 s simulated), with the discrete
//! contact and, for scale, with rapier's own contacts. Iterations advance the scene.

use criterion::{criterion_group, criterion_main, Criterion};
use discrete_contact::rapier::{DiscreteContacts, StepPolicy};
use discrete_contact::validation::drop_in::bin_scene;
use discrete_contact::{Friction, IntegrationMode, Material, OverlapSettings};

const BODIES: usize = 108;
const WARM_STEPS: usize = 48;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("drop_in_step");
    group.sample_size(10).measurement_time(std::time::Duration::from_secs(10)).warm_up_time(std::time::Duration::from_millis(500));

    let mut scene = bin_scene(BODIES);
    for _ in 0..WARM_STEPS {
        scene.world.step();
    }
    group.bench_function("rapier_contacts", |b| b.iter(|| scene.world.step()));

    let mut scene = bin_scene(BODIES);
    let mut contacts = DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
        .unwrap()
        .with_friction(Friction::new(0.5, 0.4, 0.01).unwrap())
        .with_substeps_per_contact(6.0)
        .unwrap()
        .with_policy(StepPolicy::AutoSubstep { max_substeps: 1000 });
    contacts.handle_all(&mut scene.world, Material::new(5e6, 0.4).unwrap()).unwrap();
    for _ in 0..WARM_STEPS {
        contacts.step(&mut scene.world).unwrap();
    }
    eprintln!("{} contacts alive after {WARM_STEPS} steps", contacts.contact_count());
    group.bench_function("discrete_contacts_nc4", |b| b.iter(|| contacts.step(&mut scene.world).unwrap()));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
