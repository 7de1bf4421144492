//! The live contacts as one network of springs between rigid bodies, and its highest
//! vibration frequency: what an explicit sub-step must resolve once bodies rest on each other.
//!
//! Each live contact couples its two bodies at its contact point by its normal stiffness
//! `k_n` along the normal and, with the tangential spring, `κ k_n` across it, and by the
//! overlap's resistance to tilting ([`ContactFrame::rocking`](crate::contact::ContactFrame)),
//! which a point spring leaves out. A body's translation and turning both move its contact
//! points, so a body with several contacts vibrates in modes that no pair alone shows: a
//! pile's highest frequency may lie above every pair's own (a chain of equal bodies reaches
//! twice one pair's `ω²`), or below a pair's bound taken at the bounding radius (a contact
//! under a face's centre has a short lever).
//!
//! The network's `ω²_max`, the largest eigenvalue of `M⁻¹K`, is found by the Lanczos process
//! in the mass-weighted inner product (`M⁻¹K` is self-adjoint in it), from a fixed start, with
//! momenta and velocities side by side so that no inertia tensor is inverted: after
//! [`ITERATIONS`] steps the largest eigenvalue of the tridiagonal matrix it builds never lies
//! above `ω²_max` and comes to it far faster than power iteration's Rayleigh quotient (to
//! round-off on the tests' networks; how close on a pile of hundreds of bodies depends on the
//! gap below the top of its spectrum). The sub-step's margin below explicit integration's
//! limit ([`STABLE_SUBSTEPS_PER_HALF_PERIOD`] sub-steps per half-period at least) covers what
//! is left, and what a linear network does not hold: the stiffness's rise within a step and
//! the damping.
//!
//! Contacts are taken in the order of their collider handles, so the estimate does not depend
//! on the order of the contact map (a resumed run gives the same sub-steps).

use super::*;
use crate::math::Matrix;

/// Lanczos steps per estimate at most (fewer where the bodies have fewer degrees of freedom).
pub(super) const ITERATIONS: usize = 30;

/// A body's velocity or momentum, or a load on it: (linear, angular).
type Motion = (Vector, Vector);

/// A contact of the network: its bodies (indices into the bodies' list, `None` for a body
/// that does not move), their levers to the contact point, the normal and the stiffnesses.
struct Spring {
    bodies: [Option<usize>; 2],
    levers: [Vector; 2],
    normal: Vector,
    normal_stiffness: Real,
    tangential_stiffness: Real,
    /// The overlap's resistance to tilting (N·m/rad, world frame; zero where it has none).
    rocking: Matrix,
    pair: (ColliderHandle, ColliderHandle),
}

impl Spring {
    /// How far the first body's contact point moves against the second's, and how far the
    /// first body turns against the second, when the bodies move by `v`.
    fn stretch(&self, v: &[Motion]) -> Motion {
        let at = |s: usize| {
            self.bodies[s].map_or((Vector::ZERO, Vector::ZERO), |b| {
                (v[b].0 + v[b].1.cross(self.levers[s]), v[b].1)
            })
        };
        let ((x0, w0), (x1, w1)) = (at(0), at(1));
        (x0 - x1, w0 - w1)
    }

    /// The spring's force on the first body and its torque about the contact point, for a
    /// stretch `(u, turn)`.
    fn load(&self, (u, turn): Motion) -> Motion {
        let along = self.normal * u.dot(self.normal);
        (
            -(along * self.normal_stiffness + (u - along) * self.tangential_stiffness),
            -(self.rocking * turn),
        )
    }

    /// The spring's energy `vᵀ K_s v` (twice its potential energy) for the bodies' motion `v`.
    fn energy(&self, v: &[Motion]) -> Real {
        let stretch = self.stretch(v);
        let (f, t) = self.load(stretch);
        -(f.dot(stretch.0) + t.dot(stretch.1))
    }
}

/// A moving body: inverse mass and world inverse inertia (locked axes left out).
struct Body {
    inverse_mass: Vector,
    inverse_inertia: [Vector; 3],
}

impl Body {
    /// `M⁻¹ (f, τ)`.
    fn yield_to(&self, (f, t): Motion) -> Motion {
        let j = &self.inverse_inertia;
        (f * self.inverse_mass, Vector::new(j[0].dot(t), j[1].dot(t), j[2].dot(t)))
    }
}

