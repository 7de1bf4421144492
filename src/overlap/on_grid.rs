//! The overlap integrated on a grid laid on a box: a first touch on its cutting-plane box, a
//! persistent contact on its last box (padded where the overlap reaches that grid's boundary),
//! counting on its corrected box; and the integral finished into an [`OverlapGeometry`].

use parry3d_f64::bounding_volume::Aabb;

use super::{count, intersect, subcell, Grid, Integral, OverlapGeometry, Pair};
use super::{IntegrationMode, OverlapSettings};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// The overlap on an `N_c` grid laid on `corrected`: counting with one more node layer around
/// it, sub-cell integration with a quarter cell of padding; `corrected` is the box returned.
pub(super) fn overlap_in_box<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    corrected: &Aabb,
    rough: &Aabb,
    settings: &OverlapSettings,
) -> Option<OverlapGeometry> {
    let n = settings.n_c;
    let grid = Grid::on(corrected, n)?;
    let integral = match settings.mode {
        IntegrationMode::Count => {
            // One more node layer around the box: the surface layer of the paper's normal lies
            // outside the overlap, also where the overlap fills the box up to a face.
            let outer = grid.padded();
            count::integrate(pair, &outer, &outer.sample(pair, IntegrationMode::Count))
        }
        IntegrationMode::Subcell => {
            // A quarter cell of padding: flat faces on the box's faces become facets.
            let pad = grid.h * 0.25;
            let padded = Grid::on(&Aabb::new(corrected.mins - pad, corrected.maxs + pad), n)?;
            subcell::integrate(pair, &padded, &padded.sample(pair, IntegrationMode::Subcell))
        }
    };
    finish(pair, integral, &grid, rough, *corrected)
}

/// A first sub-cell touch: the grid on `bounds` (the cutting-plane box that holds the whole
/// overlap), then again on the box of the pieces it found — a quarter cell larger, as a
/// searched box is: the pieces' box is tight where `bounds` is loose (a lens's rim), so the
/// second grid is the finer one; its nodes do not lie on the pieces' extreme faces (a flat
/// face there would lie on a node layer, where which cell's facet counts is decided by
/// round-off). Where no side of the pieces' box lies more than [`SAME_BOX`] of a cell inside
/// `bounds` (the cutting planes met the overlap's extremes: flat faces, edges, a cylinder's
/// rim), the second grid would not be finer, and the first's integral is kept, with `bounds`
/// as the box the next sub-step follows (so that a contact at rest lays the same grid again).
/// Pieces beyond `bounds`, which holds all of the overlap, are the tangent planes' outer error
/// in bent cells: a grid laid on their box would only be coarser.
pub(super) fn first_touch<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    bounds: &Aabb,
    rough: &Aabb,
    settings: &OverlapSettings,
) -> Option<OverlapGeometry> {
    let grid = Grid::on(bounds, settings.n_c)?;
    let pad = grid.h * 0.25;
    let padded = Grid::on(&Aabb::new(bounds.mins - pad, bounds.maxs + pad), settings.n_c)?;
    let integral =
        subcell::integrate(pair, &padded, &padded.sample(pair, IntegrationMode::Subcell));
    let pieces = integral.bounds?;
    let slack = grid.h * SAME_BOX;
    let same = (pieces.mins - bounds.mins).cmple(slack).all()
        && (bounds.maxs - pieces.maxs).cmple(slack).all();
    if same {
        return finish(pair, integral, &grid, rough, *bounds);
    }
    overlap_in_box(pair, &pieces, rough, settings)
        .or_else(|| finish(pair, integral, &grid, rough, pieces))
}

/// How far (per cell) the pieces' box of a first touch may lie inside its cutting-plane box on
/// any side for the first grid's integral to stand ([`first_touch`]).
pub(super) const SAME_BOX: Real = 1.0 / 16.0;

/// A persistent sub-cell contact without a box search, on the grid a first touch builds from
/// the box of its pieces: last sub-step's box of the overlap's pieces a quarter cell larger on
/// every side, `N_c` cells across. Where the overlap reaches that grid's boundary
/// ([`meets_boundary`]), the box padded by one cell on every side at its own spacing (`N_c + 2`
/// cells); `None` when the overlap reaches the padding's outer node layer too (it moved by more
/// than a cell): then the search runs. The new pieces' box is next sub-step's.
///
/// The overlap of two convex bodies is convex, so connected: a part of it beyond the box joins
/// the part inside across the box's boundary. Between most sub-steps an overlap moves and grows
/// by far less than a quarter cell, and then the padding's cells — most of a padded grid's,
/// each costly where an edge or a curved side passes it by — are not integrated at all. The
/// pieces' box of the first grid is not the test: where a body's tangent plane holds a smooth
/// side within a cell, the pieces reach the cell's faces although the overlap does not.
pub(super) fn follow<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    previous: &Aabb,
    rough: &Aabb,
    n: usize,
) -> Option<OverlapGeometry> {
    let inner = Grid::on(&intersect(previous, rough)?, n)?;
    let (b, pad) = (inner.bounds(), inner.h * 0.25);
    let snug = Grid::on(&Aabb::new(b.mins - pad, b.maxs + pad), n)?;
    within(pair, &snug, rough, meets_boundary).or_else(|| {
        within(pair, &inner.padded(), rough, |grid, values| {
            any_boundary_node(grid, |node, _, _| in_both(values[node]))
        })
    })
}

