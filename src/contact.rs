//! Persistent contact state: a contact fixes its damping at first touch and carries its
//! corrected box and its tangential spring's history from one sub-step to the next until the
//! bodies part.

use parry3d_f64::bounding_volume::Aabb;

use crate::error::Result;
use crate::force::{contact_force_with_history, BodyKinematics, ContactForce};
use crate::material::PairParameters;
use crate::math::{Pose, Real};
use crate::overlap::{compute_overlap, OverlapGeometry, OverlapSettings};
use crate::shape::Sdf;
use crate::tangential::TangentialHistory;

/// A body as the contact sees it: shape, pose and motion.
#[derive(Clone, Copy, Debug)]
pub struct BodyState<'a, S: ?Sized> {
    /// The body's SDF (body frame).
    pub shape: &'a S,
    /// Body frame → world.
    pub pose: Pose,
    /// Centre of mass and velocities (world).
    pub kinematics: BodyKinematics,
}

impl<'a, S: ?Sized> BodyState<'a, S> {
    /// A body at rest whose centre of mass is the origin of its frame.
    pub fn at_rest(shape: &'a S, pose: Pose) -> Self {
        Self { shape, pose, kinematics: BodyKinematics::at_rest(pose.translation) }
    }

    /// With velocities (m/s, rad/s) about the centre of mass.
    pub fn moving(mut self, linvel: crate::math::Vector, angvel: crate::math::Vector) -> Self {
        self.kinematics.linvel = linvel;
        self.kinematics.angvel = angvel;
        self
    }
}

/// What a live contact remembers between sub-steps.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct ContactState {
    /// Damping constant `c` (s/m), fixed at first touch from the approach speed then (and
    /// lowered if the contact is later driven faster, see [`ContactModel::evaluate`]).
    pub damping: Real,
    /// The approach speed `c` was set from (m/s): the first touch's, or a larger one seen
    /// later.
    pub reference_approach_speed: Real,
    /// Last corrected overlap box (pair frame), the rough box of the next sub-step.
    pub corrected_box: Aabb,
    /// The tangential spring's history ([`TangentialLaw::Spring`](crate::TangentialLaw::Spring);
    /// stays empty under the slip-speed law).
    #[cfg_attr(feature = "checkpoint", serde(default))]
    pub tangential: TangentialHistory,
    /// Normal stiffness `dF_n/dd` at the last evaluation (N/m): what the time-step advice of
    /// the live contact resolves.
    #[cfg_attr(feature = "checkpoint", serde(default))]
    pub normal_stiffness: Real,
}

/// Geometry and force of one evaluation.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactOutput {
    /// Overlap geometry.
    pub geometry: OverlapGeometry,
    /// Force and torques.
    pub force: ContactForce,
}

/// The contact law for one kind of pair: force parameters plus overlap resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactModel {
    /// Force-law parameters.
    pub params: PairParameters,
    /// Overlap grid resolution and mode.
    pub settings: OverlapSettings,
}

impl ContactModel {
    /// A model from checked parameters.
    pub fn new(params: PairParameters, settings: OverlapSettings) -> Self {
        Self { params, settings }
    }

    /// Evaluates the pair and updates its persistent `state`: `None` → a new contact starts
    /// (damping from the current approach speed); bodies apart → `state` is cleared and
    /// `Ok(None)` returned. A live contact keeps its damping unless it approaches faster than
    /// it did when `c` was set; then `c` is set anew from that speed.
    pub fn evaluate<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        a: &BodyState<'_, A>,
        b: &BodyState<'_, B>,
        state: &mut Option<ContactState>,
    ) -> Result<Option<ContactOutput>> {
        a.kinematics.check("kinematics of body A")?;
        b.kinematics.check("kinematics of body B")?;
        let previous = state.as_ref().map(|s| s.corrected_box);
        let Some(geometry) = compute_overlap(a.shape, &a.pose, b.shape, &b.pose, &self.settings, previous.as_ref())? else {
            *state = None;
            return Ok(None);
        };
        let x = geometry.contact_point;
        let approach = -(a.kinematics.velocity_at(x) - b.kinematics.velocity_at(x)).dot(geometry.normal);
        let s = state.get_or_insert_with(|| ContactState {
            damping: self.params.damping_for(approach),
            reference_approach_speed: approach,
            corrected_box: geometry.corrected_box,
            tangential: TangentialHistory::default(),
            normal_stiffness: 0.0,
        });
        // In a binary impact the approach speed only falls after first touch. A contact that
        // a third body drives faster (a pile, a contact begun while sliding) re-bases `c` on
        // the larger speed, so `c ḋ` never exceeds `a(e)`: a contact begun at a crawl would
        // otherwise multiply a later impact's force by `1 + a(e) ḋ / v_crawl` and explode.
        if approach > s.reference_approach_speed.max(self.params.min_approach_speed) {
            s.damping = self.params.damping_for(approach);
            s.reference_approach_speed = approach;
        }
        s.corrected_box = geometry.corrected_box;
        let carried = s.tangential.carried(&a.pose, &b.pose, geometry.normal);
        let (force, spring) =
            contact_force_with_history(&self.params, s.damping, &geometry, &a.kinematics, &b.kinematics, carried, s.tangential.sliding);
        s.normal_stiffness = force.stiffness;
        if self.params.tangential == crate::TangentialLaw::Spring {
            s.tangential.record(spring.displacement, spring.sliding, geometry.contact_point, &a.pose, &b.pose);
        }
        Ok(Some(ContactOutput { geometry, force }))
    }
}