/// The springs and the bodies they join.
struct Network {
    bodies: Vec<Body>,
    springs: Vec<Spring>,
}

impl Network {
    /// `K v`: the momenta the springs' restoring loads take away per unit time.
    fn stiffness(&self, v: &[Motion]) -> Vec<Motion> {
        let mut out = vec![(Vector::ZERO, Vector::ZERO); v.len()];
        for s in &self.springs {
            let (f, t) = s.load(s.stretch(v));
            for (end, f, t) in [(0, f, t), (1, -f, -t)] {
                if let Some(b) = s.bodies[end] {
                    out[b].0 -= f;
                    out[b].1 -= s.levers[end].cross(f) + t;
                }
            }
        }
        out
    }

    /// `M⁻¹ p`.
    fn velocities(&self, p: &[Motion]) -> Vec<Motion> {
        p.iter().zip(&self.bodies).map(|(p, b)| b.yield_to(*p)).collect()
    }
}

/// `Σ vᵢ · pᵢ` over both parts: with `p = M v`, the mass-weighted inner product.
fn dot(v: &[Motion], p: &[Motion]) -> Real {
    v.iter().zip(p).map(|(v, p)| v.0.dot(p.0) + v.1.dot(p.1)).sum()
}

/// `x ← a x`.
fn scale(x: &mut [Motion], a: Real) {
    x.iter_mut().for_each(|x| *x = (x.0 * a, x.1 * a));
}

/// `y ← y + a x`.
fn add_scaled(y: &mut [Motion], a: Real, x: &[Motion]) {
    for (y, x) in y.iter_mut().zip(x) {
        *y = (y.0 + x.0 * a, y.1 + x.1 * a);
    }
}

/// The network's highest `ω²` (1/s²) and the pair that carries most of that mode's energy;
/// `None` without a live contact between moving bodies, or where the network degenerates (a
/// non-finite or no positive stiffness).
pub(super) fn highest_frequency(
    contacts: &DiscreteContacts,
    world: &PhysicsWorld,
    spring: bool,
) -> Option<(Real, (ColliderHandle, ColliderHandle))> {
    let network = assemble(contacts, world, spring)?;
    // Momenta `p` and velocities `v = M⁻¹ p` of the Lanczos vectors, `vᵀ p = 1`.
    let start = |b: usize, axis: usize| {
        // A fixed spread of signs and sizes: almost surely not orthogonal to the top mode.
        let h = (b * 6 + axis + 1).wrapping_mul(2_654_435_761) % 1_000;
        h as Real / 1_000.0 - 0.5
    };
    let mut p: Vec<Motion> = (0..network.bodies.len())
        .map(|b| {
            let v = |k: usize| Vector::new(start(b, k), start(b, k + 1), start(b, k + 2));
            (v(0), v(3))
        })
        .collect();
    let mut v = network.velocities(&p);
    let norm = dot(&v, &p);
    if !(norm > 0.0 && norm.is_finite()) {
        return None;
    }
    scale(&mut p, norm.sqrt().recip());
    scale(&mut v, norm.sqrt().recip());
    // The tridiagonal matrix: `alpha` on the diagonal, `beta` beside it.
    let steps = ITERATIONS.min(6 * network.bodies.len());
    let (mut alpha, mut beta): (Vec<Real>, Vec<Real>) =
        (Vec::with_capacity(steps), Vec::with_capacity(steps));
    let mut basis: Vec<Vec<Motion>> = Vec::with_capacity(steps);
    let mut previous: Option<Vec<Motion>> = None;
    loop {
        let mut w = network.stiffness(&v);
        let a = dot(&v, &w);
        if !a.is_finite() {
            return None;
        }
        alpha.push(a);
        add_scaled(&mut w, -a, &p);
        if let (Some(q), Some(b)) = (&previous, beta.last()) {
            add_scaled(&mut w, -*b, q);
        }
        let mut wv = network.velocities(&w);
        let b2 = dot(&wv, &w);
        basis.push(v);
        // Done, or the vectors span a space the network maps into itself (its modes there
        // are found exactly).
        let largest = alpha.iter().fold(0.0, |m: Real, a| m.max(a.abs()));
        if alpha.len() == steps || !(b2 > (1e-12 * largest).powi(2)) {
            break;
        }
        let b = b2.sqrt();
        beta.push(b);
        scale(&mut w, b.recip());
        scale(&mut wv, b.recip());
        previous = Some(std::mem::replace(&mut p, w));
        v = wv;
    }
    let lambda = largest_eigenvalue(&alpha, &beta);
    if !(lambda > 0.0 && lambda.is_finite()) {
        return None;
    }
    // The mode (its velocities), from the tridiagonal matrix's eigenvector; the pair whose
    // spring holds most of its energy names the limit.
    let weights = eigenvector(&alpha, &beta, lambda);
    let mut mode = vec![(Vector::ZERO, Vector::ZERO); network.bodies.len()];
    for (w, q) in weights.iter().zip(&basis) {
        add_scaled(&mut mode, *w, q);
    }
    let springs = &network.springs;
    let pair = springs
        .iter()
        .map(|s| (s.energy(&mode), s.pair))
        .fold((Real::NEG_INFINITY, springs[0].pair), |best, e| if e.0 > best.0 { e } else { best })
        .1;
    Some((lambda, pair))
}

