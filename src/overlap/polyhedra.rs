//! Exact overlap of two bodies bounded by planes — cuboids, convex polyhedra, a half-space.
//! Opt-in through [`OverlapSettings::with_exact_polyhedra`](super::OverlapSettings::with_exact_polyhedra).
//!
//! The overlap of two such bodies is itself a convex polyhedron: the intersection of both
//! bodies' face half-spaces. It is built by clipping a box around the pair by every face plane
//! in turn (Sutherland–Hodgman on each face polygon, the cut closed by a cap polygon on the
//! plane), and then everything the grid integration approximates is exact: the volume and
//! centroid by the divergence theorem (tetrahedra from an inner point to the faces' fans), the
//! normal from the faces' area vectors — blended as [`subcell`](super::subcell) does, B's
//! faces against A's — and the indentation as the chord through the centroid along the normal.
//!
//! An enlargement `ε` moves every face plane out by `ε`: a sharp-edged enlargement, where the
//! grid's `d <= ε` rounds the edges and corners. The two differ only where the overlap reaches
//! an edge or a corner of an enlarged body, by the volume between a sharp and a rounded edge of
//! radius `ε` (a cube's moved-out corner lies (√3 − 1) ε beyond the rounded one). Whether a
//! pair is tested at all is still decided by the rounded bodies' bounds, so a sharp vertex's
//! overlap beyond them begins only when those bounds meet — for a cube with `ε` a fifth of a
//! lattice cell, a step of well under a thousandth of a cell's volume. Without enlargement the
//! result is what the grid converges to as `N_c` grows.

use parry3d_f64::bounding_volume::Aabb;

use super::{blended_normal, Exact, OverlapGeometry, Pair};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// A face of the clipped polyhedron: its vertices (ordered around its plane's normal), its
/// plane `n·x <= h` and the body it lies on (`None`: the starting box).
pub(super) struct Face {
    pub(super) verts: Vec<Vector>,
    normal: Vector,
    body: Option<usize>,
}

/// The overlap of the pair when both bodies are bounded by planes: [`Exact::Overlap`] when they
/// overlap (in the pair's frame), [`Exact::Apart`] when they do not, [`Exact::Uncovered`] when
/// a body is not planar (or the clipping met a degenerate configuration): the caller
/// integrates on the grid.
pub(super) fn overlap<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    rough: &Aabb,
) -> Exact {
    let (Some(planes_a), Some(planes_b)) = (pair.a.planes(), pair.b.planes()) else {
        return Exact::Uncovered;
    };
    let mut planes: Vec<(Vector, Real, usize)> = [planes_a, planes_b]
        .into_iter()
        .enumerate()
        .flat_map(|(body, planes)| planes.into_iter().map(move |(n, h)| (n, h, body)))
        .collect();
    // Clipped in an order by the planes' coefficients, not by body: swapping the bodies then
    // builds the same polyhedron to the last bit, so the forces are exactly opposite also where
    // the overlap's net area vector is a small difference of large facets (a body nearly
    // engulfed).
    planes.sort_by(|p, q| {
        let key = |(n, h, _): &(Vector, Real, usize)| [n.x, n.y, n.z, *h];
        key(p)
            .iter()
            .zip(key(q).iter())
            .map(|(x, y)| x.total_cmp(y))
            .find(|o| o.is_ne())
            .unwrap_or(core::cmp::Ordering::Equal)
    });
    let size = (rough.maxs - rough.mins).length();
    if !(size.is_finite() && size > 0.0) {
        return Exact::Uncovered;
    }
    let tol = 1e-12 * size;
    // Clip a box a little larger than the rough box. The rough box bounds the bodies dilated
    // by `ε` (rounded), but a face moved out by `ε` reaches further at a sharp vertex (√3 ε at
    // a cube's corner, more at a sharper one): when a face of the start box survives the
    // clipping, the start was too small, and a larger one is tried.
    let mut pad = 0.01 * size + 2.0 * (pair.a.eps + pair.b.eps);
    let faces = 'grow: {
        for _ in 0..4 {
            let mut faces =
                start_box(rough.mins - Vector::splat(pad), rough.maxs + Vector::splat(pad));
            for &(n, h, body) in &planes {
                clip(&mut faces, n, h, body, tol);
                if faces.is_empty() {
                    return Exact::Apart;
                }
            }
            if faces.iter().all(|f| f.body.is_some()) {
                break 'grow faces;
            }
            pad = 4.0 * pad + size;
        }
        return Exact::Uncovered;
    };
    let count: usize = faces.iter().map(|f| f.verts.len()).sum();
    let inner = faces.iter().flat_map(|f| f.verts.iter().copied()).sum::<Vector>() / count as Real;
    let (mut volume, mut moment) = (0.0, Vector::ZERO);
    let (mut area_vec, mut area) = ([Vector::ZERO; 2], [0.0; 2]);
    let (mut lo, mut hi) = (Vector::splat(Real::INFINITY), Vector::splat(Real::NEG_INFINITY));
    for f in &faces {
        let p = &f.verts;
        let mut a = 0.0;
        for i in 1..p.len() - 1 {
            let v = (p[0] - inner).dot((p[i] - inner).cross(p[i + 1] - inner)).abs() / 6.0;
            volume += v;
            moment += (inner + p[0] + p[i] + p[i + 1]) * (0.25 * v);
            a += 0.5 * (p[i] - p[0]).cross(p[i + 1] - p[0]).length();
        }
        let Some(body) = f.body else { return Exact::Uncovered };
        area_vec[body] += f.normal * a;
        area[body] += a;
        for v in p {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
    }
    if volume.is_nan() {
        return Exact::Uncovered;
    }
    if volume <= 0.0 {
        return Exact::Apart;
    }
    let centroid = moment / volume;
    // Blended as the sub-cell integration blends its facets.
    let normal = blended_normal(area_vec, area).normalize_or_zero();
    if normal == Vector::ZERO || !normal.is_finite() {
        return Exact::Uncovered;
    }
    let exit = |d: Vector| {
        planes
            .iter()
            .filter(|(n, _, _)| n.dot(d) > 0.0)
            .map(|(n, h, _)| (h - n.dot(centroid)) / n.dot(d))
            .fold(Real::INFINITY, Real::min)
            .max(0.0)
    };
    let indentation = exit(normal) + exit(-normal);
    if !indentation.is_finite() {
        return Exact::Uncovered;
    }
    Exact::Overlap(OverlapGeometry {
        volume,
        contact_point: centroid,
        normal,
        indentation,
        surface_area: area[0] + area[1],
        corrected_box: Aabb::new(lo, hi),
        footprint: None,
    })
}

