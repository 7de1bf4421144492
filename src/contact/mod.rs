//! Persistent contact state: a contact fixes its damping at first touch and carries its
//! corrected box, its tangential spring's history and its last full geometry from one sub-step
//! to the next until the bodies part.
//!
//! **Geometry reuse.** Between two sub-steps a resting or slowly rolling contact moves far less
//! than one cell of its overlap grid, yet a full evaluation integrates the whole grid again.
//! A live contact therefore keeps its last full geometry in B's frame ([`Reference`]) and,
//! while the pair's relative motion since then stays small against the indentation and the
//! grid spacing ([`ContactModel::with_geometry_reuse`]), updates it from that motion instead
//! (less a body of revolution's turn about its own axis, which moves no surface: a cylinder
//! rolling or spinning is the same body turned): the indentation by the approach (how far A's
//! material at the contact point moved along the normal; a ball's centre, whose turning moves no
//! surface), the volume along the overlap's own power law `V ∝ d^p` (a flat punch's `p = 1`, a
//! cap's or an edge's 2, a corner's 3: the secant of the last two full evaluations, or at first the
//! shape measure the stiffness uses) — or, for a ball against a ball, a half-space or a face (a
//! lens or a cap), along the lens's exact law, the full evaluation scaled by the exact lens's
//! volume and surface at the ball's depth then and now — the contact point as between two balls
//! about the bodies' centres (a body flat at the contact — a face under a ball or a cylinder's side
//! — as a half-space: the point goes with the curved body) and across the contact plane as a tilt
//! of the surfaces moves the overlap's centroid (by the overlap's footprint,
//! [`OverlapGeometry::footprint`], between nearly parallel surfaces; elsewhere — an edge or a
//! corner in the overlap, surfaces at an angle — volume and centroid move as A's motion sweeps its
//! surface through B, [`OverlapGeometry::flux`]), the normal as the surfaces' own normals at the
//! contact point turn. First touch, a contact whose update would part the bodies, and any motion
//! beyond the bound get a full evaluation. The rule reads only the contact's state, so results do
//! not depend on the thread count and a checkpoint resumes bit-identically.

mod point;
mod reuse;

use parry3d_f64::bounding_volume::Aabb;

use crate::error::Result;
use crate::force::{contact_force_with_history, BodyKinematics, ContactForce};
use crate::material::PairParameters;
use crate::math::{Matrix, Pose, Real, Vector};
use crate::overlap::{compute_overlap, OverlapGeometry, OverlapSettings};
use crate::shape::Sdf;
use crate::tangential::TangentialHistory;

use point::{about_no_axis, through_ball_centres};
pub use reuse::{check_reuse, Feature, Lens, Reference, Refresh, Refreshes};

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
    /// The last full evaluation, while geometry reuse is on; `None` forces a full evaluation.
    pub reference: Option<Reference>,
    /// Where the last evaluation put the contact: what the sub-step advice of the drop-in
    /// couples the bodies at (`None` before the first evaluation).
    pub frame: Option<ContactFrame>,
}

/// A contact's point as a material point of each body, its normal and its resistance to
/// tilting: where and how its spring joins the two bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct ContactFrame {
    /// The contact point in A's body frame and in B's (m): through a periodic box's faces the
    /// bodies' poses may lie a box apart, so each body's lever comes from its own.
    pub anchors: [Vector; 2],
    /// Unit normal from B to A, in B's body frame.
    pub normal: Vector,
    /// The overlap's resistance to tilting about the contact point, `K` (N·m/rad, B's body
    /// frame): A turned by `θ` against B feels the couple `−K θ`. `K = (F/V) [n]ₓ S [n]ₓᵀ`,
    /// `S` the footprint's second moment of area about the contact point: a tilt deepens the
    /// overlap on one side, its centroid moves there by `S (θ × n) / V`, and the force `F` at
    /// it turns A back (`k_n J/A` for a flat face pressed evenly, `J` its area's moment). A
    /// point spring at the contact point leaves this out. Zero without a footprint
    /// (closed-form spheres).
    pub rocking: Matrix,
}

