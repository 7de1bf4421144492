//! Resting and slowly moving contacts taken implicitly ([`Integration::Implicit`]): each
//! contact's law over the sub-step from its evaluation (or, for a pair about to touch, from
//! a probe of the overlap it will make), the bodies they join grouped into islands, each
//! island's end-of-sub-step velocities solved as one convex problem (`crate::implicit`), and
//! the impulses found put on the bodies as forces over the sub-step.

use super::forces::film_contact;
use super::*;
use crate::contact::ContactOutput;
use crate::force::{elastic_force, normal_stiffness, rocking_damping_rate, volume_exponent};
use crate::implicit::{self, IslandBody, Motion, NormalLaw, Response, SpringLaw, StepLaw};
use crate::math::Matrix;
use crate::overlap::compute_overlap;

/// A contact taken implicitly on this sub-step: its law (island indices not yet set) and its
/// bodies.
pub(super) struct Resting {
    pub(super) law: StepLaw,
    pub(super) bodies: (Option<RigidBodyHandle>, Option<RigidBodyHandle>),
    /// The pair.
    pub(super) pair: (ColliderHandle, ColliderHandle),
}

/// What a sub-step's islands gave: each resting contact's response and the relative motion
/// at its contact at the end of the sub-step, in the order given.
pub(super) type Responses = Vec<(Response, Motion)>;

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
    ) -> Option<StepLaw> {
        let reach = a.travel(h) + b.travel(h);
        let c = film_contact((a.handled, &a.pose, a.shape), (b.handled, &b.pose, b.shape), reach)?;
        let gap = c.dist.max(0.0);
        let x = 0.5 * (c.point1 + c.point2);
        let smaller = a.handled.half_size.min(b.handled.half_size);
        // How fast the pair closes along `n` now and at the end of the sub-step.
        let closing = |n: Vector| {
            let now = -(a.kinematics.velocity_at(x) - b.kinematics.velocity_at(x)).dot(n);
            (now, now - h * (a.acceleration - b.acceleration).dot(n))
        };
        // Probed along parry's normal; where that finds no overlap (parry's normal of two
        // faces touching edge to edge is any of the faces'), along the line between the
        // bodies' centres (a half-space's own normal).
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
        let (g, shift) =
            [(-c.normal1).try_normalize(), a.towards(b).and_then(|t| t.try_normalize())]
                .into_iter()
                .flatten()
                .find_map(probe_along)?;
        // Its point placed as a live contact's is: through a ball's centre, in the plane of a
        // body of revolution's axis.
        let moved = Pose::from_parts(a.pose.translation + shift, a.pose.rotation);
        let g = crate::contact::placed(
            g,
            &BodyState { shape: &a.handled.shape, pose: moved, kinematics: a.kinematics },
            &BodyState { shape: &b.handled.shape, pose: b.pose, kinematics: b.kinematics },
        );
        // The pair takes part where it closes its gap within the sub-step slower than the
        // rest speed — or touches now: a pair touching may be pressed together by the bodies
        // it rests on or that rest on it, which its own motion does not show.
        let (approach, end_speed) = closing(g.normal);
        let touching = gap <= TOUCHING * smaller;
        if !(h * end_speed > gap || touching) || end_speed.max(approach) >= rest_speed {
            return None;
        }
        let f_el = elastic_force(params, &g);
        if !(f_el > 0.0) {
            return None;
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
        Some(StepLaw {
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

    /// Solves the islands the `resting` contacts join over a sub-step of `h`, with each
    /// dynamic body's force and torque so far this sub-step in `added` (explicit contacts,
    /// the film) besides gravity and the user's: each contact's response, in order.
    ///
    /// Islands are the connected parts of the graph of dynamic bodies the contacts join; a
    /// fixed or kinematic body moves as it does and joins no island. They are solved in
    /// parallel (feature `parallel`), each on its own, so the result does not depend on the
    /// thread count.
    pub(super) fn solve_islands(
        &self,
        world: &PhysicsWorld,
        resting: &mut [Resting],
        added: &HashMap<RigidBodyHandle, (Vector, Vector)>,
        h: Real,
    ) -> Result<(Responses, usize)> {
        // Island bodies: every dynamic body a contact touches, in first-seen order.
        let mut index: HashMap<RigidBodyHandle, usize> = HashMap::default();
        let mut handles: Vec<RigidBodyHandle> = Vec::new();
        let dynamic = |h: Option<RigidBodyHandle>| {
            h.filter(|h| world.bodies.get(*h).is_some_and(|rb| rb.is_dynamic()))
        };
        for r in resting.iter_mut() {
            for (end, body) in [r.bodies.0, r.bodies.1].into_iter().enumerate() {
                r.law.bodies[end] = dynamic(body).map(|h| {
                    *index.entry(h).or_insert_with(|| {
                        handles.push(h);
                        handles.len() - 1
                    })
                });
            }
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
        for r in resting.iter() {
            if let [Some(a), Some(b)] = r.law.bodies {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        let mut island_of = vec![usize::MAX; handles.len()];
        let mut islands: Vec<(Vec<usize>, Vec<usize>)> = Vec::new();
        for b in 0..handles.len() {
            let r = root(&mut parent, b);
            if island_of[r] == usize::MAX {
                island_of[r] = islands.len();
                islands.push((Vec::new(), Vec::new()));
            }
            island_of[b] = island_of[r];
            islands[island_of[b]].0.push(b);
        }
        for (k, r) in resting.iter().enumerate() {
            if let Some(b) = r.law.bodies[0].or(r.law.bodies[1]) {
                islands[island_of[b]].1.push(k);
            }
        }
        let gravity = vector(world.gravity);
        let body_of = |handle: RigidBodyHandle| -> IslandBody {
            let rb = &world.bodies[handle];
            let props = rb.mass_properties();
            let j = &props.effective_world_inv_inertia;
            let inverse_inertia = Matrix::from_cols(
                Vector::new(real(j.m11), real(j.m12), real(j.m13)),
                Vector::new(real(j.m12), real(j.m22), real(j.m23)),
                Vector::new(real(j.m13), real(j.m23), real(j.m33)),
            );
            let inverse_mass = vector(props.effective_inv_mass);
            let (f, t) = added.get(&handle).copied().unwrap_or((Vector::ZERO, Vector::ZERO));
            let free_axes =
                Vector::select(inverse_mass.cmpgt(Vector::ZERO), Vector::ONE, Vector::ZERO);
            let start = (vector(rb.linvel()), vector(rb.angvel()));
            let accel = gravity * real(rb.gravity_scale()) * free_axes
                + (vector(rb.user_force()) + f) * inverse_mass;
            let turn = inverse_inertia * (vector(rb.user_torque()) + t);
            IslandBody {
                inverse_mass,
                inverse_inertia,
                start,
                free: (start.0 + accel * h, start.1 + turn * h),
            }
        };
        let solve_one = |(members, laws): &(Vec<usize>, Vec<usize>)| {
            let local: HashMap<usize, usize> =
                members.iter().enumerate().map(|(i, &b)| (b, i)).collect();
            let bodies: Vec<IslandBody> = members.iter().map(|&b| body_of(handles[b])).collect();
            let mut island_laws: Vec<StepLaw> = laws
                .iter()
                .map(|&k| {
                    let mut law = resting[k].law;
                    law.bodies = law.bodies.map(|b| b.map(|b| local[&b]));
                    law
                })
                .collect();
            implicit::solve(&bodies, &mut island_laws, h, &mut None)
                .map(|s| {
                    let relative = island_laws.iter().map(|l| l.relative(&s.velocities));
                    s.responses.into_iter().zip(relative).collect::<Vec<_>>()
                })
                .map_err(|failure| (failure, laws[0]))
        };
        #[cfg(feature = "parallel")]
        let solved: Vec<_> = {
            use rayon::prelude::*;
            islands.par_iter().map(solve_one).collect()
        };
        #[cfg(not(feature = "parallel"))]
        let solved: Vec<_> = islands.iter().map(solve_one).collect();
        let mut responses = vec![None; resting.len()];
        for ((_, laws), result) in islands.iter().zip(solved) {
            match result {
                Ok(r) => {
                    for (&k, r) in laws.iter().zip(r) {
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
        let responses = responses.into_iter().map(|r| r.expect("every law is in an island"));
        Ok((responses.collect(), islands.len()))
    }
}

impl Side<'_> {
    /// The direction from `other`'s centre to this collider's (m; a half-space's normal, out
    /// of it); `None` for two half-spaces.
    fn towards(&self, other: &Side<'_>) -> Option<Vector> {
        let half_space = |s: &Side<'_>| match s.handled.shape {
            ConvexShape::HalfSpace { normal } => Some(s.pose.rotation * normal),
            _ => None,
        };
        match (half_space(self), half_space(other)) {
            (Some(_), Some(_)) => None,
            (Some(n), None) => Some(-n),
            (None, Some(n)) => Some(n),
            (None, None) => Some(
                self.pose.transform_point(self.handled.centre)
                    - other.pose.transform_point(other.handled.centre),
            ),
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

/// The change a response makes to a contact's tangential spring: the stretch to carry into
/// the next evaluation and whether it slides. Sticking, the stretch grows with the anchors'
/// motion, which the next evaluation adds to the carried one: it stays; sliding, it is what
/// the disc's force needs at the end of the sub-step, less that motion.
pub(super) fn spring_after(
    law: &StepLaw,
    r: &Response,
    h: Real,
    relative: Motion,
) -> Option<(Vector, bool)> {
    let spring = law.spring?;
    if spring.stiffness <= 0.0 {
        return None;
    }
    let n = law.normal;
    let u_t = relative.0 - n * n.dot(relative.0);
    if !r.sliding {
        return Some((spring.carried, false));
    }
    let end = -(r.tangential / h + u_t * spring.viscosity) / spring.stiffness;
    Some((end - u_t * h, true))
}
