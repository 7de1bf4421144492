//! Each sub-step's forces: the candidate pairs evaluated (in parallel), their forces and
//! torques summed in the candidates' order and put on the bodies; periodic wrapping.

use super::*;
use crate::force::{elastic_force, volume_exponent};
use crate::lubrication::{film_radius_at, reduced_radius};

impl DiscreteContacts {
    /// Moves every dynamic body of a handled bounded collider whose centre of mass left the
    /// periodic box back by whole box lengths (its colliders with it; velocities untouched).
    pub(super) fn wrap_bodies(&self, world: &mut PhysicsWorld) {
        let Some(periodic) = self.periodic else { return };
        let mut bodies: Vec<RigidBodyHandle> = self
            .handled
            .iter()
            .filter(|(_, h)| h.radius.is_finite())
            .filter_map(|(&c, _)| world.colliders.get(c).and_then(|co| co.parent()))
            .collect();
        bodies.sort_by_key(|h| h.into_raw_parts());
        bodies.dedup();
        for h in bodies {
            let Some(rb) = world.bodies.get_mut(h) else { continue };
            let shift = periodic.wrap_shift(vector(rb.center_of_mass()));
            if !rb.is_dynamic() || shift == Vector::ZERO {
                continue;
            }
            // Rapier's coordinate plus the shift, rounded once to rapier's numbers.
            let moved_by = |x: engine::math::Vector| engine_vector(vector(x) + shift);
            let pose = *rb.position();
            rb.set_translation(moved_by(pose.translation), false);
            // Rapier moves attached colliders at its next step; the fluid coupling reads them
            // before that.
            for &c in rb.colliders() {
                if let Some(co) = world.colliders.get_mut(c) {
                    let mut p = *co.position();
                    p.translation = moved_by(p.translation);
                    co.set_position(p);
                }
            }
        }
    }

    /// Collider `c`'s pose and its body's motion (at rest, of infinite mass, for a collider
    /// without a body).
    pub(super) fn kinematics(world: &PhysicsWorld, c: ColliderHandle) -> ColliderMotion {
        let co = &world.colliders[c];
        let pose = pose(co.position());
        match co.parent().and_then(|h| world.bodies.get(h).map(|rb| (h, rb))) {
            Some((h, rb)) => {
                let k = BodyKinematics {
                    center_of_mass: vector(rb.center_of_mass()),
                    linvel: vector(rb.linvel()),
                    angvel: vector(rb.angvel()),
                };
                let (mass, acceleration) = if rb.is_dynamic() {
                    let inverse = vector(rb.mass_properties().effective_inv_mass);
                    let free =
                        Vector::select(inverse.cmpgt(Vector::ZERO), Vector::ONE, Vector::ZERO);
                    let pull = vector(world.gravity) * real(rb.gravity_scale()) * free
                        + vector(rb.user_force()) * inverse;
                    (real(rb.mass()), pull)
                } else {
                    (Real::INFINITY, Vector::ZERO)
                };
                ColliderMotion { pose, kinematics: k, body: Some(h), mass, acceleration }
            }
            None => ColliderMotion {
                pose,
                kinematics: BodyKinematics::at_rest(pose.translation),
                body: None,
                mass: Real::INFINITY,
                acceleration: Vector::ZERO,
            },
        }
    }

    /// `1/m + r²/I_min` (1/kg) of the body of collider `c`: how it yields to a tangential load
    /// at distance `r` from its centre (r infinite: a half-space, not rotated by it); zero for a
    /// body that does not move.
    pub(super) fn tangential_compliance(world: &PhysicsWorld, c: ColliderHandle, r: Real) -> Real {
        let Some(rb) = world.colliders[c].parent().and_then(|h| world.bodies.get(h)) else {
            return 0.0;
        };
        if !rb.is_dynamic() {
            return 0.0;
        }
        let props = &rb.mass_properties().local_mprops;
        let i_min = real(props.principal_inertia().min_element());
        let rotation = if r.is_finite() && i_min > 0.0 { r * r / i_min } else { 0.0 };
        1.0 / real(rb.mass()) + rotation
    }

    /// The pair's effective mass against a tangential load at the contact, `1/Σ(1/m + r²/I_min)`
    /// (kg); infinite when neither body moves, zero while a mass is not yet computed.
    pub(super) fn tangential_mass(
        world: &PhysicsWorld,
        (ca, ha): (ColliderHandle, &Handled),
        (cb, hb): (ColliderHandle, &Handled),
    ) -> Real {
        1.0 / (Self::tangential_compliance(world, ca, ha.radius)
            + Self::tangential_compliance(world, cb, hb.radius))
    }

