//! The solid side of a triangle mesh as a signed distance function: a wall for convex bodies.
//!
//! The distance is the Euclidean distance to the nearest point of the mesh, signed by the
//! pseudo-normal of the feature that point lies on (the face's normal, or the angle-weighted
//! normals of the faces meeting at an edge or a vertex; Bærentzen & Aanæs 2005,
//! doi:10.1109/TVCG.2005.49): negative behind the triangles' outward faces. For a closed,
//! consistently oriented mesh this is the exact SDF of the solid it bounds; for an open one (a
//! ground sheet, a height field) the solid is what lies behind its faces, so a body resting
//! across the shared edge or vertex of coplanar triangles meets exactly the plane they lie in.
//!
//! A mesh is not convex ([`Sdf::is_convex`]): the overlap's box is cut by one of its tangent
//! planes only where the triangles that meet the box lie on the plane's inner side
//! ([`Sdf::holds_within`]). A closed mesh whose faces look inwards (a room, a drum) is the
//! solid around it. A pair keeps one contact, so a body touching two faces across a concave
//! edge gets one normal between theirs (see `docs/design.md`). Meshes are walls: the drop-in
//! hands them over on bodies that do not move under forces (fixed or kinematic), never as
//! dynamic pieces.

use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::TrianglePointLocation;
use parry3d_f64::shape::{HeightField, Shape, TriMesh, TriMeshFlags, TypedShape};

use super::Sdf;
use crate::error::{Error, Result};
use crate::math::{Real, Vector};

/// A triangle mesh's solid side (see the module's documentation).
#[derive(Clone)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct MeshSdf {
    /// The mesh with its half-edge topology and pseudo-normals.
    mesh: TriMesh,
    /// The mesh's box, grown into the solid side of an open mesh (see [`Sdf::local_bounds`]).
    bounds: Aabb,
    /// Whether every edge has a triangle on both sides (a closed surface).
    closed: bool,
    /// Distances below this (a few round-offs of the mesh's size) are on the surface.
    surface_tolerance: Real,
}

impl std::fmt::Debug for MeshSdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshSdf")
            .field("triangles", &self.mesh.indices().len())
            .field("closed", &self.closed)
            .field("bounds", &self.bounds)
            .finish_non_exhaustive()
    }
}

impl MeshSdf {
    /// The solid side of the mesh `vertices`/`indices` (counter-clockwise seen from outside,
    /// as parry orders them).
    ///
    /// Errors: [`Error::UnsupportedShape`] when the triangles do not form an oriented
    /// manifold (an edge shared by more than two triangles or crossed twice in the same
    /// direction, a degenerate triangle), which leaves the solid side undefined; the same for
    /// non-finite vertices or an empty mesh.
    pub fn new(vertices: Vec<Vector>, indices: Vec<[u32; 3]>) -> Result<Self> {
        let refuse = |why: &'static str| Error::UnsupportedShape { shape: "TriMesh".into(), why };
        if !vertices.iter().all(|v| v.is_finite()) {
            return Err(refuse("a vertex is not finite"));
        }
        let flags = TriMeshFlags::HALF_EDGE_TOPOLOGY
            | TriMeshFlags::ORIENTED
            | TriMeshFlags::MERGE_DUPLICATE_VERTICES;
        let not_manifold = || {
            refuse(
                "its triangles are not an oriented manifold (each edge shared by at most two \
                 triangles that cross it in opposite directions), so it has no solid side",
            )
        };
        let mut mesh =
            TriMesh::new(vertices, indices).map_err(|_| refuse("it has no triangles"))?;
        mesh.set_flags(flags).map_err(|_| not_manifold())?;
        if mesh.topology().is_none() || mesh.pseudo_normals_if_oriented().is_none() {
            return Err(not_manifold());
        }
        let closed =
            mesh.topology().is_some_and(|t| t.half_edges.iter().all(|h| h.twin != u32::MAX));
        let mut bounds = mesh.local_aabb();
        // A closed mesh whose faces look inwards (a drum, a room) is a hollow: its solid lies
        // outside, unbounded like an open mesh's.
        if !closed || enclosed_volume(&mesh) <= 0.0 {
            bounds = open_bounds(&mesh, bounds);
        }
        if !(bounds.maxs - bounds.mins).min_element().is_finite() {
            return Err(refuse("its box is not finite"));
        }
        let size = (mesh.local_aabb().maxs - mesh.local_aabb().mins).max_element();
        let surface_tolerance = 1e3 * Real::EPSILON * size.max(Real::MIN_POSITIVE);
        Ok(Self { mesh, bounds, closed, surface_tolerance })
    }

