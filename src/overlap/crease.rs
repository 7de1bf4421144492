//! A grid cell that a body's edge or corner passes through, integrated as the cell clipped by
//! the bodies' tangent planes.
//!
//! Linear interpolation between exact surface crossings (see [`subcell`](super::subcell)) is
//! second order where a surface is smooth, but it cuts off every edge and corner of a body: an
//! SDF is convex, so its linear interpolant lies above it and the interpolated body inside the
//! true one. In a cell an edge passes through, the lost volume is a fraction of the cell, and
//! a corner reaching between a cell's nodes is lost altogether; on thin overlaps of boxes at
//! random orientations those cells carry a large part of the volume.
//!
//! A convex body with an exact SDF lies in the half-space of its tangent plane at every point
//! `x`: `{y : ∇d(x)·(y − x) <= −d(x)}` (inside the body too: the gradient is a subgradient of
//! the convex `d`). Intersecting the cell with those planes at its corners and centre, for both
//! bodies, gives a polyhedron that holds the overlap within the cell. It is exact where every
//! face near the cell is the nearest face of one of those points — for flat-faced bodies, an
//! edge through the cell has corners on both of its faces' sides — and an outer approximation
//! with the surface's curvature error, second order, on a curved face such as a cylinder's
//! side. Its volume, first moment and facet area vectors (per body) are closed-form.
//!
//! The planes are clipped in an order given by the geometry alone (sorted by their
//! coefficients), so swapping the bodies clips the same planes in the same order and the cell's
//! contribution is exactly the same, its facets only assigned to the other body.

use crate::math::{Real, Vector};

/// Vertices of all faces at most; a polyhedron that would need more sends the cell back to
/// the tetrahedra.
const MAX_VERTS: usize = 256;

/// Planes at most per cell: the samples' and those added by [`refine`](super::subcell).
pub(super) const MAX_PLANES: usize = 64;

/// Faces at most: the cell's six and one per plane.
const MAX_FACES: usize = 6 + MAX_PLANES;

/// A tangent plane `n·y <= h` of body `body` (0: A, 1: B).
#[derive(Clone, Copy, Debug)]
pub(super) struct Plane {
    pub(super) n: Vector,
    pub(super) h: Real,
    pub(super) body: usize,
}

/// A face of the clipped cell: its vertices `start..start + len` of the vertex pool, in order
/// around its outward normal, and the body whose plane it lies on (`None`: a face of the cell).
#[derive(Clone, Copy)]
struct Face {
    start: usize,
    len: usize,
    body: Option<usize>,
    normal: Vector,
}

/// A polyhedron as faces over a pool of vertices.
struct Poly {
    verts: Vec<Vector>,
    faces: Vec<Face>,
}

/// Buffers for clipping, kept between cells (two polyhedra: the clip reads one, writes the
/// other).
pub(super) struct Scratch {
    polys: [Poly; 2],
    cap: Vec<Vector>,
    /// Each vertex's signed distance from the plane being clipped.
    sides: Vec<Real>,
    /// Which of `polys` holds the last clip's result.
    current: usize,
    /// Distances from a plane below this count as on it (relative to the cell's size).
    tol: Real,
    /// The result's distinct vertices, gathered by [`Scratch::gather_vertices`].
    pub(super) vertices: Vec<Vector>,
    /// The planes [`clip_cell`] and [`clip_more`] clip by.
    pub(super) planes: Vec<Plane>,
}

impl Scratch {
    pub(super) fn new() -> Self {
        let poly =
            || Poly { verts: Vec::with_capacity(MAX_VERTS), faces: Vec::with_capacity(MAX_FACES) };
        Self {
            polys: [poly(), poly()],
            cap: Vec::with_capacity(2 * MAX_FACES),
            sides: Vec::with_capacity(MAX_VERTS),
            current: 0,
            tol: 0.0,
            vertices: Vec::with_capacity(MAX_VERTS),
            planes: Vec::with_capacity(MAX_PLANES),
        }
    }

    /// Gathers into `vertices` the distinct vertices of the last clip's polyhedron.
    pub(super) fn gather_vertices(&mut self) {
        let Self { polys, vertices, current, .. } = self;
        let poly = &polys[*current];
        vertices.clear();
        for f in &poly.faces {
            for v in &poly.verts[f.start..f.start + f.len] {
                if !vertices.contains(v) {
                    vertices.push(*v);
                }
            }
        }
    }
}

/// Volume, first moment, per-body facet area vectors and areas, and the box of the clipped
/// cell.
pub(super) struct Clipped {
    pub(super) volume: Real,
    pub(super) moment: Vector,
    pub(super) normal: [Vector; 2],
    pub(super) area: [Real; 2],
    pub(super) lo: Vector,
    pub(super) hi: Vector,
}

