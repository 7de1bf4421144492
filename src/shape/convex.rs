//! The built-in convex shapes: closed-form distances, gradients, exits and crossings.

use std::sync::Arc;

use parry3d_f64::bounding_volume::Aabb;

use super::polyhedron::closest_on_segment;
use super::{box_sphere, CustomSdf, MeshSdf, PolyhedronSdf, Sdf};
use crate::error::{check_finite_vec, check_positive, Error, Result};
use crate::math::{Real, Vector};

/// The distance of `p` from the y axis and the unit vector away from it (`x` on the axis): a
/// round body's meridian coordinate `r` and the direction it grows in.
fn radial(p: Vector) -> (Real, Vector) {
    let r = (p.x * p.x + p.z * p.z).sqrt();
    (r, if r > 0.0 { Vector::new(p.x / r, 0.0, p.z / r) } else { Vector::X })
}

/// Exact 2D signed distance to a convex polygon given counter-clockwise, with its gradient.
fn polygon_sdf_2d(p: [Real; 2], poly: &[[Real; 2]]) -> (Real, [Real; 2]) {
    let n = poly.len();
    let mut inside_max = Real::NEG_INFINITY;
    let mut inside_grad = [0.0, 0.0];
    let mut best_out = Real::INFINITY;
    let mut out_grad = [0.0, 0.0];
    let mut outside = false;
    for i in 0..n {
        let a = poly[i];
        let b = poly[(i + 1) % n];
        let e = [b[0] - a[0], b[1] - a[1]];
        let len = (e[0] * e[0] + e[1] * e[1]).sqrt();
        let nrm = [e[1] / len, -e[0] / len]; // outward for CCW
        let w = [p[0] - a[0], p[1] - a[1]];
        let s = w[0] * nrm[0] + w[1] * nrm[1];
        if s > inside_max {
            inside_max = s;
            inside_grad = nrm;
        }
        if s > 0.0 {
            outside = true;
        }
        let t = ((w[0] * e[0] + w[1] * e[1]) / (len * len)).clamp(0.0, 1.0);
        let c = [w[0] - t * e[0], w[1] - t * e[1]];
        let d = (c[0] * c[0] + c[1] * c[1]).sqrt();
        if d < best_out {
            best_out = d;
            out_grad = if d > 0.0 { [c[0] / d, c[1] / d] } else { nrm };
        }
    }
    if outside {
        (best_out, out_grad)
    } else {
        (inside_max, inside_grad)
    }
}

/// A convex body with a closed-form (or user) signed distance function.
///
/// Cylinders and cones have their axis along the body's `y` axis, as in parry.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub enum ConvexShape {
    /// A sphere of the given radius about the origin.
    Ball {
        /// Radius (m).
        radius: Real,
    },
    /// A box with the given half extents.
    Cuboid {
        /// Half extents along x, y, z (m).
        half_extents: Vector,
    },
    /// A cylinder along `y`.
    Cylinder {
        /// Half the height (m).
        half_height: Real,
        /// Radius (m).
        radius: Real,
    },
    /// A cone along `y`, apex at `+half_height`.
    Cone {
        /// Half the height (m).
        half_height: Real,
        /// Base radius (m).
        radius: Real,
    },
    /// A capsule: all points within `radius` of the segment `a`–`b`.
    Capsule {
        /// First end of the segment (m).
        a: Vector,
        /// Second end of the segment (m).
        b: Vector,
        /// Radius (m).
        radius: Real,
    },
    /// A convex polyhedron.
    Polyhedron(Arc<PolyhedronSdf>),
    /// The inner shape dilated by a border radius (parry's `Round*` shapes).
    Rounded {
        /// The shape before rounding.
        inner: Box<ConvexShape>,
        /// The dilation (m).
        border_radius: Real,
    },
    /// The half-space below the plane through the origin with outward unit normal `normal`.
    HalfSpace {
        /// Outward unit normal.
        normal: Vector,
    },
    /// A user SDF (must be exact — Euclidean inside and outside — for the guarantees above).
    /// A closure: a state holding one cannot be checkpointed.
    #[cfg_attr(feature = "checkpoint", serde(skip))]
    Custom(CustomSdf),
    /// The solid side of a triangle mesh or height field ([`MeshSdf`]): not convex, so a wall
    /// only — the drop-in takes it on colliders whose bodies do not move under forces.
    Mesh(Arc<MeshSdf>),
}

