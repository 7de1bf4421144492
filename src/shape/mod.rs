//! Convex shapes as signed distance functions (SDFs).
//!
//! Every shape is evaluated in its own body frame: [`Sdf::distance`] is negative inside, positive
//! outside, and its magnitude is the Euclidean distance to the surface on *both* sides (an exact
//! SDF). The overlap geometry relies on this: `max(d_A, d_B)` is then a 1-Lipschitz lower bound
//! of the distance to the overlap region, so sphere tracing never steps through it.
//!
//! Built-in shapes ([`ConvexShape`]) have closed-form distances and gradients; parry shapes are
//! converted with [`ConvexShape::from_parry`]; any other convex body is a user closure
//! ([`ConvexShape::custom`]).

use parry3d_f64::bounding_volume::Aabb;

use crate::math::{Real, Vector};

mod convex;
mod custom;
mod mesh;
mod parry;
#[cfg(feature = "rapier-f32")]
pub use parry::widen_f32;
mod polyhedron;

pub use convex::ConvexShape;
pub use custom::CustomSdf;
pub use mesh::MeshSdf;
pub use polyhedron::PolyhedronSdf;

/// Where `shape` is flat: its [`face_planes`](Sdf::face_planes) when it is a polyhedron, else
/// its [`flat_faces`](Sdf::flat_faces) (a cylinder's caps); `None` for a body with neither. The
/// body dilated by a radius (rounded, or enlarged for contact) is flat on these planes moved out
/// by the radius, and rounded elsewhere.
pub(crate) fn flat_parts<S: Sdf + ?Sized>(shape: &S) -> Option<Vec<(Vector, Real)>> {
    shape.face_planes().or_else(|| shape.flat_faces())
}

/// A signed distance function of a convex body, in the body's own frame.
pub trait Sdf: Send + Sync {
    /// Signed distance from `p` (body frame) to the surface: negative inside.
    fn distance(&self, p: Vector) -> Real;

    /// The distance and the gradient at `p` together: what a caller that needs both asks, so a
    /// shape that finds both in one pass (a polyhedron's nearest feature) computes it once. The
    /// default calls [`distance`](Self::distance) and [`gradient`](Self::gradient).
    fn distance_and_gradient(&self, p: Vector) -> (Real, Vector) {
        (self.distance(p), self.gradient(p))
    }

    /// Outward unit gradient of the distance at `p` (body frame).
    ///
    /// The default uses central differences with a step of `1e-7` times the body's size.
    fn gradient(&self, p: Vector) -> Vector {
        let b = self.local_bounds();
        let size = (b.maxs - b.mins).min_element();
        let h = if size.is_finite() && size > 0.0 {
            1e-7 * size
        } else {
            1e-7 * (1.0 + p.abs().max_element())
        };
        let g = Vector::new(
            self.distance(p + Vector::X * h) - self.distance(p - Vector::X * h),
            self.distance(p + Vector::Y * h) - self.distance(p - Vector::Y * h),
            self.distance(p + Vector::Z * h) - self.distance(p - Vector::Z * h),
        );
        g.normalize_or_zero()
    }

    /// Bounding box of the body in its frame; components may be infinite (a half-space).
    fn local_bounds(&self) -> Aabb;

    /// A sphere `(centre, radius)` enclosing the body, in its frame; the radius is infinite
    /// for an unbounded body. The default encloses [`local_bounds`](Self::local_bounds) (its
    /// half diagonal, √3 times a ball's radius); the built-in shapes give a tighter one (a
    /// ball's own), which keeps contact candidates and sub-step estimates to the pairs that
    /// can touch.
    fn bounding_sphere(&self) -> (Vector, Real) {
        box_sphere(&self.local_bounds())
    }

    /// Where the surface dilated by `offset` — the zero level of `distance − offset` — crosses
    /// the segment `p`–`q` (body frame), as the fraction `t ∈ [0, 1]` of the way from `p`, for
    /// shapes that know it in closed form. Called only when `p` lies strictly inside
    /// (`distance(p) < offset`) and `q` strictly outside: the caller knows which end is which,
    /// so the shape need not evaluate its distance to find out. `None` (the default) lets the
    /// caller find the crossing by root finding on [`distance`](Self::distance).
    fn segment_crossing(&self, p: Vector, q: Vector, offset: Real) -> Option<Real> {
        let _ = (p, q, offset);
        None
    }

    /// The radius, when the body is a sphere about its frame's origin (for the closed-form
    /// overlap of [`OverlapSettings::with_closed_form_spheres`](crate::OverlapSettings::with_closed_form_spheres));
    /// `None` (the default) otherwise.
    fn sphere_radius(&self) -> Option<Real> {
        None
    }

