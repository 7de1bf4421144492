//! Geometry reuse: between full evaluations a live contact's overlap follows the pair's small
//! relative motion; impacts, tilts, rolling, spinning and a lens's exact law against evaluating
//! in full every time.

use discrete_contact::prelude::*;
use discrete_contact::ContactState;

#[path = "common/contact.rs"]
mod shared;
use shared::*;

/// Geometry reuse between full evaluations changes an impact's restitution and peak force by
/// less than 1 % against evaluating in full every time — a sphere (a cap, `V ∝ d²`), a cube
/// falling on its corner (`V ∝ d³`) and a slightly tilted cube (corner, then edge, then face:
/// the exponent falls from 3 towards 1 during the impact) — while skipping most full
/// evaluations; set far too loose (100× the default allowance), the tilted cube's impact goes
/// wrong, since its volume law changes faster than such rare full evaluations follow.
#[test]
fn geometry_reuse_keeps_impacts_as_full_evaluation_gives_them() {
    let mat = Material::new(5e8, 0.35).unwrap();
    let full_model = |n| {
        ContactModel::new(
            PairParameters::new(&mat, &mat, 0.8).unwrap(),
            settings(n, IntegrationMode::Subcell),
        )
    };
    let r = 0.005;
    let ball = ConvexShape::ball(r).unwrap();
    let cube = ConvexShape::cuboid(Vector::splat(r)).unwrap();
    // The cube's diagonal (1, 1, 1) turned to point down.
    let corner_down = Rotation::from_rotation_arc(Vector::ONE.normalize(), -Vector::Y);
    let mass = 7800.0 * 8.0 * r.powi(3);
    let tilted = Rotation::from_rotation_x(0.0005) * Rotation::from_rotation_z(0.0015);
    let tilted_lowest = (0..8)
        .map(|i| -(tilted * Vector::new([-r, r][i & 1], [-r, r][(i >> 1) & 1], [-r, r][i >> 2])).y)
        .fold(0.0, f64::max);
    let cases = [
        ("sphere", &ball, Rotation::IDENTITY, r),
        ("cube corner", &cube, corner_down, r * 3f64.sqrt()),
        ("tilted cube", &cube, tilted, tilted_lowest),
    ];
    for (name, shape, rotation, lowest) in cases {
        let reference = drop_on_wall(&full_model(6), shape, rotation, lowest, mass);
        let reused = drop_on_wall(
            &full_model(6).with_geometry_reuse(discrete_contact::contact::GEOMETRY_REUSE).unwrap(),
            shape,
            rotation,
            lowest,
            mass,
        );
        let loose = drop_on_wall(
            &full_model(6)
                .with_geometry_reuse(100.0 * discrete_contact::contact::GEOMETRY_REUSE)
                .unwrap(),
            shape,
            rotation,
            lowest,
            mass,
        );
        let error = |run: (f64, f64, usize, usize)| {
            ((run.0 / reference.0 - 1.0).abs(), (run.1 / reference.1 - 1.0).abs())
        };
        let (e_v, e_f) = error(reused);
        println!("{name}: rebound {:.5} / {:.5} (full / reused), peak force {:.4} / {:.4} N, full evaluations {} of {}; loose: rebound {:.5}, peak {:.4} N, {} full", reference.0, reused.0, reference.1, reused.1, reused.2, reused.3, loose.0, loose.1, loose.2);
        assert_eq!(reference.2, reference.3, "reuse off evaluates in full every time");
        assert!(
            e_v < 0.01 && e_f < 0.01,
            "{name}: rebound off by {e_v:.4}, peak force by {e_f:.4}"
        );
        assert!(
            reused.2 * 2 < reused.3,
            "{name}: reuse skipped too few full evaluations ({} of {})",
            reused.2,
            reused.3
        );
        if name == "tilted cube" {
            let (l_v, l_f) = error(loose);
            assert!(
                l_v.max(l_f) > 0.01,
                "a far too loose bound must show: rebound off by {l_v:.4}, peak by {l_f:.4}"
            );
        }
    }
}

/// A cube (half side `r`, isotropic inertia `2 m r²/3`) dropped at 1 m/s and spinning at
/// `spin` on a wall from `rotation`, integrated with velocity Verlet for its translation and
/// rotation through the contact by `model`: (velocity, angular velocity, peak normal force,
/// full evaluations, all evaluations) after the contact.
fn tumble_on_wall(
    model: &ContactModel,
    r: f64,
    rotation: Rotation,
    spin: Vector,
    mass: f64,
) -> (Vector, Vector, f64, usize, usize) {
    let cube = ConvexShape::cuboid(Vector::splat(r)).unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let wall = BodyState::at_rest(&floor, Pose::IDENTITY);
    let inertia = 2.0 / 3.0 * mass * r * r;
    let lowest = (0..8)
        .map(|i| {
            -(rotation * Vector::new([-r, r][i & 1], [-r, r][(i >> 1) & 1], [-r, r][i >> 2])).y
        })
        .fold(0.0, f64::max);
    let (mut x, mut q, mut v, mut w) =
        (Vector::new(0.0, lowest + 1e-7, 0.0), rotation, -Vector::Y, spin);
    let dt = 2e-7;
    let (mut state, mut peak, mut full, mut all) = (None, 0.0f64, 0, 0);
    let mut load =
        |x: Vector, q: Rotation, v: Vector, w: Vector, state: &mut Option<ContactState>| {
            let body = BodyState::at_rest(&cube, Pose::from_parts(x, q)).moving(v, w);
            let out = model.evaluate(&body, &wall, state).unwrap();
            if let Some(o) = &out {
                (peak, full, all) =
                    (peak.max(o.force.normal_force), full + usize::from(o.full()), all + 1);
            }
            out.map_or((Vector::ZERO, Vector::ZERO), |o| (o.force.force_on_a, o.force.torque_on_a))
        };
    let (mut f, mut t) = load(x, q, v, w, &mut state);
    let mut touched = false;
    for _ in 0..100_000 {
        let (v_half, w_half) = (v + f * (0.5 * dt / mass), w + t * (0.5 * dt / inertia));
        x += v_half * dt;
        q = (Rotation::from_scaled_axis(w_half * dt) * q).normalize();
        (f, t) = load(x, q, v_half, w_half, &mut state);
        (v, w) = (v_half + f * (0.5 * dt / mass), w_half + t * (0.5 * dt / inertia));
        touched |= state.is_some();
        if touched && state.is_none() {
            break;
        }
    }
    assert!(touched && state.is_none(), "contact did not end");
    (v, w, peak, full, all)
}

