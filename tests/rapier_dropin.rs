//! The drop-in in a rapier world: the cylinder–wall impact against Park (2003), the user's
//! forces survive, and a step that cannot resolve a contact is refused with advice.
#![cfg(feature = "rapier")]

use discrete_contact::rapier::{DiscreteContacts, ParaViewSeries, StepPolicy};
use discrete_contact::rapier3d_f64::prelude::*;
use discrete_contact::{Error, IntegrationMode, Material, OverlapSettings};
use discrete_contact_validation::cylinder_impact::{park, simulate};

/// Measured: at most 0.013 off Park for v+/v and R ω+/v over 10°…80° (sub-cell, N_c = 8).
#[test]
fn cylinder_impact_matches_park_within_0_05() {
    let s = OverlapSettings::new(8, IntegrationMode::Subcell).unwrap();
    for theta in [10.0, 25.0, 40.0, 55.0, 70.0, 80.0] {
        let r = simulate(theta, s).unwrap();
        let (v, w) = park(theta);
        assert!((r.v_ratio - v).abs() < 0.05, "θ = {theta}: v+/v {} vs {v}", r.v_ratio);
        assert!(
            (r.omega_r_ratio - w).abs() < 0.05,
            "θ = {theta}: Rω+/v {} vs {w}",
            r.omega_r_ratio
        );
    }
}

fn ball_on_floor(dt: f64, policy: StepPolicy) -> (PhysicsWorld, DiscreteContacts, RigidBodyHandle) {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = dt;
    let floor = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(
        ColliderBuilder::new(SharedShape::halfspace(discrete_contact::math::Vector::Y)),
        Some(floor),
    );
    let ball = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(discrete_contact::math::Vector::new(0.0, 0.0101, 0.0))
            .linvel(discrete_contact::math::Vector::new(0.0, -2.0, 0.0)),
    );
    world.insert_collider(ColliderBuilder::ball(0.01).density(7800.0), Some(ball));
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.9)
            .unwrap()
            .with_policy(policy);
    contacts.handle_all(&mut world, Material::new(2e11, 0.3).unwrap()).unwrap();
    (world, contacts, ball)
}

#[test]
fn a_step_too_large_for_the_contact_is_refused_with_advice() {
    let (mut world, mut contacts, _) = ball_on_floor(1e-3, StepPolicy::Fixed { substeps: 1 });
    // The first step finds the candidate pair; the next must refuse.
    let mut refused = None;
    for _ in 0..3 {
        if let Err(e) = contacts.step(&mut world) {
            refused = Some(e);
            break;
        }
    }
    match refused {
        Some(Error::TimeStepTooLarge { dt, recommended, substeps_needed, .. }) => {
            assert_eq!(dt, 1e-3);
            assert!(recommended < 1e-5 && substeps_needed > 100, "{recommended} {substeps_needed}");
        }
        other => panic!("expected TimeStepTooLarge, got {other:?}"),
    }
}

#[test]
fn automatic_substeps_resolve_a_stiff_impact_and_keep_user_forces() {
    let (mut world, mut contacts, ball) =
        ball_on_floor(1e-4, StepPolicy::AutoSubstep { max_substeps: 5000 });
    // A user force: pushes sideways; it must act exactly as without the contact model.
    world.bodies[ball].add_force(discrete_contact::math::Vector::new(1e-3, 0.0, 0.0), true);
    let mut max_sub = 0;
    for _ in 0..20 {
        // The world's sub-steps, or the impact's own (implicit integration).
        let s = contacts.step(&mut world).unwrap();
        max_sub = max_sub.max(s.substeps + s.impact_substeps);
    }
    let rb = &world.bodies[ball];
    assert!(max_sub > 1, "no sub-stepping happened");
    assert_eq!(rb.user_force(), discrete_contact::math::Vector::new(1e-3, 0.0, 0.0));
    // Bounced: moving up with about e × 2 m/s, never through the floor.
    assert!(rb.linvel().y > 1.5 && rb.linvel().y <= 2.0, "rebound {}", rb.linvel().y);
    assert!(rb.translation().y > 0.0099);
}

/// A fixed policy divides the step into exactly its sub-steps, impacts included: the ball's
/// one contact is evaluated once per sub-step, not once per sub-step of each sub-step.
#[test]
fn a_fixed_policy_takes_its_sub_steps_and_no_more() {
    let (mut world, mut contacts, ball) = ball_on_floor(1e-5, StepPolicy::Fixed { substeps: 8 });
    let mut in_contact = 0;
    for _ in 0..400 {
        let s = contacts.step(&mut world).unwrap();
        assert!(s.substeps + s.impact_substeps <= 2 * 8, "{} + {}", s.substeps, s.impact_substeps);
        assert!(s.evaluations <= 8, "{} evaluations of one pair in 8 sub-steps", s.evaluations);
        in_contact += usize::from(s.evaluations > 0);
    }
    assert!(in_contact > 1, "the ball never touched the floor");
    assert!(world.bodies[ball].linvel().y > 1.5, "no rebound: {}", world.bodies[ball].linvel().y);
}

/// A step refused while a contact lives (a body's velocity made NaN between steps) loses no
/// contact: the ball is still pressed into the floor when the next step, with the velocity
/// mended, resumes, and its force keeps it out of the floor.
#[test]
fn a_refused_step_keeps_the_live_contacts() {
    let (mut world, mut contacts, ball) =
        ball_on_floor(1e-4, StepPolicy::AutoSubstep { max_substeps: 5000 });
    let in_contact = |contacts: &DiscreteContacts, world: &PhysicsWorld| {
        let colliders: Vec<ColliderHandle> = world.colliders.iter().map(|(h, _)| h).collect();
        contacts.contact(colliders[0], colliders[1]).is_some()
    };
    // Into the floor: the impact is in its compression.
    let mut steps = 0;
    while !in_contact(&contacts, &world) {
        contacts.step(&mut world).unwrap();
        steps += 1;
        assert!(steps < 20, "the ball never touched the floor");
    }
    let velocity = world.bodies[ball].linvel();
    world.bodies[ball].set_linvel(discrete_contact::math::Vector::splat(f64::NAN), true);
    let refused = contacts.step(&mut world);
    assert!(matches!(refused, Err(Error::NonFinite { .. })), "{refused:?}");
    assert_eq!(contacts.contact_count(), 1);
    assert!(in_contact(&contacts, &world), "the refused step dropped the contact");
    world.bodies[ball].set_linvel(velocity, true);
    for _ in 0..20 {
        contacts.step(&mut world).unwrap();
    }
    let rb = &world.bodies[ball];
    assert!(rb.linvel().y > 1.5 && rb.translation().y > 0.0099, "v {}", rb.linvel().y);
}

