//! Geometry reuse: what a live contact keeps of its last full evaluation ([`Reference`]), how
//! an update follows the pair's small relative motion from it, and when the motion is too
//! large and the next evaluation is full ([`Refresh`]). See the [module docs](super).

use super::BodyState;
use crate::math::{Pose, Real, Rotation, Vector};
use crate::overlap::{lens_measures, Flux, Footprint, OverlapGeometry, OverlapSettings};
use crate::shape::Sdf;
use parry3d_f64::bounding_volume::Aabb;

mod lens;
mod refresh;
mod surface;

pub use lens::Lens;
use lens::LENS_ALLOWANCE;
pub use refresh::{check_reuse, Refresh, Refreshes};
pub use surface::Feature;
use surface::{flat_at, glide, gradient_on, surface_gradients};

/// A full evaluation's geometry in B's body frame, with A's pose in that frame then: what the
/// updates between full evaluations start from, and how far they may go.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct Reference {
    /// A's body frame → B's body frame at the full evaluation.
    pub relative: Pose,
    /// Contact point (B's frame, m).
    pub contact_point: Vector,
    /// Unit normal from B to A (B's frame).
    pub normal: Vector,
    /// The bodies' distance gradients at the contact point, A's and B's (B's frame): an update
    /// turns `normal` as `∇d_B − ∇d_A` turns, and counts their turn as tilt.
    pub gradients: [Vector; 2],
    /// The part of each body's surface those gradients belong to (A's, B's): an update takes
    /// each body's gradient from the same part, so that it turns with the surfaces instead of
    /// jumping from face to face where the contact point crosses an edge's bisector.
    #[cfg_attr(feature = "checkpoint", serde(default))]
    pub features: [Feature; 2],
    /// Each body's bounding-sphere centre (A's in A's frame, B's in B's frame): an update moves
    /// the contact point as it would move between two balls about these centres.
    pub centres: [Vector; 2],
    /// The distances of [`centres`](Self::centres) from the contact point (m), infinite for an
    /// unbounded body (a half-space) and for a body flat at the contact point (a face) against
    /// one that is not.
    pub radii: [Real; 2],
    /// A ball against a ball or against a body flat at the contact: their overlap is a lens,
    /// or a cap, of the ball's depth alone, and an update follows its exact law. `None` for
    /// other pairs.
    #[cfg_attr(feature = "checkpoint", serde(default))]
    pub lens: Option<Lens>,
    /// Volume (m³).
    pub volume: Real,
    /// Indentation (m).
    pub indentation: Real,
    /// Surface area (m²).
    pub surface_area: Real,
    /// Exponent `p` of the volume law `V ∝ d^p` the updates follow, within [1, 3].
    pub exponent: Real,
    /// The indentation's rate against the approach, `dd/dδ`, within [0.05, 1].
    pub depth_rate: Real,
    /// Farthest an overlap point may be from the contact point (m): the corrected box's
    /// diagonal (the box holds the overlap and its centroid), the lever by which a relative
    /// rotation changes the local indentation.
    pub reach: Real,
    /// The lever by which a relative rotation moves A's material point at the contact (m): the
    /// nearer of the bodies' centres (a body rolling on another), at least `reach`.
    pub lever: Real,
    /// The overlap grid's cell (m): the corrected box's longest side over `N_c`.
    pub cell: Real,
    /// The overlap's footprint (B's frame; see [`OverlapGeometry::footprint`]), where the
    /// evaluation gave one: how an update moves the centroid when the surfaces tilt.
    #[cfg_attr(feature = "checkpoint", serde(default))]
    pub footprint: Option<Footprint>,
    /// A's flux (B's frame; see [`OverlapGeometry::flux`]), where the evaluation gave one: how
    /// an update moves the volume and the centroid when the footprint does not apply (an edge
    /// or a corner in the overlap, surfaces at an angle).
    #[cfg_attr(feature = "checkpoint", serde(default))]
    pub flux: Option<Flux>,
}

