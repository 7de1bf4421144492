//! How rapier is kept off the handled pairs: its broad phase does not pair two handled
//! colliders while a step runs its pipeline, and the physics hook switches its contact
//! response off for any handled pair it still meets, passing everything else to the user's
//! hooks.

use super::*;

impl DiscreteContacts {
    /// Clears the handled colliders' active collision types for the step, keeping the user's
    /// for [`interact`](Self::interact) and for [`restore_collision_types`]: rapier's broad
    /// phase then pairs no two handled colliders (a pair whose types neither collider admits is
    /// never created), where at its default length unit it pairs each centimetre body with
    /// dozens, and its narrow phase would visit every such pair at every sub-step for nothing.
    ///
    /// Rapier admits a pair when either collider's types admit it, so a handled collider's
    /// pairs with colliders that are not handled stay as they were only where each of those
    /// admits all that the handled colliders do (the default types everywhere, for one); else
    /// the types are left alone.
    ///
    /// [`restore_collision_types`]: Self::restore_collision_types
    pub(super) fn set_aside_collision_types(&mut self, world: &mut PhysicsWorld) {
        let mut handled: Vec<ColliderHandle> =
            self.handled.keys().copied().filter(|c| world.colliders.get(*c).is_some()).collect();
        handled.sort_by_key(|c| c.into_raw_parts());
        let admitted = handled.iter().fold(ActiveCollisionTypes::empty(), |all, &c| {
            all | world.colliders[c].active_collision_types()
        });
        let others_admit = world
            .colliders
            .iter()
            .filter(|(c, _)| !self.handled.contains_key(c))
            .all(|(_, co)| co.active_collision_types().contains(admitted));
        if !others_admit {
            return;
        }
        for c in handled {
            let co = &mut world.colliders[c];
            self.set_aside.insert(c, co.active_collision_types());
            co.set_active_collision_types(ActiveCollisionTypes::empty());
        }
    }

    /// Gives the handled colliders back the active collision types
    /// [`set_aside_collision_types`](Self::set_aside_collision_types) cleared.
    pub(super) fn restore_collision_types(&mut self, world: &mut PhysicsWorld) {
        let mut set_aside: Vec<_> = self.set_aside.drain().collect();
        set_aside.sort_by_key(|(c, _)| c.into_raw_parts());
        for (c, types) in set_aside {
            if let Some(co) = world.colliders.get_mut(c) {
                co.set_active_collision_types(types);
            }
        }
    }

    /// Collider `c`'s (`co`) active collision types as the user set them.
    pub(super) fn collision_types(&self, c: ColliderHandle, co: &Collider) -> ActiveCollisionTypes {
        self.set_aside.get(&c).copied().unwrap_or_else(|| co.active_collision_types())
    }
}

/// Wraps the user's hooks: handled pairs get no rapier contact response.
pub(super) struct Hooks<'a> {
    pub(super) handled: &'a HashMap<ColliderHandle, Handled>,
    pub(super) user: &'a dyn PhysicsHooks,
}

impl PhysicsHooks for Hooks<'_> {
    fn filter_contact_pair(&self, ctx: &PairFilterContext) -> Option<SolverFlags> {
        if self.handled.contains_key(&ctx.collider1) && self.handled.contains_key(&ctx.collider2) {
            None
        } else {
            self.user.filter_contact_pair(ctx)
        }
    }
    fn filter_intersection_pair(&self, ctx: &PairFilterContext) -> bool {
        self.user.filter_intersection_pair(ctx)
    }
    fn modify_solver_contacts(&self, ctx: &mut ContactModificationContext) {
        self.user.modify_solver_contacts(ctx)
    }
}
