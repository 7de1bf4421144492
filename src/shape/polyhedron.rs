//! Convex polyhedra (parry's `ConvexPolyhedron`, convex hulls of points) with an exact SDF.

use parry3d_f64::bounding_volume::Aabb;

use crate::error::{check_finite_vec, Error, Result};
use crate::math::{Real, Vector};

/// A convex polyhedron with an exact SDF: inside, the largest face-plane distance; outside,
/// the distance to the nearest point of the surface (see `distance_and_gradient`).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "checkpoint", serde(from = "PolyhedronFaces", into = "PolyhedronFaces"))]
pub struct PolyhedronSdf {
    /// Outward unit normal and offset of each face plane (`n·p - offset` is the plane distance).
    pub(super) planes: Vec<(Vector, Real)>,
    /// Each face's vertices, ordered around the face.
    pub(super) faces: Vec<Vec<Vector>>,
    /// Each face's edges, face after face in the order of `faces` (see [`FaceEdge`]).
    edges: Vec<FaceEdge>,
    /// Where each face's edges begin in `edges`, and their end.
    edge_start: Vec<usize>,
    /// The distinct vertices (for the test that a point of the surface is the nearest).
    vertices: Vec<Vector>,
    pub(super) bounds: Aabb,
}

/// An edge of a face, `a → b` in the face's counter-clockwise order, with the face's side
/// plane through it: `o·p <= c` on the face's side, `o` the edge direction turned outward in
/// the face's plane. A point projects into a face when it lies on the inner side of every side
/// plane, which needs no projection: the side planes contain the face's normal.
#[derive(Clone, Copy, Debug)]
struct FaceEdge {
    a: Vector,
    b: Vector,
    o: Vector,
    c: Real,
}

/// What a polyhedron's checkpoint holds: its faces; the edges are rebuilt from them.
#[cfg(feature = "checkpoint")]
#[derive(serde::Serialize, serde::Deserialize)]
struct PolyhedronFaces {
    planes: Vec<(Vector, Real)>,
    faces: Vec<Vec<Vector>>,
    bounds: Aabb,
}

#[cfg(feature = "checkpoint")]
impl From<PolyhedronFaces> for PolyhedronSdf {
    fn from(f: PolyhedronFaces) -> Self {
        Self::from_faces(f.planes, f.faces, f.bounds)
    }
}

#[cfg(feature = "checkpoint")]
impl From<PolyhedronSdf> for PolyhedronFaces {
    fn from(p: PolyhedronSdf) -> Self {
        Self { planes: p.planes, faces: p.faces, bounds: p.bounds }
    }
}

impl PolyhedronSdf {
    /// Builds the SDF of the convex hull of `points` (at least 4 points, not coplanar).
    pub fn from_points(points: &[Vector]) -> Result<Self> {
        for p in points {
            check_finite_vec("polyhedron vertex", *p)?;
        }
        let hull = parry3d_f64::shape::ConvexPolyhedron::from_convex_hull(points).ok_or(
            Error::UnsupportedShape {
                shape: "ConvexPolyhedron".into(),
                why: "the points do not span a volume (need at least 4 non-coplanar points)",
            },
        )?;
        let sdf = Self::from_parry(&hull);
        // Divergence theorem: V = Σ offset·area / 3 over the faces.
        let volume: Real = sdf
            .planes
            .iter()
            .zip(&sdf.faces)
            .map(|((n, off), v)| {
                let area = (1..v.len() - 1)
                    .map(|i| (v[i] - v[0]).cross(v[i + 1] - v[0]).dot(*n))
                    .sum::<Real>()
                    * 0.5;
                off * area / 3.0
            })
            .sum();
        let size = (sdf.bounds.maxs - sdf.bounds.mins).length();
        if !(volume > 1e-12 * size * size * size) {
            return Err(Error::UnsupportedShape {
                shape: "ConvexPolyhedron".into(),
                why: "the points do not span a volume (need at least 4 non-coplanar points)",
            });
        }
        Ok(sdf)
    }

    /// Builds the SDF of a parry convex polyhedron.
    ///
    /// The faces come from the hull's triangles, joined only where they lie in one plane to
    /// within `COPLANAR` of the body's size: parry joins triangles whose normals agree to
    /// within its own tolerance, and such a face can bend by far more than round-off, which
    /// would put a single face plane (and so the distance) off the true hull. Should the
    /// triangulation fail, parry's faces are taken as they are.
    pub fn from_parry(poly: &parry3d_f64::shape::ConvexPolyhedron) -> Self {
        let pts = poly.points();
        let mut mins = Vector::splat(Real::INFINITY);
        let mut maxs = Vector::splat(Real::NEG_INFINITY);
        for p in pts {
            mins = mins.min(*p);
            maxs = maxs.max(*p);
        }
        let bounds = Aabb::new(mins, maxs);
        let (planes, faces) = match parry3d_f64::transformation::try_convex_hull(pts) {
            Ok((vertices, triangles)) => planar_faces(&vertices, &triangles, bounds),
            Err(_) => parry_faces(poly),
        };
        Self::from_faces(planes, faces, bounds)
    }

