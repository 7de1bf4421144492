//! The step's check of itself: never an `Ok` for a world that blew up.
//!
//! The sub-step advice, the implicit laws and the impacts' own sub-steps each assume
//! something of the step — that no contact goes deeper than its bodies can hold, that no force
//! law releases more energy than its contact stored. After the step these are checked: no
//! contact deeper than the indentation limit (the same fraction of the smaller body that
//! refuses too soft an impact), no body at a non-finite place or speed, and the mechanical
//! energy of the handled bodies — kinetic, and potential in gravity — grown by no more than
//! the contacts' elastic energy at the step's start, the work the users' forces could do, and
//! a tolerance ([`ENERGY_TOLERANCE`] of the energy in play, and the energy of every body at
//! [`REST_FRACTION`] of the rest speed). A step that fails is undone — bodies, colliders and
//! the contacts' states as they were — and taken again in four times the sub-steps
//! ([`FailedStep::Redo`]), until it passes or the policy's sub-steps run out; then it is
//! refused with [`Error::StepRejected`], naming the pair and the step, the world left as it
//! was before the step.
//!
//! The energy check leaves out what does work the step cannot count: a moving kinematic body
//! touching a handled collider, a joint motor, a body on a joint, and wet runs (contacts with
//! an enlargement or a liquid film), where the fluid's forces and its virtual mass act.

use super::*;

/// Of the energy in play (the bodies' kinetic energy and the contacts' elastic energy at the
/// step's start), how much a step may create beyond the work the users' forces could do:
/// discretisation errors of explicit impacts stay far below it, a blow-up far above.
pub const ENERGY_TOLERANCE: Real = 0.25;

/// The fraction of the rest speed at which every handled body's kinetic energy is tolerated
/// too, however little energy is in play (bodies at rest jitter by less).
pub const REST_FRACTION: Real = 0.25;

/// What a step that fails its check does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum FailedStep {
    /// Undo it and take it again in four times the sub-steps, as long as the policy allows;
    /// then refuse it. The default.
    #[default]
    Redo,
    /// Undo it and refuse it at once.
    Refuse,
}

/// What a step is undone to: every dynamic and kinematic body's pose and velocities (and a
/// kinematic body's target), every handled collider's pose, and the contacts' states.
pub(super) struct Snapshot {
    bodies: Vec<BodyRecord>,
    colliders: Vec<(ColliderHandle, engine::math::Pose)>,
    states: HashMap<(ColliderHandle, ColliderHandle), Box<ContactState>>,
    gaps: HashMap<(ColliderHandle, ColliderHandle), Gap>,
    impacts: HashMap<(ColliderHandle, ColliderHandle), Real>,
    elastic: HashMap<(ColliderHandle, ColliderHandle), Real>,
}

/// A body as a snapshot keeps it: handle, pose, a position-based kinematic body's target,
/// velocities.
type BodyRecord = (
    RigidBodyHandle,
    engine::math::Pose,
    Option<engine::math::Pose>,
    engine::math::Vector,
    engine::math::Vector,
);

/// The energy account a step's check starts from.
pub(super) struct Ledger {
    /// Kinetic and gravitational energy of the handled bodies (J).
    mechanical: Real,
    /// Their kinetic energy alone (J).
    kinetic: Real,
    /// The contacts' elastic energy (J).
    elastic: Real,
    /// The floor of the tolerance: every handled body at [`REST_FRACTION`] of the rest speed.
    floor: Real,
    /// Whether the energy is checked (no moving kinematic body, no joint motor, dry).
    checked: bool,
}

impl DiscreteContacts {
    /// What the step is undone to.
    pub(super) fn snapshot(&self, world: &PhysicsWorld) -> Snapshot {
        let bodies = world
            .bodies
            .iter()
            .filter(|(_, rb)| rb.is_dynamic() || rb.is_kinematic())
            .map(|(h, rb)| {
                let target = rb.is_kinematic().then(|| *rb.next_position());
                (h, *rb.position(), target, rb.linvel(), rb.angvel())
            })
            .collect();
        let colliders = self
            .handled
            .keys()
            .filter_map(|&c| world.colliders.get(c).map(|co| (c, *co.position())))
            .collect();
        Snapshot {
            bodies,
            colliders,
            states: self.states.clone(),
            gaps: self.gaps.clone(),
            impacts: self.impacts.clone(),
            elastic: self.elastic.clone(),
        }
    }

    /// Puts the world and the contacts back as `snapshot` holds them.
    pub(super) fn restore(&mut self, world: &mut PhysicsWorld, snapshot: &Snapshot) {
        for &(h, pose, target, linvel, angvel) in &snapshot.bodies {
            if let Some(rb) = world.bodies.get_mut(h) {
                rb.set_position(pose, false);
                if let Some(target) = target {
                    rb.set_next_kinematic_position(target);
                }
                rb.set_linvel(linvel, false);
                rb.set_angvel(angvel, false);
            }
        }
        for &(c, pose) in &snapshot.colliders {
            if let Some(co) = world.colliders.get_mut(c) {
                co.set_position(pose);
            }
        }
        self.states = snapshot.states.clone();
        self.gaps = snapshot.gaps.clone();
        self.impacts = snapshot.impacts.clone();
        self.elastic = snapshot.elastic.clone();
    }

