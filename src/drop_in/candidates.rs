//! The handled pairs that may touch: bounded pairs from the drop-in's own bounding-sphere
//! neighbour list (through periodic faces), half-space pairs from each half-space's plane, and
//! the look-ahead pairs the sub-step count considers; rapier's pair rules applied to each, the
//! user's `filter_contact_pair` hook among them.

use super::*;

impl DiscreteContacts {
    /// Handled pairs that may touch now: the pairs with a half-space and the bounded pairs
    /// whose bounding spheres grown by the contact margin meet (through the periodic faces,
    /// with the image shift, in a periodic box). Rapier's own broad phase is not asked: its
    /// margins follow `length_unit`, so a scene of centimetre bodies left at 1 m pairs each
    /// body with dozens (14 000 pairs for the 180 bodies of `drop_in`, against ~1 500 whose
    /// spheres meet), and a step keeps it from pairing handled colliders at all (see
    /// `set_aside_collision_types`).
    pub(super) fn candidate_pairs(
        &self,
        world: &PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        out: &mut Vec<Candidate>,
    ) -> Result<()> {
        out.clear();
        self.half_space_pairs(world, hooks, &mut |a, b| out.push((a, b, Vector::ZERO)));
        let margin = self.margin();
        self.sphere_pairs(world, hooks, |_, _| margin, &mut |a, b, shift| out.push((a, b, shift)))
    }

    /// [`candidate_pairs`](Self::candidate_pairs) for a sub-step of `h` taken implicitly: each
    /// bounding sphere also grown by how far its body may move within the sub-step (its speed
    /// and its acceleration), so that a pair about to touch is found before it does.
    pub(super) fn candidates_within(
        &self,
        world: &PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        h: Real,
        out: &mut Vec<Candidate>,
    ) -> Result<()> {
        out.clear();
        self.half_space_pairs(world, hooks, &mut |a, b| out.push((a, b, Vector::ZERO)));
        let margin = self.margin();
        let gravity = vector(world.gravity).length();
        let reach = |handled: &Handled, k: &BodyKinematics| {
            let rim = k.angvel.length() * (handled.radius + handled.centre.length());
            margin + h * (k.linvel.length() + rim) + h * h * gravity
        };
        self.sphere_pairs(world, hooks, reach, &mut |a, b, shift| out.push((a, b, shift)))
    }

    /// Whether rapier would let colliders `a` and `b` push each other: on different bodies,
    /// both enabled and solid, one of their active collision types admitting the pair of body
    /// types (a collider without a body counts as fixed), their collision and solver groups
    /// admitting each other, no joint between their bodies with contacts disabled (nor a
    /// multibody without self-contacts), and — where the user had asked for the
    /// `filter_contact_pair` hook on either collider when it was handed over — the user's
    /// `hooks` returning solver flags that compute impulses.
    pub(super) fn interact(
        &self,
        world: &PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        a: ColliderHandle,
        b: ColliderHandle,
    ) -> bool {
        let (ca, cb) = (&world.colliders[a], &world.colliders[b]);
        let body_type = |co: &Collider| {
            co.parent()
                .and_then(|h| world.bodies.get(h))
                .map_or(RigidBodyType::Fixed, |rb| rb.body_type())
        };
        let (ta, tb) = (body_type(ca), body_type(cb));
        (ca.parent().is_none() || ca.parent() != cb.parent())
            && ca.is_enabled()
            && cb.is_enabled()
            && !ca.is_sensor()
            && !cb.is_sensor()
            && (self.collision_types(a, ca).test(ta, tb)
                || self.collision_types(b, cb).test(ta, tb))
            && ca.collision_groups().test(cb.collision_groups())
            && ca.solver_groups().test(cb.solver_groups())
            && Self::joints_allow(world, ca.parent(), cb.parent())
            && (!(self.handled[&a].user_filter || self.handled[&b].user_filter)
                || hooks
                    .filter_contact_pair(&PairFilterContext {
                        bodies: &world.bodies,
                        colliders: &world.colliders,
                        collider1: a,
                        collider2: b,
                        rigid_body1: ca.parent(),
                        rigid_body2: cb.parent(),
                    })
                    .is_some_and(|flags| flags.contains(SolverFlags::COMPUTE_RIGID_IMPULSES)))
    }

    /// Whether the joints between bodies `a` and `b` allow contacts between them, by rapier's
    /// rules: no impulse joint between them with contacts disabled; in one multibody, its
    /// self-contacts enabled and the joint between them (if any) with contacts enabled.
    fn joints_allow(
        world: &PhysicsWorld,
        a: Option<RigidBodyHandle>,
        b: Option<RigidBodyHandle>,
    ) -> bool {
        let (Some(a), Some(b)) = (a, b) else { return true };
        if world.impulse_joints.joints_between(a, b).any(|(_, j)| !j.data.contacts_enabled) {
            return false;
        }
        let mb = &world.multibody_joints;
        match (mb.rigid_body_link(a), mb.rigid_body_link(b)) {
            (Some(la), Some(lb)) if la.multibody == lb.multibody => {
                mb.get_multibody(la.multibody).is_none_or(|m| m.self_contacts_enabled())
                    && mb
                        .joint_between(a, b)
                        .is_none_or(|(_, _, link)| link.joint.data.contacts_enabled)
            }
            _ => true,
        }
    }

