//! The drop-in for rapier scenes (feature `rapier`, on by default, f64 rapier).
//!
//! A user keeps their [`PhysicsWorld`] — bodies, colliders, joints, gravity, their own hooks
//! and event handlers — and replaces `world.step()` by [`DiscreteContacts::step`]. For every
//! pair of *handled* colliders that rapier's broad phase reports, rapier's own contact response
//! is switched off (a physics hook returns `None`), and the discrete overlap-volume force is
//! applied instead, with contact sub-steps: each sub-step is one rapier step of `dt / n` with
//! one solver iteration, forces computed from the poses at its start (a leapfrog). Everything
//! else rapier does — joints, gravity, contacts of unhandled pairs, events — keeps working.
//!
//! **Small bodies**: rapier sizes its broad-phase margins by
//! `integration_parameters.length_unit` (1 m by default). For millimetre bodies set it to their
//! size — left at 1 m, 1934 settling 3 mm spheres were all paired with each other (1.9 million
//! pairs, seconds per step); at 3 mm the step takes a millisecond.
//!
//! ```
//! use discrete_contact::prelude::*;
//! use discrete_contact::rapier::{DiscreteContacts, StepPolicy};
//! use rapier3d_f64::prelude::*;
//! # use discrete_contact::math::Vector;
//! let mut world = PhysicsWorld::new();
//! let floor = world.insert_body(RigidBodyBuilder::fixed());
//! world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(floor));
//! let ball = world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 0.0105, 0.0)));
//! world.insert_collider(ColliderBuilder::ball(0.01).density(7800.0), Some(ball));
//! world.integration_parameters.dt = 1e-4;
//!
//! let steel = Material::new(2e11, 0.3)?;
//! let mut contacts = DiscreteContacts::new(OverlapSettings::new(6, IntegrationMode::Subcell)?, 0.9)?
//!     .with_policy(StepPolicy::AutoSubstep { max_substeps: 1000 });
//! contacts.handle_all(&mut world, steel)?;        // every convex collider
//! for _ in 0..100 {
//!     contacts.step(&mut world)?;                 // instead of world.step()
//! }
//! assert!(world.bodies[ball].translation().y > 0.009); // resting on the floor, not through it
//! # Ok::<(), discrete_contact::Error>(())
//! ```

/// The drop-in's maps, keyed by handles: a fixed-seed fast hash (see `Cargo.toml`).
type HashMap<K, V> = std::collections::HashMap<K, V, foldhash::fast::FixedState>;

use rapier3d_f64::prelude::{
    ActiveHooks, Collider, ColliderHandle, ContactModificationContext, EventHandler,
    PairFilterContext, PhysicsHooks, PhysicsWorld, RigidBodyHandle, RigidBodyType, SolverFlags,
};
use std::ops::Bound::{Excluded, Included};

use crate::contact::{BodyState, ContactModel, ContactState};
use crate::error::{check_positive, Error, Result};
use crate::force::BodyKinematics;
use crate::material::{
    effective_modulus, hertz_contact_time, Friction, Material, PairParameters, StiffnessFactor,
};
use crate::math::{Pose, Real, Vector};
use crate::neighbours::NeighbourList;
use crate::overlap::OverlapSettings;
use crate::periodic::{PeriodicBox, Sphere};
use crate::shape::{ConvexShape, Sdf};
use crate::tangential::{stiffness_ratio, TangentialLaw};

/// What to do when the user's step cannot resolve a contact.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub enum StepPolicy {
    /// Always this many sub-steps per step; refuse with [`Error::TimeStepTooLarge`] when a
    /// contact needs more.
    Fixed {
        /// Sub-steps per step (>= 1).
        substeps: usize,
    },
    /// As many sub-steps as the stiffest contact needs (by default [`SUBSTEPS_PER_CONTACT`] per
    /// Hertz contact time), up to `max_substeps`; beyond that, refuse.
    AutoSubstep {
        /// Upper bound on sub-steps per step.
        max_substeps: usize,
    },
}

/// Sub-steps a contact gets within its Hertz contact time by default: restitution within about
/// 1 % of `e`. [`DiscreteContacts::with_substeps_per_contact`] trades accuracy for speed.
pub const SUBSTEPS_PER_CONTACT: Real = 30.0;

/// The fewest sub-steps per Hertz contact time accepted: the explicit integration of the
/// stiffest contact stays stable with a margin.
pub const MIN_SUBSTEPS_PER_CONTACT: Real = 5.0;

/// The fewest sub-steps per half-period of a live contact's own oscillation (normal, or the
/// tangential spring's): `ω Δt <= π/2.5 ≈ 1.26`, a margin below the explicit integration's
/// limit `ω Δt < 2`.
pub const STABLE_SUBSTEPS_PER_HALF_PERIOD: Real = 2.5;

/// A handled collider: its SDF and material.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
struct Handled {
    shape: ConvexShape,
    material: Material,
    /// Bounding-sphere centre in the collider frame and radius (m); radius infinite for a
    /// half-space.
    centre: Vector,
    radius: Real,
    /// Smallest half-extent of the bounds (m), infinite for a half-space.
    half_size: Real,
}

/// A candidate pair and the shift that moves the second collider to its image nearest the
/// first (zero without periodic axes).
type Candidate = (ColliderHandle, ColliderHandle, Vector);