    /// From the face planes, each face's counter-clockwise vertices and the bounds.
    fn from_faces(planes: Vec<(Vector, Real)>, faces: Vec<Vec<Vector>>, bounds: Aabb) -> Self {
        let edges = planes
            .iter()
            .zip(&faces)
            .flat_map(|(&(n, _), verts)| {
                let m = verts.len();
                (0..m).map(move |i| {
                    let (a, b) = (verts[i], verts[(i + 1) % m]);
                    let o = (b - a).cross(n);
                    FaceEdge { a, b, o, c: o.dot(a) }
                })
            })
            .collect();
        let edge_start = std::iter::once(0)
            .chain(faces.iter().scan(0, |end, f| {
                *end += f.len();
                Some(*end)
            }))
            .collect();
        let mut vertices: Vec<Vector> = Vec::new();
        for v in faces.iter().flatten() {
            if !vertices.contains(v) {
                vertices.push(*v);
            }
        }
        Self { planes, faces, edges, edge_start, vertices, bounds }
    }

    /// Distance and outward gradient.
    ///
    /// Outside, the nearest point `q` of a convex body is the one with `p − q` in the normal
    /// cone at `q`. So a face whose plane sees `p` and into which `p` projects gives it: its
    /// projection. Failing that, `q` lies on an edge, and on one that `p` lies beyond as seen
    /// from a face whose plane sees it (of the edge's two faces, at least one sees `p`, and `p`
    /// lies on the outer side of that face's side plane through the edge). The farthest
    /// plane's face, the likeliest, is tried first: the nearest point of its edges that `p`
    /// lies beyond is the body's nearest point when the plane through it normal to `p − q`
    /// has every vertex on its inner side (a supporting plane). Otherwise only the edges that
    /// `p` lies beyond, as seen from faces that see it, are measured.
    pub(super) fn distance_and_gradient(&self, p: Vector) -> (Real, Vector) {
        let (mut farthest, mut face) = (Real::NEG_INFINITY, 0);
        for (k, (n, off)) in self.planes.iter().enumerate() {
            let s = n.dot(p) - off;
            if s > farthest {
                (farthest, face) = (s, k);
            }
        }
        let best = (farthest, self.planes[face].0);
        if farthest <= 0.0 {
            return best;
        }
        let face_edges = |k: usize| &self.edges[self.edge_start[k]..self.edge_start[k + 1]];
        let beyond = |e: &FaceEdge| e.o.dot(p) > e.c;
        if !face_edges(face).iter().any(beyond) {
            return best;
        }
        // The farthest plane's face: its nearest point, if no vertex lies beyond the plane
        // through it normal to `p − q`.
        let tiny = 1e-9 * (self.bounds.maxs - self.bounds.mins).max_element();
        let mut near = (Real::INFINITY, Vector::ZERO);
        for e in face_edges(face).iter().filter(|e| beyond(e)) {
            let q = closest_on_segment(p, e.a, e.b);
            let d = (p - q).length();
            if d < near.0 {
                near = (d, q);
            }
        }
        let (d, q) = near;
        if d > tiny {
            let g = (p - q) / d;
            // Round-off only: a vertex beyond the plane by this much could bring the body at
            // most this much nearer.
            let c = g.dot(q) + 1e-4 * tiny;
            if self.vertices.iter().all(|v| g.dot(*v) <= c) {
                return (d, g);
            }
        }
        let mut out = (Real::INFINITY, best.1);
        for (k, (n, off)) in self.planes.iter().enumerate() {
            let s = n.dot(p) - off;
            // A face that does not see `p`, or no nearer than the nearest point so far.
            if s <= 0.0 || s >= out.0 {
                continue;
            }
            let mut inside = true;
            for e in face_edges(k).iter().filter(|e| beyond(e)) {
                inside = false;
                let q = closest_on_segment(p, e.a, e.b);
                let d = (p - q).length();
                if d < out.0 {
                    // Within round-off of an edge, `p − q` has no direction: the face's normal
                    // is then as good a (sub)gradient there.
                    out = (d, if d > tiny { (p - q) / d } else { *n });
                }
            }
            if inside {
                return (s, *n);
            }
        }
        out
    }
}

