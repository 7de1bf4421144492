//! Rapier's collision events for the pairs the discrete contact handles.
//!
//! Rapier's narrow phase never sees a handled pair touch (the drop-in clears its collision
//! types for the step), so the step reports its contacts' beginnings and ends itself, with
//! rapier's semantics: `CollisionEvent::Started` when a contact begins, where either collider
//! asks for collision events (`ActiveEvents::COLLISION_EVENTS`); `Stopped` when a contact
//! whose start was reported ends, with `CollisionEventFlags::REMOVED` where a collider was
//! removed from the world. A contact that begins and ends within one step (an impact shorter
//! than rapier's step) reports both, in that order. Events go out once the step has passed its
//! check, never for an attempt that was undone; a removal is reported at the next step, the
//! first the contacts learn of it. Rapier's `ContactPair` cannot be built outside rapier, so
//! the events carry none.

use super::*;

impl DiscreteContacts {
    /// Reports the step's collision events to `events` (see the module): `touched` holds every
    /// pair with a live contact at some point of the step.
    pub(super) fn report_collisions(&mut self, world: &PhysicsWorld, events: &dyn EventHandler) {
        let mut pairs: Vec<Pair> = self
            .touched
            .iter()
            .chain(self.states.keys())
            .chain(self.reported.iter())
            .copied()
            .collect();
        pairs.sort_by_key(pair_order);
        pairs.dedup();
        let wants = |c: ColliderHandle| {
            world
                .colliders
                .get(c)
                .is_some_and(|co| co.active_events().contains(ActiveEvents::COLLISION_EVENTS))
        };
        for (a, b) in pairs {
            let live = self.states.contains_key(&(a, b));
            let begun = !self.reported.contains(&(a, b))
                && (live || self.touched.contains(&(a, b)))
                && (wants(a) || wants(b));
            if begun {
                let event = CollisionEvent::Started(a, b, CollisionEventFlags::empty());
                events.handle_collision_event(&world.bodies, &world.colliders, event, None);
            }
            if live {
                if begun {
                    self.reported.insert((a, b));
                }
            } else if begun || self.reported.remove(&(a, b)) {
                let event = CollisionEvent::Stopped(a, b, CollisionEventFlags::empty());
                events.handle_collision_event(&world.bodies, &world.colliders, event, None);
            }
        }
        self.touched.clear();
    }

    /// Reports `Stopped` with `REMOVED` for each reported contact of a collider in `gone`.
    pub(super) fn report_removed(
        &mut self,
        world: &PhysicsWorld,
        gone: &[ColliderHandle],
        events: &dyn EventHandler,
    ) {
        let mut ended: Vec<Pair> = self
            .reported
            .iter()
            .filter(|(a, b)| gone.contains(a) || gone.contains(b))
            .copied()
            .collect();
        ended.sort_by_key(pair_order);
        for (a, b) in ended {
            self.reported.remove(&(a, b));
            let event = CollisionEvent::Stopped(a, b, CollisionEventFlags::REMOVED);
            events.handle_collision_event(&world.bodies, &world.colliders, event, None);
        }
    }
}
