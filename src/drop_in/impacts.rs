//! Impacts under [`Integration::Implicit`]: the bodies that impacts set moving are stepped on
//! their own, in sub-steps of the impacts' contact time, while the rest of the world takes the
//! user's step.
//!
//! An impact lasts a Hertz contact time (tens of microseconds for steel) and its restitution
//! needs tens of sub-steps within it; dividing the whole world's step for it would cost every
//! body and contact that many evaluations. Here a group is sub-stepped for each set of bodies
//! the impacts join, together with every free body those touch or may reach within the step (a
//! body struck while resting on others passes the blow on: held still, it would return the
//! striker's whole momentum and gain its own as well). Within the group's sub-steps every
//! contact is evaluated and applied as it is (explicit), in sub-steps that resolve each
//! impact's contact time and, bounded from above by Gershgorin's theorem, the fastest
//! vibration of all the group's contacts together; the bodies at the contacts' other ends move
//! on as they were (a fixed body stays, a body of a multibody is held). Gravity, the user's
//! force and the liquid film are held over the step. What comes out is each body's impulse
//! from its contacts and where it ends the step; the impulse joins the world's island solve as
//! a force over the step (the bodies held take theirs), and a group's body starts rapier's step
//! where, moving with its velocity at the step's end, it ends where its own sub-steps took it.
//!
//! A group that holds a body on an impulse joint is not stepped here: rapier's joint solver
//! alone knows how such a body moves while it is struck. The world's step is then taken
//! explicitly, each of its sub-steps a step of rapier's (as [`Integration::Explicit`] takes
//! every step).

use super::forces::separation;
use super::*;
use crate::implicit::IslandBody;
use crate::math::{Matrix, Rotation};

/// The turn per step beyond which rapier caps a body's angular velocity, unless the body
/// allows fast rotation (rapier 0.36's solver, `MAX_ROTATION`).
const RAPIER_MAX_ROTATION: Real = core::f64::consts::FRAC_PI_4;

/// The velocities `(linvel, angvel)` of body `b` as rapier integrates them in a step of `h`:
/// its linear speed capped at `IntegrationParameters::max_linear_velocity` (400 lengths of
/// `length_unit` per second by default), its turn at [`RAPIER_MAX_ROTATION`] per step unless
/// the body allows fast rotation. Rapier moves the body with them and keeps them after the
/// step.
fn capped(
    world: &PhysicsWorld,
    b: RigidBodyHandle,
    (linvel, angvel): (Vector, Vector),
    h: Real,
) -> (Vector, Vector) {
    let max_linear = real(world.integration_parameters.max_linear_velocity());
    let linvel = match linvel.length() {
        speed if speed > max_linear => linvel * (max_linear / speed),
        _ => linvel,
    };
    let fast = world.bodies.get(b).is_some_and(|rb| rb.is_fast_rotation_allowed());
    let max_angular = RAPIER_MAX_ROTATION / h;
    let angvel = match angvel.length() {
        rate if !fast && rate > max_angular => angvel * (max_angular / rate),
        _ => angvel,
    };
    (linvel, angvel)
}

/// The impulses (linear, angular) of the bodies a group's sub-steps held where they were.
type Held = Vec<(RigidBodyHandle, (Vector, Vector))>;

/// A body stepped in an impact's sub-steps.
#[derive(Clone, Copy)]
struct Moving {
    handle: RigidBodyHandle,
    /// Centre of mass (world), orientation, velocities.
    centre: Vector,
    rotation: Rotation,
    linvel: Vector,
    angvel: Vector,
    /// The centre of mass in the body's frame.
    local_centre: Vector,
    inverse_mass: Vector,
    /// Principal inverse inertia and its axes in the body frame; which world axes the body
    /// may turn about (rapier's locked rotations).
    principal: (Vector, Rotation),
    turns: Vector,
    /// Force and torque held over the step (gravity, the user's, the film's), and the
    /// impulses its contacts gave.
    held: (Vector, Vector),
    impulse: (Vector, Vector),
    mass: Real,
}

