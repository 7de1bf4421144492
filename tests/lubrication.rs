//! The liquid film's force in the drop-in: Brenner's force on a ball closing in on a wall, a
//! force that only ever takes energy out, the wet impacts it decides — no rebound at a low
//! Stokes number, a rebound at a high one — and the sliding terms' drag and torque.
#![cfg(feature = "rapier")]

use discrete_contact::lubrication::Lubrication;
use discrete_contact::math::Vector;
use discrete_contact::rapier::DiscreteContacts;
use discrete_contact::rapier3d_f64::prelude::*;
use discrete_contact::{IntegrationMode, Material, OverlapSettings};

const RADIUS: f64 = 3e-3;
const CUTOFF: f64 = 1e-4;
const MIN_GAP: f64 = 1e-6;

/// A ball of `density` over a floor (half-space `y <= 0`), no gravity, its surface `gap` above
/// the floor and moving at `vy`, with the film of a liquid of viscosity `mu`; the ball's
/// collider inserted before the floor's when `ball_first`.
fn ball_over_floor(
    density: f64,
    gap: f64,
    vy: f64,
    mu: f64,
    ball_first: bool,
) -> (PhysicsWorld, DiscreteContacts, RigidBodyHandle) {
    ball_over_floor_with(density, gap, Vector::new(0.0, vy, 0.0), mu, ball_first, false)
}

/// The same moving at `v`, with the film's sliding terms when `shear`.
fn ball_over_floor_with(
    density: f64,
    gap: f64,
    v: Vector,
    mu: f64,
    ball_first: bool,
    shear: bool,
) -> (PhysicsWorld, DiscreteContacts, RigidBodyHandle) {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    world.integration_parameters.dt = 1e-5;
    let floor = world.insert_body(RigidBodyBuilder::fixed());
    let ball = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, RADIUS + gap, 0.0))
            .linvel(v)
            .can_sleep(false),
    );
    // Ball first and floor first: the pair's order must not matter.
    let insert_floor = |w: &mut PhysicsWorld| {
        w.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(floor))
    };
    if ball_first {
        world.insert_collider(ColliderBuilder::ball(RADIUS).density(density), Some(ball));
        insert_floor(&mut world);
    } else {
        insert_floor(&mut world);
        world.insert_collider(ColliderBuilder::ball(RADIUS).density(density), Some(ball));
    }
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.9)
            .unwrap()
            .with_lubrication(Lubrication::new(mu, CUTOFF, MIN_GAP).unwrap().with_shear(shear));
    contacts.handle_all(&mut world, Material::new(1e8, 0.3).unwrap()).unwrap();
    (world, contacts, ball)
}

/// A heavy ball closing in at a near-constant 1 cm/s feels Brenner's `6π μ R² v / h` less its
/// value at the cut-off, within 1 % over 0.9 … 0.05 of the cut-off (measured from its change of
/// momentum over one step, against the force at the step's start, where the drop-in takes it).
#[test]
fn a_ball_closing_in_on_a_wall_feels_brenners_force() {
    let mu = 0.1;
    let law = Lubrication::new(mu, CUTOFF, MIN_GAP).unwrap();
    for ball_first in [false, true] {
        let (mut world, mut contacts, ball) =
            ball_over_floor(1e7, 0.95 * CUTOFF, -0.01, mu, ball_first);
        let mut checked = 0;
        let dt = world.integration_parameters.dt;
        while world.bodies[ball].translation().y - RADIUS > 0.05 * CUTOFF {
            let (y0, v0) = (world.bodies[ball].translation().y, world.bodies[ball].linvel().y);
            contacts.step(&mut world).unwrap();
            let v1 = world.bodies[ball].linvel().y;
            let measured = world.bodies[ball].mass() * (v1 - v0) / dt;
            let gap = y0 - RADIUS;
            let expected = law.normal_force(gap, -v0, RADIUS);
            if gap < 0.9 * CUTOFF {
                assert!(
                    (measured - expected).abs() <= 0.01 * expected,
                    "gap {gap:.3e}: {measured:.5e} N against {expected:.5e} N"
                );
                checked += 1;
            }
        }
        assert!(checked > 100, "{checked} steps checked");
    }
}

/// The film always opposes the relative motion: a ball parting from the wall is held back, one
/// closing in is slowed, and its kinetic energy never grows.
#[test]
fn the_film_only_takes_energy_out() {
    for vy in [0.02, -0.02] {
        let (mut world, mut contacts, ball) =
            ball_over_floor(7800.0, 0.3 * CUTOFF, vy, 0.05, vy > 0.0);
        let mut speed = vy.abs();
        for _ in 0..200 {
            contacts.step(&mut world).unwrap();
            let v = world.bodies[ball].linvel();
            assert!(v.length() <= speed, "v = {vy}: speed grew from {speed} to {}", v.length());
            speed = v.length();
            if world.bodies[ball].translation().y - RADIUS >= CUTOFF {
                break;
            }
        }
        assert!(speed < vy.abs(), "v = {vy}: the film did nothing");
    }
}

