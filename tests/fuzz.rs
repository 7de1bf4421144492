//! Property tests (proptest) over shapes, poses, sizes, materials, velocities and N_c: no
//! panic, no NaN or infinite force, forces equal and opposite when the roles swap, nothing when
//! apart; and the public constructors fed hostile values (NaN, ±∞, 0, negative, 1e300).
//!
//! Soak (six seeds × 20 000 pairs, ~77 000 in contact): none failed; with the plain
//! `n_B − n_A` normal, seed 11 failed at 0.46 engulfment (10 % asymmetry).
//!
//! CI runs the default budget (`PROPTEST_CASES` unset: 256 cases per property) from a fixed
//! seed, so a red run is reproducible and never a roll of the dice; a local soak explores
//! other seeds: `PROPTEST_RNG_SEED=7 PROPTEST_CASES=20000 cargo test --release --test fuzz`.

use discrete_contact::math::{Pose, Real, Rotation, Vector};
use discrete_contact::parry3d_f64::shape::SharedShape;
use discrete_contact::prelude::*;
use proptest::prelude::*;

/// Cases per property unless `PROPTEST_CASES` says otherwise; a fixed seed unless
/// `PROPTEST_RNG_SEED` gives one.
fn config() -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(256);
    let defaults = ProptestConfig::default(); // reads PROPTEST_RNG_SEED
    let rng_seed = if std::env::var_os("PROPTEST_RNG_SEED").is_some() {
        defaults.rng_seed
    } else {
        proptest::test_runner::RngSeed::Fixed(0x5eed_0002)
    };
    ProptestConfig { cases, failure_persistence: None, rng_seed, ..defaults }
}

/// A bounded convex parry shape of size about `s` (m), one of seven kinds (the last the hull of
/// the `hull` directions pushed out to `s`), and its SDF.
fn shape(kind: u8, s: Real, a: Real, b: Real, hull: &[[Real; 3]]) -> (SharedShape, ConvexShape) {
    let (a, b) = (0.2 + a, 0.2 + b); // aspect factors in [0.2, 1.2]
    let parry = match kind % 7 {
        0 => SharedShape::ball(s),
        1 => SharedShape::cuboid(s, a * s, b * s),
        2 => SharedShape::cylinder(a * s, s),
        3 => SharedShape::cone(a * s, s),
        4 => {
            SharedShape::capsule(Vector::new(0.0, -a * s, 0.0), Vector::new(0.0, a * s, 0.0), b * s)
        }
        5 => SharedShape::round_cuboid(s, a * s, b * s, 0.1 * s),
        _ => {
            let points: Vec<Vector> =
                hull.iter().map(|p| Vector::from(*p).normalize_or(Vector::X) * s).collect();
            SharedShape::convex_hull(&points).unwrap_or_else(|| SharedShape::ball(s))
        }
    };
    let sdf = ConvexShape::from_parry(&*parry).expect("a convex parry shape");
    (parry, sdf)
}

/// Ten directions for a random convex hull.
fn hull_points() -> impl Strategy<Value = Vec<[Real; 3]>> {
    prop::collection::vec(prop::array::uniform3(-0.5..0.5f64), 10)
}

prop_compose! {
    /// A rotation and a translation in the unit cube (scaled to the pair's size later).
    fn pose()(x in -1.0..1.0f64, y in -1.0..1.0f64, z in -1.0..1.0f64,
                         rx in -3.2..3.2f64, ry in -3.2..3.2f64, rz in -3.2..3.2f64) -> Pose {
        Pose::from_parts(Vector::new(x, y, z), Rotation::from_scaled_axis(Vector::new(rx, ry, rz)))
    }
}

prop_compose! {
    fn velocity()(v in prop::array::uniform3(-100.0..100.0f64), w in prop::array::uniform3(-1e3..1e3f64)) -> (Vector, Vector) {
        (Vector::from(v), Vector::from(w))
    }
}