impl Moving {
    /// The inverse inertia tensor in the world frame at the body's orientation.
    fn inverse_inertia(&self) -> Matrix {
        let (inverse, frame) = self.principal;
        let axes = Matrix::from_quat(self.rotation * frame);
        let w = axes * Matrix::from_diagonal(inverse) * axes.transpose();
        let lock = Matrix::from_diagonal(self.turns);
        lock * w * lock
    }

    /// The pose of the body's frame.
    fn pose(&self) -> Pose {
        Pose::from_parts(self.centre - self.rotation * self.local_centre, self.rotation)
    }

    /// The body as an island's body over a sub-step of `tau`, with the explicit contacts'
    /// `load` besides the held force.
    fn island_body(&self, tau: Real, load: (Vector, Vector)) -> IslandBody {
        let inverse_inertia = self.inverse_inertia();
        let start = (self.linvel, self.angvel);
        let force = self.held.0 + load.0;
        let torque = self.held.1 + load.1;
        IslandBody {
            inverse_mass: self.inverse_mass,
            inverse_inertia,
            start,
            free: (
                start.0 + force * self.inverse_mass * tau,
                start.1 + inverse_inertia * torque * tau,
            ),
        }
    }

    /// One sub-step of `tau` ending at velocities `end`, the contacts having given `impulse`,
    /// as rapier steps a body: the motion with the new velocities.
    fn advance(&mut self, tau: Real, end: (Vector, Vector), impulse: (Vector, Vector)) {
        (self.linvel, self.angvel) = end;
        self.centre += self.linvel * tau;
        self.rotation = (Rotation::from_scaled_axis(self.angvel * tau) * self.rotation).normalize();
        self.impulse.0 += impulse.0;
        self.impulse.1 += impulse.1;
    }
}

