//! Friction through the drop-in's tangential spring, in the rapier pipeline: a box holds on a
//! slope below `atan μ_s` and slides above it at `g (sin θ − μ_k cos θ)`; a sphere rolls without
//! slipping at `5/7 g sin θ`; a sphere striking a wall obliquely rebounds as impulse theory
//! says when it slides throughout (Maw, Barber & Fawcett 1976, doi:10.1016/0043-1648(76)90203-3),
//! and when it sticks an elastic impact gives back its tangential energy as Hertz–Mindlin
//! contact says (what the elastic tangential compliance adds, which a slip-speed law cannot
//! show); over incident angles 5–85° an alumina sphere rebounds as the DEM benchmark of Chung &
//! Ooi (2011) tabulates Kharaz, Gorham & Salman's (2001) experiment.
//!
//! A slope is the floor under a tilted gravity: the same as a tilted floor, and the displacement
//! down the slope is the `x` coordinate.
#![cfg(feature = "rapier")]

use discrete_contact::math::Vector;
use discrete_contact::rapier::{DiscreteContacts, StepPolicy};
use discrete_contact::rapier3d_f64::prelude::*;
use discrete_contact::{Friction, IntegrationMode, Material, OverlapSettings, TangentialLaw};

const G: f64 = 9.81;

/// A body resting on the floor y = 0 under gravity tilted by `theta_deg` (down the slope = +x).
struct Slope {
    world: PhysicsWorld,
    contacts: DiscreteContacts,
    body: RigidBodyHandle,
}

fn slope(
    theta_deg: f64,
    collider: ColliderBuilder,
    height: f64,
    friction: Friction,
    law: TangentialLaw,
) -> Slope {
    let t = theta_deg.to_radians();
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(G * t.sin(), -G * t.cos(), 0.0);
    world.integration_parameters.dt = 1.0 / 240.0;
    let floor = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(floor));
    let body =
        world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, height, 0.0)));
    world.insert_collider(collider.density(1000.0), Some(body));
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap()
            .with_friction(friction)
            .with_tangential_law(law)
            .with_policy(StepPolicy::AutoSubstep { max_substeps: 1000 });
    // Rubber-like.
    contacts.handle_all(&mut world, Material::new(1e7, 0.45).unwrap()).unwrap();
    Slope { world, contacts, body }
}

impl Slope {
    /// Runs `seconds`; returns (time, x) every step.
    fn run(&mut self, seconds: f64) -> Vec<(f64, f64)> {
        let dt = self.world.integration_parameters.dt;
        let steps = (seconds / dt).round() as usize;
        (1..=steps)
            .map(|i| {
                self.contacts.step(&mut self.world).unwrap();
                (i as f64 * dt, self.world.bodies[self.body].translation().x)
            })
            .collect()
    }
}

fn box_on_slope(theta_deg: f64, law: TangentialLaw) -> Slope {
    slope(
        theta_deg,
        ColliderBuilder::cuboid(0.05, 0.05, 0.05),
        0.05,
        Friction::new(0.5, 0.4, 0.01).unwrap(),
        law,
    )
}

/// The least-squares acceleration `2 c` of `x ≈ a + b t + c t²` over the samples.
fn fitted_acceleration(samples: &[(f64, f64)]) -> f64 {
    let n = samples.len() as f64;
    let mean = |f: &dyn Fn(f64, f64) -> f64| samples.iter().map(|&(t, x)| f(t, x)).sum::<f64>() / n;
    let t0 = mean(&|t, _| t);
    // Centred powers keep the normal equations well conditioned.
    let (s1, s2) = (|t: f64| t - t0, |t: f64| (t - t0) * (t - t0));
    let m2 = mean(&|t, _| s2(t));
    let q = |t: f64| s2(t) - m2;
    let (sqq, sq1, s11) =
        (mean(&|t, _| q(t) * q(t)), mean(&|t, _| q(t) * s1(t)), mean(&|t, _| s1(t) * s1(t)));
    let (xq, x1) = (mean(&|t, x| q(t) * x), mean(&|t, x| s1(t) * x));
    let c = (xq * s11 - x1 * sq1) / (sqq * s11 - sq1 * sq1);
    2.0 * c
}