/// Geometry reuse keeps a spinning cube's impact on an edge or a corner as full evaluation
/// gives it while the cube turns during the contact: the rebound velocity and the peak force
/// within 1 % (of the velocity change and of the peak), the spin within 2 % of its change;
/// set far too loose (100× the default allowance), some impact leaves these bounds.
#[test]
fn geometry_reuse_keeps_a_spinning_cubes_impact_as_full_evaluation_gives_it() {
    let mat = Material::new(5e8, 0.35).unwrap();
    let model = |reuse: f64| {
        ContactModel::new(
            PairParameters::new(&mat, &mat, 0.8).unwrap(),
            settings(6, IntegrationMode::Subcell),
        )
        .with_geometry_reuse(reuse)
        .unwrap()
    };
    let r: f64 = 0.005;
    let mass = 7800.0 * 8.0 * r.powi(3);
    let edge_down = Rotation::from_rotation_x(0.02) * Rotation::from_rotation_z(0.8);
    let corner_down =
        Rotation::from_rotation_arc(Vector::new(1.0, 1.2, 0.9).normalize(), -Vector::Y);
    let cases = [
        ("edge, spinning about it", edge_down, Vector::new(0.0, 0.0, 60.0)),
        ("edge, spinning across it", edge_down, Vector::new(60.0, 10.0, 0.0)),
        ("corner, tumbling", corner_down, Vector::new(40.0, -20.0, 50.0)),
    ];
    let mut loose_shows = false;
    for (name, rotation, spin) in cases {
        let reference = tumble_on_wall(&model(0.0), r, rotation, spin, mass);
        let (dv, dw) = (reference.0 + Vector::Y, reference.1 - spin);
        let errors = |run: &(Vector, Vector, f64, usize, usize)| {
            (
                (run.0 - reference.0).length() / dv.length(),
                (run.1 - reference.1).length() / dw.length(),
                (run.2 / reference.2 - 1.0).abs(),
            )
        };
        let within = |(e_v, e_w, e_f): (f64, f64, f64)| e_v < 0.01 && e_w < 0.02 && e_f < 0.01;
        let reuse = discrete_contact::contact::GEOMETRY_REUSE;
        let reused = tumble_on_wall(&model(reuse), r, rotation, spin, mass);
        let loose = tumble_on_wall(&model(100.0 * reuse), r, rotation, spin, mass);
        let (e, l) = (errors(&reused), errors(&loose));
        println!(
            "{name}: errors (velocity, spin, peak) {e:.4?}, full evaluations {} of {}; far too loose {l:.4?}",
            reused.3, reused.4
        );
        assert_eq!(reference.3, reference.4, "reuse off evaluates in full every time");
        assert!(within(e), "{name}: errors (velocity, spin, peak force) {e:.4?}");
        assert!(reused.3 * 2 < reused.4, "{name}: reuse skipped too few full evaluations");
        loose_shows |= !within(l);
    }
    assert!(loose_shows, "a far too loose bound must show");
}

/// A face resting on a face, rocked: the updates between full evaluations move the contact
/// point across the face as the overlap's uneven depth moves its centroid, so the restoring
/// torque of a rocking body follows the rocking without a full evaluation (a cube pressed
/// 20 µm into the floor, turned by up to 0.08 mrad about its centre: the centroid moves by
/// up to 0.04 mm). The updated contact point and the torque about the cube's centre agree
/// with a full evaluation's within 5 % of what the tilt changed.
#[test]
fn geometry_reuse_moves_the_contact_point_as_a_tilt_does() {
    for angle in [3e-5, -5e-5, 8e-5] {
        let turn = Rotation::from_rotation_z(angle) * Rotation::from_rotation_x(0.4 * angle);
        let t = Tilted::cube_on_the_floor(Rotation::IDENTITY, turn);
        let (moved, off, turned, t_off) = t.errors();
        println!("{angle:+.0e} rad: centroid moved {moved:.3e} m, update off by {off:.3e} m; torque changed {turned:.3e} N m, update off by {t_off:.3e} N m");
        assert!(!t.updated.full(), "a tilt of {angle} rad within the allowance is an update");
        assert!(moved > 1e-5, "the tilt must move the centroid ({moved:.3e} m)");
        assert!(off <= 0.05 * moved, "contact point off by {off:.3e} m of {moved:.3e} m");
        assert!(t_off <= 0.05 * turned, "torque off by {t_off:.3e} of {turned:.3e} N m");
    }
}

