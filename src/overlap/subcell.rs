//! Sub-cell integration: the overlap's surface is located exactly on the cut edges of the grid
//! and interpolated linearly between them, on the six tetrahedra of every cell it cuts (where
//! a surface leaves two corners of a tetrahedron on each side, its quadrilateral cut is split
//! along the diagonal that folds it convexly: the bodies are convex).
//!
//! Each tetrahedron is clipped by one body's surface and the pieces by the other's (which body
//! first is decided by the geometry, see `Cutter::tet`). Where a clipped edge is a grid edge,
//! the crossing is found by root finding on the exact SDF and cached for the evaluation
//! (neighbouring cells share it, so the surface is watertight); an edge the first clip made
//! (only in cells both surfaces cut) is solved once per cell, shared by the pieces and the
//! first body's facet that meet there. Cells are classified by their corners' inside bits
//! before any vertex is built.
//!
//! A cell that an edge or a corner of a body passes through is not interpolated: linear
//! interpolation cuts the edge off (see [`crease`], which clips such cells by the bodies'
//! tangent planes instead). Cells are told apart by the distance at their centre, and only for
//! bodies that may have edges ([`Sdf::has_edges`]); for those, cells whose corners all lie
//! outside a body but within a cell's diagonal of it are tested too — a corner may reach in
//! between the nodes. A polyhedron ([`Sdf::face_planes`], not enlarged) clips by its own faces
//! there, and a cell that only polyhedral surfaces pass through is clipped by their faces
//! without the test: a pair of polyhedra is integrated exactly. A smooth body cut by flat faces
//! ([`Sdf::flat_faces`], a cylinder or a cone, not enlarged) clips by those faces and its smooth
//! part's tangent plane, so its edges stay sharp; so does an enlarged polyhedron or cylinder, whose
//! faces moved out by the enlargement are the flat parts of its rounded surface and the whole
//! enlarged body its smooth part, so its rounding is followed, not bevelled.
//!
//! Root finding instead of interpolating SDF values matters: inside a cylinder or a box the
//! SDF has kinks (the nearest face changes), where interpolated values would misplace the
//! surface by a large fraction of a cell. With exact crossings the error is
//! the surface's curvature within a cell: second order. A body smooth and curved everywhere (a
//! ball, a capsule) may also add the layer between each of its facets and its surface
//! ([`Cutter::add_facet`]) and complete its area at the rims ([`Cutter::add_rim`]): its volume
//! is then third order ([`OverlapSettings::with_facet_bulge`](super::OverlapSettings::with_facet_bulge)).
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

use super::crease::{self, Plane};
use super::{blended_normal, crossing, Grid, Integral, Pair};
use super::{flux, footprint};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

mod bent;