/// A fast subset of the stability matrix (the full one: `cargo run --release --example
/// stability_report`).
#[test]
fn stability_cases_end_right_or_are_refused() {
    use discrete_contact_validation::stability::{Case, Verdict};
    let expect = [
        (Case::NormalImpact { youngs: 2e11, speed: 30.0, restitution: 0.85 }, Verdict::Ok),
        (Case::NormalImpact { youngs: 5e8, speed: 0.01, restitution: 0.1 }, Verdict::Ok),
        (Case::NormalImpact { youngs: 5e8, speed: 1.0, restitution: 1.0 }, Verdict::Ok),
        (Case::NormalImpact { youngs: 1e6, speed: 30.0, restitution: 0.85 }, Verdict::Refused),
        (Case::MassRatio { ratio: 1000.0 }, Verdict::Ok),
        (Case::Grazing, Verdict::Ok),
        (Case::ThinPlate, Verdict::Ok),
        (Case::RefusedStep, Verdict::Refused),
        (Case::Resting { steps: 2000, dt: 1e-4 }, Verdict::Ok),
    ];
    for (case, verdict) in expect {
        let o = case.run();
        assert_eq!(o.verdict, verdict, "{}: {o:?}", case.describe());
        if verdict == Verdict::Ok {
            assert!(o.error <= 0.05, "{}: error {}", case.describe(), o.error);
        }
    }
}

/// A step's contacts are evaluated in parallel and summed in a fixed order: the drop_in scene,
/// with friction through the tangential spring and its per-contact history, ends bit-identical
/// on one thread and on two.
#[test]
fn contact_forces_do_not_depend_on_the_thread_count() {
    use discrete_contact_validation::drop_in::bin_scene;
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut scene = bin_scene(12);
            let mut contacts = DiscreteContacts::new(
                OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(),
                0.5,
            )
            .unwrap()
            .with_substeps_per_contact(6.0)
            .unwrap()
            .with_friction(discrete_contact::Friction::new(0.5, 0.4, 0.01).unwrap());
            contacts.handle_all(&mut scene.world, Material::new(5e6, 0.4).unwrap()).unwrap();
            let mut touched = 0;
            for _ in 0..60 {
                touched = touched.max(contacts.step(&mut scene.world).unwrap().contacts);
            }
            assert!(touched >= 4, "the bodies must land: {touched} contacts");
            scene
                .bodies
                .iter()
                .map(|h| (scene.world.bodies[*h].translation(), scene.world.bodies[*h].angvel()))
                .collect::<Vec<_>>()
        })
    };
    assert_eq!(run(1), run(2));
}

/// Precision: a stiff slow impact (E = 200 GPa, 1 cm/s) rebounds the same 10 m from the
/// origin as at it in f64. In f32 it rebounds as well near the origin, and 1 m and 10 m away —
/// where its sub-step's displacement (7e-9 m) is below the spacing of the coordinates — the
/// step is refused instead of the body stalling.
#[test]
fn a_stiff_slow_impact_rebounds_anywhere_in_f64_and_in_f32_near_the_origin_only() {
    use discrete_contact_validation::precision::{Ending, Impact};
    let at =
        |offset: f64, f32: bool| Impact { youngs: 2e11, speed: 0.01, offset }.run(f32).unwrap();
    let (Ending::Rebound(near), Ending::Rebound(far)) = (at(0.0, false), at(10.0, false)) else {
        panic!("f64 impacts must rebound")
    };
    assert!(
        near < 0.01 && (near - far).abs() < 1e-3,
        "restitution error {near} at the origin, {far} 10 m away"
    );
    let Ending::Rebound(near32) = at(0.0, true) else { panic!("f32 near the origin must rebound") };
    assert!(near32 < 0.015, "f32 restitution error {near32} at the origin");
    assert_eq!(at(1.0, true), Ending::Refused);
    assert_eq!(at(10.0, true), Ending::Refused);
}

/// A frictionless ball spinning on the floor stays where it is with geometry reuse (the
/// default): its updates move the contact point and turn the normal as the ball's own
/// geometry does — not at all — so no sideways force builds up between full evaluations.
/// Reuse must also skip most of them here.
#[test]
fn a_spinning_ball_stays_put_with_geometry_reuse() {
    use discrete_contact::math::Vector;
    let r = 0.005;
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, -9.81, 0.0);
    world.integration_parameters.dt = 1e-4;
    let floor = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(floor));
    let ball = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, r, 0.0))
            .angvel(Vector::new(0.0, 0.0, 20.0))
            .can_sleep(false),
    );
    world.insert_collider(ColliderBuilder::ball(r).density(7800.0), Some(ball));
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap();
    contacts.handle_all(&mut world, Material::new(5e8, 0.3).unwrap()).unwrap();
    let (mut full, mut all) = (0, 0);
    for _ in 0..2000 {
        let s = contacts.step(&mut world).unwrap();
        (full, all) = (full + s.full_evaluations(), all + s.evaluations);
    }
    let p = world.bodies[ball].translation();
    let sideways = p.x.hypot(p.z);
    println!("sideways {sideways:e} m after 0.2 s, {full} of {all} evaluations full");
    assert!(sideways < 1e-8, "the spinning ball moved {sideways:e} m sideways");
    assert!(2 * full < all, "reuse skipped too few full evaluations ({full} of {all})");
}

