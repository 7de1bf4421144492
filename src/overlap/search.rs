//! Counting mode's box search: axis rays and the paper's Algorithm-1 correction shrink a box
//! around the overlap, with a located seed when every ray misses.

use parry3d_f64::bounding_volume::Aabb;

use super::{correction, intersect, Grid, IntegrationMode, Pair};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// Finds the overlap's box, starting the search from `seed` (the conservative rough box, or
/// last sub-step's box grown a little).
///
/// Each round runs the Algorithm-1 correction on the searched box. When the hits fill less
/// than half of it in some direction, the rays were coarse for this overlap: the next round
/// searches the hits' box padded by one spacing, with rays that much denser. When no ray hits,
/// a point inside both bodies is looked for by alternating projections from the closest point
/// the rays saw (both bodies are convex and their SDFs exact), and the search restarts around
/// it. When the overlap reaches a face of a searched box that is not a face of the rough box,
/// the box is grown and searched again.
pub(super) fn find_box<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    seed: &Aabb,
    rough: &Aabb,
    n: usize,
    mode: IntegrationMode,
) -> Option<Aabb> {
    let mut search = *seed;
    let mut found: Option<(Aabb, Aabb)> = None; // (hits, the box they were searched in)
    let mut located = false;
    // Rays from the conservative box are coarse for a small overlap and search their gaps;
    // a persistent contact's box was fitted to the overlap one sub-step ago.
    let mut coarse = seed == rough;
    // Axis rays find the region (cheap); counting mode then runs the paper's 26-direction
    // correction once on the final search box.
    for _ in 0..5 {
        let grid = Grid::on(&search, n)?;
        let open = if search == *rough { None } else { Some(rough) };
        let gaps = std::mem::replace(&mut coarse, false);
        match correction::correct(pair, &grid, correction::Rays::Axes, open, gaps) {
            correction::Outcome::Box(b) => {
                found = Some((b, search));
                let (wb, ws) = (b.maxs - b.mins, search.maxs - search.mins);
                if !(0..3).any(|j| wb[j] < 0.5 * ws[j]) {
                    break;
                }
                let next = intersect(&Aabb::new(b.mins - grid.h, b.maxs + grid.h), rough)?;
                if next == search {
                    break;
                }
                search = next;
            }
            correction::Outcome::Truncated => {
                let w = search.maxs - search.mins;
                search = intersect(&Aabb::new(search.mins - w, search.maxs + w), rough)?;
            }
            correction::Outcome::Empty { closest } => {
                if found.is_some() || located {
                    break;
                }
                located = true;
                coarse = true;
                search = locate(pair, closest, rough)?;
            }
        }
    }
    let (hits, searched) = found?;
    if mode == IntegrationMode::Count {
        if let correction::Outcome::Box(b) = correction::correct(
            pair,
            &Grid::on(&searched, n)?,
            correction::Rays::Neighbours,
            None,
            false,
        ) {
            return Some(b);
        }
    }
    Some(hits)
}

/// A box around the overlap near `start`: alternating projections onto the violated body
/// find a point inside both, the exits along the axes from it give the box (doubled).
pub(super) fn locate<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    start: Vector,
    rough: &Aabb,
) -> Option<Aabb> {
    let scale = (rough.maxs - rough.mins).length();
    let mut x = start;
    let mut inside = false;
    // Newton-like: linearise both SDFs and take the shortest step into both half-spaces,
    // aiming a little inside; wedges between nearly parallel surfaces take a few steps.
    for _ in 0..64 {
        let (da, db) = pair.both(x);
        if da.max(db) < 0.0 {
            inside = true;
            break;
        }
        let (ga, gb) = (pair.a.gradient(x), pair.b.gradient(x));
        let eta = 0.25 * (da.abs() + db.abs()) + 1e-12 * scale;
        x += shortest_step(ga, -eta - da, gb, -eta - db);
    }
    if !inside {
        return None;
    }
    let mut lo = x;
    let mut hi = x;
    for j in 0..3 {
        let e = Vector::AXES[j];
        hi[j] += 2.0 * pair.exit_distance(x, e, scale);
        lo[j] -= 2.0 * pair.exit_distance(x, -e, scale);
    }
    intersect(&Aabb::new(lo, hi), rough)
}

/// The shortest `s` with `ga·s <= ra` and `gb·s <= rb` (unit `ga`, `gb`): the projection
/// onto the intersection of two half-spaces, by trying the active sets; when the half-spaces
/// do not meet, the step that satisfies the more violated one.
pub(super) fn shortest_step(ga: Vector, ra: Real, gb: Vector, rb: Real) -> Vector {
    let ok = |s: Vector| ga.dot(s) <= ra + 1e-15 && gb.dot(s) <= rb + 1e-15;
    let mut best: Option<Vector> = None;
    let mut consider = |s: Vector| {
        if s.is_finite() && ok(s) && best.is_none_or(|b| s.length_squared() < b.length_squared()) {
            best = Some(s);
        }
    };
    consider(Vector::ZERO);
    consider(ga * ra.min(0.0));
    consider(gb * rb.min(0.0));
    let c = ga.dot(gb);
    let det = 1.0 - c * c;
    if det > 1e-12 {
        let (alpha, beta) = ((ra - c * rb) / det, (rb - c * ra) / det);
        consider(ga * alpha + gb * beta);
    }
    best.unwrap_or(if ra < rb { ga * ra } else { gb * rb })
}