/// The larger root of `|w + t v|² = r²` — where the line `w + t v` leaves the ball of radius
/// `r` about the origin — in the form without cancellation; `None` when the line misses it.
fn exit_root(w: Vector, v: Vector, r: Real) -> Option<Real> {
    let (a, b, c) = (v.length_squared(), w.dot(v), w.length_squared() - r * r);
    let disc = b * b - a * c;
    if !(a > 0.0 && disc >= 0.0) {
        return None;
    }
    // (-b + √D) / a, rewritten as -c / (b + √D) where b > 0 would cancel.
    Some(if b > 0.0 { -c / (b + disc.sqrt()) } else { (-b + disc.sqrt()) / a })
}

impl ConvexShape {
    /// For a point `p` inside the capsule `a`–`b` of radius `r`: the fraction of `d` after
    /// which `p + t d` leaves it. The squared distance to the segment is a convex, piecewise
    /// quadratic function of `t` — to the end `a`, to the line, to the end `b`, switching where
    /// the projection onto the line passes the ends — so the exit is the one root past 0 of
    /// the piece it falls in.
    fn capsule_exit(p: Vector, d: Vector, a: Vector, b: Vector, r: Real) -> Option<Real> {
        let axis = b - a;
        let l2 = axis.length_squared();
        // The exit from one piece's ball or cylinder, if it falls within the piece [lo, hi].
        let exit = |w: Vector, v: Vector, lo: Real, hi: Real| {
            exit_root(w, v, r).filter(|t| (lo..=hi).contains(t))
        };
        if l2 <= 0.0 {
            return exit(p - a, d, 0.0, Real::INFINITY);
        }
        // Projection parameter s(t) = s0 + t s1 along the axis.
        let (s0, s1) = ((p - a).dot(axis) / l2, d.dot(axis) / l2);
        // Pieces in t: where s < 0 (end a), 0 <= s <= 1 (line), s > 1 (end b).
        let cut = |s: Real| if s1 != 0.0 { (s - s0) / s1 } else { Real::NAN };
        let (t0, t1) = (cut(0.0), cut(1.0));
        let w_line = (p - a) - axis * s0;
        let v_line = d - axis * s1;
        let line = |lo: Real, hi: Real| exit(w_line, v_line, lo, hi);
        let end_a = |lo: Real, hi: Real| exit(p - a, d, lo, hi);
        let end_b = |lo: Real, hi: Real| exit(p - b, d, lo, hi);
        let pieces: [(Real, Real, u8); 3] = if s1 > 0.0 {
            [(Real::NEG_INFINITY, t0, 0), (t0, t1, 1), (t1, Real::INFINITY, 2)]
        } else if s1 < 0.0 {
            [(Real::NEG_INFINITY, t1, 2), (t1, t0, 1), (t0, Real::INFINITY, 0)]
        } else {
            let which = if s0 < 0.0 {
                0
            } else if s0 > 1.0 {
                2
            } else {
                1
            };
            [(Real::NEG_INFINITY, Real::INFINITY, which); 3]
        };
        pieces.iter().find_map(|&(lo, hi, k)| {
            let lo = lo.max(0.0);
            if hi < lo {
                return None;
            }
            match k {
                0 => end_a(lo, hi),
                1 => line(lo, hi),
                _ => end_b(lo, hi),
            }
        })
    }