/// Whether the plane cuts the box `lo`–`hi` at all (some corner lies beyond it by more than
/// `tol`): a plane that does not changes nothing and is left out.
pub(super) fn cuts(plane: &Plane, lo: Vector, hi: Vector, tol: Real) -> bool {
    let (mid, half) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
    plane.n.dot(mid) + plane.n.abs().dot(half) > plane.h + tol
}

/// Sets the polyhedron to the cell `lo`–`hi` clipped by all of `scratch.planes` and returns
/// its integrals; `None` when the polyhedron would outgrow the buffers (the caller integrates
/// the cell's tetrahedra instead). Zero volume when the planes cut the cell away.
pub(super) fn clip_cell(lo: Vector, hi: Vector, scratch: &mut Scratch) -> Option<Clipped> {
    scratch.tol = 1e-12 * (hi - lo).length();
    scratch.current = 0;
    cell_faces(lo, hi, &mut scratch.polys[0]);
    clip_more(0, scratch)
}

/// Clips the polyhedron of the last [`clip_cell`] by `scratch.planes[from..]` and returns the
/// integrals of what is left (`None` as there).
///
/// The planes are clipped in an order given by the geometry alone (sorted by their
/// coefficients): the same for either labelling of the bodies.
pub(super) fn clip_more(from: usize, scratch: &mut Scratch) -> Option<Clipped> {
    let Scratch { polys, cap, sides, current, tol, planes, .. } = scratch;
    let planes = &mut planes[from..];
    planes.sort_unstable_by(|p, q| {
        (p.n.x.total_cmp(&q.n.x))
            .then(p.n.y.total_cmp(&q.n.y))
            .then(p.n.z.total_cmp(&q.n.z))
            .then(p.h.total_cmp(&q.h))
    });
    let mut next = 1 - *current;
    for &p in planes.iter() {
        if polys[*current].faces.is_empty() {
            break;
        }
        let (a, b) = polys.split_at_mut(1);
        let (from, to) = if *current == 0 { (&a[0], &mut b[0]) } else { (&b[0], &mut a[0]) };
        if clip(from, to, cap, sides, p, *tol)? {
            std::mem::swap(current, &mut next);
        }
    }
    Some(integrals(&polys[*current]))
}

/// Volume, first moment, per-body facet area vectors and areas, and the box of `poly`.
fn integrals(poly: &Poly) -> Clipped {
    let mut out = Clipped {
        volume: 0.0,
        moment: Vector::ZERO,
        normal: [Vector::ZERO; 2],
        area: [0.0; 2],
        lo: Vector::splat(Real::INFINITY),
        hi: Vector::splat(Real::NEG_INFINITY),
    };
    let points: usize = poly.faces.iter().map(|f| f.len).sum();
    if points == 0 {
        return out;
    }
    let inner = poly
        .faces
        .iter()
        .flat_map(|f| poly.verts[f.start..f.start + f.len].iter().copied())
        .sum::<Vector>()
        / points as Real;
    for f in &poly.faces {
        let p = &poly.verts[f.start..f.start + f.len];
        let mut a = Vector::ZERO;
        for i in 1..p.len() - 1 {
            let v = (p[0] - inner).dot((p[i] - inner).cross(p[i + 1] - inner)).abs() / 6.0;
            out.volume += v;
            out.moment += (inner + p[0] + p[i] + p[i + 1]) * (0.25 * v);
            a += (p[i] - p[0]).cross(p[i + 1] - p[0]);
        }
        for v in p {
            out.lo = out.lo.min(*v);
            out.hi = out.hi.max(*v);
        }
        if let Some(s) = f.body {
            let area = 0.5 * a.length();
            out.normal[s] += f.normal * area;
            out.area[s] += area;
        }
    }
    out
}

/// The six faces of the box `lo`–`hi`.
fn cell_faces(lo: Vector, hi: Vector, poly: &mut Poly) {
    let corner = |c: usize| {
        Vector::new(
            if c & 1 == 0 { lo.x } else { hi.x },
            if c & 2 == 0 { lo.y } else { hi.y },
            if c & 4 == 0 { lo.z } else { hi.z },
        )
    };
    // Corner indices of each face, counter-clockwise seen from outside.
    const QUADS: [([usize; 4], [Real; 3]); 6] = [
        ([0, 4, 6, 2], [-1.0, 0.0, 0.0]),
        ([1, 3, 7, 5], [1.0, 0.0, 0.0]),
        ([0, 1, 5, 4], [0.0, -1.0, 0.0]),
        ([2, 6, 7, 3], [0.0, 1.0, 0.0]),
        ([0, 2, 3, 1], [0.0, 0.0, -1.0]),
        ([4, 5, 7, 6], [0.0, 0.0, 1.0]),
    ];
    poly.verts.clear();
    poly.faces.clear();
    for (quad, n) in QUADS {
        poly.faces.push(Face {
            start: poly.verts.len(),
            len: 4,
            body: None,
            normal: Vector::from_array(n),
        });
        poly.verts.extend(quad.iter().map(|&c| corner(c)));
    }
}