#[test]
fn a_box_holds_on_a_slope_below_the_friction_angle() {
    // tan 20° = 0.36 < μ_s = 0.5.
    let mut s = box_on_slope(20.0, TangentialLaw::Spring);
    let x = s.run(10.0);
    let at = |t: f64| x.iter().find(|p| p.0 >= t - 1e-9).unwrap().1;
    let (settled, end) = (at(0.5), at(10.0));
    // Settling into the spring's stretch takes a fraction of a millimetre, then it holds: the
    // grid's noise leaves a wander of micrometres, no creep (the slip-speed law: centimetres).
    assert!(end.abs() < 5e-4, "moved {end:e} m down the slope in 10 s");
    assert!((end - settled).abs() < 1e-4, "crept {:e} m from 0.5 s to 10 s", end - settled);
    let mean_speed = (end - at(8.0)) / 2.0;
    assert!(mean_speed.abs() < 2e-5, "still creeping at {mean_speed:e} m/s");
}

#[test]
fn the_slip_speed_law_lets_the_same_box_creep() {
    // The papers' law vanishes at zero slip: the contrast that makes the test above meaningful.
    let mut s = box_on_slope(20.0, TangentialLaw::SlipSpeed);
    let x = s.run(2.0);
    assert!(
        x.last().unwrap().1 > 1e-3,
        "the slip-speed law held the box: {:e} m",
        x.last().unwrap().1
    );
}

#[test]
fn a_box_slides_above_the_friction_angle_at_the_kinetic_rate() {
    // tan 35° = 0.70 > μ_s = 0.5: slides with g (sin θ − μ_k cos θ).
    let theta: f64 = 35.0;
    let mut s = box_on_slope(theta, TangentialLaw::Spring);
    let x = s.run(1.0);
    let sliding: Vec<(f64, f64)> = x.into_iter().filter(|p| p.0 >= 0.25).collect();
    let a = fitted_acceleration(&sliding);
    let t = theta.to_radians();
    let expected = G * (t.sin() - 0.4 * t.cos());
    assert!((a / expected - 1.0).abs() < 0.02, "a = {a} m/s², expected {expected}");
}

#[test]
fn a_sphere_rolls_down_a_slope_without_slipping() {
    // Rolling holds while tan θ < 7/2 μ_s = 1.75; a = 5/7 g sin θ.
    let theta: f64 = 20.0;
    let r = 0.05;
    let mut s = slope(
        theta,
        ColliderBuilder::ball(r),
        r,
        Friction::new(0.5, 0.4, 0.01).unwrap(),
        TangentialLaw::Spring,
    );
    let x = s.run(1.0);
    let rolling: Vec<(f64, f64)> = x.into_iter().filter(|p| p.0 >= 0.25).collect();
    let a = fitted_acceleration(&rolling);
    let expected = 5.0 / 7.0 * G * theta.to_radians().sin();
    assert!((a / expected - 1.0).abs() < 0.02, "a = {a} m/s², expected {expected}");
    // No slip: the contact point's speed is a small fraction of the centre's.
    let rb = &s.world.bodies[s.body];
    let slip = rb.linvel().x + rb.angvel().z * r;
    assert!(slip.abs() < 0.01 * rb.linvel().x, "slip {slip} m/s at {} m/s", rb.linvel().x);
}

/// A sphere striking the floor without spin: radius `radius`, density `density`, Young's
/// modulus and Poisson's ratio of the sphere against a rigid floor (`material`), incident
/// velocity `v_t` along the floor and `v_n` into it, μ_s = μ_k = `mu`, normal restitution
/// `restitution`.
struct Impact {
    radius: f64,
    density: f64,
    material: (f64, f64),
    v_t: f64,
    v_n: f64,
    mu: f64,
    restitution: f64,
}

/// Velocities after an [`Impact`]: along the floor, away from it, and the spin `ω'` about the
/// axis that rolls the sphere forwards (positive when it does).
struct Rebound {
    v_t: f64,
    v_n: f64,
    spin: f64,
}

