use super::*;

/// A body of mass `m` and inertia `i` (about every axis) starting at velocity `v`, with `v*`
/// after gravity `g` over `h`.
fn body(m: Real, i: Real, v: Vector, g: Vector, h: Real) -> IslandBody {
    IslandBody {
        inverse_mass: Vector::splat(1.0 / m),
        inverse_inertia: Matrix::from_diagonal(Vector::splat(1.0 / i)),
        start: (v, Vector::ZERO),
        free: (v + g * h, Vector::ZERO),
    }
}

/// A contact of body 0 on the ground below it (normal +y), at `lever` from its centre.
fn on_ground(depth: Real, a: Real, q: Real, c: Real, lever: Vector) -> StepLaw {
    StepLaw {
        bodies: [Some(0), None],
        given: [(Vector::ZERO, Vector::ZERO); 2],
        levers: [lever, Vector::ZERO],
        normal: Vector::Y,
        normal_law: NormalLaw { depth, coefficient: a, exponent: q, damping: c },
        spring: None,
        rocking: Matrix::ZERO,
        rocking_damping: Matrix::ZERO,
    }
}

/// The solution balances momentum: `M (v − v*)` equals the laws' impulses on each body.
fn assert_balanced(bodies: &[IslandBody], laws: &[Law], s: &Solution) {
    let mut sum = vec![(Vector::ZERO, Vector::ZERO); bodies.len()];
    for (law, r) in laws.iter().zip(&s.responses) {
        for (end, (f, t)) in law.on_bodies(r).into_iter().enumerate() {
            if let Some(b) = law.bodies()[end] {
                sum[b].0 += f;
                sum[b].1 += t;
            }
        }
    }
    for (b, body) in bodies.iter().enumerate() {
        let (dv, dw) = body.yield_to(sum[b]);
        let expected = (body.free.0 + dv, body.free.1 + dw);
        let v = s.velocities[b];
        let scale = expected.0.length().max(1e-3);
        assert!((v.0 - expected.0).length() <= 1e-5 * scale, "{:?} against {expected:?}", v.0);
        assert!((v.1 - expected.1).length() <= 1e-5 * expected.1.length().max(1e-3));
    }
}

/// A steel-stiff face (`F = a d`, `a` = 1e10 N/m) under a 1 kg box at a 60 Hz step. Just
/// touching at rest, one step ends where the face carries the weight, `d = m g / a`. From
/// any other start — pressed a millimetre in, a millimetre apart and falling — the face's
/// force at the end of the step is what changes the box's momentum within the step, never more:
/// a box pressed in leaves no faster than the step undoes the compression.
#[test]
fn a_stiff_face_carries_its_load_in_one_step() {
    let (m, h, a) = (1.0, 1.0 / 60.0, 1e10);
    let g = Vector::new(0.0, -9.81, 0.0);
    let weight = m * 9.81;
    for (depth, v) in [(0.0, 0.0), (1e-3, 0.0), (-1e-3, -0.5), (2e-6, 0.1)] {
        let bodies = [body(m, 1e-3, Vector::new(0.0, v, 0.0), g, h)];
        let mut laws = [Law::Contact(on_ground(depth, a, 1.0, 0.0, Vector::new(0.0, -0.05, 0.0)))];
        let s = solve(&bodies, &mut laws, h, &mut None).unwrap();
        assert_balanced(&bodies, &laws, &s);
        let v_end = s.velocities[0].0.y;
        let end = depth - h * v_end;
        let rest = weight / a;
        if depth == 0.0 && v == 0.0 {
            assert!((end - rest).abs() < 1e-6 * rest, "ends at {end}, rests at {rest}");
        }
        assert!(end > 0.0);
        let change = m * (v_end - v).abs() / h;
        assert!(
            a * end <= weight + change + 1e-6 * weight,
            "force {} against {}",
            a * end,
            weight + change
        );
        assert!(v_end <= depth.max(0.0) / h * (1.0 + 1e-9) + 1e-12);
    }
}

