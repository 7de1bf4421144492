//! Parry shapes converted to [`ConvexShape`]s, and (feature `rapier-f32`) f32 parry shapes
//! widened to f64 ones.

use std::sync::Arc;

#[cfg(feature = "rapier-f32")]
use parry3d_f64::shape::{ConvexPolyhedron as ConvexPolyhedron64, Cuboid, RoundShape, SharedShape};
use parry3d_f64::shape::{Shape, TypedShape};

#[cfg(feature = "rapier-f32")]
use crate::math::Real;

use super::{ConvexShape, PolyhedronSdf};
use crate::error::{Error, Result};

impl ConvexShape {
    /// Converts a parry shape. Supported: Ball, Cuboid, Cylinder, Cone, Capsule,
    /// ConvexPolyhedron, their `Round*` variants and HalfSpace.
    pub fn from_parry(shape: &dyn Shape) -> Result<Self> {
        Ok(match shape.as_typed_shape() {
            TypedShape::Ball(b) => Self::ball(b.radius)?,
            TypedShape::Cuboid(c) => Self::cuboid(c.half_extents)?,
            TypedShape::Cylinder(c) => Self::cylinder(c.half_height, c.radius)?,
            TypedShape::Cone(c) => Self::cone(c.half_height, c.radius)?,
            TypedShape::Capsule(c) => Self::capsule(c.segment.a, c.segment.b, c.radius)?,
            TypedShape::ConvexPolyhedron(p) => {
                Self::Polyhedron(Arc::new(PolyhedronSdf::from_parry(p)))
            }
            TypedShape::HalfSpace(h) => Self::half_space(h.normal)?,
            TypedShape::RoundCuboid(r) => {
                Self::rounded(Self::cuboid(r.inner_shape.half_extents)?, r.border_radius)?
            }
            TypedShape::RoundCylinder(r) => Self::rounded(
                Self::cylinder(r.inner_shape.half_height, r.inner_shape.radius)?,
                r.border_radius,
            )?,
            TypedShape::RoundCone(r) => Self::rounded(
                Self::cone(r.inner_shape.half_height, r.inner_shape.radius)?,
                r.border_radius,
            )?,
            TypedShape::RoundConvexPolyhedron(r) => Self::rounded(
                Self::Polyhedron(Arc::new(PolyhedronSdf::from_parry(&r.inner_shape))),
                r.border_radius,
            )?,
            other => return Err(not_convex(shape_type_name(&other).to_string())),
        })
    }
}

/// An f32 parry shape (`parry3d`, as `rapier3d` re-exports it) as the f64 parry shape it
/// stands for (feature `rapier-f32`): every number widened exactly, a convex polyhedron as the
/// convex hull of its widened vertices. The shapes [`ConvexShape::from_parry`] supports;
/// others give [`Error::UnsupportedShape`]. The f32 drop-in computes its distances and its
/// SDFs on these, in f64.
#[cfg(feature = "rapier-f32")]
pub fn widen_f32(shape: &dyn rapier3d::parry::shape::Shape) -> Result<SharedShape> {
    use rapier3d::parry::shape::{ConvexPolyhedron, TypedShape as T32};
    let hull = |p: &ConvexPolyhedron| {
        let points: Vec<crate::math::Vector> = p.points().iter().map(|&v| v.into()).collect();
        ConvexPolyhedron64::from_convex_hull(&points).ok_or(Error::UnsupportedShape {
            shape: "ConvexPolyhedron".into(),
            why: "its vertices widened to f64 do not span a volume",
        })
    };
    let w = |x: f32| Real::from(x);
    Ok(match shape.as_typed_shape() {
        T32::Ball(b) => SharedShape::ball(w(b.radius)),
        T32::Cuboid(c) => SharedShape::new(Cuboid::new(c.half_extents.into())),
        T32::Cylinder(c) => SharedShape::cylinder(w(c.half_height), w(c.radius)),
        T32::Cone(c) => SharedShape::cone(w(c.half_height), w(c.radius)),
        T32::Capsule(c) => {
            SharedShape::capsule(c.segment.a.into(), c.segment.b.into(), w(c.radius))
        }
        T32::ConvexPolyhedron(p) => SharedShape::new(hull(p)?),
        T32::HalfSpace(h) => SharedShape::halfspace(h.normal.into()),
        T32::RoundCuboid(r) => {
            let e = r.inner_shape.half_extents;
            SharedShape::round_cuboid(w(e.x), w(e.y), w(e.z), w(r.border_radius))
        }
        T32::RoundCylinder(r) => SharedShape::round_cylinder(
            w(r.inner_shape.half_height),
            w(r.inner_shape.radius),
            w(r.border_radius),
        ),
        T32::RoundCone(r) => SharedShape::round_cone(
            w(r.inner_shape.half_height),
            w(r.inner_shape.radius),
            w(r.border_radius),
        ),
        T32::RoundConvexPolyhedron(r) => SharedShape::new(RoundShape {
            inner_shape: hull(&r.inner_shape)?,
            border_radius: w(r.border_radius),
        }),
        T32::TriMesh(m) => {
            let vertices = m.vertices().iter().map(|&v| v.into()).collect();
            mesh(vertices, m.indices().to_vec())?
        }
        T32::HeightField(h) => {
            let (vertices, indices) = h.to_trimesh();
            mesh(vertices.into_iter().map(|v| v.into()).collect(), indices)?
        }
        _ => return Err(not_convex(format!("{:?}", shape.shape_type()))),
    })
}

/// The f64 triangle mesh of widened `vertices` and `indices`, as [`MeshSdf`](super::MeshSdf)
/// refuses it where it has no solid side.
#[cfg(feature = "rapier-f32")]
fn mesh(vertices: Vec<crate::math::Vector>, indices: Vec<[u32; 3]>) -> Result<SharedShape> {
    let m = super::MeshSdf::new(vertices, indices)?;
    Ok(SharedShape::new(m.mesh().clone()))
}

impl ConvexShape {
    /// Converts an f32 parry shape (`parry3d`, as `rapier3d` re-exports it; feature
    /// `rapier-f32`): [`from_parry`](Self::from_parry) of its [`widen_f32`] twin.
    #[cfg(feature = "rapier-f32")]
    pub fn from_parry_f32(shape: &dyn rapier3d::parry::shape::Shape) -> Result<Self> {
        Self::from_parry(widen_f32(shape)?.as_ref())
    }
}

/// The error for a parry shape (named `shape`) that is not a convex solid.
fn not_convex(shape: String) -> Error {
    Error::UnsupportedShape {
        shape,
        why: "not a convex solid; decompose it into convex pieces (ConvexPolyhedron) or give a custom SDF",
    }
}

fn shape_type_name(s: &TypedShape<'_>) -> &'static str {
    match s {
        TypedShape::Segment(_) => "Segment",
        TypedShape::Triangle(_) => "Triangle",
        TypedShape::TriMesh(_) => "TriMesh",
        TypedShape::Polyline(_) => "Polyline",
        TypedShape::HeightField(_) => "HeightField",
        TypedShape::Compound(_) => "Compound",
        TypedShape::Voxels(_) => "Voxels",
        TypedShape::RoundTriangle(_) => "RoundTriangle",
        _ => "Shape",
    }
}
