//! Physics of the contact core: Hertz, sharp edges, symmetry, invariance, monotonicity, damping,
//! friction, restitution of a dynamic impact, the tangential spring, footprints and tilting.

use approx::assert_relative_eq;
use discrete_contact::prelude::*;
use discrete_contact::{compute_overlap, damping_from_restitution, ContactState};
use discrete_contact_validation::hertz::HertzCase;

#[path = "common/contact.rs"]
mod shared;
use shared::*;

#[test]
fn hertz_counting_within_ten_percent_at_nc_8() {
    for case in HertzCase::all() {
        let e = case.rms_relative_error(&settings(8, IntegrationMode::Count)).unwrap();
        assert!(e <= 0.10, "{}: RMS relative error {e:.4} > 10 %", case.name());
    }
}

/// Measured: at most 1.1 % (sphere–half-space R = 1 m, mostly the model's own deviation from
/// Hertz at d/R = 0.05); the bound is 1.5 %.
#[test]
fn hertz_subcell_within_one_and_a_half_percent_at_nc_8() {
    for case in HertzCase::all() {
        let e = case.rms_relative_error(&settings(8, IntegrationMode::Subcell)).unwrap();
        assert!(e <= 0.015, "{}: RMS relative error {e:.4} > 1.5 %", case.name());
    }
}

/// The flat punch is exact in the model (`V d = π R² d²`), so its error is pure discretisation:
/// halving the cell must cut it by more than 2^1.5 in sub-cell mode (second order), and by
/// more than 2^0.8 in counting mode (first order).
#[test]
fn subcell_converges_at_second_order_counting_at_first() {
    let case = HertzCase::Punch { r: 1.0 };
    let err = |n, m| case.rms_relative_error(&settings(n, m)).unwrap();
    let sub = err(8, IntegrationMode::Subcell) / err(16, IntegrationMode::Subcell);
    let cnt = err(8, IntegrationMode::Count) / err(16, IntegrationMode::Count);
    assert!(sub > 2f64.powf(1.5), "sub-cell error ratio {sub:.2}");
    assert!(cnt > 2f64.powf(0.8), "counting error ratio {cnt:.2}");
}

/// The overlap of `body` at `pose` with the floor `y <= 0` of the frame `floor`.
fn floor_overlap(
    body: &ConvexShape,
    pose: &Pose,
    floor: &Pose,
    settings: &OverlapSettings,
) -> discrete_contact::OverlapGeometry {
    let half_space = ConvexShape::half_space(Vector::Y).unwrap();
    discrete_contact::compute_overlap(body, pose, &half_space, floor, settings, None)
        .unwrap()
        .expect("overlap")
}

/// A cylinder whose whole bottom cap lies below a tilted floor: the overlap is a slanted
/// slice of it, `V = π R² d` for the vertical depth `d` of the cap's centre, and its rim runs
/// round the cap's edge through cells from the coarsest grid on. Those cells are clipped by
/// the cap itself and the side's tangent planes, so the volume converges at second order from
/// `N_c` = 2, within `0.8 % (2/N_c)²`, and the normal is the floor's. (A cell clipped by the
/// whole body's tangent planes at sample points instead bevels the rim and fails the bound.)
#[test]
fn a_cylinders_rim_below_a_tilted_floor_is_integrated_sharp() {
    let (r, half_height, depth) = (0.02, 0.03, 0.002);
    let cylinder = ConvexShape::cylinder(half_height, r).unwrap();
    let tilt = Rotation::from_rotation_z(0.05);
    let n = tilt * Vector::Y;
    // The cap's centre `depth` below the floor along its normal: its rim is below the floor
    // everywhere (by at least depth − r tan 0.05 = 1 mm along the vertical).
    let pose = Pose::from_translation(-n * depth + Vector::Y * half_height);
    let exact = std::f64::consts::PI * r * r * depth / n.y;
    for n_c in [2, 4, 8] {
        let s = settings(n_c, IntegrationMode::Subcell);
        let g = floor_overlap(&cylinder, &pose, &Pose::from_parts(Vector::ZERO, tilt), &s);
        let err = g.volume / exact - 1.0;
        let bound = 0.008 * (2.0 / n_c as f64).powi(2);
        assert!(err.abs() < bound, "N_c = {n_c}: volume off by {err:.2e}, bound {bound:.1e}");
        assert!((g.normal - n).length() < 1e-4, "N_c = {n_c}: normal {:?}", g.normal);
    }
}

/// A cone standing on its base, pressed into the floor: the overlap is a frustum,
/// `V = π d (R² + R r + r²) / 3` with `r` the radius at the floor. Its rim runs round the base's
/// edge, whose cells are clipped by the base and the cone's side, within `1 % (2/N_c)²`. (A
/// cell clipped by the whole body's tangent planes at sample points instead bevels the edge
/// and fails the bound.)
#[test]
fn a_cones_base_below_the_floor_is_integrated_sharp() {
    let (half_height, big, depth) = (0.03, 0.02, 0.002);
    let cone = ConvexShape::cone(half_height, big).unwrap();
    let pose = Pose::from_parts(Vector::Y * (half_height - depth), Rotation::from_rotation_y(0.3));
    let small = big * (1.0 - depth / (2.0 * half_height));
    let exact = std::f64::consts::PI * depth * (big * big + big * small + small * small) / 3.0;
    for n_c in [2, 4, 8] {
        let g =
            floor_overlap(&cone, &pose, &Pose::IDENTITY, &settings(n_c, IntegrationMode::Subcell));
        let err = g.volume / exact - 1.0;
        let bound = 0.01 * (2.0 / n_c as f64).powi(2);
        assert!(err.abs() < bound, "N_c = {n_c}: volume off by {err:.2e}, bound {bound:.1e}");
        assert!((g.normal - Vector::Y).length() < 1e-4, "N_c = {n_c}: normal {:?}", g.normal);
    }
}

