//! The paper's integration (Marquardt et al. §3.3.3): count the grid nodes inside both bodies.

use super::footprint;
use super::{Grid, Integral, Pair};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// `sin 22.5°`: a gradient component larger than this points to a neighbour along that axis.
const SECTOR: Real = 0.382_683_432_365_089_8;

/// Distance from a surface, per grid spacing, within which a node counts as on it (at least
/// [`ROUND_OFF`]).
const SURFACE_TOL: Real = 1e-9;

/// Distance from a surface, per unit of the grid's coordinates, within which a node counts as
/// on it: the round-off of a distance taken there.
const ROUND_OFF: Real = 64.0 * Real::EPSILON;

/// `grid` is the corrected box's grid with one extra node layer on every side; only the box's
/// own nodes count for the volume.
///
/// Volume = inside nodes × cell volume; centroid = mean inside node; normal = area-weighted
/// mean of the outward unit gradients on the first layer of nodes outside the overlap whose
/// neighbour against the gradient is inside (B's surface counts `+∇d_B`, A's `-∇d_A`).
pub(crate) fn integrate<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    grid: &Grid,
    values: &[(Real, Real)],
) -> Integral {
    let n = grid.n;
    // A node on a surface to round-off counts as inside (the bodies are closed): where a
    // body's face lies on a node layer (a face on the box's boundary), the layer's distances
    // are zero to round-off and would flip in or out with the last bit of the box.
    // Round-off in a distance grows with the coordinates (the pair's frame), not with the cell.
    let b = grid.bounds();
    let reach = b.mins.abs().max(b.maxs.abs()).max_element();
    let on = (SURFACE_TOL * grid.h.min_element()).max(ROUND_OFF * reach);
    let inside = |i: usize, j: usize, k: usize| {
        let (a, b) = values[grid.index(i, j, k)];
        a.max(b) <= on
    };
    let mut count = 0usize;
    let mut sum = Vector::ZERO;
    let mut footprint = footprint::Sums::default();
    let mut normal = Vector::ZERO;
    let mut area = 0.0;
    let h = grid.h;
    let cell = h.x * h.y * h.z;
    let face_area = Vector::new(h.y * h.z, h.x * h.z, h.x * h.y);
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                if inside(i, j, k) {
                    let in_box = |v: usize| v >= 1 && v < n;
                    if in_box(i) && in_box(j) && in_box(k) {
                        count += 1;
                        sum += grid.node(i, j, k);
                    }
                    continue;
                }
                let (da, db) = values[grid.index(i, j, k)];
                // Only nodes next to the overlap can be on its surface layer.
                let near = |i: usize, j: usize, k: usize| {
                    let (lo, hi) = (|v: usize| v.saturating_sub(1), |v: usize| (v + 1).min(n));
                    (lo(k)..=hi(k)).any(|kk| {
                        (lo(j)..=hi(j)).any(|jj| (lo(i)..=hi(i)).any(|ii| inside(ii, jj, kk)))
                    })
                };
                if !near(i, j, k) {
                    continue;
                }
                let x = grid.node(i, j, k);
                let (g, sign) =
                    if db >= da { (pair.b.gradient(x), 1.0) } else { (pair.a.gradient(x), -1.0) };
                let step = |c: Real| {
                    if c > SECTOR {
                        -1i64
                    } else if c < -SECTOR {
                        1
                    } else {
                        0
                    }
                };
                let (si, sj, sk) =
                    (i as i64 + step(g.x), j as i64 + step(g.y), k as i64 + step(g.z));
                let ok = |v: i64| (0..=n as i64).contains(&v);
                if (si, sj, sk) == (i as i64, j as i64, k as i64) || !(ok(si) && ok(sj) && ok(sk)) {
                    continue;
                }
                if inside(si as usize, sj as usize, sk as usize) {
                    let a_i = face_area.dot(g * g);
                    normal += g * (sign * a_i);
                    area += a_i;
                    footprint.add(x, h, 0.5 * a_i);
                }
            }
        }
    }
    let volume = count as Real * cell;
    let centroid = if count > 0 { sum / count as Real } else { Vector::ZERO };
    Integral {
        volume,
        centroid,
        footprint: footprint.finish(),
        flux: None,
        normal,
        surface_area: area,
        bounds: None,
    }
}