/// Rebound speed over impact speed of a steel ball thrown at the wall from the cut-off at `v`
/// through a liquid of viscosity `mu` (the largest upward speed over 20 ms; 0 if none).
fn wet_restitution(v: f64, mu: f64) -> f64 {
    let (mut world, mut contacts, ball) = ball_over_floor(7800.0, CUTOFF, -v, mu, true);
    let mut up: f64 = 0.0;
    for _ in 0..2000 {
        contacts.step(&mut world).unwrap();
        up = up.max(world.bodies[ball].linvel().y);
    }
    up / v
}

/// With the film alone (no lattice), Stokes number `St = m v / (6π μ R²)`: the film takes
/// `ln(h_c/h_min)/St` of the speed on the way in and again on the way out (4.6/St here), so a
/// ball at St = 2 stops in the film without a rebound, one at St = 500 rebounds with nearly its
/// dry restitution (0.9, less 2 × 4.6/500).
#[test]
fn a_low_stokes_impact_does_not_rebound_and_a_high_one_does() {
    let m = 7800.0 * 4.0 / 3.0 * std::f64::consts::PI * RADIUS.powi(3);
    let mu_for = |st: f64, v: f64| m * v / (6.0 * std::f64::consts::PI * RADIUS * RADIUS * st);
    let low = wet_restitution(0.05, mu_for(2.0, 0.05));
    assert!(low < 0.01, "St = 2: e = {low}");
    let high = wet_restitution(0.05, mu_for(500.0, 0.05));
    assert!((0.8..0.92).contains(&high), "St = 500: e = {high}");
}

/// A ball sliding along a wall inside the film: Goldman, Cox & Brenner's drag `6π μ R (8/15)
/// ln(h_c/h) v` (measured from the change of momentum over a step, within 1 %), a torque that
/// sets it rolling the way it slides, kinetic energy (with the rotation's) that only falls,
/// whichever collider comes first; without the sliding terms it slides on untouched.
#[test]
fn a_ball_sliding_along_a_wall_is_dragged_and_set_rolling() {
    let (mu, gap, u) = (0.05, 0.3 * CUTOFF, 0.02);
    for ball_first in [false, true] {
        let v = Vector::new(u, 0.0, 0.0);
        let (mut world, mut contacts, ball) =
            ball_over_floor_with(7800.0, gap, v, mu, ball_first, true);
        let energy = |w: &PhysicsWorld| {
            let b = &w.bodies[ball];
            let i = b.mass_properties().local_mprops.principal_inertia();
            0.5 * b.mass() * b.linvel().length_squared() + 0.5 * (i * b.angvel()).dot(b.angvel())
        };
        let dt = world.integration_parameters.dt;
        let mut e = energy(&world);
        for step in 0..50 {
            let v0 = world.bodies[ball].linvel().x;
            let gap = world.bodies[ball].translation().y - RADIUS;
            contacts.step(&mut world).unwrap();
            let b = &world.bodies[ball];
            // From the second step on: the broad phase finds the pair in the first.
            if step == 1 {
                let measured = b.mass() * (b.linvel().x - v0) / dt;
                let expected = -6.0
                    * std::f64::consts::PI
                    * mu
                    * RADIUS
                    * (8.0 / 15.0)
                    * (CUTOFF / gap).ln()
                    * v0;
                assert!(
                    (measured - expected).abs() <= 0.01 * expected.abs(),
                    "{measured:.5e} N against {expected:.5e} N"
                );
            }
            assert!(
                step == 0 || b.angvel().z < 0.0,
                "step {step}: not rolling forward: {}",
                b.angvel()
            );
            let now = energy(&world);
            assert!(now <= e * (1.0 + 1e-12), "step {step}: energy grew from {e} to {now}");
            e = now;
        }
        assert!(world.bodies[ball].linvel().x < 0.999 * u);
    }
    let (mut world, mut contacts, ball) =
        ball_over_floor_with(7800.0, gap, Vector::new(u, 0.0, 0.0), mu, true, false);
    for _ in 0..50 {
        contacts.step(&mut world).unwrap();
    }
    assert_eq!(world.bodies[ball].linvel().x, u);
    assert_eq!(world.bodies[ball].angvel().z, 0.0);
}