    /// For a point `p` inside the body dilated by `offset` (a ball or capsule), or inside the
    /// undilated cuboid, cylinder or polyhedron: the fraction of `d` after which `p + t d`
    /// leaves it (for the polytopes the smallest exit over their slabs).
    fn exit_along(&self, p: Vector, d: Vector, offset: Real) -> Option<Real> {
        // Leaving the slab `n·x <= h` (`n·d > 0`): t = (h - n·p) / (n·d).
        let slab = |n: Vector, h: Real| {
            let nd = n.dot(d);
            if nd > 0.0 {
                (h - n.dot(p)) / nd
            } else {
                Real::INFINITY
            }
        };
        let t = match self {
            Self::Ball { radius } => return exit_root(p, d, radius + offset),
            Self::Capsule { a, b, radius } => {
                return Self::capsule_exit(p, d, *a, *b, radius + offset)
            }
            Self::Cuboid { half_extents } => (0..3)
                .map(|j| {
                    slab(Vector::AXES[j], half_extents[j])
                        .min(slab(-Vector::AXES[j], half_extents[j]))
                })
                .fold(Real::INFINITY, Real::min),
            Self::Cylinder { half_height, radius } => {
                let caps = slab(Vector::Y, *half_height).min(slab(-Vector::Y, *half_height));
                // Round side: the exit from the disc of `radius` in the xz plane.
                let xz = |v: Vector| Vector::new(v.x, 0.0, v.z);
                caps.min(exit_root(xz(p), xz(d), *radius).unwrap_or(Real::INFINITY))
            }
            Self::Polyhedron(poly) => {
                poly.planes.iter().map(|&(n, h)| slab(n, h)).fold(Real::INFINITY, Real::min)
            }
            _ => return None,
        };
        t.is_finite().then_some(t)
    }

    /// A sphere; refuses a radius that is not finite and positive.
    pub fn ball(radius: Real) -> Result<Self> {
        Ok(Self::Ball { radius: check_positive("radius", radius)? })
    }

    /// A box with the given half extents.
    pub fn cuboid(half_extents: Vector) -> Result<Self> {
        for (name, v) in [
            ("half_extents.x", half_extents.x),
            ("half_extents.y", half_extents.y),
            ("half_extents.z", half_extents.z),
        ] {
            check_positive(name, v)?;
        }
        Ok(Self::Cuboid { half_extents })
    }

    /// A cylinder along `y`.
    pub fn cylinder(half_height: Real, radius: Real) -> Result<Self> {
        Ok(Self::Cylinder {
            half_height: check_positive("half_height", half_height)?,
            radius: check_positive("radius", radius)?,
        })
    }

    /// A cone along `y`.
    pub fn cone(half_height: Real, radius: Real) -> Result<Self> {
        Ok(Self::Cone {
            half_height: check_positive("half_height", half_height)?,
            radius: check_positive("radius", radius)?,
        })
    }

    /// A capsule around the segment `a`–`b`.
    pub fn capsule(a: Vector, b: Vector, radius: Real) -> Result<Self> {
        check_finite_vec("capsule end a", a)?;
        check_finite_vec("capsule end b", b)?;
        Ok(Self::Capsule { a, b, radius: check_positive("radius", radius)? })
    }

    /// The convex hull of `points`.
    pub fn convex_hull(points: &[Vector]) -> Result<Self> {
        Ok(Self::Polyhedron(Arc::new(PolyhedronSdf::from_points(points)?)))
    }

    /// `inner` dilated by `border_radius`.
    pub fn rounded(inner: ConvexShape, border_radius: Real) -> Result<Self> {
        Ok(Self::Rounded {
            inner: Box::new(inner),
            border_radius: check_positive("border_radius", border_radius)?,
        })
    }

    /// The half-space `{p : normal·p <= 0}`; `normal` is normalised.
    pub fn half_space(normal: Vector) -> Result<Self> {
        check_finite_vec("half-space normal", normal)?;
        let n = normal.try_normalize().ok_or(Error::InvalidParameter {
            name: "normal",
            value: normal.length(),
            allowed: "a non-zero vector",
        })?;
        Ok(Self::HalfSpace { normal: n })
    }

    /// A user SDF `f` (body frame, negative inside, exact) with the body's bounding box.
    pub fn custom(
        f: impl Fn(Vector) -> Real + Send + Sync + 'static,
        bounds: Aabb,
    ) -> Result<Self> {
        check_finite_vec("custom SDF bounds (mins)", bounds.mins)?;
        check_finite_vec("custom SDF bounds (maxs)", bounds.maxs)?;
        let w = bounds.maxs - bounds.mins;
        check_positive("custom SDF bounds width", w.min_element())?;
        Ok(Self::Custom(CustomSdf { f: Arc::new(f), bounds }))
    }

