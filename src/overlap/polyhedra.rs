//! Exact overlap of two bodies bounded by planes — cuboids, convex polyhedra, a half-space.
//! Taken in sub-cell mode for every pair without enlargement (see below), and for enlarged
//! pairs and in counting mode through
//! [`OverlapSettings::with_exact_polyhedra`](super::OverlapSettings::with_exact_polyhedra).
//!
//! The overlap of two such bodies is itself a convex polyhedron: the intersection of both
//! bodies' face half-spaces. It is built by clipping a box around the pair by every face plane
//! in turn (with [`crease`]'s clip, which keeps each vertex once), and then everything the grid
//! integration approximates is exact: the volume and centroid by the divergence theorem
//! (tetrahedra from an inner point to the faces' fans), the normal from the faces' area vectors
//! — blended as [`subcell`](super::subcell) does, B's faces against A's — the indentation as the
//! chord through the centroid along the normal, and the footprint from the faces.
//!
//! In sub-cell mode a pair of polyhedra without enlargement always takes this form: the grid
//! would clip its cells by the same faces and sum to the same polyhedron
//! ([`OverlapSettings::with_polyhedra_on_grid`](super::OverlapSettings::with_polyhedra_on_grid)
//! checks one against the other).
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

use super::crease::{self, Plane};
use super::{blended_normal, Exact, OverlapGeometry, Pair};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

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
    let size = (rough.maxs - rough.mins).length();
    if !(size.is_finite() && size > 0.0) {
        return Exact::Uncovered;
    }
    let mut scratch = crease::Scratch::take();
    scratch.planes.clear();
    for (body, planes) in [planes_a, planes_b].into_iter().enumerate() {
        scratch.planes.extend(planes.into_iter().map(|(n, h)| Plane { n, h, body }));
    }
    let pad = 0.01 * size + 2.0 * (pair.a.eps + pair.b.eps);
    let exact = clip_and_measure(&mut scratch, rough, size, pad);
    scratch.give_back();
    exact
}

/// The overlap polyhedron of the face planes in `scratch.planes`, clipped from a box `pad`
/// larger than `rough` (of diagonal `size`), and what it measures.
fn clip_and_measure(scratch: &mut crease::Scratch, rough: &Aabb, size: Real, pad: Real) -> Exact {
    // The rough box bounds the bodies dilated by `ε` (rounded), but a face moved out by `ε`
    // reaches further at a sharp vertex (√3 ε at a cube's corner, more at a sharper one): when
    // a face of the start box survives the clipping, the start was too small, and a larger one
    // is tried (the clip only reorders the planes). The planes are clipped in an order given by
    // their geometry, not by body (see `crease`): swapping the bodies builds the same
    // polyhedron to the last bit, so the forces are exactly opposite also where the overlap's
    // net area vector is a small difference of large facets (a body nearly engulfed).
    let mut pad = pad;
    let mut clipped = None;
    for _ in 0..4 {
        let pad_v = Vector::splat(pad);
        clipped = crease::clip_box(rough.mins - pad_v, rough.maxs + pad_v, scratch);
        if clipped.is_some() {
            break;
        }
        pad = 4.0 * pad + size;
    }
    let Some((c, footprint, flux)) = clipped else { return Exact::Uncovered };
    if c.volume.is_nan() {
        return Exact::Uncovered;
    }
    if c.volume <= 0.0 {
        return Exact::Apart;
    }
    let centroid = c.moment / c.volume;
    // Blended as the sub-cell integration blends its facets.
    let normal = blended_normal(c.normal, c.area).normalize_or_zero();
    if normal == Vector::ZERO || !normal.is_finite() {
        return Exact::Uncovered;
    }
    let exit = |d: Vector| {
        scratch
            .planes
            .iter()
            .filter(|p| p.n.dot(d) > 0.0)
            .map(|p| (p.h - p.n.dot(centroid)) / p.n.dot(d))
            .fold(Real::INFINITY, Real::min)
            .max(0.0)
    };
    let indentation = exit(normal) + exit(-normal);
    if !indentation.is_finite() {
        return Exact::Uncovered;
    }
    Exact::Overlap(OverlapGeometry {
        volume: c.volume,
        contact_point: centroid,
        normal,
        indentation,
        surface_area: c.area[0] + c.area[1],
        corrected_box: Aabb::new(c.lo, c.hi),
        footprint: footprint.finish(),
        flux: flux.finish(centroid),
    })
}