impl Reference {
    /// The geometry after A moved (relative to B, now at `pose_b`) to `relative`, or why a
    /// full evaluation is needed instead: the motion exceeds the allowances of the reuse
    /// `fraction` (see [`ContactModel::with_geometry_reuse`](super::ContactModel::with_geometry_reuse)), or the update lost the overlap.
    /// The poses are [`representative`](Self::representative)'s.
    pub(super) fn update<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        shapes: (&A, &B),
        relative: &Pose,
        pose_b: &Pose,
        corrected_box: Aabb,
        fraction: Real,
    ) -> core::result::Result<OverlapGeometry, Refresh> {
        let motion = self.motion_since(relative);
        let q = motion.rotation;
        // A rotation by θ moves a point at distance r by its chord 2 r sin(θ/2) = 2 r |q_xyz|.
        let chord = 2.0 * Vector::new(q.x, q.y, q.z).length();
        // A's material at the contact point: its move across the contact plane and along the
        // normal into B (the approach). A ball's surface moves with its centre alone: its own
        // turning moves no surface.
        let ball_a = shapes.0.sphere_radius().is_some();
        let shift = if ball_a { self.centre_a(&motion).1 } else { self.material_shift(&motion) };
        let (across, approach) = (self.in_plane(shift).length(), -shift.dot(self.normal));
        // The local indentation changes by the approach plus the tilt of the surfaces across
        // the overlap: how far their normals at the contact point turned against each other
        // (not when both turn alike, as in B's frame under a spinning B, nor for a ball
        // spinning about its centre), weighted by `TILT_WEIGHT`. The contact travels across the
        // grid by the shift plus the roll.
        let (turned, contact_point, gradients) = self.turn(shapes, relative, &motion);
        let followed = self.tilted(turned, approach).or_else(|| {
            let turn = if ball_a { Vector::ZERO } else { motion.rotation.to_scaled_axis() };
            self.swept(shift, turn, contact_point)
        });
        let (tilted, weight) = match followed {
            Some(t) => (t, TILT_WEIGHT),
            None => (Tilt { volume: 0.0, shift: Vector::ZERO }, FROZEN_TILT),
        };
        // A ball has no orientation: against one, the overlap is a function of the ball's
        // centre in the other body's frame alone, which the approach and the travel bound, and
        // the normal and the contact point are the other body's gradient at that centre
        // (`through_ball_centres`, after every update), so no tilt counts.
        let ball_b = shapes.1.sphere_radius().is_some();
        let tilt = if ball_a || ball_b { 0.0 } else { weight * turned.length() * self.reach };
        // How far the contact travelled over the surfaces. A ball looks the same from every
        // side, so its own turning does not count: under a ball A the contact travels over B as
        // the moved contact point does, and between two balls the overlap is a lens of the
        // centres' distance alone, which the approach follows.
        let travel = match (ball_a, ball_b) {
            (true, true) => 0.0,
            (true, false) => self.in_plane(contact_point - self.contact_point).length(),
            _ => across + chord * self.lever,
        };
        // A cap follows its exact law for as long as it stays on the face beneath it.
        let glide = self.lens.map_or(0.0, |lens| lens.glide);
        // A lens follows its exact law, so only the grid's own error, which hardly changes with
        // the lens's size, is left for the allowance on its approach.
        let allowance = if self.lens.is_some() { LENS_ALLOWANCE } else { 1.0 };
        let limit = allowance * fraction * self.indentation;
        // The tilt is never negative: an approach beyond the limit is the approach's doing.
        if !(approach.abs() <= limit) {
            return Err(Refresh::Approach);
        }
        if !(approach.abs() + tilt <= limit) {
            return Err(Refresh::Tilt);
        }
        if !(travel <= (fraction * self.cell).max(glide)) {
            return Err(Refresh::Travel);
        }
        let (volume, indentation, surface_area) =
            self.grown(shapes, relative, approach).ok_or(Refresh::Lost)?;
        // The normal turns as the surfaces' own normal there does.
        let (before, now) = (
            (self.gradients[1] - self.gradients[0]).normalize_or_zero(),
            (gradients[1] - gradients[0]).normalize_or_zero(),
        );
        if before == Vector::ZERO || now == Vector::ZERO || !now.is_finite() {
            return Err(Refresh::Lost);
        }
        let normal = Rotation::from_rotation_arc(before, now) * self.normal;
        let volume = volume + tilted.volume;
        if !(volume > 0.0) {
            return Err(Refresh::Lost);
        }
        let contact_point = contact_point + tilted.shift;
        Ok(OverlapGeometry {
            volume,
            contact_point: pose_b.transform_point(contact_point),
            normal: pose_b.rotation * normal,
            indentation,
            surface_area,
            corrected_box,
            footprint: self.footprint.map(|f| f.transformed(pose_b)),
            flux: self.flux.map(|f| f.transformed(pose_b)),
        })
    }

    /// Volume, indentation and surface area after an `approach` at the contact point (A now at
    /// `relative`), or `None` when the bodies part (possible only with allowances above 1; left
    /// to a full evaluation).
    ///
    /// A lens (or a cap) scales the full evaluation's values by its exact law, from the ball's
    /// depth then and now: what the grid gives differs from the exact lens only by its
    /// discretisation error, which the scaling carries along. Other overlaps grow as if similar
    /// about their deepest point: the depth `D = d / rate` follows the approach one to one, `d`
    /// and `V` in proportion to `D` and `D^p`.
    fn grown<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        shapes: (&A, &B),
        relative: &Pose,
        approach: Real,
    ) -> Option<(Real, Real, Real)> {
        if let Some(lens) = self.lens {
            let (then, now) = (lens.depth, lens.depth_at(shapes, relative, self.centres));
            if !(now > 0.0 && then > 0.0) {
                return None;
            }
            let ((v0, a0), (v1, a1)) =
                (lens_measures(lens.radii, then), lens_measures(lens.radii, now));
            return Some((
                self.volume * (v1 / v0),
                self.indentation + (now - then),
                self.surface_area * (a1 / a0),
            ));
        }
        let ratio = 1.0 + approach * self.depth_rate / self.indentation;
        if !(ratio > 0.0) {
            return None;
        }
        let p = self.exponent;
        Some((
            self.volume * ratio.powf(p),
            self.indentation * ratio,
            self.surface_area * ratio.powf(p - 1.0),
        ))
    }

    /// The first-order effect of a tilt on an overlap between two nearly parallel surfaces
    /// (`None` for others, or without a footprint): `turned`, how far the bodies' summed
    /// distance gradients at the contact point turned since this reference, is the change of
    /// the overlap's depth gradient across the contact plane (its in-plane part `t`: the depth
    /// at an in-plane offset `u` from the centroid changes by `−t·u`); `approach` is the
    /// approach at the contact point ([`material_shift`](Self::material_shift)).
    ///
    /// Over the footprint (area `A`, centroid `c`, second moment `J₀`), which stays put for a
    /// face on a face, the centroid moves by `(δa S₁ − J t)/V` and the volume changes by
    /// `−t·S₁`, with `S₁ = A (c − x_c)`, `J = J₀ + A (c − x_c)(c − x_c)ᵀ` about the centroid
    /// `x_c` and `δa` the approach there. Exact to first order in the tilt for a face on a
    /// face; where faces meet at a small angle the footprint ends where the depth does, so its
    /// change is of second order too; round bodies rolling on each other do not turn their
    /// gradients (no change). The surfaces count as nearly parallel while the in-plane part of
    /// the gradient sum at the reference is at most [`PARALLEL`]; between an edge or a corner
    /// and a face it is no depth gradient (the gradient inside a body near its edge is a
    /// face's normal).
    fn tilted(&self, turned: Vector, approach: Real) -> Option<Tilt> {
        if !self.parallel() {
            return None;
        }
        let f = self.footprint?;
        let (t, offset) = (self.in_plane(turned), self.in_plane(f.centroid - self.contact_point));
        let s1 = offset * f.area;
        let j_t = f.spread * t + offset * (f.area * offset.dot(t));
        Some(Tilt { volume: -t.dot(s1), shift: self.in_plane(s1 * approach - j_t) / self.volume })
    }

    /// The first-order effect of A's motion on an overlap the footprint does not cover (an edge
    /// or a corner in it, surfaces at an angle; `None` without a flux), by Reynolds' transport
    /// over A's surface within B ([`Flux`]): A moves by `shift` at the contact point (a ball by
    /// its centre's move, its own turning moves no surface) and turns by `turn` (rad). The
    /// volume's change beyond the approach's, which the volume law follows, and the centroid's
    /// move as the shift from `moved`, the contact point as
    /// [`moved_contact_point`](Self::moved_contact_point) moves it.
    fn swept(&self, shift: Vector, turn: Vector, moved: Vector) -> Option<Tilt> {
        let f = self.flux?;
        let (volume, moment) = f.swept(shift + turn.cross(f.origin - self.contact_point), turn);
        let approach = shift.dot(self.normal) * self.normal.dot(f.area);
        Some(Tilt {
            volume: volume - approach,
            shift: self.contact_point + moment / self.volume - moved,
        })
    }

    /// How far the bodies' summed distance gradients turned at the contact point under A's
    /// `motion` since this reference (A now at `relative`), with the moved contact point (B's
    /// frame) and the gradients there, each from the part of its body's surface it came from
    /// at the reference ([`features`](Self::features)).
    fn turn<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        shapes: (&A, &B),
        relative: &Pose,
        motion: &Pose,
    ) -> (Vector, Vector, [Vector; 2]) {
        let contact_point = self.moved_contact_point(motion);
        let gradients =
            [0, 1].map(|s| gradient_on(shapes, relative, s, self.features[s], contact_point));
        let turned = (gradients[0] + gradients[1]) - (self.gradients[0] + self.gradients[1]);
        (turned, contact_point, gradients)
    }

    /// How far A's `motion` moved its material at the contact point (B's frame, m). Its part
    /// along the normal into B, `−shift·n`, is the approach: to first order the change of the
    /// local indentation, whatever the shapes — a face turned about A's centre approaches by
    /// its turn times the lever, a ball rolling or spinning on another does not approach it,
    /// and a body on a long one (a plank, a wall) approaches along the normal where it rests,
    /// not along the line of the centres.
    fn material_shift(&self, motion: &Pose) -> Vector {
        motion.transform_point(self.contact_point) - self.contact_point
    }

    /// Whether the surfaces at the contact point are nearly parallel (the in-plane part of the
    /// summed gradients at most [`PARALLEL`]).
    fn parallel(&self) -> bool {
        self.in_plane(self.gradients[0] + self.gradients[1]).length() <= PARALLEL
    }

    /// The part of `v` in the contact plane (normal to [`normal`](Self::normal)).
    fn in_plane(&self, v: Vector) -> Vector {
        v - self.normal * self.normal.dot(v)
    }

    /// A's pose in B's frame (for A now at `relative`) and B's pose (now `pose_b`), each
    /// body of revolution ([`Sdf::revolution_axis`]) turned back about its own axis by as much
    /// as it turned about it since this reference; `None` where neither turned so. Such a body
    /// is the same body after any turn about its axis, so the pair is the same pair, and the
    /// turn is no motion for an update: a cylinder spinning on its side does not lift off it,
    /// and one rolling on it slides as far. A body's turn since the reference is split into its
    /// twist about the axis and the rest (swing–twist); the twist is taken back.
    pub(super) fn representative<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        (a, b): (&A, &B),
        relative: &Pose,
        pose_b: &Pose,
    ) -> Option<(Pose, Pose)> {
        let (mut relative, mut pose_b, mut turned) = (*relative, *pose_b, false);
        if let Some(twist) = a.revolution_axis().and_then(|axis| {
            // A's turn in its own frame since the reference.
            twist_about(self.relative.rotation.inverse() * relative.rotation, axis)
        }) {
            relative *= twist.inverse();
            turned = true;
        }
        if let Some(twist) = b.revolution_axis().and_then(|axis| {
            // A's turn in B's frame since the reference: B's own turn about its axis shows
            // here as the inverse turn about it.
            twist_about(relative.rotation * self.relative.rotation.inverse(), axis)
        }) {
            relative = twist.inverse() * relative;
            pose_b *= twist;
            turned = true;
        }
        turned.then_some((relative, pose_b))
    }

    /// A's motion in B's frame since this reference, for A now at `relative`.
    fn motion_since(&self, relative: &Pose) -> Pose {
        *relative * self.relative.inverse()
    }

    /// A's bounding-sphere centre at this reference (B's frame) and its displacement by
    /// `motion`.
    fn centre_a(&self, motion: &Pose) -> (Vector, Vector) {
        let then = self.relative.transform_point(self.centres[0]);
        (then, motion.transform_point(then) - then)
    }

    /// The contact point (B's frame) after A's `motion`, moved as between two balls about
    /// the bodies' centres: by `R_B / (R_A + R_B)` of A's centre's displacement (all of it
    /// against a flat B), or turned with A about B's centre under a flat A. Exact for two
    /// balls and a ball on a plane (whether it slides, rolls or spins); for other shapes an
    /// estimate within the allowances.
    fn moved_contact_point(&self, motion: &Pose) -> Vector {
        let [r_a, r_b] = self.radii;
        let (x, centre_b) = (self.contact_point, self.centres[1]);
        let (_, moved_a) = self.centre_a(motion);
        if !r_a.is_finite() {
            centre_b + motion.rotation * (x - centre_b)
        } else if !r_b.is_finite() {
            x + moved_a
        } else {
            x + moved_a * (r_b / (r_a + r_b))
        }
    }
}