    /// The liquid film's force on a pair whose colliders (`a`, `b`: pose, parry shape, body
    /// motion, body) are closer than the lubrication cut-off; `None` without lubrication or
    /// when they are farther apart. `nearest`: the bodies' nearest points (A's, B's) where
    /// they are apart and [`separation`] found them, so that they are not looked for twice.
    fn film(
        &self,
        ha: &Handled,
        hb: &Handled,
        a: (&Pose, &dyn parry3d_f64::shape::Shape, &BodyKinematics, Option<RigidBodyHandle>),
        b: (&Pose, &dyn parry3d_f64::shape::Shape, &BodyKinematics, Option<RigidBodyHandle>),
        nearest: Option<(Vector, Vector)>,
    ) -> Option<Film> {
        let lub = self.lubrication?;
        let c = match nearest {
            Some((x_a, x_b)) => {
                let n = (x_b - x_a).try_normalize()?;
                let dist = (x_b - x_a).length();
                if dist > lub.cutoff() {
                    return None;
                }
                parry3d_f64::query::Contact::new(x_a, x_b, n, -n, dist)
            }
            None => film_contact((ha, a.0, a.1), (hb, b.0, b.1), lub.cutoff())?,
        };
        let x = 0.5 * (c.point1 + c.point2);
        let velocity = |k: &BodyKinematics| k.linvel + k.angvel.cross(x - k.center_of_mass);
        // `normal1` points out of A, towards B: closing when A moves along it faster than B.
        let closing = (velocity(a.2) - velocity(b.2)).dot(c.normal1);
        let radii = (
            film_radius_at(&ha.shape, a.0.inverse_transform_point(c.point1)),
            film_radius_at(&hb.shape, b.0.inverse_transform_point(c.point2)),
        );
        let f = lub.normal_force(c.dist, closing, reduced_radius(radii.0, radii.1));
        let normal_on_a = -f * c.normal1;
        let (shear_on_a, shear_torque_a, shear_torque_b) =
            lub.shear_force(c.dist, x, c.normal1, radii, (a.2, b.2));
        let force_on_a = normal_on_a + shear_on_a;
        if force_on_a == Vector::ZERO && shear_torque_a == Vector::ZERO || !force_on_a.is_finite() {
            return None;
        }
        Some(Film {
            bodies: (a.3, b.3),
            force_on_a,
            torque_on_a: (x - a.2.center_of_mass).cross(normal_on_a) + shear_torque_a,
            torque_on_b: (x - b.2.center_of_mass).cross(-normal_on_a) + shear_torque_b,
        })
    }

    pub(super) fn params(&self, a: &Handled, b: &Handled) -> Result<PairParameters> {
        PairParameters::new(&a.material, &b.material, self.restitution)?
            .with_friction(self.friction)
            .with_tangential_law(self.tangential)
            .with_stiffness(self.stiffness)
    }

    /// Computes and adds the contact forces of all handled candidate pairs over a sub-step
    /// (`pass.h`); leaves in the sub-step buffers' `applied` each body's force and torque as
    /// they were before (for [`take_back`]). `first`: the step's first sub-step, which keeps
    /// the remembered gaps of this sub-step's candidates only.
    ///
    /// Pairs are evaluated in parallel (feature `parallel`) and their forces summed in the
    /// candidates' order afterwards, so the result does not depend on the thread count. Each
    /// candidate's contact state is moved out of the map (a box), updated where it is
    /// evaluated, and moved back while the contact lives; the contacts of pairs that are no
    /// longer candidates end. The lists a sub-step fills are kept between sub-steps.
    ///
    /// Under [`Integration::Implicit`] the impacts are resolved first, each group of bodies
    /// they join in sub-steps of its own (see `impacts`), and every other contact and pair
    /// about to touch goes to the islands' implicit solve (see `islands`) with every other
    /// force of the sub-step on its bodies; the impulses found are applied as forces over the
    /// sub-step, and the impacts' bodies placed where their sub-steps took them.
    pub(super) fn apply_forces(
        &mut self,
        world: &mut PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        stats: &mut StepStats,
        first: bool,
        pass: Pass,
    ) -> Result<bool> {
        let mut buffers = std::mem::take(&mut self.buffers);
        let result = self.forces_into(world, hooks, stats, first, pass, &mut buffers);
        self.buffers = buffers;
        result
    }

