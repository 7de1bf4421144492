//! Sub-cell integration: the overlap's surface is located exactly on the cut edges of the grid
//! and interpolated linearly between them, on the six tetrahedra of every cell it cuts.
//!
//! Each tetrahedron is clipped by A's surface and the pieces by B's. Where a clipped edge is a
//! grid edge, the crossing is found by root finding on the exact SDF and cached (neighbouring
//! cells share it, so the surface is watertight); other edges (only in cells both surfaces cut)
//! are solved on the fly. Root finding instead of interpolating SDF values matters: inside a
//! cylinder or a box the SDF has kinks (the nearest face changes), where interpolated values
//! would misplace the surface by a large fraction of a cell. With exact crossings the error is
//! the surface's curvature within a cell: second order.
//!
//! Volume and first moment of the clipped pieces are closed-form; cells wholly inside count
//! whole, cells wholly outside cost nothing. The normal is the area vector of the surface
//! facets: B's part (`d_B = 0` inside A) and minus A's part — for a closed overlap both equal
//! `|S| n`, so no gradient is evaluated. The two are blended with the *other* part's area as
//! weight, so the smaller part counts most: when one body is mostly inside the other, its own
//! surface is nearly closed and its area vector a small difference of large facets (where the
//! rim's linearisation errors would tilt the normal by several per cent), while the other
//! body's cap is small and well resolved. Equal parts give the plain mean; swapping the bodies
//! swaps the weights, so the result stays equal and opposite.

use parry3d_f64::bounding_volume::Aabb;