/// An enlarged cube (`ε` round its faces: rounded edges and corners), or a cube rounded by `ε`,
/// standing on an edge turned 45° onto a floor, turned about the vertical so that the grid
/// meets it at no particular angle, and pressed in by less than its edge's rounding reaches:
/// the overlap is the rounded edge's circular segment along the edge plus a spherical cap
/// shared by its two ends,
/// `V = L (ε² acos(1 − p/ε) − (ε − p) √(2εp − p²)) + π p² (3ε − p) / 3`. The rounded edge
/// runs through the cells the overlap's rim passes; those are clipped by the faces moved out
/// by `ε` and the rounded edge's tangent planes, within `1 % (4/N_c)^1.5`, and the normal is the
/// floor's. (A cell clipped by the enlarged body's tangent planes at sample points instead
/// bevels the rounding and fails the bound.)
#[test]
fn an_enlarged_cubes_rounded_edge_is_integrated_sharp() {
    let (half, eps, p) = (0.01, 0.005, 0.001);
    let cube = ConvexShape::cuboid(Vector::splat(half)).unwrap();
    let turn =
        Rotation::from_rotation_y(0.4) * Rotation::from_rotation_x(std::f64::consts::FRAC_PI_4);
    // The edge's lowest line `eps + half √2` below the centre, `p` below the floor.
    let pose = Pose::from_parts(Vector::Y * (half * 2f64.sqrt() + eps - p), turn);
    let segment = eps * eps * (1.0 - p / eps).acos() - (eps - p) * (2.0 * eps * p - p * p).sqrt();
    let exact = 2.0 * half * segment + std::f64::consts::PI * p * p * (3.0 * eps - p) / 3.0;
    // The same body as a rounded cube (parry's `RoundCuboid`), without enlargement.
    let rounded = ConvexShape::rounded(cube.clone(), eps).unwrap();
    for n_c in [4, 8, 16] {
        let plain = settings(n_c, IntegrationMode::Subcell);
        let enlarged = plain.with_enlargement(eps, 0.0).unwrap();
        for (body, s) in [(&cube, enlarged), (&rounded, plain)] {
            let g = floor_overlap(body, &pose, &Pose::IDENTITY, &s);
            let err = g.volume / exact - 1.0;
            let bound = 0.01 * (4.0 / n_c as f64).powf(1.5);
            assert!(err.abs() < bound, "N_c = {n_c}: volume off by {err:.2e}, bound {bound:.1e}");
            assert!((g.normal - Vector::Y).length() < 1e-3, "N_c = {n_c}: normal {:?}", g.normal);
        }
    }
}

/// Without enlargement, and with one that rounds the cube's edges and the cylinder's rims
/// (their cells clipped by the faces moved out and the rounded body's tangent planes).
const ENLARGEMENTS: [[f64; 2]; 2] = [[0.0; 2], [0.004, 0.002]];

/// An oblique cube–cylinder pair, both rotated and moving.
fn oblique_pair() -> (ConvexShape, Pose, Vector, Vector, ConvexShape, Pose, Vector, Vector) {
    let cube = ConvexShape::cuboid(Vector::new(0.05, 0.04, 0.03)).unwrap();
    let cyl = ConvexShape::cylinder(0.06, 0.03).unwrap();
    let pa = Pose::from_parts(
        Vector::new(0.01, 0.058, -0.005),
        Rotation::from_euler(discrete_contact::parry3d_f64::glamx::EulerRot::XYZ, 0.3, 0.2, 0.1),
    );
    let pb = Pose::from_parts(
        Vector::new(0.0, -0.01, 0.0),
        Rotation::from_euler(discrete_contact::parry3d_f64::glamx::EulerRot::XYZ, 0.1, -0.4, 1.2),
    );
    (
        cube,
        pa,
        Vector::new(0.1, -0.5, 0.2),
        Vector::new(1.0, 2.0, -3.0),
        cyl,
        pb,
        Vector::new(-0.1, 0.3, 0.0),
        Vector::new(0.5, 0.0, 1.0),
    )
}

#[test]
fn forces_are_equal_and_opposite_when_the_roles_swap() {
    let (sa, pa, va, wa, sb, pb, vb, wb) = oblique_pair();
    for mode in [IntegrationMode::Count, IntegrationMode::Subcell] {
        for [ea, eb] in ENLARGEMENTS {
            let a = BodyState::at_rest(&sa, pa).moving(va, wa);
            let b = BodyState::at_rest(&sb, pb).moving(vb, wb);
            let ab = enlarged_model(mode, 8, 0.8, [ea, eb]).evaluate(&a, &b, &mut None);
            let ba = enlarged_model(mode, 8, 0.8, [eb, ea]).evaluate(&b, &a, &mut None);
            let (ab, ba) = (ab.unwrap().expect("overlap"), ba.unwrap().expect("overlap"));
            let scale = ab.force.force_on_a.length();
            assert!(scale > 0.0);
            let asym = (ab.force.force_on_a + ba.force.force_on_a).length() / scale;
            assert!(asym <= 1e-9, "{mode:?}, ε = {ea}, {eb}: relative asymmetry {asym:e}");
            assert!((ab.force.torque_on_a - ba.force.torque_on_b).length() <= 1e-9 * scale);
            assert!((ab.force.torque_on_b - ba.force.torque_on_a).length() <= 1e-9 * scale);
        }
    }
}

#[test]
fn force_is_invariant_under_a_rigid_motion_of_the_pair() {
    let (sa, pa, va, wa, sb, pb, vb, wb) = oblique_pair();
    let motion = Pose::from_parts(
        Vector::new(3.0, -2.0, 7.5),
        Rotation::from_axis_angle(Vector::new(1.0, 2.0, 3.0).normalize(), 2.1),
    );
    let r = motion.rotation;
    for mode in [IntegrationMode::Count, IntegrationMode::Subcell] {
        // Both modes with and without the enlargement: where the counted box's face lies on a
        // body's face (the cylinder's cap), a whole node layer sits on it, and a node on a
        // surface to round-off counts as inside whatever the last bit of the box.
        for &enlargement in &ENLARGEMENTS {
            let m = enlarged_model(mode, 8, 0.8, enlargement);
            let before = m
                .evaluate(
                    &BodyState::at_rest(&sa, pa).moving(va, wa),
                    &BodyState::at_rest(&sb, pb).moving(vb, wb),
                    &mut None,
                )
                .unwrap()
                .unwrap();
            let after = m
                .evaluate(
                    &BodyState::at_rest(&sa, motion * pa).moving(r * va, r * wa),
                    &BodyState::at_rest(&sb, motion * pb).moving(r * vb, r * wb),
                    &mut None,
                )
                .unwrap()
                .unwrap();
            let f = before.force.force_on_a;
            let err = (r * f - after.force.force_on_a).length() / f.length();
            assert!(err <= 1e-8, "{mode:?}, ε = {enlargement:?}: {err:e}");
            assert!(
                (r * before.force.torque_on_a - after.force.torque_on_a).length()
                    <= 1e-8 * before.force.torque_on_a.length().max(1e-12)
            );
            assert_relative_eq!(before.geometry.volume, after.geometry.volume, max_relative = 1e-9);
            assert_relative_eq!(
                before.geometry.indentation,
                after.geometry.indentation,
                max_relative = 1e-9
            );
        }
    }
}

