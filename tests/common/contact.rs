//! Contact models and a drop on a wall shared by the contact-core tests (`physics`,
//! `geometry_reuse`, `exact_forms`); each test binary uses a part of them.
#![allow(dead_code)]

use discrete_contact::prelude::*;
use discrete_contact::ContactState;

pub fn settings(n: usize, mode: IntegrationMode) -> OverlapSettings {
    OverlapSettings::new(n, mode).unwrap()
}

pub fn model(mode: IntegrationMode, n: usize, e: f64) -> ContactModel {
    enlarged_model(mode, n, e, [0.0; 2])
}

/// [`model`] with the contact enlargement `ε_A, ε_B` (m).
pub fn enlarged_model(mode: IntegrationMode, n: usize, e: f64, [ea, eb]: [f64; 2]) -> ContactModel {
    let m = Material::new(1e8, 0.3).unwrap();
    let s = settings(n, mode).with_enlargement(ea, eb).unwrap();
    ContactModel::new(PairParameters::new(&m, &m, e).unwrap(), s)
}

/// A body dropped at 1 m/s on a wall (translation only), integrated with velocity Verlet
/// through the contact by `model`: (rebound speed, peak normal force, full evaluations, all
/// evaluations).
pub fn drop_on_wall(
    model: &ContactModel,
    shape: &ConvexShape,
    rotation: Rotation,
    lowest: f64,
    mass: f64,
) -> (f64, f64, usize, usize) {
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let wall = BodyState::at_rest(&floor, Pose::IDENTITY);
    let (mut y, mut v, dt) = (lowest + 1e-7, -1.0, 2e-7);
    let (mut state, mut peak, mut full, mut all) = (None, 0.0f64, 0, 0);
    let mut force = |y: f64, v: f64, state: &mut Option<ContactState>| {
        let body = BodyState::at_rest(shape, Pose::from_parts(Vector::new(0.0, y, 0.0), rotation))
            .moving(Vector::new(0.0, v, 0.0), Vector::ZERO);
        let out = model.evaluate(&body, &wall, state).unwrap();
        if let Some(o) = &out {
            (peak, full, all) =
                (peak.max(o.force.normal_force), full + usize::from(o.full()), all + 1);
        }
        out.map_or(0.0, |o| o.force.force_on_a.y)
    };
    let mut f = force(y, v, &mut state);
    let mut touched = false;
    for _ in 0..40000 {
        let v_half = v + 0.5 * dt * f / mass;
        y += dt * v_half;
        f = force(y, v_half, &mut state);
        v = v_half + 0.5 * dt * f / mass;
        touched |= state.is_some();
        if touched && state.is_none() {
            break;
        }
    }
    assert!(touched && state.is_none(), "contact did not end");
    (v, peak, full, all)
}
