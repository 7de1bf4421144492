//! Resting and slowly moving contacts taken implicitly ([`Integration::Implicit`]): each
//! contact's law over the sub-step from its evaluation (or, for a pair about to touch, from
//! a probe of the overlap it will make), the bodies they join grouped into islands, each
//! island's end-of-sub-step velocities solved as one convex problem (`crate::implicit`), and
//! the impulses found put on the bodies as forces over the sub-step.

use super::forces::film_contact;
use super::*;
use crate::contact::ContactOutput;
use crate::force::{elastic_force, normal_stiffness, rocking_damping_rate, volume_exponent};
use crate::implicit::{
    self, IslandBody, JointLaw, Law, Motion, NormalLaw, Response, SpringLaw, StepLaw,
};
use crate::math::Matrix;
use crate::overlap::compute_overlap;

/// A contact taken implicitly on this sub-step: its law (island indices not yet set) and its
/// bodies.
pub(super) struct Resting {
    pub(super) law: StepLaw,
    pub(super) bodies: (Option<RigidBodyHandle>, Option<RigidBodyHandle>),
    /// The pair, and the shift to B's image nearest A.
    pub(super) pair: (ColliderHandle, ColliderHandle),
    pub(super) shift: Vector,
}

/// What a sub-step's islands gave: each resting contact's response, the relative motion at
/// its contact at the end of the sub-step and its two ends' velocities then, in the order
/// given.
pub(super) type Responses = Vec<(Response, (Motion, [Motion; 2]))>;

impl DiscreteContacts {
    /// The law of a live contact evaluated as `out`, with parameters `params`, state `state`,
    /// between the colliders `a` and `b` (as they are at the evaluation): the normal law from the overlap's volume
    /// law, the tangential spring from the stretch it `carried` into the evaluation and
    /// whether it was sliding (the evaluation's own stick-or-slide decision, taken at the
    /// velocities at its start, is the explicit law's, not this one's), the rocking from the
    /// overlap's footprint (none against a ball).
    ///
    /// Its damping is Nassauer & Kuna's for an impact at `rest_speed` where the contact began
    /// slower: their `c = a(e)/v₀` belongs to an impact at `v₀`, and for a contact that began
    /// at rest it would cut the force off at any separation faster than the floor speed
    /// ([`PairParameters::min_approach_speed`], a millimetre per second) — a step in the law
    /// that an implicit step of milliseconds crosses at every motion, while the implicit
    /// step damps a resting contact by itself.
    pub(super) fn resting_law(
        &self,
        params: &PairParameters,
        (out, state, carried): (&ContactOutput, &ContactState, (Vector, bool)),
        (a, b): (&Side<'_>, &Side<'_>),
        (h, rest_speed): (Real, Real),
    ) -> StepLaw {
        let (ka, kb) = (&a.kinematics, &b.kinematics);
        let g = &out.geometry;
        let damping = state.damping.min(params.damping_for(rest_speed));
        let f_el = elastic_force(params, g);
        let (d, n, x) = (g.indentation, g.normal, g.contact_point);
        let q = 0.5 * (1.0 + volume_exponent(g.volume, d, g.surface_area).clamp(1.0, 2.0));
        let coefficient = if d > 0.0 && f_el > 0.0 { f_el / d.powf(q) } else { 0.0 };
        let k_n = normal_stiffness(f_el, g);
        let spring =
            self.spring_law(params, k_n, damping, f_el, out.force.normal_force, carried, h);
        let ball =
            a.handled.shape.sphere_radius().is_some() || b.handled.shape.sphere_radius().is_some();
        let (rocking, rocking_damping) = match (ball, state.frame) {
            (false, Some(frame)) => {
                let turn = Matrix::from_quat(b.pose.rotation);
                (turn * frame.rocking * turn.transpose(), rocking_damping_rate(damping, f_el, g))
            }
            _ => (Matrix::ZERO, Matrix::ZERO),
        };
        StepLaw {
            bodies: [None, None],
            given: [(ka.linvel, ka.angvel), (kb.linvel, kb.angvel)],
            levers: [x - ka.center_of_mass, x - kb.center_of_mass],
            normal: n,
            normal_law: NormalLaw { depth: d, coefficient, exponent: q, damping },
            spring,
            rocking,
            rocking_damping,
        }
    }