/// Two overlapping balls in zero gravity, the second free to slide along x on a prismatic
/// joint to the first (fixed): the contact pushes it away along x unless a rapier rule says
/// the pair does not interact. `joint_contacts`: the joint's `contacts_enabled`; `flag`:
/// whether the second ball's collider asks for the `filter_contact_pair` hook.
fn pressed_pair(
    joint_contacts: bool,
    flag: bool,
) -> (PhysicsWorld, DiscreteContacts, RigidBodyHandle) {
    use discrete_contact::math::Vector;
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    world.integration_parameters.dt = 1e-4;
    let a = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(ColliderBuilder::ball(0.01), Some(a));
    let b =
        world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.0195, 0.0, 0.0)));
    let hooks = if flag { ActiveHooks::FILTER_CONTACT_PAIRS } else { ActiveHooks::empty() };
    world.insert_collider(ColliderBuilder::ball(0.01).density(7800.0).active_hooks(hooks), Some(b));
    let joint = PrismaticJointBuilder::new(Vector::X)
        .local_anchor2(Vector::new(-0.0195, 0.0, 0.0))
        .contacts_enabled(joint_contacts);
    world.insert_impulse_joint(a, b, joint);
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.9)
            .unwrap();
    contacts.handle_all(&mut world, Material::new(1e8, 0.3).unwrap()).unwrap();
    (world, contacts, b)
}

/// A user hook that forbids every contact pair it is asked about.
struct NoContacts;

impl PhysicsHooks for NoContacts {
    fn filter_contact_pair(&self, _: &PairFilterContext) -> Option<SolverFlags> {
        None
    }
}

/// Rapier's rules hold for handled pairs too: a joint with contacts disabled, and the user's
/// `filter_contact_pair` hook on a collider that asked for it, leave the pair without a
/// contact; the same pair pushes apart otherwise (and the hook is not asked for a collider
/// that did not ask for it).
#[test]
fn joints_without_contacts_and_the_users_pair_filter_are_honoured() {
    let run = |joint_contacts: bool, flag: bool| {
        let (mut world, mut contacts, b) = pressed_pair(joint_contacts, flag);
        for _ in 0..20 {
            contacts.step_with_events(&mut world, &NoContacts, &()).unwrap();
        }
        (world.bodies[b].linvel().x, contacts.contact_count())
    };
    let (pushed, _) = run(true, false);
    assert!(pushed > 1e-3, "the overlapping pair pushes apart: {pushed} m/s");
    for (joint_contacts, flag) in [(false, false), (true, true)] {
        let (v, live) = run(joint_contacts, flag);
        assert!(
            v.abs() < 1e-9 && live == 0,
            "no contact ({joint_contacts}, {flag}): {v} m/s, {live} live"
        );
    }
}

/// A floor and bodies dropped onto it from a millimetre above: `(x, collider, lying)`, lying
/// turned a quarter about z; the bin scene's contact (rubber, friction, geometry reuse) handles
/// them. Runs 1.5 s at 1/240 s and gives the world, the bodies and the full evaluations over
/// the last 0.5 s.
fn dropped_on_a_floor(
    bodies: Vec<(f64, ColliderBuilder, bool)>,
    angvel: discrete_contact::math::Vector,
) -> (PhysicsWorld, Vec<RigidBodyHandle>, usize) {
    use discrete_contact::math::Vector;
    use discrete_contact_validation::drop_in::{discrete_contacts, rubber};
    let r = 0.01;
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, -9.81, 0.0);
    world.integration_parameters.dt = 1.0 / 240.0;
    let floor = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(floor));
    let handles = bodies
        .into_iter()
        .map(|(x, collider, lying)| {
            let turn = if lying { std::f64::consts::FRAC_PI_2 } else { 0.0 };
            let body = world.insert_body(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(x, r + 1e-3, 0.0))
                    .rotation(Vector::new(0.0, 0.0, turn))
                    .angvel(angvel)
                    .can_sleep(false),
            );
            world.insert_collider(collider.density(1000.0), Some(body));
            body
        })
        .collect();
    let mut contacts = discrete_contacts(4, 10.0).unwrap();
    contacts.handle_all(&mut world, rubber().unwrap()).unwrap();
    let mut late_full = 0;
    for step in 0..360 {
        let s = contacts.step(&mut world).unwrap();
        if step >= 240 {
            late_full += s.full_evaluations();
        }
    }
    (world, handles, late_full)
}

/// A ball and a standing cylinder, each released alone a millimetre above a floor, come to rest
/// and stay there. The ball's force passes through its centre along the floor's normal (the
/// grid's contact point, off the centre by its discretisation error, would roll it away ever
/// faster), and the cylinder's footprint keeps its whole cap (with half of it, each full
/// evaluation would kick it into a rocking that needs a full evaluation nearly every sub-step).
#[test]
fn a_ball_and_a_cylinder_settle_on_a_floor_and_stay() {
    let r = 0.01;
    // Speed, and turning about other axes than the floor's normal: nothing in a point contact's
    // friction resists spinning about the normal (the cylinder may keep some spin from its
    // landing).
    let motion = |world: &PhysicsWorld, b: RigidBodyHandle| {
        let body = &world.bodies[b];
        let w = body.angvel();
        (body.linvel().length(), w.x.hypot(w.z))
    };
    let (world, bodies, _) =
        dropped_on_a_floor(vec![(0.0, ColliderBuilder::ball(r), false)], Vector::ZERO);
    let (v_ball, w_ball) = motion(&world, bodies[0]);
    let (world, bodies, late_full) =
        dropped_on_a_floor(vec![(0.0, ColliderBuilder::cylinder(r, r), false)], Vector::ZERO);
    let (v_cyl, w_cyl) = motion(&world, bodies[0]);
    println!(
        "ball {v_ball:.2e} m/s, {w_ball:.2e} rad/s; cylinder {v_cyl:.2e} m/s, {w_cyl:.2e} rad/s, \
         {late_full} full evaluations over the last 0.5 s"
    );
    assert!(v_ball < 1e-6 && w_ball < 1e-4, "the ball moves: {v_ball:e} m/s, {w_ball:e} rad/s");
    assert!(v_cyl < 1e-4 && w_cyl < 1e-3, "the cylinder rocks: {v_cyl:e} m/s, {w_cyl:e} rad/s");
    assert!(late_full <= 60, "{late_full} full evaluations at rest over 0.5 s");
}

