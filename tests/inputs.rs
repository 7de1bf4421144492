//! Every bad parameter is refused with a typed error naming it; nothing panics or yields NaN.

use discrete_contact::prelude::*;
use discrete_contact::{damping_from_restitution, Error};

fn names(e: Error) -> &'static str {
    match e {
        Error::InvalidParameter { name, .. } => name,
        other => panic!("expected InvalidParameter, got {other:?}"),
    }
}

#[test]
fn material_parameters() {
    for e in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(names(Material::new(e, 0.3).unwrap_err()), "youngs_modulus");
    }
    for nu in [-0.01, 0.51, f64::NAN] {
        assert_eq!(names(Material::new(1e9, nu).unwrap_err()), "poisson_ratio");
    }
    assert!(Material::new(1e9, 0.0).is_ok() && Material::new(1e9, 0.5).is_ok());
    let msg = Material::new(-5.0, 0.3).unwrap_err().to_string();
    assert!(msg.contains("youngs_modulus") && msg.contains("> 0"), "{msg}");
}

#[test]
fn restitution_friction_and_resolution() {
    let m = Material::new(1e9, 0.3).unwrap();
    for e in [0.0, -0.5, 1.01, f64::NAN] {
        assert_eq!(names(PairParameters::new(&m, &m, e).unwrap_err()), "restitution");
        assert_eq!(names(damping_from_restitution(e, 1.0).unwrap_err()), "restitution");
    }
    assert_eq!(names(damping_from_restitution(0.5, 0.0).unwrap_err()), "approach_speed");
    assert_eq!(names(Friction::new(0.2, 0.3, 1e-3).unwrap_err()), "static_coefficient");
    assert_eq!(names(Friction::new(0.3, -0.1, 1e-3).unwrap_err()), "kinetic_coefficient");
    assert_eq!(names(Friction::new(0.3, 0.2, 0.0).unwrap_err()), "transition_speed");
    assert_eq!(names(Friction::new(f64::NAN, 0.2, 1.0).unwrap_err()), "static_coefficient");
    assert_eq!(names(OverlapSettings::new(0, IntegrationMode::Count).unwrap_err()), "n_c");
    let s = OverlapSettings::new(4, IntegrationMode::Count).unwrap();
    assert_eq!(names(s.with_enlargement(-1e-3, 0.0).unwrap_err()), "enlargement_a");
    let p = PairParameters::new(&m, &m, 0.5).unwrap();
    assert_eq!(
        names(p.with_stiffness(StiffnessFactor::Custom(0.0)).unwrap_err()),
        "stiffness factor k"
    );
    assert_eq!(names(p.with_min_approach_speed(-1.0).unwrap_err()), "min_approach_speed");
    for m_t in [0.0, -1.0, f64::NAN] {
        assert_eq!(names(p.with_tangential_mass(m_t).unwrap_err()), "tangential_mass");
    }
}

#[test]
fn shape_sizes() {
    assert_eq!(names(ConvexShape::ball(0.0).unwrap_err()), "radius");
    assert_eq!(names(ConvexShape::ball(f64::NAN).unwrap_err()), "radius");
    assert_eq!(names(ConvexShape::cylinder(-1.0, 1.0).unwrap_err()), "half_height");
    assert_eq!(
        names(ConvexShape::cuboid(Vector::new(1.0, 0.0, 1.0)).unwrap_err()),
        "half_extents.y"
    );
    assert_eq!(names(ConvexShape::half_space(Vector::ZERO).unwrap_err()), "normal");
    assert!(matches!(
        ConvexShape::capsule(Vector::splat(f64::NAN), Vector::ZERO, 1.0),
        Err(Error::NonFinite { .. })
    ));
    assert!(ConvexShape::convex_hull(&[Vector::ZERO, Vector::X, Vector::Y]).is_err());
}

