//! The drop-in for f32 rapier scenes (`rapier3d`): the same contacts as the f64 build where f32
//! resolves them, the same shapes from f32 parry, and a typed refusal where the coordinates
//! cannot resolve a contact.
#![cfg(all(feature = "rapier", feature = "rapier-f32"))]

use discrete_contact::math::Vector as V64;
use discrete_contact::{ConvexShape, Error, Friction, IntegrationMode, Material, OverlapSettings};

/// A steel ball (r = 1 cm) thrown at 0.5 m/s onto a steel floor 45° off its normal, with
/// friction, in either build: `(rebound velocity, spin, largest sub-step count)` after the
/// bounce, and the first step's error if the drop-in refused.
macro_rules! oblique_bounce {
    ($engine:ident, $drop_in:ident, $offset:expr) => {{
        use discrete_contact::$drop_in::{DiscreteContacts, StepPolicy};
        use discrete_contact::$engine::prelude::*;
        type V = discrete_contact::$engine::math::Vector;
        let offset: f64 = $offset;
        let mut world = PhysicsWorld::new();
        world.gravity = V::ZERO;
        world.integration_parameters.dt = 1e-4;
        let floor = world.insert_body(RigidBodyBuilder::fixed().translation(V::splat(offset as _)));
        world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(V::Y)), Some(floor));
        let v = 0.5 * std::f64::consts::FRAC_1_SQRT_2;
        let ball = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(V::new(offset as _, (offset + 0.01 + 2e-5) as _, offset as _))
                .linvel(V::new(v as _, -v as _, 0.0))
                .can_sleep(false),
        );
        world.insert_collider(ColliderBuilder::ball(0.01).density(7800.0), Some(ball));
        let mut contacts =
            DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.8)
                .unwrap()
                .with_friction(Friction::new(0.3, 0.3, 1e-3).unwrap())
                .with_policy(StepPolicy::AutoSubstep { max_substeps: 10_000 });
        contacts.handle_all(&mut world, Material::new(2e11, 0.3).unwrap()).unwrap();
        let mut substeps = 0;
        let mut outcome = None;
        for _ in 0..200 {
            match contacts.step(&mut world) {
                Ok(s) => substeps = substeps.max(s.substeps),
                Err(e) => {
                    outcome = Some(e);
                    break;
                }
            }
        }
        let rb = &world.bodies[ball];
        let (l, w) = (rb.linvel(), rb.angvel());
        (
            V64::new(l.x as f64, l.y as f64, l.z as f64),
            V64::new(w.x as f64, w.y as f64, w.z as f64),
            substeps,
            outcome,
        )
    }};
}

/// Near the origin the f32 drop-in gives the f64 one's bounce: the same sub-step count, the
/// rebound velocity within 1e-4 and the spin within 2e-3 of the f64 ones (measured: 6e-4; the
/// tangential spring sums the slip from sub-step poses held in f32), and the ball did bounce
/// (it leaves upwards, slowed by the restitution, spun by the friction).
#[test]
fn an_oblique_bounce_near_the_origin_is_the_same_in_f32_and_f64() {
    let (v64, w64, n64, e64) = oblique_bounce!(rapier3d_f64, rapier, 0.0);
    let (v32, w32, n32, e32) = oblique_bounce!(rapier3d, rapier_f32, 0.0);
    assert!(e64.is_none() && e32.is_none(), "refused: {e64:?} / {e32:?}");
    assert_eq!(n64, n32, "sub-steps per step");
    let v_n = 0.5 * std::f64::consts::FRAC_1_SQRT_2;
    assert!(v64.y > 0.7 * v_n && v64.y < 0.9 * v_n, "f64 rebound {v64:?}");
    assert!(w64.length() > 1.0, "f64 spin {w64:?}");
    assert!((v32 - v64).length() < 1e-4 * v64.length(), "velocity {v32:?} vs {v64:?}");
    assert!((w32 - w64).length() < 2e-3 * w64.length(), "spin {w32:?} vs {w64:?}");
}