    /// The dynamic bodies of handled colliders whose energy the check counts, each once, in
    /// handle order: those on no joint (rapier's joint solver does work on a jointed body that
    /// the step cannot count).
    fn handled_bodies(&self, world: &PhysicsWorld) -> Vec<RigidBodyHandle> {
        let mut bodies: Vec<RigidBodyHandle> = self
            .handled
            .keys()
            .filter_map(|c| world.colliders.get(*c).and_then(|co| co.parent()))
            .filter(|&b| {
                world.bodies.get(b).is_some_and(|rb| rb.is_dynamic())
                    && world.impulse_joints.attached_joints(b).next().is_none()
                    && world.multibody_joints.rigid_body_link(b).is_none()
            })
            .collect();
        bodies.sort_by_key(|b| b.into_raw_parts());
        bodies.dedup();
        bodies
    }

    /// The energy account before a step of `dt`.
    pub(super) fn ledger(&self, world: &PhysicsWorld, rest_speed: Real) -> Ledger {
        let gravity = vector(world.gravity);
        let (mut mechanical, mut kinetic, mut floor) = (0.0, 0.0, 0.0);
        for b in self.handled_bodies(world) {
            let rb = &world.bodies[b];
            let (m, ke) = (real(rb.mass()), real(rb.kinetic_energy()));
            kinetic += ke;
            mechanical +=
                ke - m * real(rb.gravity_scale()) * gravity.dot(vector(rb.center_of_mass()));
            floor += 0.5 * m * (REST_FRACTION * rest_speed).powi(2);
        }
        let elastic = self.states.keys().filter_map(|k| self.elastic.get(k)).copied().sum::<Real>();
        let driven = self.handled.keys().any(|c| {
            world
                .colliders
                .get(*c)
                .and_then(|co| co.parent())
                .and_then(|b| world.bodies.get(b))
                .is_some_and(|rb| {
                    rb.is_kinematic()
                        && (rb.linvel() != engine::math::Vector::ZERO
                            || rb.angvel() != engine::math::Vector::ZERO)
                })
        }) || world.impulse_joints.iter().any(|(_, j)| !j.data.motor_axes.is_empty())
            || self.lubrication.is_some()
            || self.settings.enlargement() != [0.0, 0.0];
        Ledger { mechanical, kinetic, elastic, floor, checked: !driven }
    }

    /// What went wrong with the step just taken (of `dt`, from `before`), naming the pair
    /// where one is to blame; `None` when it holds.
    pub(super) fn verify(
        &self,
        world: &PhysicsWorld,
        before: &Ledger,
        dt: Real,
    ) -> Option<(String, String)> {
        let named = |(a, b): (ColliderHandle, ColliderHandle)| format!("colliders {a:?} and {b:?}");
        if let Some((ratio, pair, depth, limit)) = self.deepest {
            if ratio > 1.0 {
                return Some((
                    named(pair),
                    format!(
                        "an overlap of {depth:e} m, beyond the {limit:e} m its bodies can hold"
                    ),
                ));
            }
        }
        let gravity = vector(world.gravity);
        let (mut mechanical, mut work) = (0.0, 0.0);
        let mut worst: Option<(Real, RigidBodyHandle)> = None;
        for b in self.handled_bodies(world) {
            let rb = &world.bodies[b];
            let (v, w) = (vector(rb.linvel()), vector(rb.angvel()));
            if !(v.is_finite() && w.is_finite() && vector(rb.translation()).is_finite()) {
                return Some((
                    format!("body {b:?}"),
                    "a non-finite position or velocity".to_string(),
                ));
            }
            let (m, ke) = (real(rb.mass()), real(rb.kinetic_energy()));
            mechanical +=
                ke - m * real(rb.gravity_scale()) * gravity.dot(vector(rb.center_of_mass()));
            // What the user's force and torque could do over the step at the larger of the
            // speeds: the body's now, or one it could have started from.
            work += dt
                * (vector(rb.user_force()).length() * v.length()
                    + vector(rb.user_torque()).length() * w.length());
            if worst.is_none_or(|(e, _)| ke > e) {
                worst = Some((ke, b));
            }
        }
        if !before.checked {
            return None;
        }
        let created = mechanical - before.mechanical - before.elastic - work;
        let allowed = ENERGY_TOLERANCE * (before.kinetic + before.elastic) + before.floor;
        if created > allowed {
            let body = worst.map_or(String::from("the handled bodies"), |(_, b)| {
                format!("body {b:?} and its contacts")
            });
            return Some((
                body,
                format!(
                    "the step created {created:e} J of energy (allowed {allowed:e} J: kinetic {:e} J and elastic {:e} J before it)",
                    before.kinetic, before.elastic
                ),
            ));
        }
        None
    }

    /// Notes a contact's overlap `depth` (m) for the step's check, against its limit.
    pub(super) fn note_depth(&mut self, pair: (ColliderHandle, ColliderHandle), depth: Real) {
        let (Some(a), Some(b)) = (self.handled.get(&pair.0), self.handled.get(&pair.1)) else {
            return;
        };
        let limit = self.indentation_limit * a.half_size.min(b.half_size);
        let ratio = depth / limit;
        if ratio.is_finite() && self.deepest.is_none_or(|d| ratio > d.0) {
            self.deepest = Some((ratio, pair, depth, limit));
        }
    }
}