    /// Whether the body is unbounded (a half-space).
    pub fn is_unbounded(&self) -> bool {
        matches!(self, Self::HalfSpace { .. })
    }

    /// Distance and outward unit gradient, in closed form.
    pub fn distance_and_gradient(&self, p: Vector) -> (Real, Vector) {
        match self {
            Self::Ball { radius } => {
                let l = p.length();
                (l - radius, if l > 0.0 { p / l } else { Vector::Y })
            }
            Self::Cuboid { half_extents } => {
                let q = p.abs() - *half_extents;
                let qo = q.max(Vector::ZERO);
                let out = qo.length();
                if out > 0.0 {
                    (out, (qo * p.signum()) / out)
                } else {
                    let m = q.max_element();
                    let axis = if q.x == m {
                        Vector::X
                    } else if q.y == m {
                        Vector::Y
                    } else {
                        Vector::Z
                    };
                    (m, axis * p.signum())
                }
            }
            Self::Cylinder { half_height, radius } => {
                let (r, radial) = radial(p);
                let (qx, qy) = (r - radius, p.y.abs() - half_height);
                let axial = Vector::new(0.0, p.y.signum(), 0.0);
                let (ox, oy) = (qx.max(0.0), qy.max(0.0));
                let out = (ox * ox + oy * oy).sqrt();
                if out > 0.0 {
                    (out, (radial * ox + axial * oy) / out)
                } else if qx > qy {
                    (qx, radial)
                } else {
                    (qy, axial)
                }
            }
            Self::Cone { half_height, radius } => {
                let (r, radial) = radial(p);
                let tri = [[-radius, -half_height], [*radius, -half_height], [0.0, *half_height]];
                let (d, g) = polygon_sdf_2d([r, p.y], &tri);
                (d, radial * g[0] + Vector::Y * g[1])
            }
            Self::Capsule { a, b, radius } => {
                let q = closest_on_segment(p, *a, *b);
                let l = (p - q).length();
                (l - radius, if l > 0.0 { (p - q) / l } else { Vector::Y })
            }
            Self::Polyhedron(poly) => poly.distance_and_gradient(p),
            Self::Rounded { inner, border_radius } => {
                let (d, g) = inner.distance_and_gradient(p);
                (d - border_radius, g)
            }
            Self::HalfSpace { normal } => (normal.dot(p), *normal),
            Self::Custom(c) => (c.distance(p), c.gradient(p)),
            Self::Mesh(m) => m.distance_and_gradient(p),
        }
    }
}

impl ConvexShape {
    /// [`Sdf::distance`] of the shapes it does not inline.
    #[inline(never)]
    fn distance_out_of_line(&self, p: Vector) -> Real {
        match self {
            Self::Rounded { inner, border_radius } => inner.distance(p) - border_radius,
            Self::Custom(c) => c.distance(p),
            _ => self.distance_and_gradient(p).0,
        }
    }
}

impl Sdf for ConvexShape {
    /// The closed-form primitives (ball, cuboid, cylinder, half-space) inline into the caller —
    /// the lattice mapping calls this for every node a body may cover, and through a call into
    /// the whole match a ball's distance cost ~a fifth of the mapping; the composite and
    /// general shapes (rounded, custom, cone, capsule, polyhedron) out of line.
    #[inline(always)]
    fn distance(&self, p: Vector) -> Real {
        match self {
            Self::Ball { radius } => p.length() - radius,
            Self::Cuboid { half_extents } => {
                let q = p.abs() - *half_extents;
                q.max(Vector::ZERO).length() + q.max_element().min(0.0)
            }
            Self::Cylinder { half_height, radius } => {
                let r = (p.x * p.x + p.z * p.z).sqrt();
                let (qx, qy) = (r - radius, p.y.abs() - half_height);
                let (ox, oy) = (qx.max(0.0), qy.max(0.0));
                (ox * ox + oy * oy).sqrt() + qx.max(qy).min(0.0)
            }
            Self::HalfSpace { normal } => normal.dot(p),
            _ => self.distance_out_of_line(p),
        }
    }

