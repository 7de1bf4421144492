//! The drop-in, written once for both rapier builds: its parent module (`rapier` for f64,
//! `rapier_f32` for f32) names the rapier crate as `engine` and gives the conversions between
//! rapier's numbers and the contact model's f64 in `boundary`.

mod candidates;
mod events;
mod forces;
mod hooks;
mod impacts;
mod islands;
mod neighbours;
mod network;
mod paraview;
mod readout;
mod substeps;
mod verify;

use hooks::Hooks;

use super::boundary::{engine_real, engine_vector, pose, real, vector};
use super::{boundary, engine};
use engine::prelude::{
    ActiveCollisionTypes, ActiveEvents, ActiveHooks, Collider, ColliderHandle, CollisionEvent,
    CollisionEventFlags, ContactModificationContext, EventHandler, PairFilterContext, PhysicsHooks,
    PhysicsWorld, RigidBodyHandle, RigidBodySet, RigidBodyType, SolverFlags,
};
use std::ops::Bound::{Excluded, Included};

use crate::contact::{BodyState, ContactModel, ContactState};
use crate::error::{check_positive, Error, Result};
use crate::force::BodyKinematics;
use crate::lubrication::Lubrication;
use crate::material::{
    effective_modulus, hertz_contact_time, hertz_max_indentation, Friction, Material,
    PairParameters, StiffnessFactor,
};
use crate::math::{Pose, Real, Vector};
use crate::overlap::OverlapSettings;
use crate::periodic::{PeriodicBox, Sphere};
use crate::shape::{ConvexShape, MeshSdf, Sdf};
use crate::substep::coordinate_spacing;
pub use crate::substep::{
    Integration, StepPolicy, StepStats, AT_REST_SPEED, IMPACT_WINDOW, MIN_SUBSTEPS_PER_CONTACT,
    PRECISION_SPACINGS, REST_STEPS, STABLE_SUBSTEPS_PER_HALF_PERIOD, SUBSTEPS_PER_CONTACT,
};
use crate::tangential::{stiffness_ratio, TangentialLaw};
use neighbours::NeighbourList;
pub use paraview::ParaViewSeries;
use parry3d_f64::shape::{SharedShape, TypedShape};
pub use readout::ContactReading;
pub use verify::{FailedStep, ENERGY_TOLERANCE, REST_FRACTION};

/// The drop-in's maps, keyed by handles: a fixed-seed fast hash (see `Cargo.toml`).
type HashMap<K, V> = std::collections::HashMap<K, V, foldhash::fast::FixedState>;
type HashSet<K> = std::collections::HashSet<K, foldhash::fast::FixedState>;

/// A pair of colliders as the contacts' maps key it.
type Pair = (ColliderHandle, ColliderHandle);

/// The order in which pairs are listed wherever the order shows: by their colliders' handles.
fn pair_order(pair: &Pair) -> ((u32, u32), (u32, u32)) {
    (pair.0.into_raw_parts(), pair.1.into_raw_parts())
}

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
    /// Whether the user had asked for the `filter_contact_pair` hook on the collider when it
    /// was handed over: then the user's hook decides, with rapier's other rules, whether the
    /// pair interacts.
    #[cfg_attr(feature = "checkpoint", serde(default))]
    user_filter: bool,
}

impl Handled {
    /// A wall's outward unit normal (world) where it is nearest the world point `at`: a
    /// half-space's own, a mesh's gradient there; `None` for a body that is not a wall.
    fn wall_normal(&self, pose: &Pose, at: Vector) -> Option<Vector> {
        match &self.shape {
            ConvexShape::HalfSpace { normal } => Some(pose.rotation * *normal),
            ConvexShape::Mesh(m) => {
                Some(pose.rotation * m.gradient(pose.inverse_transform_point(at)))
            }
            _ => None,
        }
    }