    /// The tangential part of a resting law over a sub-step of `h`: the spring with the
    /// stretch it `carried` and whether it was sliding (nothing for a new pair), or — under the slip-speed law — its
    /// regularised Coulomb force, a viscous slip up to `μ_k F_n` at the transition speed, held
    /// within the same disc.
    ///
    /// The spring is at most as stiff as [`STICK_RESOLUTION`] makes it against the pair's
    /// tangential mass `m_t` over the sub-step, `k_t h² <= m_t / σ`: stiffer, its stretch
    /// under any load the step can carry is below what the step resolves anyway (a
    /// micrometre at 60 Hz), while the implicit step's Newton iterations, which cross between
    /// sticking and sliding, converge the slower the stiffer the stick.
    #[allow(clippy::too_many_arguments)]
    fn spring_law(
        &self,
        params: &PairParameters,
        k_n: Real,
        damping: Real,
        f_el: Real,
        f_n: Real,
        (carried, sliding): (Vector, bool),
        h: Real,
    ) -> Option<SpringLaw> {
        let friction = params.friction;
        if friction.is_none() {
            return None;
        }
        Some(match params.tangential {
            TangentialLaw::Spring => {
                let resolved = params
                    .tangential_mass
                    .filter(|m| m.is_finite())
                    .map_or(Real::INFINITY, |m_t| m_t / (STICK_RESOLUTION * h * h));
                let k_t = (params.tangential_stiffness_ratio * k_n).min(resolved);
                SpringLaw {
                    stiffness: k_t,
                    viscosity: crate::tangential::damping(params, k_t, damping, f_el),
                    carried,
                    coefficient: if sliding {
                        friction.kinetic_coefficient
                    } else {
                        friction.static_coefficient
                    },
                    normal_force: f_n,
                }
            }
            TangentialLaw::SlipSpeed => SpringLaw {
                stiffness: 0.0,
                viscosity: friction.kinetic_coefficient * f_n.max(0.0) / friction.transition_speed,
                carried: Vector::ZERO,
                coefficient: friction.kinetic_coefficient,
                normal_force: f_n,
            },
        })
    }
}

/// `σ`: a sticking contact's spring is at most `1/σ` times as stiff as its tangential mass
/// over the step squared (see `spring_law`).
const STICK_RESOLUTION: Real = 1e-3;

/// What a pair apart (or touching without an overlap) does within a sub-step.
// The law is carried by value: one per pair about to touch and sub-step, where a box would
// allocate each time.
#[allow(clippy::large_enum_variant)]
pub(super) enum Approach {
    /// It touches slowly: its law over the sub-step.
    Resting(StepLaw),
    /// It meets at the rest speed or faster: an impact.
    Impact,
    /// It stays apart.
    Apart,
}

/// The gap, in the smaller body's half-size, within which a pair apart counts as touching
/// (and the least depth its overlap is probed at).
const TOUCHING: Real = 1e-3;

/// A collider's side of a pair about to touch: its handled record, pose, parry shape and
/// body motion, and the linear acceleration of its body from gravity and the user's force.
pub(super) struct Side<'a> {
    pub(super) handled: &'a Handled,
    pub(super) pose: Pose,
    pub(super) shape: &'a dyn parry3d_f64::shape::Shape,
    pub(super) kinematics: BodyKinematics,
    pub(super) acceleration: Vector,
}

