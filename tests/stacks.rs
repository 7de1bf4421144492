//! Stacks built as rapier's own examples build them — boxes exactly touching on a ground box,
//! rapier's `length_unit` at their size, 60 Hz — at the stiffnesses where explicitly
//! integrated contacts blew up while every step returned `Ok`: each stands now, and never
//! gains energy. And random stacks of any size, stiffness and step: no step returns `Ok` with
//! energy created.

use discrete_contact::math::{Real, Vector};
use discrete_contact::rapier::{FailedStep, StepPolicy};
use discrete_contact::rapier3d_f64::prelude::*;
use discrete_contact::{Error, Friction, IntegrationMode, Material, OverlapSettings};
use discrete_contact_validation::stacks::{self, mechanical_energy, Outcome, Scene};
use proptest::prelude::*;

/// A scene run for one second at Young's modulus `youngs` must stand (every body within a
/// tenth of its size of where it began, at rest at the end) without its energy rising above
/// where it began by more than a hundredth of what one box's fall through its own height
/// gives.
fn stands(scene: Scene, youngs: Real, length_unit: Option<Real>) {
    let built = stacks::build_at(scene, length_unit);
    let (size, weight) = (built.size, 1000.0 * 0.1f64.powi(3) * 9.81);
    let contacts = stacks::discrete_contacts(100_000).unwrap();
    let run = stacks::run_built(scene, built, 1.0, youngs, contacts, false).unwrap();
    assert_eq!(run.outcome, Outcome::Stands, "{} at {youngs:e} Pa", scene.name());
    assert!(
        run.energy_gain < 0.01 * weight * size,
        "{} at {youngs:e} Pa gained {:e} J",
        scene.name(),
        run.energy_gain
    );
}

/// Explicit contacts: the top box thrown ~15 m up, 1.4e3 J at 1 s.
#[test]
fn a_pyramid_of_55_boxes_stands_at_1e8_pa() {
    stands(Scene::Pyramid { base: 10 }, 1e8, None);
}

/// Explicit contacts, rapier's `length_unit` left at 1 m: 5e4 J.
#[test]
fn a_pyramid_of_10_boxes_stands_at_1e9_pa_at_rapiers_default_length_unit() {
    stands(Scene::Pyramid { base: 4 }, 1e9, Some(1.0));
}

/// Explicit contacts: 6.6e2 J.
#[test]
fn a_pyramid_of_10_boxes_stands_at_1e10_pa() {
    stands(Scene::Pyramid { base: 4 }, 1e10, None);
}

/// Steel, and a tower of crossed planks.
#[test]
fn steel_pyramids_and_a_plank_tower_stand() {
    stands(Scene::Pyramid { base: 4 }, 2e11, None);
    stands(Scene::PlankTower { layers: 8 }, 2e11, None);
}

/// Cases of the random-stack property (each runs a stack for up to 40 steps): `PROPTEST_CASES`
/// raises it for a soak; a fixed seed unless `PROPTEST_RNG_SEED` gives one.
fn config() -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(12);
    let defaults = ProptestConfig::default();
    let rng_seed = if std::env::var_os("PROPTEST_RNG_SEED").is_some() {
        defaults.rng_seed
    } else {
        proptest::test_runner::RngSeed::Fixed(0x57ac_0001)
    };
    ProptestConfig { cases, failure_persistence: None, rng_seed, ..defaults }
}

proptest! {
    #![proptest_config(config())]

    /// A stack released at rest — `count` boxes of half-size `half` (1–20 cm, each a little
    /// narrower than the one below it, shifted up to a quarter of its width), Young's modulus
    /// from 1e6 to 2e11 Pa, a step from 1/240 to 1/30 s — never returns `Ok` from a step whose
    /// world has more mechanical energy than it began with, beyond the step check's floor
    /// (every box at a quarter of the rest speed: what gravity gives in two steps). A step
    /// may be refused; it must not pass with energy created.
    #[test]
    fn random_stacks_never_gain_energy(
        count in 1usize..8,
        half in 0.01f64..0.2,
        log_youngs in 6.0f64..11.3,
        rate in prop::sample::select(vec![240.0, 120.0, 60.0, 30.0]),
        shifts in prop::collection::vec(-0.25f64..0.25, 8),
        narrowing in 0.8f64..1.0,
    ) {
        let dt = 1.0 / rate;
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = dt;
        world.integration_parameters.length_unit = 2.0 * half;
        let ground = world.insert_body(RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.1, 0.0)));
        world.insert_collider(ColliderBuilder::cuboid(10.0, 0.1, 10.0), Some(ground));
        let mut bodies = Vec::new();
        let (mut y, mut size) = (0.0, half);
        for k in 0..count {
            let x = shifts[k] * size;
            let b = world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(x, y + size, 0.0)));
            world.insert_collider(ColliderBuilder::cuboid(size, size, size).density(1000.0), Some(b));
            bodies.push(b);
            y += 2.0 * size;
            size *= narrowing;
        }
        let mut contacts = discrete_contact::rapier::DiscreteContacts::new(
            OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(),
            0.5,
        )
        .unwrap()
        .with_friction(Friction::new(0.6, 0.5, 1e-3).unwrap())
        .with_policy(StepPolicy::AutoSubstep { max_substeps: 100_000 })
        .with_failed_step(FailedStep::Redo);
        contacts.handle_all(&mut world, Material::new(10f64.powf(log_youngs), 0.3).unwrap()).unwrap();
        let start = mechanical_energy(&world, &bodies);
        let rest_speed = 2.0 * 9.81 * dt;
        let floor: Real = bodies
            .iter()
            .map(|b| 0.5 * world.bodies[*b].mass() * (0.25 * rest_speed).powi(2))
            .sum::<Real>()
            .max(1e-12);
        for step in 0..40 {
            match contacts.step(&mut world) {
                Ok(_) => {
                    let gain = mechanical_energy(&world, &bodies) - start;
                    prop_assert!(
                        gain <= floor,
                        "step {step}: {gain:e} J gained (floor {floor:e} J), {count} boxes of {half} m, E = {:e} Pa, dt = {dt}",
                        10f64.powf(log_youngs)
                    );
                }
                Err(Error::StepRejected { .. }) | Err(Error::TimeStepTooLarge { .. }) => break,
                Err(e) => prop_assert!(false, "step {step}: {e}"),
            }
        }
    }
}