/// The network of the live contacts between moving bodies; `None` when there is none.
fn assemble(contacts: &DiscreteContacts, world: &PhysicsWorld, spring: bool) -> Option<Network> {
    let mut keys: Vec<_> =
        contacts.states.iter().filter(|(_, s)| s.normal_stiffness > 0.0).map(|(k, _)| *k).collect();
    keys.sort_by_key(pair_order);
    let mut index: HashMap<RigidBodyHandle, usize> = HashMap::default();
    let mut bodies: Vec<Body> = Vec::new();
    let mut springs = Vec::with_capacity(keys.len());
    for (ca, cb) in keys {
        let s = &contacts.states[&(ca, cb)];
        let Some(frame) = s.frame else { continue };
        let (ma, mb) =
            (DiscreteContacts::kinematics(world, ca), DiscreteContacts::kinematics(world, cb));
        // Each body's lever to the contact point as seen from its own pose (through periodic
        // faces the two bodies' poses lie a box apart).
        let points =
            [ma.pose.transform_point(frame.anchors[0]), mb.pose.transform_point(frame.anchors[1])];
        let mut slot = |m: &ColliderMotion| -> Option<usize> {
            let h = m.body?;
            let rb = world.bodies.get(h).filter(|rb| rb.is_dynamic())?;
            Some(*index.entry(h).or_insert_with(|| {
                let props = rb.mass_properties();
                let j = &props.effective_world_inv_inertia;
                let (x, y, z) = (real(j.m11), real(j.m22), real(j.m33));
                let (xy, xz, yz) = (real(j.m12), real(j.m13), real(j.m23));
                bodies.push(Body {
                    inverse_mass: vector(props.effective_inv_mass),
                    inverse_inertia: [
                        Vector::new(x, xy, xz),
                        Vector::new(xy, y, yz),
                        Vector::new(xz, yz, z),
                    ],
                });
                bodies.len() - 1
            }))
        };
        let ends = [slot(&ma), slot(&mb)];
        if ends == [None, None] {
            continue;
        }
        let (ha, hb) = (&contacts.handled[&ca], &contacts.handled[&cb]);
        let kappa = if spring { stiffness_ratio(&ha.material, &hb.material) } else { 0.0 };
        // A ball turning about its centre moves no surface: it resists no tilt (what its cap's
        // footprint would give is the normal force's moment about the contact point, which the
        // lever already holds).
        let ball = ha.shape.sphere_radius().is_some() || hb.shape.sphere_radius().is_some();
        let turn = Matrix::from_quat(mb.pose.rotation);
        let rocking = if ball { Matrix::ZERO } else { turn * frame.rocking * turn.transpose() };
        springs.push(Spring {
            bodies: ends,
            levers: [
                points[0] - ma.kinematics.center_of_mass,
                points[1] - mb.kinematics.center_of_mass,
            ],
            normal: mb.pose.rotation * frame.normal,
            normal_stiffness: s.normal_stiffness,
            tangential_stiffness: kappa * s.normal_stiffness,
            rocking,
            pair: (ca, cb),
        });
    }
    (!springs.is_empty()).then_some(Network { bodies, springs })
}