/// A standing cylinder and a cube landing on a floor while turning at 3 rad/s about a
/// horizontal axis stop rocking: the law's damping, spread over the footprint, damps the
/// rocking as it damps a bounce (at the contact point alone it acts on the approach there,
/// which a rocking leaves still: the cylinder would still rock at ~4e-4 rad/s after 1.5 s).
#[test]
fn a_body_landing_while_rocking_comes_to_rest() {
    use discrete_contact::math::Vector;
    let r = 0.01;
    for collider in [ColliderBuilder::cylinder(r, r), ColliderBuilder::cuboid(r, r, r)] {
        let (world, bodies, late_full) =
            dropped_on_a_floor(vec![(0.0, collider, false)], Vector::new(3.0, 0.0, 0.0));
        let w = world.bodies[bodies[0]].angvel();
        let rocking = w.x.hypot(w.z);
        println!("rocks at {rocking:.2e} rad/s after 1.5 s, {late_full} full evaluations late");
        assert!(rocking < 1e-8, "it rocks at {rocking:e} rad/s after 1.5 s");
        assert!(late_full <= 60, "{late_full} full evaluations at rest over 0.5 s");
    }
}

/// A cylinder lying on a floor does not roll: its normal force has no moment about its axis
/// (the grid's contact point, off the axis's plane by its discretisation error, would roll it
/// away ever faster).
#[test]
fn a_cylinder_lying_on_a_floor_does_not_roll_away() {
    let r = 0.01;
    let (world, bodies, _) =
        dropped_on_a_floor(vec![(0.0, ColliderBuilder::cylinder(r, r), true)], Vector::ZERO);
    // Lying, its axis is along x: the roll is the turning about x, the travel along z.
    let body = &world.bodies[bodies[0]];
    let (roll, travel) = (body.angvel().x.abs(), body.translation().z.abs());
    println!("rolls at {roll:.2e} rad/s, {travel:.2e} m away after 1.5 s");
    assert!(roll < 1e-4 && travel < 1e-5, "it rolls at {roll:e} rad/s, {travel:e} m away");
}

/// `ball_on_floor` (all handled) with a steel ball of the same size that is not handled,
/// dropped beside the other from 1 cm up, its active collision types `types`, after `steps`
/// steps: the world, the floor's, the handled ball's and the other ball's colliders, and the
/// two balls' bodies.
fn beside_a_ball_left_to_rapier(
    types: ActiveCollisionTypes,
    steps: usize,
) -> (PhysicsWorld, [ColliderHandle; 3], [RigidBodyHandle; 2]) {
    use discrete_contact::math::Vector;
    let (mut world, mut contacts, ball) =
        ball_on_floor(1e-3, StepPolicy::AutoSubstep { max_substeps: 5000 });
    let floor = world.colliders.iter().find(|(_, c)| c.shape().as_halfspace().is_some()).unwrap().0;
    let handled = world.bodies[ball].colliders()[0];
    let free =
        world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.1, 0.02, 0.0)));
    let other = world.insert_collider(
        ColliderBuilder::ball(0.01).density(7800.0).active_collision_types(types),
        Some(free),
    );
    for _ in 0..steps {
        contacts.step(&mut world).unwrap();
    }
    (world, [floor, handled, other], [ball, free])
}

/// Rapier's broad phase pairs no two handled colliders while a step runs (their active
/// collision types are cleared for it and given back after), and a collider that is not
/// handled keeps rapier's own contacts with handled ones: a ball left to rapier rests on the
/// handled floor. Where a collider that is not handled admits fewer pair types than the
/// handled ones, the types are left alone, so its pairs stay as the user set them.
#[test]
fn rapier_pairs_no_handled_colliders_and_keeps_its_own_contacts() {
    let (world, [floor, handled, other], [ball, free]) =
        beside_a_ball_left_to_rapier(ActiveCollisionTypes::default(), 300);
    let types = |c: ColliderHandle| world.colliders[c].active_collision_types();
    assert_eq!(types(floor), ActiveCollisionTypes::default(), "given back after the step");
    assert_eq!(types(handled), ActiveCollisionTypes::default());
    assert!(
        world.narrow_phase.contact_pair(floor, handled).is_none(),
        "rapier paired two handled colliders"
    );
    let y = world.bodies[free].translation().y;
    assert!(
        world.narrow_phase.contact_pair(floor, other).is_some_and(|p| p.has_any_active_contact())
            && (y - 0.01).abs() < 1e-3,
        "the ball left to rapier must rest on the floor by rapier's contact: y = {y}"
    );
    assert!(world.bodies[ball].translation().y > 0.0099, "the handled ball went through the floor");

    // Admitting only dynamic–fixed pairs, the ball left to rapier admits less than the handled
    // colliders (default types): their types stay, and rapier pairs them as before.
    let (world, [floor, handled, _], _) =
        beside_a_ball_left_to_rapier(ActiveCollisionTypes::DYNAMIC_FIXED, 3);
    assert!(world.narrow_phase.contact_pair(floor, handled).is_some(), "the types must stay");
}

/// Two boxes stacked on a floor; the top one removed mid-run (its body with its colliders, or
/// its collider alone): the next steps run, the removed collider's contacts end, and the box
/// left keeps resting where it was.
#[test]
fn removing_a_body_or_a_collider_mid_run_ends_its_contacts() {
    for remove_body in [true, false] {
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = 1.0 / 60.0;
        let floor = world.insert_body(RigidBodyBuilder::fixed());
        world.insert_collider(ColliderBuilder::cuboid(1.0, 0.1, 1.0), Some(floor));
        let mut boxes = Vec::new();
        for k in 0..2 {
            let b =
                world.insert_body(RigidBodyBuilder::dynamic().translation(
                    discrete_contact::math::Vector::new(0.0, 0.15 + 0.1 * k as f64, 0.0),
                ));
            let c = world.insert_collider(ColliderBuilder::cuboid(0.05, 0.05, 0.05), Some(b));
            boxes.push((b, c));
        }
        let mut contacts =
            DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
                .unwrap();
        contacts.handle_all(&mut world, Material::new(1e8, 0.3).unwrap()).unwrap();
        for _ in 0..60 {
            contacts.step(&mut world).unwrap();
        }
        let (bottom, bottom_collider) = boxes[0];
        let (top, top_collider) = boxes[1];
        assert!(contacts.contact(bottom_collider, top_collider).is_some(), "the boxes never met");
        let resting = world.bodies[bottom].translation();
        if remove_body {
            world.remove_body_with_colliders(top, true);
        } else {
            world.remove_collider(top_collider);
        }
        for _ in 0..60 {
            contacts.step(&mut world).unwrap();
        }
        assert!(contacts.contact(bottom_collider, top_collider).is_none());
        assert_eq!(contacts.contact_count(), 1, "only the bottom box's contact with the floor");
        let rb = &world.bodies[bottom];
        // Unloaded, the bottom box rises by the few micrometres its neighbour pressed it in.
        assert!((rb.translation() - resting).length() < 1e-4, "{:?}", rb.translation() - resting);
        assert!(rb.linvel().length() < 1e-3, "{:?}", rb.linvel());
    }
}