fn oblique_impact(impact: &Impact) -> Rebound {
    let Impact { radius: r, density, material: (youngs, poisson), v_t, v_n, mu, restitution } =
        *impact;
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    // The contact lasts ~100 sub-steps of the automatic sub-stepping whatever the step.
    world.integration_parameters.dt = 1e-4;
    let floor = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(floor));
    let ball = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, r * 1.002, 0.0))
            .linvel(Vector::new(v_t, -v_n, 0.0)),
    );
    world.insert_collider(ColliderBuilder::ball(r).density(density), Some(ball));
    let mut contacts = DiscreteContacts::new(
        OverlapSettings::new(6, IntegrationMode::Subcell).unwrap(),
        restitution,
    )
    .unwrap()
    .with_friction(Friction::new(mu, mu, 1e-3).unwrap())
    .with_policy(StepPolicy::AutoSubstep { max_substeps: 5000 });
    // A rigid floor, as both bodies at twice the modulus: the same effective modulus
    // E / (1 − ν²) and the same tangential stiffness ratio 2 (1 − ν) / (2 − ν).
    contacts.handle_all(&mut world, Material::new(2.0 * youngs, poisson).unwrap()).unwrap();
    // Until the sphere moves away and no contact is live (a short impact begins and ends
    // within one step).
    for _ in 0..2000 {
        contacts.step(&mut world).unwrap();
        if world.bodies[ball].linvel().y > 0.0 && contacts.contact_count() == 0 {
            break;
        }
    }
    assert!(
        world.bodies[ball].linvel().y > 0.0 && contacts.contact_count() == 0,
        "the impact did not end"
    );
    let rb = &world.bodies[ball];
    Rebound { v_t: rb.linvel().x, v_n: rb.linvel().y, spin: -rb.angvel().z }
}

/// A 5 cm steel sphere (ν = 0.3) at 1 m/s normal speed and `tan_incidence` times that along the
/// floor; returns (v_n'/v_n, v_t'/v_n, R ω'/v_n).
fn steel_impact(tan_incidence: f64, mu: f64, restitution: f64) -> (f64, f64, f64) {
    let r = 0.05;
    let b = oblique_impact(&Impact {
        radius: r,
        density: 7800.0,
        material: (1e11, 0.3),
        v_t: tan_incidence,
        v_n: 1.0,
        mu,
        restitution,
    });
    (b.v_n, b.v_t, b.spin * r)
}

#[test]
fn an_oblique_impact_that_slides_throughout_follows_impulse_theory() {
    // tan θ = 4 > 7/2 μ (1 + e) ≈ 2: the contact slides all through the impact, so the
    // tangential impulse is μ times the normal one: v_t' = v_t − μ (1 + e) v_n and
    // R ω' = 5/2 μ (1 + e) v_n, with e the rebound's own normal restitution.
    let mu = 0.3;
    let (e, vt, rw) = steel_impact(4.0, mu, 0.9);
    assert!((e - 0.9).abs() < 0.02, "normal restitution {e}");
    let impulse = mu * (1.0 + e);
    assert!(
        (vt - (4.0 - impulse)).abs() < 0.01 * 4.0,
        "v_t'/v_n = {vt}, impulse theory {}",
        4.0 - impulse
    );
    assert!(
        (rw / (2.5 * impulse) - 1.0).abs() < 0.02,
        "R ω'/v_n = {rw}, impulse theory {}",
        2.5 * impulse
    );
}

#[test]
fn a_steep_elastic_impact_that_sticks_returns_its_tangential_energy() {
    // tan θ = 0.3, μ = 5: the contact sticks throughout. Rigid bodies with Coulomb friction would
    // end the impact rolling (contact point at rest); Mindlin's elastic tangential compliance
    // stores the tangential energy and gives it back. Hertz's normal law with Mindlin's no-slip
    // stiffness (k_t/k_n = 2(1 − ν)/(2 − ν), m_t = 2/7 m), integrated over the impact, sends the
    // contact point off at 0.955 of its incident tangential speed, in the same sense, for
    // ν = 0.3 (the tangential oscillation completes nearly one period in the contact time).
    let (e, vt, rw) = steel_impact(0.3, 5.0, 1.0);
    let contact_point = (vt - rw) / 0.3;
    assert!(
        (contact_point - 0.955).abs() < 0.03,
        "contact point leaves at {contact_point} of its incident speed"
    );
    // Elastic: the kinetic energy (per unit mass, with I = 2/5 m R²) comes back whole.
    let energy = |v2: f64, w2: f64| 0.5 * v2 + 0.5 * 0.4 * w2;
    let ratio = energy(e * e + vt * vt, rw * rw) / energy(1.0 + 0.09, 0.0);
    assert!((ratio - 1.0).abs() < 0.01, "kinetic energy after / before = {ratio}");
}