/// Two bodies on a linear spring (`q = 1`, no damping) without gravity: the step is backward
/// Euler, whose end velocity has a closed form, `v₁ = (v₀ − h ω² x₀) / (1 + h² ω²)` for the
/// relative coordinate; its energy never grows.
#[test]
fn a_linear_spring_steps_as_backward_euler() {
    let (m, k, h) = (2.0, 5e6, 1e-2);
    let bodies = [
        body(m, 1.0, Vector::new(0.0, -0.3, 0.0), Vector::ZERO, h),
        body(m, 1.0, Vector::new(0.0, 0.3, 0.0), Vector::ZERO, h),
    ];
    // Body 0 above body 1, pressed in by 1 mm and closing at 0.6 m/s; A is the lower one.
    let d0 = 1e-3;
    let mut laws = [Law::Contact(StepLaw {
        bodies: [Some(1), Some(0)],
        normal: -Vector::Y,
        ..on_ground(d0, k, 1.0, 0.0, Vector::ZERO)
    })];
    let s = solve(&bodies, &mut laws, h, &mut None).unwrap();
    assert_balanced(&bodies, &laws, &s);
    // The relative coordinate: x = d (compression), reduced mass m/2, approach speed 0.6.
    let omega2 = k / (0.5 * m);
    let approach0 = 0.6;
    let approach1 = (approach0 - h * omega2 * d0) / (1.0 + h * h * omega2);
    let approach = s.velocities[1].0.y - s.velocities[0].0.y;
    assert!(
        (approach - approach1).abs() < 1e-9 * approach1.abs(),
        "{approach} against {approach1}"
    );
    let energy = |d: Real, v: Real| 0.5 * k * d * d + 0.5 * (0.5 * m) * v * v;
    let d1 = d0 + h * approach1;
    assert!(energy(d1.max(0.0), approach1) < energy(d0, approach0));
}

/// A box on a slope of 20°: with `μ = 0.5 > tan 20°` the spring holds it (no slip at the end
/// of the step, the friction force `m g sin θ`); with `μ = 0.2` it slides and the disc caps
/// the force at `μ m g cos θ`, so it gains `g (sin θ − μ cos θ) h`.
#[test]
fn friction_holds_below_the_slope_and_slides_above() {
    let (m, h) = (1.0, 1.0 / 60.0);
    let theta: Real = 20f64.to_radians();
    // The slope's frame: normal n, downhill t.
    let n = Vector::new(-theta.sin(), theta.cos(), 0.0);
    let t = Vector::new(theta.cos(), theta.sin(), 0.0) * -1.0;
    let g = Vector::new(0.0, -9.81, 0.0);
    let weight = m * 9.81;
    let a = 1e8;
    for mu in [0.5, 0.2] {
        let rest = weight * theta.cos() / a;
        let bodies = [body(m, 1e9, Vector::ZERO, g, h)];
        let mut laws = [Law::Contact(StepLaw {
            normal: n,
            spring: Some(SpringLaw {
                stiffness: 0.8 * a,
                viscosity: 0.0,
                carried: Vector::ZERO,
                coefficient: mu,
                normal_force: 0.0,
            }),
            ..on_ground(rest, a, 1.0, 0.0, Vector::ZERO)
        })];
        let s = solve(&bodies, &mut laws, h, &mut None).unwrap();
        assert_balanced(&bodies, &laws, &s);
        let slip = s.velocities[0].0.dot(t);
        let r = &s.responses[0];
        if mu == 0.5 {
            assert!(!r.sliding);
            // It moves by no more than the spring's own stretch under the load.
            assert!(slip.abs() * h < 2.0 * weight / (0.8 * a), "slips {slip} m/s");
            assert!((r.tangential.length() / h - weight * theta.sin()).abs() < 1e-3 * weight);
        } else {
            assert!(r.sliding);
            let expected = 9.81 * (theta.sin() - mu * theta.cos()) * h;
            assert!((slip - expected).abs() < 1e-3 * expected, "{slip} against {expected}");
        }
    }
}