/// Collects the collision events a step reports.
#[derive(Default)]
struct Collisions(std::sync::Mutex<Vec<CollisionEvent>>);

impl EventHandler for Collisions {
    fn handle_collision_event(
        &self,
        _: &RigidBodySet,
        _: &ColliderSet,
        event: CollisionEvent,
        _: Option<&ContactPair>,
    ) {
        self.0.lock().unwrap().push(event);
    }
    fn handle_contact_force_event(
        &self,
        _: f64,
        _: &RigidBodySet,
        _: &ColliderSet,
        _: &ContactPair,
        _: f64,
    ) {
    }
    fn handle_soft_body_tear_event(&self, _: &SoftBodySet, _: &SoftBodyTearEvent) {}
}

/// The collision events of a scene run with rapier's own contacts and with the drop-in: two
/// balls meeting head-on and parting (an impact shorter than the step), a box built resting on
/// the floor, a ball without collision events (nor the floor) bouncing on the floor, and the
/// box removed. Rapier and the drop-in report the same events, within a few steps of each
/// other: the balls' start and end, the box's start, and its end marked as a removal.
#[test]
fn collision_events_of_handled_pairs_are_rapiers() {
    let run = |discrete: bool| -> Vec<(usize, String)> {
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = 1.0 / 60.0;
        let events = ActiveEvents::COLLISION_EVENTS;
        let floor = world.insert_body(RigidBodyBuilder::fixed());
        world.insert_collider(ColliderBuilder::cuboid(2.0, 0.1, 2.0), Some(floor));
        let v = discrete_contact::math::Vector::new;
        let mut ball = |x: f64, vx: f64, y: f64, active: ActiveEvents| {
            let b = world.insert_body(
                RigidBodyBuilder::dynamic()
                    .translation(v(x, y, 0.0))
                    .linvel(v(vx, 0.0, 0.0))
                    .gravity_scale(if y > 1.0 { 0.0 } else { 1.0 }),
            );
            world.insert_collider(
                ColliderBuilder::ball(0.05).restitution(0.9).active_events(active),
                Some(b),
            );
            b
        };
        ball(-0.3, 2.0, 2.0, events);
        ball(0.3, -2.0, 2.0, events);
        ball(1.0, 0.0, 0.5, ActiveEvents::empty());
        let boxed = world.insert_body(RigidBodyBuilder::dynamic().translation(v(-1.0, 0.15, 0.0)));
        world.insert_collider(
            ColliderBuilder::cuboid(0.05, 0.05, 0.05).active_events(events),
            Some(boxed),
        );
        let mut contacts =
            DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.9)
                .unwrap();
        if discrete {
            contacts.handle_all(&mut world, Material::new(1e8, 0.3).unwrap()).unwrap();
        }
        let collector = Collisions::default();
        let mut seen = Vec::new();
        for step in 0..90 {
            if step == 60 {
                world.remove_body_with_colliders(boxed, true);
            }
            if discrete {
                contacts.step_with_events(&mut world, &(), &collector).unwrap();
            } else {
                world.step_with_events(&(), &collector);
            }
            for e in collector.0.lock().unwrap().drain(..) {
                let removed = matches!(e, CollisionEvent::Stopped(_, _, f) if f.contains(CollisionEventFlags::REMOVED));
                let mut pair = [e.collider1().into_raw_parts().0, e.collider2().into_raw_parts().0];
                pair.sort();
                seen.push((
                    step,
                    format!(
                        "{} {pair:?}{}",
                        if e.started() { "started" } else { "stopped" },
                        if removed { " removed" } else { "" }
                    ),
                ));
            }
        }
        seen
    };
    let rapier = run(false);
    let discrete = run(true);
    assert_eq!(rapier.len(), 4, "rapier's own: {rapier:?}");
    // The same events in the same order, each within three steps of rapier's (rapier's pair
    // stays touching while within its prediction distance, the drop-in's impact ends within
    // the step it began in); the removal at once.
    let events = |v: &[(usize, String)]| v.iter().map(|e| e.1.clone()).collect::<Vec<_>>();
    assert_eq!(events(&discrete), events(&rapier), "{discrete:?} against {rapier:?}");
    for (d, r) in discrete.iter().zip(&rapier) {
        assert!(d.0.abs_diff(r.0) <= 3, "{discrete:?} against {rapier:?}");
    }
    assert_eq!(discrete.last().unwrap().0, 60);
}