    /// [`apply_forces`](Self::apply_forces) with the sub-step's buffers taken out of `self`.
    fn forces_into(
        &mut self,
        world: &mut PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        stats: &mut StepStats,
        first: bool,
        pass: Pass,
        buffers: &mut SubstepBuffers,
    ) -> Result<bool> {
        let SubstepBuffers { pairs, slots, checks, added, applied } = buffers;
        let h = pass.h;
        if pass.resting {
            self.candidates_within(world, hooks, h, pairs)?;
        } else {
            self.candidate_pairs(world, hooks, pairs)?;
        }
        slots.clear();
        slots.extend(pairs.iter().map(|&(ca, cb, _)| self.states.remove(&(ca, cb))));
        {
            let this = &*self;
            let w = &*world;
            let evaluate = |(&pair, slot): (&Candidate, &mut Option<Box<ContactState>>)| {
                let motions = (Self::kinematics(w, pair.0), Self::kinematics(w, pair.1));
                this.check_pair(w, pair, motions, slot, pass)
            };
            #[cfg(feature = "parallel")]
            {
                use rayon::prelude::*;
                pairs.par_iter().zip(slots.par_iter_mut()).map(evaluate).collect_into_vec(checks);
            }
            #[cfg(not(feature = "parallel"))]
            {
                checks.clear();
                checks.extend(pairs.iter().zip(slots.iter_mut()).map(evaluate));
            }
        }
        self.put_back(pairs, slots, checks)?;

        // Each body's sum runs in the candidates' order, whichever thread evaluated them.
        added.clear();
        // The step's first sub-step keeps the gaps of its candidates only; the others update
        // them in place.
        let mut gaps = if first {
            HashMap::with_capacity_and_hasher(self.gaps.len(), Default::default())
        } else {
            std::mem::take(&mut self.gaps)
        };
        let mut resting: Vec<islands::Resting> = Vec::new();
        let mut colliding: Vec<Candidate> = Vec::new();
        let mut apart: Vec<Candidate> = Vec::new();
        for (e, &(ca, cb, shift)) in checks.iter().zip(pairs.iter()) {
            let Ok((contact, gap, film)) = e else { unreachable!("errors were returned above") };
            match gap {
                GapCheck::Kept if first => {
                    gaps.insert((ca, cb), self.gaps[&(ca, cb)]);
                }
                GapCheck::Kept => {}
                GapCheck::Found(gap) => {
                    gaps.insert((ca, cb), *gap);
                }
                GapCheck::Closed if !first => {
                    gaps.remove(&(ca, cb));
                }
                GapCheck::Closed => {}
            }
            if let Some(Film { bodies, force_on_a, torque_on_a, torque_on_b }) = film {
                add(added, *bodies, *force_on_a, (*torque_on_a, *torque_on_b));
            }
            let Some(c) = contact else {
                apart.push((ca, cb, shift));
                continue;
            };
            match &c.treatment {
                Treatment::Resting(law) => {
                    resting.push(islands::Resting {
                        law: *law,
                        bodies: c.bodies,
                        pair: (ca, cb),
                        shift,
                    });
                    if self.states.contains_key(&(ca, cb)) {
                        stats.evaluations += 1;
                    } else {
                        stats.approaching_contacts += 1;
                    }
                }
                Treatment::Explicit => {
                    stats.evaluations += 1;
                    add(added, c.bodies, c.force_on_a, c.torques);
                }
                Treatment::Impact => colliding.push((ca, cb, shift)),
            }
            if let Some(why) = c.refresh {
                stats.refreshes.count(why);
            }
            stats.max_indentation = stats.max_indentation.max(c.indentation);
            if self.states.contains_key(&(ca, cb)) && !matches!(c.treatment, Treatment::Impact) {
                self.elastic.insert((ca, cb), c.elastic);
                self.note_depth((ca, cb), c.indentation);
                let explicit = matches!(c.treatment, Treatment::Explicit);
                self.note_reading(
                    (ca, cb),
                    c,
                    if explicit { c.force_on_a * h } else { Vector::ZERO },
                );
            }
        }
        self.gaps = gaps;
        self.track_impacts(checks, pairs, h, pass.rest_speed, !pass.resting);
        // The impacts, each group of bodies on its own: their contacts' impulses over the
        // sub-step, and where the bodies end it.
        let placed = if colliding.is_empty() {
            Vec::new()
        } else {
            match self.resolve_impacts(
                world,
                &colliding,
                &mut resting,
                &apart,
                pass,
                stats,
                added,
            )? {
                Some(placed) => placed,
                // An impact struck a body on a joint: nothing applied, the step goes explicit.
                None => {
                    applied.clear();
                    return Ok(false);
                }
            }
        };
        if !resting.is_empty() {
            let bodies = |b: RigidBodyHandle| {
                islands::moves_in_islands(world, b)
                    .then(|| islands::island_body(world, b, added, h))
            };
            let (responses, islands) = self.solve_islands(world, &mut resting, &bodies, h)?;
            stats.implicit_contacts += resting.len();
            stats.islands += islands;
            for (r, (response, relative)) in resting.iter().zip(responses) {
                let [on_a, on_b] = r.law.on_bodies(&response);
                add(added, r.bodies, on_a.0 / h, (on_a.1 / h, on_b.1 / h));
                let depth = r.law.normal_law.depth - h * r.law.normal.dot(relative.0 .0);
                stats.max_indentation = stats.max_indentation.max(depth);
                self.note_depth(r.pair, depth);
                self.note_implicit(r.pair, on_a.0, depth);
                if let Some((stretch, sliding)) =
                    islands::spring_after(&r.law, &response, h, relative)
                {
                    if let Some(state) = self.states.get_mut(&r.pair) {
                        state.tangential.displacement = stretch;
                        state.tangential.sliding = sliding;
                    }
                }
            }
        }
        applied.clear();
        for (&b, &(f, t)) in added.iter() {
            if let Some(rb) = world.bodies.get_mut(b) {
                if rb.is_dynamic() {
                    applied.push((b, rb.user_force(), rb.user_torque()));
                    rb.add_force(engine_vector(f), true);
                    rb.add_torque(engine_vector(t), true);
                }
            }
        }
        // An impact's bodies start rapier's step where, moving with their end velocities
        // over the step, they end where their own sub-steps took them.
        for (b, pose) in placed {
            let rb = &mut world.bodies[b];
            rb.set_position(boundary::engine_pose(&pose), true);
            let moved = *rb.position();
            for &c in rb.colliders() {
                if let Some(co) = world.colliders.get_mut(c) {
                    if let Some(relative) = co.position_wrt_parent().copied() {
                        co.set_position(moved * relative);
                    }
                }
            }
        }
        Ok(true)
    }

