//! Parry shapes converted to [`ConvexShape`]s.

use std::sync::Arc;

use parry3d_f64::shape::{Shape, TypedShape};

use super::{ConvexShape, PolyhedronSdf};
use crate::error::{Error, Result};

impl ConvexShape {
    /// Converts a parry shape. Supported: Ball, Cuboid, Cylinder, Cone, Capsule,
    /// ConvexPolyhedron, their `Round*` variants and HalfSpace.
    pub fn from_parry(shape: &dyn Shape) -> Result<Self> {
        let unsupported = |name: &str| {
            Error::UnsupportedShape {
            shape: name.to_string(),
            why: "not a convex solid; decompose it into convex pieces (ConvexPolyhedron) or give a custom SDF",
        }
        };
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
            other => return Err(unsupported(&format!("{:?}", shape_type_name(&other)))),
        })
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
