//! A pair of bodies placed in one body's frame: each body's SDF moved there (`Placed`), the
//! pair's distances and crossings (`Pair`), and the root finding on a segment (`crossing`).

use parry3d_f64::bounding_volume::Aabb;

use crate::math::{Matrix, Real, Vector};
use crate::shape::Sdf;

/// A body's SDF placed in the pair's frame (A's or B's body frame): `d(x) = sdf(R^T (x - t)) - ε`.
pub(crate) struct Placed<'a, S: ?Sized> {
    pub(super) shape: &'a S,
    pub(super) rot: Matrix,
    pub(super) rot_t: Matrix,
    pub(super) origin: Vector,
    pub(super) eps: Real,
}

impl<S: Sdf + ?Sized> Placed<'_, S> {
    #[inline]
    pub(super) fn distance(&self, x: Vector) -> Real {
        self.shape.distance(self.rot_t * (x - self.origin)) - self.eps
    }

    pub(super) fn gradient(&self, x: Vector) -> Vector {
        self.rot * self.shape.gradient(self.rot_t * (x - self.origin))
    }

    /// Distance and gradient at `x` in one call ([`Sdf::distance_and_gradient`]).
    pub(super) fn distance_and_gradient(&self, x: Vector) -> (Real, Vector) {
        let (d, g) = self.shape.distance_and_gradient(self.rot_t * (x - self.origin));
        (d - self.eps, self.rot * g)
    }

    /// [`Sdf::has_edges`] of the shape.
    pub(super) fn has_edges(&self) -> bool {
        self.shape.has_edges()
    }

    /// Whether the body is smooth and curved everywhere: no edge ([`Sdf::has_edges`]) and not
    /// a half-space (a ball, a capsule, either enlarged).
    pub(super) fn is_smooth_and_curved(&self) -> bool {
        !self.shape.has_edges() && self.shape.half_space_normal().is_none()
    }

    /// The shape's closed-form crossing of the segment from `inside` to `outside`, as the
    /// fraction from `inside` ([`Sdf::segment_crossing`]).
    pub(super) fn segment_crossing(&self, inside: Vector, outside: Vector) -> Option<Real> {
        self.shape.segment_crossing(
            self.rot_t * (inside - self.origin),
            self.rot_t * (outside - self.origin),
            self.eps,
        )
    }

    /// The body's face planes `(n, h)` in the pair's frame (`n·x <= h` inside), moved out by `ε`.
    /// A plane given with a non-unit normal is scaled to a unit one (the same half-space; the
    /// enlargement and the chord need the unit form); a zero or non-finite one gives `None`,
    /// and the pair goes to the grid.
    pub(super) fn planes(&self) -> Option<Vec<(Vector, Real)>> {
        self.placed(self.shape.face_planes()?)
    }

    /// `planes` given in the body's frame, in the pair's frame as [`planes`](Self::planes) puts
    /// them.
    pub(super) fn placed(&self, planes: Vec<(Vector, Real)>) -> Option<Vec<(Vector, Real)>> {
        planes
            .into_iter()
            .map(|(n, h)| {
                let len = n.length();
                (len > 0.0 && len.is_finite() && h.is_finite()).then(|| {
                    let n = self.rot * (n / len);
                    (n, h / len + n.dot(self.origin) + self.eps)
                })
            })
            .collect()
    }

    /// The body's face planes in the pair's frame when they bound exactly the body its SDF
    /// describes: a polyhedron without enlargement (an enlarged one has rounded edges).
    pub(super) fn exact_planes(&self) -> Option<Vec<(Vector, Real)>> {
        if self.eps == 0.0 {
            self.planes()
        } else {
            None
        }
    }

    /// The body's flat faces in the pair's frame, which with its
    /// [`smooth_part`](Self::smooth_part) bound exactly the body its SDF describes. Without
    /// enlargement those of [`Sdf::flat_faces`] (a cylinder's caps). Enlarged by `ε`, a body
    /// with face planes or flat faces is rounded along its edges and corners, and its faces,
    /// moved out by `ε`, are the flat parts of its surface: they are its flat faces, and the
    /// whole enlarged body is its smooth part.
    pub(super) fn exact_flat_faces(&self) -> Option<Vec<(Vector, Real)>> {
        if self.eps == 0.0 {
            self.placed(self.shape.flat_faces()?)
        } else {
            self.placed(crate::shape::flat_parts(self.shape)?)
        }
    }

    /// Distance and gradient at `x` of the body's smooth part, the convex body its
    /// [`exact_flat_faces`](Self::exact_flat_faces) cut down to it: without enlargement
    /// [`Sdf::smooth_part`], enlarged the enlarged body itself.
    pub(super) fn smooth_part(&self, x: Vector) -> (Real, Vector) {
        let local = self.rot_t * (x - self.origin);
        let (d, g) = if self.eps == 0.0 {
            self.shape.smooth_part(local)
        } else {
            self.shape.distance_and_gradient(local)
        };
        (d - self.eps, self.rot * g)
    }

    /// Whether the body is convex ([`Sdf::is_convex`]).
    pub(super) fn is_convex(&self) -> bool {
        self.shape.is_convex()
    }

    /// Whether the plane `n·x <= h` (pair frame) holds the body within `region` (pair frame;
    /// [`Sdf::holds_within`], enlarged by `ε`: the plane moved out by it).
    pub(super) fn holds_within(&self, n: Vector, h: Real, region: &Aabb) -> bool {
        let (lo, hi) = (region.mins - self.origin, region.maxs - self.origin);
        let (mut mins, mut maxs) =
            (Vector::splat(Real::INFINITY), Vector::splat(Real::NEG_INFINITY));
        for c in 0..8 {
            let corner = Vector::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            );
            let local = self.rot_t * corner;
            (mins, maxs) = (mins.min(local), maxs.max(local));
        }
        let local_n = self.rot_t * n;
        let local_h = h - n.dot(self.origin) - self.eps * n.length();
        self.shape.holds_within(local_n, local_h, &Aabb::new(mins, maxs))
    }

    /// The shape's bounds in the pair's frame, enlarged by `ε`; infinite components stay infinite.
    pub(super) fn bounds(&self) -> Aabb {
        let b = self.shape.local_bounds();
        let mut mins = self.origin - Vector::splat(self.eps);
        let mut maxs = self.origin + Vector::splat(self.eps);
        for j in 0..3 {
            let row = self.rot.row(j);
            for k in 0..3 {
                // A zero entry contributes nothing, also for an infinite extent (round-off in
                // a rotation must not make a half-space's bounded side unbounded).
                let infinite = !(b.mins[k].is_finite() && b.maxs[k].is_finite());
                if row[k].abs() > if infinite { 1e-12 } else { 0.0 } {
                    let (u, v) = (row[k] * b.mins[k], row[k] * b.maxs[k]);
                    mins[j] += u.min(v);
                    maxs[j] += u.max(v);
                }
            }
        }
        Aabb::new(mins, maxs)
    }
}