/// The contacts' readout of a stack at rest: three 10 cm boxes on a floor tilted by 10°,
/// stuck by friction (μ_s = 0.5 > tan 10°; upright, as tan 10° < 1/3). Each contact carries
/// the weight of the boxes above it: its normal force `n m g cos 10°` and its friction
/// `n m g sin 10°` (within 1 %),
/// sticking, the normal across the slope; the floor's contacts are the box's one.
#[test]
fn the_contacts_readout_carries_the_weight_above_each_contact() {
    let tilt: f64 = 10f64.to_radians();
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = 1.0 / 60.0;
    world.integration_parameters.length_unit = 0.1;
    let turn = discrete_contact::math::Vector::new(0.0, 0.0, tilt);
    let up = discrete_contact::math::Rotation::from_scaled_axis(turn)
        * discrete_contact::math::Vector::Y;
    let floor = world.insert_body(RigidBodyBuilder::fixed().rotation(turn));
    let floor_collider = world.insert_collider(ColliderBuilder::cuboid(1.0, 0.1, 1.0), Some(floor));
    let mut boxes = Vec::new();
    for k in 0..3 {
        let b = world.insert_body(
            RigidBodyBuilder::dynamic().translation(up * (0.15 + 0.1 * k as f64)).rotation(turn),
        );
        boxes.push(
            world.insert_collider(
                ColliderBuilder::cuboid(0.05, 0.05, 0.05).density(1000.0),
                Some(b),
            ),
        );
    }
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap()
            .with_friction(discrete_contact::Friction::new(0.5, 0.4, 1e-3).unwrap());
    contacts.handle_all(&mut world, Material::new(1e8, 0.3).unwrap()).unwrap();
    assert_eq!(contacts.contacts().count(), 0, "no readout before the first step");
    for _ in 0..120 {
        contacts.step(&mut world).unwrap();
    }
    let weight = 1.0 * 9.81;
    assert_eq!(contacts.contacts().count(), 3);
    let below = [floor_collider, boxes[0], boxes[1]];
    for (k, (&under, &over)) in below.iter().zip(&boxes).enumerate() {
        let carried = (3 - k) as f64 * weight;
        let c = contacts
            .contacts_with(over)
            .find(|r| r.colliders == (under, over) || r.colliders == (over, under))
            .unwrap_or_else(|| panic!("no contact under box {k}"));
        // Signs: the reading is of A; the box above is pushed up the normal.
        let on_box = if c.colliders.0 == over { c.force_on_a } else { -c.force_on_a };
        let n = on_box.dot(up);
        let t = (on_box - up * n).length();
        assert!((n / (carried * tilt.cos()) - 1.0).abs() < 0.01, "box {k}: normal force {n}");
        assert!((t / (carried * tilt.sin()) - 1.0).abs() < 0.01, "box {k}: friction {t}");
        assert!((c.normal_force().abs() / n - 1.0).abs() < 0.01, "box {k}: {c:?}");
        assert!(c.normal.dot(up).abs() > 0.999, "box {k}: normal {:?}", c.normal);
        assert!(c.indentation > 0.0 && c.volume > 0.0 && !c.sliding, "box {k}: {c:?}");
    }
    assert_eq!(contacts.contacts_with(floor_collider).count(), 1);
}

/// `handle_all` names the colliders it leaves to rapier's own contacts, and why: a compound is
/// not a convex solid; the ball and the box are handled, and so are the triangle mesh and the
/// height field on the fixed body, as walls.
#[test]
fn handle_all_names_the_colliders_it_leaves_to_rapier() {
    use discrete_contact::math::{Pose, Vector};
    let mut world = PhysicsWorld::new();
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    let mesh = world.insert_collider(
        ColliderBuilder::trimesh(
            vec![
                Vector::new(-1.0, 0.0, -1.0),
                Vector::new(1.0, 0.0, -1.0),
                Vector::new(0.0, 0.0, 1.0),
            ],
            vec![[0, 1, 2]],
        )
        .unwrap(),
        Some(ground),
    );
    let field = world.insert_collider(
        ColliderBuilder::heightfield(
            discrete_contact::rapier3d_f64::parry::utils::Array2::zeros(3, 3),
            Vector::new(2.0, 1.0, 2.0),
        ),
        Some(ground),
    );
    let body =
        world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 1.0, 0.0)));
    let ball = world.insert_collider(ColliderBuilder::ball(0.1), Some(body));
    let cuboid = world.insert_collider(ColliderBuilder::cuboid(0.1, 0.1, 0.1), Some(body));
    let dumbbell = world.insert_collider(
        ColliderBuilder::compound(vec![
            (Pose::from_translation(Vector::new(-0.2, 0.0, 0.0)), SharedShape::ball(0.1)),
            (Pose::from_translation(Vector::new(0.2, 0.0, 0.0)), SharedShape::ball(0.1)),
        ]),
        Some(body),
    );
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap();
    let left = contacts.handle_all(&mut world, Material::new(1e7, 0.3).unwrap()).unwrap();
    let named: Vec<ColliderHandle> = left.iter().map(|(c, _)| *c).collect();
    assert_eq!(named, vec![dumbbell]);
    for (c, why) in &left {
        assert!(matches!(why, Error::UnsupportedShape { .. }), "{c:?}: {why}");
    }
    for handled in [ball, cuboid, mesh, field] {
        assert!(contacts.is_handled(handled), "{handled:?}");
    }
}

/// Rapier caps the speeds it integrates with (400 lengths of `length_unit` per second): two
/// 1 cm steel balls meeting at 10 m/s each with `length_unit` 0.01 (a cap of 4 m/s) rebound,
/// each on its own side, leaving at the cap — as rapier's own contacts would. Before, an impact
/// resolved in its own sub-steps placed the bodies for their uncapped speed and rapier's capped
/// step carried them through each other.
#[test]
fn an_impact_past_rapiers_speed_cap_never_passes_through() {
    let v = discrete_contact::math::Vector::new;
    let mut world = PhysicsWorld::new();
    world.gravity = v(0.0, 0.0, 0.0);
    world.integration_parameters.dt = 1.0 / 60.0;
    world.integration_parameters.length_unit = 0.01;
    let mut balls = Vec::new();
    for side in [-1.0, 1.0] {
        let b = world.insert_body(
            RigidBodyBuilder::dynamic().translation(v(side * 0.11, 0.0, 0.0)).linvel(v(
                -side * 10.0,
                0.0,
                0.0,
            )),
        );
        world.insert_collider(ColliderBuilder::ball(0.01).density(7800.0), Some(b));
        balls.push(b);
    }
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 1.0)
            .unwrap();
    contacts.handle_all(&mut world, Material::new(2e11, 0.3).unwrap()).unwrap();
    for step in 0..10 {
        contacts.step(&mut world).unwrap();
        let x = world.bodies[balls[1]].translation().x - world.bodies[balls[0]].translation().x;
        assert!(x > 0.019, "step {step}: the balls' centres {x} m apart, crossed");
    }
    let cap = world.integration_parameters.max_linear_velocity();
    for (b, side) in balls.iter().zip([-1.0, 1.0]) {
        let u = world.bodies[*b].linvel().x * side;
        assert!((u / cap - 1.0).abs() < 1e-9, "leaving at {u} m/s, rapier's cap {cap}");
    }
}

