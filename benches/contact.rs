//! Time per contact evaluation (overlap geometry + force) for five pair types, both
//! integration modes, N_c = 4, 8, 16: from the bodies' bounding boxes (a first touch, the most
//! expensive case), and as a persistent contact seeded with the previous sub-step's box; and
//! the sphere pair in closed form (`OverlapSettings::with_closed_form_spheres`), the cube and
//! rock pairs exactly (`OverlapSettings::with_exact_polyhedra`).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use discrete_contact::prelude::*;

#[path = "common/pairs.rs"]
mod pairs;
use pairs::pairs;

fn bench(c: &mut Criterion) {
    let m = Material::new(5e8, 0.35).unwrap();
    let params = PairParameters::new(&m, &m, 0.85).unwrap();
    let mut group = c.benchmark_group("contact_evaluation");
    group
        .sample_size(20)
        .measurement_time(std::time::Duration::from_secs(2))
        .warm_up_time(std::time::Duration::from_millis(300));
    for (name, sa, pa, sb, pb) in pairs() {
        for mode in [IntegrationMode::Count, IntegrationMode::Subcell] {
            for n in [4usize, 8, 16] {
                let model = ContactModel::new(params, OverlapSettings::new(n, mode).unwrap());
                let a =
                    BodyState::at_rest(&sa, pa).moving(Vector::new(0.0, -1.0, 0.0), Vector::ZERO);
                let b = BodyState::at_rest(&sb, pb);
                assert!(
                    model.evaluate(&a, &b, &mut None).unwrap().is_some(),
                    "{name} must overlap"
                );
                group.bench_with_input(
                    BenchmarkId::new(format!("{name}/{}", mode.name()), n),
                    &n,
                    |bch, _| bch.iter(|| model.evaluate(&a, &b, &mut None).unwrap()),
                );
                // A persistent contact: last sub-step's corrected box seeds the search.
                let mut state = None;
                model.evaluate(&a, &b, &mut state).unwrap();
                group.bench_with_input(
                    BenchmarkId::new(format!("{name}/{}/persistent", mode.name()), n),
                    &n,
                    |bch, _| {
                        bch.iter(|| {
                            let mut s = state;
                            model.evaluate(&a, &b, &mut s).unwrap()
                        })
                    },
                );
            }
        }
    }
    // The exact forms: sphere pair in closed form, cube and rock pairs as the clipped polyhedron.
    let exact = OverlapSettings::new(8, IntegrationMode::Subcell)
        .unwrap()
        .with_closed_form_spheres(true)
        .with_exact_polyhedra(true);
    let model = ContactModel::new(params, exact);
    for (name, sa, pa, sb, pb) in
        pairs().into_iter().filter(|p| ["sphere_sphere", "cube_cube", "hull_hull"].contains(&p.0))
    {
        let a = BodyState::at_rest(&sa, pa).moving(Vector::new(0.0, -1.0, 0.0), Vector::ZERO);
        let b = BodyState::at_rest(&sb, pb);
        let mut state = None;
        model.evaluate(&a, &b, &mut state).unwrap();
        group.bench_function(format!("{name}/exact/persistent"), |bch| {
            bch.iter(|| {
                let mut s = state;
                model.evaluate(&a, &b, &mut s).unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