    /// The largest reduced radius of curvature `R*` (m) the liquid film between this collider
    /// and `other` can act with ([`film_radius`](crate::lubrication::film_radius) of each, the
    /// bound of the radius at the gap): for the sub-step advice.
    fn film_radius_with(&self, other: &Handled) -> Real {
        use crate::lubrication::{film_radius, reduced_radius};
        reduced_radius(film_radius(&self.shape), film_radius(&other.shape))
    }
}

/// A collider's pose and its body's motion as a contact sees them: the body's kinematics, its
/// handle, and its mass (infinite for a body that does not move, or no body at all).
struct ColliderMotion {
    pose: Pose,
    kinematics: BodyKinematics,
    body: Option<RigidBodyHandle>,
    mass: Real,
    /// The linear acceleration gravity and the user's force give the body (m/s²; zero for a
    /// body that does not move).
    acceleration: Vector,
}

/// A candidate pair and the shift that moves the second collider to its image nearest the
/// first (zero without periodic axes).
type Candidate = (ColliderHandle, ColliderHandle, Vector);

/// A checked pair's forces on a sub-step, before they are summed (its state stays in its
/// slot, see `forces`).
struct Evaluated {
    bodies: (Option<RigidBodyHandle>, Option<RigidBodyHandle>),
    force_on_a: Vector,
    torques: (Vector, Vector),
    refresh: Option<crate::contact::Refresh>,
    indentation: Real,
    /// Where it touches: contact point, normal from B to A (world) and overlap volume; `None`
    /// for a pair about to touch.
    place: Option<(Vector, Vector, Real)>,
    /// How its force is taken.
    treatment: Treatment,
    /// For a contact that began on this sub-step as an impact: how long it counts as one (s).
    impact: Option<Real>,
    /// The approach speed at the contact point (m/s; negative while separating).
    approach: Real,
    /// The contact's elastic energy `∫ F_el dd` at its evaluation (J).
    elastic: Real,
}

/// How a checked pair's force is taken over a sub-step.
// The law is carried by value: one per candidate and sub-step in a list kept between them,
// where a box would allocate each time.
#[allow(clippy::large_enum_variant)]
enum Treatment {
    /// As evaluated, at the sub-step's start (explicit integration; an impact's sub-steps).
    Explicit,
    /// Implicitly, with this law over the sub-step: a resting or slowly moving contact, or a
    /// pair about to touch slowly.
    Resting(crate::implicit::StepLaw),
    /// An impact, or a pair about to meet as one: resolved in sub-steps of its own.
    Impact,
}

/// How a (sub-)step's pairs are checked.
#[derive(Clone, Copy, Debug)]
struct Pass {
    /// The (sub-)step (s).
    h: Real,
    /// The speed below which two bodies meet without an impact (m/s).
    rest_speed: Real,
    /// Resting contacts and pairs about to touch taken implicitly, impacts set aside
    /// ([`Integration::Implicit`], outside an impact's own sub-steps).
    resting: bool,
    /// The impacts' record kept ([`Integration::Implicit`]).
    impacts: bool,
    /// Inside an impact's own sub-steps: its impacts evaluated and applied as they are.
    sub_cycle: bool,
    /// How many times finer than their advice impacts' own sub-steps are (a step redone).
    refine: usize,
}

/// A candidate pair last found apart: the exact distance's margin over the contact
/// enlargement then (m) and both colliders' poses at that time.
#[derive(Clone, Copy)]
struct Gap {
    margin: Real,
    poses: (Pose, Pose),
}

/// What a sub-step's check did to a candidate's remembered gap.
enum GapCheck {
    /// The pair is apart and its last gap still bounds its distance: kept as it is.
    Kept,
    /// The pair is apart by this newly measured gap.
    Found(Gap),
    /// The pair may touch: no gap to remember.
    Closed,
}

/// The liquid film's force on a pair (see [`Lubrication`]): on A, the torques about each
/// body's centre of mass; B takes minus the force.
#[derive(Clone, Copy)]
struct Film {
    bodies: (Option<RigidBodyHandle>, Option<RigidBodyHandle>),
    force_on_a: Vector,
    torque_on_a: Vector,
    torque_on_b: Vector,
}