/// One evaluated contact, before its forces are summed.
struct Evaluated {
    pair: (ColliderHandle, ColliderHandle),
    bodies: (Option<RigidBodyHandle>, Option<RigidBodyHandle>),
    out: crate::contact::ContactOutput,
    state: ContactState,
}

/// A candidate pair last found apart: the exact distance's margin over the contact
/// enlargement then (m) and both colliders' poses at that time.
#[derive(Clone, Copy)]
struct Gap {
    margin: Real,
    poses: (Pose, Pose),
}

/// What a pair's check on a sub-step found: a contact, and the gap to remember when the pair
/// is apart.
type Checked = (Option<Evaluated>, Option<Gap>);

/// How far any point of collider `h` may have moved between poses `from` and `to` (m): the
/// translation plus the chord of the rotation at the farthest point, `2 r sin(θ/2) <= 2 r
/// |q_to − q_from|` (the quaternions' sign chosen nearer; no cancellation at small angles).
/// Infinite for a half-space that turned.
fn moved(h: &Handled, from: &Pose, to: &Pose) -> Real {
    let (p, q) = (from.rotation, to.rotation);
    let dq = if p.dot(q) >= 0.0 { (q - p).length() } else { (q + p).length() };
    let turn = if dq > 0.0 { 2.0 * dq * (h.centre.length() + h.radius) } else { 0.0 };
    (to.translation - from.translation).length() + turn
}

/// What a step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepStats {
    /// Sub-steps taken.
    pub substeps: usize,
    /// Contacts alive at the end of the step.
    pub contacts: usize,
    /// Largest indentation seen during the step (m).
    pub max_indentation: Real,
    /// Contact evaluations during the step (one per live contact per sub-step).
    pub evaluations: usize,
    /// Of these, the ones integrated in full (the rest updated their last full geometry, see
    /// [`DiscreteContacts::with_geometry_reuse`]).
    pub full_evaluations: usize,
    /// Times the bounding-sphere neighbour list was rebuilt during the step (usually 0: it
    /// lasts until some body may have moved half its skin, a tenth of the smallest bounding
    /// radius).
    pub neighbour_builds: usize,
}

/// Rapier keeps user forces across steps: puts back each body's force and torque as they were
/// before this crate added its own for one step (`applied` holds them, in the order they were
/// recorded; restored in reverse). Restored, not subtracted: `f + g − g` is not always `f` in
/// floating point, and the user's force must come back exactly.
pub(crate) fn take_back(world: &mut PhysicsWorld, applied: &[(RigidBodyHandle, Vector, Vector)]) {
    for &(h, f, t) in applied.iter().rev() {
        if let Some(rb) = world.bodies.get_mut(h) {
            rb.reset_forces(false);
            rb.reset_torques(false);
            rb.add_force(f, false);
            rb.add_torque(t, false);
        }
    }
}

/// The discrete contact model applied to a rapier world.
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct DiscreteContacts {
    settings: OverlapSettings,
    restitution: Real,
    friction: Friction,
    #[cfg_attr(feature = "checkpoint", serde(default = "default_tangential_law"))]
    tangential: TangentialLaw,
    stiffness: StiffnessFactor,
    geometry_reuse: Real,
    policy: StepPolicy,
    substeps_per_contact: Real,
    handled: HashMap<ColliderHandle, Handled>,
    states: HashMap<(ColliderHandle, ColliderHandle), ContactState>,
    /// Candidate pairs found apart, kept while they stay candidates: a pair that cannot have
    /// closed its gap since needs no new distance (a cache; rebuilt by the exact distance).
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    gaps: HashMap<(ColliderHandle, ColliderHandle), Gap>,
    periodic: Option<PeriodicBox>,
    indentation_limit: Real,
    /// Bumped whenever the handled set changes.
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    generation: u64,
    /// The neighbour search's memory; rebuilt from the bodies when empty (after a restart).
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    neighbours: std::sync::Mutex<Neighbours>,
}

/// The drop-in's tangential law unless set: the spring, so that a scene at rest stays at rest.
fn default_tangential_law() -> TangentialLaw {
    TangentialLaw::Spring
}

/// The handled bounded colliders in handle order (for the generation of the handled set they
/// were taken from) and their Verlet list.
#[derive(Default)]
struct Neighbours {
    generation: Option<u64>,
    bounded: Vec<ColliderHandle>,
    list: NeighbourList,
}

/// Wraps the user's hooks: handled pairs get no rapier contact response.
struct Hooks<'a> {
    handled: &'a HashMap<ColliderHandle, Handled>,
    user: &'a dyn PhysicsHooks,
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

impl DiscreteContacts {
    /// Contacts with this overlap resolution and restitution `0 < e <= 1`; frictionless, curved
    /// `k`, automatic sub-stepping up to 10 000 sub-steps per step. Friction, once set with
    /// [`with_friction`](Self::with_friction), acts through the tangential spring
    /// ([`TangentialLaw::Spring`]): what a rapier scene expects — a box stays on a ramp, a stack
    /// stands — where Nassauer & Kuna's slip-speed law lets everything at rest creep;
    /// [`with_tangential_law`](Self::with_tangential_law) switches.
    pub fn new(settings: OverlapSettings, restitution: Real) -> Result<Self> {
        crate::error::check_range(
            "restitution",
            restitution,
            (Excluded(0.0), Included(1.0)),
            "0 < e <= 1",
        )?;
        Ok(Self {
            settings,
            restitution,
            friction: Friction::NONE,
            tangential: default_tangential_law(),
            stiffness: StiffnessFactor::Curved,
            geometry_reuse: crate::contact::GEOMETRY_REUSE,
            policy: StepPolicy::AutoSubstep { max_substeps: 10_000 },
            substeps_per_contact: SUBSTEPS_PER_CONTACT,
            handled: HashMap::default(),
            states: HashMap::default(),
            gaps: HashMap::default(),
            periodic: None,
            indentation_limit: 0.5,
            generation: 0,
            neighbours: Default::default(),
        })
    }