    /// Moves the candidates' contact states back to the map after their checks (on an error
    /// too, as far as they were updated, and then returns the first error); the states of
    /// pairs that are no longer candidates end.
    pub(super) fn put_back(
        &mut self,
        pairs: &[Candidate],
        slots: &mut Vec<Option<Box<ContactState>>>,
        checks: &mut Vec<Result<Checked>>,
    ) -> Result<()> {
        let keep = |this: &mut Self, slots: &mut Vec<Option<Box<ContactState>>>| {
            for (&(ca, cb, _), slot) in pairs.iter().zip(slots.drain(..)) {
                if let Some(state) = slot {
                    this.states.insert((ca, cb), state);
                    this.touched.insert((ca, cb));
                }
            }
        };
        if let Some(k) = checks.iter().position(|e| e.is_err()) {
            keep(self, slots);
            return Err(checks.swap_remove(k).err().expect("an error was found"));
        }
        self.states.clear();
        keep(self, slots);
        Ok(())
    }

    /// Checks the candidate `(ca, cb, shift)`, its colliders moving as `motions` (B's not yet
    /// shifted to its image), with its contact state in `slot`: its contact evaluated, or
    /// where it is apart, its gap, its film, and — under `pass.resting` — the law of a resting
    /// contact or of a pair about to touch, or that it is an impact.
    pub(super) fn check_pair(
        &self,
        w: &PhysicsWorld,
        (ca, cb, shift): Candidate,
        (ma, mut mb): (ColliderMotion, ColliderMotion),
        slot: &mut Option<Box<ContactState>>,
        pass: Pass,
    ) -> Result<Checked> {
        let Pass { h, rest_speed, resting: implicit, .. } = pass;
        let (ha, hb) = (&self.handled[&ca], &self.handled[&cb]);
        // B's nearest image (periodic boxes); a rigid shift changes no force or torque.
        mb.pose.translation += shift;
        mb.kinematics.center_of_mass += shift;
        let (pa, ka, ba, pb, kb, bb) =
            (ma.pose, ma.kinematics, ma.body, mb.pose, mb.kinematics, mb.body);
        let (sa, sb) = (self.queries[&ca].as_ref(), self.queries[&cb].as_ref());
        let film = |pb: &Pose, kb: &BodyKinematics, nearest| {
            self.film(ha, hb, (&pa, sa, &ka, ba), (pb, sb, kb, bb), nearest)
        };
        let side = |handled, m: &ColliderMotion, shape| islands::Side {
            handled,
            pose: m.pose,
            shape,
            kinematics: m.kinematics,
            acceleration: m.acceleration,
        };
        let (a, b) = (side(ha, &ma, sa), side(hb, &mb, sb));
        // The pair's parameters: the spring's damping needs the pair's tangential mass; a
        // body whose mass rapier has not computed yet (zero before its first step) leaves
        // it unknown.
        let pair_params = || -> Result<PairParameters> {
            let m_t = Self::tangential_mass(w, (ca, ha), (cb, hb));
            if m_t > 0.0 {
                self.params(ha, hb)?.with_tangential_mass(m_t)
            } else {
                self.params(ha, hb)
            }
        };
        let untouched = |treatment| Evaluated {
            bodies: (ba, bb),
            force_on_a: Vector::ZERO,
            torques: (Vector::ZERO, Vector::ZERO),
            refresh: None,
            indentation: 0.0,
            place: None,
            treatment,
            impact: None,
            approach: 0.0,
            elastic: 0.0,
        };
        // A pair about to touch: slowly, its law over the sub-step from a probe; fast, an
        // impact.
        let approaching = |film: Option<Film>| -> Result<Checked> {
            let treatment = match self.approaching_law(&pair_params()?, &a, &b, h, rest_speed) {
                islands::Approach::Resting(law) => Some(Treatment::Resting(law)),
                // Inside an impact's sub-steps a pair about to meet fast is left to the next
                // sub-steps, which resolve its approach.
                islands::Approach::Impact if !pass.sub_cycle => Some(Treatment::Impact),
                _ => None,
            };
            Ok((treatment.map(untouched), GapCheck::Closed, film))
        };
        let live = slot.is_some();
        // An impact under way is resolved in its own sub-steps.
        let impact = live && self.impacts.contains_key(&(ca, cb));
        if implicit && impact && !pass.sub_cycle {
            return Ok((Some(untouched(Treatment::Impact)), GapCheck::Closed, None));
        }
        // The tangential spring as the evaluation will find it, for an implicit law.
        let history = slot.as_ref().map(|s| s.tangential);
        // A live contact is evaluated (it ends there when the bodies part). Other pairs: a
        // lower bound of their distance (`separation`) rules out those that do not touch for
        // a fraction of an evaluation's cost, and a pair found apart stays apart without one
        // while the bodies have moved less than its margin (and, implicit, cannot close it
        // within the sub-step).
        if !live {
            let ahead = if implicit { a.travel(h) + b.travel(h) } else { 0.0 };
            if let Some(gap) = self.gaps.get(&(ca, cb)) {
                if moved(ha, &gap.poses.0, &pa) + moved(hb, &gap.poses.1, &pb) + ahead < gap.margin
                {
                    return Ok((None, GapCheck::Kept, None));
                }
            }
            let (distance, nearest) = separation((&pa, sa, &ha.shape), (&pb, sb, &hb.shape));
            let margin = distance - self.reach();
            if margin > ahead {
                return Ok((None, GapCheck::Found(Gap { margin, poses: (pa, pb) }), None));
            }
            let eps = self.settings.enlargement();
            if distance - (eps[0] + eps[1]) > 0.0 {
                // Within the film's reach, not in contact: the film's gap is the nearest
                // points' (a half-space's contact is parry's own, exact for it).
                let bounded = ha.radius.is_finite() && hb.radius.is_finite();
                let nearest = nearest.filter(|_| bounded);
                let film = film(&pb, &kb, nearest);
                if implicit {
                    return approaching(film);
                }
                return Ok((None, GapCheck::Closed, film));
            }
        }
        let film = film(&pb, &kb, None);
        let params = pair_params()?;
        let model =
            ContactModel::new(params, self.settings).with_geometry_reuse(self.geometry_reuse)?;
        let (body_a, body_b) = (
            BodyState { shape: &ha.shape, pose: pa, kinematics: ka },
            BodyState { shape: &hb.shape, pose: pb, kinematics: kb },
        );
        // A live contact's boxed state is evaluated where it lies (a state is ~1 kB).
        let out = match slot {
            Some(boxed) => model.evaluate_live(&body_a, &body_b, boxed)?,
            None => {
                let mut state = None;
                let out = model.evaluate(&body_a, &body_b, &mut state)?;
                *slot = state.map(Box::new);
                out
            }
        };
        let Some(out) = out else {
            *slot = None;
            // Touching without an overlap (boxes stacked exactly touching, or a contact whose
            // overlap has just gone): the bodies may still meet within the sub-step.
            if implicit {
                return approaching(film);
            }
            return Ok((None, GapCheck::Closed, film));
        };
        // A pair found touching with an overlap no coordinate resolves (bodies set down
        // exactly touching, round-off putting a sliver of a node in both): no law can be
        // taken from it, and the resting law's stiffness there is nil, so the bodies would
        // meet through a whole sub-step. It is a pair about to touch.
        let resolved = PRECISION_SPACINGS
            * coordinate_spacing(out.geometry.contact_point.abs().max_element(), Real::EPSILON);
        if implicit && !live && !(out.geometry.indentation > resolved) {
            *slot = None;
            return approaching(film);
        }
        let f = out.force;
        let state = slot.as_deref().expect("a live contact has a state");
        // Under implicit integration a contact that begins at the rest speed or faster is an
        // impact for its window; every other contact outside an impact's sub-steps is resting.
        let window =
            (pass.impacts && !live && state.reference_approach_speed >= rest_speed).then(|| {
                let m_star = 1.0 / (1.0 / ma.mass + 1.0 / mb.mass);
                let r_star = 1.0 / (1.0 / ha.radius + 1.0 / hb.radius);
                let e_star = effective_modulus(&ha.material, &hb.material);
                let t_h =
                    hertz_contact_time(m_star, r_star, e_star, state.reference_approach_speed);
                IMPACT_WINDOW * t_h
            });
        let treatment = if !implicit || pass.sub_cycle && (impact || window.is_some()) {
            Treatment::Explicit
        } else if window.is_some() {
            Treatment::Impact
        } else {
            let carried = history.map_or((Vector::ZERO, false), |t| {
                (t.carried(&pa, &pb, out.geometry.normal), t.sliding)
            });
            Treatment::Resting(self.resting_law(
                &params,
                (&out, state, carried),
                (&a, &b),
                (h, rest_speed),
            ))
        };
        let g = &out.geometry;
        let q =
            0.5 * (1.0 + volume_exponent(g.volume, g.indentation, g.surface_area).clamp(1.0, 2.0));
        let evaluated = Evaluated {
            bodies: (ba, bb),
            force_on_a: f.force_on_a,
            torques: (f.torque_on_a, f.torque_on_b),
            refresh: out.refresh,
            indentation: g.indentation,
            place: Some((g.contact_point, g.normal, g.volume)),
            treatment,
            impact: window,
            approach: f.approach_speed,
            elastic: elastic_force(&params, g) * g.indentation / (q + 1.0),
        };
        Ok((Some(evaluated), GapCheck::Closed, film))
    }