/// What a pair's check on a sub-step found: a contact's forces, what became of its gap, and
/// the film's force when lubrication is on and the pair is within its cut-off.
/// Every candidate's check is collected and read on one thread each sub-step, so it holds
/// no contact state.
type Checked = (Option<Evaluated>, GapCheck, Option<Film>);

/// The lists a sub-step fills, kept between sub-steps so that a sub-step allocates none (once
/// they have grown to the scene's size): the candidate pairs, their contact states while they
/// are evaluated, their checks, each body's summed force and torque, and the bodies' own
/// forces and torques before these were added (for [`take_back`]).
#[derive(Default)]
struct SubstepBuffers {
    pairs: Vec<Candidate>,
    slots: Vec<Option<Box<ContactState>>>,
    checks: Vec<Result<Checked>>,
    added: HashMap<RigidBodyHandle, (Vector, Vector)>,
    applied: Vec<Applied>,
}

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

/// A body's user force and torque before this crate added its own, in rapier's numbers.
type Applied = (RigidBodyHandle, engine::math::Vector, engine::math::Vector);

/// Rapier keeps user forces across steps: puts back each body's force and torque as they were
/// before this crate added its own for one step (`applied` holds them, in the order they were
/// recorded; restored in reverse). Restored, not subtracted: `f + g − g` is not always `f` in
/// floating point, and the user's force must come back exactly.
pub(crate) fn take_back(world: &mut PhysicsWorld, applied: &[Applied]) {
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
    #[cfg_attr(feature = "checkpoint", serde(default))]
    integration: Integration,
    #[cfg_attr(feature = "checkpoint", serde(default))]
    failed_step: FailedStep,
    substeps_per_contact: Real,
    handled: HashMap<ColliderHandle, Handled>,
    /// Each handled collider's shape as f64 parry sees it, for the pairs' exact distances:
    /// rapier's own shape in the f64 build, its widened twin in the f32 one (whose own f32
    /// distances can be off by more than the gap they decide on). Rebuilt from the world
    /// where missing (after a restart).
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    queries: HashMap<ColliderHandle, SharedShape>,
    /// The live contacts' states, boxed: each sub-step moves them out to its evaluations and
    /// back, which a box does without copying the state.
    states: HashMap<(ColliderHandle, ColliderHandle), Box<ContactState>>,
    /// Candidate pairs found apart: a pair that cannot have closed its gap since needs no new
    /// distance (a cache; rebuilt by the exact distance). A step's first sub-step keeps those
    /// of its candidates, the later ones update them in place (a gap bounds the distance
    /// whenever it is read, so one kept for a pair that left the candidates stays right).
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    gaps: HashMap<(ColliderHandle, ColliderHandle), Gap>,
    periodic: Option<PeriodicBox>,
    indentation_limit: Real,
    /// The liquid film's force between handled pairs, when set.
    #[cfg_attr(feature = "checkpoint", serde(default))]
    lubrication: Option<Lubrication>,
    /// The live contacts that are impacts (integrated explicitly under
    /// [`Integration::Implicit`]), with how long each still counts as one (s).
    #[cfg_attr(feature = "checkpoint", serde(default))]
    impacts: HashMap<(ColliderHandle, ColliderHandle), Real>,
    /// Each live contact's elastic energy at its last evaluation (J): what the step's check
    /// allows its contacts to release.
    #[cfg_attr(feature = "checkpoint", serde(default))]
    elastic: HashMap<(ColliderHandle, ColliderHandle), Real>,
    /// The step's deepest overlap against its limit: (depth over limit, the pair, depth,
    /// limit).
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    deepest: Option<(Real, (ColliderHandle, ColliderHandle), Real, Real)>,
    /// This step is taken explicitly, though the integration is implicit: an impact struck a
    /// body on an impulse joint (see `impacts`).
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    explicit_step: bool,
    /// Steps taken: where an error says when it happened.
    #[cfg_attr(feature = "checkpoint", serde(default))]
    steps: u64,
    /// Bumped whenever the handled set changes.
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    generation: u64,
    /// The neighbour search's memory; rebuilt from the bodies when empty (after a restart).
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    neighbours: std::sync::Mutex<Neighbours>,
    /// The handled colliders' active collision types as the user set them, while a step has
    /// them cleared in the world (see `set_aside_collision_types`); empty between steps.
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    set_aside: HashMap<ColliderHandle, ActiveCollisionTypes>,
    /// A sub-step's lists, kept between sub-steps.
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    buffers: SubstepBuffers,
    /// The pairs whose contact's start went out as a collision event and whose end has not
    /// (see `events`).
    #[cfg_attr(feature = "checkpoint", serde(default))]
    reported: HashSet<(ColliderHandle, ColliderHandle)>,
    /// Every pair with a live contact at some point of the step's attempt so far.
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    touched: HashSet<(ColliderHandle, ColliderHandle)>,
    /// The live contacts after the last step (see `readout`).
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    readings: Vec<ContactReading>,
    /// The contacts' records over the step's attempt so far.
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    step_readings: HashMap<(ColliderHandle, ColliderHandle), readout::Reading>,
}