    /// Refuse a pair (with [`Error::ContactTooSoft`]) when Hertz puts its deepest indentation
    /// beyond `fraction` of the smaller body's smallest half-extent, `0 < fraction <= 1`
    /// (default 0.5). Softened materials — seed 002 runs E = 5 kPa particles so that contacts
    /// span many fluid steps — need a larger fraction.
    pub fn with_indentation_limit(mut self, fraction: Real) -> Result<Self> {
        self.indentation_limit = crate::error::check_range(
            "indentation_limit",
            fraction,
            (Excluded(0.0), Included(1.0)),
            "0 < fraction <= 1",
        )?;
        Ok(self)
    }

    /// With periodic boundaries (see [`crate::periodic`]): contacts between handled bounded
    /// colliders are found by their bounding spheres through the periodic faces and evaluated
    /// against the nearest image; at the end of every step a dynamic body whose centre of mass
    /// left the box through a periodic face is moved back by one box length. Pairs with a
    /// half-space still come from rapier's broad phase.
    pub fn with_periodic(mut self, periodic: PeriodicBox) -> Self {
        self.periodic = periodic.is_periodic().then_some(periodic);
        self
    }

    /// The periodic box, when one is set.
    pub fn periodic(&self) -> Option<&PeriodicBox> {
        self.periodic.as_ref()
    }

    /// With friction for every handled pair.
    pub fn with_friction(mut self, friction: Friction) -> Self {
        self.friction = friction;
        self
    }

    /// With another tangential law for the friction (the default is
    /// [`TangentialLaw::Spring`]; [`TangentialLaw::SlipSpeed`] is the seeds' model).
    pub fn with_tangential_law(mut self, law: TangentialLaw) -> Self {
        self.tangential = law;
        self
    }

    /// With another stiffness factor `k`.
    pub fn with_stiffness(mut self, stiffness: StiffnessFactor) -> Self {
        self.stiffness = stiffness;
        self
    }

    /// With geometry reuse at `fraction` (default
    /// [`GEOMETRY_REUSE`](crate::contact::GEOMETRY_REUSE); 0: every sub-step evaluates every
    /// contact in full). See [`ContactModel::with_geometry_reuse`].
    pub fn with_geometry_reuse(mut self, fraction: Real) -> Result<Self> {
        self.geometry_reuse = crate::contact::check_reuse(fraction)?;
        Ok(self)
    }

    /// With another sub-stepping policy.
    pub fn with_policy(mut self, policy: StepPolicy) -> Self {
        self.policy = policy;
        self
    }

    /// With `n` sub-steps per Hertz contact time instead of [`SUBSTEPS_PER_CONTACT`] (at least
    /// [`MIN_SUBSTEPS_PER_CONTACT`]): fewer sub-steps are cheaper and less accurate (a settling
    /// pile needs far fewer than a restitution measurement).
    pub fn with_substeps_per_contact(mut self, n: Real) -> Result<Self> {
        self.substeps_per_contact = crate::error::check_range(
            "substeps_per_contact",
            n,
            MIN_SUBSTEPS_PER_CONTACT..=1e6,
            "5 <= n <= 1e6",
        )?;
        Ok(self)
    }

    /// Hands `collider` to the discrete contact (its shape must be convex) with `material`.
    pub fn handle(
        &mut self,
        world: &mut PhysicsWorld,
        collider: ColliderHandle,
        material: Material,
    ) -> Result<()> {
        let co = world.colliders.get_mut(collider).ok_or(Error::InvalidArgument {
            name: "collider",
            allowed: "a handle of a collider in this world",
        })?;
        let shape = ConvexShape::from_parry(co.shape())?;
        let (centre, radius) = shape.bounding_sphere();
        let b = shape.local_bounds();
        let half_size =
            if radius.is_finite() { (b.maxs - b.mins).min_element() * 0.5 } else { Real::INFINITY };
        co.set_active_hooks(co.active_hooks() | ActiveHooks::FILTER_CONTACT_PAIRS);
        self.handled.insert(collider, Handled { shape, material, centre, radius, half_size });
        // A gap measured for another shape or size bounds nothing now, nor does a live
        // contact's last full geometry.
        self.gaps.clear();
        for (_, state) in
            self.states.iter_mut().filter(|((a, b), _)| *a == collider || *b == collider)
        {
            state.reference = None;
        }
        self.generation += 1;
        Ok(())
    }

    /// Hands every collider with a convex shape to the discrete contact; returns how many.
    pub fn handle_all(&mut self, world: &mut PhysicsWorld, material: Material) -> Result<usize> {
        let all: Vec<ColliderHandle> = world.colliders.iter().map(|(h, _)| h).collect();
        let mut n = 0;
        for h in all {
            if ConvexShape::from_parry(world.colliders[h].shape()).is_ok() {
                self.handle(world, h, material)?;
                n += 1;
            }
        }
        Ok(n)
    }