/// A cube pressed 20 µm into the floor on an edge (turned 0.6 rad about the edge's axis), then
/// turned by up to 0.1 mrad about axes across and along the edge: the edge dips at one end, so
/// the centroid runs along it by tens of µm. The surfaces meet at an angle, so no footprint
/// follows the tilt; the update follows it by A's flux (Reynolds' transport over the cube's
/// faces within the floor): its contact point within 5 % of what the tilt changed, its
/// torque about the cube's centre within 10 %, and its volume within 10 % (the approach's
/// share follows the volume law, whose depth rate at first touch is the flux's: a wedge's
/// depth through its centroid grows as 2/3 of its deepest).
#[test]
fn geometry_reuse_follows_a_tilt_on_an_edge() {
    for angle in [3e-5, -6e-5, 1e-4] {
        let turn = Rotation::from_rotation_x(angle) * Rotation::from_rotation_z(0.3 * angle);
        let t = Tilted::cube_on_the_floor(Rotation::from_rotation_z(0.6), turn);
        let (moved, off, turned, t_off) = t.errors();
        let [v0, v1, v] = [&t.level, &t.exact, &t.updated].map(|o| o.geometry.volume);
        println!("{angle:+.0e} rad: volume {v0:.4e} -> {v1:.4e} m³, update {v:.4e}; centroid moved {moved:.3e} m, update off by {off:.3e} m; torque changed {turned:.3e} N m, update off by {t_off:.3e} N m");
        assert!(!t.updated.full(), "a tilt of {angle} rad within the allowance is an update");
        assert!(moved > 1e-5, "the tilt must move the centroid ({moved:.3e} m)");
        assert!((v - v1).abs() <= 0.1 * (v1 - v0).abs(), "volume {v:.4e}, full {v1:.4e}");
        assert!(off <= 0.05 * moved, "contact point off by {off:.3e} m of {moved:.3e} m");
        assert!(t_off <= 0.1 * turned, "torque off by {t_off:.3e} of {turned:.3e} N m");
    }
}

/// Bodies of the drop-in scene (rubber, sub-cell `N_c = 4`, the default geometry reuse) pressed
/// 20 µm and 100 µm into the floor — a cube on an edge and on a face 0.01 rad off level, a
/// cylinder on its rim and lying on its side, and a cube's edge and a cylinder's rim at 45°,
/// their contact point on the edge's bisector — then turned about their contact point by
/// `θ = ρ d / reach` (`d` the indentation, `reach` the overlap's extent) about three axes, for
/// ρ from 0.25 to 2: a turn with no approach, which only the tilt allowance bounds. Every
/// update the allowance lets through is within 3 % of the full evaluation's force and 1 % of
/// the reach in its contact point (2 % on a rim's bisector; an update follows the tilt to first
/// order, so what it misses grows as ρ²: ~2 % at ρ = 0.5, ~7 % at 1, ~20 % at 2), and tilts up
/// to ρ = 0.5 are updated, not evaluated in full: the allowance admits the tilt whose error
/// matches the approach's at its own limit. On a bisector too: a body's gradient there jumps
/// from face to face (side) as the contact point crosses, and the update takes it from the
/// face it came from, so the jump is no tilt.
#[test]
fn geometry_reuse_bounds_a_tilt_by_its_error() {
    // Bodies at rest: the restitution's damping adds nothing.
    let (full, reuse) = full_and_reused(5e6, 0.35, 4);
    let r = 0.005;
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let wall = BodyState::at_rest(&floor, Pose::IDENTITY);
    let cube = ConvexShape::cuboid(Vector::splat(r)).unwrap();
    let cylinder = ConvexShape::cylinder(r, r).unwrap();
    let cases = [
        ("cube on an edge", &cube, Rotation::from_rotation_z(0.6)),
        ("cube on a face", &cube, Rotation::from_rotation_z(0.01)),
        ("cylinder on its rim", &cylinder, Rotation::from_rotation_z(0.3)),
        ("cylinder lying", &cylinder, Rotation::from_rotation_z(std::f64::consts::FRAC_PI_2)),
        // The contact point on the edge's bisector: a turn moves it across.
        (
            "cube on an edge's bisector",
            &cube,
            Rotation::from_rotation_z(std::f64::consts::FRAC_PI_4),
        ),
        (
            "cylinder on its rim's bisector",
            &cylinder,
            Rotation::from_rotation_z(std::f64::consts::FRAC_PI_4),
        ),
    ];
    let (mut worst, mut worst_bisector, mut updated_at_half, mut bisectors_updated) =
        ((0.0, 0.0), 0.0, 0, 0);
    for (name, shape, base) in cases {
        for depth in [2e-5, 1e-4] {
            let at = |y: Real| Pose::from_parts(Vector::new(0.0, y, 0.0), base);
            let indentation = |pose: Pose| {
                let body = BodyState::at_rest(shape, pose);
                full.evaluate(&body, &wall, &mut None)
                    .unwrap()
                    .map_or(0.0, |o| o.geometry.indentation)
            };
            // The height at which the body is `depth` into the floor.
            let (mut deep, mut shallow) = (0.0, 2.0 * r);
            for _ in 0..50 {
                let y = 0.5 * (deep + shallow);
                if indentation(at(y)) > depth {
                    deep = y
                } else {
                    shallow = y
                }
            }
            let mut state: Option<ContactState> = None;
            let level = reuse.evaluate(&BodyState::at_rest(shape, at(deep)), &wall, &mut state);
            let level = level.unwrap().expect("overlap");
            let reach = state.as_ref().and_then(|s| s.reference).expect("a reference").reach;
            let (d, p) = (level.geometry.indentation, level.geometry.contact_point);
            for rho in [0.25, 0.5, 1.0, 2.0] {
                for axis in [Vector::X, Vector::Z, Vector::new(1.0, 0.0, 1.0).normalize()] {
                    let turn = Rotation::from_axis_angle(axis, rho * d / reach);
                    let pose = Pose::from_parts(p + turn * (at(deep).translation - p), turn * base);
                    let body = BodyState::at_rest(shape, pose);
                    let exact = full.evaluate(&body, &wall, &mut None).unwrap().expect("overlap");
                    let out = reuse.evaluate(&body, &wall, &mut state.clone()).unwrap();
                    let out = out.expect("overlap");
                    if out.refresh.is_some() {
                        continue;
                    }
                    let force = (out.force.force_on_a - exact.force.force_on_a).length()
                        / exact.force.force_on_a.length();
                    let point = (out.geometry.contact_point - exact.geometry.contact_point)
                        .length()
                        / reach;
                    println!(
                        "{name}, {depth:.0e} m, ρ = {rho}: force {force:.4}, point {point:.4}"
                    );
                    updated_at_half += usize::from(rho == 0.5);
                    worst.0 = force.max(worst.0);
                    if name.contains("bisector") {
                        worst_bisector = point.max(worst_bisector);
                        bisectors_updated += usize::from(rho <= 0.5);
                    } else {
                        worst.1 = point.max(worst.1);
                    }
                }
            }
        }
    }
    assert!(worst.0 <= 0.03, "an update's force is {} off the full evaluation's", worst.0);
    assert!(worst.1 <= 0.01, "an update's contact point is {} of the reach off", worst.1);
    assert!(
        worst_bisector <= 0.02,
        "contact point {worst_bisector} of the reach off at a bisector"
    );
    assert!(updated_at_half >= 18, "{updated_at_half} of 36 tilts of ρ = 0.5 updated");
    assert!(bisectors_updated >= 20, "{bisectors_updated} of 24 tilts across a bisector updated");
}

