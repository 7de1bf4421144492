//! The drop-in for f32 rapier scenes (`rapier3d`): the same contacts as the f64 build where f32
//! resolves them, the same shapes from f32 parry, and a typed refusal where the coordinates
//! cannot resolve a contact.
#![cfg(all(feature = "rapier", feature = "rapier-f32"))]

use discrete_contact::math::{Rotation as R64, Vector as V64};
use discrete_contact::{ConvexShape, Error, Friction, IntegrationMode, Material, OverlapSettings};

/// The ball's speed before the impact (m/s).
const SPEED: f64 = 0.5;
/// The ball's radius (m) and its gap to the floor at the start (m).
const RADIUS: f64 = 0.01;
const GAP: f64 = 2e-5;
/// Steps of 1e-4 s a bounce may take: the slowest approach drawn (80° off the normal,
/// 0.087 m/s along it) crosses the gap in 2.3 steps and its contact lasts 1.1 (Hertz's `t_H`
/// at that speed); every draw's bounce is over within 3.
const MAX_STEPS: usize = 20;

/// Where and how the ball meets the floor.
#[derive(Clone, Copy, Debug)]
struct Draw {
    /// The floor's point under the ball (m).
    offset: V64,
    /// The floor's rotation, its axis times its angle (rad).
    tilt: V64,
    /// The impact's angle off the floor's normal (rad).
    angle: f64,
    /// The direction of the velocity's part along the floor, from the floor's own x axis
    /// towards its z axis (rad).
    azimuth: f64,
}

impl Draw {
    /// The floor flat at `(offset, offset, offset)`, the ball thrown 45° off its normal along x.
    fn at(offset: f64) -> Self {
        Self {
            offset: V64::splat(offset),
            tilt: V64::ZERO,
            angle: std::f64::consts::FRAC_PI_4,
            azimuth: 0.0,
        }
    }

    /// `n` draws from a fixed seed (SplitMix64): the floor's point anywhere within 3 cm of the
    /// origin along each axis, tilted up to 30° about a random axis, the impact 10°–80° off
    /// its normal in any direction along it.
    fn many(n: usize) -> Vec<Self> {
        let mut state = 0x5eed_0071_u64;
        let mut uniform = |lo: f64, hi: f64| {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^= z >> 31;
            lo + (hi - lo) * (z >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let offset =
                    V64::new(uniform(-0.03, 0.03), uniform(-0.03, 0.03), uniform(-0.03, 0.03));
                let axis = V64::new(uniform(-1.0, 1.0), uniform(-1.0, 1.0), uniform(-1.0, 1.0));
                let tilt = axis.normalize() * uniform(0.0, 30f64.to_radians());
                let angle = uniform(10f64.to_radians(), 80f64.to_radians());
                let azimuth = uniform(0.0, std::f64::consts::TAU);
                Self { offset, tilt, angle, azimuth }
            })
            .collect()
    }

    /// The floor's normal.
    fn normal(&self) -> V64 {
        R64::from_scaled_axis(self.tilt) * V64::Y
    }

    /// The ball's velocity before the impact (m/s).
    fn velocity(&self) -> V64 {
        let r = R64::from_scaled_axis(self.tilt);
        let along = r * V64::new(self.azimuth.cos(), 0.0, self.azimuth.sin());
        SPEED * (self.angle.sin() * along - self.angle.cos() * self.normal())
    }

    /// The ball's centre at the start (m).
    fn centre(&self) -> V64 {
        self.offset + (RADIUS + GAP) * self.normal()
    }
}

/// A bounce's outcome in either build.
#[derive(Debug)]
struct Bounce {
    /// The ball's velocity (m/s) and spin (rad/s) after it.
    velocity: V64,
    spin: V64,
    /// The largest sub-step count of a step, and the impact's own sub-steps, summed over the
    /// steps.
    substeps: usize,
    impact_substeps: usize,
    /// Whether the bounce was over within [`MAX_STEPS`]: no live contact, the ball leaving.
    over: bool,
    /// The first step's error where the drop-in refused.
    refused: Option<Error>,
}