impl DiscreteContacts {
    /// The law over a sub-step of `h` of a pair apart (or touching without overlap) that
    /// closes within the sub-step slower than `rest_speed`: `None` where it does not reach
    /// the other body, or reaches it faster (an impact, which the explicit sub-steps
    /// resolve).
    ///
    /// The pair's nearest points give the normal and the gap; how far the gap closes follows
    /// from the bodies' velocities and accelerations at them. The overlap it will make is
    /// probed with A moved towards B by the gap and a little more (what the sub-step may
    /// press in, at least a thousandth of the smaller body's half-size): its volume law gives
    /// the normal law, taken from the gap onwards, and its normal and centroid the contact's
    /// frame. A pair touching now at rest, as rapier's examples stack their boxes, thus
    /// carries its load from the first sub-step.
    pub(super) fn approaching_law(
        &self,
        params: &PairParameters,
        a: &Side<'_>,
        b: &Side<'_>,
        h: Real,
        rest_speed: Real,
    ) -> Approach {
        let reach = a.travel(h) + b.travel(h);
        let Some(c) =
            film_contact((a.handled, &a.pose, a.shape), (b.handled, &b.pose, b.shape), reach)
        else {
            return Approach::Apart;
        };
        let gap = c.dist.max(0.0);
        let x = 0.5 * (c.point1 + c.point2);
        let smaller = a.handled.half_size.min(b.handled.half_size);
        // How fast the pair closes along `n` now and at the end of the sub-step.
        let closing = |n: Vector| {
            let now = -(a.kinematics.velocity_at(x) - b.kinematics.velocity_at(x)).dot(n);
            (now, now - h * (a.acceleration - b.acceleration).dot(n))
        };
        // The directions to probe along: parry's normal; where that finds no overlap (parry's
        // normal of two faces touching edge to edge is any of the faces'), the line between
        // the bodies' centres (a half-space's own normal).
        let directions =
            [(-c.normal1).try_normalize(), a.towards(b).and_then(|t| t.try_normalize())];
        // The pair takes part where it closes its gap within the sub-step — or touches now: a
        // pair touching may be pressed together by the bodies it rests on or that rest on it,
        // which its own motion does not show. Meeting at the rest speed or faster, it is an
        // impact.
        let Some(n) = directions.into_iter().flatten().next() else { return Approach::Apart };
        let (approach, end_speed) = closing(n);
        let touching = gap <= TOUCHING * smaller;
        if !(h * end_speed > gap || touching) {
            // Not closing along the normal within the sub-step; yet a turning body's corner
            // may reach the other within its travel: fast enough to be an impact, its own
            // sub-steps find out.
            let rim = |s: &Side<'_>| {
                let r = s.handled.radius + s.handled.centre.length();
                if r.is_finite() {
                    s.kinematics.angvel.length() * r
                } else {
                    0.0
                }
            };
            let bound = (a.kinematics.linvel - b.kinematics.linvel).length()
                + rim(a)
                + rim(b)
                + h * (a.acceleration - b.acceleration).length();
            return if bound >= rest_speed { Approach::Impact } else { Approach::Apart };
        }
        if end_speed.max(approach) >= rest_speed {
            return Approach::Impact;
        }
        let probe_along = |n: Vector| {
            let (_, end) = closing(n);
            let probe = (h * end - gap).clamp(TOUCHING * smaller, 0.05 * smaller);
            let shift = -n * (gap + probe);
            let moved = Pose::from_parts(a.pose.translation + shift, a.pose.rotation);
            compute_overlap(
                &a.handled.shape,
                &moved,
                &b.handled.shape,
                &b.pose,
                &self.settings,
                None,
            )
            .ok()
            .flatten()
            .filter(|g| g.indentation > 0.0 && g.volume > 0.0)
            .map(|g| (g, shift))
        };
        let Some((g, shift)) = directions.into_iter().flatten().find_map(probe_along) else {
            return Approach::Apart;
        };
        // Its point placed as a live contact's is: through a ball's centre, in the plane of a
        // body of revolution's axis.
        let moved = Pose::from_parts(a.pose.translation + shift, a.pose.rotation);
        let g = crate::contact::placed(
            g,
            &BodyState { shape: &a.handled.shape, pose: moved, kinematics: a.kinematics },
            &BodyState { shape: &b.handled.shape, pose: b.pose, kinematics: b.kinematics },
        );
        let f_el = elastic_force(params, &g);
        if !(f_el > 0.0) {
            return Approach::Apart;
        }
        let q =
            0.5 * (1.0 + volume_exponent(g.volume, g.indentation, g.surface_area).clamp(1.0, 2.0));
        let k_n = normal_stiffness(f_el, &g);
        let damping = params.damping_for(rest_speed);
        let point = g.contact_point - shift * 0.5;
        // A face resting on a face holds its load's moment by the overlap's resistance to
        // tilting from the first sub-step on (a ball has none).
        let ball =
            a.handled.shape.sphere_radius().is_some() || b.handled.shape.sphere_radius().is_some();
        let (rocking, rocking_damping) = if ball {
            (Matrix::ZERO, Matrix::ZERO)
        } else {
            let frame = crate::contact::ContactFrame::new(&g, k_n, &moved, &b.pose);
            let turn = Matrix::from_quat(b.pose.rotation);
            (turn * frame.rocking * turn.transpose(), rocking_damping_rate(damping, f_el, &g))
        };
        Approach::Resting(StepLaw {
            bodies: [None, None],
            given: [
                (a.kinematics.linvel, a.kinematics.angvel),
                (b.kinematics.linvel, b.kinematics.angvel),
            ],
            levers: [point - a.kinematics.center_of_mass, point - b.kinematics.center_of_mass],
            normal: g.normal,
            normal_law: NormalLaw {
                // A moved by `shift` indents by its part against the normal.
                depth: g.indentation + shift.dot(g.normal),
                coefficient: f_el / g.indentation.powf(q),
                exponent: q,
                damping,
            },
            spring: self.spring_law(params, k_n, damping, f_el, 0.0, (Vector::ZERO, false), h),
            rocking,
            rocking_damping,
        })
    }

    /// Solves the islands the `resting` contacts join over a sub-step of `h`, each body as
    /// `bodies` gives it (`None`: one that moves as it does): each contact's response, in
    /// order.
    ///
    /// Islands are the connected parts of the graph of dynamic bodies the contacts and the
    /// rapier impulse joints between them join; a fixed or kinematic body moves as it does and
    /// joins no island (nor does a body of a multibody, which moves at its velocity at the
    /// start and takes its contacts' impulses as forces). A joint is held in the solve as a
    /// stiff spring on the axes it locks ([`JOINT_RESOLUTION`]): the bodies it carries press on
    /// their contacts as the joint lets them — a see-saw's plank under a pile, which, left to
    /// rapier's joint solver after the contacts were solved, would take the pile's impulses
    /// one step late and, lighter than the pile, amplify them. Rapier's joint solver then keeps
    /// the joint (its motors and limits too) as always. The islands are solved in parallel
    /// (feature `parallel`), each on its own, so the result does not depend on the thread
    /// count.
    pub(super) fn solve_islands(
        &self,
        world: &PhysicsWorld,
        resting: &mut [Resting],
        bodies: &(dyn Fn(RigidBodyHandle) -> Option<IslandBody> + Sync),
        h: Real,
    ) -> Result<(Responses, usize)> {
        // Island bodies: every dynamic body a contact touches, then the bodies their joints
        // carry, in first-seen order.
        let mut index: HashMap<RigidBodyHandle, usize> = HashMap::default();
        let mut handles: Vec<RigidBodyHandle> = Vec::new();
        fn slot(
            (index, handles): (&mut HashMap<RigidBodyHandle, usize>, &mut Vec<RigidBodyHandle>),
            b: RigidBodyHandle,
        ) -> usize {
            *index.entry(b).or_insert_with(|| {
                handles.push(b);
                handles.len() - 1
            })
        }
        let states: std::cell::RefCell<HashMap<RigidBodyHandle, Option<IslandBody>>> =
            Default::default();
        let state = |b: RigidBodyHandle| *states.borrow_mut().entry(b).or_insert_with(|| bodies(b));
        let island_body = |b: Option<RigidBodyHandle>| b.filter(|&b| state(b).is_some());
        for r in resting.iter_mut() {
            for (end, body) in [r.bodies.0, r.bodies.1].into_iter().enumerate() {
                r.law.bodies[end] = island_body(body).map(|b| slot((&mut index, &mut handles), b));
            }
        }
        let mut joints: Vec<(JointLaw, usize)> = Vec::new();
        let mut seen = std::collections::HashSet::new();
        let mut k = 0;
        while k < handles.len() {
            let b = handles[k];
            let mut attached: Vec<_> = world.impulse_joints.attached_enabled_joints(b).collect();
            attached.sort_by_key(|(_, _, j, _)| j.into_raw_parts());
            for (b1, b2, handle, joint) in attached {
                if !seen.insert(handle) {
                    continue;
                }
                let ends = [island_body(Some(b1)), island_body(Some(b2))]
                    .map(|e| e.map(|e| slot((&mut index, &mut handles), e)));
                let now = |b: RigidBodyHandle| BodyNow::of(world, b);
                if let Some(law) = self.joint_law(world, (b1, b2), &joint.data, ends, h, &now) {
                    joints.push((law, k));
                }
            }
            k += 1;
        }
        // Connected parts (union–find with path halving), each part's bodies and laws in order.
        let mut parent: Vec<usize> = (0..handles.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let edges =
            resting.iter().map(|r| r.law.bodies).chain(joints.iter().map(|(j, _)| j.bodies));
        for ends in edges {
            if let [Some(a), Some(b)] = ends {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        let mut island_of = vec![usize::MAX; handles.len()];
        // Each island: its bodies, its contacts (indices into `resting`), its joints.
        let mut islands: Vec<(Vec<usize>, Vec<usize>, Vec<usize>)> = Vec::new();
        for b in 0..handles.len() {
            let r = root(&mut parent, b);
            if island_of[r] == usize::MAX {
                island_of[r] = islands.len();
                islands.push((Vec::new(), Vec::new(), Vec::new()));
            }
            island_of[b] = island_of[r];
            islands[island_of[b]].0.push(b);
        }
        for (k, r) in resting.iter().enumerate() {
            if let Some(b) = r.law.bodies[0].or(r.law.bodies[1]) {
                islands[island_of[b]].1.push(k);
            }
        }
        for (k, (j, _)) in joints.iter().enumerate() {
            if let Some(b) = j.bodies[0].or(j.bodies[1]) {
                islands[island_of[b]].2.push(k);
            }
        }
        // Islands without a contact move as rapier moves them.
        islands.retain(|(_, contacts, _)| !contacts.is_empty());
        let states = states.into_inner();
        let body_of = |b: RigidBodyHandle| states[&b].expect("an island body");
        let solve_one =
            |(members, contacts, island_joints): &(Vec<usize>, Vec<usize>, Vec<usize>)| {
                let local: HashMap<usize, usize> =
                    members.iter().enumerate().map(|(i, &b)| (b, i)).collect();
                let bodies: Vec<IslandBody> =
                    members.iter().map(|&b| body_of(handles[b])).collect();
                let to_local = |ends: [Option<usize>; 2]| ends.map(|b| b.map(|b| local[&b]));
                let mut laws: Vec<Law> = contacts
                    .iter()
                    .map(|&k| {
                        let mut law = resting[k].law;
                        law.bodies = to_local(law.bodies);
                        Law::Contact(law)
                    })
                    .chain(island_joints.iter().map(|&k| {
                        let mut law = joints[k].0;
                        law.bodies = to_local(law.bodies);
                        Law::Joint(law)
                    }))
                    .collect();
                implicit::solve(&bodies, &mut laws, h, &mut None)
                    .map(|s| {
                        laws.iter()
                            .zip(s.responses)
                            .take(contacts.len())
                            .map(|(l, r)| {
                                let Law::Contact(c) = l else { unreachable!("contacts first") };
                                let end =
                                    |e: usize| c.bodies[e].map_or(c.given[e], |b| s.velocities[b]);
                                (r, (l.relative(&s.velocities), [end(0), end(1)]))
                            })
                            .collect::<Vec<_>>()
                    })
                    .map_err(|failure| (failure, contacts[0]))
            };
        #[cfg(feature = "parallel")]
        let solved: Vec<_> = {
            use rayon::prelude::*;
            islands.par_iter().map(solve_one).collect()
        };
        #[cfg(not(feature = "parallel"))]
        let solved: Vec<_> = islands.iter().map(solve_one).collect();
        let mut responses = vec![None; resting.len()];
        for ((_, contacts, _), result) in islands.iter().zip(solved) {
            match result {
                Ok(r) => {
                    for (&k, r) in contacts.iter().zip(r) {
                        responses[k] = Some(r);
                    }
                }
                Err((failure, k)) => {
                    let (a, b) = resting[k].pair;
                    let problem = match failure {
                        implicit::Failure::NotConverged { residual } => format!(
                            "the implicit step of its island did not converge (residual {residual:e})"
                        ),
                        implicit::Failure::Singular => {
                            "the implicit step of its island met a body without mass or a non-finite force law"
                                .to_string()
                        }
                    };
                    return Err(Error::StepRejected {
                        step: self.steps,
                        pair: format!("colliders {a:?} and {b:?}"),
                        problem,
                    });
                }
            }
        }
        // A contact whose bodies both move as they do (a body of a multibody on a fixed one):
        // its law at their velocities.
        let responses = responses.into_iter().zip(resting.iter()).map(|(r, rest)| {
            r.unwrap_or_else(|| {
                let relative = rest.law.relative(&[]);
                (rest.law.response(relative, h), (relative, rest.law.given))
            })
        });
        Ok((responses.collect(), islands.len()))
    }

    /// A rapier impulse joint between bodies `b1` and `b2` (island indices `ends`, `None`
    /// where the body is not in an island) as a stiff spring on its locked axes over a
    /// sub-step of `h` (see [`solve_islands`](Self::solve_islands)); `None` where it locks
    /// nothing.
    pub(super) fn joint_law(
        &self,
        world: &PhysicsWorld,
        (b1, b2): (RigidBodyHandle, RigidBodyHandle),
        data: &engine::prelude::GenericJoint,
        ends: [Option<usize>; 2],
        h: Real,
        state: &dyn Fn(RigidBodyHandle) -> BodyNow,
    ) -> Option<JointLaw> {
        use engine::prelude::JointAxesMask;
        let (s1, s2) = (state(b1), state(b2));
        let (f1, f2) = (s1.pose * pose(&data.local_frame1), s2.pose * pose(&data.local_frame2));
        let axes = [Vector::X, Vector::Y, Vector::Z].map(|a| f1.rotation * a);
        let locked = data.locked_axes;
        let pick = |flags: [JointAxesMask; 3]| {
            let mut out = [Vector::ZERO; 3];
            for k in 0..3 {
                if locked.contains(flags[k]) {
                    out[k] = axes[k];
                }
            }
            out
        };
        let linear = pick([JointAxesMask::LIN_X, JointAxesMask::LIN_Y, JointAxesMask::LIN_Z]);
        let angular = pick([JointAxesMask::ANG_X, JointAxesMask::ANG_Y, JointAxesMask::ANG_Z]);
        if linear == [Vector::ZERO; 3] && angular == [Vector::ZERO; 3] {
            return None;
        }
        // The spring: stiff against the lighter moving end over the sub-step.
        let (mut mass, mut inertia): (Real, Real) = (Real::INFINITY, Real::INFINITY);
        for (b, end) in [(b1, ends[0]), (b2, ends[1])] {
            if end.is_some() {
                let rb = &world.bodies[b];
                mass = mass.min(real(rb.mass()));
                let i = vector(rb.mass_properties().local_mprops.principal_inertia());
                inertia = inertia.min(i.min_element());
            }
        }
        if !(mass.is_finite() && mass > 0.0) {
            return None;
        }
        let inertia = if inertia.is_finite() && inertia > 0.0 { inertia } else { 0.0 };
        let scale = 1.0 / (JOINT_RESOLUTION * h * h);
        Some(JointLaw {
            bodies: ends,
            given: [s1.velocity, s2.velocity],
            levers: [f1.translation - s1.centre, f2.translation - s2.centre],
            linear,
            angular,
            offset: f1.translation - f2.translation,
            turn: (f1.rotation * f2.rotation.inverse()).to_scaled_axis(),
            stiffness: (mass * scale, inertia * scale),
        })
    }
}

/// A body as a joint's law sees it: the pose of its frame, its centre of mass and its
/// velocities, now.
#[derive(Clone, Copy)]
pub(super) struct BodyNow {
    pub(super) pose: Pose,
    pub(super) centre: Vector,
    pub(super) velocity: Motion,
}

impl BodyNow {
    /// Body `b` as the world has it.
    pub(super) fn of(world: &PhysicsWorld, b: RigidBodyHandle) -> Self {
        let rb = &world.bodies[b];
        BodyNow {
            pose: pose(rb.position()),
            centre: vector(rb.center_of_mass()),
            velocity: (vector(rb.linvel()), vector(rb.angvel())),
        }
    }
}

/// `σ` of a joint in the implicit solve: its spring is `1/σ` times as stiff as the lighter
/// end's mass (and smallest inertia) over the step squared, so that a load the step can
/// carry opens it by `σ` of what the load would move the body in a step unheld.
pub(super) const JOINT_RESOLUTION: Real = 1e-3;

/// A rapier world inverse inertia as a matrix.
fn world_inverse_inertia(j: &engine::prelude::AngularInertia) -> Matrix {
    Matrix::from_cols(
        Vector::new(real(j.m11), real(j.m12), real(j.m13)),
        Vector::new(real(j.m12), real(j.m22), real(j.m23)),
        Vector::new(real(j.m13), real(j.m23), real(j.m33)),
    )
}

/// Body `b` as an island's body over a sub-step of `h`, with the force and torque so far this
/// sub-step in `added` (explicit contacts, the film) besides gravity and the user's.
pub(super) fn island_body(
    world: &PhysicsWorld,
    b: RigidBodyHandle,
    added: &HashMap<RigidBodyHandle, (Vector, Vector)>,
    h: Real,
) -> IslandBody {
    let rb = &world.bodies[b];
    let props = rb.mass_properties();
    let inverse_inertia = world_inverse_inertia(&props.effective_world_inv_inertia);
    let inverse_mass = vector(props.effective_inv_mass);
    let (f, t) = added.get(&b).copied().unwrap_or((Vector::ZERO, Vector::ZERO));
    let free_axes = Vector::select(inverse_mass.cmpgt(Vector::ZERO), Vector::ONE, Vector::ZERO);
    let start = (vector(rb.linvel()), vector(rb.angvel()));
    let accel = vector(world.gravity) * real(rb.gravity_scale()) * free_axes
        + (vector(rb.user_force()) + f) * inverse_mass;
    let turn = inverse_inertia * (vector(rb.user_torque()) + t);
    IslandBody {
        inverse_mass,
        inverse_inertia,
        start,
        free: (start.0 + accel * h, start.1 + turn * h),
    }
}

/// Whether body `b` moves in the islands' solve and an impact's sub-steps: dynamic, and not a
/// link of a multibody (which rapier's multibody solver alone moves).
pub(super) fn moves_in_islands(world: &PhysicsWorld, b: RigidBodyHandle) -> bool {
    world.bodies.get(b).is_some_and(|rb| rb.is_dynamic())
        && world.multibody_joints.rigid_body_link(b).is_none()
}

impl Side<'_> {
    /// The direction from `other`'s centre to this collider's (m; a wall's normal, out of it,
    /// where one of them is a wall); `None` for two walls.
    fn towards(&self, other: &Side<'_>) -> Option<Vector> {
        let (here, there) = (
            self.pose.transform_point(self.handled.centre),
            other.pose.transform_point(other.handled.centre),
        );
        match (
            self.handled.wall_normal(&self.pose, there),
            other.handled.wall_normal(&other.pose, here),
        ) {
            (Some(_), Some(_)) => None,
            (Some(n), None) => Some(-n),
            (None, Some(n)) => Some(n),
            (None, None) => Some(here - there),
        }
    }

    /// How far any point of the collider may move within `h` (m): its centre's speed and its
    /// rim's, and its acceleration.
    pub(super) fn travel(&self, h: Real) -> Real {
        let k = &self.kinematics;
        let rim = if self.handled.radius.is_finite() {
            k.angvel.length() * (self.handled.radius + self.handled.centre.length())
        } else {
            0.0
        };
        h * (k.linvel.length() + rim) + h * h * self.acceleration.length()
    }
}

/// The change a response makes to a contact's tangential spring: the stretch to record for
/// the next evaluation, and whether it slides. At the end of the sub-step the spring is
/// stretched by what the law took — sticking, the stretch it carried plus the relative motion
/// at the contact over the sub-step; sliding, what the disc's force needs. The next evaluation
/// adds to the recorded stretch how far its two anchors (the contact point as a material
/// point of each body) have moved apart, which for a turning body is not quite the relative
/// motion the law took (a rolling ball's anchor lifts off along a cycloid): the recorded
/// stretch is the end stretch less the anchors' own motion over the sub-step, each body
/// moving with its end velocities `ends` as rapier moves it.
pub(super) fn spring_after(
    law: &StepLaw,
    r: &Response,
    h: Real,
    (relative, ends): (Motion, [Motion; 2]),
) -> Option<(Vector, bool)> {
    let spring = law.spring?;
    if spring.stiffness <= 0.0 {
        return None;
    }
    let n = law.normal;
    let across = |v: Vector| v - n * n.dot(v);
    let u_t = across(relative.0);
    let end = if r.sliding {
        -(r.tangential / h + u_t * spring.viscosity) / spring.stiffness
    } else {
        spring.carried + u_t * h
    };
    let travel = |e: usize| {
        let ((v, w), lever) = (ends[e], law.levers[e]);
        v * h + (crate::math::Rotation::from_scaled_axis(w * h) * lever - lever)
    };
    Some((end - across(travel(0) - travel(1)), r.sliding))
}