/// The turn about the axis `(point, unit direction)` that is the twist of `turn` about the
/// direction (`turn` = swing · twist, the swing about an axis normal to it); `None` where
/// `turn` has no twist (or no defined one: a half turn about a normal axis).
fn twist_about(turn: Rotation, (point, axis): (Vector, Vector)) -> Option<Pose> {
    let along = Vector::new(turn.x, turn.y, turn.z).dot(axis);
    if along == 0.0 {
        return None;
    }
    let twist = Rotation::from_xyzw(axis.x * along, axis.y * along, axis.z * along, turn.w);
    let norm = twist.length();
    if !(norm > 1e-12) {
        return None;
    }
    let twist = twist / norm;
    Some(Pose::from_parts(point - twist * point, twist))
}

/// How much a tilt counts against the normal allowance, as the change of depth `|t| reach` it
/// makes across the overlap, where an update follows it. An update moves the centroid and the
/// volume as a tilt does to first order (by the footprint between nearly parallel surfaces,
/// [`Reference::tilted`], else by A's flux, [`Reference::swept`]: the restoring torque of a
/// rocking body follows the rocking), so what it misses grows with the tilt's square; this
/// weight lets through the tilt at which an update misses as much of the force as the volume
/// law does at the approach's own limit (a few per cent at the default reuse; the test
/// `geometry_reuse_bounds_a_tilt_by_its_error` holds it to that).
const TILT_WEIGHT: Real = 0.5;

