//! The live contacts as one network of springs between rigid bodies, and its highest
//! vibration frequency: what an explicit sub-step must resolve once bodies rest on each other.
//!
//! Each live contact couples its two bodies at its contact point by its normal stiffness
//! `k_n` along the normal and, with the tangential spring, `κ k_n` across it. A body's
//! translation and turning both move its contact points, so a body with several contacts
//! vibrates in modes that no pair alone shows: a pile's highest frequency may lie above every
//! pair's own (a chain of equal bodies reaches twice one pair's `ω²`), or below a pair's bound
//! taken at the bounding radius (a contact under a face's centre has a short lever). The
//! network's `ω²_max`, the largest eigenvalue of `M⁻¹K`, is estimated by power iteration from
//! a fixed start: its Rayleigh quotient rises towards `ω²_max` from below and comes within a
//! few per cent of the value of many more rounds in [`ITERATIONS`] rounds on the piles measured
//! (`docs/performance.md`). That shortfall, and a face's resistance to tilting that point
//! springs leave out (the overlap's centroid moves towards the deeper side), are for the
//! sub-step's margin below explicit integration's limit ([`STABLE_SUBSTEPS_PER_HALF_PERIOD`]
//! sub-steps per half-period at least) to cover.
//!
//! Contacts are taken in the order of their collider handles, so the estimate does not depend
//! on the order of the contact map (a resumed run gives the same sub-steps).

use super::*;

/// Rounds of power iteration per estimate.
pub(super) const ITERATIONS: usize = 30;

/// A contact of the network: its bodies (indices into the bodies' list, `None` for a body
/// that does not move), their levers to the contact point, the normal and the stiffnesses.
struct Spring {
    bodies: [Option<usize>; 2],
    levers: [Vector; 2],
    normal: Vector,
    normal_stiffness: Real,
    tangential_stiffness: Real,
    pair: (ColliderHandle, ColliderHandle),
}

impl Spring {
    /// How far the first body's contact point moves against the second's when the bodies
    /// move by `v` (linear, angular).
    fn stretch(&self, v: &[(Vector, Vector)]) -> Vector {
        let at = |s: usize| {
            self.bodies[s].map_or(Vector::ZERO, |b| v[b].0 + v[b].1.cross(self.levers[s]))
        };
        at(0) - at(1)
    }

    /// The spring's force on the first body for a stretch `u`.
    fn force(&self, u: Vector) -> Vector {
        let along = self.normal * u.dot(self.normal);
        -(along * self.normal_stiffness + (u - along) * self.tangential_stiffness)
    }
}

/// A moving body: inverse mass and world inverse inertia (locked axes left out).
struct Body {
    inverse_mass: Vector,
    inverse_inertia: [Vector; 3],
}

impl Body {
    /// `M⁻¹ (f, τ)`.
    fn yield_to(&self, (f, t): (Vector, Vector)) -> (Vector, Vector) {
        let j = &self.inverse_inertia;
        (f * self.inverse_mass, Vector::new(j[0].dot(t), j[1].dot(t), j[2].dot(t)))
    }
}