/// The overlap on `grid`, or `None` where it `reaches` the grid's boundary (as the nodes'
/// distances tell), or holds no piece, or holds no node in both bodies while its pieces reach
/// a face of the grid.
///
/// The nodes miss an overlap that moved past the box (a rolling body's contact travels across
/// its frame) and crosses the boundary through the inside of a cell's face, between the nodes
/// and edges the boundary test sees, leaving only a sliver of itself on the grid. Such a
/// sliver holds no node and its pieces end on the grid's face; an overlap the box holds has
/// its inner nodes in both bodies, or (too thin for any node) pieces inside the box.
pub(super) fn within<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    grid: &Grid,
    rough: &Aabb,
    reaches: impl FnOnce(&Grid, &[(Real, Real)]) -> bool,
) -> Option<OverlapGeometry> {
    let values = grid.sample(pair, IntegrationMode::Subcell);
    if reaches(grid, &values) {
        return None;
    }
    let integral = subcell::integrate(pair, grid, &values);
    let pieces = integral.bounds?;
    if !values.iter().any(|&v| in_both(v)) && reaches_a_face(&pieces, grid) {
        return None;
    }
    finish(pair, integral, grid, rough, pieces)
}

/// Whether `pieces` — the box of an integral's pieces — reaches a face of `grid`'s box.
fn reaches_a_face(pieces: &Aabb, grid: &Grid) -> bool {
    let (b, slack) = (grid.bounds(), grid.h * 1e-9);
    (pieces.mins - b.mins).cmple(slack).any() || (b.maxs - pieces.maxs).cmple(slack).any()
}

/// Whether the overlap reaches the grid's boundary, as its nodes' distances (`values`) tell: a
/// node on the boundary lies in both bodies, or on an edge of the grid in the boundary with
/// one end in A and the other in B the parts of the edge inside each meet (by linear
/// interpolation).
pub(super) fn meets_boundary(grid: &Grid, values: &[(Real, Real)]) -> bool {
    // Where a body's part of an edge ends, as a fraction of the edge from its end `d0`.
    let cross = |d0: Real, d1: Real| d0 / (d0 - d1);
    let meet = |(a0, b0): (Real, Real), (a1, b1): (Real, Real)| {
        (a0 <= 0.0 && b1 <= 0.0 && a1 > 0.0 && b0 > 0.0 && cross(b0, b1) <= cross(a0, a1))
            || (a1 <= 0.0 && b0 <= 0.0 && a0 > 0.0 && b1 > 0.0 && cross(a0, a1) <= cross(b0, b1))
    };
    let m = grid.n + 1;
    let steps = [1, m, m * m];
    any_boundary_node(grid, |node, idx, on| {
        in_both(values[node])
            || (0..3).any(|axis| {
                // An edge lies in the boundary where another of its coordinates is on it.
                idx[axis] + 1 < m
                    && (0..3).any(|o| o != axis && on[o])
                    && meet(values[node], values[node + steps[axis]])
            })
    })
}

/// Whether a node with distances `(d_A, d_B)` lies in both bodies.
pub(super) fn in_both((a, b): (Real, Real)) -> bool {
    a.max(b) <= 0.0
}

/// Whether `f` holds for some node on the grid's boundary, given the node's index in the grid's
/// values, its `(i, j, k)` and whether each coordinate lies on the boundary. Rows inside the
/// grid visit their two end nodes only.
pub(super) fn any_boundary_node(
    grid: &Grid,
    mut f: impl FnMut(usize, [usize; 3], [bool; 3]) -> bool,
) -> bool {
    let last = grid.n;
    let on = |i: usize| i == 0 || i == last;
    for k in 0..=last {
        for j in 0..=last {
            let row = grid.index(0, j, k);
            let (on_j, on_k) = (on(j), on(k));
            let mut node = |i: usize| f(row + i, [i, j, k], [on(i), on_j, on_k]);
            if on_j || on_k {
                if (0..=last).any(&mut node) {
                    return true;
                }
            } else if node(0) || node(last) {
                return true;
            }
        }
    }
    false
}

/// Normal, indentation and the output from an integral; `None` when it found no overlap.
pub(super) fn finish<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    integral: Integral,
    grid: &Grid,
    rough: &Aabb,
    corrected_box: Aabb,
) -> Option<OverlapGeometry> {
    if integral.volume <= 0.0 {
        return None;
    }
    let x_c = integral.centroid;
    let mut normal = integral.normal.normalize_or_zero();
    if normal == Vector::ZERO {
        normal = pair.gradient_normal(x_c);
    }
    if normal == Vector::ZERO || !normal.is_finite() {
        return None;
    }
    let t_max = (rough.maxs - rough.mins).length().max(grid.h.max_element());
    let indentation =
        pair.exit_distance(x_c, normal, t_max) + pair.exit_distance(x_c, -normal, t_max);
    Some(OverlapGeometry {
        volume: integral.volume,
        contact_point: x_c,
        normal,
        indentation,
        surface_area: integral.surface_area,
        corrected_box,
        footprint: integral.footprint,
        flux: integral.flux,
    })
}
