//! The stability cases in one rapier build: its parent module names the rapier crate `engine`
//! and the drop-in `drop_in`. Written once for both builds, so conversions between the
//! cases' f64 and rapier's numbers are identities in the f64 build.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use super::drop_in::{DiscreteContacts, StepPolicy};
use super::engine::math::{Pose, Real, Rotation, Vector};
use super::engine::prelude::{
    ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle, SharedShape,
};

use super::super::{Case, Verdict, BOX, RADIUS};
use discrete_contact::error::Result;
use discrete_contact::material::{effective_modulus, Material};
use discrete_contact::overlap::{IntegrationMode, OverlapSettings};

/// Runs `case` (see [`Case::run_in`]): its verdict, error and largest sub-step count.
pub(crate) fn run(case: &Case) -> Result<(Verdict, f64, usize)> {
    run_inner(case)
}

fn run_inner(case: &Case) -> Result<(Verdict, f64, usize)> {
    let r = RADIUS as Real;
    let settings = OverlapSettings::new(4, IntegrationMode::Subcell)?;
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    world.integration_parameters.dt = 1e-4;
    let wall = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(wall));
    let sphere = |world: &mut PhysicsWorld, y: Real, v: Vector, density: Real| -> RigidBodyHandle {
        let b = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, y, 0.0))
                .linvel(v)
                .can_sleep(false),
        );
        world.insert_collider(ColliderBuilder::ball(r).density(density), Some(b));
        b
    };
    let (e, youngs, policy) = match *case {
        Case::NormalImpact { youngs, restitution, .. } => {
            (restitution, youngs, StepPolicy::AutoSubstep { max_substeps: 100_000 })
        }
        Case::RefusedStep => (0.85, 2e11, StepPolicy::Fixed { substeps: 1 }),
        _ => (0.85, 5e8, StepPolicy::AutoSubstep { max_substeps: 100_000 }),
    };
    let mut contacts = DiscreteContacts::new(settings, e)?.with_policy(policy);
    let speed_in = match *case {
        Case::NormalImpact { speed, .. } => speed,
        Case::RefusedStep => 30.0,
        _ => 1.0,
    };
    // (body, normal along which the rebound is measured, approach speed along it)
    let (body, normal, v_n) = match *case {
        Case::NormalImpact { .. } | Case::RefusedStep => (
            sphere(&mut world, r + 1e-6, Vector::new(0.0, -speed_in as Real, 0.0), 7800.0),
            Vector::Y,
            speed_in,
        ),
        Case::Grazing => {
            let a = 89f64.to_radians();
            let v = Vector::new(a.sin() as Real, -a.cos() as Real, 0.0);
            (sphere(&mut world, r + 1e-7, v, 7800.0), Vector::Y, a.cos())
        }
        Case::MassRatio { ratio } => {
            // Free space: B at rest far from the wall, A coming at 1 m/s along -x.
            let b = world.insert_body(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(0.0, 1.0, 0.0))
                    .can_sleep(false),
            );
            world.insert_collider(ColliderBuilder::ball(r).density(7800.0), Some(b));
            let a = world.insert_body(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(2.0 * r + 1e-6, 1.0, 0.0))
                    .linvel(Vector::new(-1.0, 0.0, 0.0))
                    .can_sleep(false),
            );
            world
                .insert_collider(ColliderBuilder::ball(r).density(7800.0 * ratio as Real), Some(a));
            contacts.handle_all(&mut world, Material::new(youngs, 0.3)?)?;
            return two_body(&mut world, &mut contacts, a, b, e);
        }
        Case::ThinPlate => {
            let b = world.insert_body(
                RigidBodyBuilder::dynamic()
                    .pose(Pose::from_parts(
                        Vector::new(0.0, 0.0005 + 1e-6, 0.0),
                        Rotation::IDENTITY,
                    ))
                    .linvel(Vector::new(0.0, -1.0, 0.0))
                    .can_sleep(false),
            );
            world.insert_collider(
                ColliderBuilder::cuboid(0.025, 0.0005, 0.025).density(2700.0),
                Some(b),
            );
            (b, Vector::Y, 1.0)
        }
        Case::Resting { steps, dt } => {
            world.gravity = Vector::new(0.0, -9.81, 0.0);
            world.integration_parameters.dt = dt as Real;
            let b = sphere(&mut world, r, Vector::ZERO, 7800.0);
            // The contact law's own rest, to a nanometre: every sub-step evaluated in full.
            // Geometry reuse re-anchors the force at each full evaluation, a jump of the
            // grid's noise that a frictionless ball does not damp out at this level.
            let mut contacts = contacts.with_geometry_reuse(0.0)?;
            let material = Material::new(5e8, 0.3)?;
            contacts.handle_all(&mut world, material)?;
            return resting(
                &mut world,
                &mut contacts,
                b,
                steps,
                effective_modulus(&material, &material),
            );
        }
        Case::Ramp { seconds } => return boxes(seconds, true),
        Case::Pyramid { seconds } => return boxes(seconds, false),
    };
    contacts.handle_all(&mut world, Material::new(youngs, 0.3)?)?;
    let ke0 = 0.5 * world.bodies[body].mass() as f64 * speed_in * speed_in;
    let mut touched = false;
    let mut substeps = 0;
    let mut lowest = Real::INFINITY;
    // Long enough for the slowest, softest contact to end.
    for _ in 0..200_000 {
        let s = contacts.step(&mut world)?;
        substeps = substeps.max(s.substeps);
        let rb = &world.bodies[body];
        lowest = lowest.min(rb.translation().y);
        if !rb.translation().is_finite() {
            return Ok((Verdict::Failed("non-finite state".into()), f64::NAN, substeps));
        }
        // A stiff contact can begin and end within one step: its depth tells it was there.
        touched |= s.max_indentation > 0.0 || s.contacts > 0;
        if touched && s.contacts == 0 {
            break;
        }
    }
    let rb = &world.bodies[body];
    let ke1 = (0.5 * rb.mass() * rb.linvel().length_squared()
        + 0.5 * rb.angvel().dot(rb.angvel()) * rb.mass() * r * r * 0.4) as f64;
    let e_meas = rb.linvel().dot(normal) as f64 / v_n;
    if !touched {
        return Ok((Verdict::Failed("no contact".into()), f64::NAN, substeps));
    }
    if lowest < 0.0 {
        return Ok((
            Verdict::Failed(format!("tunnelled (centre at {lowest:e} m)")),
            f64::NAN,
            substeps,
        ));
    }
    // Sub-stepped symplectic Euler errs by O(Δt_c / t_H) per contact: with >= 30 sub-steps
    // an elastic rebound comes out up to ~0.6 % fast; more than 1 % is a failure.
    if ke1 > ke0 * (1.0 + 1e-2) {
        return Ok((
            Verdict::Failed(format!("energy created ({:.3}×)", ke1 / ke0)),
            f64::NAN,
            substeps,
        ));
    }
    let err = (e_meas / e - 1.0).abs();
    let verdict =
        if err <= 0.05 { Verdict::Ok } else { Verdict::Failed(format!("e = {e_meas:.4}")) };
    Ok((verdict, err, substeps))
}