/// A 1 cm cube (E = 500 MPa, sub-cell `N_c = 6`) at an orientation, its lowest corner 20 µm
/// into the floor `y <= 0`, evaluated in full there (`level`); then turned about its centre,
/// evaluated in full (`exact`) and updated from `level` with the default geometry reuse.
struct Tilted {
    centre: Vector,
    level: discrete_contact::contact::ContactOutput,
    exact: discrete_contact::contact::ContactOutput,
    updated: discrete_contact::contact::ContactOutput,
}

impl Tilted {
    fn cube_on_the_floor(base: Rotation, turn: Rotation) -> Self {
        let (full, reuse) = full_and_reused(5e8, 0.35, 6);
        let r = 0.005;
        let cube = ConvexShape::cuboid(Vector::splat(r)).unwrap();
        let floor = ConvexShape::half_space(Vector::Y).unwrap();
        let wall = BodyState::at_rest(&floor, Pose::IDENTITY);
        let corner = |c: usize| {
            let sign = |bit: usize| if c & bit == 0 { -r } else { r };
            (base * Vector::new(sign(1), sign(2), sign(4))).y
        };
        let low = (0..8).map(corner).fold(Real::INFINITY, Real::min);
        let centre = Vector::new(0.0, -low - 2e-5, 0.0);
        let evaluate = |m: &ContactModel, turn: Rotation, state: &mut Option<ContactState>| {
            let body = BodyState::at_rest(&cube, Pose::from_parts(centre, turn * base));
            m.evaluate(&body, &wall, state).unwrap().expect("overlap")
        };
        let mut state = None;
        evaluate(&reuse, Rotation::IDENTITY, &mut state);
        Self {
            centre,
            level: evaluate(&full, Rotation::IDENTITY, &mut None),
            exact: evaluate(&full, turn, &mut None),
            updated: evaluate(&reuse, turn, &mut state),
        }
    }

    /// How far the full evaluation's contact point moved with the turn and how far the
    /// update's is from it (m); how much the torque about the centre changed and how far the
    /// update's is from it (N m).
    fn errors(&self) -> (Real, Real, Real, Real) {
        let torque = |o: &discrete_contact::contact::ContactOutput| {
            (o.geometry.contact_point - self.centre).cross(o.force.force_on_a)
        };
        let (exact, updated) = (&self.exact.geometry, &self.updated.geometry);
        (
            (exact.contact_point - self.level.geometry.contact_point).length(),
            (updated.contact_point - exact.contact_point).length(),
            (torque(&self.exact) - torque(&self.level)).length(),
            (torque(&self.updated) - torque(&self.exact)).length(),
        )
    }
}