    fn gradient(&self, p: Vector) -> Vector {
        self.distance_and_gradient(p).1
    }

    fn distance_and_gradient(&self, p: Vector) -> (Real, Vector) {
        ConvexShape::distance_and_gradient(self, p)
    }

    /// Closed forms, one evaluation instead of ~4–5 distance calls of root finding, and exact:
    /// the half-space (linear), the ball (a quadratic) and the capsule (piecewise quadratic)
    /// also dilated; the cuboid, the cylinder and the polyhedron undilated (`offset = 0`), as
    /// the exit of the segment from the intersection of their slabs (and the cylinder's round
    /// side), taken from the inside end `p`.
    fn segment_crossing(&self, p: Vector, q: Vector, offset: Real) -> Option<Real> {
        let e = q - p;
        let t = match self {
            Self::HalfSpace { normal } => (offset - normal.dot(p)) / normal.dot(e),
            Self::Ball { .. } | Self::Capsule { .. } => self.exit_along(p, e, offset)?,
            Self::Cuboid { .. } | Self::Cylinder { .. } | Self::Polyhedron(_) if offset == 0.0 => {
                self.exit_along(p, e, offset)?
            }
            _ => return None,
        };
        t.is_finite().then(|| t.clamp(0.0, 1.0))
    }

    fn sphere_radius(&self) -> Option<Real> {
        match self {
            Self::Ball { radius } => Some(*radius),
            _ => None,
        }
    }

    fn revolution_axis(&self) -> Option<(Vector, Vector)> {
        match self {
            Self::Cylinder { .. } | Self::Cone { .. } => Some((Vector::ZERO, Vector::Y)),
            Self::Capsule { a, b, .. } => {
                let d = (*b - *a).normalize_or_zero();
                (d != Vector::ZERO).then_some((*a, d))
            }
            Self::Rounded { inner, .. } => inner.revolution_axis(),
            _ => None,
        }
    }

    fn bounding_sphere(&self) -> (Vector, Real) {
        match self {
            Self::Ball { radius } => (Vector::ZERO, *radius),
            // Rims at y = ±h (a cone's apex lies inside the same sphere).
            Self::Cylinder { half_height, radius } | Self::Cone { half_height, radius } => {
                (Vector::ZERO, radius.hypot(*half_height))
            }
            Self::Capsule { a, b, radius } => ((*a + *b) * 0.5, 0.5 * (*b - *a).length() + radius),
            Self::Polyhedron(p) => {
                let centre = (p.bounds.mins + p.bounds.maxs) * 0.5;
                (
                    centre,
                    p.faces.iter().flatten().map(|v| (*v - centre).length()).fold(0.0, Real::max),
                )
            }
            Self::Rounded { inner, border_radius } => {
                let (centre, r) = inner.bounding_sphere();
                (centre, r + border_radius)
            }
            _ => box_sphere(&self.local_bounds()),
        }
    }

    fn half_space_normal(&self) -> Option<Vector> {
        match self {
            Self::HalfSpace { normal } => Some(*normal),
            _ => None,
        }
    }

    fn is_convex(&self) -> bool {
        !matches!(self, Self::Mesh(_))
    }

    fn holds_within(&self, n: Vector, h: Real, region: &Aabb) -> bool {
        match self {
            Self::Mesh(m) => m.holds_within(n, h, region),
            _ => true,
        }
    }

    fn has_edges(&self) -> bool {
        !matches!(self, Self::Ball { .. } | Self::Capsule { .. } | Self::HalfSpace { .. })
    }

    fn face_planes(&self) -> Option<Vec<(Vector, Real)>> {
        match self {
            Self::Cuboid { half_extents } => Some(
                (0..6)
                    .map(|k| {
                        (Vector::AXES[k % 3] * if k < 3 { 1.0 } else { -1.0 }, half_extents[k % 3])
                    })
                    .collect(),
            ),
            Self::Polyhedron(p) => Some(p.planes.clone()),
            Self::HalfSpace { normal } => Some(vec![(*normal, 0.0)]),
            _ => None,
        }
    }