fn two_body(
    world: &mut PhysicsWorld,
    contacts: &mut DiscreteContacts,
    a: RigidBodyHandle,
    b: RigidBodyHandle,
    e: f64,
) -> Result<(Verdict, f64, usize)> {
    let p0 = world.bodies[a].mass() * world.bodies[a].linvel()
        + world.bodies[b].mass() * world.bodies[b].linvel();
    let mut touched = false;
    let mut substeps = 0;
    for _ in 0..200_000 {
        let s = contacts.step(world)?;
        substeps = substeps.max(s.substeps);
        touched |= s.max_indentation > 0.0 || s.contacts > 0;
        if touched && s.contacts == 0 {
            break;
        }
    }
    let (ra, rb) = (&world.bodies[a], &world.bodies[b]);
    let p1 = ra.mass() * ra.linvel() + rb.mass() * rb.linvel();
    let e_meas = (rb.linvel().x - ra.linvel().x) as f64 / 1.0;
    // Conserved to the round-off of rapier's numbers.
    let tolerance = (1e-9 as Real).max(100.0 * Real::EPSILON);
    if (p1 - p0).length() > tolerance * p0.length() {
        return Ok((Verdict::Failed(format!("momentum {p0:?} → {p1:?}")), f64::NAN, substeps));
    }
    let err = (-e_meas / e - 1.0).abs();
    Ok((
        if err <= 0.05 { Verdict::Ok } else { Verdict::Failed(format!("e = {:.4}", -e_meas)) },
        err,
        substeps,
    ))
}