/// Writes into `to` the part of `from` with `n·x <= h`, closed by a face on the plane; returns
/// `Some(false)` (and leaves `to` alone) when the plane cuts nothing off, `None` when the
/// result would outgrow the buffers.
fn clip(
    from: &Poly,
    to: &mut Poly,
    cap: &mut Vec<Vector>,
    sides: &mut Vec<Real>,
    plane: Plane,
    tol: Real,
) -> Option<bool> {
    sides.clear();
    sides.extend(from.verts.iter().map(|&x| {
        let s = plane.n.dot(x) - plane.h;
        if s.abs() <= tol {
            0.0
        } else {
            s
        }
    }));
    if sides.iter().all(|&s| s <= 0.0) {
        return Some(false);
    }
    to.verts.clear();
    to.faces.clear();
    cap.clear();
    for f in &from.faces {
        let start = to.verts.len();
        let (p, side) = (&from.verts[f.start..f.start + f.len], &sides[f.start..f.start + f.len]);
        for k in 0..p.len() {
            let next = if k + 1 == p.len() { 0 } else { k + 1 };
            let (a, b, sa, sb) = (p[k], p[next], side[k], side[next]);
            if sa <= 0.0 {
                to.verts.push(a);
                if sa == 0.0 {
                    cap.push(a);
                }
            }
            if (sa < 0.0 && sb > 0.0) || (sa > 0.0 && sb < 0.0) {
                let x = a + (b - a) * (sa / (sa - sb));
                to.verts.push(x);
                cap.push(x);
            }
        }
        let len = to.verts.len() - start;
        if len >= 3 {
            to.faces.push(Face { start, len, ..*f });
        } else {
            to.verts.truncate(start);
        }
    }
    super::polyhedra::cap_polygon(cap, plane.n, tol);
    let distinct = cap.len();
    if distinct >= 3 && !to.faces.is_empty() {
        to.faces.push(Face {
            start: to.verts.len(),
            len: distinct,
            body: Some(plane.body),
            normal: plane.n,
        });
        to.verts.extend_from_slice(cap);
    }
    (to.verts.len() <= MAX_VERTS && to.faces.len() <= MAX_FACES).then_some(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cell cut by the plane x + y <= 1 keeps half of itself, its centroid at
    /// (1/3, 1/3, 1/2) of the prism, and one facet of area √2 along (1, 1, 0)/√2.
    #[test]
    fn a_cell_halved_by_a_diagonal_plane() {
        let n = Vector::new(1.0, 1.0, 0.0).normalize();
        let mut scratch = Scratch::new();
        scratch.planes.push(Plane { n, h: n.dot(Vector::new(0.5, 0.5, 0.0)), body: 1 });
        let c = clip_cell(Vector::ZERO, Vector::ONE, &mut scratch).unwrap();
        assert!((c.volume - 0.5).abs() < 1e-14);
        let centroid = c.moment / c.volume;
        assert!((centroid - Vector::new(1.0 / 3.0, 1.0 / 3.0, 0.5)).length() < 1e-14);
        assert!((c.normal[1] - n * 2f64.sqrt()).length() < 1e-14 && c.area[0] == 0.0);
    }

    /// Two planes meeting in an edge through the cell (a box's edge) keep exactly the quarter
    /// they bound; a plane that misses the cell changes nothing, one beyond it empties it.
    #[test]
    fn an_edge_through_the_cell_is_kept_sharp() {
        let mut scratch = Scratch::new();
        scratch.planes.extend([
            Plane { n: Vector::X, h: 0.5, body: 0 },
            Plane { n: Vector::Y, h: 0.5, body: 0 },
            Plane { n: Vector::Z, h: 2.0, body: 1 },
        ]);
        let c = clip_cell(Vector::ZERO, Vector::ONE, &mut scratch).unwrap();
        assert!((c.volume - 0.25).abs() < 1e-14);
        assert!((c.area[0] - 1.0).abs() < 1e-14 && c.area[1] == 0.0);
        scratch.planes.clear();
        scratch.planes.push(Plane { n: -Vector::Z, h: -1.5, body: 1 });
        assert_eq!(clip_cell(Vector::ZERO, Vector::ONE, &mut scratch).unwrap().volume, 0.0);
    }
}
