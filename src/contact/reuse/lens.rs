//! A ball's overlap with a ball or a flat body, whose update follows its exact law.

use crate::math::{Pose, Real, Vector};
use crate::shape::Sdf;

/// A ball's overlap with a ball or a flat body (a lens or a cap), as
/// [`Reference`](super::Reference) keeps it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct Lens {
    /// The bodies' radii (m, their enlargement included), A's then B's; infinite for a flat
    /// body. At least one is finite: the ball whose depth is measured.
    pub radii: [Real; 2],
    /// The enlargements (m), A's then B's.
    pub enlargement: [Real; 2],
    /// The ball's depth at the full evaluation (m): its radius less the other body's enlarged
    /// distance at its centre.
    pub depth: Real,
    /// How far a cap may travel over the flat body's face (m) with all of it staying on the
    /// face, where its exact law holds: 0 between two balls (whose lens no travel bounds) and
    /// where the face was not found to reach that far.
    #[cfg_attr(feature = "checkpoint", serde(default))]
    pub glide: Real,
}

impl Lens {
    /// How deep the ball (A's if A is one, else B's) reaches into the other body, A at
    /// `relative` in B's frame, `centres` the bodies' centres in their own frames: its radius
    /// less the other's enlarged distance at its centre — for two balls the radii's sum less
    /// the centres' distance, for a ball on a face the cap's height.
    pub(super) fn depth_at<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        (a, b): (&A, &B),
        relative: &Pose,
        centres: [Vector; 2],
    ) -> Real {
        let [eps_a, eps_b] = self.enlargement;
        if self.radii[0].is_finite() {
            self.radii[0] + eps_b - b.distance(relative.transform_point(centres[0]))
        } else {
            self.radii[1] + eps_a - a.distance(relative.inverse_transform_point(centres[1]))
        }
    }
}

/// How many times the approach allowance a lens's update may go
/// ([`Reference::grown`](super::Reference::grown)): it follows the lens's exact law, so its
/// error is the grid's discretisation error at the last full evaluation carried to another
/// depth.
pub(super) const LENS_ALLOWANCE: Real = 16.0;