/// The largest eigenvalue of the symmetric tridiagonal matrix with `alpha` on its diagonal
/// and `beta` beside it, by bisection on Sturm counts: the least `x` below which all
/// eigenvalues lie, within round-off, taken from above.
fn largest_eigenvalue(alpha: &[Real], beta: &[Real]) -> Real {
    let m = alpha.len();
    let off = |i: usize| if i < beta.len() { beta[i].abs() } else { 0.0 };
    let radius = |i: usize| off(i) + if i > 0 { off(i - 1) } else { 0.0 };
    // The largest diagonal entry (a Rayleigh quotient) and Gershgorin's bound bracket it.
    let mut lo = alpha.iter().copied().fold(Real::NEG_INFINITY, Real::max);
    let mut hi = (0..m).map(|i| alpha[i] + radius(i)).fold(Real::NEG_INFINITY, Real::max);
    // How many eigenvalues lie below `x`: the negative pivots of `T − x I`.
    let below = |x: Real| {
        let (mut count, mut q) = (0, 1.0);
        for i in 0..m {
            q = alpha[i] - x - if i > 0 { off(i - 1).powi(2) / q } else { 0.0 };
            if q == 0.0 {
                q = -Real::EPSILON * (x.abs() + radius(i)).max(Real::MIN_POSITIVE);
            }
            count += usize::from(q < 0.0);
        }
        count
    };
    while hi - lo > Real::EPSILON * hi.abs() {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if below(mid) == m {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// An eigenvector of the symmetric tridiagonal matrix (`alpha`, `beta`) for its largest
/// eigenvalue `lambda` (from above, so every pivot of `T − λ I` is negative), by two rounds of
/// inverse iteration, scaled to unit length (all ones where the elimination fails).
fn eigenvector(alpha: &[Real], beta: &[Real], lambda: Real) -> Vec<Real> {
    let m = alpha.len();
    let tiny = Real::EPSILON * lambda.abs().max(Real::MIN_POSITIVE);
    let mut x = vec![1.0; m];
    for _ in 0..2 {
        // `(T − λ I) y = x` by elimination down the diagonal, a zero pivot nudged.
        let (mut c, mut y) = (vec![0.0; m], vec![0.0; m]);
        for i in 0..m {
            let below = if i > 0 { beta[i - 1] } else { 0.0 };
            let mut pivot = alpha[i] - lambda - if i > 0 { below * c[i - 1] } else { 0.0 };
            if pivot.abs() < tiny {
                pivot = -tiny;
            }
            c[i] = if i < beta.len() { beta[i] / pivot } else { 0.0 };
            y[i] = (x[i] - if i > 0 { below * y[i - 1] } else { 0.0 }) / pivot;
        }
        for i in (0..m.saturating_sub(1)).rev() {
            y[i] -= c[i] * y[i + 1];
        }
        let norm = y.iter().map(|y| y * y).sum::<Real>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            break;
        }
        x = y.into_iter().map(|y| y / norm).collect();
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Friction;
    use crate::overlap::IntegrationMode;
    use engine::prelude::{ColliderBuilder, RigidBodyBuilder, SharedShape};

    const DENSITY: Real = 2000.0;

    fn material() -> Material {
        Material::new(1e7, 0.3).unwrap()
    }

    /// Bodies stacked on a floor, each `2 h` above the last, left to settle (on the grid, or
    /// with the exact forms where they exist): the world, the drop-in and the bodies from the
    /// bottom up.
    fn stack(
        colliders: &[ColliderBuilder],
        h: Real,
        law: TangentialLaw,
        exact: bool,
    ) -> (PhysicsWorld, DiscreteContacts, Vec<RigidBodyHandle>) {
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = engine_real(1e-3);
        let floor = world.insert_body(RigidBodyBuilder::fixed());
        let up = engine_vector(Vector::Y);
        world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(up)), Some(floor));
        let bodies: Vec<_> = colliders
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let at = engine_vector(Vector::new(0.0, h * (1 + 2 * i) as Real, 0.0));
                let b = world.insert_body(RigidBodyBuilder::dynamic().translation(at));
                world.insert_collider(c.clone().density(engine_real(DENSITY)), Some(b));
                b
            })
            .collect();
        let settings = OverlapSettings::new(4, IntegrationMode::Subcell)
            .unwrap()
            .with_closed_form_spheres(exact)
            .with_exact_polyhedra(exact);
        // The network is what explicit integration resolves.
        let mut contacts = DiscreteContacts::new(settings, 0.5)
            .unwrap()
            .with_friction(Friction::new(0.5, 0.4, 1e-3).unwrap())
            .with_tangential_law(law)
            .with_integration(Integration::Explicit);
        contacts.handle_all(&mut world, material()).unwrap();
        for _ in 0..100 {
            contacts.step(&mut world).unwrap();
        }
        assert_eq!(contacts.contact_count(), colliders.len(), "each body rests on the one below");
        (world, contacts, bodies)
    }

    /// The live contact between bodies `a` and `b` (`None`: the floor).
    fn contact<'c>(
        contacts: &'c DiscreteContacts,
        world: &PhysicsWorld,
        a: Option<RigidBodyHandle>,
        b: Option<RigidBodyHandle>,
    ) -> &'c ContactState {
        let body = |c: &ColliderHandle| {
            world.colliders[*c].parent().filter(|p| world.bodies[*p].is_dynamic())
        };
        let ((_, _), state) = contacts
            .states
            .iter()
            .find(|((x, y), _)| [(body(x), body(y)), (body(y), body(x))].contains(&(a, b)))
            .expect("a live contact");
        state
    }

    /// In the network, a cube resting on a face vibrates fastest by sliding and rocking on its
    /// contact: the tangential spring `κ k` at the lever `ℓ` down to the face's centre (the
    /// contact point, the overlap's centroid, lies between `h − d` and `h` below the centre)
    /// and the face's resistance to tilting `k_r = (F/V) J`, for a face pressed evenly `k J/A =
    /// k h²/3` (a punch's `F = k d`, `V = A d`; its volume law's exponent `1 + d/h` takes up
    /// to `d/2h` off `F`). The mode's `ω²` is the larger eigenvalue of `M⁻¹K` with
    /// `K = [[κk, κkℓ], [κkℓ, κkℓ² + k_r]]`, `M = diag(m, I)` — well below what the bounding
    /// radius `√3 h` as the lever would give, and above the point spring's `κ k (1/m + ℓ²/I)`.
    #[test]
    fn a_cube_on_a_floor_vibrates_as_its_spring_and_its_face_at_the_face_centre() {
        // On the grid and as exact polyhedra (no geometry kept between evaluations).
        for exact in [false, true] {
            let h = 0.01;
            let cube = ColliderBuilder::cuboid(engine_real(h), engine_real(h), engine_real(h));
            let (world, contacts, bodies) = stack(&[cube], h, TangentialLaw::Spring, exact);
            let k = contact(&contacts, &world, Some(bodies[0]), None).normal_stiffness;
            // The cube's centre lies `h − d` above the floor.
            let d = h - real(world.bodies[bodies[0]].translation().y);
            let m = real(world.bodies[bodies[0]].mass());
            let inertia = m * (2.0 * h).powi(2) / 6.0;
            let kt = stiffness_ratio(&material(), &material()) * k;
            let mode = |lever: Real, rocking: Real| {
                let (a, c) = (kt / m, (kt * lever * lever + rocking) / inertia);
                let b = kt * lever / (m * inertia).sqrt();
                0.5 * (a + c) + (0.25 * (a - c).powi(2) + b * b).sqrt()
            };
            let rocking = k * h * h / 3.0;
            let (low, high) = (mode(h - d, rocking * (1.0 - d / (2.0 * h))), mode(h, rocking));
            let (omega2, _) = highest_frequency(&contacts, &world, true).unwrap();
            assert!(low > k / m, "the sliding and rocking mode is the highest");
            assert!(
                omega2 >= low * (1.0 - 1e-6) && omega2 <= high * (1.0 + 1e-6),
                "{omega2} outside [{low}, {high}] ({exact})"
            );
            assert!(omega2 > 1.1 * kt * (1.0 / m + h * h / inertia), "the face's tilt counts");
            assert!(omega2 < 0.6 * mode(3.0_f64.sqrt() * h, 0.0));
        }
    }

    /// Two balls stacked on a floor, normal springs alone (the levers lie along the normals,
    /// so nothing turns): a chain of two masses whose highest `ω²` is
    /// `(k₁ + 2k₂ + √(k₁² + 4k₂²)) / 2m`, above either contact's own `k/m*` — on the grid and
    /// with the balls' overlaps in closed form, which keep no geometry between evaluations.
    #[test]
    fn a_stack_vibrates_faster_than_either_of_its_contacts() {
        for exact in [false, true] {
            let r = 0.01;
            let ball = ColliderBuilder::ball(engine_real(r));
            let (world, mut contacts, bodies) =
                stack(&[ball.clone(), ball], r, TangentialLaw::SlipSpeed, exact);
            let k1 = contact(&contacts, &world, Some(bodies[0]), None).normal_stiffness;
            let k2 = contact(&contacts, &world, Some(bodies[0]), Some(bodies[1])).normal_stiffness;
            let m = real(world.bodies[bodies[0]].mass());
            let chain = (k1 + 2.0 * k2 + (k1 * k1 + 4.0 * k2 * k2).sqrt()) / (2.0 * m);
            let (omega2, pair) = highest_frequency(&contacts, &world, false).unwrap();
            // Within the round-off of rapier's numbers (f32 in `rapier_f32`).
            assert!((omega2 / chain - 1.0).abs() < 1e-6, "{omega2} against {chain} ({exact})");
            assert!(omega2 > (k1 / m).max(2.0 * k2 / m) * 1.05);
            // The top mode moves the balls against each other: their contact holds most of it.
            let body = |c: ColliderHandle| world.colliders[c].parent();
            let named = [body(pair.0), body(pair.1)];
            let balls = [Some(bodies[0]), Some(bodies[1])];
            assert!(named == balls || named == [balls[1], balls[0]], "the balls' contact named");
            // The sub-step advice resolves the chain's half-period, which neither contact's own
            // rule asks as much of. (Both contacts made far stiffer, so that no impact rule at
            // rest speed asks more, and asked for a long step, so that the counts differ by
            // more than their rounding.)
            for state in contacts.states.values_mut() {
                state.normal_stiffness *= 1e4;
            }
            let (omega2, _) = highest_frequency(&contacts, &world, false).unwrap();
            let dt = 0.02;
            let needed = |omega2: Real| {
                (dt * omega2.sqrt() / core::f64::consts::PI * MIN_SUBSTEPS_PER_CONTACT).ceil()
            };
            let substeps = contacts.substeps(&world, engine_real(dt)).unwrap() as Real;
            assert!(
                substeps >= needed(omega2),
                "{substeps} sub-steps for the chain's {} ({exact})",
                needed(omega2)
            );
            assert!(needed(omega2) > needed(1e4 * (k1 / m).max(2.0 * k2 / m)));
        }
    }

    /// A live contact whose stiffness is not finite (a force law that overflowed) is refused
    /// by the sub-step advice with the pair named, not resolved by no sub-step at all.
    #[test]
    fn a_contact_stiffness_beyond_the_numbers_is_reported() {
        let r = 0.01;
        let ball = ColliderBuilder::ball(engine_real(r));
        let (world, mut contacts, _) = stack(&[ball], r, TangentialLaw::Spring, false);
        for state in contacts.states.values_mut() {
            state.normal_stiffness = Real::INFINITY;
        }
        let dt = world.integration_parameters.dt;
        match contacts.substeps(&world, dt) {
            Err(Error::NonFinite { what, detail }) => {
                assert!(what.contains("stiffness"), "{what}");
                assert!(detail.contains("colliders"), "{detail}");
            }
            other => panic!("expected a non-finite stiffness reported, got {other:?}"),
        }
    }

    /// A stack of six bodies of three kinds (36 degrees of freedom, more than the Lanczos
    /// steps), with contacts between moving bodies at both ends: the network's stiffness is
    /// symmetric (each spring's loads on its two bodies are equal and opposite, levers and
    /// turns alike), and the estimate is the largest eigenvalue of `M⁻¹K` assembled densely.
    #[test]
    fn the_estimate_is_the_largest_eigenvalue_of_the_assembled_network() {
        let h = 0.01;
        let cube = ColliderBuilder::cuboid(engine_real(h), engine_real(h), engine_real(h));
        let cylinder = ColliderBuilder::cylinder(engine_real(h), engine_real(0.8 * h));
        let ball = ColliderBuilder::ball(engine_real(h));
        let bodies = [cube.clone(), cylinder.clone(), cube.clone(), cylinder, cube, ball];
        let (world, contacts, _) = stack(&bodies, h, TangentialLaw::Spring, false);
        let network = assemble(&contacts, &world, true).unwrap();
        let n = 6 * network.bodies.len();
        assert_eq!(n, 36);
        let column = |f: &dyn Fn(&[Motion]) -> Vec<Motion>, j: usize| {
            let mut e = vec![(Vector::ZERO, Vector::ZERO); n / 6];
            let (b, k) = (j / 6, j % 6);
            if k < 3 {
                e[b].0[k] = 1.0
            } else {
                e[b].1[k - 3] = 1.0
            }
            f(&e)
                .iter()
                .flat_map(|(x, w)| x.to_array().into_iter().chain(w.to_array()))
                .collect::<Vec<_>>()
        };
        let dense = |f: &dyn Fn(&[Motion]) -> Vec<Motion>| {
            let columns: Vec<_> = (0..n).map(|j| column(f, j)).collect();
            engine::na::DMatrix::<f64>::from_fn(n, n, |i, j| columns[j][i])
        };
        let k = dense(&|v| network.stiffness(v));
        let m_inv = dense(&|p| network.velocities(p));
        let scale = k.amax();
        assert!((&k - k.transpose()).amax() <= 1e-12 * scale, "K is symmetric");
        // `M⁻¹ = L Lᵀ`: `M⁻¹K` has the eigenvalues of `Lᵀ K L`.
        let l = m_inv.cholesky().expect("every body moves on every axis").l();
        let top = (l.transpose() * &k * &l).symmetric_eigenvalues().max();
        let (omega2, _) = highest_frequency(&contacts, &world, true).unwrap();
        assert!(omega2 <= top * (1.0 + 1e-9), "{omega2} above {top}");
        assert!(omega2 >= top * (1.0 - 1e-6), "{omega2} below {top}");
    }

    /// Two balls pressed together across a periodic box's corner and the same pair inside the
    /// box: each body's lever comes from its own pose (the two lie a box apart across the
    /// faces), so the network and its highest frequency are the same.
    #[test]
    fn a_contact_across_periodic_faces_vibrates_as_inside_the_box() {
        let (l, r) = (0.1, 0.01);
        let offset = Vector::new(2.0, 0.3, 0.2).normalize() * (2.0 * r - 3e-4);
        let mut estimates = Vec::new();
        for a in [Vector::new(l - 0.004, l - 0.002, 0.05), Vector::new(0.05, 0.05, 0.05)] {
            let b = a + offset;
            let wrapped = b - Vector::new((b.x / l).floor() * l, (b.y / l).floor() * l, 0.0);
            let mut world = PhysicsWorld::new();
            world.gravity = engine_vector(Vector::ZERO);
            world.integration_parameters.dt = engine_real(1e-4);
            let domain =
                crate::periodic::PeriodicBox::new(Vector::ZERO, Vector::splat(l), [true; 3])
                    .unwrap();
            let settings = OverlapSettings::new(4, IntegrationMode::Subcell).unwrap();
            let mut contacts = DiscreteContacts::new(settings, 0.5)
                .unwrap()
                .with_friction(Friction::new(0.5, 0.4, 1e-3).unwrap())
                .with_periodic(domain);
            for (at, spin) in [(a, Vector::new(0.0, 0.0, 3.0)), (wrapped, Vector::ZERO)] {
                let body = world.insert_body(
                    RigidBodyBuilder::dynamic()
                        .translation(engine_vector(at))
                        .angvel(engine_vector(spin)),
                );
                let ball = ColliderBuilder::ball(engine_real(r)).density(engine_real(DENSITY));
                let c = world.insert_collider(ball, Some(body));
                contacts.handle(&mut world, c, material()).unwrap();
            }
            contacts.step(&mut world).unwrap();
            assert_eq!(contacts.contact_count(), 1, "the pair touches");
            estimates.push(highest_frequency(&contacts, &world, true).unwrap().0);
        }
        let [across, inside] = [estimates[0], estimates[1]];
        // Within the round-off of rapier's numbers (f32 in `rapier_f32`).
        assert!((across / inside - 1.0).abs() < 1e-5, "across {across}, inside {inside}");
    }
}