/// A body added mid-run and handed over comes to rest on the floor from its next step, and
/// the step's statistics stay whole (the candidate search, started afresh for the new handled
/// set, keeps counting its builds).
#[test]
fn a_body_added_mid_run_is_handled_from_its_next_step() {
    let v = discrete_contact::math::Vector::new;
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = 1.0 / 60.0;
    let floor = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(ColliderBuilder::cuboid(1.0, 0.1, 1.0), Some(floor));
    // Dropped: its fall rebuilds the candidate search's list many times before the addition.
    let first = world.insert_body(RigidBodyBuilder::dynamic().translation(v(-0.3, 0.5, 0.0)));
    world.insert_collider(ColliderBuilder::cuboid(0.05, 0.05, 0.05), Some(first));
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap();
    let plastic = Material::new(1e8, 0.3).unwrap();
    contacts.handle_all(&mut world, plastic).unwrap();
    for _ in 0..60 {
        contacts.step(&mut world).unwrap();
    }
    let added = world.insert_body(RigidBodyBuilder::dynamic().translation(v(0.3, 0.15, 0.0)));
    let collider = world.insert_collider(ColliderBuilder::cuboid(0.05, 0.05, 0.05), Some(added));
    contacts.handle(&mut world, collider, plastic).unwrap();
    for _ in 0..120 {
        let stats = contacts.step(&mut world).unwrap();
        assert!(stats.neighbour_builds < 10, "{} builds in one step", stats.neighbour_builds);
    }
    for b in [first, added] {
        let y = world.bodies[b].translation().y;
        assert!((y - 0.15).abs() < 1e-5, "a box at {y} m, not resting on the floor");
    }
}

/// Contact-force events of handled pairs, read after the step: two balls meeting head-on in
/// less than a step report one event, in that step, whose force is the impulse each ball
/// took over the step (`m Δv / dt`, within 1e-6) — though the contact ended within the step;
/// above the collider's threshold only, and only where a collider asks for such events.
#[test]
fn contact_force_events_carry_the_impulse_of_the_step() {
    let v = discrete_contact::math::Vector::new;
    for (threshold, active) in [
        (0.0, ActiveEvents::CONTACT_FORCE_EVENTS),
        (1e9, ActiveEvents::CONTACT_FORCE_EVENTS),
        (0.0, ActiveEvents::empty()),
    ] {
        let mut world = PhysicsWorld::new();
        world.gravity = v(0.0, 0.0, 0.0);
        world.integration_parameters.dt = 1.0 / 60.0;
        let mut balls = Vec::new();
        for side in [-1.0, 1.0] {
            let b = world.insert_body(
                RigidBodyBuilder::dynamic().translation(v(side * 0.02, 0.0, 0.0)).linvel(v(
                    -side * 1.0,
                    0.0,
                    0.0,
                )),
            );
            let c = ColliderBuilder::ball(0.01).density(7800.0);
            let c = if side > 0.0 {
                c.active_events(active).contact_force_event_threshold(threshold)
            } else {
                c
            };
            world.insert_collider(c, Some(b));
            balls.push(b);
        }
        let mut contacts =
            DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.9)
                .unwrap();
        contacts.handle_all(&mut world, Material::new(2e11, 0.3).unwrap()).unwrap();
        let mut events = Vec::new();
        for step in 0..10 {
            let before = world.bodies[balls[1]].linvel();
            contacts.step(&mut world).unwrap();
            let taken = world.bodies[balls[1]].mass() * (world.bodies[balls[1]].linvel() - before);
            for e in contacts.contact_force_events(&world) {
                assert!(!e.touching, "the impact outlived its step");
                let force = e.force_on_a.length();
                let expected = taken.length() / world.integration_parameters.dt;
                assert!((force / expected - 1.0).abs() < 1e-6, "{force} N against {expected} N");
                events.push(step);
            }
        }
        let expected = usize::from(threshold == 0.0 && !active.is_empty());
        assert_eq!(events.len(), expected, "threshold {threshold}, {active:?}: {events:?}");
        assert!(world.bodies[balls[1]].linvel().x > 0.8, "no rebound");
    }
}

/// A box resting on the floor given back to rapier mid-run: its discrete contact ends (its
/// collision event's end reported at the next step), rapier's own contact takes it over and
/// it keeps resting; a collider never handled is not given back.
#[test]
fn a_collider_given_back_rests_on_rapiers_own_contact() {
    let v = discrete_contact::math::Vector::new;
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = 1.0 / 60.0;
    let floor = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(ColliderBuilder::cuboid(1.0, 0.1, 1.0), Some(floor));
    let b = world.insert_body(RigidBodyBuilder::dynamic().translation(v(0.0, 0.15, 0.0)));
    let boxed = world.insert_collider(
        ColliderBuilder::cuboid(0.05, 0.05, 0.05).active_events(ActiveEvents::COLLISION_EVENTS),
        Some(b),
    );
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap();
    contacts.handle_all(&mut world, Material::new(1e8, 0.3).unwrap()).unwrap();
    let collector = Collisions::default();
    for _ in 0..30 {
        contacts.step_with_events(&mut world, &(), &collector).unwrap();
    }
    assert_eq!(contacts.contact_count(), 1);
    assert!(contacts.unhandle(&mut world, boxed));
    assert!(!contacts.unhandle(&mut world, boxed), "given back twice");
    assert_eq!(contacts.contact_count(), 0);
    for _ in 0..60 {
        contacts.step_with_events(&mut world, &(), &collector).unwrap();
    }
    assert_eq!(contacts.contacts().count(), 0);
    assert!(
        world.narrow_phase.contact_pairs().any(|p| p.has_any_active_contact()),
        "rapier's own contact"
    );
    let y = world.bodies[b].translation().y;
    assert!((y - 0.15).abs() < 2e-3, "the box at {y} m");
    let events: Vec<CollisionEvent> = collector.0.lock().unwrap().clone();
    assert!(events.first().is_some_and(|e| e.started()), "{events:?}");
    assert!(events.iter().any(|e| e.stopped()), "no end of the discrete contact: {events:?}");
}