    /// The candidate search's memory, its lists of handled colliders in handle order brought
    /// up to the handled set.
    fn search(&self) -> std::sync::MutexGuard<'_, Neighbours> {
        let mut guard = self.neighbours.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let n = &mut *guard;
        if n.generation != Some(self.generation) {
            n.all = self.handled.keys().copied().collect();
            n.all.sort_by_key(|c| c.into_raw_parts());
            let bounded = |c: &ColliderHandle| self.handled[c].radius.is_finite();
            n.bounded = n.all.iter().copied().filter(bounded).collect();
            n.half_spaces = n.all.iter().copied().filter(|c| !bounded(c)).collect();
            n.list.restart();
            n.generation = Some(self.generation);
        }
        guard
    }

    /// Calls `pair` with each pair of two handled colliders of which one is unbounded (a
    /// half-space), the lower handle first, in the half-spaces' handle order and then the other
    /// collider's: every such pair that rapier's rules admit, as rapier's broad phase pairs a
    /// half-space (its box is unbounded) with every collider — a few per body, whose gap the
    /// candidates' check answers from its cache while the body stays far.
    pub(super) fn half_space_pairs(
        &self,
        world: &PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        pair: &mut dyn FnMut(ColliderHandle, ColliderHandle),
    ) {
        let n = self.search();
        let key = |c: &ColliderHandle| c.into_raw_parts();
        for p in &n.half_spaces {
            for c in &n.all {
                // Two half-spaces once, from the first of them.
                let once = self.handled[c].radius.is_finite() || key(p) < key(c);
                let (a, b) = if key(p) < key(c) { (*p, *c) } else { (*c, *p) };
                if c != p && once && self.interact(world, hooks, a, b) {
                    pair(a, b);
                }
            }
        }
    }

    /// Half the reach of a pair — the contact enlargement, or the lubrication cut-off if that
    /// is larger: each bounding sphere grows by it.
    pub(super) fn margin(&self) -> Real {
        0.5 * self.reach()
    }

    /// The gap (m) below which a pair acts: the contact enlargement, or the lubrication
    /// cut-off if that is larger.
    pub(super) fn reach(&self) -> Real {
        let contact = self.settings.enlargement()[0] + self.settings.enlargement()[1];
        self.lubrication.map_or(contact, |l| contact.max(l.cutoff()))
    }

    /// Calls `pair` with each pair of handled bounded colliders, at least one on a dynamic
    /// body, whose bounding spheres grown by `reach(collider, kinematics)` each meet (through
    /// the periodic faces when a box is set, with the image shift); in handle order. Answered
    /// from the Verlet list (see `neighbours`).
    pub(super) fn sphere_pairs(
        &self,
        world: &PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        reach: impl Fn(&Handled, &BodyKinematics) -> Real,
        pair: &mut dyn FnMut(ColliderHandle, ColliderHandle, Vector),
    ) -> Result<()> {
        let mut guard = self.search();
        let Neighbours { bounded, list, spheres, reaches, mobile, found, .. } = &mut *guard;
        spheres.clear();
        reaches.clear();
        mobile.clear();
        for c in bounded.iter() {
            let h = &self.handled[c];
            let ColliderMotion { pose, kinematics: k, mass, .. } = Self::kinematics(world, *c);
            spheres.push(Sphere { centre: pose.transform_point(h.centre), radius: h.radius });
            reaches.push(reach(h, &k));
            mobile.push(mass.is_finite());
        }
        list.query(spheres, reaches, self.periodic.as_ref(), found)?;
        for &(i, j, shift) in found.iter() {
            if (mobile[i] || mobile[j]) && self.interact(world, hooks, bounded[i], bounded[j]) {
                pair(bounded[i], bounded[j], shift);
            }
        }
        Ok(())
    }

    /// How many times the neighbour list has been built.
    pub(super) fn neighbour_builds(&self) -> usize {
        self.neighbours.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).list.builds()
    }

    /// Handled pairs that may touch during the next `dt`: the pairs with a half-space, and
    /// those whose bounding spheres, grown by the contact margin, can meet at their current
    /// speeds — the candidates and the pairs a fast stiff impact will make before the step
    /// ends.
    pub(super) fn lookahead_pairs(
        &self,
        world: &PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        dt: Real,
    ) -> Result<Vec<(ColliderHandle, ColliderHandle)>> {
        let speed = |h: &Handled, k: &BodyKinematics| {
            k.linvel.length()
                + if h.radius.is_finite() { k.angvel.length() * h.radius } else { 0.0 }
        };
        let margin = self.margin();
        // Spheres grown by the margin and the distance they travel: the periodic candidates
        // and more.
        let reach = |h: &Handled, k: &BodyKinematics| margin + speed(h, k) * dt;
        let mut pairs = Vec::new();
        self.half_space_pairs(world, hooks, &mut |a, b| pairs.push((a, b)));
        self.sphere_pairs(world, hooks, reach, &mut |a, b, _| pairs.push((a, b)))?;
        Ok(pairs)
    }
}