/// A ball pressed 20 µm onto a cube's edge, then moved across the edge by up to 3 µm: the
/// contact point crosses the edge's bisector, where the gradient inside the cube jumps from one
/// face's normal to the other's. A ball has no orientation, so the overlap depends on its
/// centre alone, which the approach and the travel bound: the move is an update, and its
/// force is within 0.1 % of a full evaluation's, its normal within 1e-3 rad.
#[test]
fn geometry_reuse_moves_a_ball_across_an_edge() {
    let (full, reuse) = full_and_reused(5e8, 0.35, 6);
    let (r, radius) = (0.005, 0.004);
    let cube = ConvexShape::cuboid(Vector::splat(r)).unwrap();
    let ball = ConvexShape::ball(radius).unwrap();
    let edge = BodyState::at_rest(
        &cube,
        Pose::from_parts(Vector::ZERO, Rotation::from_rotation_z(std::f64::consts::FRAC_PI_4)),
    );
    let top = r * std::f64::consts::SQRT_2;
    let at = |x: f64| {
        BodyState::at_rest(&ball, Pose::from_translation(Vector::new(x, top + radius - 2e-5, 0.0)))
    };
    let evaluate = |m: &ContactModel, x: f64, state: &mut Option<ContactState>| {
        m.evaluate(&at(x), &edge, state).unwrap().expect("overlap")
    };
    for x in [1e-6, -2e-6, 3e-6] {
        let mut state = None;
        evaluate(&reuse, 0.0, &mut state);
        let updated = evaluate(&reuse, x, &mut state);
        let exact = evaluate(&full, x, &mut None);
        assert!(
            updated.refresh.is_none(),
            "a move of {x} m across the edge: {:?}",
            updated.refresh
        );
        let (f, f_exact) = (updated.force.force_on_a, exact.force.force_on_a);
        let turn = updated.geometry.normal.angle_between(exact.geometry.normal);
        println!(
            "{x:+.0e} m: force {:.6e} N, full {:.6e} N; normals {turn:.2e} rad apart",
            f.length(),
            f_exact.length()
        );
        assert!((f - f_exact).length() <= 1e-3 * f_exact.length(), "force {f:?}, full {f_exact:?}");
        assert!(turn <= 1e-3, "normals {turn:.2e} rad apart");
    }
}

/// A ball (4 mm) pressed 20 µm onto the middle of a cube's top face (1 cm wide) and rolled
/// over it: its overlap is a cap of its depth alone wherever all of the cap lies on the face,
/// so a roll of 0.5 mm (many grid cells) is an update within 1e-3 of the full evaluation's
/// force, while a roll that takes the cap near the face's edge, where the face may end under
/// it, is evaluated in full (`Refresh::Travel`).
#[test]
fn geometry_reuse_rolls_a_ball_over_a_face() {
    let (full, reuse) = full_and_reused(5e8, 0.35, 6);
    let (r, radius) = (0.005, 0.004);
    let cube = ConvexShape::cuboid(Vector::splat(r)).unwrap();
    let ball = ConvexShape::ball(radius).unwrap();
    let face = BodyState::at_rest(&cube, Pose::IDENTITY);
    let at = |x: f64| {
        // Rolled without slipping: turned by x / radius about z.
        let pose = Pose::from_parts(
            Vector::new(x, r + radius - 2e-5, 0.0),
            Rotation::from_rotation_z(-x / radius),
        );
        BodyState::at_rest(&ball, pose)
    };
    let evaluate = |m: &ContactModel, x: f64, state: &mut Option<ContactState>| {
        m.evaluate(&at(x), &face, state).unwrap().expect("overlap")
    };
    for (x, near_the_edge) in [(5e-4, false), (-5e-4, false), (4.8e-3, true)] {
        let mut state = None;
        evaluate(&reuse, 0.0, &mut state);
        let updated = evaluate(&reuse, x, &mut state);
        if near_the_edge {
            assert_eq!(
                updated.refresh,
                Some(discrete_contact::contact::Refresh::Travel),
                "a roll of {x} m to the edge"
            );
            continue;
        }
        assert!(updated.refresh.is_none(), "a roll of {x} m: {:?}", updated.refresh);
        let exact = evaluate(&full, x, &mut None);
        let (f, f_exact) = (updated.force.force_on_a, exact.force.force_on_a);
        println!("{x:+.0e} m: force {:.6e} N, full {:.6e} N", f.length(), f_exact.length());
        assert!((f - f_exact).length() <= 1e-3 * f_exact.length(), "force {f:?}, full {f_exact:?}");
    }
}

/// A body of revolution is the same body after any turn about its own axis: a cylinder and a
/// capsule lying 20 µm deep on a floor, spun about their axes by up to 0.8 rad in forty steps
/// (each body as A on the floor, and as B under it), keep every update and the first full
/// evaluation's force to round-off (a spin is neither an approach nor a lift); rolled without
/// slipping, they are updated as a full evaluation gives them.
#[test]
fn geometry_reuse_spins_a_body_of_revolution_about_its_axis() {
    let (full, reuse) = full_and_reused(5e8, 0.35, 6);
    let radius = 0.005;
    let cylinder = ConvexShape::cylinder(0.01, radius).unwrap();
    // Parry's capsule along y, as the cylinder's axis.
    let capsule =
        ConvexShape::capsule(Vector::new(0.0, -0.01, 0.0), Vector::new(0.0, 0.01, 0.0), radius)
            .unwrap();
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    let ground = BodyState::at_rest(&floor, Pose::IDENTITY);
    for (name, body) in [("cylinder", &cylinder), ("capsule", &capsule)] {
        // Lying along z, turned by `turn` about its axis, rolled by `x` along the floor.
        let at = |turn: f64, x: f64| {
            let lying = Rotation::from_rotation_x(core::f64::consts::FRAC_PI_2);
            let pose = Pose::from_parts(
                Vector::new(x, radius - 2e-5, 0.0),
                Rotation::from_rotation_z(-turn) * lying,
            );
            BodyState::at_rest(body, pose)
        };
        for body_first in [true, false] {
            let evaluate =
                |m: &ContactModel, turn: f64, x: f64, state: &mut Option<ContactState>| {
                    let out = if body_first {
                        m.evaluate(&at(turn, x), &ground, state)
                    } else {
                        m.evaluate(&ground, &at(turn, x), state)
                    };
                    out.unwrap().expect("overlap")
                };
            let mut state = None;
            let first = evaluate(&reuse, 0.0, 0.0, &mut state).force.force_on_a;
            for k in 1..=40 {
                let turn = 0.02 * k as f64;
                let spun = evaluate(&reuse, turn, 0.0, &mut state);
                assert!(spun.refresh.is_none(), "{name} spun by {turn}: {:?}", spun.refresh);
                let f = spun.force.force_on_a;
                assert!(
                    (f - first).length() <= 1e-9 * first.length(),
                    "{name} spun by {turn}: force {f:?}, first {first:?}"
                );
            }
            let mut state = None;
            evaluate(&reuse, 0.0, 0.0, &mut state);
            let (turn, x) = (0.008, 0.008 * radius);
            let rolled = evaluate(&reuse, turn, x, &mut state);
            assert!(rolled.refresh.is_none(), "{name} rolled: {:?}", rolled.refresh);
            let exact = evaluate(&full, turn, x, &mut None);
            let (f, f_exact) = (rolled.force.force_on_a, exact.force.force_on_a);
            println!("{name} rolled: force {:.6e} N, full {:.6e} N", f.length(), f_exact.length());
            assert!(
                (f - f_exact).length() <= 1e-3 * f_exact.length(),
                "{name} rolled: force {f:?}, full {f_exact:?}"
            );
        }
    }
}