/// [`TILT_WEIGHT`] where an update cannot follow the tilt (an overlap with neither a footprint
/// nor a flux: counting): the centroid stays, so the restoring torque lags the rocking unless
/// the tilt is held smaller.
const FROZEN_TILT: Real = 8.0;

/// Largest angle (rad, as the in-plane part of the summed gradients) between two surfaces
/// whose tilt an update follows ([`Reference::tilted`]).
const PARALLEL: Real = 0.1;

/// Relative change of the indentation, `|ln(d₁/d₀)|`, below which two full evaluations are too
/// close to measure the volume law by their secants (the last law is kept).
const MIN_LOG_INDENTATION_STEP: Real = 0.05;

/// The volume law at the full evaluation `g`: the exponent `p` of `V ∝ d^p`, within [1, 3] (a
/// punch's 1, a cap's or an edge's 2, a corner's 3), and the indentation's rate against the
/// approach at the contact point since `previous` (`approach`, see
/// [`Reference::material_shift`]), `dd/dδ` within [0.05, 1] (1 where the deepest point lies
/// under the centroid, as for caps and punches; less for a tilted corner). Both are secants
/// from the `previous` full evaluation of the same contact where the indentation
/// changed enough between them, else the previous law; at first touch the overlap's shape
/// measure [`volume_exponent`](crate::force::volume_exponent) and the rate that makes the
/// law's first-order change A's flux's ([`OverlapGeometry::flux`]; 1 without one).
fn volume_law(
    previous: Option<&Reference>,
    approach: impl FnOnce(&Reference) -> Real,
    g: &OverlapGeometry,
) -> (Real, Real) {
    let Some(r) = previous else {
        let exponent =
            crate::force::volume_exponent(g.volume, g.indentation, g.surface_area).clamp(1.0, 3.0);
        // The law's first-order change under an approach, `p V rate / d`, is the area A's
        // surface sweeps across the normal, `−n·S` (A's flux): 1 for a cap, 2/3 for a wedge,
        // whose depth through the centroid is 2/3 of its deepest.
        let rate =
            g.flux.map_or(1.0, |f| -g.normal.dot(f.area) * g.indentation / (exponent * g.volume));
        return (exponent, if rate.is_finite() { rate.clamp(0.05, 1.0) } else { 1.0 });
    };
    let step = (g.indentation / r.indentation).ln();
    let exponent = (g.volume / r.volume).ln() / step;
    let rate = (g.indentation - r.indentation) / approach(r);
    if step.abs() >= MIN_LOG_INDENTATION_STEP && exponent.is_finite() && rate.is_finite() {
        (exponent.clamp(1.0, 3.0), rate.clamp(0.05, 1.0))
    } else {
        (r.exponent, r.depth_rate)
    }
}