    /// Whether the pair (in either order) is in contact now.
    pub fn contact(&self, a: ColliderHandle, b: ColliderHandle) -> Option<&ContactState> {
        self.states.get(&(a, b)).or_else(|| self.states.get(&(b, a)))
    }

    /// Number of live contacts.
    pub fn contact_count(&self) -> usize {
        self.states.len()
    }

    /// One step of `world.integration_parameters.dt`, with the world's own hooks doing nothing.
    pub fn step(&mut self, world: &mut PhysicsWorld) -> Result<StepStats> {
        self.step_with_events(world, &(), &())
    }

    /// One step with the user's hooks and event handler.
    pub fn step_with_events(
        &mut self,
        world: &mut PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        events: &dyn EventHandler,
    ) -> Result<StepStats> {
        let dt = world.integration_parameters.dt;
        check_positive("integration_parameters.dt", dt)?;
        let builds = self.neighbour_builds();
        let substeps = self.substeps(world, dt)?;
        let saved =
            (world.integration_parameters.dt, world.integration_parameters.num_solver_iterations);
        world.integration_parameters.dt = dt / substeps as Real;
        world.integration_parameters.num_solver_iterations = 1;
        let mut stats = StepStats { substeps, ..Default::default() };
        let mut result = Ok(());
        for _ in 0..substeps {
            let applied = match self.apply_forces(world, &mut stats) {
                Ok(a) => a,
                Err(e) => {
                    result = Err(e);
                    break;
                }
            };
            world.step_with_events(&Hooks { handled: &self.handled, user: hooks }, events);
            take_back(world, &applied);
        }
        world.integration_parameters.dt = saved.0;
        world.integration_parameters.num_solver_iterations = saved.1;
        result?;
        self.wrap_bodies(world);
        stats.contacts = self.states.len();
        stats.neighbour_builds = self.neighbour_builds() - builds;
        Ok(stats)
    }