prop_compose! {
    /// One random pair: shapes, sizes, poses, velocities, material, resolution, mode.
    fn pair_case()(
        kinds in (0u8..7, 0u8..7),
        scale in -3.0..1.0f64,           // sizes 1 mm … 10 m
        ratio in -1.0..1.0f64,           // B's size relative to A: 0.1 … 10
        aspect in prop::array::uniform4(0.0..1.0f64),
        hulls in (hull_points(), hull_points()),
        poses in (pose(), pose()),
        velocities in (velocity(), velocity()),
        material in (5.0..12.0f64, 0.0..0.5f64, 0.05..1.0f64),
        grid in (1usize..10, any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>()),
        closeness in 0.0..1.3f64,
        enlargement in (any::<bool>(), -3.0..-1.0f64),
    ) -> PairCase {
        PairCase {
            kinds, scale, ratio, aspect, hulls, poses, velocities, material, grid, closeness,
            enlargement,
        }
    }
}

/// What [`pair_case`] draws.
#[derive(Clone, Debug)]
struct PairCase {
    kinds: (u8, u8),
    scale: Real,
    ratio: Real,
    aspect: [Real; 4],
    /// Directions whose hull is the polyhedron kind.
    hulls: (Vec<[Real; 3]>, Vec<[Real; 3]>),
    poses: (Pose, Pose),
    velocities: ((Vector, Vector), (Vector, Vector)),
    /// log10 E, ν, e.
    material: (Real, Real, Real),
    /// N_c, sub-cell, friction, exact forms (closed-form spheres and exact polyhedra; without
    /// them polyhedral pairs on the grid), smooth bodies' facet layers.
    grid: (usize, bool, bool, bool, bool),
    closeness: Real,
    /// Whether both bodies are enlarged, and by what log10 fraction of A's size.
    enlargement: (bool, Real),
}

