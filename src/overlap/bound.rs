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

use parry3d_f64::bounding_volume::Aabb;

use super::polyhedra::{clip, start_box, Face};
use super::Pair;
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// Rounds of cuts at most (each clips `P` by up to six planes).
const ROUNDS: usize = 24;

/// The box of `A ∩ B` within `rough` (the conservative rough box of the pair, which contains
/// it): `None` when the cuts prove the bodies apart. `hint` — last sub-step's box of the
/// same pair, or nothing — only adds the first cuts near where the overlap was; the result is
/// conservative whatever it is. The rounds stop when the last one moved no bound by more than
/// a quarter of a grid cell (`n` cells will be laid on the box), or after `ROUNDS`: the box
/// may then be a little loose, never short.
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
    let tol = 1e-12 * size;
    // Moves each plane out a little: the gradient of a user SDF may be a finite difference.
    let margin = 1e-9 * size;
    let mut faces = start_box(rough.mins, rough.maxs);
    // The cut at `x` by the body that `x` lies farther outside (both when the two agree):
    // a choice by the geometry, so the planes do not depend on which body is called A.
    let cut = |faces: &mut Vec<Face>, x: Vector| -> bool {
        let (da, db) = pair.both(x);
        let mut any = false;
        for s in [0, 1] {
            let (d, other) = if s == 0 { (da, db) } else { (db, da) };
            if d <= margin || d < other {
                continue;
            }
            let g = if s == 0 { pair.a.gradient(x) } else { pair.b.gradient(x) };
            let g = g.normalize_or_zero();
            if g == Vector::ZERO || !g.is_finite() {
                continue;
            }
            clip(faces, g, g.dot(x) - d + margin, tol);
            any = true;
            if faces.is_empty() {
                break;
            }
        }
        any
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
            cut(&mut faces, x);
            if faces.is_empty() {
                return None;
            }
        }
    }
    let mut bounds = extent(&faces)?;
    for _ in 0..ROUNDS {
        let mut cuts = false;
        for x in extremes(&faces, margin) {
            cuts |= cut(&mut faces, x);
            if faces.is_empty() {
                return None;
            }
        }
        let next = extent(&faces)?;
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
fn extent(faces: &[Face]) -> Option<Aabb> {
    let mut lo = Vector::splat(Real::INFINITY);
    let mut hi = Vector::splat(Real::NEG_INFINITY);
    for v in faces.iter().flat_map(|f| f.verts.iter()) {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    (lo.cmple(hi).all()).then(|| Aabb::new(lo, hi))
}

/// The polytope's vertices extreme along each axis, lowest and highest, duplicates removed:
/// all of those within `tie` of an extreme, so that a symmetric pair gets symmetric cuts
/// (and a box symmetric to round-off) although clipping rounds mirror vertices differently.
fn extremes(faces: &[Face], tie: Real) -> Vec<Vector> {
    let mut best = [Real::INFINITY; 6];
    for v in faces.iter().flat_map(|f| f.verts.iter()) {
        for j in 0..3 {
            best[2 * j] = best[2 * j].min(v[j]);
            best[2 * j + 1] = best[2 * j + 1].min(-v[j]);
        }
    }
    let mut out: Vec<Vector> = Vec::with_capacity(8);
    for v in faces.iter().flat_map(|f| f.verts.iter()) {
        if (0..3).any(|j| v[j] <= best[2 * j] + tie || -v[j] <= best[2 * j + 1] + tie)
            && !out.contains(v)
        {
            out.push(*v);
        }
    }
    out
}