/// The pair in one body's frame (A's or B's, see [`compute_overlap`](super::compute_overlap)); `phi = max(d_A, d_B)`
/// is negative inside the overlap.
pub(crate) struct Pair<'a, A: ?Sized, B: ?Sized> {
    pub(super) a: Placed<'a, A>,
    pub(super) b: Placed<'a, B>,
    /// Whether smooth bodies' facets carry the layer to their surface
    /// ([`OverlapSettings::with_facet_bulge`](super::OverlapSettings::with_facet_bulge)).
    pub(super) facet_bulge: bool,
}

impl<A: Sdf + ?Sized, B: Sdf + ?Sized> Pair<'_, A, B> {
    #[inline]
    pub(super) fn both(&self, x: Vector) -> (Real, Real) {
        (self.a.distance(x), self.b.distance(x))
    }

    #[inline]
    pub(super) fn phi(&self, x: Vector) -> Real {
        let (a, b) = self.both(x);
        a.max(b)
    }

    /// Distance from `origin` (inside the overlap) along unit `dir` to the overlap's boundary.
    pub(super) fn exit_distance(&self, origin: Vector, dir: Vector, t_max: Real) -> Real {
        let f = |t: Real| self.phi(origin + dir * t);
        let f0 = f(0.0);
        if f0 >= 0.0 {
            return 0.0;
        }
        let (mut lo, mut flo) = (0.0, f0);
        let (mut hi, mut fhi) = (t_max, f(t_max));
        let mut grow = 0;
        while fhi < 0.0 && grow < 60 {
            (lo, flo) = (hi, fhi);
            hi *= 2.0;
            fhi = f(hi);
            grow += 1;
        }
        if fhi < 0.0 {
            return hi;
        }
        crossing(f, (lo, flo), (hi, fhi), 1e-12 * t_max, 0.0)
    }

    /// Unit normal from the SDF gradients at `x`: `∇d_B - ∇d_A`, B→A.
    pub(super) fn gradient_normal(&self, x: Vector) -> Vector {
        (self.b.gradient(x) - self.a.gradient(x)).normalize_or_zero()
    }
}

/// Root of `f` between `a` and `b` (values of opposite sign, or one zero) by Illinois regula
/// falsi with a bisection every fourth step: superlinear, always bracketed, never stalls.
/// Stops when the bracket is narrower than `tol` or `|f| <= f_tol` (for a distance function,
/// the point is then within `f_tol` of the surface).
pub(crate) fn crossing(
    f: impl Fn(Real) -> Real,
    a: (Real, Real),
    b: (Real, Real),
    tol: Real,
    f_tol: Real,
) -> Real {
    let ((mut ta, mut fa), (mut tb, mut fb)) = (a, b);
    if fa == 0.0 {
        return ta;
    }
    if fb == 0.0 {
        return tb;
    }
    let mut side = 0i8;
    for it in 0..200 {
        let t = (ta * fb - tb * fa) / (fb - fa);
        let inside = if ta < tb { t > ta && t < tb } else { t > tb && t < ta };
        let t = if inside && it % 4 != 3 { t } else { 0.5 * (ta + tb) };
        let ft = f(t);
        if ft.abs() <= f_tol {
            return t;
        }
        if (ft > 0.0) == (fa > 0.0) {
            (ta, fa) = (t, ft);
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            (tb, fb) = (t, ft);
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
        if (tb - ta).abs() <= tol {
            break;
        }
    }
    0.5 * (ta + tb)
}