/// A ten-box column on the ground, steel-stiff faces, every box starting with a random
/// velocity: one step on the block structure and on a dense solve of the same problem agree,
/// and the result is the same whichever order the bodies are numbered in.
#[test]
fn a_column_of_boxes_solves_the_same_in_any_numbering() {
    let (m, h, a) = (1.0, 1.0 / 60.0, 1e10);
    let g = Vector::new(0.0, -9.81, 0.0);
    let n = 10;
    let solve_with = |perm: &[usize]| {
        let mut state = 5u64;
        let mut rnd = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as Real / (1u64 << 53) as Real - 0.5
        };
        let mut bodies = vec![body(m, 1e-3, Vector::ZERO, g, h); n];
        for k in 0..n {
            let v = Vector::new(rnd(), rnd(), rnd()) * 0.1;
            bodies[perm[k]] = body(m, 1.7e-3, v, g, h);
        }
        let mut laws = vec![on_ground(1e-7, a, 1.0, 0.0, Vector::new(0.01, -0.05, 0.0))];
        laws[0].bodies = [Some(perm[0]), None];
        for k in 1..n {
            laws.push(StepLaw {
                bodies: [Some(perm[k]), Some(perm[k - 1])],
                levers: [
                    Vector::new(0.01 * rnd(), -0.05, 0.0),
                    Vector::new(0.0, 0.05, 0.01 * rnd()),
                ],
                spring: Some(SpringLaw {
                    stiffness: 0.8 * a,
                    viscosity: 10.0,
                    carried: Vector::ZERO,
                    coefficient: 0.5,
                    normal_force: 50.0,
                }),
                rocking: Matrix::from_diagonal(Vector::new(1e7, 0.0, 1e7)),
                ..on_ground(1e-7, a, 1.0, 1.0, Vector::ZERO)
            });
        }
        let mut laws: Vec<Law> = laws.into_iter().map(Law::Contact).collect();
        let s = solve(&bodies, &mut laws, h, &mut None).unwrap();
        assert_balanced(&bodies, &laws, &s);
        (0..n).map(|k| s.velocities[perm[k]]).collect::<Vec<_>>()
    };
    let straight: Vec<usize> = (0..n).collect();
    let shuffled = [3, 7, 0, 9, 1, 5, 8, 2, 6, 4];
    let (x, y) = (solve_with(&straight), solve_with(&shuffled));
    for (p, q) in x.iter().zip(&y) {
        assert!((p.0 - q.0).length() < 1e-9 && (p.1 - q.1).length() < 1e-7, "{p:?} against {q:?}");
    }
}

/// A 1 kg body hanging from a fixed anchor on a ball joint (translations locked), released
/// 2 mm below where the joint holds it and falling at 0.3 m/s: one step pulls it back to the
/// anchor, to the joint spring's stretch under the weight, `m g / k`, and leaves it at rest
/// there but for the speed that closes the opening within the step.
#[test]
fn a_joint_holds_its_body_to_the_anchor() {
    let (m, h) = (1.0, 1.0 / 60.0);
    let g = Vector::new(0.0, -9.81, 0.0);
    let k = m / (1e-3 * h * h);
    let bodies = [body(m, 1e-2, Vector::new(0.0, -0.3, 0.0), g, h)];
    // The anchor 0.1 m above the body's centre, the body 2 mm too low.
    let mut laws = [Law::Joint(JointLaw {
        bodies: [Some(0), None],
        given: [(Vector::ZERO, Vector::ZERO); 2],
        levers: [Vector::new(0.0, 0.1, 0.0), Vector::ZERO],
        linear: [Vector::X, Vector::Y, Vector::Z],
        angular: [Vector::ZERO; 3],
        offset: Vector::new(0.0, -2e-3, 0.0),
        turn: Vector::ZERO,
        stiffness: (k, 0.0),
    })];
    let s = solve(&bodies, &mut laws, h, &mut None).unwrap();
    assert_balanced(&bodies, &laws, &s);
    let v = s.velocities[0].0;
    let end = -2e-3 + h * v.y;
    let stretch = m * 9.81 / k;
    // The opening left after the step is what carries the weight and the speed it ends at.
    let carried = -(m * (v.y - (-0.3 + g.y * h))) / (k * h);
    assert!((end - carried).abs() < 1e-9, "{end} against {carried}");
    assert!(end.abs() < 20.0 * stretch, "the joint stays open by {end} m, {stretch} under load");
    assert!(v.y > 0.0 && v.y <= 2e-3 / h * 1.001, "it closes the opening: {v:?}");
}