    /// A cylinder's caps `y = ±h`; a cone's base `y = −h`; a rounded shape's inner faces (or
    /// flat faces) moved out by the border radius, the flat parts of its surface (its smooth
    /// part is then the whole rounded body).
    fn flat_faces(&self) -> Option<Vec<(Vector, Real)>> {
        match self {
            Self::Cylinder { half_height, .. } => {
                Some(vec![(Vector::Y, *half_height), (-Vector::Y, *half_height)])
            }
            Self::Cone { half_height, .. } => Some(vec![(-Vector::Y, *half_height)]),
            Self::Rounded { inner, border_radius } => Some(
                super::flat_parts(inner.as_ref())?
                    .into_iter()
                    .map(|(n, h)| (n, h + border_radius * n.length()))
                    .collect(),
            ),
            _ => None,
        }
    }

    /// A cylinder's infinite round side; a cone's infinite cone, from its apex; a rounded shape
    /// itself.
    fn smooth_part(&self, p: Vector) -> (Real, Vector) {
        match self {
            Self::Cylinder { radius, .. } => {
                let (r, radial) = radial(p);
                (r - radius, radial)
            }
            Self::Cone { half_height, radius } => {
                // In the half-plane (r, y) the infinite cone is a wedge with its apex at
                // (0, h), its side running down through the base's rim (R, −h): along `t`,
                // outward normal `n`. A point whose projection on that side falls above the
                // apex is nearest the apex.
                let (r, radial) = radial(p);
                let side = radius.hypot(2.0 * half_height);
                let (t, n) = (
                    [radius / side, -2.0 * half_height / side],
                    [2.0 * half_height / side, radius / side],
                );
                let q = [r, p.y - half_height];
                if q[0] * t[0] + q[1] * t[1] < 0.0 {
                    let l = q[0].hypot(q[1]);
                    (
                        l,
                        if l > 0.0 {
                            radial * (q[0] / l) + Vector::Y * (q[1] / l)
                        } else {
                            Vector::Y
                        },
                    )
                } else {
                    (q[0] * n[0] + q[1] * n[1], radial * n[0] + Vector::Y * n[1])
                }
            }
            _ => self.distance_and_gradient(p),
        }
    }

    fn local_bounds(&self) -> Aabb {
        match self {
            Self::Ball { radius } => Aabb::new(Vector::splat(-radius), Vector::splat(*radius)),
            Self::Cuboid { half_extents } => Aabb::new(-*half_extents, *half_extents),
            Self::Cylinder { half_height, radius } | Self::Cone { half_height, radius } => {
                let h = Vector::new(*radius, *half_height, *radius);
                Aabb::new(-h, h)
            }
            Self::Capsule { a, b, radius } => {
                Aabb::new(a.min(*b) - Vector::splat(*radius), a.max(*b) + Vector::splat(*radius))
            }
            Self::Polyhedron(p) => p.bounds,
            Self::Rounded { inner, border_radius } => {
                let b = inner.local_bounds();
                Aabb::new(
                    b.mins - Vector::splat(*border_radius),
                    b.maxs + Vector::splat(*border_radius),
                )
            }
            Self::HalfSpace { normal } => {
                // Bounded only along an axis-aligned normal.
                let mut maxs = Vector::splat(Real::INFINITY);
                let mut mins = Vector::splat(Real::NEG_INFINITY);
                for j in 0..3 {
                    let e = Vector::AXES[j];
                    if (normal.dot(e) - 1.0).abs() < 1e-12 {
                        maxs[j] = 0.0;
                    } else if (normal.dot(e) + 1.0).abs() < 1e-12 {
                        mins[j] = 0.0;
                    }
                }
                Aabb::new(mins, maxs)
            }
            Self::Custom(c) => c.bounds,
            Self::Mesh(m) => m.local_bounds(),
        }
    }
}