    /// The face planes `(n, h)` — outward normal and offset, `n·p <= h` inside — when the
    /// body is the intersection of finitely many half-spaces (for the exact overlap of
    /// [`OverlapSettings::with_exact_polyhedra`](crate::OverlapSettings::with_exact_polyhedra),
    /// and on the sub-cell grid, whose cells such a body clips by the faces that cut them, moved
    /// out by the contact enlargement where there is one); `None` (the default) otherwise. The
    /// planes must bound exactly the body [`distance`](Self::distance) describes. The normal
    /// need not be unit (the overlap scales `n` and `h` together); a zero or non-finite plane
    /// sends the pair to the `N_c` grid instead.
    fn face_planes(&self) -> Option<Vec<(Vector, Real)>> {
        None
    }

    /// The axis `(point, unit direction)` (body frame) when the body is a body of revolution
    /// about it — a cylinder, a cone, a capsule, such a body rounded: every normal of its
    /// surface lies in a plane through the axis, so no pressure on the body has a moment about
    /// it, and the contact keeps its normal force so (see
    /// [`ContactModel::evaluate`](crate::ContactModel::evaluate)). `None` (the default)
    /// otherwise; a ball says [`sphere_radius`](Self::sphere_radius) instead.
    fn revolution_axis(&self) -> Option<(Vector, Vector)> {
        None
    }

    /// The planes `(n, h)` of the flat faces (`n·p <= h` inside), when the body is a smooth
    /// convex body — its [`smooth_part`](Self::smooth_part) — cut by finitely many half-spaces
    /// whose faces meet the smooth surface in edges: a cylinder's two caps. Also the flat parts
    /// of a rounded body (a polyhedron or a cylinder dilated by a radius: its faces moved out),
    /// which touch its rounded edges, the whole body being its smooth part. `None` (the
    /// default) otherwise; a polyhedron gives [`face_planes`](Self::face_planes) instead (where
    /// both are given, the face planes are used and these are not).
    ///
    /// On the sub-cell grid a cell such an edge passes through is clipped by the faces
    /// themselves and by the smooth part's tangent planes, which keep the edge sharp (or follow
    /// the rounding), instead of by the whole body's tangent planes at fifteen points, whose
    /// envelope bevels it at a cost of a dozen more planes per cell. The faces and the smooth
    /// part must bound exactly the body [`distance`](Self::distance) describes.
    fn flat_faces(&self) -> Option<Vec<(Vector, Real)>> {
        None
    }

    /// Signed distance and outward unit gradient at `p` of the body's smooth part: the body
    /// without its [`flat_faces`](Self::flat_faces) (for a cylinder, the infinite round
    /// cylinder; for a cone, the infinite cone; for a rounded body, the body itself). Asked
    /// only of bodies that have flat faces; the default is the body's own.
    ///
    /// Contract: the exact signed distance of a convex body that holds the whole body (so its
    /// tangent planes hold the body, as the clip needs), and which the flat faces cut down to
    /// exactly the body [`distance`](Self::distance) describes.
    fn smooth_part(&self, p: Vector) -> (Real, Vector) {
        self.distance_and_gradient(p)
    }

    /// The outward unit normal, when the body is the half-space `n·x <= 0` of its frame (for
    /// the same closed form); `None` (the default) otherwise.
    fn half_space_normal(&self) -> Option<Vector> {
        None
    }

    /// Whether the body is convex (`true`, the default: the shapes this crate is for). A body
    /// that is not (a mesh's solid side) is asked [`holds_within`](Self::holds_within) before
    /// a tangent plane cuts the overlap's box.
    fn is_convex(&self) -> bool {
        true
    }

    /// Whether the half-space `n·p <= h` (body frame) holds every part of the body that lies in
    /// `region` (body frame): the test a cutting plane through a nearest surface point must
    /// pass before the overlap's box is cut by it. Any tangent plane of a convex body holds the
    /// whole body, so the default is `true`; a body that is not convex (a mesh's solid side)
    /// answers for the part of it the region holds.
    fn holds_within(&self, n: Vector, h: Real, region: &Aabb) -> bool {
        let _ = (n, h, region);
        true
    }

    /// Whether the surface may have edges or corners. `true` (the default) unless it is smooth
    /// (a ball, a capsule) or flat (a half-space); `false` lets the sub-cell grid skip its test
    /// for cells an edge or a corner passes through, which then integrate better by the
    /// body's tangent planes than by interpolation (see
    /// [`IntegrationMode::Subcell`](crate::IntegrationMode::Subcell)).
    fn has_edges(&self) -> bool {
        true
    }
}

/// The sphere through the corners of `b` (`(centre, radius)`); radius infinite for an
/// unbounded box.
fn box_sphere(b: &Aabb) -> (Vector, Real) {
    if b.mins.is_finite() && b.maxs.is_finite() {
        ((b.mins + b.maxs) * 0.5, (b.maxs - b.mins).length() * 0.5)
    } else {
        (Vector::ZERO, Real::INFINITY)
    }
}