    /// Keeps the impacts' record (implicit integration) after a sub-step of `h`: a contact that
    /// began as an impact is entered with its window, and — where the sub-step resolved the
    /// impacts (`resolved`; not the world's step whose impacts their own sub-steps resolve)
    /// — every impact's window shortens by `h`, and an impact leaves when its contact has
    /// ended, or its window has passed and its normal motion is slower than `rest_speed`.
    /// Pairs not checked keep their record.
    pub(super) fn track_impacts(
        &mut self,
        checks: &[Result<Checked>],
        pairs: &[Candidate],
        h: Real,
        rest_speed: Real,
        resolved: bool,
    ) {
        if self.integration != Integration::Implicit {
            self.impacts.clear();
            return;
        }
        for (e, &(ca, cb, _)) in checks.iter().zip(pairs) {
            let pair = (ca, cb);
            let live = self.states.contains_key(&pair);
            match e {
                Ok((Some(c), _, _)) if live => {
                    if matches!(c.treatment, Treatment::Resting(_)) {
                        self.impacts.remove(&pair);
                        continue;
                    }
                    let window = c.impact.or_else(|| self.impacts.get(&pair).copied());
                    let Some(window) = window else { continue };
                    if !resolved {
                        self.impacts.insert(pair, window);
                        continue;
                    }
                    let left = window - h;
                    if left > 0.0 || c.approach.abs() >= rest_speed {
                        self.impacts.insert(pair, left);
                    } else {
                        self.impacts.remove(&pair);
                    }
                }
                // Not in contact (or not checked: an error).
                _ => {
                    self.impacts.remove(&pair);
                }
            }
        }
    }
}