/// Checks one pair; returns whether it was in contact.
fn check_pair(c: &PairCase) -> Result<bool, TestCaseError> {
    let PairCase {
        kinds,
        scale,
        ratio,
        aspect,
        hulls,
        poses: (pa, pb),
        velocities: (va, vb),
        material: (modulus, nu, e),
        grid: (n_c, subcell, friction, exact, bulge),
        closeness,
        enlargement: (enlarged, eps),
    } = c.clone();
    let s = 10f64.powf(scale);
    let eps = if enlarged { 10f64.powf(eps) * s } else { 0.0 };
    let (parry_a, a) = shape(kinds.0, s, aspect[0], aspect[1], &hulls.0);
    let (parry_b, b) = shape(kinds.1, s * 10f64.powf(ratio), aspect[2], aspect[3], &hulls.1);
    // B's centre at `closeness` times the sum of the sizes from A's, in a random direction:
    // deep overlaps, grazing touches and pairs just apart.
    let sum = s * (1.0 + 10f64.powf(ratio));
    let pa = Pose::from_parts(pa.translation * sum, pa.rotation);
    let pb = Pose::from_parts(
        pa.translation + pb.translation.normalize_or(Vector::Y) * closeness * sum,
        pb.rotation,
    );
    let material = Material::new(10f64.powf(modulus), nu).unwrap();
    let mut params = PairParameters::new(&material, &material, e).unwrap();
    if friction {
        params = params.with_friction(Friction::new(0.5, 0.3, 1e-3).unwrap());
    }
    let mode = if subcell { IntegrationMode::Subcell } else { IntegrationMode::Count };
    let model = ContactModel::new(
        params,
        OverlapSettings::new(n_c, mode)
            .unwrap()
            .with_closed_form_spheres(exact)
            .with_exact_polyhedra(exact)
            .with_polyhedra_on_grid(!exact)
            .with_facet_bulge(bulge)
            .with_enlargement(eps, eps)
            .unwrap(),
    );
    let ba = BodyState::at_rest(&a, pa).moving(va.0, va.1);
    let bb = BodyState::at_rest(&b, pb).moving(vb.0, vb.1);
    let ab = model.evaluate(&ba, &bb, &mut None);
    let rev = model.evaluate(&bb, &ba, &mut None);
    let (ab, rev) = match (ab, rev) {
        (Ok(x), Ok(y)) => (x, y),
        (x, y) => return Err(TestCaseError::fail(format!("refused a valid pair: {x:?} / {y:?}"))),
    };
    // Apart (by parry's exact distance, with a margin for the grid): no force either way.
    // Parry's GJK stops on absolute tolerances, which at millimetre sizes can overstate a gap
    // by 10 %; it is asked at unit size, where it converges, and scaled back.
    let (unit_a, _) = shape(kinds.0, 1.0, aspect[0], aspect[1], &hulls.0);
    let (unit_b, _) = shape(kinds.1, 10f64.powf(ratio), aspect[2], aspect[3], &hulls.1);
    let unit = |p: Pose| Pose::from_parts(p.translation / s, p.rotation);
    let gap =
        discrete_contact::parry3d_f64::query::distance(&unit(pa), &*unit_a, &unit(pb), &*unit_b)
            .map_or(0.0, |d| d.distance * s);
    // The enlargement rounds a body by `ε`, except in the exact polyhedral form, which moves
    // the faces out and so a sharp vertex by more (unboundedly for a sharp one): no bound there.
    let sharp = exact && eps > 0.0;
    if gap > 2.0 * eps + 1e-9 * s && !sharp {
        prop_assert!(ab.is_none() && rev.is_none(), "force at distance {gap}");
    }
    match (ab, rev) {
        (Some(x), Some(y)) => {
            let f = x.force;
            for v in [f.force_on_a, f.torque_on_a, f.torque_on_b] {
                prop_assert!(v.is_finite(), "non-finite output {f:?}");
            }
            prop_assert!(f.normal_force >= 0.0);
            let size = f.force_on_a.length().max(y.force.force_on_a.length());
            // Same pair, roles swapped: equal and opposite up to the root finder's tolerance —
            // while neither body is mostly inside the other. Beyond half the smaller body's
            // volume the overlap's surface is nearly that body's whole (closed) surface, its
            // area vector a small difference of large facets, and the normal has no robust
            // direction (soaks saw 5–9 % asymmetry there, an arbitrary one for a body wholly
            // inside); the drop-in refuses such depths before they happen (indentation limit),
            // so only finite output is asserted for them.
            let smaller =
                parry_a.mass_properties(1.0).mass().min(parry_b.mass_properties(1.0).mass());
            if x.geometry.volume <= 0.5 * smaller {
                prop_assert!(
                    (f.force_on_a + y.force.force_on_a).length() <= 1e-6 * size + 1e-300,
                    "asymmetric: {:?} vs {:?} (overlap {:.2} of the smaller body)",
                    f.force_on_a,
                    y.force.force_on_a,
                    x.geometry.volume / smaller
                );
            }
        }
        (None, None) => return Ok(false),
        // A grazing touch can be found from one side and missed from the other only when
        // the overlap is below the grid's resolution.
        (Some(x), None) | (None, Some(x)) => {
            prop_assert!(
                x.geometry.volume <= 1e-9 * s * s * s,
                "one-sided contact with volume {}",
                x.geometry.volume
            );
        }
    }
    Ok(true)
}