impl ContactFrame {
    /// The frame of an evaluation's geometry `g` (world frame), between A at `pose_a` and B at
    /// `pose_b`, whose normal stiffness is `k_n`. The force `F` of its resistance to tilting
    /// ([`rocking`](Self::rocking)) is the elastic force behind `k_n` (`2 d k_n / (1 + p)`, the
    /// inverse of [`normal_stiffness`](crate::force::normal_stiffness) on the same geometry).
    pub(crate) fn new(g: &OverlapGeometry, k_n: Real, pose_a: &Pose, pose_b: &Pose) -> Self {
        let (x, n) = (g.contact_point, g.normal);
        let rocking = g.footprint.map_or(Matrix::ZERO, |f| {
            let offset = f.centroid - x - n * n.dot(f.centroid - x);
            let spread = f.spread
                + Matrix::from_cols(offset * offset.x, offset * offset.y, offset * offset.z)
                    * f.area;
            let p = crate::force::volume_exponent(g.volume, g.indentation, g.surface_area)
                .clamp(1.0, 2.0);
            let force = 2.0 * g.indentation * k_n / (1.0 + p);
            // `[n]ₓ`, the cross product with `n` as a matrix (columns `n × eᵢ`), in B's frame.
            let n = pose_b.rotation.inverse() * n;
            let turn = Matrix::from_quat(pose_b.rotation);
            let cross =
                Matrix::from_cols(n.cross(Vector::X), n.cross(Vector::Y), n.cross(Vector::Z));
            let k =
                cross * (turn.transpose() * spread * turn) * cross.transpose() * (force / g.volume);
            if k.is_finite() {
                k
            } else {
                Matrix::ZERO
            }
        });
        Self {
            anchors: [pose_a.inverse_transform_point(x), pose_b.inverse_transform_point(x)],
            normal: pose_b.rotation.inverse() * n,
            rocking,
        }
    }
}

/// The geometry with its contact point placed where the normal force of a ball (through its
/// centre) and of a body of revolution (without moment about its axis) acts: see
/// [`ContactModel::evaluate`].
pub(crate) fn placed<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    geometry: OverlapGeometry,
    a: &BodyState<'_, A>,
    b: &BodyState<'_, B>,
) -> OverlapGeometry {
    about_no_axis(through_ball_centres(geometry, a, b), a, b)
}

/// A's body frame in B's body frame.
fn relative_pose(a: &Pose, b: &Pose) -> Pose {
    b.inverse() * *a
}

/// Geometry and force of one evaluation.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactOutput {
    /// Overlap geometry; its contact point is where the normal force acts, moved off the
    /// overlap's centroid for a ball (onto the line through its centre) and for a body of
    /// revolution (into the plane of its axis and the normal), see
    /// [`ContactModel::evaluate`].
    pub geometry: OverlapGeometry,
    /// Force and torques.
    pub force: ContactForce,
    /// Why the geometry was integrated in full; `None`: it was updated from the last full one.
    pub refresh: Option<Refresh>,
}

impl ContactOutput {
    /// Whether the geometry was integrated in full (`false`: updated from the last full one).
    pub fn full(&self) -> bool {
        self.refresh.is_some()
    }
}

/// The geometry reuse fraction by default: the indentation may change by this fraction of
/// itself, the contact travel by this fraction of a cell, between full evaluations (see
/// [`ContactModel::with_geometry_reuse`]).
pub const GEOMETRY_REUSE: Real = 0.25;

/// The contact law for one kind of pair: force parameters plus overlap resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactModel {
    /// Force-law parameters.
    pub params: PairParameters,
    /// Overlap grid resolution and mode.
    pub settings: OverlapSettings,
    /// Geometry reuse fraction (0: every evaluation is full); private so that it stays checked.
    reuse: Real,
}

impl ContactModel {
    /// A model from checked parameters that evaluates every contact in full (geometry reuse
    /// off; [`with_geometry_reuse`](Self::with_geometry_reuse) turns it on).
    pub fn new(params: PairParameters, settings: OverlapSettings) -> Self {
        Self { params, settings, reuse: 0.0 }
    }

    /// With geometry reuse at `fraction` (`0 <= fraction <= 100`; 0 turns reuse off): between
    /// full evaluations a live contact's geometry is updated from the pair's relative motion
    /// (see the module docs) while
    /// - its local indentation changes by at most `fraction × d` — the approach at the
    ///   contact point (A's material there, along the normal) plus half the tilt across the
    ///   overlap (how far the surfaces' normals at the contact point turned, each on the face
    ///   or smooth part it lay on at the full evaluation, so that crossing an edge's bisector
    ///   is no tilt, times the corrected box's diagonal: an update follows a tilt to first
    ///   order, and what it misses at that tilt is what the volume law misses at its own
    ///   limit; eight times the tilt for a counted overlap, which it does not follow; none
    ///   against a ball, which has no orientation); a lens or a cap, which an update follows
    ///   by its exact law, by sixteen times that, and
    /// - A's material point at the contact travels across the grid by at most
    ///   `fraction × w / N_c`, `w` the corrected box's longest side — the tangential shift plus
    ///   the roll's chord at the nearer body's bounding-sphere centre; a ball's cap on a face
    ///   as far as the face is found to reach ([`Lens::glide`]).
    ///
    /// Beyond either, the next evaluation is full. Values above 1 let the geometry drift far
    /// from what the grid gives; they exist to show that the bound matters.
    pub fn with_geometry_reuse(mut self, fraction: Real) -> Result<Self> {
        self.reuse = check_reuse(fraction)?;
        Ok(self)
    }