/// A pair's force on A (B takes minus it) and its torques on A and B, added to its bodies'.
pub(super) fn add(
    added: &mut HashMap<RigidBodyHandle, (Vector, Vector)>,
    bodies: (Option<RigidBodyHandle>, Option<RigidBodyHandle>),
    f: Vector,
    torques: (Vector, Vector),
) {
    for (b, f, t) in [(bodies.0, f, torques.0), (bodies.1, -f, torques.1)] {
        if let Some(b) = b {
            let e = added.entry(b).or_insert((Vector::ZERO, Vector::ZERO));
            e.0 += f;
            e.1 += t;
        }
    }
}

/// The film's contact between two colliders (handled, pose, parry shape) within `cutoff` of
/// each other: parry's contact, its gap brought to the nearest points where they are apart.
pub(super) fn film_contact(
    (ha, pa, sa): (&Handled, &Pose, &dyn parry3d_f64::shape::Shape),
    (hb, pb, sb): (&Handled, &Pose, &dyn parry3d_f64::shape::Shape),
    cutoff: Real,
) -> Option<parry3d_f64::query::Contact> {
    // Parry's contact of a ball with a half-space is wrong with the ball first (its gap
    // and first point), right with the half-space first: a half-space goes first.
    let half_space = |h: &Handled| matches!(h.shape, ConvexShape::HalfSpace { .. });
    let mut c = if half_space(hb) && !half_space(ha) {
        let mut c = parry3d_f64::query::contact(pb, sb, pa, sa, cutoff).ok()??;
        c.flip();
        c
    } else {
        parry3d_f64::query::contact(pa, sa, pb, sb, cutoff).ok()??
    };
    // The film's force goes as 1/h: a gap from GJK, which between millimetre bodies can be
    // tens of per cent long, is brought to the nearest points.
    if c.dist > 0.0 {
        let (x_a, x_b) = nearest_points((&ha.shape, pa), (&hb.shape, pb), (c.point1, c.point2));
        if let Some(n) = (x_b - x_a).try_normalize() {
            c.dist = (x_b - x_a).length();
            (c.point1, c.point2, c.normal1, c.normal2) = (x_a, x_b, n, -n);
        }
    }
    Some(c)
}