/// The network's highest `ω²` (1/s²) and the pair that carries most of that mode's energy;
/// `None` without a live contact between moving bodies.
pub(super) fn highest_frequency(
    contacts: &DiscreteContacts,
    world: &PhysicsWorld,
    spring: bool,
) -> Option<(Real, (ColliderHandle, ColliderHandle))> {
    let mut keys: Vec<_> =
        contacts.states.iter().filter(|(_, s)| s.normal_stiffness > 0.0).map(|(k, _)| *k).collect();
    keys.sort_by_key(|(a, b)| (a.into_raw_parts(), b.into_raw_parts()));
    let mut index: HashMap<RigidBodyHandle, usize> = HashMap::default();
    let mut bodies: Vec<Body> = Vec::new();
    let mut springs = Vec::with_capacity(keys.len());
    for (ca, cb) in keys {
        let s = &contacts.states[&(ca, cb)];
        let Some(r) = s.reference else { continue };
        let (ma, mb) =
            (DiscreteContacts::kinematics(world, ca), DiscreteContacts::kinematics(world, cb));
        // Each body's lever to the contact point as seen from its own pose (through periodic
        // faces the two bodies' poses lie a box apart).
        let points = [
            ma.pose.transform_point(r.relative.inverse_transform_point(r.contact_point)),
            mb.pose.transform_point(r.contact_point),
        ];
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
        springs.push(Spring {
            bodies: ends,
            levers: [
                points[0] - ma.kinematics.center_of_mass,
                points[1] - mb.kinematics.center_of_mass,
            ],
            normal: mb.pose.rotation * r.normal,
            normal_stiffness: s.normal_stiffness,
            tangential_stiffness: kappa * s.normal_stiffness,
            pair: (ca, cb),
        });
    }
    if springs.is_empty() {
        return None;
    }
    // Momenta `p` and velocities `v = M⁻¹ p`; `λ = vᵀ K v / vᵀ M v` with `vᵀ M v = vᵀ p`.
    let start = |b: usize, axis: usize| {
        // A fixed spread of signs and sizes: almost surely not orthogonal to the top mode.
        let h = (b * 6 + axis + 1).wrapping_mul(2_654_435_761) % 1_000;
        h as Real / 1_000.0 - 0.5
    };
    let mut p: Vec<(Vector, Vector)> = (0..bodies.len())
        .map(|b| {
            (
                Vector::new(start(b, 0), start(b, 1), start(b, 2)),
                Vector::new(start(b, 3), start(b, 4), start(b, 5)),
            )
        })
        .collect();
    let mut v: Vec<(Vector, Vector)> = p.iter().zip(&bodies).map(|(p, b)| b.yield_to(*p)).collect();
    let mut lambda = 0.0;
    for _ in 0..ITERATIONS {
        // `p ← −K v` (the springs' forces and torques), then `v ← M⁻¹ p`, normalised.
        let (mut vkv, mut vmv) = (0.0, 0.0);
        for (pb, vb) in p.iter().zip(&v) {
            vmv += vb.0.dot(pb.0) + vb.1.dot(pb.1);
        }
        p.iter_mut().for_each(|q| *q = (Vector::ZERO, Vector::ZERO));
        for s in &springs {
            let u = s.stretch(&v);
            let f = s.force(u);
            vkv -= f.dot(u);
            for (end, f) in [(0, f), (1, -f)] {
                if let Some(b) = s.bodies[end] {
                    p[b].0 += f;
                    p[b].1 += s.levers[end].cross(f);
                }
            }
        }
        if !(vmv > 0.0 && vkv.is_finite()) {
            return None;
        }
        lambda = vkv / vmv;
        let mut norm = 0.0;
        for ((pb, vb), body) in p.iter_mut().zip(v.iter_mut()).zip(&bodies) {
            *pb = (-pb.0, -pb.1);
            *vb = body.yield_to(*pb);
            norm += vb.0.dot(pb.0) + vb.1.dot(pb.1);
        }
        if !(norm > 0.0) {
            return None;
        }
        let scale = norm.sqrt().recip();
        for (pb, vb) in p.iter_mut().zip(v.iter_mut()) {
            *pb = (pb.0 * scale, pb.1 * scale);
            *vb = (vb.0 * scale, vb.1 * scale);
        }
    }
    // The pair whose spring holds most of the mode's energy names the limit.
    let energy = |s: &Spring| {
        let u = s.stretch(&v);
        -s.force(u).dot(u)
    };
    let pair = springs
        .iter()
        .map(|s| (energy(s), s.pair))
        .fold((Real::NEG_INFINITY, springs[0].pair), |best, e| if e.0 > best.0 { e } else { best })
        .1;
    (lambda > 0.0 && lambda.is_finite()).then_some((lambda, pair))
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

    /// Bodies stacked on a floor, each `2 h` above the last, left to settle: the world, the
    /// drop-in and the bodies from the bottom up.
    fn stack(
        colliders: &[ColliderBuilder],
        h: Real,
        law: TangentialLaw,
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
        let settings = OverlapSettings::new(4, IntegrationMode::Subcell).unwrap();
        let mut contacts = DiscreteContacts::new(settings, 0.5)
            .unwrap()
            .with_friction(Friction::new(0.5, 0.4, 1e-3).unwrap())
            .with_tangential_law(law);
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
    /// spring, whose lever is the half-height down to the face's centre (the contact point, the
    /// overlap's centroid, lies between `h - d` and `h` below the centre):
    /// `ω² = κ k (1/m + r²/I)`, far below what the bounding radius `√3 h` as the lever would give.
    #[test]
    fn a_cube_on_a_floor_vibrates_as_its_spring_at_the_face_centre() {
        let h = 0.01;
        let cube = ColliderBuilder::cuboid(engine_real(h), engine_real(h), engine_real(h));
        let (world, contacts, bodies) = stack(&[cube], h, TangentialLaw::Spring);
        let state = contact(&contacts, &world, Some(bodies[0]), None);
        let (k, d) = (state.normal_stiffness, state.reference.unwrap().indentation);
        let m = real(world.bodies[bodies[0]].mass());
        let inertia = m * (2.0 * h).powi(2) / 6.0;
        let kappa = stiffness_ratio(&material(), &material());
        let sliding = |r: Real| kappa * k * (1.0 / m + r * r / inertia);
        let (omega2, _) = highest_frequency(&contacts, &world, true).unwrap();
        assert!(sliding(h - d) > k / m, "the spring's mode is the highest");
        assert!(
            omega2 >= sliding(h - d) * (1.0 - 1e-6) && omega2 <= sliding(h) * (1.0 + 1e-6),
            "{omega2} outside [{}, {}]",
            sliding(h - d),
            sliding(h)
        );
        assert!(omega2 < 0.5 * sliding(3.0_f64.sqrt() * h));
    }

    /// Two balls stacked on a floor, normal springs alone (the levers lie along the normals,
    /// so nothing turns): a chain of two masses whose highest `ω²` is
    /// `(k₁ + 2k₂ + √(k₁² + 4k₂²)) / 2m`, above either contact's own `k/m*`.
    #[test]
    fn a_stack_vibrates_faster_than_either_of_its_contacts() {
        let r = 0.01;
        let ball = ColliderBuilder::ball(engine_real(r));
        let (world, contacts, bodies) = stack(&[ball.clone(), ball], r, TangentialLaw::SlipSpeed);
        let k1 = contact(&contacts, &world, Some(bodies[0]), None).normal_stiffness;
        let k2 = contact(&contacts, &world, Some(bodies[0]), Some(bodies[1])).normal_stiffness;
        let m = real(world.bodies[bodies[0]].mass());
        let chain = (k1 + 2.0 * k2 + (k1 * k1 + 4.0 * k2 * k2).sqrt()) / (2.0 * m);
        let (omega2, pair) = highest_frequency(&contacts, &world, false).unwrap();
        // Within the round-off of rapier's numbers (f32 in `rapier_f32`).
        assert!((omega2 / chain - 1.0).abs() < 1e-6, "{omega2} against {chain}");
        assert!(omega2 > (k1 / m).max(2.0 * k2 / m) * 1.05);
        // The top mode moves the balls against each other: their contact holds most of it.
        let body = |c: ColliderHandle| world.colliders[c].parent();
        let named = [body(pair.0), body(pair.1)];
        let balls = [Some(bodies[0]), Some(bodies[1])];
        assert!(named == balls || named == [balls[1], balls[0]], "the balls' contact is named");
    }
}