use super::{blended_normal, crossing, Grid, Integral, Pair};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// Kuhn decomposition of the unit cell (corner bits: x = 1, y = 2, z = 4) into six tetrahedra
/// around the diagonal 0–7. Along each, the corner bits only grow, so every edge is a
/// "forward" edge from its lower corner in direction `upper ^ lower` (1..=7).
const TETS: [[usize; 4]; 6] = [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

/// Relative accuracy of a surface crossing on an edge (fraction of the edge, and distance
/// from the surface per edge length): far below the second-order discretisation error.
const EDGE_TOL: Real = 1e-7;

/// The same for an edge made by clipping (not shared with a neighbouring cell).
const CLIPPED_EDGE_TOL: Real = 1e-3;

/// No grid node: a point made by clipping.
const NOT_A_NODE: u32 = u32::MAX;

/// A vertex of a clipped piece: position, both distances, and its grid node if it is one.
#[derive(Clone, Copy, Debug, Default)]
struct Vert {
    x: Vector,
    d: [Real; 2],
    node: u32,
}

/// Per body, per node, per forward edge: (fraction along the edge, other body's distance).
type Crossings = [Vec<[(Real, Real); 7]>; 2];

/// Crossings of A's (0) and B's (1) surface on the forward edges of every node: the fraction
/// along the edge and the other body's distance there; NaN until computed.
struct EdgeCache {
    t: Crossings,
    m: usize,
}

thread_local! {
    /// Each thread's edge-cache buffers, kept between evaluations: a fresh ~150 kB allocation
    /// per contact evaluation cost page faults and a copy (~6 % of an evaluation).
    static SPARE: std::cell::RefCell<Crossings> = const { std::cell::RefCell::new([Vec::new(), Vec::new()]) };
}

impl EdgeCache {
    fn new(nodes: usize, m: usize) -> Self {
        let mut t = SPARE.with(|s| std::mem::take(&mut *s.borrow_mut()));
        for v in &mut t {
            v.clear();
            v.resize(nodes, [(Real::NAN, Real::NAN); 7]);
        }
        Self { t, m }
    }

    /// Direction code (1..=7) of the forward edge between nodes `lo < hi`.
    fn dir(&self, lo: u32, hi: u32) -> usize {
        let diff = (hi - lo) as usize;
        let (m, m2) = (self.m, self.m * self.m);
        let mut code = 0;
        let mut rest = diff;
        if rest >= m2 {
            code |= 4;
            rest -= m2;
        }
        if rest >= m {
            code |= 2;
            rest -= m;
        }
        if rest >= 1 {
            code |= 1;
        }
        code
    }
}

impl Drop for EdgeCache {
    fn drop(&mut self) {
        let t = std::mem::take(&mut self.t);
        SPARE.with(|s| *s.borrow_mut() = t);
    }
}

/// Finds surface crossings on edges (cached on grid edges).
struct Cutter<'p, 'a, A: ?Sized, B: ?Sized> {
    pair: &'p Pair<'a, A, B>,
    cache: EdgeCache,
    /// Whether crossings need the other body's distance (a second clip follows).
    need_other: bool,
}

/// Volume, moment, normal and bounds summed over the clipped pieces.
struct Sums {
    volume: Real,
    moment: Vector,
    /// Area vectors of A's facets (oriented out of A) and of B's (out of B) and their areas.
    normal: [Vector; 2],
    area: [Real; 2],
    lo: Vector,
    hi: Vector,
}

#[inline]
fn tet_volume(p: &[Vert; 4]) -> Real {
    ((p[1].x - p[0].x).cross(p[2].x - p[0].x).dot(p[3].x - p[0].x)).abs() / 6.0
}

/// Area vector of a convex polygon (fan), oriented along `outward`.
fn area_vector(poly: &[Vert], outward: Vector) -> Vector {
    let mut a = Vector::ZERO;
    for i in 1..poly.len().saturating_sub(1) {
        a += (poly[i].x - poly[0].x).cross(poly[i + 1].x - poly[0].x);
    }
    a *= 0.5;
    if a.dot(outward) < 0.0 {
        -a
    } else {
        a
    }
}

impl<A: Sdf + ?Sized, B: Sdf + ?Sized> Cutter<'_, '_, A, B> {
    fn distance(&self, s: usize, x: Vector) -> Real {
        if s == 0 {
            self.pair.a.distance(x)
        } else {
            self.pair.b.distance(x)
        }
    }

    /// The point where body `s`'s surface crosses the edge `p`–`q` (`p` inside, `q` outside),
    /// with the other body's distance there when a clip by the other body follows
    /// (`need_other`; NaN otherwise — computed later if a neighbouring cell needs it).
    fn cut(&mut self, s: usize, p: &Vert, q: &Vert) -> Vert {
        let o = 1 - s;
        let (lo, hi) = if p.node < q.node { (p, q) } else { (q, p) };
        let cached = hi.node != NOT_A_NODE;
        let slot = if cached { Some((lo.node as usize, self.cache.dir(lo.node, hi.node) - 1)) } else { None };
        let e = hi.x - lo.x;
        let mut d = [0.0; 2];
        if let Some((n, k)) = slot {
            let (t, other) = self.cache.t[s][n][k];
            if !t.is_nan() {
                let x = lo.x + e * t;
                d[o] = other;
                if other.is_nan() && self.need_other {
                    d[o] = self.distance(o, x);
                    self.cache.t[s][n][k].1 = d[o];
                }
                return Vert { x, d, node: NOT_A_NODE };
            }
        }
        let closed_form = if lo.d[s] == 0.0 || hi.d[s] == 0.0 {
            None
        } else if s == 0 {
            self.pair.a.segment_crossing(lo.x, hi.x)
        } else {
            self.pair.b.segment_crossing(lo.x, hi.x)
        };
        let t = closed_form.unwrap_or_else(|| {
            let f = |t: Real| self.distance(s, lo.x + e * t);
            // An edge made by the first clip (rim cells only) is used by this cell alone: a
            // loose crossing keeps its error within the piecewise-linear surface's.
            let tol = if cached { EDGE_TOL } else { CLIPPED_EDGE_TOL };
            crossing(f, (0.0, lo.d[s]), (1.0, hi.d[s]), tol, tol * e.length())
        });
        let x = lo.x + e * t;
        d[o] = if self.need_other { self.distance(o, x) } else { Real::NAN };
        if let Some((n, k)) = slot {
            self.cache.t[s][n][k] = (t, d[o]);
        }
        Vert { x, d, node: NOT_A_NODE }
    }

    /// Splits tetrahedron `p` by body `s`'s surface: calls `piece` with each tetrahedron of
    /// the part inside `s`, and `facet` with the cut polygon and a vector pointing out of `s`.
    fn clip(&mut self, s: usize, p: &[Vert; 4], piece: &mut impl FnMut(&mut Self, &[Vert; 4]), facet: &mut impl FnMut(&[Vert], Vector)) {
        let (mut neg, mut pos) = ([0usize; 4], [0usize; 4]);
        let (mut nn, mut np) = (0, 0);
        for i in 0..4 {
            if p[i].d[s] <= 0.0 {
                neg[nn] = i;
                nn += 1;
            } else {
                pos[np] = i;
                np += 1;
            }
        }
        let outward = || {
            let mean = |idx: &[usize]| idx.iter().map(|&i| p[i].x).sum::<Vector>() / idx.len() as Real;
            mean(&pos[..np]) - mean(&neg[..nn])
        };
        match nn {
            0 => {}
            4 => piece(self, p),
            1 => {
                let (i, [a, b, c]) = (neg[0], [pos[0], pos[1], pos[2]]);
                let q = [self.cut(s, &p[i], &p[a]), self.cut(s, &p[i], &p[b]), self.cut(s, &p[i], &p[c])];
                piece(self, &[p[i], q[0], q[1], q[2]]);
                facet(&q, outward());
            }
            3 => {
                // Prism (a, b, c) – (qa, qb, qc) as three tetrahedra.
                let (i, [a, b, c]) = (pos[0], [neg[0], neg[1], neg[2]]);
                let q = [self.cut(s, &p[a], &p[i]), self.cut(s, &p[b], &p[i]), self.cut(s, &p[c], &p[i])];
                piece(self, &[p[a], p[b], p[c], q[2]]);
                piece(self, &[p[a], p[b], q[1], q[2]]);
                piece(self, &[p[a], q[0], q[1], q[2]]);
                facet(&q, outward());
            }
            _ => {
                // Wedge (a, ac, ad) – (b, bc, bd) as three tetrahedra.
                let ([a, b], [c, d]) = ([neg[0], neg[1]], [pos[0], pos[1]]);
                let (ac, ad) = (self.cut(s, &p[a], &p[c]), self.cut(s, &p[a], &p[d]));
                let (bc, bd) = (self.cut(s, &p[b], &p[c]), self.cut(s, &p[b], &p[d]));
                piece(self, &[p[a], ac, ad, bd]);
                piece(self, &[p[a], ac, bc, bd]);
                piece(self, &[p[a], p[b], bc, bd]);
                facet(&[ac, bc, bd, ad], outward());
            }
        }
    }

    /// Clips `p` by body `first`, then by the other: adds `weight` times the volume and
    /// moment (the other order adds the rest) and the other body's facets to the normal.
    fn ordered(&mut self, first: usize, p: &[Vert; 4], weight: Real, sums: &mut Sums) {
        let second = 1 - first;
        self.need_other = true;
        self.clip(
            first,
            p,
            &mut |cutter, outer| {
                // The first clip's crossings are done; the second clip's are final.
                cutter.need_other = false;
                cutter.clip(
                    second,
                    outer,
                    &mut |_, r| {
                        for v in r {
                            sums.lo = sums.lo.min(v.x);
                            sums.hi = sums.hi.max(v.x);
                        }
                        let v = tet_volume(r) * weight;
                        sums.volume += v;
                        sums.moment += (r[0].x + r[1].x + r[2].x + r[3].x) * (0.25 * v);
                    },
                    &mut |poly, outward| {
                        let a = area_vector(poly, outward);
                        sums.normal[second] += a;
                        sums.area[second] += a.length();
                    },
                )
            },
            &mut |_, _| {},
        );
    }

    /// The overlap inside one tetrahedron of grid nodes. Where only one surface cuts it, one
    /// clip does; where both do (the rim), both clipping orders run and are averaged, so the
    /// result does not depend on which body is A.
    fn tet(&mut self, p: &[Vert; 4], sums: &mut Sums) {
        let inside = |s: usize| p.iter().all(|v| v.d[s] <= 0.0);
        if inside(0) {
            self.ordered(0, p, 1.0, sums);
        } else if inside(1) {
            self.ordered(1, p, 1.0, sums);
        } else {
            self.ordered(0, p, 0.5, sums);
            self.ordered(1, p, 0.5, sums);
        }
    }
}

/// Integrates the overlap on `grid` from node values `(d_A, d_B)`.
pub(crate) fn integrate<A: Sdf + ?Sized, B: Sdf + ?Sized>(pair: &Pair<'_, A, B>, grid: &Grid, values: &[(Real, Real)]) -> Integral {
    let n = grid.n;
    let m = n + 1;
    let h = grid.h;
    let cell = h.x * h.y * h.z;
    let mut cutter = Cutter { pair, cache: EdgeCache::new(values.len(), m), need_other: true };
    let inf = Vector::splat(Real::INFINITY);
    let mut it = Sums { volume: 0.0, moment: Vector::ZERO, normal: [Vector::ZERO; 2], area: [0.0; 2], lo: inf, hi: -inf };
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let corners: [Vert; 8] = core::array::from_fn(|c| {
                    let (ci, cj, ck) = (i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                    let node = grid.index(ci, cj, ck);
                    let (da, db) = values[node];
                    Vert { x: grid.node(ci, cj, ck), d: [da, db], node: node as u32 }
                });
                let all = |s: usize, inside: bool| corners.iter().all(|v| (v.d[s] <= 0.0) == inside);
                if all(0, false) || all(1, false) {
                    continue;
                }
                if all(0, true) && all(1, true) {
                    it.volume += cell;
                    it.moment += (corners[0].x + h * 0.5) * cell;
                    it.lo = it.lo.min(corners[0].x);
                    it.hi = it.hi.max(corners[7].x);
                    continue;
                }
                for tet in TETS {
                    cutter.tet(&tet.map(|c| corners[c]), &mut it);
                }
            }
        }
    }
    Integral {
        volume: it.volume,
        centroid: if it.volume > 0.0 { it.moment / it.volume } else { Vector::ZERO },
        // B's outward normal points from B to A, A's from A to B: both B→A as `n_B − n_A`.
        normal: blended_normal(it.normal, it.area),
        surface_area: it.area[0] + it.area[1],
        bounds: (it.volume > 0.0).then(|| Aabb::new(it.lo, it.hi)),
    }
}