#[test]
fn no_force_when_apart_and_the_contact_ends() {
    let ball = ConvexShape::ball(0.1).unwrap();
    let m = model(IntegrationMode::Subcell, 8, 0.9);
    let b = BodyState::at_rest(&ball, Pose::IDENTITY);
    let mut state = None;
    let touching = BodyState::at_rest(&ball, Pose::from_translation(Vector::new(0.0, 0.199, 0.0)));
    assert!(m.evaluate(&touching, &b, &mut state).unwrap().is_some());
    assert!(state.is_some());
    for gap in [1e-9, 1e-4, 0.05] {
        let apart =
            BodyState::at_rest(&ball, Pose::from_translation(Vector::new(0.0, 0.2 + gap, 0.0)));
        assert!(m.evaluate(&apart, &b, &mut state).unwrap().is_none(), "gap {gap}");
        assert!(state.is_none());
    }
}

#[test]
fn force_grows_monotonically_with_indentation() {
    for case in [
        HertzCase::SphereHalfSpace { r: 1.0 },
        HertzCase::CrossedCylinders { r: 1.0 },
        HertzCase::Punch { r: 1.0 },
    ] {
        let s = settings(8, IntegrationMode::Subcell);
        let forces: Vec<f64> =
            (1..=40).map(|i| case.force(&s, 0.05 * i as f64 / 40.0).unwrap()).collect();
        for w in forces.windows(2) {
            assert!(w[1] > w[0], "{}: {} then {}", case.name(), w[0], w[1]);
        }
    }
}

#[test]
fn damping_from_restitution_matches_the_exact_solution() {
    assert_relative_eq!(damping_from_restitution(0.85, 1.0).unwrap(), 0.26401, epsilon = 5e-6);
    for (e, a) in [(0.5, 1.4328), (0.7, 0.6348), (0.9, 0.1665)] {
        assert_relative_eq!(damping_from_restitution(e, 1.0).unwrap(), a, epsilon = 5e-5);
        assert_relative_eq!(damping_from_restitution(e, 2.0).unwrap(), a / 2.0, epsilon = 5e-5);
    }
    assert_eq!(damping_from_restitution(1.0, 1.0).unwrap(), 0.0);
    // e -> 1 is continuous: the series branch meets the root-finding branch.
    let near = damping_from_restitution(1.0 - 2e-7, 1.0).unwrap();
    let series = damping_from_restitution(1.0 - 5e-8, 1.0).unwrap();
    assert!(near > series && series > 0.0 && near < 1e-6);
}

#[test]
fn friction_law_limits() {
    let f = Friction::new(0.4, 0.3, 0.01).unwrap();
    assert_eq!(f.coefficient(0.0), 0.0);
    assert_relative_eq!(f.coefficient(1e3), 0.3, epsilon = 1e-6);
    let mu_s_star = 0.4 * (1.0 - 0.09 * (0.3f64 / 0.4).powi(4));
    assert_relative_eq!(f.coefficient(0.01), mu_s_star, epsilon = 1e-12);
    assert!(f.coefficient(1e-5) < 1e-5);
    assert_eq!(Friction::NONE.coefficient(1.0), 0.0);
    // In a contact: opposite to the slip, μ_k F_n when sliding fast.
    let ball = ConvexShape::ball(0.1).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let m = Material::new(1e8, 0.3).unwrap();
    let params = PairParameters::new(&m, &m, 1.0).unwrap().with_friction(f);
    let model = ContactModel::new(params, settings(8, IntegrationMode::Subcell));
    let a = BodyState::at_rest(&ball, Pose::from_translation(Vector::new(0.0, 0.099, 0.0)))
        .moving(Vector::new(50.0, 0.0, 0.0), Vector::ZERO);
    let out = model
        .evaluate(&a, &BodyState::at_rest(&floor, Pose::IDENTITY), &mut None)
        .unwrap()
        .unwrap();
    let fc = out.force;
    assert!(fc.force_on_a.x < 0.0);
    assert_relative_eq!(fc.tangential_force, 0.3 * fc.normal_force, max_relative = 1e-4);
    // Frictionless pair: no tangential force at all.
    let plain = ContactModel::new(
        PairParameters::new(&m, &m, 1.0).unwrap(),
        settings(8, IntegrationMode::Subcell),
    );
    let out = plain
        .evaluate(&a, &BodyState::at_rest(&floor, Pose::IDENTITY), &mut None)
        .unwrap()
        .unwrap();
    assert_eq!(out.force.tangential_force, 0.0);
}

#[test]
fn damping_is_fixed_at_first_touch() {
    let ball = ConvexShape::ball(0.1).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let m = model(IntegrationMode::Subcell, 6, 0.85);
    let wall = BodyState::at_rest(&floor, Pose::IDENTITY);
    let mut state: Option<ContactState> = None;
    let at = |y: f64, v: f64| {
        BodyState::at_rest(&ball, Pose::from_translation(Vector::new(0.0, y, 0.0)))
            .moving(Vector::new(0.0, -v, 0.0), Vector::ZERO)
    };
    m.evaluate(&at(0.0999, 1.0), &wall, &mut state).unwrap().unwrap();
    let c = state.unwrap().damping;
    assert_relative_eq!(c, 0.26401, epsilon = 1e-4);
    m.evaluate(&at(0.0995, 0.2), &wall, &mut state).unwrap().unwrap();
    assert_eq!(state.unwrap().damping, c);
}