#[test]
fn non_finite_states_and_unbounded_pairs() {
    let ball = ConvexShape::ball(0.1).unwrap();
    let m = Material::new(1e9, 0.3).unwrap();
    let model = ContactModel::new(
        PairParameters::new(&m, &m, 0.5).unwrap(),
        OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(),
    );
    let ok = BodyState::at_rest(&ball, Pose::IDENTITY);
    let nan_pose =
        BodyState::at_rest(&ball, Pose::from_translation(Vector::new(f64::NAN, 0.0, 0.0)));
    assert!(matches!(model.evaluate(&nan_pose, &ok, &mut None), Err(Error::NonFinite { .. })));
    let nan_vel = BodyState::at_rest(&ball, Pose::IDENTITY)
        .moving(Vector::new(0.0, f64::INFINITY, 0.0), Vector::ZERO);
    assert!(matches!(model.evaluate(&ok, &nan_vel, &mut None), Err(Error::NonFinite { .. })));
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let wall = ConvexShape::half_space(Vector::X).unwrap();
    let (f, w) =
        (BodyState::at_rest(&floor, Pose::IDENTITY), BodyState::at_rest(&wall, Pose::IDENTITY));
    assert!(matches!(model.evaluate(&f, &w, &mut None), Err(Error::UnboundedOverlap { .. })));
    // Hostile but finite sizes give finite results.
    for r in [1e-9, 1e6] {
        let b = ConvexShape::ball(r).unwrap();
        let a = BodyState::at_rest(&b, Pose::from_translation(Vector::new(0.0, 0.99 * r, 0.0)));
        let out = model.evaluate(&a, &f, &mut None).unwrap().unwrap();
        assert!(out.force.force_on_a.is_finite() && out.force.force_on_a.y > 0.0, "r = {r}");
    }
}

/// An evaluation refused for bad input leaves a live contact's state as it was: a caller may
/// fix the input and go on with the contact's history (damping, tangential spring, reference).
#[test]
fn a_refused_evaluation_leaves_a_live_contact_as_it_was() {
    let ball = ConvexShape::ball(0.1).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let m = Material::new(1e7, 0.3).unwrap();
    let model = ContactModel::new(
        PairParameters::new(&m, &m, 0.5)
            .unwrap()
            .with_friction(Friction::new(0.5, 0.4, 1e-3).unwrap()),
        OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(),
    );
    let f = BodyState::at_rest(&floor, Pose::IDENTITY);
    let at = |y: f64| Pose::from_translation(Vector::new(0.0, y, 0.0));
    let mut state = None;
    for y in [0.099, 0.0989] {
        let a = BodyState::at_rest(&ball, at(y)).moving(Vector::new(0.1, -0.1, 0.0), Vector::ZERO);
        model.evaluate(&a, &f, &mut state).unwrap().expect("in contact");
    }
    let live = state.expect("a live contact");
    let bad = [
        BodyState::at_rest(&ball, at(0.0988)).moving(Vector::new(f64::NAN, 0.0, 0.0), Vector::ZERO),
        BodyState::at_rest(&ball, at(f64::NAN)),
    ];
    for a in &bad {
        let mut kept = Some(live);
        assert!(matches!(model.evaluate(a, &f, &mut kept), Err(Error::NonFinite { .. })));
        assert_eq!(kept, Some(live));
    }
}

#[test]
fn enlargement_makes_a_near_miss_a_contact() {
    let ball = ConvexShape::ball(0.1).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let m = Material::new(1e9, 0.3).unwrap();
    let params = PairParameters::new(&m, &m, 0.5).unwrap();
    let a = BodyState::at_rest(&ball, Pose::from_translation(Vector::new(0.0, 0.1005, 0.0)));
    let f = BodyState::at_rest(&floor, Pose::IDENTITY);
    let plain =
        ContactModel::new(params, OverlapSettings::new(8, IntegrationMode::Subcell).unwrap());
    assert!(plain.evaluate(&a, &f, &mut None).unwrap().is_none());
    let enlarged = ContactModel::new(
        params,
        OverlapSettings::new(8, IntegrationMode::Subcell)
            .unwrap()
            .with_enlargement(1e-3, 0.0)
            .unwrap(),
    );
    let out = enlarged.evaluate(&a, &f, &mut None).unwrap().unwrap();
    assert!((out.geometry.indentation - 0.5e-3).abs() < 1e-6, "{}", out.geometry.indentation);
}