/// A tilt's first-order effect on an updated overlap (see [`Reference::tilted`]).
struct Tilt {
    /// Change of the volume beyond the approach's (m³).
    volume: Real,
    /// The centroid's move (B's frame, m).
    shift: Vector,
}

impl Reference {
    /// What the updates until the next full evaluation start from, after the full evaluation
    /// `g` (see [`ContactModel::with_geometry_reuse`](super::ContactModel::with_geometry_reuse) for the allowances).
    pub(super) fn new<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        settings: &OverlapSettings,
        relative: Pose,
        previous: Option<&Reference>,
        a: &BodyState<'_, A>,
        b: &BodyState<'_, B>,
        g: &OverlapGeometry,
    ) -> Self {
        let sides = g.corrected_box.maxs - g.corrected_box.mins;
        let reach = sides.length();
        let (exponent, depth_rate) = volume_law(
            previous,
            |r| {
                let now = r.representative((a.shape, b.shape), &relative, &b.pose);
                -r.material_shift(&r.motion_since(&now.map_or(relative, |(p, _)| p))).dot(r.normal)
            },
            g,
        );
        let contact_point = b.pose.inverse_transform_point(g.contact_point);
        let normal = b.pose.rotation.inverse() * g.normal;
        // Each body's bounding-sphere centre (its own frame), and its distance from the contact
        // point; infinite for an unbounded body.
        let (sphere_a, sphere_b) = (a.shape.bounding_sphere(), b.shape.bounding_sphere());
        let radius = |(_, r): (Vector, Real), in_b: Vector| {
            if r.is_finite() {
                (in_b - contact_point).length()
            } else {
                Real::INFINITY
            }
        };
        let (mut r_a, mut r_b) =
            (radius(sphere_a, relative.transform_point(sphere_a.0)), radius(sphere_b, sphere_b.0));
        let gradients = surface_gradients((a.shape, b.shape), &relative, contact_point);
        let in_a = relative.inverse_transform_point(contact_point);
        let features = [
            Feature::at(a.shape, in_a, relative.rotation.inverse() * gradients[0]),
            Feature::at(b.shape, contact_point, gradients[1]),
        ];
        // A body flat at the contact (a face) under a curved one: the contact point moves as
        // against a half-space, with the curved body (a ball sliding or rolling on a face
        // takes it along; a face moving over a ball leaves it at the ball).
        match flat_at((a.shape, b.shape), &relative, contact_point, normal, 0.5 * reach, gradients)
        {
            [false, true] => r_b = Real::INFINITY,
            [true, false] => r_a = Real::INFINITY,
            _ => {}
        }
        let centres = [sphere_a.0, sphere_b.0];
        // A ball against a ball or a flat body: a lens, or a cap, of the ball's depth alone.
        let enlargement = settings.enlargement();
        let [eps_a, eps_b] = enlargement;
        let radii = match (a.shape.sphere_radius(), b.shape.sphere_radius()) {
            (Some(ra), Some(rb)) => Some([ra + eps_a, rb + eps_b]),
            (Some(ra), None) if !r_b.is_finite() => Some([ra + eps_a, Real::INFINITY]),
            (None, Some(rb)) if !r_a.is_finite() => Some([Real::INFINITY, rb + eps_b]),
            _ => None,
        };
        let lens = radii.map(|radii| {
            let mut lens = Lens { radii, enlargement, depth: 0.0, glide: 0.0 };
            lens.depth = lens.depth_at((a.shape, b.shape), &relative, centres);
            // The flat body of a cap: the one whose radius is infinite.
            let flat = radii.iter().position(|r| !r.is_finite());
            lens.glide = flat.map_or(0.0, |s| {
                glide((a.shape, b.shape), &relative, (contact_point, normal), reach, gradients, s)
            });
            lens
        });
        Reference {
            lens,
            relative,
            contact_point,
            normal,
            gradients,
            features,
            centres,
            radii: [r_a, r_b],
            volume: g.volume,
            indentation: g.indentation,
            surface_area: g.surface_area,
            exponent,
            depth_rate,
            reach,
            lever: r_a.min(r_b).max(reach),
            cell: sides.max_element() / settings.n_c() as Real,
            footprint: g.footprint.map(|f| f.transformed(&b.pose.inverse())),
            flux: g.flux.map(|f| f.transformed(&b.pose.inverse())),
        }
    }
}