    /// The geometry reuse fraction (see [`with_geometry_reuse`](Self::with_geometry_reuse)).
    pub fn geometry_reuse(&self) -> Real {
        self.reuse
    }

    /// Evaluates the pair and updates its persistent `state`: `None` → a new contact starts
    /// (damping from the current approach speed); bodies apart → `state` is cleared and
    /// `Ok(None)` returned. A live contact keeps its damping unless it approaches faster than
    /// it did when `c` was set; then `c` is set anew from that speed.
    ///
    /// The normal force of a ball passes through its centre, and that of a body of revolution
    /// ([`Sdf::revolution_axis`]) has no moment about its axis, as the pressure on such a body
    /// has none: the contact point is moved across the normal where the grid's lies off by its
    /// discretisation error (see `through_ball_centres` and `about_no_axis`).
    pub fn evaluate<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        a: &BodyState<'_, A>,
        b: &BodyState<'_, B>,
        state: &mut Option<ContactState>,
    ) -> Result<Option<ContactOutput>> {
        let out = match state {
            Some(s) => self.evaluate_live(a, b, s)?,
            None => {
                a.kinematics.check("kinematics of body A")?;
                b.kinematics.check("kinematics of body B")?;
                let geometry =
                    compute_overlap(a.shape, &a.pose, b.shape, &b.pose, &self.settings, None)?;
                geometry.map(|g| {
                    let relative = relative_pose(&a.pose, &b.pose);
                    let (geometry, approach) = self.placed(g, a, b);
                    let tangential = self.first_stretch(&geometry, approach, a, b);
                    let s = state.insert(ContactState {
                        damping: self.params.damping_for(approach),
                        reference_approach_speed: approach,
                        corrected_box: geometry.corrected_box,
                        tangential,
                        normal_stiffness: 0.0,
                        reference: None,
                        frame: None,
                    });
                    self.respond(a, b, &relative, s, geometry, Refresh::FirstTouch)
                })
            }
        };
        if out.is_none() {
            *state = None;
        }
        Ok(out)
    }

    /// [`evaluate`](Self::evaluate) for a live contact, its `state` updated in place. On an
    /// error the state is left as it was; `Ok(None)` when the bodies have parted, the state
    /// then left as it was and spent (the caller drops it). Lets a caller that keeps its states
    /// boxed evaluate them without moving them.
    pub(crate) fn evaluate_live<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        a: &BodyState<'_, A>,
        b: &BodyState<'_, B>,
        state: &mut ContactState,
    ) -> Result<Option<ContactOutput>> {
        let s = state;
        a.kinematics.check("kinematics of body A")?;
        b.kinematics.check("kinematics of body B")?;
        let relative = relative_pose(&a.pose, &b.pose);
        let updated = match &s.reference {
            Some(r) if self.reuse > 0.0 => {
                let update = |relative: &Pose, pose_b: &Pose| {
                    r.update((a.shape, b.shape), relative, pose_b, s.corrected_box, self.reuse)
                };
                // A body of revolution turned back about its axis first; where that moves the
                // contact beyond an allowance (a disc rolling on its rim carries its contact
                // point round with it, the turned-back one slides), the pair as it is: either
                // describes the same pair exactly.
                match r.representative((a.shape, b.shape), &relative, &b.pose) {
                    Some((turned, pose_b)) => {
                        update(&turned, &pose_b).or_else(|_| update(&relative, &b.pose))
                    }
                    None => update(&relative, &b.pose),
                }
            }
            _ => Err(Refresh::Off),
        };
        let (geometry, refresh) = match updated {
            Ok(g) => (g, None),
            Err(why) => {
                let previous = Some(&s.corrected_box);
                let overlap =
                    compute_overlap(a.shape, &a.pose, b.shape, &b.pose, &self.settings, previous)?;
                let Some(g) = overlap else { return Ok(None) };
                (g, Some(why))
            }
        };
        let (geometry, approach) = self.placed(geometry, a, b);
        // In a binary impact the approach speed only falls after first touch. A contact that
        // a third body drives faster (a pile, a contact begun while sliding) re-bases `c` on
        // the larger speed, so `c ḋ` never exceeds `a(e)`: a contact begun at a crawl would
        // otherwise multiply a later impact's force by `1 + a(e) ḋ / v_crawl` and explode.
        if approach > s.reference_approach_speed.max(self.params.min_approach_speed) {
            s.damping = self.params.damping_for(approach);
            s.reference_approach_speed = approach;
        }
        Ok(Some(match refresh {
            Some(why) => self.respond(a, b, &relative, s, geometry, why),
            None => self.respond_updated(a, b, s, geometry),
        }))
    }

    /// The tangential spring of a contact found at its first evaluation with `geometry`,
    /// approaching at `approach`: the bodies touched `d / ḋ` earlier, at the approach they
    /// close with, and the spring has been stretched by their tangential slip since — where
    /// the first evaluation falls late in a step or sub-step, a spring started unstretched
    /// would miss that slip and its force for the whole impact. Unstretched under the
    /// slip-speed law, or where the bodies do not approach.
    fn first_stretch<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        geometry: &OverlapGeometry,
        approach: Real,
        a: &BodyState<'_, A>,
        b: &BodyState<'_, B>,
    ) -> TangentialHistory {
        let (x, n, d) = (geometry.contact_point, geometry.normal, geometry.indentation);
        if self.params.tangential != crate::TangentialLaw::Spring
            || self.params.friction.is_none()
            || !(approach > 0.0 && d > 0.0)
        {
            return TangentialHistory::default();
        }
        let u = a.kinematics.velocity_at(x) - b.kinematics.velocity_at(x);
        let slip = (u - n * n.dot(u)) * (d / approach);
        let mut history = TangentialHistory::default();
        history.record(slip, false, x, &a.pose, &b.pose);
        history
    }

    /// The geometry with its contact point placed for balls and bodies of revolution (see
    /// [`evaluate`](Self::evaluate)), and the approach speed there.
    fn placed<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        geometry: OverlapGeometry,
        a: &BodyState<'_, A>,
        b: &BodyState<'_, B>,
    ) -> (OverlapGeometry, Real) {
        let geometry = placed(geometry, a, b);
        let x = geometry.contact_point;
        let approach =
            -(a.kinematics.velocity_at(x) - b.kinematics.velocity_at(x)).dot(geometry.normal);
        (geometry, approach)
    }

    /// The response to a fully evaluated `geometry` (refreshed for `why`; A at `relative` in
    /// B's frame): the contact's box and its reference for later updates set anew, then
    /// [`respond_updated`](Self::respond_updated)'s forces, reported as refreshed for `why`.
    fn respond<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        a: &BodyState<'_, A>,
        b: &BodyState<'_, B>,
        relative: &Pose,
        s: &mut ContactState,
        geometry: OverlapGeometry,
        why: Refresh,
    ) -> ContactOutput {
        s.corrected_box = geometry.corrected_box;
        // An exact form (closed-form spheres, exact polyhedra) costs less than an update.
        let reuse =
            self.reuse > 0.0 && !crate::overlap::has_exact_form(a.shape, b.shape, &self.settings);
        s.reference = reuse.then(|| {
            Reference::new(&self.settings, *relative, s.reference.as_ref(), a, b, &geometry)
        });
        let mut out = self.respond_updated(a, b, s, geometry);
        out.refresh = Some(why);
        out
    }

    /// The forces for `geometry` and the contact state they leave: the normal stiffness, the
    /// frame, the tangential spring's history. Reported as an update (`refresh: None`).
    fn respond_updated<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        a: &BodyState<'_, A>,
        b: &BodyState<'_, B>,
        s: &mut ContactState,
        geometry: OverlapGeometry,
    ) -> ContactOutput {
        let carried = s.tangential.carried(&a.pose, &b.pose, geometry.normal);
        let (force, spring) = contact_force_with_history(
            &self.params,
            s.damping,
            &geometry,
            &a.kinematics,
            &b.kinematics,
            carried,
            s.tangential.sliding,
        );
        s.normal_stiffness = force.stiffness;
        s.frame = Some(ContactFrame::new(&geometry, force.stiffness, &a.pose, &b.pose));
        if self.params.tangential == crate::TangentialLaw::Spring {
            s.tangential.record(
                spring.displacement,
                spring.sliding,
                geometry.contact_point,
                &a.pose,
                &b.pose,
            );
        }
        ContactOutput { geometry, force, refresh: None }
    }
}