    /// The unit pseudo-normal of the feature `location` of `triangle`: the face's normal, or
    /// the angle-weighted normal of the faces meeting at an edge or a vertex.
    fn pseudo_normal(&self, triangle: u32, location: TrianglePointLocation) -> Vector {
        let face = self.mesh.triangle(triangle).normal().unwrap_or(Vector::Y);
        let Some(pseudo) = self.mesh.pseudo_normals_if_oriented() else { return face };
        let n = match location {
            TrianglePointLocation::OnEdge(i, _) => {
                pseudo.edges_pseudo_normal.get(triangle as usize).map(|e| e[i as usize])
            }
            TrianglePointLocation::OnVertex(i) => {
                let v = self.mesh.indices()[triangle as usize][i as usize];
                pseudo.vertices_pseudo_normal.get(v as usize).copied()
            }
            _ => None,
        };
        n.and_then(|n| n.try_normalize()).unwrap_or(face)
    }

    /// The solid side of a parry triangle mesh or height field (a height field's triangles
    /// face up: the solid lies below it). Errors: [`Error::UnsupportedShape`] for any other
    /// shape, and as [`new`](Self::new).
    pub fn from_parry(shape: &dyn Shape) -> Result<Self> {
        match shape.as_typed_shape() {
            TypedShape::TriMesh(m) => Self::new(m.vertices().to_vec(), m.indices().to_vec()),
            TypedShape::HeightField(h) => Self::from_height_field(h),
            _ => Err(Error::UnsupportedShape {
                shape: format!("{:?}", shape.shape_type()),
                why: "not a triangle mesh or a height field",
            }),
        }
    }

    fn from_height_field(h: &HeightField) -> Result<Self> {
        let (vertices, indices) = h.to_trimesh();
        Self::new(vertices, indices)
    }

    /// Whether every edge of the mesh has a triangle on both sides (a closed surface).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The mesh, with its pseudo-normals.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }
}

/// The volume a closed mesh's faces enclose, positive when they look outwards (the divergence
/// theorem over the triangles' cones from the origin).
fn enclosed_volume(mesh: &TriMesh) -> Real {
    mesh.triangles().map(|t| t.a.dot(t.b.cross(t.c)) / 6.0).sum()
}

/// The box of an open mesh's solid side: the solid behind an open sheet has no far side, so
/// its box `mesh_box` is grown by the mesh's own size — which holds every overlap a body
/// smaller than the mesh can make — towards the solid side only, along each axis the faces'
/// summed normal points along (a floor's box ends at the floor): the overlap's grid then lies
/// in the wall's frame, where a rolling body's contact stays upright.
fn open_bounds(mesh: &TriMesh, mesh_box: Aabb) -> Aabb {
    let grow = (mesh_box.maxs - mesh_box.mins).max_element();
    let (mut area, mut normal) = (0.0, Vector::ZERO);
    for t in mesh.triangles() {
        let n = t.scaled_normal();
        area += n.length();
        normal += n;
    }
    let (mut mins, mut maxs) = (mesh_box.mins, mesh_box.maxs);
    for j in 0..3 {
        // Faces facing +j (the solid towards −j) keep the top; a mixed axis grows both ways.
        let lean = normal[j] / area;
        if lean < 1e-3 {
            maxs[j] += grow;
        }
        if lean > -1e-3 {
            mins[j] -= grow;
        }
    }
    Aabb::new(mins, maxs)
}

impl Sdf for MeshSdf {
    fn distance(&self, p: Vector) -> Real {
        self.distance_and_gradient(p).0
    }

    /// The nearest point's direction (see [`distance_and_gradient`](Self::distance_and_gradient)),
    /// from the one nearest-point query rather than the default's six of finite differences.
    fn gradient(&self, p: Vector) -> Vector {
        self.distance_and_gradient(p).1
    }

    /// The direction from the nearest point of the mesh to `p`, outward; on the surface (within
    /// a round-off of the mesh's size, where that direction is noise), the pseudo-normal there.
    fn distance_and_gradient(&self, p: Vector) -> (Real, Vector) {
        let (proj, (triangle, location)) = self.mesh.project_local_point_and_get_location(p, false);
        let away = p - proj.point;
        let length = away.length();
        let sign = if proj.is_inside { -1.0 } else { 1.0 };
        let gradient = if length > self.surface_tolerance {
            away / length * sign
        } else {
            self.pseudo_normal(triangle, location)
        };
        (sign * length, gradient)
    }

    fn local_bounds(&self) -> Aabb {
        self.bounds
    }

    /// Every triangle that meets `region` lies in the half-space (to a round-off of the mesh's
    /// size): the surface there, and so the solid behind it, is on the plane's inner side. At
    /// a concave edge the other face rises past the plane and the cut is refused.
    fn is_convex(&self) -> bool {
        false
    }

    fn holds_within(&self, n: Vector, h: Real, region: &Aabb) -> bool {
        let tolerance = self.surface_tolerance;
        let grown = region.loosened(tolerance);
        let holds = self.mesh.bvh().intersect_aabb(&grown).all(|t| {
            let t = self.mesh.triangle(t);
            [t.a, t.b, t.c].iter().all(|v| n.dot(*v) <= h + tolerance)
        });
        holds
    }
}