/// A sphere dropped on a wall at 1 m/s, integrated with velocity Verlet through the contact:
/// the rebound speed ratio is the restitution, and an elastic contact creates no energy.
#[test]
fn dynamic_impact_restitution_and_no_energy_created() {
    for (e, mode) in [
        (0.85, IntegrationMode::Subcell),
        (1.0, IntegrationMode::Subcell),
        (0.85, IntegrationMode::Count),
    ] {
        let r = 0.005;
        let ball = ConvexShape::ball(r).unwrap();
        let mat = Material::new(5e8, 0.35).unwrap();
        let m = ContactModel::new(PairParameters::new(&mat, &mat, e).unwrap(), settings(6, mode));
        let mass = 7800.0 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        let (v, ..) = drop_on_wall(&m, &ball, Rotation::IDENTITY, r, mass);
        let measured = v / 1.0;
        if e < 1.0 {
            assert!(
                (measured - e).abs() <= 0.03 * e,
                "{mode:?}: restitution {measured:.4} for e = {e}"
            );
        }
        assert!(measured <= 1.0 + 2e-3, "{mode:?}: energy created, rebound {measured}");
        assert!(measured >= 0.97 * e, "{mode:?}: rebound {measured}");
    }
}

/// A persistent contact follows its overlap from sub-step to sub-step (sub-cell mode reuses
/// last sub-step's box instead of searching): along a path that deepens, slides and turns
/// the oblique cube–cylinder contact, its overlap volume must stay as close to the converged
/// one (N_c = 64) as a fresh evaluation's. Measured at N_c = 8: mean error 3.3 % followed,
/// 3.2 % fresh (a fresh search's box misses part of this overlap's corners).
#[test]
fn persistent_contact_is_as_accurate_as_a_fresh_evaluation() {
    let (sa, pa, va, wa, sb, pb, vb, wb) = oblique_pair();
    let (m, fine) =
        (model(IntegrationMode::Subcell, 8, 0.8), model(IntegrationMode::Subcell, 64, 0.8));
    let b = BodyState::at_rest(&sb, pb).moving(vb, wb);
    let mut state = None;
    let (mut followed_err, mut fresh_err) = (0.0, 0.0);
    for i in 0..30 {
        let s = i as f64 / 29.0;
        let motion = Pose::from_parts(
            Vector::new(0.004 * s, -0.006 * s, 0.003 * s),
            Rotation::from_rotation_y(0.2 * s),
        );
        let a = BodyState::at_rest(&sa, motion * pa).moving(va, wa);
        let volume = |m: &ContactModel, st: &mut Option<ContactState>| {
            m.evaluate(&a, &b, st).unwrap().expect("overlap").geometry.volume
        };
        let reference = volume(&fine, &mut None);
        followed_err += (volume(&m, &mut state) / reference - 1.0).abs() / 30.0;
        fresh_err += (volume(&m, &mut None) / reference - 1.0).abs() / 30.0;
        assert!(state.is_some(), "the contact must persist");
    }
    println!("mean relative volume error: followed {followed_err:.4}, fresh {fresh_err:.4}");
    assert!(
        followed_err <= 0.04 && followed_err <= 1.2 * fresh_err,
        "followed {followed_err:.4}, fresh {fresh_err:.4}"
    );
}

/// A contact begun at a crawl and then driven hard (a third body lands on the pair) re-bases
/// its damping on the faster approach: `c ḋ <= a(e)`, so the force stays within `1 + a(e)`
/// times the elastic force instead of growing with `ḋ / v_crawl`.
#[test]
fn damping_rebases_when_a_contact_is_driven_faster() {
    let ball = ConvexShape::ball(0.1).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let m = model(IntegrationMode::Subcell, 6, 0.5);
    let wall = BodyState::at_rest(&floor, Pose::IDENTITY);
    let mut state: Option<ContactState> = None;
    let at = |v: f64| {
        BodyState::at_rest(&ball, Pose::from_translation(Vector::new(0.0, 0.0995, 0.0)))
            .moving(Vector::new(0.0, -v, 0.0), Vector::ZERO)
    };
    m.evaluate(&at(1e-3), &wall, &mut state).unwrap().unwrap();
    let crawl = state.unwrap().damping;
    let hard = m.evaluate(&at(2.0), &wall, &mut state).unwrap().unwrap();
    let elastic = discrete_contact::normal_force(&m.params, 0.0, &hard.geometry, 0.0);
    let a = damping_from_restitution(0.5, 1.0).unwrap();
    assert_relative_eq!(state.unwrap().damping, a / 2.0, max_relative = 1e-12);
    assert!(state.unwrap().damping < crawl);
    let ratio = hard.force.normal_force / elastic;
    assert_relative_eq!(ratio, 1.0 + a, max_relative = 1e-9);
}

/// A contact that begins with a vanishing overlap (1e-18 m, as when a body lands exactly on a
/// sub-step) has a box of almost nothing; one sub-step later the sphere is 0.9 µm deep. The
/// persistent evaluation must still find the whole overlap — before the fix it lost the contact
/// for a sub-step and let the sphere sink unopposed.
#[test]
fn a_contact_begun_at_a_vanishing_overlap_is_kept_when_it_deepens() {
    let (r, d) = (0.005, 8.8e-7);
    let ball = ConvexShape::ball(r).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let m = model(IntegrationMode::Subcell, 4, 0.85);
    let wall = BodyState::at_rest(&floor, Pose::IDENTITY);
    let at = |y: f64| {
        BodyState::at_rest(&ball, Pose::from_translation(Vector::new(0.0, y, 0.0)))
            .moving(Vector::new(0.0, -1.0, 0.0), Vector::ZERO)
    };
    let mut state: Option<ContactState> = None;
    m.evaluate(&at(r - 1e-18), &wall, &mut state).unwrap();
    assert!(state.is_some(), "the touch starts a contact");
    let deeper =
        m.evaluate(&at(r - d), &wall, &mut state).unwrap().expect("the deeper overlap is found");
    assert_relative_eq!(deeper.geometry.indentation, d, max_relative = 0.02);
    let fresh = m.evaluate(&at(r - d), &wall, &mut None).unwrap().unwrap();
    assert_relative_eq!(deeper.geometry.volume, fresh.geometry.volume, max_relative = 0.05);
}