/// The drop-in's tangential law unless set: the spring, so that a scene at rest stays at rest.
fn default_tangential_law() -> TangentialLaw {
    TangentialLaw::Spring
}

/// The candidate search's memory: the handled colliders in handle order (all, the bounded and
/// the half-spaces, for the generation of the handled set they were taken from), the bounded
/// ones' Verlet list, and the buffers a search fills (kept, so a sub-step allocates none).
#[derive(Default)]
struct Neighbours {
    generation: Option<u64>,
    all: Vec<ColliderHandle>,
    bounded: Vec<ColliderHandle>,
    half_spaces: Vec<ColliderHandle>,
    list: NeighbourList,
    spheres: Vec<Sphere>,
    reaches: Vec<Real>,
    mobile: Vec<bool>,
    found: Vec<(usize, usize, Vector)>,
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
            integration: Integration::Implicit,
            failed_step: FailedStep::Redo,
            substeps_per_contact: SUBSTEPS_PER_CONTACT,
            handled: HashMap::default(),
            queries: HashMap::default(),
            states: HashMap::default(),
            gaps: HashMap::default(),
            periodic: None,
            indentation_limit: 0.5,
            lubrication: None,
            impacts: HashMap::default(),
            elastic: HashMap::default(),
            deepest: None,
            explicit_step: false,
            steps: 0,
            generation: 0,
            neighbours: Default::default(),
            set_aside: HashMap::default(),
            buffers: SubstepBuffers::default(),
            reported: HashSet::default(),
            touched: HashSet::default(),
            readings: Vec::new(),
            step_readings: HashMap::default(),
        })
    }

    /// Refuse a pair (with [`Error::ContactTooSoft`]) when Hertz puts its deepest indentation
    /// beyond `fraction` of the smaller body's smallest half-extent, `0 < fraction <= 1`
    /// (default 0.5). Softened materials — Marquardt, Hafen & Krause run E = 5 kPa particles so that contacts
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

    /// With the liquid film's normal force ([`Lubrication`], and its sliding terms when
    /// [`Lubrication::with_shear`]) between every handled pair closer than its cut-off, beside the contact force (and through the contact, the gap
    /// held at the film's minimum). The sub-step advice resolves the film's damping at its
    /// minimum gap. For bodies immersed in a liquid whose solver does not resolve gaps below
    /// the cut-off (see `coupling`).
    pub fn with_lubrication(mut self, lubrication: Lubrication) -> Self {
        self.lubrication = Some(lubrication);
        self
    }

    /// The lubrication law, when set.
    pub fn lubrication(&self) -> Option<&Lubrication> {
        self.lubrication.as_ref()
    }

    /// With friction for every handled pair.
    pub fn with_friction(mut self, friction: Friction) -> Self {
        self.friction = friction;
        self
    }

    /// With another tangential law for the friction (the default is
    /// [`TangentialLaw::Spring`]; [`TangentialLaw::SlipSpeed`] is the papers' model).
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

    /// With another way of integrating the contacts (see [`Integration`]; the default is
    /// [`Integration::Implicit`]).
    pub fn with_integration(mut self, integration: Integration) -> Self {
        self.integration = integration;
        self
    }

    /// How the contacts are integrated.
    pub fn integration(&self) -> Integration {
        self.integration
    }

    /// Whether the step takes its resting contacts implicitly: [`Integration::Implicit`] for
    /// dry contacts. Contacts with an enlargement or a liquid film (wet runs, see `coupling`)
    /// are integrated explicitly: the film's force acts across a gap and with the fluid's
    /// step, which the implicit laws, taken where bodies touch, do not follow.
    fn implicit(&self) -> bool {
        self.integration == Integration::Implicit
            && self.lubrication.is_none()
            && self.settings.enlargement() == [0.0, 0.0]
            && !self.explicit_step
    }

    /// With another answer to a step that fails its check (see [`FailedStep`]; the default is
    /// [`FailedStep::Redo`]).
    pub fn with_failed_step(mut self, failed: FailedStep) -> Self {
        self.failed_step = failed;
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

    /// Hands `collider` to the discrete contact with `material`: a convex solid, or a triangle
    /// mesh or height field on a fixed or kinematic body as a wall (its solid side,
    /// [`MeshSdf`]).
    ///
    /// Errors: [`Error::InvalidArgument`] for a handle not in `world`;
    /// [`Error::UnsupportedShape`] for a shape that is neither (a compound, a polyline), a
    /// mesh on a dynamic body, or a mesh whose triangles have no solid side.
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
        let shapes = Self::shapes_of(&world.bodies, co)?;
        self.hand_over(co, collider, material, shapes);
        Ok(())
    }

    /// Whether `collider` is handed to the discrete contact.
    pub fn is_handled(&self, collider: ColliderHandle) -> bool {
        self.handled.contains_key(&collider)
    }

    /// Gives `collider` back to rapier's own contacts: its live contacts with the discrete
    /// contact end (the ends of those reported as started go out as collision events at the
    /// next step), and its contact-pair hook flag is as the user had it before it was handed
    /// over. `false` where it was not handled. A collider whose shape changed is handed over
    /// again with [`handle`](Self::handle) (the contact keeps the shape it was given).
    pub fn unhandle(&mut self, world: &mut PhysicsWorld, collider: ColliderHandle) -> bool {
        let Some(h) = self.forget(&[collider]).pop() else { return false };
        if let Some(co) = world.colliders.get_mut(collider) {
            if !h.user_filter {
                co.set_active_hooks(co.active_hooks() - ActiveHooks::FILTER_CONTACT_PAIRS);
            }
        }
        true
    }

    /// Forgets the handled colliders among `colliders` and ends their contacts; returns what
    /// was kept of those that were handled.
    fn forget(&mut self, colliders: &[ColliderHandle]) -> Vec<Handled> {
        let forgotten: Vec<Handled> = colliders
            .iter()
            .filter_map(|c| {
                self.queries.remove(c);
                self.set_aside.remove(c);
                self.handled.remove(c)
            })
            .collect();
        if forgotten.is_empty() {
            return forgotten;
        }
        let kept = |(a, b): &(ColliderHandle, ColliderHandle)| {
            !colliders.contains(a) && !colliders.contains(b)
        };
        self.states.retain(|pair, _| kept(pair));
        self.gaps.retain(|pair, _| kept(pair));
        self.impacts.retain(|pair, _| kept(pair));
        self.elastic.retain(|pair, _| kept(pair));
        self.generation += 1;
        forgotten
    }

    /// A collider's shape as f64 parry sees it and as the contact's SDF: a convex solid, or
    /// the solid side of a triangle mesh or height field on a body that does not move under
    /// forces (a wall); an error for any other shape, and for a mesh on a dynamic body.
    fn shapes_of(bodies: &RigidBodySet, co: &Collider) -> Result<(SharedShape, ConvexShape)> {
        let query = boundary::query_shape(co)?;
        let mesh =
            matches!(query.as_typed_shape(), TypedShape::TriMesh(_) | TypedShape::HeightField(_));
        if !mesh {
            let shape = ConvexShape::from_parry(query.as_ref())?;
            return Ok((query, shape));
        }
        if co.parent().and_then(|b| bodies.get(b)).is_some_and(|rb| rb.is_dynamic()) {
            return Err(Error::UnsupportedShape {
                shape: format!("{:?}", query.shape_type()),
                why: "a triangle mesh or height field is a wall: handled on a fixed or \
                      kinematic body only; give a dynamic body convex pieces",
            });
        }
        let shape = ConvexShape::Mesh(std::sync::Arc::new(MeshSdf::from_parry(query.as_ref())?));
        Ok((query, shape))
    }

    /// Records collider `collider` (`co`) as handled with `material` and its `shapes`.
    fn hand_over(
        &mut self,
        co: &mut Collider,
        collider: ColliderHandle,
        material: Material,
        (query, shape): (SharedShape, ConvexShape),
    ) {
        let (centre, radius) = shape.bounding_sphere();
        let b = shape.local_bounds();
        // A wall (a half-space, a mesh's solid side) bounds no indentation by its size.
        let wall = matches!(shape, ConvexShape::HalfSpace { .. } | ConvexShape::Mesh(_));
        let half_size = if wall { Real::INFINITY } else { (b.maxs - b.mins).min_element() * 0.5 };
        // Handed over again, the flag may be ours: keep what the user had asked for.
        let user_filter = match self.handled.get(&collider) {
            Some(h) => h.user_filter,
            None => co.active_hooks().contains(ActiveHooks::FILTER_CONTACT_PAIRS),
        };
        co.set_active_hooks(co.active_hooks() | ActiveHooks::FILTER_CONTACT_PAIRS);
        self.handled
            .insert(collider, Handled { shape, material, centre, radius, half_size, user_filter });
        self.queries.insert(collider, query);
        // A gap measured for another shape or size bounds nothing now, nor does a live
        // contact's last full geometry, nor where its last evaluation put it.
        self.gaps.clear();
        for (_, state) in
            self.states.iter_mut().filter(|((a, b), _)| *a == collider || *b == collider)
        {
            state.reference = None;
            state.frame = None;
        }
        self.generation += 1;
    }

    /// Hands every collider whose shape is a convex solid to the discrete contact; returns
    /// the colliders it left to rapier's own contacts, each with why (triangle meshes, height
    /// fields, compounds and other shapes that are not convex solids:
    /// [`Error::UnsupportedShape`]), in the world's order. An empty list: every collider is
    /// handled.
    pub fn handle_all(
        &mut self,
        world: &mut PhysicsWorld,
        material: Material,
    ) -> Result<Vec<(ColliderHandle, Error)>> {
        let all: Vec<ColliderHandle> = world.colliders.iter().map(|(h, _)| h).collect();
        let mut left = Vec::new();
        for h in all {
            let co = &mut world.colliders[h];
            match Self::shapes_of(&world.bodies, co) {
                Ok(shapes) => self.hand_over(co, h, material, shapes),
                Err(why) => left.push((h, why)),
            }
        }
        Ok(left)
    }

    /// Forgets the handled colliders the world no longer holds (removed with their body or
    /// alone since the last step): their contacts end, and nothing of them is looked up again.
    /// Their reported contacts' ends go to `events` (see `events`).
    fn forget_removed(&mut self, world: &PhysicsWorld, events: &dyn EventHandler) {
        let gone: Vec<ColliderHandle> =
            self.handled.keys().filter(|c| world.colliders.get(**c).is_none()).copied().collect();
        if gone.is_empty() {
            return;
        }
        self.report_removed(world, &gone, events);
        self.forget(&gone);
    }

    /// Builds the missing query shapes of handled colliders (all of them after a restart).
    fn restore_queries(&mut self, world: &PhysicsWorld) -> Result<()> {
        if self.queries.len() == self.handled.len() {
            return Ok(());
        }
        for &c in self.handled.keys() {
            if let std::collections::hash_map::Entry::Vacant(slot) = self.queries.entry(c) {
                let co = world.colliders.get(c).ok_or(Error::InvalidArgument {
                    name: "world",
                    allowed: "the world whose colliders were handed to these contacts",
                })?;
                slot.insert(boundary::query_shape(co)?);
            }
        }
        Ok(())
    }

    /// Whether the pair (in either order) is in contact now.
    pub fn contact(&self, a: ColliderHandle, b: ColliderHandle) -> Option<&ContactState> {
        self.states.get(&(a, b)).or_else(|| self.states.get(&(b, a))).map(|s| &**s)
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
    ///
    /// While the step runs rapier's pipeline, the handled colliders' active collision types
    /// read empty in the world wherever that changes no pair with a collider that is not
    /// handled (every such collider admits all the handled ones do, as with the default
    /// types): rapier's broad phase then pairs no two handled colliders. Hooks and event
    /// handlers called during the step see them so; the step gives them back before it returns.
    ///
    /// The step checks itself afterwards (see [`FailedStep`]): a contact deeper than its
    /// bodies can hold, a body at a non-finite place, or energy the step created beyond the
    /// contacts' stored energy and the users' forces' work undoes it; it is taken again in
    /// four times the sub-steps, or refused with [`Error::StepRejected`] and the world left
    /// as it was. Rapier's own events of an undone attempt (pairs the drop-in does not handle)
    /// have reached `events` already; the handled pairs' collision events go out once the
    /// step has passed its check (see the `rapier` module).
    pub fn step_with_events(
        &mut self,
        world: &mut PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        events: &dyn EventHandler,
    ) -> Result<StepStats> {
        let dt = real(world.integration_parameters.dt);
        check_positive("integration_parameters.dt", dt)?;
        self.forget_removed(world, events);
        self.restore_queries(world)?;
        self.compute_masses(world);
        let rest_speed = self.rest_speed(world, dt);
        let snapshot = self.snapshot(world);
        let before = self.ledger(world, rest_speed);
        let mut multiplier = 1;
        self.explicit_step = false;
        loop {
            self.deepest = None;
            let (problem, refused) = match self.try_step(world, hooks, events, dt, multiplier) {
                Ok(Some(stats)) => match self.verify(world, &before, dt) {
                    None => {
                        self.steps += 1;
                        self.explicit_step = false;
                        self.report_collisions(world, events);
                        self.keep_readings(dt);
                        return Ok(stats);
                    }
                    Some(problem) => (problem, None),
                },
                // An impact struck a body on a joint: the step again, explicitly.
                Ok(None) => {
                    self.restore(world, &snapshot);
                    self.explicit_step = true;
                    continue;
                }
                Err(Error::StepRejected { pair, problem, .. }) => ((pair, problem), None),
                Err(e) => ((String::new(), String::new()), Some(e)),
            };
            self.restore(world, &snapshot);
            if let Some(e) = refused {
                self.steps += 1;
                self.explicit_step = false;
                return Err(e);
            }
            let more = multiplier * 4;
            let allowed = match self.policy {
                StepPolicy::Fixed { .. } => false,
                StepPolicy::AutoSubstep { max_substeps } => {
                    self.substeps_with(world, hooks, dt)? * more <= max_substeps.max(1)
                }
            };
            if self.failed_step == FailedStep::Refuse || !allowed {
                let step = self.steps;
                self.steps += 1;
                self.explicit_step = false;
                return Err(Error::StepRejected { step, pair: problem.0, problem: problem.1 });
            }
            multiplier = more;
        }
    }

    /// One attempt at the step of `dt`, in `multiplier` times the sub-steps the advice asks
    /// for; `None` where an impact struck a body on an impulse joint under implicit
    /// integration, which the step must then take explicitly.
    fn try_step(
        &mut self,
        world: &mut PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        events: &dyn EventHandler,
        dt: Real,
        multiplier: usize,
    ) -> Result<Option<StepStats>> {
        let builds = self.neighbour_builds();
        self.touched.clear();
        self.step_readings.clear();
        let rest_speed = self.rest_speed(world, dt);
        let substeps = self.substeps_with(world, hooks, dt)? * multiplier;
        let saved =
            (world.integration_parameters.dt, world.integration_parameters.num_solver_iterations);
        let h = dt / substeps as Real;
        world.integration_parameters.dt = engine_real(h);
        // One solver iteration: rapier then integrates each (sub-)step as one symplectic Euler
        // step, `x += h v'`, the motion the contacts' forces were taken for (with n iterations
        // it moves a body by `(n + 1)/2n` of the change of velocity's share).
        world.integration_parameters.num_solver_iterations = 1;
        let mut stats = StepStats { substeps, ..Default::default() };
        self.set_aside_collision_types(world);
        let mut result = Ok(());
        let implicit = self.implicit();
        let records = self.integration == Integration::Implicit;
        let pass = Pass {
            h,
            rest_speed,
            resting: implicit,
            impacts: records,
            sub_cycle: false,
            refine: multiplier,
        };
        let mut jointed = false;
        for k in 0..substeps {
            match self.apply_forces(world, hooks, &mut stats, k == 0, pass) {
                Err(e) => {
                    result = Err(e);
                    break;
                }
                Ok(false) => {
                    jointed = true;
                    break;
                }
                Ok(true) => {}
            }
            world.step_with_events(&Hooks { handled: &self.handled, user: hooks }, events);
            take_back(world, &self.buffers.applied);
        }
        world.integration_parameters.dt = saved.0;
        world.integration_parameters.num_solver_iterations = saved.1;
        self.restore_collision_types(world);
        result?;
        if jointed {
            return Ok(None);
        }
        self.wrap_bodies(world);
        stats.contacts = self.states.len();
        stats.neighbour_builds = self.neighbour_builds() - builds;
        Ok(Some(stats))
    }

    /// The speed (m/s) below which two bodies meet without an impact under
    /// [`Integration::Implicit`]: the larger of [`AT_REST_SPEED`] and what gravity gives a
    /// body in [`REST_STEPS`] steps of `dt`.
    fn rest_speed(&self, world: &PhysicsWorld, dt: Real) -> Real {
        AT_REST_SPEED.max(REST_STEPS * vector(world.gravity).length() * dt)
    }

    /// Computes the mass properties of the dynamic bodies of handled colliders that rapier has
    /// not computed yet (it does so at the start of its step, after this crate's forces are
    /// set): a body inserted since the last step then carries its weight from its first step.
    fn compute_masses(&self, world: &mut PhysicsWorld) {
        let PhysicsWorld { bodies, colliders, .. } = world;
        let mut missing: Vec<RigidBodyHandle> = self
            .handled
            .keys()
            .filter_map(|c| colliders.get(*c).and_then(|co| co.parent()))
            .filter(|b| bodies.get(*b).is_some_and(|rb| rb.is_dynamic() && rb.mass() == 0.0))
            .collect();
        missing.sort_by_key(|b| b.into_raw_parts());
        missing.dedup();
        for b in missing {
            bodies[b].recompute_mass_properties_from_colliders(colliders);
        }
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
            user_filter: false,
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