/// Kuhn decomposition of the unit cell (corner bits: x = 1, y = 2, z = 4) into six tetrahedra
/// around the diagonal 0–7. Along each, the corner bits only grow, so every edge is a
/// "forward" edge from its lower corner in direction `upper ^ lower` (1..=7).
const TETS: [[usize; 4]; 6] =
    [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

/// Relative accuracy of a surface crossing on an edge (fraction of the edge, and distance
/// from the surface per edge length): far below the second-order discretisation error.
const EDGE_TOL: Real = 1e-7;

/// The same for an edge made by clipping (not shared with a neighbouring cell).
const CLIPPED_EDGE_TOL: Real = 1e-3;

/// No grid node: a point made by clipping.
const NOT_A_NODE: u32 = u32::MAX;

/// No key: a point made by the second clip (never an end of an edge that is cut again).
const NO_KEY: u64 = u64::MAX;

/// Tetrahedra cut by the other body within one cell share the second clip's crossings on the
/// first clip's edges; at most this many are remembered per cell.
const MEMO: usize = 48;

/// A vertex of a clipped piece: position, both distances, and a key naming the point within
/// the evaluation — a grid node, or body `s`'s crossing of a grid edge — so that crossings on
/// grid edges are cached by node and the second clip finds each crossing on an edge between
/// two named points once.
#[derive(Clone, Copy, Debug)]
struct Vert {
    x: Vector,
    d: [Real; 2],
    key: u64,
}

impl Vert {
    /// The grid node the vertex is, or [`NOT_A_NODE`].
    #[inline]
    fn node(&self) -> u32 {
        if self.key & 0xF == 0 && self.key != NO_KEY {
            (self.key >> 4) as u32
        } else {
            NOT_A_NODE
        }
    }

    /// The key of grid node `node`.
    fn node_key(node: u32) -> u64 {
        (node as u64) << 4
    }

    /// The key of body `s`'s crossing of the forward edge `k` (0..7) of node `lo`.
    fn crossing_key(lo: u32, k: usize, s: usize) -> u64 {
        ((lo as u64) << 4) | ((k as u64 + 1) << 1) | s as u64
    }
}

/// One cached crossing: the fraction along the forward edge, the other body's distance there
/// (NaN until a clip by the other body needs it), and the evaluation it was computed in.
#[derive(Clone, Copy)]
struct Slot {
    t: Real,
    other: Real,
    stamp: u32,
}

const EMPTY: Slot = Slot { t: 0.0, other: Real::NAN, stamp: 0 };

/// Per body, per node, per forward edge.
type Crossings = [Vec<[Slot; 7]>; 2];

/// Per body, per node: the distance gradient there and the evaluation it was computed in.
type NodeGradients = [Vec<(u32, Vector)>; 2];

/// Crossings of A's (0) and B's (1) surface on the forward edges of every node, and the
/// bodies' gradients at the nodes (a node is a corner of up to eight cells clipped by tangent
/// planes). A slot holds a value of this evaluation only when its stamp is this evaluation's:
/// the buffers are kept between evaluations and never cleared (a fill of the whole cache cost
/// more than the crossings of a small overlap).
struct EdgeCache {
    t: Crossings,
    gradients: NodeGradients,
    /// Per node, which bodies may reach its cells (see [`integrate`]); rewritten each evaluation.
    reach: Vec<u8>,
    stamp: u32,
    m: usize,
}

thread_local! {
    /// Each thread's edge-cache buffers and the last stamp used, kept between evaluations.
    static SPARE: std::cell::RefCell<(Crossings, NodeGradients, Vec<u8>, u32)> = const {
        std::cell::RefCell::new(([Vec::new(), Vec::new()], [Vec::new(), Vec::new()], Vec::new(), 0))
    };
}

impl EdgeCache {
    fn new(nodes: usize, m: usize) -> Self {
        let (mut t, mut gradients, reach, mut stamp) =
            SPARE.with(|s| std::mem::take(&mut *s.borrow_mut()));
        if stamp == u32::MAX {
            // Stamps wrapped: forget every slot once.
            t.iter_mut().for_each(Vec::clear);
            gradients.iter_mut().for_each(Vec::clear);
            stamp = 0;
        }
        stamp += 1;
        for v in &mut t {
            if v.len() < nodes {
                v.resize(nodes, [EMPTY; 7]);
            }
        }
        for v in &mut gradients {
            if v.len() < nodes {
                v.resize(nodes, (0, Vector::ZERO));
            }
        }
        Self { t, gradients, reach, stamp, m }
    }

    /// Body `s`'s gradient at node `n`: computed by `gradient` the first time this evaluation
    /// asks for it, kept after.
    #[inline]
    fn node_gradient(&mut self, s: usize, n: usize, gradient: impl FnOnce() -> Vector) -> Vector {
        let slot = &mut self.gradients[s][n];
        if slot.0 != self.stamp {
            *slot = (self.stamp, gradient());
        }
        slot.1
    }

    /// The slot of node `n`'s forward edge `k` of body `s`, if computed in this evaluation.
    #[inline]
    fn get(&self, s: usize, n: usize, k: usize) -> Option<&Slot> {
        let slot = &self.t[s][n][k];
        (slot.stamp == self.stamp).then_some(slot)
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
        let (t, gradients) = (std::mem::take(&mut self.t), std::mem::take(&mut self.gradients));
        let (reach, stamp) = (std::mem::take(&mut self.reach), self.stamp);
        SPARE.with(|s| *s.borrow_mut() = (t, gradients, reach, stamp));
    }
}

/// Finds surface crossings on edges (cached on grid edges, remembered per cell on the first
/// clip's edges).
struct Cutter<'p, 'a, A: ?Sized, B: ?Sized> {
    pair: &'p Pair<'a, A, B>,
    cache: EdgeCache,
    /// Whether crossings need the other body's distance (a second clip follows).
    need_other: bool,
    /// This cell's second-clip crossings: the two end keys (ordered), the body, the point.
    memo: [(u64, u64, usize, Vert); MEMO],
    memo_len: usize,
    sums: Sums,
    /// Whether each body may have edges or corners ([`Sdf::has_edges`]): only then are cells
    /// tested for being bent.
    edges: [bool; 2],
    /// Whether each body's facets carry the layer to its surface: with the setting on, for a
    /// body smooth and curved everywhere (no edge, not a half-space), the layer between each of
    /// its facets and its surface is added ([`Cutter::add_facet`]), and the area at the rims it
    /// shares with the other body is completed ([`Cutter::add_rim`]).
    bulge: [bool; 2],
    /// Buffers of the tangent-plane clip, reused from cell to cell.
    scratch: crease::Scratch,
    /// Each body's face planes when it is a polyhedron: its cells are clipped by those that cut
    /// them (the body within the cell exactly) instead of by tangent planes at samples.
    /// Each face comes with its spread over a cell, `|n|·h/2`: the cells all have the same size.
    faces: [Option<Vec<(Plane, Real)>>; 2],
    /// Each body's flat faces when it is a smooth body cut by planes ([`Sdf::flat_faces`]) or an
    /// enlarged body with faces (its faces moved out), with their spreads as for `faces`: its
    /// bent cells are clipped by those that cut them and by its smooth part's tangent planes.
    flats: [Option<Vec<(Plane, Real)>>; 2],
}

/// Volume, moment, normal and bounds summed over the clipped pieces.
struct Sums {
    volume: Real,
    moment: Vector,
    footprint: footprint::Sums,
    /// A's facets' moments ([`flux`]).
    flux: flux::Sums,
    /// Area vectors of A's facets (oriented out of A) and of B's (out of B) and their areas.
    normal: [Vector; 2],
    area: [Real; 2],
    lo: Vector,
    hi: Vector,
}

impl Sums {
    /// Adds a clipped cell's integrals; a cell whose clip left only a body's face on its
    /// boundary adds that facet alone.
    fn add_clipped(&mut self, k: &crease::Clipped) {
        if k.volume > 0.0 {
            self.volume += k.volume;
            self.moment += k.moment;
            self.lo = self.lo.min(k.lo);
            self.hi = self.hi.max(k.hi);
        }
        for s in 0..2 {
            self.normal[s] += k.normal[s];
            self.area[s] += k.area[s];
        }
    }

    /// Adds body `s`'s facet `poly` (oriented along `outward`) to its area vector and area;
    /// returns the facet's area vector.
    fn add_facet(&mut self, s: usize, poly: &[Vert], outward: Vector) -> Vector {
        let a = area_vector(poly, outward);
        self.normal[s] += a;
        self.area[s] += a.length();
        a
    }
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

    /// Body `s`'s distance and outward unit gradient at `x`, in one call.
    fn distance_and_gradient(&self, s: usize, x: Vector) -> (Real, Vector) {
        if s == 0 {
            self.pair.a.distance_and_gradient(x)
        } else {
            self.pair.b.distance_and_gradient(x)
        }
    }

    /// The point where body `s`'s surface crosses the edge `p`–`q` (`p` inside, `q` outside),
    /// with the other body's distance there when a clip by the other body follows
    /// (`need_other`; NaN otherwise — computed later if a neighbouring cell needs it).
    fn cut(&mut self, s: usize, p: &Vert, q: &Vert) -> Vert {
        let o = 1 - s;
        let (pn, qn) = (p.node(), q.node());
        let ((lo, lo_node), (hi, hi_node)) =
            if pn < qn { ((p, pn), (q, qn)) } else { ((q, qn), (p, pn)) };
        let cached = hi_node != NOT_A_NODE;
        let slot = if cached {
            Some((lo_node as usize, self.cache.dir(lo_node, hi_node) - 1))
        } else {
            None
        };
        let key = slot.map_or(NO_KEY, |(n, k)| Vert::crossing_key(n as u32, k, s));
        let e = hi.x - lo.x;
        let mut d = [0.0; 2];
        if let Some((n, k)) = slot {
            if let Some(&Slot { t, other, .. }) = self.cache.get(s, n, k) {
                let x = lo.x + e * t;
                d[o] = other;
                if other.is_nan() && self.need_other {
                    d[o] = self.distance(o, x);
                    self.cache.t[s][n][k].other = d[o];
                }
                return Vert { x, d, key };
            }
        }
        // An edge the first clip made, between two named points: its crossing may be known.
        let ends = (p.key != NO_KEY && q.key != NO_KEY && !cached)
            .then(|| (p.key.min(q.key), p.key.max(q.key)));
        if let Some((k0, k1)) = ends {
            if let Some(m) =
                self.memo[..self.memo_len].iter().find(|m| m.0 == k0 && m.1 == k1 && m.2 == s)
            {
                return m.3;
            }
        }
        // The closed form runs from the inside end `p`; the fraction is kept from `lo`.
        let closed_form = if p.d[s] == 0.0 || q.d[s] == 0.0 {
            None
        } else if s == 0 {
            self.pair.a.segment_crossing(p.x, q.x)
        } else {
            self.pair.b.segment_crossing(p.x, q.x)
        };
        let t = match closed_form {
            Some(t) if std::ptr::eq(lo, p) => t,
            Some(t) => 1.0 - t,
            None => {
                let f = |t: Real| self.distance(s, lo.x + e * t);
                // An edge made by the first clip (rim cells only) is used by this cell alone: a
                // loose crossing keeps its error within the piecewise-linear surface's.
                let tol = if cached { EDGE_TOL } else { CLIPPED_EDGE_TOL };
                crossing(f, (0.0, lo.d[s]), (1.0, hi.d[s]), tol, tol * e.length())
            }
        };
        let x = lo.x + e * t;
        d[o] = if self.need_other { self.distance(o, x) } else { Real::NAN };
        if let Some((n, k)) = slot {
            self.cache.t[s][n][k] = Slot { t, other: d[o], stamp: self.cache.stamp };
        }
        let v = Vert { x, d, key };
        if let Some((k0, k1)) = ends {
            if self.memo_len < MEMO {
                self.memo[self.memo_len] = (k0, k1, s, v);
                self.memo_len += 1;
            }
        }
        v
    }

    /// Adds body `s`'s facet `poly` (oriented along `outward`) to the normal's area vectors and
    /// returns its area vector; where `s` is smooth and the facet bulge is on
    /// ([`Cutter::bulge`]), also adds the layer between the facet and the surface over it. The
    /// facet's corners lie on the surface (at the rim, on the other body's) and the facet inside
    /// the convex body, so the layer's height `q = −d_s` is quadratic over the facet to leading
    /// order: `∫q = A (¾ q(centroid) + Σ q(corner) / 12)` over each triangle is exact for a
    /// quadratic, and makes the volume third order.
    #[inline(always)]
    fn add_facet(&mut self, s: usize, poly: &[Vert], outward: Vector) -> Vector {
        let area = self.sums.add_facet(s, poly, outward);
        if self.bulge[s] && poly.len() >= 3 {
            self.add_layer(s, poly);
        }
        area
    }

    /// The layer of [`add_facet`](Self::add_facet).
    #[inline(never)]
    fn add_layer(&mut self, s: usize, poly: &[Vert]) {
        let height =
            |c: &Self, v: &Vert| if v.d[s].is_nan() { -c.distance(s, v.x) } else { -v.d[s] };
        let q0 = height(self, &poly[0]);
        let mut q_prev = height(self, &poly[1]);
        for i in 2..poly.len() {
            let q_next = height(self, &poly[i]);
            let (a, b, c) = (poly[0].x, poly[i - 1].x, poly[i].x);
            let area = 0.5 * (b - a).cross(c - a).length();
            let centre = (a + b + c) / 3.0;
            let layer = area * (0.75 * -self.distance(s, centre) + (q0 + q_prev + q_next) / 12.0);
            self.sums.volume += layer;
            self.sums.moment += centre * layer;
            q_prev = q_next;
        }
    }

    /// Completes the surface area at the rim of body `first`'s facet `poly` (area vector `area`,
    /// out of `first`; clipped by the other body) where a body is smooth. Along an edge of `poly`
    /// with both ends on the other surface, the overlap's surface ends at the straight edge; the
    /// two bodies' surfaces meet beyond it, on the rim's curve and past the layer `first`'s
    /// facet leaves out. Across the edge, at a point `x` with distances `d_f`, `d_o` and unit
    /// gradients `g_f`, `g_o` (without their parts along the edge, `c = g_f·g_o`), the
    /// surfaces' tangent planes meet at `x + α g_f + β g_o`, `α + c β = −d_f`, `c α + β = −d_o`:
    /// `first`'s surface reaches `β √(1 − c²)` further, the other's `α √(1 − c²)` (no less than
    /// nothing, and only where the surfaces meet in an acute wedge, `c < 0`), and Simpson's rule
    /// over the edge's ends and middle gives each strip's area. Where `Cutter::tet` runs both
    /// orders (an exact tie, rare) no rim is completed. Without it the area stays second order
    /// while the layers make the volume third, and the volume law's exponent `d s / 2V` of a cap
    /// falls below 2 (the stiffness then follows the grid).
    #[inline(never)]
    fn add_rim(&mut self, first: usize, poly: &[Vert], area: Vector) {
        let other = 1 - first;
        let n_first = area.normalize_or_zero();
        if n_first == Vector::ZERO {
            return;
        }
        // A rim edge joins two points the clip cut on the facet's edges: on the other surface
        // (`d_o = 0`) and not corners of the facet (which lie on `first`'s, `d_f = 0`; a corner
        // that lies on both to the last bit is not a cut).
        let cut = |v: &Vert| v.d[other] == 0.0 && v.d[first] != 0.0;
        for i in 0..poly.len() {
            let (p, q) = (&poly[i], &poly[(i + 1) % poly.len()]);
            if !(cut(p) && cut(q)) {
                continue;
            }
            let (u, v) = (p.x, q.x);
            let length = (v - u).length();
            if !(length > 0.0) {
                continue;
            }
            let t = (v - u) / length;
            let across = |g: Vector| (g - t * g.dot(t)).normalize_or_zero();
            let mut g_other = Vector::ZERO;
            let mut rim = |c: &Self, x: Vector| {
                let ((d_f, g_f), (d_o, g_o)) =
                    (c.distance_and_gradient(first, x), c.distance_and_gradient(other, x));
                let (g_f, g_o) = (across(g_f), across(g_o));
                g_other += g_o;
                let cos = g_f.dot(g_o);
                let sin2 = 1.0 - cos * cos;
                // Only a rim where the surfaces close the overlap in an acute wedge (outward
                // normals more than a right angle apart) is completed.
                if !(sin2 > 0.0 && cos < 0.0) {
                    return [0.0; 2];
                }
                let (alpha, beta) = ((-d_f + cos * d_o) / sin2, (-d_o + cos * d_f) / sin2);
                [(beta * sin2.sqrt()).max(0.0), (alpha * sin2.sqrt()).max(0.0)]
            };
            let (a, m, b) = (rim(self, u), rim(self, (u + v) * 0.5), rim(self, v));
            let [strip_f, strip_o] = [0, 1].map(|k| length * (a[k] + 4.0 * m[k] + b[k]) / 6.0);
            if strip_f.is_finite() && strip_o.is_finite() {
                self.sums.area[first] += strip_f;
                self.sums.normal[first] += n_first * strip_f;
                self.sums.area[other] += strip_o;
                self.sums.normal[other] += g_other.normalize_or_zero() * strip_o;
            }
        }
    }

    /// Splits tetrahedron `p` by body `s`'s surface: calls `piece` with each tetrahedron of
    /// the part inside `s`, then `facet` with each triangle of the cut (the wedge's
    /// quadrilateral split along its pieces' diagonal) and a vector pointing out of `s`.
    fn clip(
        &mut self,
        s: usize,
        p: &[Vert; 4],
        piece: &mut impl FnMut(&mut Self, &[Vert; 4]),
        facet: &mut impl FnMut(&mut Self, &[Vert; 3], Vector),
    ) {
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
            let mean =
                |idx: &[usize]| idx.iter().map(|&i| p[i].x).sum::<Vector>() / idx.len() as Real;
            mean(&pos[..np]) - mean(&neg[..nn])
        };
        match nn {
            0 => {}
            4 => piece(self, p),
            1 => {
                let (i, [a, b, c]) = (neg[0], [pos[0], pos[1], pos[2]]);
                let q = [
                    self.cut(s, &p[i], &p[a]),
                    self.cut(s, &p[i], &p[b]),
                    self.cut(s, &p[i], &p[c]),
                ];
                piece(self, &[p[i], q[0], q[1], q[2]]);
                facet(self, &q, outward());
            }
            3 => {
                // Prism (a, b, c) – (qa, qb, qc) as three tetrahedra.
                let (i, [a, b, c]) = (pos[0], [neg[0], neg[1], neg[2]]);
                let q = [
                    self.cut(s, &p[a], &p[i]),
                    self.cut(s, &p[b], &p[i]),
                    self.cut(s, &p[c], &p[i]),
                ];
                piece(self, &[p[a], p[b], p[c], q[2]]);
                piece(self, &[p[a], p[b], q[1], q[2]]);
                piece(self, &[p[a], q[0], q[1], q[2]]);
                facet(self, &q, outward());
            }
            _ => {
                // Wedge (a, ac, ad) – (b, bc, bd) as three tetrahedra.
                let ([a, b], [c, d]) = ([neg[0], neg[1]], [pos[0], pos[1]]);
                let (ac, ad) = (self.cut(s, &p[a], &p[c]), self.cut(s, &p[a], &p[d]));
                let (bc, bd) = (self.cut(s, &p[b], &p[c]), self.cut(s, &p[b], &p[d]));
                let out = outward();
                // The cut, the quadrilateral ac–bc–bd–ad, is split along the diagonal that
                // folds it convexly (seen from inside): its four points lie on a convex
                // body, and the concave fold lies inside the convex one by the whole fold.
                // Along ac–bd unless ad lies outside the plane of (ac, bc, bd).
                let n = (bc.x - ac.x).cross(bd.x - ac.x);
                let n = if n.dot(out) < 0.0 { -n } else { n };
                if n.dot(ad.x - ac.x) > 0.0 {
                    piece(self, &[p[a], p[b], bc, bd]);
                    piece(self, &[p[a], bc, bd, ad]);
                    piece(self, &[p[a], ac, bc, ad]);
                    facet(self, &[ac, bc, ad], out);
                    facet(self, &[bc, bd, ad], out);
                } else {
                    piece(self, &[p[a], ac, ad, bd]);
                    piece(self, &[p[a], ac, bc, bd]);
                    piece(self, &[p[a], p[b], bc, bd]);
                    facet(self, &[ac, bc, bd], out);
                    facet(self, &[ac, bd, ad], out);
                }
            }
        }
    }

    /// The part of triangle `tri` inside body `s` (at most a quadrilateral) and its length.
    fn clip_triangle(&mut self, s: usize, tri: &[Vert; 3]) -> ([Vert; 4], usize) {
        let mut out = [tri[0]; 4];
        let mut len = 0;
        for i in 0..3 {
            let (u, v) = (&tri[i], &tri[(i + 1) % 3]);
            let (u_in, v_in) = (u.d[s] <= 0.0, v.d[s] <= 0.0);
            if u_in {
                out[len] = *u;
                len += 1;
            }
            if u_in != v_in {
                out[len] = if u_in { self.cut(s, u, v) } else { self.cut(s, v, u) };
                len += 1;
            }
        }
        (out, len)
    }

    /// Clips `p` by body `first`, then by the other: adds `weight` times the volume and
    /// moment and the other body's facets to the normal; with `own_facets`, also the first
    /// body's facets, clipped by the other body.
    fn ordered(&mut self, first: usize, p: &[Vert; 4], weight: Real, own_facets: bool) {
        let second = 1 - first;
        self.need_other = true;
        self.clip(
            first,
            p,
            &mut |cutter, outer| cutter.last_clip(second, outer, weight),
            &mut |cutter, tri, outward| {
                if own_facets {
                    cutter.need_other = false;
                    let (poly, len) = cutter.clip_triangle(second, tri);
                    let area = cutter.add_facet(first, &poly[..len], outward);
                    if cutter.bulge != [false; 2] {
                        cutter.add_rim(first, &poly[..len], area);
                    }
                }
            },
        );
    }

    /// Clips `outer`, a piece inside the other body, by body `second`: adds `weight` times the
    /// volume and moment of what lies inside, and `second`'s facets to the normal.
    fn last_clip(&mut self, second: usize, outer: &[Vert; 4], weight: Real) {
        // The first clip's crossings are done; the second clip's are final.
        self.need_other = false;
        self.clip(
            second,
            outer,
            &mut |cutter, r| {
                let sums = &mut cutter.sums;
                for v in r {
                    sums.lo = sums.lo.min(v.x);
                    sums.hi = sums.hi.max(v.x);
                }
                let v = tet_volume(r) * weight;
                sums.volume += v;
                sums.moment += (r[0].x + r[1].x + r[2].x + r[3].x) * (0.25 * v);
            },
            &mut |cutter, tri, outward| {
                cutter.add_facet(second, tri, outward);
            },
        );
    }

    /// The overlap inside one tetrahedron of grid nodes. Where only one surface cuts it, one
    /// clip does. Where both do (the rim), one order runs: the body with more corners inside
    /// clips first (then the smaller sum of corner distances) — a choice by the geometry, not
    /// by which body is called A, so the result is the same either way — and its facets are
    /// clipped by the second body. Only when the rule cannot choose (equal counts and sums) do
    /// both orders run, averaged. Of the two single-order rules this one is the more
    /// accurate on the Hertz cases, and no less accurate there than both orders averaged.
    fn tet(&mut self, p: &[Vert; 4]) {
        let count = |s: usize| p.iter().filter(|v| v.d[s] <= 0.0).count();
        let (na, nb) = (count(0), count(1));
        // Wholly inside one body, the first clip keeps the tetrahedron whole: only the second
        // runs (the same arithmetic as `ordered`).
        if na == 4 {
            self.last_clip(1, p, 1.0);
        } else if nb == 4 {
            self.last_clip(0, p, 1.0);
        } else {
            let sum = |s: usize| p.iter().map(|v| v.d[s]).sum::<Real>();
            let first = match nb.cmp(&na).then_with(|| sum(0).total_cmp(&sum(1))) {
                std::cmp::Ordering::Less => 0,
                std::cmp::Ordering::Greater => 1,
                std::cmp::Ordering::Equal => {
                    self.ordered(0, p, 0.5, false);
                    self.ordered(1, p, 0.5, false);
                    return;
                }
            };
            self.ordered(first, p, 1.0, true);
        }
    }
}