#[test]
fn random_pairs_give_finite_symmetric_forces() {
    let config = config();
    let cases = config.cases as usize;
    let touching = std::sync::atomic::AtomicUsize::new(0);
    let mut runner = proptest::test_runner::TestRunner::new(config);
    let result = runner.run(&pair_case(), |c| {
        if check_pair(&c)? {
            touching.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e}");
    }
    let touching = touching.into_inner();
    println!("{cases} random pairs, {touching} in contact: none failed");
    // The budget is spent on contacts, not on misses.
    assert!(touching * 4 >= cases, "only {touching} of {cases} pairs touched");
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn constructors_refuse_hostile_values(v in prop_oneof![
        Just(Real::NAN), Just(Real::INFINITY), Just(Real::NEG_INFINITY), Just(0.0), Just(-1.0),
        Just(1e300), Just(-1e300), Just(Real::MIN_POSITIVE), any::<f64>()
    ]) {
        // Each call either accepts (finite, in range) or returns an error — never panics.
        let _ = Material::new(v, 0.3);
        let _ = Material::new(1e9, v);
        let _ = ConvexShape::ball(v);
        let _ = ConvexShape::cuboid(Vector::new(v, 1.0, 1.0));
        let _ = ConvexShape::cylinder(v, v);
        let _ = ConvexShape::cone(1.0, v);
        let _ = ConvexShape::capsule(Vector::ZERO, Vector::new(v, 0.0, 0.0), 1.0);
        let _ = ConvexShape::half_space(Vector::new(v, 0.0, 0.0));
        let _ = ConvexShape::convex_hull(&[Vector::ZERO, Vector::X, Vector::Y, Vector::new(0.0, 0.0, v)]);
        let m = Material::new(1e9, 0.3).unwrap();
        let _ = PairParameters::new(&m, &m, v);
        let _ = Friction::new(v, 0.1, 1e-3);
        let _ = Friction::new(0.5, 0.1, v);
        let _ = discrete_contact::damping_from_restitution(v, 1.0);
        let _ = discrete_contact::damping_from_restitution(0.5, v);
        let _ = OverlapSettings::new(3, IntegrationMode::Subcell).unwrap().with_enlargement(v, 0.0);
        let _ = discrete_contact::rapier::DiscreteContacts::new(OverlapSettings::new(3, IntegrationMode::Subcell).unwrap(), v);
        let _ = discrete_contact::coupling::FluidSettings::new(v, 1e-4, 1e-6, 1000.0);
        let _ = discrete_contact::coupling::FluidSettings::new(1e-3, v, 1e-6, 1000.0);
        // Out-of-range values are refused by name.
        if !(v.is_finite() && v > 0.0) {
            prop_assert!(Material::new(v, 0.3).is_err());
            prop_assert!(ConvexShape::ball(v).is_err());
            prop_assert!(discrete_contact::coupling::FluidSettings::new(v, 1e-4, 1e-6, 1000.0).is_err());
        }
        if !(v > 0.0 && v <= 1.0) {
            prop_assert!(PairParameters::new(&m, &m, v).is_err());
        }
    }

    #[test]
    fn hostile_poses_are_refused_not_propagated(v in prop_oneof![Just(Real::NAN), Just(Real::INFINITY), Just(Real::NEG_INFINITY)], which in 0usize..4) {
        let ball = ConvexShape::ball(0.01).unwrap();
        let m = Material::new(1e9, 0.3).unwrap();
        let model = ContactModel::new(PairParameters::new(&m, &m, 0.5).unwrap(), OverlapSettings::new(4, IntegrationMode::Subcell).unwrap());
        let mut t = [Vector::new(0.0, 0.0, 0.0), Vector::new(0.0, 0.019, 0.0)];
        let mut vel = Vector::ZERO;
        match which {
            0 => t[0].x = v,
            1 => t[1].y = v,
            2 => vel.y = v,
            _ => vel.z = v,
        }
        let a = BodyState::at_rest(&ball, Pose::from_translation(t[0])).moving(vel, Vector::ZERO);
        let b = BodyState::at_rest(&ball, Pose::from_translation(t[1]));
        match model.evaluate(&a, &b, &mut None) {
            Err(_) | Ok(None) => {}
            Ok(Some(out)) => prop_assert!(false, "a non-finite input gave a force: {:?}", out.force),
        }
    }
}