/// A sub-cell model at `N_c = n` for two bodies of Young's modulus `e_mod` and Poisson's
/// ratio `nu` (restitution 0.8) evaluating every contact in full, and the same with the default
/// geometry reuse.
fn full_and_reused(e_mod: f64, nu: f64, n: usize) -> (ContactModel, ContactModel) {
    let m = Material::new(e_mod, nu).unwrap();
    let full = ContactModel::new(
        PairParameters::new(&m, &m, 0.8).unwrap(),
        settings(n, IntegrationMode::Subcell),
    );
    (full, full.with_geometry_reuse(discrete_contact::contact::GEOMETRY_REUSE).unwrap())
}

/// A 1 cm cube on a plank 20 cm long at rest at the origin (its top face at y = 5 mm): the
/// cube, the plank, and the cube's pose 20 µm deep in the plank at `x` along it, sunk `sink`
/// further and turned by `turn` about z.
fn cube_on_a_plank() -> (ConvexShape, ConvexShape, impl Fn(f64, f64, f64) -> Pose) {
    let r = 0.005;
    let cube = ConvexShape::cuboid(Vector::splat(r)).unwrap();
    let plank = ConvexShape::cuboid(Vector::new(0.1, 0.005, 0.02)).unwrap();
    let at = move |x: f64, sink: f64, turn: f64| {
        let centre = Vector::new(x, 0.005 + r - 2e-5 - sink, 0.0);
        Pose::from_parts(centre, Rotation::from_rotation_z(turn))
    };
    (cube, plank, at)
}

/// Geometry reuse measures the approach where the bodies meet, not along the line of their
/// centres: a cube resting near the end of a long plank (the line of the centres nearly along
/// the plank) pressed 3 µm further in is updated as a full evaluation gives it, and slid along
/// the plank it is updated without a full evaluation and without parting.
#[test]
fn geometry_reuse_takes_the_approach_at_the_contact_on_a_long_body() {
    let (full, reuse) = full_and_reused(5e8, 0.35, 6);
    let (cube, plank, cube_at) = cube_on_a_plank();
    let b = BodyState::at_rest(&plank, Pose::IDENTITY);
    let at = |x: f64, sink: f64| BodyState::at_rest(&cube, cube_at(x, sink, 0.0));
    let evaluate =
        |m: &ContactModel, a: &BodyState<ConvexShape>, state: &mut Option<ContactState>| {
            m.evaluate(a, &b, state).unwrap().expect("overlap")
        };
    let start = evaluate(&full, &at(0.08, 0.0), &mut None).geometry;
    // Pressed in.
    let mut state = None;
    evaluate(&reuse, &at(0.08, 0.0), &mut state);
    let updated = evaluate(&reuse, &at(0.08, 3e-6), &mut state);
    let exact = evaluate(&full, &at(0.08, 3e-6), &mut None).geometry;
    assert!(!updated.full(), "3 µm of 20 µm is within the allowance");
    let (dd, dv) = (exact.indentation - start.indentation, exact.volume - start.volume);
    let (off_d, off_v) = (
        (updated.geometry.indentation - exact.indentation).abs(),
        (updated.geometry.volume - exact.volume).abs(),
    );
    println!("pressed: indentation change {dd:.3e} m, update off by {off_d:.3e}; volume change {dv:.3e} m³, off by {off_v:.3e}");
    assert!(
        off_d <= 0.05 * dd && off_v <= 0.05 * dv,
        "pressed: {off_d:.3e} of {dd:.3e} m, {off_v:.3e} of {dv:.3e} m³"
    );
    // Slid along the plank, away from its centre.
    let mut state = None;
    evaluate(&reuse, &at(0.08, 0.0), &mut state);
    let slid = evaluate(&reuse, &at(0.0802, 0.0), &mut state);
    let exact = evaluate(&full, &at(0.0802, 0.0), &mut None).geometry;
    let off = (slid.geometry.indentation / exact.indentation - 1.0).abs();
    println!("slid 0.2 mm: full evaluation {}, indentation off by {off:.2e}", slid.full());
    assert!(
        !slid.full() && off < 0.01,
        "slid: full evaluation {}, indentation off by {off:.2e}",
        slid.full()
    );
}