    /// Moves every dynamic body of a handled bounded collider whose centre of mass left the
    /// periodic box back by whole box lengths (its colliders with it; velocities untouched).
    fn wrap_bodies(&self, world: &mut PhysicsWorld) {
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
            let shift = periodic.wrap_shift(rb.center_of_mass());
            if !rb.is_dynamic() || shift == Vector::ZERO {
                continue;
            }
            let pose = *rb.position();
            rb.set_translation(pose.translation + shift, false);
            // Rapier moves attached colliders at its next step; the fluid coupling reads them
            // before that.
            for &c in rb.colliders() {
                if let Some(co) = world.colliders.get_mut(c) {
                    let mut p = *co.position();
                    p.translation += shift;
                    co.set_position(p);
                }
            }
        }
    }

    fn kinematics(
        world: &PhysicsWorld,
        c: ColliderHandle,
    ) -> (Pose, BodyKinematics, Option<RigidBodyHandle>, Real) {
        let co = &world.colliders[c];
        let pose = *co.position();
        match co.parent().and_then(|h| world.bodies.get(h).map(|rb| (h, rb))) {
            Some((h, rb)) => {
                let k = BodyKinematics {
                    center_of_mass: rb.center_of_mass(),
                    linvel: rb.linvel(),
                    angvel: rb.angvel(),
                };
                let mass = if rb.is_dynamic() { rb.mass() } else { Real::INFINITY };
                (pose, k, Some(h), mass)
            }
            None => (pose, BodyKinematics::at_rest(pose.translation), None, Real::INFINITY),
        }
    }

    /// `1/m + r²/I_min` (1/kg) of the body of collider `c`: how it yields to a tangential load
    /// at distance `r` from its centre (r infinite: a half-space, not rotated by it); zero for a
    /// body that does not move.
    fn tangential_compliance(world: &PhysicsWorld, c: ColliderHandle, r: Real) -> Real {
        let Some(rb) = world.colliders[c].parent().and_then(|h| world.bodies.get(h)) else {
            return 0.0;
        };
        if !rb.is_dynamic() {
            return 0.0;
        }
        let props = &rb.mass_properties().local_mprops;
        let i_min = props.principal_inertia().min_element();
        let rotation = if r.is_finite() && i_min > 0.0 { r * r / i_min } else { 0.0 };
        1.0 / rb.mass() + rotation
    }

    /// The pair's effective mass against a tangential load at the contact, `1/Σ(1/m + r²/I_min)`
    /// (kg); infinite when neither body moves, zero while a mass is not yet computed.
    fn tangential_mass(
        world: &PhysicsWorld,
        (ca, ha): (ColliderHandle, &Handled),
        (cb, hb): (ColliderHandle, &Handled),
    ) -> Real {
        1.0 / (Self::tangential_compliance(world, ca, ha.radius)
            + Self::tangential_compliance(world, cb, hb.radius))
    }

    fn params(&self, a: &Handled, b: &Handled) -> Result<PairParameters> {
        PairParameters::new(&a.material, &b.material, self.restitution)?
            .with_friction(self.friction)
            .with_tangential_law(self.tangential)
            .with_stiffness(self.stiffness)
    }

    /// Computes and adds the contact forces of all handled candidate pairs; returns each body's
    /// force and torque as they were before (for [`take_back`]).
    ///
    /// Pairs are evaluated in parallel (feature `parallel`) and their forces summed in the
    /// candidates' order afterwards, so the result does not depend on the thread count.
    fn apply_forces(
        &mut self,
        world: &mut PhysicsWorld,
        stats: &mut StepStats,
    ) -> Result<Vec<(RigidBodyHandle, Vector, Vector)>> {
        let pairs = self.candidate_pairs(world)?;
        let eps = self.settings.enlargement();
        let this = &*self;
        let w = &*world;
        let evaluate = |&(ca, cb, shift): &Candidate| -> Result<Checked> {
            let (ha, hb) = (&this.handled[&ca], &this.handled[&cb]);
            let (pa, ka, ba, _) = Self::kinematics(w, ca);
            let (mut pb, mut kb, bb, _) = Self::kinematics(w, cb);
            // B's nearest image (periodic boxes); a rigid shift changes no force or torque.
            pb.translation += shift;
            kb.center_of_mass += shift;
            // A live contact is evaluated (it ends there when the bodies part). Other pairs:
            // parry's exact distance (GJK) rules out those that do not touch for a fraction of
            // an evaluation's cost, and a pair found apart stays apart without one while the
            // bodies have moved less than its margin.
            let mut state = this.states.get(&(ca, cb)).copied();
            if state.is_none() {
                if let Some(gap) = this.gaps.get(&(ca, cb)) {
                    if moved(ha, &gap.poses.0, &pa) + moved(hb, &gap.poses.1, &pb) < gap.margin {
                        return Ok((None, Some(*gap)));
                    }
                }
                let margin = parry3d_f64::query::distance(
                    &pa,
                    w.colliders[ca].shape(),
                    &pb,
                    w.colliders[cb].shape(),
                )
                .map_or(Real::NAN, |d| d.distance - (eps[0] + eps[1]));
                if margin > 0.0 {
                    return Ok((None, Some(Gap { margin, poses: (pa, pb) })));
                }
            }
            // The spring's damping needs the pair's tangential mass; a body whose mass rapier has
            // not computed yet (zero before its first step) leaves it unknown.
            let m_t = Self::tangential_mass(w, (ca, ha), (cb, hb));
            let params = if m_t > 0.0 {
                this.params(ha, hb)?.with_tangential_mass(m_t)?
            } else {
                this.params(ha, hb)?
            };
            let model = ContactModel::new(params, this.settings)
                .with_geometry_reuse(this.geometry_reuse)?;
            let out = model.evaluate(
                &BodyState { shape: &ha.shape, pose: pa, kinematics: ka },
                &BodyState { shape: &hb.shape, pose: pb, kinematics: kb },
                &mut state,
            )?;
            Ok((
                out.zip(state).map(|(out, state)| Evaluated {
                    pair: (ca, cb),
                    bodies: (ba, bb),
                    out,
                    state,
                }),
                None,
            ))
        };
        #[cfg(feature = "parallel")]
        let evaluated: Vec<Result<Checked>> = {
            use rayon::prelude::*;
            pairs.par_iter().map(evaluate).collect()
        };
        #[cfg(not(feature = "parallel"))]
        let evaluated: Vec<Result<Checked>> = pairs.iter().map(evaluate).collect();

        // Each body's sum runs in the candidates' order, whichever thread evaluated them.
        let mut alive = HashMap::with_capacity_and_hasher(self.states.len(), Default::default());
        let mut added: HashMap<RigidBodyHandle, (Vector, Vector)> = HashMap::default();
        let mut add = |h: RigidBodyHandle, f: Vector, t: Vector| {
            let e = added.entry(h).or_insert((Vector::ZERO, Vector::ZERO));
            e.0 += f;
            e.1 += t;
        };
        let mut gaps = HashMap::with_capacity_and_hasher(self.gaps.len(), Default::default());
        for (e, &(ca, cb, _)) in evaluated.into_iter().zip(&pairs) {
            let (contact, gap) = e?;
            if let Some(gap) = gap {
                gaps.insert((ca, cb), gap);
            }
            let Some(Evaluated { pair, bodies, out, state }) = contact else { continue };
            alive.insert(pair, state);
            stats.evaluations += 1;
            stats.full_evaluations += usize::from(out.full);
            stats.max_indentation = stats.max_indentation.max(out.geometry.indentation);
            let f = out.force;
            if let Some(h) = bodies.0 {
                add(h, f.force_on_a, f.torque_on_a);
            }
            if let Some(h) = bodies.1 {
                add(h, -f.force_on_a, f.torque_on_b);
            }
        }
        self.states = alive;
        self.gaps = gaps;
        let mut applied = Vec::with_capacity(added.len());
        for (h, (f, t)) in added {
            if let Some(rb) = world.bodies.get_mut(h) {
                if rb.is_dynamic() {
                    applied.push((h, rb.user_force(), rb.user_torque()));
                    rb.add_force(f, true);
                    rb.add_torque(t, true);
                }
            }
        }
        Ok(applied)
    }

    /// Handled pairs that may touch now: the bounded pairs whose bounding spheres grown by the
    /// contact margin meet (through the periodic faces, with the image shift, in a periodic
    /// box) and rapier's pairs with a half-space. Rapier's own broad phase is not asked for the
    /// bounded pairs: its margins follow `length_unit`, so a scene of centimetre bodies left at
    /// 1 m pairs each body with dozens (14 000 pairs for the 180 bodies of `drop_in`, against
    /// ~1 500 whose spheres meet).
    fn candidate_pairs(&self, world: &PhysicsWorld) -> Result<Vec<Candidate>> {
        let mut pairs: Vec<Candidate> =
            self.rapier_half_space_pairs(world).map(|(a, b)| (a, b, Vector::ZERO)).collect();
        let margin = self.margin();
        pairs.extend(self.sphere_pairs(world, |_, _| margin)?);
        Ok(pairs)
    }

    /// Whether rapier would let colliders `a` and `b` push each other: on different bodies,
    /// both enabled and solid, one of their active collision types admitting the pair of body
    /// types (a collider without a body counts as fixed), their collision and solver groups
    /// admitting each other.
    fn interact(world: &PhysicsWorld, a: ColliderHandle, b: ColliderHandle) -> bool {
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
            && (ca.active_collision_types().test(ta, tb)
                || cb.active_collision_types().test(ta, tb))
            && ca.collision_groups().test(cb.collision_groups())
            && ca.solver_groups().test(cb.solver_groups())
    }

    /// Rapier's broad-phase pairs of two handled colliders.
    fn rapier_pairs<'w>(
        &'w self,
        world: &'w PhysicsWorld,
    ) -> impl Iterator<Item = (ColliderHandle, ColliderHandle)> + 'w {
        world
            .narrow_phase
            .contact_pairs()
            .map(|p| (p.collider1, p.collider2))
            .filter(|(a, b)| self.handled.contains_key(a) && self.handled.contains_key(b))
    }

    /// Rapier's pairs of two handled colliders of which one is unbounded (a half-space): the
    /// bounded pairs come from the neighbour list.
    fn rapier_half_space_pairs<'w>(
        &'w self,
        world: &'w PhysicsWorld,
    ) -> impl Iterator<Item = (ColliderHandle, ColliderHandle)> + 'w {
        let unbounded = |c: &ColliderHandle| !self.handled[c].radius.is_finite();
        self.rapier_pairs(world)
            .filter(move |&(a, b)| (unbounded(&a) || unbounded(&b)) && Self::interact(world, a, b))
    }

    /// Half the contact enlargement of a pair: each bounding sphere grows by it.
    fn margin(&self) -> Real {
        0.5 * (self.settings.enlargement()[0] + self.settings.enlargement()[1])
    }

    /// Pairs of handled bounded colliders, at least one on a dynamic body, whose bounding
    /// spheres grown by `reach(collider, kinematics)` each meet (through the periodic faces
    /// when a box is set); in handle order. Answered from the Verlet list (see `neighbours`).
    fn sphere_pairs(
        &self,
        world: &PhysicsWorld,
        reach: impl Fn(&Handled, &BodyKinematics) -> Real,
    ) -> Result<Vec<Candidate>> {
        let mut guard = self.neighbours.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let n = &mut *guard;
        if n.generation != Some(self.generation) {
            n.bounded = self
                .handled
                .iter()
                .filter(|(_, h)| h.radius.is_finite())
                .map(|(&c, _)| c)
                .collect();
            n.bounded.sort_by_key(|c| c.into_raw_parts());
            n.list = NeighbourList::default();
            n.generation = Some(self.generation);
        }
        let count = n.bounded.len();
        let (mut spheres, mut reaches, mut mobile) =
            (Vec::with_capacity(count), Vec::with_capacity(count), Vec::with_capacity(count));
        for c in &n.bounded {
            let h = &self.handled[c];
            let (pose, k, _, mass) = Self::kinematics(world, *c);
            spheres.push(Sphere { centre: pose.transform_point(h.centre), radius: h.radius });
            reaches.push(reach(h, &k));
            mobile.push(mass.is_finite());
        }
        let found = n.list.query(&spheres, &reaches, self.periodic.as_ref())?;
        Ok(found
            .into_iter()
            .filter(|&(i, j, _)| {
                (mobile[i] || mobile[j]) && Self::interact(world, n.bounded[i], n.bounded[j])
            })
            .map(|(i, j, shift)| (n.bounded[i], n.bounded[j], shift))
            .collect())
    }

    /// How many times the neighbour list has been built.
    fn neighbour_builds(&self) -> usize {
        self.neighbours.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).list.builds()
    }

    /// Handled pairs that may touch during the next `dt`: the candidates, plus pairs whose
    /// bounding spheres (or sphere and half-space) can meet at their current speeds — rapier
    /// only knows a pair after a step has run its broad phase, too late for a fast stiff impact.
    fn lookahead_pairs(
        &self,
        world: &PhysicsWorld,
        dt: Real,
    ) -> Result<Vec<(ColliderHandle, ColliderHandle)>> {
        let speed = |h: &Handled, k: &BodyKinematics| {
            k.linvel.length()
                + if h.radius.is_finite() { k.angvel.length() * h.radius } else { 0.0 }
        };
        let margin = self.margin();
        // Spheres grown by the margin and the distance they travel: the periodic candidates
        // and more.
        let reached = self.sphere_pairs(world, |h, k| margin + speed(h, k) * dt)?;
        // Rapier's pairs with a half-space, then the list's.
        let mut pairs: Vec<(ColliderHandle, ColliderHandle)> =
            self.rapier_half_space_pairs(world).collect();
        let known: std::collections::HashSet<
            (ColliderHandle, ColliderHandle),
            foldhash::fast::FixedState,
        > = pairs.iter().flat_map(|&(a, b)| [(a, b), (b, a)]).collect();
        pairs.extend(reached.into_iter().map(|(a, b, _)| (a, b)));
        // Half-spaces against bounded bodies: few half-spaces, so a plain loop.
        let mut planes: Vec<ColliderHandle> =
            self.handled.iter().filter(|(_, h)| !h.radius.is_finite()).map(|(&c, _)| c).collect();
        planes.sort_by_key(|c| c.into_raw_parts());
        for &p in &planes {
            let (pose, kp, _, _) = Self::kinematics(world, p);
            let ConvexShape::HalfSpace { normal } = self.handled[&p].shape else { continue };
            let (n, on_plane) = (pose.rotation * normal, pose.translation);
            for (&c, h) in self.handled.iter().filter(|(_, h)| h.radius.is_finite()) {
                let (pose_c, kc, _, _) = Self::kinematics(world, c);
                let gap = n.dot(pose_c.transform_point(h.centre) - on_plane) - h.radius;
                if gap <= (speed(h, &kc) + speed(&self.handled[&p], &kp)) * dt
                    && !known.contains(&(p, c))
                    && Self::interact(world, p, c)
                {
                    pairs.push((p, c));
                }
            }
        }
        Ok(pairs)
    }

    /// Sub-steps this step needs: the Hertz contact time
    /// `t_H = 2.87 (m*² / (R* E*² v0))^(1/5)` of every handled candidate pair, at its current
    /// approach speed, must span [`SUBSTEPS_PER_CONTACT`] sub-steps (or the number set with
    /// [`with_substeps_per_contact`](Self::with_substeps_per_contact)). A pair whose Hertz
    /// indentation `(15 m* v0² / (16 E* √R*))^(2/5)` exceeds a fraction (by default half, see
    /// [`with_indentation_limit`](Self::with_indentation_limit)) of the smaller body's smallest
    /// half-extent is refused
    /// with [`Error::ContactTooSoft`].
    ///
    /// With friction through the tangential spring, its oscillation counts too: stiffness
    /// `κ k_n` against the tangential effective mass `m_t` (`1/m_t = Σ 1/m + r²/I_min` over the
    /// bodies, `r` the bounding radius; `2/7 m*` for two spheres), so its contact time is
    /// `t_H √(m_t / (κ m*))`, about half of `t_H`. A live contact also counts with its own
    /// stiffness `k_n = dF_n/dd` from its last evaluation (a face resting on a face is far
    /// stiffer than the Hertz sphere of the bounding radii): half-periods `π √(m*/k_n)` and,
    /// with the spring, `π √(m_t/(κ k_n))`. These need stability and a steady hold, not a
    /// restitution's accuracy: each gets [`MIN_SUBSTEPS_PER_CONTACT`] sub-steps at the default
    /// [`SUBSTEPS_PER_CONTACT`], fewer in proportion when fewer sub-steps per contact are set,
    /// never fewer than [`STABLE_SUBSTEPS_PER_HALF_PERIOD`].
    pub fn substeps(&self, world: &PhysicsWorld, dt: Real) -> Result<usize> {
        // (largest sub-step, the contact time that sets it, the pair)
        let mut worst: Option<(Real, Real, String)> = None;
        let spring = self.tangential == TangentialLaw::Spring && !self.friction.is_none();
        let per_half_period = (MIN_SUBSTEPS_PER_CONTACT * self.substeps_per_contact
            / SUBSTEPS_PER_CONTACT)
            .max(STABLE_SUBSTEPS_PER_HALF_PERIOD);
        for (ca, cb) in self.lookahead_pairs(world, dt)? {
            let (ha, hb) = (&self.handled[&ca], &self.handled[&cb]);
            let (pa, ka, _, ma) = Self::kinematics(world, ca);
            let (pb, kb, _, mb) = Self::kinematics(world, cb);
            let m_star = 1.0 / (1.0 / ma + 1.0 / mb);
            // Two immovable bodies, or a mass rapier has not computed yet (before its first step).
            if !(m_star.is_finite() && m_star > 0.0) {
                continue;
            }
            let r_star = 1.0 / (1.0 / ha.radius + 1.0 / hb.radius);
            let e_star = effective_modulus(&ha.material, &hb.material);
            // Relative speed bound: centre speeds plus rim speeds of the bounded bodies.
            let rim = |k: &BodyKinematics, r: Real| {
                if r.is_finite() {
                    k.angvel.length() * r
                } else {
                    0.0
                }
            };
            let rims = rim(&ka, ha.radius) + rim(&kb, hb.radius);
            let v0 = ((ka.linvel - kb.linvel).length() + rims).max(1e-3);
            let t_h = hertz_contact_time(m_star, r_star, e_star, v0);
            // Hertz's deepest indentation, from the speed along the line from A to B (a body
            // sliding past another does not indent it); beyond the limit the bodies pass through.
            let towards_b = match (&ha.shape, &hb.shape) {
                (ConvexShape::HalfSpace { normal }, _) => pa.rotation * *normal,
                (_, ConvexShape::HalfSpace { normal }) => -(pb.rotation * *normal),
                _ => {
                    let (a, b) = (pa.transform_point(ha.centre), pb.transform_point(hb.centre));
                    let image = self.periodic.map_or(Vector::ZERO, |p| p.nearest_image_shift(a, b));
                    (b + image - a).normalize_or_zero()
                }
            };
            let v_normal = if towards_b == Vector::ZERO {
                v0
            } else {
                ((ka.linvel - kb.linvel).dot(towards_b).max(0.0) + rims).max(1e-3)
            };
            let depth =
                (15.0 * m_star * v_normal * v_normal / (16.0 * e_star * r_star.sqrt())).powf(0.4);
            let limit = self.indentation_limit * ha.half_size.min(hb.half_size);
            if depth > limit {
                return Err(Error::ContactTooSoft {
                    pair: format!("colliders {ca:?} and {cb:?}"),
                    speed: v_normal,
                    indentation: depth,
                    limit,
                });
            }
            let mut limit = (t_h / self.substeps_per_contact, t_h);
            let mut resolve = |t: Real| {
                if t.is_finite() && t > 0.0 && t / per_half_period < limit.0 {
                    limit = (t / per_half_period, t);
                }
            };
            // The spring's stiffness ratio and tangential mass.
            let tangential = spring.then(|| {
                (
                    stiffness_ratio(&ha.material, &hb.material),
                    Self::tangential_mass(world, (ca, ha), (cb, hb)),
                )
            });
            if let Some((kappa, m_t)) = tangential {
                resolve(t_h * (m_t / (kappa * m_star)).sqrt());
            }
            // A live contact may be far stiffer than Hertz's sphere of the bounding radii (a face
            // on a face): its own stiffness's half-periods, normal and tangential, count too.
            if let Some(k_n) = self.contact(ca, cb).map(|s| s.normal_stiffness).filter(|k| *k > 0.0)
            {
                resolve(core::f64::consts::PI * (m_star / k_n).sqrt());
                if let Some((kappa, m_t)) = tangential {
                    resolve(core::f64::consts::PI * (m_t / (kappa * k_n)).sqrt());
                }
            }
            if worst.as_ref().is_none_or(|w| limit.0 < w.0) {
                worst = Some((limit.0, limit.1, format!("colliders {ca:?} and {cb:?}")));
            }
        }
        let Some((recommended, contact_time, pair)) = worst else {
            return Ok(match self.policy {
                StepPolicy::Fixed { substeps } => substeps.max(1),
                StepPolicy::AutoSubstep { .. } => 1,
            });
        };
        let needed = (dt / recommended).ceil().max(1.0) as usize;
        let (allowed, chosen) = match self.policy {
            StepPolicy::Fixed { substeps } => (substeps.max(1), substeps.max(1)),
            StepPolicy::AutoSubstep { max_substeps } => (max_substeps.max(1), needed),
        };
        if needed > allowed {
            return Err(Error::TimeStepTooLarge {
                dt,
                recommended,
                contact_time,
                substeps_needed: needed,
                pair,
            });
        }
        Ok(chosen.max(needed))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rotation;

    /// The motion bound that lets a pair found apart skip its distance holds every point of the
    /// body, for small turns (where a bound from the angle's cosine would round to zero) and
    /// large ones (the quaternion's sign flipped), and is zero for a body that did not move.
    #[test]
    fn the_motion_bound_holds_every_point_of_the_body() {
        let shape = ConvexShape::cuboid(Vector::new(0.03, 0.01, 0.02)).unwrap();
        let (centre, radius) = shape.bounding_sphere();
        let h = Handled {
            shape,
            material: Material::new(1e7, 0.3).unwrap(),
            centre,
            radius,
            half_size: 0.01,
        };
        let from = Pose::from_parts(
            Vector::new(0.1, -0.2, 0.3),
            Rotation::from_axis_angle(Vector::new(1.0, 2.0, 2.0).normalize(), 0.7),
        );
        assert_eq!(moved(&h, &from, &from), 0.0);
        let mut tightest: Real = 0.0;
        for (k, angle) in [1e-9, 1e-4, 0.3, 3.0, 6.2].into_iter().enumerate() {
            let axis = Vector::new(1.0, -(k as Real), 0.5).normalize();
            let to = Pose::from_parts(
                from.translation + Vector::new(1e-3, 0.0, -2e-3) * k as Real,
                Rotation::from_axis_angle(axis, angle) * from.rotation,
            );
            let (to_neg, bound) =
                (Pose::from_parts(to.translation, -to.rotation), moved(&h, &from, &to));
            assert_eq!(moved(&h, &from, &to_neg), bound, "the quaternion's sign must not matter");
            // The corners of the box are its farthest points.
            for c in 0..8 {
                let x = Vector::new(
                    if c & 1 == 0 { -0.03 } else { 0.03 },
                    if c & 2 == 0 { -0.01 } else { 0.01 },
                    if c & 4 == 0 { -0.02 } else { 0.02 },
                );
                let moved_by = (to.transform_point(x) - from.transform_point(x)).length();
                assert!(
                    moved_by <= bound * (1.0 + 1e-12),
                    "angle {angle}: corner moved {moved_by:e} > bound {bound:e}"
                );
                tightest = tightest.max(moved_by / bound);
            }
        }
        // Not vacuous: the corners come within a factor of three of the bound.
        assert!(tightest > 0.3, "bound loose by {tightest}");
    }
}