/// The six faces of the box `lo`–`hi`.
pub(super) fn start_box(lo: Vector, hi: Vector) -> Vec<Face> {
    let corner = |c: usize| {
        Vector::new(
            if c & 1 == 0 { lo.x } else { hi.x },
            if c & 2 == 0 { lo.y } else { hi.y },
            if c & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let mut faces = Vec::with_capacity(6);
    for axis in 0..3 {
        for side in 0..2 {
            let bit = 1 << axis;
            let mut verts: Vec<Vector> =
                (0..8).filter(|c| (c & bit != 0) == (side == 1)).map(corner).collect();
            let normal = Vector::AXES[axis] * if side == 1 { 1.0 } else { -1.0 };
            order_around(&mut verts, normal);
            faces.push(Face { verts, normal, body: None });
        }
    }
    faces
}

/// Keeps the part of the polyhedron with `n·x <= h` and closes it with a face of `body` on the
/// plane, in place (the faces' vertex buffers are reused). Points within `tol` of the plane
/// count as on it.
pub(super) fn clip(faces: &mut Vec<Face>, n: Vector, h: Real, body: usize, tol: Real) {
    let side = |x: Vector| {
        let s = n.dot(x) - h;
        if s.abs() <= tol {
            0.0
        } else {
            s
        }
    };
    if faces.iter().all(|f| f.verts.iter().all(|&v| side(v) <= 0.0)) {
        return;
    }
    let mut cap: Vec<Vector> = Vec::new();
    let mut kept: Vec<Vector> = Vec::new();
    faces.retain_mut(|f| {
        let m = f.verts.len();
        kept.clear();
        for i in 0..m {
            let (p, q) = (f.verts[i], f.verts[(i + 1) % m]);
            let (sp, sq) = (side(p), side(q));
            if sp <= 0.0 {
                kept.push(p);
                if sp == 0.0 {
                    cap.push(p);
                }
            }
            if sp * sq < 0.0 {
                let x = p + (q - p) * (sp / (sp - sq));
                kept.push(x);
                cap.push(x);
            }
        }
        if kept.len() >= 3 {
            std::mem::swap(&mut f.verts, &mut kept);
            true
        } else {
            false
        }
    });
    cap_polygon(&mut cap, n, tol);
    let distinct = cap.len();
    if distinct >= 3 && !faces.is_empty() {
        faces.push(Face { verts: cap, normal: n, body: Some(body) });
    }
}

/// A cut's cap from the points the clipped faces left on the plane normal to `n`: the distinct
/// ones (within `4 tol`), ordered counter-clockwise about `n`.
pub(super) fn cap_polygon(points: &mut Vec<Vector>, n: Vector, tol: Real) {
    let mut distinct = 0;
    for i in 0..points.len() {
        let p = points[i];
        if !points[..distinct].iter().any(|q| (*q - p).length_squared() <= 16.0 * tol * tol) {
            points[distinct] = p;
            distinct += 1;
        }
    }
    points.truncate(distinct);
    if distinct >= 3 {
        order_around(points, n);
    }
}

/// Orders the points of a convex polygon in the plane normal to `n` counter-clockwise about
/// `n`.
fn order_around(points: &mut [Vector], n: Vector) {
    let c = points.iter().copied().sum::<Vector>() / points.len() as Real;
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    // A pseudo-angle: in the same order as `atan2(y, x)` on (−π, π], without the atan2.
    let angle = |p: &Vector| {
        let (x, y) = ((*p - c).dot(u), (*p - c).dot(v));
        let r = y / (x.abs() + y.abs());
        if x >= 0.0 {
            r
        } else if y >= 0.0 {
            2.0 - r
        } else {
            -2.0 - r
        }
    };
    // Each point's angle once, not once per comparison.
    const KEYED: usize = 32;
    if points.len() <= KEYED {
        let mut keys = [(0.0, Vector::ZERO); KEYED];
        for (k, p) in keys.iter_mut().zip(points.iter()) {
            *k = (angle(p), *p);
        }
        let keys = &mut keys[..points.len()];
        keys.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        for (p, k) in points.iter_mut().zip(keys.iter()) {
            *p = k.1;
        }
    } else {
        points.sort_by(|a, b| angle(a).total_cmp(&angle(b)));
    }
}