/// A full evaluation says why it was full: a new contact; with geometry reuse on, the motion
/// that exceeded its allowance (a cube resting 20 µm deep on a plank, so 5 µm of approach at
/// the default reuse): pressed 8 µm further in, turned by 1 mrad about its centre (the face's
/// far edge sinks ~7 µm, the centre does not), slid by 1 mm (the grid's cell is ~1.7 mm); and
/// with reuse off, every evaluation.
#[test]
fn a_full_evaluation_says_why_it_was_full() {
    use discrete_contact::contact::Refresh;
    let (full, reuse) = full_and_reused(5e8, 0.35, 6);
    let (cube, plank, cube_at) = cube_on_a_plank();
    let b = BodyState::at_rest(&plank, Pose::IDENTITY);
    let at = |x: f64, sink: f64, turn: f64| BodyState::at_rest(&cube, cube_at(x, sink, turn));
    let why = |m: &ContactModel, moved: BodyState<ConvexShape>| {
        let mut state = None;
        let first = m.evaluate(&at(0.0, 0.0, 0.0), &b, &mut state).unwrap().expect("overlap");
        assert_eq!(first.refresh, Some(Refresh::FirstTouch));
        m.evaluate(&moved, &b, &mut state).unwrap().expect("overlap").refresh
    };
    assert_eq!(why(&reuse, at(0.0, 1e-6, 0.0)), None, "1 µm of 5 µm is an update");
    assert_eq!(why(&reuse, at(0.0, 8e-6, 0.0)), Some(Refresh::Approach));
    assert_eq!(why(&reuse, at(0.0, 0.0, 1e-3)), Some(Refresh::Tilt));
    assert_eq!(why(&reuse, at(1e-3, 0.0, 0.0)), Some(Refresh::Travel));
    assert_eq!(why(&full, at(0.0, 1e-6, 0.0)), Some(Refresh::Off));
}

/// A ball rolling over a flat face is updated between full evaluations as on a half-space: a
/// face is flat at the contact, so the contact point goes along with the ball and the surfaces
/// do not tilt against each other (as between two balls about the bodies' centres, the contact
/// point would lag the ball and the ball's normal there turn). Over the same roll on a cube's
/// top face, no more full evaluations than on a half-space, and the updated forces within the
/// full evaluations' own scatter.
#[test]
fn a_ball_rolling_on_a_face_is_updated_as_on_a_half_space() {
    let (model, reused) = full_and_reused(1e8, 0.3, 4);
    let (r, depth) = (0.01, 1e-4);
    let ball = ConvexShape::ball(r).unwrap();
    let plane = ConvexShape::half_space(Vector::Y).unwrap();
    let cube = ConvexShape::cuboid(Vector::splat(r)).unwrap();
    let floors = [(&plane, Pose::IDENTITY), (&cube, Pose::from_translation(-r * Vector::Y))];
    let mut runs = Vec::new();
    for (floor, pose) in floors {
        let wall = BodyState::at_rest(floor, pose);
        let (mut state, mut full, mut worst) = (None, 0, 0.0f64);
        // 2 mm of roll in 1 µm steps, the ball turning as it rolls.
        for i in 0..2000 {
            let x = i as f64 * 1e-6;
            let at =
                Pose::from_parts(Vector::new(x, r - depth, 0.0), Rotation::from_rotation_z(-x / r));
            let body = BodyState::at_rest(&ball, at);
            let out = reused.evaluate(&body, &wall, &mut state).unwrap().unwrap();
            full += usize::from(out.full());
            let exact = model.evaluate(&body, &wall, &mut None).unwrap().unwrap();
            let err = (out.force.force_on_a - exact.force.force_on_a).length()
                / exact.force.force_on_a.length();
            worst = worst.max(err);
        }
        runs.push((full, worst));
    }
    let [(full_plane, worst_plane), (full_cube, worst_cube)] = [runs[0], runs[1]];
    println!(
        "full evaluations over the roll: half-space {full_plane}, cube {full_cube}; worst force \
         error {worst_plane:.3e} / {worst_cube:.3e}"
    );
    assert!(
        full_cube <= full_plane + 1,
        "full evaluations {full_cube}, on a half-space {full_plane}"
    );
    // The full evaluations themselves scatter by up to ~2.5 % at N_c = 4 as the cap moves
    // across the grid.
    for worst in [worst_plane, worst_cube] {
        assert!(worst <= 0.03, "force off by {worst:.3e}");
    }
}

/// Two balls pressed together are one lens whatever they turn: a ball spinning against another
/// (its centre still) is updated without a full evaluation, and every update gives the force of
/// the first full evaluation (a full evaluation of the turned ball differs only by where its
/// grid, in a body's frame, falls on the lens).
#[test]
fn a_ball_spinning_against_another_is_updated_without_full_evaluations() {
    let (_, reused) = full_and_reused(1e8, 0.3, 4);
    let r = 0.01;
    let ball = ConvexShape::ball(r).unwrap();
    let other = BodyState::at_rest(&ball, Pose::IDENTITY);
    let (mut state, mut full, mut first) = (None, 0, None);
    // A full turn in 1° steps about an axis across the line of the centres.
    for i in 0..360 {
        let turn = Rotation::from_rotation_x((i as f64).to_radians());
        let at = Pose::from_parts(Vector::new(0.0, 2.0 * r - 2e-4, 0.0), turn);
        let body = BodyState::at_rest(&ball, at);
        let out = reused.evaluate(&body, &other, &mut state).unwrap().unwrap();
        full += usize::from(out.full());
        let f0: Vector = *first.get_or_insert(out.force.force_on_a);
        let err = (out.force.force_on_a - f0).length() / f0.length();
        assert!(err < 1e-9, "turned {i}°: force off by {err:.2e}");
    }
    assert_eq!(full, 1, "only the first touch is evaluated in full");
}