/// A 10 cm sphere pressed 0.1 mm into the floor, at rest, moved sideways by `shift` each
/// evaluation (`steps` of them) under the tangential spring (μ_s = 0.5, μ_k = 0.3), the pair
/// placed by `rotation`; returns the tangential force on the sphere after each (in the pair's
/// frame, `A`↔`B` swapped when `swap`) and the last normal force.
fn spring_sequence(
    shift: Vector,
    rotation: Rotation,
    steps: usize,
    swap: bool,
) -> (Vec<Vector>, f64) {
    let ball = ConvexShape::ball(0.1).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let m = Material::new(1e8, 0.3).unwrap();
    let params = PairParameters::new(&m, &m, 0.8)
        .unwrap()
        .with_friction(Friction::new(0.5, 0.3, 1e-3).unwrap())
        .with_tangential_law(TangentialLaw::Spring);
    let model = ContactModel::new(params, settings(8, IntegrationMode::Subcell));
    let frame = Pose::from_parts(Vector::new(0.3, -0.2, 0.7), rotation);
    let mut state = None;
    let mut forces = vec![];
    let mut normal = 0.0;
    for k in 0..steps {
        let a = BodyState::at_rest(
            &ball,
            frame * Pose::from_translation(Vector::new(0.0, 0.0999, 0.0) + shift * k as f64),
        );
        let b = BodyState::at_rest(&floor, frame);
        let out = if swap {
            model.evaluate(&b, &a, &mut state)
        } else {
            model.evaluate(&a, &b, &mut state)
        };
        let f = out.unwrap().expect("overlap").force;
        let on_ball = frame.rotation.inverse() * if swap { f.force_on_b() } else { f.force_on_a };
        forces.push(on_ball - Vector::Y * on_ball.y);
        normal = f.normal_force;
    }
    (forces, normal)
}

#[test]
fn the_tangential_spring_sticks_below_mu_s_then_slides_at_mu_k() {
    let (f, f_n) = spring_sequence(Vector::new(3e-7, 0.0, 0.0), Rotation::IDENTITY, 400, false);
    let x: Vec<f64> = f.iter().map(|v| v.x).collect();
    // Sticking: the spring pulls the sphere back, linearly in the displacement, at Mindlin's
    // stiffness κ 1.5 F_n/d (κ = 2(1 − ν)/(2 − ν), d = 0.1 mm).
    assert!(x[0].abs() < 1e-5 * f_n && x[1] < 0.0);
    let k_t = -x[10] / (10.0 * 3e-7);
    let mindlin = 2.0 * 0.7 / 1.7 * 1.5 * f_n / 1e-4;
    assert!((k_t / mindlin - 1.0).abs() < 0.05, "k_t = {k_t}, Mindlin {mindlin}");
    // The hold never exceeds μ_s F_n; past it the contact slides at μ_k F_n and stays there.
    let peak = x.iter().fold(0.0f64, |m, v| m.max(-v));
    assert!(
        peak <= 0.5 * f_n * (1.0 + 1e-9) && peak > 0.45 * f_n,
        "peak {peak}, μ_s F_n {}",
        0.5 * f_n
    );
    // (To the grid normal's tilt, a few 1e-6 rad here.)
    assert_relative_eq!(-x[399], 0.3 * f_n, max_relative = 1e-4);
    assert!(f.iter().all(|v| v.z.abs() < 1e-4 * f_n), "sideways force");
}

#[test]
fn the_tangential_spring_is_symmetric_and_moves_rigidly_with_the_pair() {
    // Equal and opposite whichever body is A, and the same in any placement of the pair.
    let shift = Vector::new(1e-7, 0.0, 4e-8);
    let (plain, _) = spring_sequence(shift, Rotation::IDENTITY, 200, false);
    let (swapped, _) = spring_sequence(shift, Rotation::IDENTITY, 200, true);
    let (turned, _) =
        spring_sequence(shift, Rotation::from_scaled_axis(Vector::new(0.4, -1.1, 0.7)), 200, false);
    // A persistent contact keeps its grid in the frame it chose, so the two orders and the
    // rotated pair integrate on different grids: they agree to the grid's resolution.
    let scale = plain.iter().map(|v| v.length()).fold(0.0, f64::max);
    let worst = |other: &[Vector]| {
        (0..200).map(|k| (plain[k] - other[k]).length() / scale).fold(0.0, f64::max)
    };
    let (ab, rigid) = (worst(&swapped), worst(&turned));
    assert!(
        ab < 1e-4 && rigid < 1e-4,
        "A↔B differ by {ab:e}, rotated by {rigid:e} of the largest force"
    );
}