/// A steel ball (r = 1 cm) thrown at 0.5 m/s onto a steel floor as `$draw` says, with friction,
/// in either build (`$engine`, `$drop_in`) with `$settings`, until the contact is over (the
/// velocity and spin are final then: no gravity). `$round`: the probe, the f64 build with every
/// body's translation, rotation, velocity and spin rounded to f32 at the start and after every
/// step, and the ball's radius the f32 build's.
macro_rules! oblique_bounce {
    ($engine:ident, $drop_in:ident, $draw:expr, $settings:expr, $round:expr) => {{
        use discrete_contact::$drop_in::{DiscreteContacts, StepPolicy};
        use discrete_contact::$engine::prelude::*;
        type V = discrete_contact::$engine::math::Vector;
        type Q = discrete_contact::$engine::math::Rotation;
        let (draw, round): (Draw, bool) = ($draw, $round);
        let engine = |v: V64| V::new(v.x as _, v.y as _, v.z as _);
        let to_f32 = |v: V| V::new(v.x as f32 as _, v.y as f32 as _, v.z as f32 as _);
        // The probe's rounding: every body's translation, rotation, velocity and spin to f32
        // and back, and its colliders moved with it (rapier moves them at its next step; the
        // drop-in reads them before).
        let round_state = |world: &mut PhysicsWorld| {
            let PhysicsWorld { bodies, colliders, .. } = world;
            for (_, rb) in bodies.iter_mut() {
                let (x, q, l, w) = (rb.translation(), *rb.rotation(), rb.linvel(), rb.angvel());
                let q = Q::from_xyzw(
                    q.x as f32 as _,
                    q.y as f32 as _,
                    q.z as f32 as _,
                    q.w as f32 as _,
                );
                rb.set_translation(to_f32(x), false);
                rb.set_rotation(q, false);
                rb.set_linvel(to_f32(l), false);
                rb.set_angvel(to_f32(w), false);
                let pose = *rb.position();
                for &c in rb.colliders() {
                    let co = &mut colliders[c];
                    if let Some(relative) = co.position_wrt_parent().copied() {
                        co.set_position(pose * relative);
                    }
                }
            }
        };
        let mut world = PhysicsWorld::new();
        world.gravity = V::ZERO;
        world.integration_parameters.dt = 1e-4;
        let floor = world.insert_body(
            RigidBodyBuilder::fixed().translation(engine(draw.offset)).rotation(engine(draw.tilt)),
        );
        world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(V::Y)), Some(floor));
        let ball = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(engine(draw.centre()))
                .linvel(engine(draw.velocity()))
                .can_sleep(false),
        );
        // The probe's ball has the f32 build's radius.
        let radius = if round { RADIUS as f32 as f64 } else { RADIUS };
        world.insert_collider(ColliderBuilder::ball(radius as _).density(7800.0), Some(ball));
        let mut contacts = DiscreteContacts::new($settings, 0.8)
            .unwrap()
            .with_friction(Friction::new(0.3, 0.3, 1e-3).unwrap())
            .with_policy(StepPolicy::AutoSubstep { max_substeps: 10_000 });
        contacts.handle_all(&mut world, Material::new(2e11, 0.3).unwrap()).unwrap();
        let mut bounce = Bounce {
            velocity: V64::ZERO,
            spin: V64::ZERO,
            substeps: 0,
            impact_substeps: 0,
            over: false,
            refused: None,
        };
        if round {
            round_state(&mut world);
        }
        let normal = engine(draw.normal());
        for _ in 0..MAX_STEPS {
            match contacts.step(&mut world) {
                Ok(s) => {
                    bounce.substeps = bounce.substeps.max(s.substeps);
                    bounce.impact_substeps += s.impact_substeps;
                }
                Err(e) => {
                    bounce.refused = Some(e);
                    break;
                }
            }
            if round {
                round_state(&mut world);
            }
            if contacts.contact_count() == 0 && world.bodies[ball].linvel().dot(normal) > 0.0 {
                bounce.over = true;
                break;
            }
        }
        let rb = &world.bodies[ball];
        let (l, w) = (rb.linvel(), rb.angvel());
        bounce.velocity = V64::new(l.x as f64, l.y as f64, l.z as f64);
        bounce.spin = V64::new(w.x as f64, w.y as f64, w.z as f64);
        bounce
    }};
}