/// Integrates the overlap on `grid` from node values `(d_A, d_B)`.
pub(crate) fn integrate<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    grid: &Grid,
    values: &[(Real, Real)],
) -> Integral {
    let n = grid.n;
    let m = n + 1;
    let h = grid.h;
    let diagonal = h.length();
    let cell = h.x * h.y * h.z;
    let unset = Vert { x: Vector::ZERO, d: [0.0; 2], key: NO_KEY };
    let inf = Vector::splat(Real::INFINITY);
    let sums = Sums {
        volume: 0.0,
        moment: Vector::ZERO,
        footprint: footprint::Sums::default(),
        flux: flux::Sums::about(grid.bounds().center()),
        normal: [Vector::ZERO; 2],
        area: [0.0; 2],
        lo: inf,
        hi: -inf,
    };
    // A face with the whole grid inside its half-space, by more than any cell's clip
    // tolerance, neither cuts nor bounds a cell ([`Cutter::face_planes`]): it is left out.
    let Aabb { mins: grid_lo, maxs: grid_hi } = grid.bounds();
    let inside_tol = crease::tolerance(grid_lo, grid_hi);
    let faces = |body: usize, planes: Option<Vec<(Vector, Real)>>| {
        let spread = |n: Vector| n.abs().dot(h * 0.5);
        planes.map(|p| {
            p.into_iter()
                .map(|(n, h)| Plane { n, h, body })
                .filter(|p| crease::span(p, grid_lo, grid_hi).1 >= -inside_tol)
                .map(|p| (p, spread(p.n)))
                .collect()
        })
    };
    let planes = [pair.a.exact_planes(), pair.b.exact_planes()];
    // A polyhedron's faces already bound it: flat faces count only for a body without them.
    let flats = [
        if planes[0].is_none() { pair.a.exact_flat_faces() } else { None },
        if planes[1].is_none() { pair.b.exact_flat_faces() } else { None },
    ];
    let [planes_a, planes_b] = planes;
    let [flats_a, flats_b] = flats;
    let mut cutter = Cutter {
        pair,
        cache: EdgeCache::new(values.len(), m),
        need_other: true,
        memo: [(0, 0, 0, unset); MEMO],
        memo_len: 0,
        sums,
        edges: [pair.a.has_edges(), pair.b.has_edges()],
        bulge: [
            pair.facet_bulge && pair.a.is_smooth_and_curved(),
            pair.facet_bulge && pair.b.is_smooth_and_curved(),
        ],
        scratch: crease::Scratch::take(),
        faces: [faces(0, planes_a), faces(1, planes_b)],
        flats: [faces(0, flats_a), faces(1, flats_b)],
    };
    let offsets = [0, 1, m, m + 1, m * m, m * m + 1, m * m + m, m * m + m + 1];
    let edges = cutter.edges;
    // Per node: bit `s` set when body `s` may reach a cell with the node as a corner.
    let reach_within = |s: usize| if edges[s] { diagonal } else { 0.0 };
    let (within_a, within_b) = (reach_within(0), reach_within(1));
    let mut reach = std::mem::take(&mut cutter.cache.reach);
    reach.clear();
    reach.extend(
        values.iter().map(|&(da, db)| (da <= within_a) as u8 | ((db <= within_b) as u8) << 1),
    );
    let polyhedral = [cutter.faces[0].is_some(), cutter.faces[1].is_some()];
    // Where both bodies are polyhedra, a face on a node layer is the facet of the cell on its
    // body's side ([`Cutter::face_planes`]), even one wholly inside both bodies.
    let face_tol = crease::tolerance(Vector::ZERO, h);
    let on_face = |far: Real| polyhedral == [true; 2] && far >= -face_tol;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                // Classify by the corners' inside bits before building any vertex: most cells
                // of a box lie wholly outside one body.
                let base = grid.index(i, j, k);
                // A body reaches into a cell when a corner lies inside it — or, for a body with
                // edges, when a corner lies within the cell's diagonal: an edge or a corner may
                // reach between the nodes.
                let reached = offsets.iter().fold(0u8, |f, off| f | reach[base + off]);
                if reached != 3 {
                    continue;
                }
                let (mut far_a, mut far_b) = (Real::NEG_INFINITY, Real::NEG_INFINITY);
                let (mut in_a, mut in_b) = (0u8, 0u8);
                for (c, off) in offsets.into_iter().enumerate() {
                    let (da, db) = values[base + off];
                    far_a = far_a.max(da);
                    far_b = far_b.max(db);
                    in_a |= ((da <= 0.0) as u8) << c;
                    in_b |= ((db <= 0.0) as u8) << c;
                }
                let origin = grid.node(i, j, k);
                if in_a == 0xFF && in_b == 0xFF && !on_face(far_a) && !on_face(far_b) {
                    let it = &mut cutter.sums;
                    it.volume += cell;
                    it.moment += (origin + h * 0.5) * cell;
                    it.lo = it.lo.min(origin);
                    it.hi = it.hi.max(origin + h);
                    continue;
                }
                let corners: [Vert; 8] = core::array::from_fn(|c| {
                    let node = base + offsets[c];
                    let (da, db) = values[node];
                    Vert {
                        x: origin + h * corner(c),
                        d: [da, db],
                        key: Vert::node_key(node as u32),
                    }
                });
                let (volume, moment, area, normal_a) = (
                    cutter.sums.volume,
                    cutter.sums.moment,
                    cutter.sums.area[0] + cutter.sums.area[1],
                    cutter.sums.normal[0],
                );
                // Every surface that may pass through the cell is a polyhedron's: the cell
                // clipped by their faces is the overlap in it, exactly.
                let clipped = (in_a == 0xFF || polyhedral[0])
                    && (in_b == 0xFF || polyhedral[1])
                    && cutter.polyhedral_cell(&corners);
                if !clipped {
                    cutter.memo_len = 0;
                    cutter.cell(&corners, h, [in_a, in_b]);
                }
                // The footprint and A's flux cell by cell: the cell's facets at the centroid of
                // its part of the overlap, or at its centre where it holds a facet alone (a
                // body's face on a node layer goes to the cell on the body's side, which may
                // hold no volume).
                let it = &mut cutter.sums;
                let part = it.volume - volume;
                let facets = 0.5 * (it.area[0] + it.area[1] - area);
                if facets > 0.0 {
                    let at =
                        if part > 0.0 { (it.moment - moment) / part } else { origin + h * 0.5 };
                    it.footprint.add(at, h, facets);
                    let a = it.normal[0] - normal_a;
                    if a != Vector::ZERO {
                        it.flux.add(at, a);
                    }
                }
            }
        }
    }
    cutter.cache.reach = reach;
    let Cutter { sums: it, scratch, .. } = cutter;
    scratch.give_back();
    let centroid = if it.volume > 0.0 { it.moment / it.volume } else { Vector::ZERO };
    Integral {
        volume: it.volume,
        centroid,
        footprint: it.footprint.finish(),
        flux: it.flux.finish(centroid),
        // B's outward normal points from B to A, A's from A to B: both B→A as `n_B − n_A`.
        normal: blended_normal(it.normal, it.area),
        surface_area: it.area[0] + it.area[1],
        bounds: (it.volume > 0.0).then(|| Aabb::new(it.lo, it.hi)),
    }
}

/// Corner `c` of the unit cell (bits: x = 1, y = 2, z = 4).
#[inline]
fn corner(c: usize) -> Vector {
    Vector::new((c & 1) as Real, ((c >> 1) & 1) as Real, ((c >> 2) & 1) as Real)
}