/// Two bodies with curved edges (cylinders, cones, rounded boxes), turned at random and moved
/// apart by a small gap, are never joined on a coarse grid: a bent cell's tangent planes hold
/// the bodies with their curvature error, which can exceed the gap, and the cell must not
/// report an overlap that no point of both bodies is in.
#[test]
fn curved_edges_apart_by_less_than_a_coarse_cell_are_not_joined() {
    use discrete_contact::compute_overlap;
    use discrete_contact::parry3d_f64::query::distance;
    use discrete_contact::parry3d_f64::shape::SharedShape;
    // Sizes from 1 to ~7: a small body's edge against a large one's rim.
    let shapes = [
        SharedShape::cylinder(1.0, 0.5),
        SharedShape::cone(0.8, 0.6),
        SharedShape::round_cuboid(1.0, 0.6, 0.35, 0.1),
        SharedShape::cylinder(6.7, 3.2),
        SharedShape::round_cuboid(4.0, 2.0, 3.0, 0.5),
    ];
    let mut seed = 0x2545_F491_4F6C_DD1Du64;
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut apart = 0;
    for k in 0..250 {
        let (pa, pb) = (&shapes[k % 5], &shapes[(k / 5) % 5]);
        let (a, b) =
            (ConvexShape::from_parry(&**pa).unwrap(), ConvexShape::from_parry(&**pb).unwrap());
        let mut rot = || {
            let axis = Vector::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
            Rotation::from_axis_angle(axis, 6.3 * rnd())
        };
        let (ra, rb) = (rot(), rot());
        let dir = Vector::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
        // Gaps from 1 µm to 20 mm, evenly in their logarithm: down to 1e-6 of a cell.
        let gap = 1e-6 * 2e4f64.powf(rnd());
        let far = 20.0;
        // Bisect the centre distance to the gap.
        let pose_b = |t: f64| Pose::from_parts(dir * t, rb);
        let pose_a = Pose::from_parts(Vector::ZERO, ra);
        let (mut lo, mut hi) = (0.0, far);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            let d = distance(&pose_a, &**pa, &pose_b(mid), &**pb).unwrap().distance;
            if d < gap {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let pb_pose = pose_b(hi);
        assert!(distance(&pose_a, &**pa, &pb_pose, &**pb).unwrap().distance >= gap * (1.0 - 1e-9));
        for n_c in 1..=3 {
            let s = OverlapSettings::new(n_c, IntegrationMode::Subcell).unwrap();
            let g = compute_overlap(&a, &pose_a, &b, &pb_pose, &s, None).unwrap();
            assert!(g.is_none(), "pair {k} at N_c = {n_c}, gap {gap}: {g:?}");
            apart += 1;
        }
    }
    assert_eq!(apart, 750);
}

/// The bin scene's rubber (E = 5 MPa, ν = 0.4, e = 0.5) on the sub-cell grid at `N_c` = 4.
fn rubber_contact() -> ContactModel {
    let m = Material::new(5e6, 0.4).unwrap();
    ContactModel::new(
        PairParameters::new(&m, &m, 0.5).unwrap(),
        settings(4, IntegrationMode::Subcell),
    )
}

/// A cube's face rocking on a floor: the law's damping spread over the footprint gives the
/// couple `−c F_el (L²/12) ω` of a uniform pressure on a square of side `L` (the grid's
/// footprint within a few per cent), equal and opposite on the two bodies, taking energy out
/// (`T·ω < 0`); nothing for a spin about the normal, for both bodies turning alike, or
/// without damping. (At its contact point alone, the damping acts on the approach there,
/// which the rocking leaves still: nothing would damp it.)
#[test]
fn a_face_rocking_on_a_face_is_damped_by_a_couple() {
    let (half, depth) = (0.01, 2e-6);
    let cube = ConvexShape::cuboid(Vector::splat(half)).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let pose = Pose::from_translation(Vector::new(0.0, half - depth, 0.0));
    let a = BodyState::at_rest(&cube, pose);
    let b = BodyState::at_rest(&floor, Pose::IDENTITY);
    let geometry = rubber_contact().evaluate(&a, &b, &mut None).unwrap().unwrap().geometry;
    let m = Material::new(5e6, 0.4).unwrap();
    let params = PairParameters::new(&m, &m, 0.5).unwrap();
    let c = 0.2; // s/m
    let com_a = pose.translation;
    let couple = |damping: f64, w_a: Vector, w_b: Vector| {
        let ka = BodyKinematics { center_of_mass: com_a, linvel: Vector::ZERO, angvel: w_a };
        let kb = BodyKinematics { center_of_mass: Vector::ZERO, linvel: Vector::ZERO, angvel: w_b };
        let f = discrete_contact::contact_force(&params, damping, &geometry, &ka, &kb);
        let x = geometry.contact_point;
        let t_a = f.torque_on_a - (x - com_a).cross(f.force_on_a);
        let t_b = f.torque_on_b - (x - Vector::ZERO).cross(-f.force_on_a);
        (t_a, t_b, f)
    };
    let w = Vector::new(0.5, 0.0, 0.0);
    let (t_a, t_b, f) = couple(c, w, Vector::ZERO);
    assert!(f.approach_speed.abs() < 1e-12, "the rocking moves the contact point along the floor");
    let side = 2.0 * half;
    let expected = -c * f.normal_force * side * side / 12.0 * w.x;
    println!("rocking couple {:.4e} N m, uniform pressure's {expected:.4e} N m", t_a.x);
    assert!((t_a.x / expected - 1.0).abs() < 0.05, "couple {t_a:?}, expected {expected:e} about x");
    assert!((t_a + t_b).length() <= 1e-12 * t_a.length(), "not a couple: {t_a:?} vs {t_b:?}");
    assert!(t_a.dot(w) < 0.0, "the couple feeds the rocking");
    for (damping, w_a, w_b) in
        [(c, Vector::new(0.0, 3.0, 0.0), Vector::ZERO), (c, w, w), (0.0, w, Vector::ZERO)]
    {
        let (t_a, _, _) = couple(damping, w_a, w_b);
        assert!(t_a.length() <= 1e-12 * expected.abs(), "{w_a:?}, {w_b:?}, c {damping}: {t_a:?}");
    }
}

/// A cylinder standing on a floor: its footprint is the whole cap at every evaluation, also
/// where the persistent grid puts the cap and the floor on node layers (each face's facet
/// then goes to a cell that holds no volume), and an update follows a rocking tilt with the
/// restoring torque a full evaluation gives. With half the footprint, the torque between full
/// evaluations would be half the full evaluations' and each full evaluation would kick the
/// cylinder into rocking again.
#[test]
fn a_flat_face_on_a_floor_keeps_its_whole_footprint() {
    let model = rubber_contact();
    let reused = model.with_geometry_reuse(discrete_contact::contact::GEOMETRY_REUSE).unwrap();
    let (r, depth) = (0.01, 2.6e-6);
    let cylinder = ConvexShape::cylinder(r, r).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let b = BodyState::at_rest(&floor, Pose::IDENTITY);
    let at = |tilt: f64| {
        let centre = Vector::new(0.0, r - depth, 0.0);
        Pose::from_parts(centre, Rotation::from_axis_angle(Vector::X, tilt))
    };
    let torque = |o: &discrete_contact::ContactOutput, pose: &Pose| {
        (o.geometry.contact_point - pose.translation).cross(o.geometry.normal).x
            * o.force.normal_force
    };
    let (mut state, mut full_state) = (None, None);
    let mut worst = 0.0f64;
    for k in 0..=5 {
        let pose = at(2e-6 * k as f64);
        let a = BodyState::at_rest(&cylinder, pose);
        let out = reused.evaluate(&a, &b, &mut state).unwrap().unwrap();
        let full = model.evaluate(&a, &b, &mut full_state).unwrap().unwrap();
        let footprint = full.geometry.footprint.expect("a footprint from the grid");
        let area = footprint.area / (std::f64::consts::PI * r * r);
        assert!((area - 1.0).abs() < 0.02, "tilt step {k}: footprint {area:.4} of the cap");
        if k > 0 {
            let (updated, exact) = (torque(&out, &pose), torque(&full, &pose));
            assert!(!out.full(), "tilt step {k}: the update should follow the tilt");
            worst = worst.max((updated / exact - 1.0).abs());
        }
    }
    println!("update's torque off the full evaluations' by {worst:.3}");
    assert!(worst < 0.15, "the update's restoring torque is off by {worst:.3}");
}

/// A cylinder lying on a floor: the overlap is a strip along its side, symmetric about its
/// middle, and every evaluation gives its volume and its middle — also the persistent ones,
/// whose grid has the caps on the box's end layers (interpolated across the rims there, the
/// strip comes out 7 % short, its contact point 0.44 mm towards one cap).
#[test]
fn a_cylinder_lying_on_a_floor_keeps_its_strip_whole() {
    let model = rubber_contact();
    let (r, half) = (0.01, 0.01);
    let cylinder = ConvexShape::cylinder(half, r).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let b = BodyState::at_rest(&floor, Pose::IDENTITY);
    let lying = Rotation::from_axis_angle(Vector::Z, std::f64::consts::FRAC_PI_2);
    let mut state = None;
    for k in 0..4 {
        let depth = 8.6e-6 + 1e-7 * k as f64;
        let centre = Vector::new(0.0012, r - depth, -0.0031);
        let a = BodyState::at_rest(&cylinder, Pose::from_parts(centre, lying));
        let g = model.evaluate(&a, &b, &mut state).unwrap().unwrap().geometry;
        // The circular segment of height `depth`, along the whole side.
        let angle = 2.0 * ((r - depth) / r).acos();
        let exact = 2.0 * half * 0.5 * r * r * (angle - angle.sin());
        let along = (g.contact_point - centre).x / half;
        println!("evaluation {k}: V / exact {:.5}, contact point {along:.2e} of the half-length off the middle", g.volume / exact);
        assert!(
            (g.volume / exact - 1.0).abs() < 0.01,
            "evaluation {k}: V / exact {}",
            g.volume / exact
        );
        assert!(
            along.abs() < 1e-4,
            "evaluation {k}: contact point {along:e} half-lengths off the middle"
        );
    }
}

/// A cylinder's or a capsule's side pressed into a floor or a cube's face, at several places
/// and turns about its axis: the normal force has no moment about the body's axis, as the
/// pressure on a body of revolution has none (every normal of its side crosses the axis). The
/// grid's contact point lies off the plane of the axis and the normal by its discretisation
/// error, and that moment would roll a cylinder lying on a floor away.
#[test]
fn a_side_pressed_into_a_face_has_no_moment_about_its_axis() {
    let model = rubber_contact();
    let r = 0.01;
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let cube = ConvexShape::cuboid(Vector::splat(0.05)).unwrap();
    let bodies = [
        ("cylinder", ConvexShape::cylinder(r, r).unwrap(), Vector::Y),
        ("capsule", ConvexShape::capsule(-Vector::Y * r, Vector::Y * r, r).unwrap(), Vector::Y),
    ];
    // The floor's top at y = 0; the cube's top face at y = 0 too.
    let below =
        [(&floor, Pose::IDENTITY), (&cube, Pose::from_translation(Vector::new(0.0, -0.05, 0.0)))];
    for (name, body, axis) in &bodies {
        for (other, at) in &below {
            let b = BodyState::at_rest(*other, *at);
            for k in 0..4 {
                // Lying along x, turned about its own axis and moved about over the face.
                let spin = Rotation::from_axis_angle(Vector::Y, 0.37 * k as f64);
                let lying = Rotation::from_axis_angle(Vector::Z, std::f64::consts::FRAC_PI_2);
                let centre = Vector::new(0.0013 * k as f64, r - 8e-6, -0.0021 * k as f64);
                let pose = Pose::from_parts(centre, lying * spin);
                let a = BodyState::at_rest(body, pose);
                let out = model.evaluate(&a, &b, &mut None).unwrap().unwrap();
                let g = out.geometry;
                let direction = pose.rotation * *axis;
                let moment = (g.contact_point - centre).cross(g.normal).dot(direction);
                assert!(
                    moment.abs() < 1e-12 * r,
                    "{name}, placement {k}: lever of the moment about the axis {moment:e} m"
                );
            }
        }
    }
}

/// A contact at rest, evaluated again from its state, integrates the grid its first touch
/// built (the box of the pieces a quarter cell larger, `N_c` cells): the same overlap to the
/// last bit, and the same force — for a ball pair (its cells cut into tetrahedra) and crossed
/// cylinders (clipped by tangent planes). A grid padded around the box would give another
/// discretisation of it.
#[test]
fn a_resting_contact_integrates_the_grid_of_its_first_touch() {
    use std::f64::consts::FRAC_PI_2;
    let model = rubber_contact();
    let cylinder = ConvexShape::cylinder(0.01, 0.005).unwrap();
    let ball = ConvexShape::ball(0.005).unwrap();
    let pairs = [
        (
            &ball,
            Pose::from_translation(Vector::new(0.0003, 0.0098, -0.0002)),
            &ball,
            Pose::IDENTITY,
        ),
        (
            &cylinder,
            Pose::from_parts(Vector::new(0.0, 0.0099, 0.0), Rotation::from_rotation_z(FRAC_PI_2)),
            &cylinder,
            Pose::from_parts(Vector::ZERO, Rotation::from_rotation_x(FRAC_PI_2)),
        ),
    ];
    for (k, (sa, pa, sb, pb)) in pairs.into_iter().enumerate() {
        let (a, b) = (BodyState::at_rest(sa, pa), BodyState::at_rest(sb, pb));
        let mut state = None;
        let first = model.evaluate(&a, &b, &mut state).unwrap().expect("overlap");
        let again = model.evaluate(&a, &b, &mut state).unwrap().expect("overlap");
        assert_eq!(again.geometry.volume, first.geometry.volume, "pair {k}");
        assert_eq!(again.geometry.contact_point, first.geometry.contact_point, "pair {k}");
        assert_eq!(again.geometry.normal, first.geometry.normal, "pair {k}");
        assert_eq!(again.force.normal_force, first.force.normal_force, "pair {k}");
    }
}

/// A curved body pressed into a face — a cylinder lying on a floor, on a turned box's face —
/// takes the face's normal: the overlap's surface is closed, so the curved part's area vector
/// is exactly minus the face's, and the grid's cells would tilt it only by their gaps (a few
/// millionths, which push a lying cylinder sideways). First touch and persistent alike.
#[test]
fn a_curved_body_on_a_face_takes_the_face_normal() {
    use std::f64::consts::FRAC_PI_2;
    let model = rubber_contact();
    let r = 0.01;
    let cylinder = ConvexShape::cylinder(0.01, r).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let cube = ConvexShape::cuboid(Vector::splat(0.05)).unwrap();
    let turn = Rotation::from_axis_angle(Vector::new(0.3, 0.1, -0.5).normalize(), 0.4);
    let lying = Rotation::from_axis_angle(Vector::Z, FRAC_PI_2);
    for (face, pose) in [
        (&floor, Pose::IDENTITY),
        (&cube, Pose::from_parts(turn * Vector::new(0.0, -0.05, 0.0), turn)),
    ] {
        let up = pose.rotation * Vector::Y;
        let b = BodyState::at_rest(face, pose);
        let mut state = None;
        for k in 0..4 {
            let depth = 6e-5 + 1e-6 * k as f64;
            let centre = up * (r - depth) + pose.rotation * Vector::new(0.0012, 0.0, -0.0031);
            let a = BodyState::at_rest(&cylinder, Pose::from_parts(centre, pose.rotation * lying));
            let g = model.evaluate(&a, &b, &mut state).unwrap().expect("overlap").geometry;
            assert!(
                (g.normal - up).length() < 1e-12,
                "evaluation {k}: normal {:?} against {up:?}",
                g.normal
            );
        }
    }
}

/// With the facet bulge ([`OverlapSettings::with_facet_bulge`]) a ball's overlap with a
/// half-space and with another ball is third order in the grid's spacing: the volume's error
/// against the closed form falls at least fivefold from `N_c` = 2 to 4 and from 4 to 8 (second
/// order would give fourfold; measured 14–175×) and is below 1e-3 at `N_c` = 4, where the
/// piecewise-linear surfaces alone are ~5 % short; its surface area is within 0.5 % (the rims
/// completed); the result is the same whichever body is A, and moves rigidly with the pair.
#[test]
fn the_facet_bulge_makes_a_balls_volume_third_order() {
    let small = ConvexShape::ball(0.01).unwrap();
    let large = ConvexShape::ball(0.02).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let turn = Rotation::from_scaled_axis(Vector::new(0.3, -0.2, 0.5));
    let pose_a = Pose::from_parts(Vector::new(0.001, 0.01 - 4e-5, -0.002), turn);
    let lens_b = Pose::from_parts(Vector::new(0.0015, 0.04 - 6e-5, -0.0018), turn.inverse());
    let pairs: [(&ConvexShape, Pose); 2] = [(&floor, Pose::IDENTITY), (&large, lens_b)];
    for (b, pose_b) in pairs {
        let exact = compute_overlap(
            &small,
            &pose_a,
            b,
            &pose_b,
            &settings(4, IntegrationMode::Subcell).with_closed_form_spheres(true),
            None,
        )
        .unwrap()
        .unwrap();
        let (exact, exact_area) = (exact.volume, exact.surface_area);
        let error = |n: usize| {
            let s = settings(n, IntegrationMode::Subcell).with_facet_bulge(true);
            let g = compute_overlap(&small, &pose_a, b, &pose_b, &s, None).unwrap().unwrap();
            (g.volume / exact - 1.0).abs()
        };
        let plain = {
            let s = settings(4, IntegrationMode::Subcell).with_facet_bulge(false);
            let g = compute_overlap(&small, &pose_a, b, &pose_b, &s, None).unwrap().unwrap();
            (g.volume / exact - 1.0).abs()
        };
        let (e2, e4, e8) = (error(2), error(4), error(8));
        assert!(
            e4 < 1e-3 && e4 < plain / 20.0,
            "N_c = 4: {e4:.3e} (without the layer {plain:.3e})"
        );
        assert!(e2 > 5.0 * e4 && e4 > 5.0 * e8, "errors {e2:.3e} {e4:.3e} {e8:.3e}");

        let s = settings(4, IntegrationMode::Subcell).with_facet_bulge(true);
        let ab = compute_overlap(&small, &pose_a, b, &pose_b, &s, None).unwrap().unwrap();
        // The area's rims completed: the volume law's exponent of a cap or a lens, `d s / 2V`,
        // is not pushed below 2 by an area shorter than the volume.
        let area = (ab.surface_area / exact_area - 1.0).abs();
        assert!(area < 5e-3, "surface area off by {area:.3e}");
        let ba = compute_overlap(b, &pose_b, &small, &pose_a, &s, None).unwrap().unwrap();
        assert_relative_eq!(ab.volume, ba.volume, max_relative = 1e-12);
        assert!((ab.contact_point - ba.contact_point).length() < 1e-12, "swapped point");
        assert!((ab.normal + ba.normal).length() < 1e-9, "swapped normal");
        let moved = Pose::from_parts(
            Vector::new(0.3, -1.2, 0.7),
            Rotation::from_scaled_axis(Vector::new(-0.4, 0.9, 0.2)),
        );
        let m = compute_overlap(&small, &(moved * pose_a), b, &(moved * pose_b), &s, None)
            .unwrap()
            .unwrap();
        assert_relative_eq!(m.volume, ab.volume, max_relative = 1e-9);
        assert!((m.contact_point - moved.transform_point(ab.contact_point)).length() < 1e-12);
    }
}