pub(super) fn closest_on_segment(p: Vector, a: Vector, b: Vector) -> Vector {
    let e = b - a;
    let l2 = e.length_squared();
    let t = if l2 > 0.0 { ((p - a).dot(e) / l2).clamp(0.0, 1.0) } else { 0.0 };
    a + e * t
}

/// How far (relative to the body's diagonal) a triangle's corners may lie off a face's plane
/// and still belong to that face: round-off, not shape.
const COPLANAR: Real = 1e-11;

/// A face plane and its counter-clockwise vertices, as `from_faces` takes them.
type Faces = (Vec<(Vector, Real)>, Vec<Vec<Vector>>);

/// The faces of a triangulated convex hull: triangles in one plane (to within [`COPLANAR`])
/// form one face, the convex hull of their corners in that plane. On a convex body the
/// triangles that a plane holds are those of one face, so no adjacency is needed. Triangles
/// of no area (collinear corners) bound nothing and are skipped.
fn planar_faces(vertices: &[Vector], triangles: &[[u32; 3]], bounds: Aabb) -> Faces {
    let tol = COPLANAR * (bounds.maxs - bounds.mins).length();
    // Per face: the area-weighted normal, a point of the plane, and the corners.
    let mut groups: Vec<(Vector, Vector, Vec<Vector>)> = Vec::new();
    for t in triangles {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let area = (b - a).cross(c - a);
        let Some(n) = area.try_normalize() else { continue };
        let on_plane = |(m, o, _): &&mut (Vector, Vector, Vec<Vector>)| {
            let m = m.normalize();
            m.dot(n) > 0.0 && [a, b, c].iter().all(|p| m.dot(*p - *o).abs() <= tol)
        };
        match groups.iter_mut().find(|g| on_plane(g)) {
            Some((m, _, corners)) => {
                *m += area;
                corners.extend([a, b, c]);
            }
            None => groups.push((area, a, vec![a, b, c])),
        }
    }
    groups
        .into_iter()
        .map(|(m, _, corners)| {
            let n = m.normalize();
            let offset = corners.iter().map(|p| n.dot(*p)).sum::<Real>() / corners.len() as Real;
            ((n, offset), hull_in_plane(n, corners))
        })
        .unzip()
}

/// The convex hull of points in a plane of normal `n`, counter-clockwise about `n`, without
/// points inside it or on its edges (Andrew's monotone chain).
fn hull_in_plane(n: Vector, mut points: Vec<Vector>) -> Vec<Vector> {
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let uv = |p: &Vector| (p.dot(u), p.dot(v));
    points.sort_by(|p, q| {
        let (p, q) = (uv(p), uv(q));
        p.0.total_cmp(&q.0).then(p.1.total_cmp(&q.1))
    });
    points.dedup();
    // Whether `o → a → b` turns left (counter-clockwise) in the plane.
    let left = |o: &Vector, a: &Vector, b: &Vector| {
        let (o, a, b) = (uv(o), uv(a), uv(b));
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0) > 0.0
    };
    let mut hull: Vec<Vector> = Vec::with_capacity(points.len() + 1);
    for p in &points {
        while hull.len() >= 2 && !left(&hull[hull.len() - 2], &hull[hull.len() - 1], p) {
            hull.pop();
        }
        hull.push(*p);
    }
    let lower = hull.len() + 1;
    for p in points.iter().rev().skip(1) {
        while hull.len() >= lower && !left(&hull[hull.len() - 2], &hull[hull.len() - 1], p) {
            hull.pop();
        }
        hull.push(*p);
    }
    hull.pop(); // the first point, closing the chain
    hull
}

/// Parry's own faces: each face's plane through its vertices' centre, the vertices ordered
/// counter-clockwise about the face normal.
fn parry_faces(poly: &parry3d_f64::shape::ConvexPolyhedron) -> Faces {
    let pts = poly.points();
    let adj = poly.vertices_adj_to_face();
    poly.faces()
        .iter()
        .map(|f| {
            let first = f.first_vertex_or_edge as usize;
            let verts: Vec<Vector> = adj[first..first + f.num_vertices_or_edges as usize]
                .iter()
                .map(|&i| pts[i as usize])
                .collect();
            let n = f.normal;
            let centre = verts.iter().copied().sum::<Vector>() / verts.len() as Real;
            ((n, n.dot(centre)), hull_in_plane(n, verts))
        })
        .unzip()
}
