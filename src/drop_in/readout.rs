//! The live contacts as the last step left them: where each touches, how deep, and the force
//! it carried — what rapier's `ContactPair` tells of its own contacts, for force chains, wall
//! loads and stress tensors.

use super::*;

/// A live contact after the last step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ContactReading {
    /// The pair's colliders, A and B.
    pub colliders: (ColliderHandle, ColliderHandle),
    /// The contact point at its last evaluation (m, world; through a periodic box's faces, by
    /// A's image of B).
    pub point: Vector,
    /// Unit normal from B to A at its last evaluation (world).
    pub normal: Vector,
    /// The overlap's volume at its last evaluation (m³).
    pub volume: Real,
    /// Indentation at the step's end (m): a resting contact's as its implicit step left it,
    /// an explicit one's at its last evaluation.
    pub indentation: Real,
    /// The contact's force on A, its mean over the last step (N, world: the impulse it gave
    /// over the step divided by the step); B feels the opposite.
    pub force_on_a: Vector,
    /// Whether its tangential spring is sliding (at the friction limit) at the step's end.
    pub sliding: bool,
    /// Whether the contact is live at the step's end; `false` for one that ended within the
    /// step (an impact shorter than the step), listed by
    /// [`contact_force_events`](DiscreteContacts::contact_force_events) only.
    pub touching: bool,
}

impl ContactReading {
    /// The normal force's magnitude on A along [`normal`](Self::normal) (N; positive pushes
    /// the bodies apart).
    pub fn normal_force(&self) -> Real {
        self.normal.dot(self.force_on_a)
    }

    /// The force on A across the normal: friction (N, world).
    pub fn tangential_force(&self) -> Vector {
        self.force_on_a - self.normal * self.normal_force()
    }
}

/// A contact's record over a step's attempt: its last evaluation and its impulse so far.
#[derive(Clone, Copy, Debug)]
pub(super) struct Reading {
    point: Vector,
    normal: Vector,
    volume: Real,
    indentation: Real,
    impulse_on_a: Vector,
}

impl DiscreteContacts {
    /// Records the evaluation `c` of the live contact `pair` and the impulse `impulse_on_a` it
    /// gives A over its (sub-)step.
    pub(super) fn note_reading(&mut self, pair: Pair, c: &Evaluated, impulse_on_a: Vector) {
        let Some((point, normal, volume)) = c.place else { return };
        let r = self.step_readings.entry(pair).or_insert(Reading {
            point,
            normal,
            volume,
            indentation: c.indentation,
            impulse_on_a: Vector::ZERO,
        });
        (r.point, r.normal, r.volume, r.indentation) = (point, normal, volume, c.indentation);
        r.impulse_on_a += impulse_on_a;
    }

    /// Adds an implicit step's impulse `impulse_on_a` to `pair`'s record, the indentation it
    /// leaves `depth`.
    pub(super) fn note_implicit(&mut self, pair: Pair, impulse_on_a: Vector, depth: Real) {
        if let Some(r) = self.step_readings.get_mut(&pair) {
            r.impulse_on_a += impulse_on_a;
            r.indentation = depth;
        }
    }

    /// Makes the attempt's records the readings of a step of `dt` that passed, in the order
    /// of their colliders' handles.
    pub(super) fn keep_readings(&mut self, dt: Real) {
        self.readings.clear();
        for (&pair, r) in &self.step_readings {
            let state = self.states.get(&pair);
            self.readings.push(ContactReading {
                colliders: pair,
                point: r.point,
                normal: r.normal,
                volume: r.volume,
                indentation: r.indentation,
                force_on_a: r.impulse_on_a / dt,
                sliding: state.is_some_and(|s| s.tangential.sliding),
                touching: state.is_some(),
            });
        }
        self.readings.sort_by_key(|r| pair_order(&r.colliders));
        self.step_readings.clear();
    }

    /// The live contacts after the last step, in the order of their colliders' handles (empty
    /// before the first step and after a restart).
    pub fn contacts(&self) -> impl Iterator<Item = &ContactReading> {
        self.readings.iter().filter(|r| r.touching)
    }

    /// The live contacts of `collider` after the last step, as A or as B.
    pub fn contacts_with(&self, collider: ColliderHandle) -> impl Iterator<Item = &ContactReading> {
        self.contacts().filter(move |r| r.colliders.0 == collider || r.colliders.1 == collider)
    }

    /// The last step's contact-force events, as rapier would report them for its own contacts:
    /// each contact of the step (live or ended within it) whose mean force over the step is
    /// larger than the contact-force threshold of one of its colliders that asks for such
    /// events (`ActiveEvents::CONTACT_FORCE_EVENTS`, `Collider::contact_force_event_threshold`);
    /// its magnitude is rapier's `total_force_magnitude`. Rapier's own handler cannot be given
    /// them (its `ContactPair` is built by rapier alone), so they are read here after the step.
    pub fn contact_force_events<'a>(
        &'a self,
        world: &'a PhysicsWorld,
    ) -> impl Iterator<Item = &'a ContactReading> {
        let threshold = move |c: ColliderHandle| {
            world
                .colliders
                .get(c)
                .filter(|co| co.active_events().contains(ActiveEvents::CONTACT_FORCE_EVENTS))
                .map_or(Real::INFINITY, |co| real(co.contact_force_event_threshold()))
        };
        self.readings.iter().filter(move |r| {
            r.force_on_a.length() > threshold(r.colliders.0).min(threshold(r.colliders.1))
        })
    }
}