/// A ball pressed into a ball, or into a half-space, overlaps in a lens (a cap) of its depth
/// alone, and an update scales the last full evaluation by the lens's exact law: between full
/// evaluations the volume stays the same multiple of the exact lens's (to round-off), the
/// approach allowance is sixteen times the other shapes' (at the default, the indentation may
/// grow fivefold before a full evaluation), and every update stays within the full
/// evaluations' own scatter of them (N_c = 4). Both bodies carry a contact enlargement, which
/// the lens includes.
#[test]
fn a_lens_is_updated_by_its_exact_law() {
    let m = Material::new(1e8, 0.3).unwrap();
    let eps = 2e-4;
    let settings = settings(4, IntegrationMode::Subcell).with_enlargement(eps, eps).unwrap();
    let model =
        |s: OverlapSettings| ContactModel::new(PairParameters::new(&m, &m, 0.8).unwrap(), s);
    let full = model(settings);
    let reused = full.with_geometry_reuse(discrete_contact::contact::GEOMETRY_REUSE).unwrap();
    let exact = model(settings.with_closed_form_spheres(true));
    let (ra, rb) = (0.01, 0.015);
    let (ball_a, ball_b) = (ConvexShape::ball(ra).unwrap(), ConvexShape::ball(rb).unwrap());
    let floor = ConvexShape::half_space(Vector::Y).unwrap();
    // Along a line of the centres that no grid axis follows.
    let line = Vector::new(0.3, 1.0, 0.2).normalize();
    let cases: [(&str, &ConvexShape, Vector, Vector); 2] = [
        ("lens", &ball_b, line * (ra + rb + 2.0 * eps), line),
        ("cap", &floor, Vector::Y * (ra + 2.0 * eps), Vector::Y),
    ];
    for (name, other, touching, towards_a) in cases {
        let b = BodyState::at_rest(other, Pose::IDENTITY);
        let (mut state, mut full_state, mut exact_state) = (None, None, None);
        let (mut fulls, mut ratio, mut worst) = (0, 0.0, 0.0f64);
        // From 20 µm to 100 µm deep in 1 µm steps.
        for k in 20..=100 {
            let at = Pose::from_translation(touching - towards_a * (k as f64 * 1e-6));
            let a = BodyState::at_rest(&ball_a, at);
            let out = reused.evaluate(&a, &b, &mut state).unwrap().unwrap();
            let reference = full.evaluate(&a, &b, &mut full_state).unwrap().unwrap();
            let lens = exact.evaluate(&a, &b, &mut exact_state).unwrap().unwrap();
            let now = out.geometry.volume / lens.geometry.volume;
            if out.full() {
                fulls += 1;
            } else {
                assert!(
                    (now / ratio - 1.0).abs() < 1e-9,
                    "{name}, {k} µm: the update left the lens's law by {:.2e}",
                    now / ratio - 1.0
                );
            }
            ratio = now;
            let off = (out.force.normal_force / reference.force.normal_force - 1.0).abs();
            worst = worst.max(off);
        }
        println!(
            "{name}: {fulls} full evaluations of 81, force off the full evaluations by {worst:.2e}"
        );
        assert!(fulls <= 2, "{name}: {fulls} full evaluations");
        assert!(worst <= 0.03, "{name}: force off by {worst:.3e}");
    }
}

/// A ball rolling 1 cm per evaluation (0.2 rad: 60 Hz at 0.6 m/s, radius 5 cm) on a floor whose
/// SDF gives loose bounds, so that the overlap's grid lies in the ball's turning frame, where
/// the contact travels across the last box by more than its width: every evaluation finds the
/// whole cap, its volume within 6 % of the floor as a half-space gives it (the `N_c` = 4 grid
/// of a cap tilted against its axes; 5 % measured), never a sliver of the cap left in the last
/// box (before: 0.8 % of the volume every other evaluation).
#[test]
fn a_rolling_balls_contact_is_found_whole_in_the_balls_turning_frame() {
    let ball = ConvexShape::ball(0.05).unwrap();
    let plane = ConvexShape::half_space(Vector::Y).unwrap();
    let loose = discrete_contact::parry3d_f64::bounding_volume::Aabb::new(
        Vector::splat(-1.5),
        Vector::splat(1.5),
    );
    let slab = ConvexShape::custom(|p: Vector| (p.y + 0.1).abs() - 0.1, loose).unwrap();
    let m = Material::new(1e7, 0.3).unwrap();
    let model = ContactModel::new(
        PairParameters::new(&m, &m, 0.5).unwrap(),
        settings(4, IntegrationMode::Subcell),
    );
    let (mut on_plane, mut on_slab) = (None, None);
    for k in 0..12 {
        let turn = Vector::new(1.2, 0.0, -12.0) * (k as f64 / 60.0);
        let centre = Vector::new(-0.44 + 0.01 * k as f64, 0.04978, 0.014 + 0.001 * k as f64);
        let pose = Pose::from_parts(centre, Rotation::from_scaled_axis(turn));
        let volume = |floor: &ConvexShape, state: &mut Option<ContactState>| {
            let (a, b) =
                (BodyState::at_rest(&ball, pose), BodyState::at_rest(floor, Pose::IDENTITY));
            model.evaluate(&a, &b, state).unwrap().expect("in contact").geometry.volume
        };
        let (exact, found) = (volume(&plane, &mut on_plane), volume(&slab, &mut on_slab));
        assert!((found / exact - 1.0).abs() < 0.06, "evaluation {k}: {found:e} against {exact:e}");
    }
}