/// A lower bound of the distance between two convex bodies (m; 0 when they touch or overlap,
/// NaN when parry cannot tell), never above the true distance, and the bodies' nearest points
/// (A's, B's; world frame) where they are apart: each body as its parry shape at its pose and
/// as its exact distance.
///
/// Parry's GJK stops on absolute tolerances, so between millimetre bodies the distance it
/// gives can exceed the true one by tens of per cent (a pair so ruled out would start its
/// contact already overlapping). Its closest points, brought to the nearest points
/// ([`nearest_points`]), give a direction; the gap between the shapes' support points along
/// it is a lower bound of the distance at any size (within 1e-3 of it for the pairs of the
/// test below, where parry's own is up to a third long at 1 mm). Shapes without a
/// support map (a half-space) take the nearest points' distance, which for them is exact.
pub(super) fn separation(
    (pa, sa, a): (&Pose, &dyn parry3d_f64::shape::Shape, &ConvexShape),
    (pb, sb, b): (&Pose, &dyn parry3d_f64::shape::Shape, &ConvexShape),
) -> (Real, Option<(Vector, Vector)>) {
    use parry3d_f64::query::{closest_points, ClosestPoints};
    match closest_points(pa, sa, pb, sb, Real::MAX) {
        Ok(ClosestPoints::WithinMargin(p1, p2)) => {
            let (x_a, x_b) = nearest_points((a, pa), (b, pb), (p1, p2));
            let gap = x_b - x_a;
            let bound = match (sa.as_support_map(), sb.as_support_map(), gap.try_normalize()) {
                (Some(ma), Some(mb), Some(n)) => {
                    let apart = n.dot(mb.support_point(pb, -n)) - n.dot(ma.support_point(pa, n));
                    apart.clamp(0.0, gap.length())
                }
                _ => gap.length(),
            };
            (bound, Some((x_a, x_b)))
        }
        Ok(ClosestPoints::Intersecting) => (0.0, None),
        Ok(ClosestPoints::Disjoint) | Err(_) => (Real::NAN, None),
    }
}

/// Most steps [`nearest_points`] takes; each brings the gap closer to its value by the ratio
/// of the surfaces' curvatures (at once for a face, about halving it for two equal balls).
const NEAREST_STEPS: usize = 32;