/// The numbers of the `DataArray` named `name` in a VTK XML file's text.
fn vtk_array(file: &str, name: &str) -> Vec<f64> {
    let at = file.find(&format!(r#"Name="{name}""#)).unwrap_or_else(|| panic!("no {name}"));
    let rest = &file[at..];
    let values = &rest[rest.find('>').unwrap() + 1..rest.find("</DataArray>").unwrap()];
    values.split_whitespace().map(|x| x.parse().unwrap()).collect()
}

/// The value of attribute `name` in an XML tag's text.
fn xml_attribute<'a>(tag: &'a str, name: &str) -> &'a str {
    let start = tag.find(&format!(r#" {name}=""#)).unwrap() + name.len() + 3;
    &tag[start..start + tag[start..].find('"').unwrap()]
}

/// The `.pvd` collection's data sets: (time, part, file).
fn pvd_data_sets(series: &ParaViewSeries) -> Vec<(f64, String, String)> {
    let pvd = std::fs::read_to_string(series.collection()).unwrap();
    let sets = pvd.lines().filter(|l| l.contains("<DataSet"));
    sets.map(|l| {
        let text = |name| xml_attribute(l, name).to_owned();
        (text("timestep").parse().unwrap(), text("part"), text("file"))
    })
    .collect()
}

/// A ParaView series of two 1 kg boxes resting on a fixed box floor, written at three steps
/// and read back: the collection lists the three times in order, each with its bodies and
/// contacts files; the bodies file holds the floor and both boxes at their centres of mass;
/// the floor's force chain carries both boxes' weight (within 1 %).
#[test]
fn a_paraview_series_of_a_resting_stack_reads_back_its_weight() {
    let v = discrete_contact::math::Vector::new;
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = 1.0 / 60.0;
    world.integration_parameters.length_unit = 0.1;
    let floor = world.insert_body(RigidBodyBuilder::fixed());
    let floor_collider = world.insert_collider(ColliderBuilder::cuboid(1.0, 0.1, 1.0), Some(floor));
    let mut bodies = vec![floor];
    for k in 0..2 {
        let b = world.insert_body(RigidBodyBuilder::dynamic().translation(v(
            0.0,
            0.15 + 0.1 * k as f64,
            0.0,
        )));
        world.insert_collider(ColliderBuilder::cuboid(0.05, 0.05, 0.05).density(1000.0), Some(b));
        bodies.push(b);
    }
    let mut contacts =
        DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell).unwrap(), 0.5)
            .unwrap();
    contacts.handle_all(&mut world, Material::new(1e8, 0.3).unwrap()).unwrap();
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("paraview_stack");
    let _ = std::fs::remove_dir_all(&dir);
    let mut series = ParaViewSeries::new(&dir, "stack").unwrap();
    let dt = world.integration_parameters.dt;
    let time = |k: usize| (121 + k) as f64 * dt;
    for _ in 0..120 {
        contacts.step(&mut world).unwrap();
    }
    for k in 0..3 {
        contacts.step(&mut world).unwrap();
        series.write(&contacts, &world, time(k)).unwrap();
    }

    let sets = pvd_data_sets(&series);
    assert_eq!(sets.len(), 6, "{sets:?}");
    for (k, step) in sets.chunks(2).enumerate() {
        assert_eq!([step[0].0, step[1].0], [time(k); 2], "{sets:?}");
        assert_eq!([step[0].1.as_str(), step[1].1.as_str()], ["0", "1"], "{sets:?}");
        assert!(step.iter().all(|s| dir.join(&s.2).is_file()), "{sets:?}");
    }

    let read = |file: &str| std::fs::read_to_string(dir.join(file)).unwrap();
    let bodies_file = read(&sets[4].2);
    let (points, handles) = (vtk_array(&bodies_file, "points"), vtk_array(&bodies_file, "handle"));
    assert_eq!((points.len(), handles.len()), (3 * bodies.len(), bodies.len()));
    for (k, b) in bodies.iter().enumerate() {
        assert_eq!(handles[k], b.into_raw_parts().0 as f64);
        assert_eq!(points[3 * k..3 * k + 3], world.bodies[*b].center_of_mass().to_array());
    }

    let contacts_file = read(&sets[5].2);
    let normal_force = vtk_array(&contacts_file, "normal_force");
    let colliders = vtk_array(&contacts_file, "colliders");
    assert_eq!(normal_force.len(), 2, "{contacts_file}");
    assert_eq!(vtk_array(&contacts_file, "points").len(), 3 * 3 * normal_force.len());
    // Each line through its three points, in order (ParaView reads the connectivity as one
    // index per tuple).
    assert!(contacts_file.contains(r#"Name="connectivity" NumberOfComponents="1""#));
    assert_eq!(vtk_array(&contacts_file, "connectivity"), [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
    assert_eq!(vtk_array(&contacts_file, "offsets"), [3.0, 6.0]);
    let floor_index = floor_collider.into_raw_parts().0 as f64;
    let on_floor: f64 = normal_force
        .iter()
        .zip(colliders.chunks(2))
        .filter(|(_, pair)| pair.contains(&floor_index))
        .map(|(n, _)| n)
        .sum();
    let weight = 2.0 * 9.81;
    assert!((on_floor / weight - 1.0).abs() < 0.01, "{on_floor} N on the floor, weight {weight} N");
}

/// A ParaView series refuses a time that is not later than the last one written, or not
/// finite, and leaves its collection as it was; a stem naming a folder is refused. A write
/// before the first step gives a valid contacts file without contacts.
#[test]
fn a_paraview_series_refuses_a_time_that_does_not_increase() {
    let (world, contacts, _) = ball_on_floor(1e-4, StepPolicy::AutoSubstep { max_substeps: 5000 });
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("paraview_time");
    let _ = std::fs::remove_dir_all(&dir);
    assert!(matches!(
        ParaViewSeries::new(&dir, "a/b"),
        Err(Error::InvalidArgument { name: "stem", .. })
    ));
    let mut series = ParaViewSeries::new(&dir, "ball").unwrap();
    series.write(&contacts, &world, 1.0).unwrap();
    for t in [0.5, 1.0, f64::NAN, f64::INFINITY] {
        let refused = series.write(&contacts, &world, t);
        assert!(matches!(refused, Err(Error::InvalidParameter { name: "time", .. })), "{t}");
    }
    series.write(&contacts, &world, 2.0).unwrap();
    let sets = pvd_data_sets(&series);
    assert_eq!(sets.iter().map(|s| s.0).collect::<Vec<_>>(), [1.0, 1.0, 2.0, 2.0]);
    let empty = std::fs::read_to_string(dir.join(&sets[1].2)).unwrap();
    assert!(empty.contains(r#"NumberOfPoints="0" NumberOfVerts="0" NumberOfLines="0""#));
    assert!(vtk_array(&empty, "normal_force").is_empty());
}