/// The ramp (`ramp`) or the pyramid, left standing for `seconds` at 240 steps per second
/// under gravity; the error is the watched box's displacement from 0.5 s (once it has
/// settled into its contacts) to the end.
fn boxes(seconds: f64, ramp: bool) -> Result<(Verdict, f64, usize)> {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = 1.0 / 240.0;
    let (side, h) = (BOX as Real, 0.5 * BOX as Real);
    let fixed = world.insert_body(RigidBodyBuilder::fixed());
    let add_box = |world: &mut PhysicsWorld, pose: Pose| -> RigidBodyHandle {
        let b = world.insert_body(RigidBodyBuilder::dynamic().pose(pose).can_sleep(false));
        world.insert_collider(ColliderBuilder::cuboid(h, h, h).density(1000.0), Some(b));
        b
    };
    let watched = if ramp {
        let tilt = Rotation::from_rotation_z((20.0 as Real).to_radians());
        world.insert_collider(
            ColliderBuilder::cuboid(1.0, 0.1, 0.5).position(Pose::from_parts(Vector::ZERO, tilt)),
            Some(fixed),
        );
        add_box(&mut world, Pose::from_parts(tilt * Vector::new(0.0, 0.1 + h, 0.0), tilt))
    } else {
        world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(fixed));
        let mut top = None;
        for row in 0..4 {
            for i in 0..4 - row {
                let x = (i as Real - 0.5 * (3 - row) as Real) * (side + 1e-3);
                top = Some(add_box(
                    &mut world,
                    Pose::from_translation(Vector::new(x, h + row as Real * side, 0.0)),
                ));
            }
        }
        top.expect("four rows")
    };
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell)?, 0.5)?
            .with_friction(discrete_contact::material::Friction::new(0.5, 0.4, 0.01)?)
            .with_policy(StepPolicy::AutoSubstep { max_substeps: 1000 });
    contacts.handle_all(&mut world, Material::new(1e7, 0.45)?)?;
    let steps = (seconds * 240.0).round() as usize;
    let (mut substeps, mut settled) = (0, None);
    for k in 0..steps {
        substeps = substeps.max(contacts.step(&mut world)?.substeps);
        if k + 1 == 120 {
            settled = Some(world.bodies[watched].translation());
        }
    }
    let at = world.bodies[watched].translation();
    if !at.is_finite() {
        return Ok((Verdict::Failed("non-finite state".into()), f64::NAN, substeps));
    }
    let drift = (at - settled.unwrap_or(at)).length() as f64;
    // Held: creeping below 1 mm/s after settling. Nassauer & Kuna's slip-speed law fails it
    // on the ramp (about 7 mm/s); rapier's own contacts hold the ramp's box to 0.03 mm/s.
    let creep = drift / (seconds - 0.5);
    let verdict =
        if creep < 1e-3 { Verdict::Ok } else { Verdict::Failed(format!("creeps {creep:e} m/s")) };
    Ok((verdict, drift, substeps))
}

/// The sphere `b` (`e_star` against the floor) left resting for `steps` steps.
fn resting(
    world: &mut PhysicsWorld,
    contacts: &mut DiscreteContacts,
    b: RigidBodyHandle,
    steps: usize,
    e_star: f64,
) -> Result<(Verdict, f64, usize)> {
    let dt = world.integration_parameters.dt as f64;
    let mut substeps = 0;
    let mut y_half = 0.0;
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for k in 0..steps {
        let s = contacts.step(world)?;
        substeps = substeps.max(s.substeps);
        let y = world.bodies[b].translation().y;
        if k == steps / 2 {
            y_half = y;
        }
        if k >= steps / 2 {
            lo = lo.min(y);
            hi = hi.max(y);
        }
    }
    let rb = &world.bodies[b];
    let drift =
        (rb.translation().y - y_half).abs().max(hi - lo).max(rb.translation().x.abs()) as f64;
    // The static Hertz indentation under the sphere's weight, d = (3 m g / (4 E* √R))^(2/3).
    let r = RADIUS;
    let weight = rb.mass() as f64 * world.gravity.length() as f64;
    let d_hertz = (3.0 * weight / (4.0 * e_star * r.sqrt())).powf(2.0 / 3.0);
    let d = r - rb.translation().y as f64;
    // Tolerances: drift or jitter over the second half below 1 % of the static indentation
    // (1.3 µm here), the indentation itself within 5 % of Hertz (sub-cell N_c = 4 errs by
    // ~3 % on a sphere), and at rest.
    // At rest: below 1 µm/s, or below what moves the ball by one spacing of its coordinates
    // per sub-step, the slowest speed rapier's numbers hold as motion (f32: 19 µm/s here).
    let spacing = Real::EPSILON as f64 * (r as Real).log2().floor().exp2() as f64;
    let resting_speed = (1e-6 as f64).max(spacing * substeps as f64 / dt);
    let ok = drift < 0.01 * d_hertz
        && (d / d_hertz - 1.0).abs() < 0.05
        && (rb.linvel().length() as f64) < resting_speed;
    let verdict = if ok {
        Verdict::Ok
    } else {
        Verdict::Failed(format!(
            "drift {drift:e} m, indentation {d:e} m (Hertz {d_hertz:e}), |v| {:e}",
            rb.linvel().length()
        ))
    };
    Ok((verdict, drift, substeps))
}
