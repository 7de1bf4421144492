//! Algorithm 1 of Marquardt et al.: shrink a rough box to the overlap by sphere tracing from its surface.

use parry3d_f64::bounding_volume::Aabb;

use super::{crossing, Grid, Pair};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// Accuracy of a ray's hit, per grid spacing: the box only places the grid.
const RAY_TOL: Real = 1e-6;

/// Which rays the correction marches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rays {
    /// Along the inward axis of each face a node lies on (cheap: finds the region).
    Axes,
    /// In every one of the 26 neighbour directions that stays in the box (Algorithm 1).
    Neighbours,
}

/// What the correction found.
pub(crate) enum Outcome {
    /// The box around all ray hits.
    Box(Aabb),
    /// No ray met the overlap; the point with the smallest `max(d_A, d_B)` any ray saw.
    Empty {
        /// Where the rays came closest to the overlap.
        closest: Vector,
    },
    /// The overlap reaches a face of the box that is not a face of the conservative box.
    Truncated,
}

/// Marches from the grid's surface nodes into the box and returns the box of the hit points.
///
/// [`Rays::Neighbours`] marches in every one of the 26 neighbour directions that stays in
/// the box (the paper's); [`Rays::Axes`] only along the inward axis of each face
/// the node lies on. `conservative` is the box known to contain the overlap, when `grid` is
/// a reused (possibly too small) box. `gaps` makes the rays search the intervals their step
/// floor skips wherever the Lipschitz bound leaves room for a thin overlap.
pub(crate) fn correct<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    grid: &Grid,
    rays: Rays,
    conservative: Option<&Aabb>,
    gaps: bool,
) -> Outcome {
    let n = grid.n as i64;
    let bounds = grid.bounds();
    let tol = RAY_TOL * grid.h.min_element();
    let mut lo = Vector::splat(Real::INFINITY);
    let mut hi = Vector::splat(Real::NEG_INFINITY);
    let mut closest = (Real::INFINITY, bounds.center());
    // Faces of the box that are strictly inside the conservative box: [axis][side].
    let mut open_face = [[false; 2]; 3];
    if let Some(c) = conservative {
        for j in 0..3 {
            let slack = 1e-9 * (c.maxs[j] - c.mins[j]).max(grid.h[j]);
            open_face[j] = [bounds.mins[j] > c.mins[j] + slack, bounds.maxs[j] < c.maxs[j] - slack];
        }
    }
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                let idx = [i, j, k];
                let on_face = |a: usize| idx[a] == 0 || idx[a] == n;
                if !(on_face(0) || on_face(1) || on_face(2)) {
                    continue;
                }
                let p = grid.node(i as usize, j as usize, k as usize);
                let v0 = pair.phi(p);
                if v0 < closest.0 {
                    closest = (v0, p);
                }
                if v0 <= 0.0 {
                    for a in 0..3 {
                        if (idx[a] == 0 && open_face[a][0]) || (idx[a] == n && open_face[a][1]) {
                            return Outcome::Truncated;
                        }
                    }
                    lo = lo.min(p);
                    hi = hi.max(p);
                    continue;
                }
                let mut march = |d: [i64; 3]| {
                    if let Some(hit) = trace(pair, grid, &bounds, p, d, tol, gaps, &mut closest) {
                        lo = lo.min(hit);
                        hi = hi.max(hit);
                    }
                };
                match rays {
                    Rays::Neighbours => {
                        for dz in -1..=1i64 {
                            for dy in -1..=1i64 {
                                for dx in -1..=1i64 {
                                    let d = [dx, dy, dz];
                                    let inside = (0..3).all(|a| (0..=n).contains(&(idx[a] + d[a])));
                                    if d != [0, 0, 0] && inside {
                                        march(d);
                                    }
                                }
                            }
                        }
                    }
                    Rays::Axes => {
                        for a in 0..3 {
                            for (side, step) in [(0, 1), (n, -1)] {
                                if idx[a] == side {
                                    let mut d = [0; 3];
                                    d[a] = step;
                                    march(d);
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    if lo.x.is_finite() {
        Outcome::Box(Aabb::new(lo, hi))
    } else {
        Outcome::Empty { closest: closest.1 }
    }
}

/// Marches from `p` towards the neighbour offset `d` with steps of `max(phi, cell/4)` (sphere
/// tracing far from the overlap, a floor near it so grazing rays cannot stall) until
/// `max(d_A, d_B) <= 0`, then refines the crossing; `None` when the ray leaves the box.
#[allow(clippy::too_many_arguments)] // one ray's state; a struct for it would live one call
fn trace<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    grid: &Grid,
    bounds: &Aabb,
    p: Vector,
    d: [i64; 3],
    tol: Real,
    gaps: bool,
    closest: &mut (Real, Vector),
) -> Option<Vector> {
    let step = grid.h * Vector::new(d[0] as Real, d[1] as Real, d[2] as Real);
    let cell = step.length();
    let dir = step / cell;
    let mut t_exit = Real::INFINITY;
    for a in 0..3 {
        if dir[a] > 0.0 {
            t_exit = t_exit.min((bounds.maxs[a] - p[a]) / dir[a]);
        } else if dir[a] < 0.0 {
            t_exit = t_exit.min((bounds.mins[a] - p[a]) / dir[a]);
        }
    }
    let f = |t: Real| pair.phi(p + dir * t);
    let (mut t, mut v) = (0.0, f(0.0));
    let floor = 0.25 * cell;
    loop {
        if t >= t_exit {
            return None;
        }
        let t_next = (t + v.max(floor)).min(t_exit);
        let v_next = f(t_next);
        if v_next < closest.0 {
            *closest = (v_next, p + dir * t_next);
        }
        if v_next <= 0.0 {
            let hit = crossing(f, (t, v), (t_next, v_next), tol, tol);
            return Some(p + dir * hit);
        }
        // The floor may step over a thin overlap; with 1-Lipschitz distances it can only hide
        // where v + v_next < step, and only there is the interval searched (when asked: rays
        // that are coarse for the overlap, i.e. the first search from a rough box).
        if !gaps {
        } else if let Some((ti, vi)) = search_gap(&f, (t, v), (t_next, v_next), 4, closest, p, dir)
        {
            let hit = crossing(f, (t, v), (ti, vi), tol, tol);
            return Some(p + dir * hit);
        }
        (t, v) = (t_next, v_next);
    }
}

/// A point with `f <= 0` in `(a, b)` if the Lipschitz bound leaves room for one, by recursive
/// halving down to `depth` levels.
fn search_gap(
    f: &impl Fn(Real) -> Real,
    a: (Real, Real),
    b: (Real, Real),
    depth: u32,
    closest: &mut (Real, Vector),
    p: Vector,
    dir: Vector,
) -> Option<(Real, Real)> {
    if a.1 + b.1 >= b.0 - a.0 || depth == 0 {
        return None;
    }
    let tm = 0.5 * (a.0 + b.0);
    let vm = f(tm);
    if vm < closest.0 {
        *closest = (vm, p + dir * tm);
    }
    if vm <= 0.0 {
        return Some((tm, vm));
    }
    search_gap(f, a, (tm, vm), depth - 1, closest, p, dir)
        .or_else(|| search_gap(f, (tm, vm), b, depth - 1, closest, p, dir))
}