/// The nearest points of two convex bodies apart (A's, then B's, world frame), each body as
/// its exact distance at its pose, found from `start`, a point of A and one of B near them
/// (parry's closest points), by alternating projections: each step takes the point onto the
/// other body's surface along that body's distance gradient. The points' distance, an upper
/// bound of the gap, falls to it; the steps stop when it no longer falls by more than
/// round-off, and never give a pair farther apart than `start`.
fn nearest_points(
    (a, pose_a): (&ConvexShape, &Pose),
    (b, pose_b): (&ConvexShape, &Pose),
    start: (Vector, Vector),
) -> (Vector, Vector) {
    let onto = |shape: &ConvexShape, pose: &Pose, y: Vector| {
        let (d, g) = shape.distance_and_gradient(pose.inverse_transform_point(y));
        y - pose.rotation * g * d
    };
    let (mut x_a, mut x_b) = start;
    let mut gap = (x_b - x_a).length();
    for _ in 0..NEAREST_STEPS {
        let next_b = onto(b, pose_b, x_a);
        let next_a = onto(a, pose_a, next_b);
        let next = (next_b - next_a).length();
        if !(next < gap) {
            break;
        }
        let converged = gap - next <= 1e-12 * next;
        (x_a, x_b, gap) = (next_a, next_b, next);
        if converged {
            break;
        }
    }
    (x_a, x_b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rotation;
    use parry3d_f64::shape::SharedShape;

    /// Random convex pairs of every handled kind with bounds, a gap apart, at sizes from 1 mm
    /// to 1 m: the bound never exceeds the distance parry measures at unit size (where its GJK
    /// converges to ~1e-4: it stops on absolute tolerances) and is within 1e-3 of it at every
    /// size, where parry's own distance at 1 mm overstates some of these gaps by up to a
    /// third. The nearest points found from parry's closest points (the film's gap) lie as
    /// close to it, above the bound.
    #[test]
    fn the_separation_never_overstates_the_gap_and_the_nearest_points_find_it() {
        let mut state = 7u64;
        let mut rnd = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as Real / (1u64 << 53) as Real * 2.0 - 1.0
        };
        let shape = |k: usize, s: Real, hull: &[Vector]| match k {
            0 => SharedShape::capsule_y(0.5 * s, 0.3 * s),
            1 => SharedShape::cylinder(0.5 * s, 0.3 * s),
            2 => SharedShape::round_cuboid(0.5 * s, 0.3 * s, 0.2 * s, 0.05 * s),
            3 => SharedShape::cone(0.5 * s, 0.4 * s),
            _ => SharedShape::convex_hull(&hull.iter().map(|p| *p * s).collect::<Vec<_>>())
                .expect("a hull of twelve points on a sphere"),
        };
        let mut overstated: Real = 0.0;
        for size in [1e-3, 1e-2, 1.0] {
            for _ in 0..300 {
                let hull: Vec<Vector> = (0..12)
                    .map(|_| Vector::new(rnd(), rnd(), rnd()).normalize_or(Vector::X) * 0.5)
                    .collect();
                let kinds = [((rnd() + 1.0) * 2.5) as usize, ((rnd() + 1.0) * 2.5) as usize];
                let turn = |r: &mut dyn FnMut() -> Real| {
                    Rotation::from_scaled_axis(Vector::new(r(), r(), r()) * 3.0)
                };
                let (ra, rb) = (turn(&mut rnd), turn(&mut rnd));
                let dir = Vector::new(rnd(), rnd(), rnd()).normalize_or(Vector::X);
                let at = dir * (1.1 + 0.5 * rnd());
                let poses =
                    |s: Real| (Pose::from_parts(Vector::ZERO, ra), Pose::from_parts(at * s, rb));
                let (pa, pb) = poses(size);
                let (a, b) = (shape(kinds[0], size, &hull), shape(kinds[1], size, &hull));
                let (ua, ub) = (shape(kinds[0], 1.0, &hull), shape(kinds[1], 1.0, &hull));
                let (upa, upb) = poses(1.0);
                let truth = parry3d_f64::query::distance(&upa, &*ua, &upb, &*ub).unwrap().distance;
                let (ca, cb) =
                    (ConvexShape::from_parry(&*a).unwrap(), ConvexShape::from_parry(&*b).unwrap());
                let bound = separation((&pa, &*a, &ca), (&pb, &*b, &cb)).0 / size;
                assert!(
                    bound <= truth * (1.0 + 1e-9) + 1e-12,
                    "{kinds:?} at {size} m: {bound} > {truth}"
                );
                assert!(bound >= truth * (1.0 - 1e-3), "{kinds:?} at {size} m: {bound} < {truth}");
                // The film's gap: parry's closest points brought to the nearest points.
                use parry3d_f64::query::{closest_points, ClosestPoints};
                if let Ok(ClosestPoints::WithinMargin(p1, p2)) =
                    closest_points(&pa, &*a, &pb, &*b, Real::MAX)
                {
                    let (x_a, x_b) = nearest_points((&ca, &pa), (&cb, &pb), (p1, p2));
                    let gap = (x_b - x_a).length() / size;
                    assert!(
                        gap >= bound * (1.0 - 1e-12) && gap <= truth * (1.0 + 1e-3),
                        "{kinds:?} at {size} m: gap {gap}, bound {bound}, parry at 1 m {truth}"
                    );
                }
                let parry = parry3d_f64::query::distance(&pa, &*a, &pb, &*b).unwrap().distance;
                overstated = overstated.max(parry / size / truth - 1.0);
            }
        }
        assert!(overstated > 0.05, "parry's distance overstated gaps by {overstated} at most");
    }
}
