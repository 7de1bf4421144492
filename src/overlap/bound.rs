//! A conservative box of the overlap `A ∩ B` by cutting planes: every box it returns contains
//! the whole overlap, and it is tight to a small fraction of a grid cell.
//!
//! Both bodies are convex and their SDFs exact, so at a point `x` outside body `s` (`d_s(x) > 0`)
//! the plane through the nearest surface point `x − d_s ∇d_s` normal to `∇d_s` supports the
//! body: `s` lies in `{y : ∇d_s·(y − x) <= −d_s(x)}`. Starting from the rough box, the
//! polytope `P ⊇ A ∩ B` is clipped by such planes, each taken at a vertex of `P` that is
//! extreme along an axis and lies outside a body — a cutting-plane method for the six bounds
//! of `A ∩ B`. Every `P` contains the overlap, so its box is conservative at every step; the
//! iteration only makes it tighter. For polyhedra the cuts are soon the faces themselves
//! (finitely many); curved surfaces, and most slowly a crease where they meet (a lens's rim),
//! need more rounds, so the rounds stop once they move the bounds by little against a cell.
//! An empty `P` proves the bodies apart.
//!
//! Unlike rays or samples along grid lines, the planes see a thin wedge's tapering ends
//! wherever they lie, whatever the aspect ratio of the overlap.
//!
//! `P` is cut with [`crease`]'s clip, the one the bent cells use: each vertex stored once, in
//! buffers kept per thread. Where `P` would outgrow them, the rounds stop there (the box still
//! holds the overlap).

use parry3d_f64::bounding_volume::Aabb;

use super::crease::{self, Plane, Scratch};
use super::Pair;
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// Rounds of cuts at most (each clips `P` by the planes at its extreme vertices).
const ROUNDS: usize = 24;

/// The box of `A ∩ B` within `rough` (the conservative rough box of the pair, which contains
/// it): `None` when the cuts prove the bodies apart. `hint` — last sub-step's box of the
/// same pair, or nothing — only adds the first cuts near where the overlap was; the result is
/// conservative whatever it is. The rounds stop when the last one moved no bound by more than
/// a quarter of a grid cell (`n` cells will be laid on the box), or after `ROUNDS`, or when
/// `P` would outgrow the clip's buffers: the box may then be a little loose, never short.
pub(super) fn overlap_box<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    rough: &Aabb,
    hint: Option<&Aabb>,
    n: usize,
) -> Option<Aabb> {
    let size = (rough.maxs - rough.mins).length();
    if !(size.is_finite() && size > 0.0) {
        return Some(*rough);
    }
    let mut scratch = Scratch::take();
    let bounds = search(pair, rough, hint, n, size, &mut scratch);
    scratch.give_back();
    bounds
}

/// [`overlap_box`]'s search with the clip's buffers, the rough box's diagonal `size` positive.
fn search<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    rough: &Aabb,
    hint: Option<&Aabb>,
    n: usize,
    size: Real,
    p: &mut Scratch,
) -> Option<Aabb> {
    // Moves each plane out a little: the gradient of a user SDF may be a finite difference.
    let margin = 1e-9 * size;
    p.start_box(rough.mins, rough.maxs);
    // The cut at `x` by the body that `x` lies farther outside (both when the two agree, in
    // the order `crease::order` gives them): a choice by the geometry, so the planes and the
    // order they are clipped in do not depend on which body is called A.
    // `Some(whether it cut)`, `None` when `P` would outgrow the buffers (left as it was).
    let cut = |p: &mut Scratch, x: Vector| -> Option<bool> {
        let (da, db) = pair.both(x);
        let mut planes = [None; 2];
        for body in [0, 1] {
            let (d, other) = if body == 0 { (da, db) } else { (db, da) };
            if d <= margin || d < other {
                continue;
            }
            let g = if body == 0 { pair.a.gradient(x) } else { pair.b.gradient(x) };
            let g = g.normalize_or_zero();
            if g == Vector::ZERO || !g.is_finite() {
                continue;
            }
            let plane = Plane { n: g, h: g.dot(x) - d + margin, body };
            // A body that is not convex may reach past the plane elsewhere in `P`.
            let holds = |convex: bool, holds_within: &dyn Fn(&Aabb) -> bool| {
                convex || extent(p.current_vertices()).is_none_or(|r| holds_within(&r))
            };
            let holds = if body == 0 {
                holds(pair.a.is_convex(), &|r| pair.a.holds_within(plane.n, plane.h, r))
            } else {
                holds(pair.b.is_convex(), &|r| pair.b.holds_within(plane.n, plane.h, r))
            };
            if holds {
                planes[body] = Some(plane);
            }
        }
        if let [Some(a), Some(b)] = planes {
            if crease::order(&a, &b).is_gt() {
                planes.swap(0, 1);
            }
        }
        let mut any = false;
        for plane in planes.into_iter().flatten() {
            p.cut(plane)?;
            any = true;
            if p.current_vertices().is_empty() {
                break;
            }
        }
        Some(any)
    };
    if let Some(h) = hint {
        // Corners of the hint box grown by half: outside the overlap, near it.
        let grow = (h.maxs - h.mins) * 0.5;
        let (lo, hi) = (h.mins - grow, h.maxs + grow);
        for c in 0..8 {
            let x = Vector::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            );
            if cut(p, x).is_none() {
                return extent(p.current_vertices());
            }
            if p.current_vertices().is_empty() {
                return None;
            }
        }
    }
    let mut bounds = extent(p.current_vertices())?;
    let mut points = Vec::with_capacity(8);
    for _ in 0..ROUNDS {
        let mut cuts = false;
        extremes(p.current_vertices(), margin, &mut points);
        for &x in &points {
            let Some(cut) = cut(p, x) else { return extent(p.current_vertices()) };
            cuts |= cut;
            if p.current_vertices().is_empty() {
                return None;
            }
        }
        let next = extent(p.current_vertices())?;
        let w = (next.maxs - next.mins) / (4.0 * n as Real);
        let moved = (bounds.mins - next.mins).abs().max((next.maxs - bounds.maxs).abs());
        bounds = next;
        if !cuts || (0..3).all(|j| moved[j] <= w[j]) {
            break;
        }
    }
    Some(bounds)
}

/// The box of the polytope's vertices.
fn extent(verts: &[Vector]) -> Option<Aabb> {
    let mut lo = Vector::splat(Real::INFINITY);
    let mut hi = Vector::splat(Real::NEG_INFINITY);
    for v in verts {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    (lo.cmple(hi).all()).then(|| Aabb::new(lo, hi))
}

/// Into `out`, the polytope's vertices extreme along each axis, lowest and highest,
/// duplicates removed: all of those within `tie` of an extreme, so that a symmetric pair gets
/// symmetric cuts (and a box symmetric to round-off) although clipping rounds mirror vertices
/// differently.
fn extremes(verts: &[Vector], tie: Real, out: &mut Vec<Vector>) {
    let mut best = [Real::INFINITY; 6];
    for v in verts {
        for j in 0..3 {
            best[2 * j] = best[2 * j].min(v[j]);
            best[2 * j + 1] = best[2 * j + 1].min(-v[j]);
        }
    }
    out.clear();
    for v in verts {
        if (0..3).any(|j| v[j] <= best[2 * j] + tie || -v[j] <= best[2 * j + 1] + tie)
            && !out.contains(v)
        {
            out.push(*v);
        }
    }
}