/// The same bounce 1 km from the origin: f64 still gives it, f32 (spacing 6e-5 m there, more
/// than the impact's whole indentation) refuses the step with the pair, its distance from the
/// origin and what would work, instead of stalling or bouncing wrongly.
#[test]
fn far_from_the_origin_f32_refuses_with_the_distance_and_the_remedy() {
    let (v64, _, _, e64) = oblique_bounce!(rapier3d_f64, rapier, 1000.0);
    assert!(e64.is_none() && v64.y > 0.0, "f64 must bounce 1 km away: {e64:?}, {v64:?}");
    let (_, _, _, e32) = oblique_bounce!(rapier3d, rapier_f32, 1000.0);
    let Some(Error::PrecisionTooLow {
        precision, distance, indentation, spacing, required, ..
    }) = &e32
    else {
        panic!("f32 1 km away must be refused, got {e32:?}")
    };
    assert_eq!(*precision, "f32");
    assert!((1000.0..1000.1).contains(distance), "distance {distance}");
    assert_eq!(*spacing, 2f64.powi(9) * f32::EPSILON as f64, "f32 spacing in [512, 1024) m");
    assert!(*indentation < *required * *spacing);
    let message = e32.unwrap().to_string();
    for words in ["f32", "nearer the origin", "softer material", "f64 build"] {
        assert!(message.contains(words), "message lacks {words:?}: {message}");
    }
}

/// Every shape f32 parry offers converts to the same SDF as its f64 twin: distances at points
/// in and around it agree to f32's round-off of the shape's numbers; a shape that is not a
/// convex solid is refused by name.
#[test]
fn f32_parry_shapes_convert_to_the_same_sdfs_as_f64_ones() {
    use discrete_contact::rapier3d::parry::shape as s32;
    use discrete_contact::rapier3d_f64::parry::shape as s64;
    use discrete_contact::Sdf;
    let hull =
        [[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.0, 0.25, 0.0], [0.0, 0.0, 0.2], [0.2, 0.2, 0.2]];
    let v32 = |p: [f64; 3]| {
        discrete_contact::rapier3d::math::Vector::new(p[0] as f32, p[1] as f32, p[2] as f32)
    };
    let v64 = |p: [f64; 3]| V64::from(p);
    let pairs: Vec<(Box<dyn s32::Shape>, Box<dyn s64::Shape>)> = vec![
        (Box::new(s32::Ball::new(0.125)), Box::new(s64::Ball::new(0.125))),
        (
            Box::new(s32::Cuboid::new(v32([0.1, 0.2, 0.05]))),
            Box::new(s64::Cuboid::new(v64([0.1, 0.2, 0.05]))),
        ),
        (Box::new(s32::Cylinder::new(0.1, 0.05)), Box::new(s64::Cylinder::new(0.1, 0.05))),
        (Box::new(s32::Cone::new(0.1, 0.05)), Box::new(s64::Cone::new(0.1, 0.05))),
        (
            Box::new(s32::Capsule::new(v32([0.0, -0.1, 0.0]), v32([0.05, 0.1, 0.0]), 0.03)),
            Box::new(s64::Capsule::new(v64([0.0, -0.1, 0.0]), v64([0.05, 0.1, 0.0]), 0.03)),
        ),
        (
            Box::new(s32::ConvexPolyhedron::from_convex_hull(&hull.map(v32)).unwrap()),
            Box::new(s64::ConvexPolyhedron::from_convex_hull(&hull.map(v64)).unwrap()),
        ),
        (
            Box::new(s32::RoundCuboid {
                inner_shape: s32::Cuboid::new(v32([0.1, 0.2, 0.05])),
                border_radius: 0.01,
            }),
            Box::new(s64::RoundCuboid {
                inner_shape: s64::Cuboid::new(v64([0.1, 0.2, 0.05])),
                border_radius: 0.01,
            }),
        ),
        (
            Box::new(s32::HalfSpace::new(v32([0.0, 1.0, 0.0]))),
            Box::new(s64::HalfSpace::new(v64([0.0, 1.0, 0.0]))),
        ),
    ];
    for (a, b) in &pairs {
        let (a, b) = (
            ConvexShape::from_parry_f32(a.as_ref()).unwrap(),
            ConvexShape::from_parry(b.as_ref()).unwrap(),
        );
        for k in 0..200 {
            // Points on a spiral through the shape and 0.2 m around it.
            let t = k as f64 * 0.37;
            let p = V64::new(0.3 * (t * 0.9).sin(), 0.3 * (t * 0.5).cos(), 0.3 * (t * 0.3).sin())
                * (k as f64 / 200.0);
            let (da, db) = (a.distance(p), b.distance(p));
            assert!((da - db).abs() < 1e-7, "{a:?} at {p:?}: {da} (f32) vs {db} (f64)");
        }
    }
    let mesh = s32::TriMesh::new(
        vec![v32([0.0; 3]), v32([1.0, 0.0, 0.0]), v32([0.0, 1.0, 0.0])],
        vec![[0, 1, 2]],
    )
    .unwrap();
    assert!(matches!(
        ConvexShape::from_parry_f32(&mesh),
        Err(Error::UnsupportedShape { shape, .. }) if shape == "TriMesh"
    ));
}