/// Draws of the bounce the builds are compared over (see the test).
const DRAWS: usize = 128;

/// How far the f32 build's differences from the f64 build may exceed the probe's (see the
/// test): √2 for its two roundings of an impact step's end state against the probe's one,
/// times 1.5 for the scatter of a ratio of two rms over [`DRAWS`] draws.
const ROUNDINGS: f64 = std::f64::consts::SQRT_2;
const SCATTER: f64 = 1.5;

/// Near the origin the f32 drop-in bounces as the f64 one does, up to what rounding the state to
/// f32 gives. One bounce cannot show it: its difference is one draw of that rounding (the earlier
/// test's 45° bounce at the origin: 2.4e-6 of the rebound velocity today, 1.7e-5 with the facet
/// bulge; 0.8e-4 and 1.9e-4 before impacts had sub-steps of their own; over the draws here up to
/// 2.2e-4). A rounding of the ball's place by half a spacing (5e-10 m at 1 cm) near the peak force
/// moves the rebound speed by up to ~6e-5 (`F δ` against `½ m v_n²`), more where it flips one of
/// the contact's discrete choices (a full evaluation or a reused one). So [`DRAWS`] draws — the
/// floor anywhere within 3 cm of the origin, tilted up to 30°, the ball thrown 10°–80° off its
/// normal in any direction along it — each bounced three ways: (a) the f64 build, (b) the f32
/// build, (c) the probe, the f64 build with its state rounded to f32 at the start (the ball's
/// radius too) and after every step. Each draw's difference of (b) and of (c) from (a), relative,
/// of the rebound velocity and of the spin; their rms over the draws.
///
/// The bound: (b)'s rms at most [`ROUNDINGS`] × [`SCATTER`] times (c)'s, with the facet bulge off
/// (the default) and on.
/// - [`ROUNDINGS`] = √2: under the default `Integration::Implicit` an impact's sub-steps run inside
///   the drop-in in f64, from the f32 state widened, so the f32 build rounds the state at the
///   step's boundaries only, as the probe does — but an impact's step rounds the ball's place
///   twice: where the drop-in places it to start rapier's step (so that, moving with the end
///   velocity, it ends where the sub-steps took it), and rapier's move itself. Two independent
///   roundings of up to half a spacing each where the probe has one: twice the variance, √2 the
///   rms. The velocity's roundings (relative 6e-8) are 1e-3 of these; a step without an impact
///   rounds once in both. An upper estimate: the rounding of the start, the same in both, is part
///   of both differences.
/// - [`SCATTER`] = 1.5: the differences are heavy-tailed (most draws below 3e-5, a few flipped
///   choices at 1e-4–2e-4), so a ratio of two rms over 128 draws scatters: resampling 256 measured
///   draws, its standard error was 9–12 % and its 99.9th percentile 1.67–1.85 in the four
///   comparisons. 1.5 × √2 = 2.12 is ~5 standard errors above √2 (measured: velocity 1.40 / 1.28,
///   spin 1.35 / 1.15, bulge off / on).
///
/// So an f32-only error shows from ~6e-5 of the rebound velocity up, ~3.5e-4 of the spin (whose own
/// rounding is 2e-4 rms): the f32 build's velocity scaled by 1 + 3e-4 fails the bound by a factor
/// 4.1 (3.6 with the bulge). And every draw bounces, in all three: the same sub-step counts (or
/// within one), the rebound's normal speed 0.7–0.9 of the approach's (restitution 0.8), spun by the
/// friction (about the normal crossed with the approach, its rim speed at least a tenth of the
/// approach's speed along the floor).
#[test]
fn oblique_bounces_near_the_origin_agree_in_f32_and_f64_as_rounding_to_f32_does() {
    let draws = Draw::many(DRAWS);
    let plain = OverlapSettings::new(4, IntegrationMode::Subcell).unwrap();
    for (name, settings) in [("bulge off", plain), ("bulge on", plain.with_facet_bulge(true))] {
        // Per draw: the relative differences (velocity, spin) of the f32 build and the probe.
        let mut differences = Vec::new();
        for draw in &draws {
            let a = oblique_bounce!(rapier3d_f64, rapier, *draw, settings, false);
            let b = oblique_bounce!(rapier3d, rapier_f32, *draw, settings, false);
            let c = oblique_bounce!(rapier3d_f64, rapier, *draw, settings, true);
            let (n, v_n, v_t) = (draw.normal(), SPEED * draw.angle.cos(), SPEED * draw.angle.sin());
            let spin_axis = n.cross(draw.velocity()).normalize();
            for (which, x) in [("f64", &a), ("f32", &b), ("probe", &c)] {
                let what = format!("{name}, {which}, {draw:?}");
                assert!(x.refused.is_none() && x.over, "{what}: {:?}", x.refused);
                assert!(
                    x.substeps.abs_diff(a.substeps) <= 1
                        && x.impact_substeps.abs_diff(a.impact_substeps) <= 1,
                    "{what}: sub-steps {}, {} against {}, {}",
                    x.substeps,
                    x.impact_substeps,
                    a.substeps,
                    a.impact_substeps
                );
                let rebound = x.velocity.dot(n) / v_n;
                assert!((0.7..0.9).contains(&rebound), "{what}: rebound {rebound}");
                let rim = x.spin.dot(spin_axis) * RADIUS;
                assert!(rim > 0.1 * v_t, "{what}: spin {:?}, rim speed {rim}", x.spin);
            }
            let relative = |x: V64, y: V64| (x - y).length() / y.length();
            differences.push([
                (relative(b.velocity, a.velocity), relative(c.velocity, a.velocity)),
                (relative(b.spin, a.spin), relative(c.spin, a.spin)),
            ]);
        }
        for (k, quantity) in ["velocity", "spin"].into_iter().enumerate() {
            let rms = |d: &dyn Fn(&(f64, f64)) -> f64| {
                (differences.iter().map(|x| d(&x[k]).powi(2)).sum::<f64>() / DRAWS as f64).sqrt()
            };
            let max = |d: &dyn Fn(&(f64, f64)) -> f64| {
                differences.iter().map(|x| d(&x[k])).fold(0.0, f64::max)
            };
            let (f32_rms, probe_rms) = (rms(&|d| d.0), rms(&|d| d.1));
            let bound = ROUNDINGS * SCATTER * probe_rms;
            eprintln!(
                "{name}, {quantity}: f32 rms {f32_rms:.2e} (max {:.2e}), probe rms {probe_rms:.2e} \
                 (max {:.2e}), ratio {:.2}, bound {bound:.2e}",
                max(&|d| d.0),
                max(&|d| d.1),
                f32_rms / probe_rms
            );
            assert!(
                f32_rms <= bound,
                "{name}, {quantity}: the f32 build's rms difference {f32_rms:.2e} exceeds \
                 √2 × 1.5 times the probe's {probe_rms:.2e}"
            );
        }
    }
}

/// The same bounce 1 km from the origin: f64 still gives it, f32 (spacing 6e-5 m there, more
/// than the impact's whole indentation) refuses the step with the pair, its distance from the
/// origin and what would work, instead of stalling or bouncing wrongly.
#[test]
fn far_from_the_origin_f32_refuses_with_the_distance_and_the_remedy() {
    let plain = OverlapSettings::new(4, IntegrationMode::Subcell).unwrap();
    let f64_bounce = oblique_bounce!(rapier3d_f64, rapier, Draw::at(1000.0), plain, false);
    let (v64, e64) = (f64_bounce.velocity, &f64_bounce.refused);
    assert!(e64.is_none() && v64.y > 0.0, "f64 must bounce 1 km away: {e64:?}, {v64:?}");
    let e32 = oblique_bounce!(rapier3d, rapier_f32, Draw::at(1000.0), plain, false).refused;
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