impl DiscreteContacts {
    /// Resolves the `colliding` pairs (impacts, and pairs about to meet as impacts) over the
    /// sub-step `pass.h`, each group of bodies they join on its own — with every free body
    /// those touch, or may reach among the candidates `apart`, and all these bodies' contacts,
    /// taken out of `resting`; adds each body's impulse to `added` as a force over the
    /// sub-step, and returns where each of the groups' bodies must start rapier's step.
    /// `None`, with nothing done, where a group holds a body on an impulse joint: rapier's
    /// joint solver alone knows how such a body moves while it is struck, and the step is then
    /// taken explicitly, each of its sub-steps a step of rapier's.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn resolve_impacts(
        &mut self,
        world: &PhysicsWorld,
        colliding: &[Candidate],
        resting: &mut Vec<islands::Resting>,
        apart: &[Candidate],
        pass: Pass,
        stats: &mut StepStats,
        added: &mut HashMap<RigidBodyHandle, (Vector, Vector)>,
    ) -> Result<Option<Vec<(RigidBodyHandle, Pose)>>> {
        // The bodies the sub-steps move: dynamic ones, their impulse joints held in the
        // implicit solves as in the world's islands (a body of a multibody is held where it
        // is over them and takes its impulse with the step).
        let free = |c: ColliderHandle| {
            world.colliders[c].parent().filter(|&b| islands::moves_in_islands(world, b))
        };
        // Groups: grown from the impacts' bodies through every pair that joins a free body to
        // one of theirs, until none is left (each pair in the candidates' order, a group's
        // bodies in the order they joined).
        let all: Vec<Candidate> = colliding
            .iter()
            .copied()
            .chain(resting.iter().map(|r| (r.pair.0, r.pair.1, r.shift)))
            .chain(apart.iter().copied())
            .collect();
        let mut group_of: HashMap<RigidBodyHandle, usize> = HashMap::default();
        let mut groups: Vec<(Vec<RigidBodyHandle>, Vec<Candidate>)> = Vec::new();
        let mut taken = vec![false; all.len()];
        let mut seeded = colliding.len();
        loop {
            let mut grew = false;
            for (k, &pair) in all.iter().enumerate() {
                if taken[k] {
                    continue;
                }
                let ends: Vec<RigidBodyHandle> =
                    [free(pair.0), free(pair.1)].into_iter().flatten().collect();
                let mut joined: Vec<usize> =
                    ends.iter().filter_map(|b| group_of.get(b).copied()).collect();
                joined.sort_unstable();
                joined.dedup();
                let target = match joined.first() {
                    Some(&g) => g,
                    // The impacts seed groups; other pairs only join them.
                    None if k < seeded && !ends.is_empty() => {
                        groups.push((Vec::new(), Vec::new()));
                        groups.len() - 1
                    }
                    None => continue,
                };
                for &g in joined.iter().skip(1).rev() {
                    let (bodies, pairs) = std::mem::take(&mut groups[g]);
                    for b in &bodies {
                        group_of.insert(*b, target);
                    }
                    groups[target].0.extend(bodies);
                    groups[target].1.extend(pairs);
                }
                for b in ends {
                    if group_of.insert(b, target).is_none() {
                        groups[target].0.push(b);
                        grew = true;
                    }
                }
                groups[target].1.push(pair);
                taken[k] = true;
            }
            seeded = 0;
            if !grew {
                break;
            }
        }
        let on_joint =
            |b: &RigidBodyHandle| world.impulse_joints.attached_enabled_joints(*b).next().is_some();
        if groups.iter().any(|(bodies, _)| bodies.iter().any(on_joint)) {
            return Ok(None);
        }
        let mut k = 0;
        resting.retain(|_| {
            k += 1;
            !taken[colliding.len() + k - 1]
        });
        let mut placed = Vec::new();
        let h = pass.h;
        for (bodies, mut pairs) in groups.into_iter().filter(|(_, p)| !p.is_empty()) {
            // A group's pairs in the candidates' order, whichever way it grew.
            let order: HashMap<(ColliderHandle, ColliderHandle), usize> =
                all.iter().enumerate().map(|(k, p)| ((p.0, p.1), k)).collect();
            pairs.sort_by_key(|p| order[&(p.0, p.1)]);
            let (moving, held) = self.sub_step_group(world, &bodies, &pairs, pass, stats, added)?;
            for (b, (f, t)) in held {
                let e = added.entry(b).or_insert((Vector::ZERO, Vector::ZERO));
                e.0 += f / h;
                e.1 += t / h;
            }
            for m in moving {
                let e = added.entry(m.handle).or_insert((Vector::ZERO, Vector::ZERO));
                e.0 += m.impulse.0 / h;
                e.1 += m.impulse.1 / h;
                // Back by one step of its end velocities, as rapier will integrate them, from
                // where its sub-steps took it.
                let (linvel, angvel) = capped(world, m.handle, (m.linvel, m.angvel), h);
                let start = Moving {
                    centre: m.centre - linvel * h,
                    rotation: (Rotation::from_scaled_axis(-angvel * h) * m.rotation).normalize(),
                    ..m
                };
                placed.push((start.handle, start.pose()));
            }
        }
        Ok(Some(placed))
    }

    /// Steps one group of `bodies` and its `pairs` over `pass.h` in sub-steps of its impacts'
    /// contact times, its other contacts taken implicitly at each; returns the bodies where
    /// they end, with their impulses, and the impulses of the pairs' other dynamic bodies,
    /// held where they are.
    fn sub_step_group(
        &mut self,
        world: &PhysicsWorld,
        bodies: &[RigidBodyHandle],
        pairs: &[Candidate],
        pass: Pass,
        stats: &mut StepStats,
        added: &HashMap<RigidBodyHandle, (Vector, Vector)>,
    ) -> Result<(Vec<Moving>, Held)> {
        let gravity = vector(world.gravity);
        let mut moving: Vec<Moving> = bodies
            .iter()
            .map(|&b| {
                let rb = &world.bodies[b];
                let props = rb.mass_properties();
                let local = &props.local_mprops;
                let inverse_mass = vector(props.effective_inv_mass);
                let free =
                    Vector::select(inverse_mass.cmpgt(Vector::ZERO), Vector::ONE, Vector::ZERO);
                let j = &props.effective_world_inv_inertia;
                let turns = Vector::new(
                    (real(j.m11) > 0.0) as u8 as Real,
                    (real(j.m22) > 0.0) as u8 as Real,
                    (real(j.m33) > 0.0) as u8 as Real,
                );
                let frame = pose(&engine::math::Pose::from_parts(
                    engine::math::Vector::ZERO,
                    local.principal_inertia_local_frame,
                ))
                .rotation;
                let mass = real(rb.mass());
                let (f_added, t_added) =
                    added.get(&b).copied().unwrap_or((Vector::ZERO, Vector::ZERO));
                let weight = gravity * real(rb.gravity_scale()) * free * mass;
                Moving {
                    handle: b,
                    centre: vector(rb.center_of_mass()),
                    rotation: pose(rb.position()).rotation,
                    linvel: vector(rb.linvel()),
                    angvel: vector(rb.angvel()),
                    local_centre: vector(local.local_com),
                    inverse_mass,
                    principal: (vector(local.inv_principal_inertia), frame),
                    turns,
                    held: (
                        weight + vector(rb.user_force()) + f_added,
                        vector(rb.user_torque()) + t_added,
                    ),
                    impulse: (Vector::ZERO, Vector::ZERO),
                    mass,
                }
            })
            .collect();
        let index: HashMap<RigidBodyHandle, usize> =
            bodies.iter().enumerate().map(|(i, &b)| (b, i)).collect();
        // A collider's pose and motion at time `t` of the step: its body's in the sub-steps;
        // else as the world has it, moving on with its velocity (a body held on a joint, a
        // kinematic body), so that its motion and its pose agree.
        let motion = |moving: &[Moving], c: ColliderHandle, t: Real| -> ColliderMotion {
            let co = &world.colliders[c];
            match co.parent().and_then(|b| index.get(&b)) {
                Some(&i) => {
                    let m = &moving[i];
                    let relative = co.position_wrt_parent().map_or(Pose::IDENTITY, pose);
                    ColliderMotion {
                        pose: m.pose() * relative,
                        kinematics: BodyKinematics {
                            center_of_mass: m.centre,
                            linvel: m.linvel,
                            angvel: m.angvel,
                        },
                        body: Some(m.handle),
                        mass: m.mass,
                        acceleration: m.held.0 * m.inverse_mass,
                    }
                }
                None => {
                    let mut m = Self::kinematics(world, c);
                    let k = &mut m.kinematics;
                    if t > 0.0 && (k.linvel != Vector::ZERO || k.angvel != Vector::ZERO) {
                        let turn = Rotation::from_scaled_axis(k.angvel * t);
                        let centre = k.center_of_mass;
                        m.pose = Pose::from_parts(
                            centre + k.linvel * t + turn * (m.pose.translation - centre),
                            turn * m.pose.rotation,
                        );
                        k.center_of_mass = centre + k.linvel * t;
                    }
                    m
                }
            }
        };
        let h = pass.h;
        let mut held: Held = Vec::new();
        let mut hold = |b: RigidBodyHandle, impulse: (Vector, Vector)| {
            if world.bodies.get(b).is_some_and(|rb| rb.is_dynamic()) {
                match held.iter_mut().find(|(h, _)| *h == b) {
                    Some((_, p)) => {
                        p.0 += impulse.0;
                        p.1 += impulse.1;
                    }
                    None => held.push((b, impulse)),
                }
            }
        };
        // A fixed policy has divided the step evenly already: an impact takes each of its
        // sub-steps whole, refused where it asks for more of the step. The automatic one
        // follows the impacts from sub-step to sub-step.
        let fixed = match self.policy {
            StepPolicy::Fixed { substeps } => {
                let mut limits =
                    self.impact_limits(world, pairs, &moving, &motion, 0.0, h, false)?;
                self.group_limit(world, pairs, &moving, &index, &mut limits);
                self.divide(h * substeps.max(1) as Real, &limits)?;
                Some(1)
            }
            StepPolicy::AutoSubstep { .. } => None,
        };
        let mut t = 0.0;
        let mut slots: Vec<Option<Box<ContactState>>> = Vec::with_capacity(pairs.len());
        let mut checks: Vec<Result<Checked>> = Vec::with_capacity(pairs.len());
        while t < h {
            let left = h - t;
            let mut tau = match fixed {
                Some(n) => h / n as Real,
                None => {
                    let limits =
                        self.impact_limits(world, pairs, &moving, &motion, t, left, true)?;
                    left / (self.divide(left, &limits)? * pass.refine) as Real
                }
            };
            // The last sub-step ends the step exactly.
            if left - tau <= 1e-9 * h {
                tau = left;
            }
            slots.clear();
            slots.extend(pairs.iter().map(|&(ca, cb, _)| self.states.remove(&(ca, cb))));
            checks.clear();
            let sub_pass = Pass { h: tau, resting: false, sub_cycle: true, ..pass };
            for (&pair, slot) in pairs.iter().zip(slots.iter_mut()) {
                let motions = (motion(&moving, pair.0, t), motion(&moving, pair.1, t));
                checks.push(self.check_pair(world, pair, motions, slot, sub_pass));
            }
            // The states back into the map; the others of the world's stay where they are.
            for (&(ca, cb, _), slot) in pairs.iter().zip(slots.drain(..)) {
                if let Some(state) = slot {
                    self.states.insert((ca, cb), state);
                    self.touched.insert((ca, cb));
                }
            }
            if let Some(k) = checks.iter().position(|e| e.is_err()) {
                return Err(checks.swap_remove(k).err().expect("an error was found"));
            }
            // Every contact's force as evaluated at the sub-step's start.
            let mut loads = vec![(Vector::ZERO, Vector::ZERO); moving.len()];
            for (e, &(ca, cb, _)) in checks.iter().zip(pairs) {
                let Ok((Some(c), _, _)) = e else { continue };
                if let Some(why) = c.refresh {
                    stats.refreshes.count(why);
                }
                stats.max_indentation = stats.max_indentation.max(c.indentation);
                if self.states.contains_key(&(ca, cb)) {
                    self.elastic.insert((ca, cb), c.elastic);
                    self.note_depth((ca, cb), c.indentation);
                    self.note_reading((ca, cb), c, c.force_on_a * tau);
                }
                stats.evaluations += 1;
                for (b, f, torque) in [
                    (c.bodies.0, c.force_on_a, c.torques.0),
                    (c.bodies.1, -c.force_on_a, c.torques.1),
                ] {
                    let Some(b) = b else { continue };
                    match index.get(&b) {
                        Some(&i) => {
                            loads[i].0 += f;
                            loads[i].1 += torque;
                        }
                        None => hold(b, (f * tau, torque * tau)),
                    }
                }
            }
            let ends: Vec<(Vector, Vector)> =
                moving.iter().zip(&loads).map(|(m, load)| m.island_body(tau, *load).free).collect();
            let impulses: Vec<(Vector, Vector)> =
                loads.iter().map(|(f, torque)| (*f * tau, *torque * tau)).collect();
            for ((m, end), impulse) in moving.iter_mut().zip(ends).zip(impulses) {
                m.advance(tau, end, impulse);
            }
            self.track_impacts(&checks, pairs, tau, pass.rest_speed, true);
            stats.impact_substeps += 1;
            t = if tau == left { h } else { t + tau };
        }
        Ok((moving, held))
    }

    /// What the group's impacts ask of its next sub-step at time `t` of the step, `left` of it
    /// remaining: each impact's own limits (its Hertz contact time, its stiffness), and a pair
    /// apart the same — but, `free`, only once it may touch: until then no sub-step may carry
    /// it beyond its gap. The group's resting contacts ask nothing: they are taken implicitly.
    #[allow(clippy::too_many_arguments)]
    fn impact_limits(
        &self,
        world: &PhysicsWorld,
        pairs: &[Candidate],
        moving: &[Moving],
        motion: &dyn Fn(&[Moving], ColliderHandle, Real) -> ColliderMotion,
        t: Real,
        left: Real,
        free: bool,
    ) -> Result<substeps::Limits> {
        let mut limits = substeps::Limits::default();
        for &(ca, cb, shift) in pairs {
            let motions = (motion(moving, ca, t), motion(moving, cb, t));
            let live = self.states.contains_key(&(ca, cb));
            if live && !self.impacts.contains_key(&(ca, cb)) {
                continue;
            }
            if live {
                self.pair_limits(world, (ca, cb), &motions, false, false, &mut limits)?;
                continue;
            }
            let mut own = substeps::Limits::default();
            self.pair_limits(world, (ca, cb), &motions, false, false, &mut own)?;
            let ((a, b), (ha, hb)) = (&motions, (&self.handled[&ca], &self.handled[&cb]));
            let mut pb = b.pose;
            pb.translation += shift;
            let (sa, sb) = (self.queries[&ca].as_ref(), self.queries[&cb].as_ref());
            let gap = separation((&a.pose, sa, &ha.shape), (&pb, sb, &hb.shape)).0;
            let rim = |k: &BodyKinematics, h: &Handled| {
                let r = h.radius + h.centre.length();
                if r.is_finite() {
                    k.angvel.length() * r
                } else {
                    0.0
                }
            };
            let speed = (a.kinematics.linvel - b.kinematics.linvel).length()
                + rim(&a.kinematics, ha)
                + rim(&b.kinematics, hb)
                + left * (a.acceleration - b.acceleration).length();
            let flight = if free && gap > 0.0 && speed > 0.0 { gap / speed } else { 0.0 };
            if let Some((substep, time, pair)) = own.worst {
                limits.resolve(substep.max(flight), time, pair);
            }
            if let Some(c) = own.coarsest {
                if limits.coarsest.is_none_or(|w| c.0 < w.0) {
                    limits.coarsest = Some(c);
                }
            }
        }
        Ok(limits)
    }

    /// Adds to `limits` the half-period of the group's fastest vibration on its live contacts,
    /// bounded from above by Gershgorin's theorem on the mass-weighted stiffness: `ω² <= 2 max_b
    /// Σ_c k_c (1/m_b + r_c² j_b)`, over each body `b` of the group and its contacts `c`, with
    /// `k_c` the contact's normal and tangential stiffness, `r_c` the lever to its point and
    /// `j_b` the largest inverse inertia, and each contact's resistance to tilting against
    /// `j_b`. A body pressed by several contacts vibrates faster than under any one (a ball in
    /// a pile); the bound holds for any number of them, so the explicit sub-steps stay stable.
    fn group_limit(
        &self,
        world: &PhysicsWorld,
        pairs: &[Candidate],
        moving: &[Moving],
        index: &HashMap<RigidBodyHandle, usize>,
        limits: &mut substeps::Limits,
    ) {
        let spring = self.tangential == TangentialLaw::Spring && !self.friction.is_none();
        let mut rows = vec![0.0; moving.len()];
        let mut widest: Vec<Option<(ColliderHandle, ColliderHandle)>> = vec![None; moving.len()];
        for &(ca, cb, _) in pairs {
            let Some(s) = self.states.get(&(ca, cb)) else { continue };
            let Some(frame) = s.frame else { continue };
            let k_n = s.normal_stiffness;
            if !(k_n > 0.0 && k_n.is_finite()) {
                continue;
            }
            let (ha, hb) = (&self.handled[&ca], &self.handled[&cb]);
            let kappa = if spring { stiffness_ratio(&ha.material, &hb.material) } else { 0.0 };
            let tilt = frame.rocking.to_cols_array().iter().step_by(4).sum::<Real>().max(0.0);
            for (c, anchor) in [(ca, frame.anchors[0]), (cb, frame.anchors[1])] {
                let Some(&i) = world.colliders[c].parent().and_then(|b| index.get(&b)) else {
                    continue;
                };
                let m = &moving[i];
                let relative =
                    world.colliders[c].position_wrt_parent().map_or(Pose::IDENTITY, pose);
                let point = (m.pose() * relative).transform_point(anchor);
                let lever = (point - m.centre).length_squared();
                let j = m
                    .inverse_inertia()
                    .to_cols_array()
                    .iter()
                    .step_by(4)
                    .fold(0.0, |a: Real, x| a.max(*x));
                let w = m.inverse_mass.max_element() + lever * j;
                rows[i] += k_n * (1.0 + kappa) * w + tilt * j;
                widest[i] = widest[i].or(Some((ca, cb)));
            }
        }
        let fastest = rows.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1));
        if let Some((i, &row)) = fastest.filter(|(_, r)| **r > 0.0) {
            let half_period = core::f64::consts::PI / (2.0 * row).sqrt();
            if let Some(pair) = widest[i] {
                limits.resolve(half_period / self.per_half_period(), half_period, pair);
            }
        }
    }
}
