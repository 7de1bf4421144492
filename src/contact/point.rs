//! Where a contact's normal force acts: the overlap's centroid moved onto a ball's line through
//! its centre, and into the plane of a body of revolution's axis and the normal.

use super::BodyState;
use crate::math::{Pose, Real, Vector};
use crate::overlap::OverlapGeometry;
use crate::shape::Sdf;

/// The geometry with a ball's normal force along the ball's own normal and through its
/// centre. Every normal of a sphere passes through its centre, so no pressure on it has a
/// torque about it; and the overlap of a ball with a face or another ball is symmetric about
/// the line from the other body's nearest point to the ball's centre, which is the other
/// body's distance gradient there (between two balls, the line of their centres) — with an
/// edge, about the plane through that line normal to the edge; at a corner that line is the
/// direction in which the ball's depth is measured.
/// The grid gives both to its discretisation error only, always to the same side of its cells:
/// a fraction of a per cent of a cell off the centre, and a normal tilted by a few millionths,
/// enough to roll a ball resting on a floor away, faster and faster. A ball's contact takes
/// that normal and the point on that line nearest to the grid's contact point.
pub(super) fn through_ball_centres<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    mut g: OverlapGeometry,
    a: &BodyState<'_, A>,
    b: &BodyState<'_, B>,
) -> OverlapGeometry {
    // The other body's distance gradient at `x` (world), out of it.
    fn outwards<S: Sdf + ?Sized>(body: &BodyState<'_, S>, x: Vector) -> Vector {
        body.pose.rotation * body.shape.gradient(body.pose.inverse_transform_point(x))
    }
    let (ball_a, ball_b) = (a.shape.sphere_radius().is_some(), b.shape.sphere_radius().is_some());
    let (centre, normal) = match (ball_a, ball_b) {
        (true, true) => (b.pose.translation, a.pose.translation - b.pose.translation),
        (true, false) => (a.pose.translation, outwards(b, a.pose.translation)),
        (false, true) => (b.pose.translation, -outwards(a, b.pose.translation)),
        (false, false) => return g,
    };
    let normal = normal.normalize_or_zero();
    if normal != Vector::ZERO && normal.is_finite() {
        g.normal = normal;
    }
    g.contact_point = centre + g.normal * g.normal.dot(g.contact_point - centre);
    g
}

/// The geometry with no moment of the normal force about the axis of a body of revolution
/// ([`Sdf::revolution_axis`]): every normal of such a body lies in a plane through its axis
/// (a cylinder's side and a capsule's pass through it, a cap's runs along it), so the pressure
/// on it has no moment about the axis. The grid's contact point lies off that plane by its
/// discretisation error, always to the same side of the grid's cells, and that moment would
/// roll a cylinder lying on a floor away, ever faster. The contact point moves across the
/// normal, by the least distance that puts it in the plane of the axis and the normal (in both
/// planes, for two such bodies; on their mean where the two are nearly parallel and disagree)
/// where the normal crosses the axis, and by less, as `sin²` of their angle, as the normal
/// turns along the axis: the pressure on a cap runs along the axis and has no moment about it
/// wherever it acts, and only the blended normal's small tilt from the axis would give the
/// point's offset one — while that offset, across a face rocking on a face, is what rights
/// it. Balls are left to [`through_ball_centres`]: a ball's line through its centre along the
/// other body's gradient lies in that body's plane too.
pub(super) fn about_no_axis<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    mut g: OverlapGeometry,
    a: &BodyState<'_, A>,
    b: &BodyState<'_, B>,
) -> OverlapGeometry {
    if a.shape.sphere_radius().is_some() || b.shape.sphere_radius().is_some() {
        return g;
    }
    let n = g.normal;
    // Per body with an axis not along the normal: the unit normal of the plane of its axis
    // and the contact normal, and how far the contact point is to move towards that plane —
    // all the way where the normal crosses the axis (a side), less as it turns along it
    // (`sin²` of their angle): on a cap the pressure runs along the axis, whatever the
    // blended normal's tilt, and a point off the plane has a moment only by that tilt.
    let plane = |axis: Option<(Vector, Vector)>, pose: &Pose| {
        let (point, direction) = axis?;
        let m = n.cross(pose.rotation * direction);
        let length = m.length();
        (length > AXIS_ALONG_NORMAL).then(|| {
            let off = (g.contact_point - pose.transform_point(point)).dot(m / length);
            (m / length, off * length * length)
        })
    };
    let shift = match (
        plane(a.shape.revolution_axis(), &a.pose),
        plane(b.shape.revolution_axis(), &b.pose),
    ) {
        (None, None) => return g,
        (Some((m, off)), None) | (None, Some((m, off))) => -m * off,
        (Some((m1, off1)), Some((m2, off2))) => {
            // The least shift in the span of m1 and m2 that zeroes both offsets.
            let (m2, off2) = if m1.dot(m2) < 0.0 { (-m2, -off2) } else { (m2, off2) };
            let c = m1.dot(m2);
            let det = 1.0 - c * c;
            if det < PARALLEL_AXES {
                -(m1 + m2).normalize_or_zero() * (0.5 * (off1 + off2))
            } else {
                let alpha = (-off1 + c * off2) / det;
                let beta = (-off2 + c * off1) / det;
                m1 * alpha + m2 * beta
            }
        }
    };
    if shift.is_finite() {
        g.contact_point += shift;
    }
    g
}

/// `|n × a|` below which a body's axis `a` counts as along the contact normal `n`
/// ([`about_no_axis`]): the normal force's moment about it is then nil (or the plane of the
/// two ill-defined), and the contact point stays.
const AXIS_ALONG_NORMAL: Real = 1e-6;

/// `1 − cos²` of the angle between two bodies' planes ([`about_no_axis`]) below which they
/// count as parallel: the contact point moves onto their mean.
const PARALLEL_AXES: Real = 1e-6;