/// The oblique impact of an aluminium-oxide sphere on a flat wall at 3.9 m/s (Kharaz, Gorham &
/// Salman 2001, doi:10.1016/S0032-5910(01)00283-2), as tabulated for DEM codes by Chung & Ooi
/// 2011 (doi:10.1007/s10035-011-0277-0, test 4): R = 2.5 mm, E = 380 GPa, ν = 0.23,
/// ρ = 4000 kg/m³, μ = 0.092, e = 0.98, a rigid wall, no initial spin. Rows: incident angle
/// from the normal (°), tangential restitution `v_t'/v_t`, spin after the impact (rad/s, rolling
/// forwards), rebound angle of the contact point (°) — the values of Chung & Ooi's reference
/// curves.
const CHUNG_OOI_TEST_4: [(f64, f64, f64, f64); 13] = [
    (5.0, 0.948, 19.0, 3.76),
    (10.0, 0.687, 213.0, -1.56),
    (15.0, 0.624, 378.0, -5.54),
    (20.0, 0.616, 511.0, -7.54),
    (25.0, 0.634, 599.0, -7.54),
    (30.0, 0.684, 617.0, -3.55),
    (35.0, 0.737, 582.0, 3.43),
    (40.0, 0.781, 545.0, 11.57),
    (50.0, 0.845, 457.0, 29.35),
    (60.0, 0.893, 357.0, 47.79),
    (70.0, 0.932, 246.0, 64.58),
    (80.0, 0.966, 126.0, 78.70),
    (85.0, 0.983, 63.0, 84.52),
];

#[test]
fn oblique_impacts_rebound_as_the_dem_benchmark_tabulates() {
    // Below ~32° (tan θ < 7/2 μ (1 + e)) the contact sticks for part of the impact and the
    // tangential spring sends the contact point back (negative angles, least near 20–25°);
    // above, it slides throughout as impulse theory says. Tolerances: the references' angles
    // are digitised from plots (a few tenths of a degree).
    let (r, speed, mu, e) = (2.5e-3, 3.9, 0.092, 0.98);
    println!(
        "{:>6} {:>14} {:>18} {:>22}   (Chung & Ooi)",
        "θ (°)", "v_t'/v_t", "ω' (rad/s)", "contact angle (°)"
    );
    for &(theta, et_ref, spin_ref, phi_ref) in &CHUNG_OOI_TEST_4 {
        let (s, c) = theta.to_radians().sin_cos();
        let b = oblique_impact(&Impact {
            radius: r,
            density: 4000.0,
            material: (3.8e11, 0.23),
            v_t: speed * s,
            v_n: speed * c,
            mu,
            restitution: e,
        });
        let e_t = b.v_t / (speed * s);
        let phi = ((b.v_t - r * b.spin) / b.v_n).atan().to_degrees();
        println!("{theta:>6.0} {e_t:>7.3} ({et_ref:>5.3}) {:>9.1} ({spin_ref:>6.1}) {phi:>11.2} ({phi_ref:>6.2})", b.spin);
        assert!((e_t - et_ref).abs() <= 0.02, "θ = {theta}°: v_t'/v_t = {e_t}, tabulated {et_ref}");
        assert!(
            (b.spin - spin_ref).abs() <= 0.05 * 617.0,
            "θ = {theta}°: ω' = {} rad/s, tabulated {spin_ref}",
            b.spin
        );
        assert!(
            (phi - phi_ref).abs() <= 1.5,
            "θ = {theta}°: contact point leaves at {phi}°, tabulated {phi_ref}°"
        );
    }
}
