//! A grid cell that a body's edge or corner passes through, integrated as the cell clipped by
//! the bodies' tangent planes or faces.
//!
//! Linear interpolation between exact surface crossings (see [`subcell`](super::subcell)) is
//! second order where a surface is smooth, but it cuts off every edge and corner of a body: an
//! SDF is convex, so its linear interpolant lies above it and the interpolated body inside the
//! true one. In a cell an edge passes through, the lost volume is a fraction of the cell, and
//! a corner reaching between a cell's nodes is lost altogether; on thin overlaps of boxes at
//! random orientations those cells carry a large part of the volume.
//!
//! A convex body with an exact SDF lies in the half-space of its tangent plane at every point
//! `x`: `{y : ∇d(x)·(y − x) <= −d(x)}` (inside the body too: the gradient is a subgradient of
//! the convex `d`). Intersecting the cell with those planes at its corners and centre, for both
//! bodies, gives a polyhedron that holds the overlap within the cell. It is exact where every
//! face near the cell is the nearest face of one of those points — for flat-faced bodies, an
//! edge through the cell has corners on both of its faces' sides — and an outer approximation
//! with the surface's curvature error, second order, on a curved face such as a cylinder's
//! side. Its volume, first moment and facet area vectors (per body) are closed-form. A
//! polyhedron needs no samples: its own faces that cut the cell bound it there exactly, and a
//! cell that only polyhedral surfaces pass through is clipped by their faces alone.
//!
//! The planes are clipped in an order given by the geometry alone (sorted by their
//! coefficients), so swapping the bodies clips the same planes in the same order and the cell's
//! contribution is exactly the same, its facets only assigned to the other body.

use crate::math::{Real, Vector};

mod polyhedron;

use polyhedron::{cell_faces, clip, Links, Poly};

/// Vertex entries of all faces at most (a vertex counts once per face it is on); a polyhedron
/// that would need more sends the cell back to the tetrahedra.
const MAX_VERTS: usize = 256;

/// Planes at most per cell: the bodies' faces or flat faces that cut it, the tangent planes at
/// samples, and those the refining and following rounds add (see [`subcell`](super::subcell)).
pub(super) const MAX_PLANES: usize = 64;

/// Faces at most: the cell's six and one per plane.
const MAX_FACES: usize = 6 + MAX_PLANES;

/// [`MAX_VERTS`] for the cutting-plane box's polytope ([`Scratch::start_box`]), which gains a
/// face per cut over many rounds where the planes close in on a curved rim.
const BOX_VERTS: usize = 1024;

/// [`MAX_FACES`] for the cutting-plane box's polytope.
const BOX_FACES: usize = 256;

/// A tangent plane `n·y <= h` of body `body` (0: A, 1: B).
#[derive(Clone, Copy, Debug)]
pub(super) struct Plane {
    pub(super) n: Vector,
    pub(super) h: Real,
    pub(super) body: usize,
}

/// Buffers for clipping, kept between cells (two polyhedra: the clip reads one, writes the
/// other).
pub(super) struct Scratch {
    polys: Box<[Poly; 2]>,
    links: Box<Links>,
    /// The cap's points when its edges do not chain (degenerate cuts).
    cap: Vec<Vector>,
    /// Which of `polys` holds the last clip's result.
    current: usize,
    /// Distances from a plane below this count as on it (relative to the cell's size).
    tol: Real,
    /// Vertex entries and faces the clipped polyhedron may have ([`MAX_VERTS`] and
    /// [`MAX_FACES`] for a cell, more for the cutting-plane box).
    limits: (usize, usize),
    /// The result's distinct vertices, gathered by [`Scratch::gather_vertices`].
    pub(super) vertices: Vec<Vector>,
    /// The planes [`clip_cell`] and [`clip_more`] clip by.
    pub(super) planes: Vec<Plane>,
}

thread_local! {
    /// Each thread's clip buffers, kept between evaluations.
    static SPARE: std::cell::RefCell<Option<Scratch>> = const { std::cell::RefCell::new(None) };
}

impl Scratch {
    /// This thread's buffers (new ones the first time); [`give_back`](Self::give_back) after use.
    pub(super) fn take() -> Self {
        SPARE.with(|s| s.borrow_mut().take()).unwrap_or_else(Self::new)
    }

    /// Keeps the buffers for this thread's next [`take`](Self::take).
    pub(super) fn give_back(self) {
        SPARE.with(|s| *s.borrow_mut() = Some(self));
    }

    fn new() -> Self {
        Self {
            polys: Box::new([Poly::EMPTY, Poly::EMPTY]),
            links: Box::new(Links::new()),
            cap: Vec::with_capacity(2 * MAX_FACES),
            current: 0,
            tol: 0.0,
            limits: (MAX_VERTS, MAX_FACES),
            vertices: Vec::with_capacity(MAX_VERTS),
            planes: Vec::with_capacity(MAX_PLANES),
        }
    }

    /// The integrals of the last clip's polyhedron: its `measure` (the volume and first
    /// moment the clip returned) with each body's facet area vector and area, and its box.
    /// Apart from the clip because a cell's refining rounds read only the volume and the
    /// centroid, and only the last round's facets count.
    pub(super) fn integrals(&self, measure: Measure) -> Clipped {
        facets(&self.polys[self.current], measure)
    }

    /// Starts a polyhedron as the box `lo`–`hi`, to be cut by [`cut`](Self::cut) plane by
    /// plane (a cutting-plane search; cells go through [`clip_cell`]).
    pub(super) fn start_box(&mut self, lo: Vector, hi: Vector) {
        self.begin(lo, hi, (BOX_VERTS, BOX_FACES));
        cell_faces(lo, hi, &mut self.polys[0]);
    }

    /// Sets the clip's tolerance for the box `lo`–`hi` and its `limits`, the first polyhedron
    /// current.
    fn begin(&mut self, lo: Vector, hi: Vector, limits: (usize, usize)) {
        self.tol = tolerance(lo, hi);
        self.limits = limits;
        self.current = 0;
    }

    /// Keeps the part of the current polyhedron with `plane.n·x <= plane.h`; `None` (the
    /// polyhedron unchanged) when that would outgrow the buffers.
    pub(super) fn cut(&mut self, plane: Plane) -> Option<()> {
        if clip(self, plane)? {
            self.current = 1 - self.current;
        }
        Some(())
    }

    /// The current polyhedron's vertices (each stored once; one on the last plane may be left
    /// on no face, within the clip's tolerance of the polyhedron); none once it is cut away.
    pub(super) fn current_vertices(&self) -> &[Vector] {
        let poly = &self.polys[self.current];
        if poly.nf == 0 {
            &[]
        } else {
            poly.verts()
        }
    }

    /// Gathers into `vertices` the distinct vertices of the last clip's polyhedron.
    pub(super) fn gather_vertices(&mut self) {
        let Self { polys, vertices, current, .. } = self;
        vertices.clear();
        vertices.extend_from_slice(polys[*current].verts());
    }
}

/// Volume and first moment of a clipped cell (see [`Scratch::integrals`] for the rest).
#[derive(Clone, Copy)]
pub(super) struct Measure {
    pub(super) volume: Real,
    pub(super) moment: Vector,
}

/// Volume, first moment, per-body facet area vectors and areas, and the box of the clipped
/// cell.
pub(super) struct Clipped {
    pub(super) volume: Real,
    pub(super) moment: Vector,
    pub(super) normal: [Vector; 2],
    pub(super) area: [Real; 2],
    pub(super) lo: Vector,
    pub(super) hi: Vector,
}

/// Distances from a plane below this count as on it, in the box `lo`–`hi` (the clip's
/// tolerance, relative to the box's size).
pub(super) fn tolerance(lo: Vector, hi: Vector) -> Real {
    1e-12 * (hi - lo).length()
}

/// The least and the greatest of `n·x − h` over the corners `x` of the box `lo`–`hi`.
pub(super) fn span(plane: &Plane, lo: Vector, hi: Vector) -> (Real, Real) {
    let (mid, half) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
    let (centre, spread) = (plane.n.dot(mid) - plane.h, plane.n.abs().dot(half));
    (centre - spread, centre + spread)
}

/// Whether the plane cuts the box `lo`–`hi` at all (some corner lies beyond it by more than
/// `tol`): a plane that does not changes nothing and is left out.
pub(super) fn cuts(plane: &Plane, lo: Vector, hi: Vector, tol: Real) -> bool {
    span(plane, lo, hi).1 > tol
}

/// Sets the polyhedron to the cell `lo`–`hi` clipped by all of `scratch.planes` and returns
/// its volume and first moment ([`Scratch::integrals`] gives the rest); `None` when the
/// polyhedron would outgrow the buffers (the caller integrates the cell's tetrahedra instead).
/// Zero volume when the planes cut the cell away.
///
/// `deepest_first` clips the planes that cut deepest first (the largest share of the box's
/// span beyond them), so the polyhedron the others cut stays small and one that ends empty
/// does so early: for a polyhedron's own faces, whose clip is exact whatever the order. Else
/// the planes go by their coefficients, a plane with the whole cell on or beyond it first (a
/// body's face on the cell's boundary leaves at most that face for the others to cut).
pub(super) fn clip_cell(
    lo: Vector,
    hi: Vector,
    scratch: &mut Scratch,
    deepest_first: bool,
) -> Option<Measure> {
    scratch.begin(lo, hi, (MAX_VERTS, MAX_FACES));
    let poly = &mut scratch.polys[0];
    if excluded(&scratch.planes, lo, hi, 4.0 * scratch.tol) {
        poly.clear();
        return Some(measure(poly));
    }
    cell_faces(lo, hi, poly);
    if deepest_first {
        return clip_deepest_first(lo, hi, scratch);
    }
    let tol = scratch.tol;
    let flat = scratch.planes.iter().enumerate().filter(|(_, p)| span(p, lo, hi).0 >= -tol);
    if let Some((k, _)) = flat.min_by(|(_, p), (_, q)| order(p, q)) {
        scratch.planes.swap(0, k);
        if clip(scratch, scratch.planes[0])? {
            scratch.current = 1 - scratch.current;
        }
        return clip_more(1, scratch);
    }
    clip_more(0, scratch)
}

/// Clips the box `lo`–`hi`, already in the current polyhedron, by `scratch.planes`, those
/// that cut deepest first (see [`clip_cell`]).
fn clip_deepest_first(lo: Vector, hi: Vector, scratch: &mut Scratch) -> Option<Measure> {
    let (mid, half) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
    let depth = |p: &Plane| (p.n.dot(mid) - p.h) / p.n.abs().dot(half);
    scratch.planes.sort_unstable_by(|p, q| depth(q).total_cmp(&depth(p)).then(order(p, q)));
    clip_planes(0, scratch)
}

/// An order of planes by their coefficients alone, so the same for either labelling of the
/// bodies: the order a cell's planes are clipped in, or the tie-break after their depth.
pub(super) fn order(p: &Plane, q: &Plane) -> std::cmp::Ordering {
    (p.n.x.total_cmp(&q.n.x))
        .then(p.n.y.total_cmp(&q.n.y))
        .then(p.n.z.total_cmp(&q.n.z))
        .then(p.h.total_cmp(&q.h))
}

/// Whether two of the planes together leave nothing of the box `lo`–`hi`: every point of it
/// lies beyond one of them by more than `margin`. Then the clip would end empty (what it keeps
/// lies within its tolerance of every plane), so it is skipped: near a body's edge or where
/// two faces pass the cell apart, most of the cells a clip is asked for hold nothing.
///
/// For two planes `f_p(x) = n_p·x − h_p` this is exact (Farkas): the box misses both
/// half-spaces iff some mixture `t f_p + (1 − t) f_q`, `t ∈ [0, 1]`, is positive over all of
/// it. The mixture's least value over the box is concave and piecewise linear in `t`, with
/// kinks where a component of the mixed normal changes sign, so its maximum lies at a kink or
/// at an end (the ends are the planes alone). Three or more planes can exclude the box
/// together where no two do; those cells are clipped.
fn excluded(planes: &[Plane], lo: Vector, hi: Vector, margin: Real) -> bool {
    let least = |p: &Plane, q: &Plane, t: Real| {
        let mixture = Plane { n: p.n * t + q.n * (1.0 - t), h: p.h * t + q.h * (1.0 - t), ..*p };
        span(&mixture, lo, hi).0
    };
    planes.iter().enumerate().any(|(i, p)| {
        planes[i + 1..].iter().any(|q| {
            (0..3).any(|k| {
                let (a, b) = (p.n[k], q.n[k]);
                a * b < 0.0 && least(p, q, b / (b - a)) > margin
            })
        })
    })
}

/// Clips the polyhedron of the last [`clip_cell`] by `scratch.planes[from..]` and returns the
/// volume and first moment of what is left (`None` as there).
///
/// The planes are clipped in an order given by the geometry alone (sorted by their
/// coefficients): the same for either labelling of the bodies.
pub(super) fn clip_more(from: usize, scratch: &mut Scratch) -> Option<Measure> {
    scratch.planes[from..].sort_unstable_by(order);
    clip_planes(from, scratch)
}

/// Clips the current polyhedron by `scratch.planes[from..]` in their order and returns the
/// volume and first moment of what is left (`None` as in [`clip_cell`]).
fn clip_planes(from: usize, scratch: &mut Scratch) -> Option<Measure> {
    for k in from..scratch.planes.len() {
        if scratch.polys[scratch.current].nf == 0 {
            break;
        }
        if clip(scratch, scratch.planes[k])? {
            scratch.current = 1 - scratch.current;
        }
    }
    Some(measure(&scratch.polys[scratch.current]))
}

/// The box `lo`–`hi` clipped by `scratch.planes` (a whole overlap of two polyhedra bounded by
/// their faces, deepest first): its integrals, the footprint of the bodies' faces (half of
/// each, see [`footprint`](super::footprint)) and A's faces' flux ([`flux`](super::flux));
/// `None` when a face of the box is left (the box did not hold the overlap) or the
/// polyhedron would outgrow the buffers.
pub(super) fn clip_box(
    lo: Vector,
    hi: Vector,
    scratch: &mut Scratch,
) -> Option<(Clipped, super::footprint::Sums, super::flux::Sums)> {
    // No two-plane exclusion test first (as for a cell): it costs a pass over all pairs of
    // the bodies' faces, and the box holds the whole overlap, so it rarely excludes.
    scratch.begin(lo, hi, (MAX_VERTS, MAX_FACES));
    cell_faces(lo, hi, &mut scratch.polys[0]);
    let measure = clip_deepest_first(lo, hi, scratch)?;
    let clipped = scratch.integrals(measure);
    let poly = &scratch.polys[scratch.current];
    let mut footprint = super::footprint::Sums::default();
    let mut flux = super::flux::Sums::about((lo + hi) * 0.5);
    for f in poly.faces() {
        let body = f.body?;
        let p = |i: usize| poly.verts[poly.index[f.start + i] as usize];
        for i in 2..f.len {
            let triangle = [p(0), p(i - 1), p(i)];
            footprint.add_triangle(triangle, 0.5);
            if body == 0 {
                flux.add_triangle(triangle);
            }
        }
    }
    Some((clipped, footprint, flux))
}

/// Volume and first moment of `poly`: a tetrahedron from a point inside to each triangle of
/// a fan over each face.
fn measure(poly: &Poly) -> Measure {
    let mut out = Measure { volume: 0.0, moment: Vector::ZERO };
    if poly.nf == 0 {
        return out;
    }
    let inner = poly.verts().iter().copied().sum::<Vector>() / poly.nv as Real;
    for f in poly.faces() {
        let p = |i: usize| poly.verts[poly.index[f.start + i] as usize];
        // A fan of triangles from the face's first vertex, each the base of a tetrahedron
        // with its apex at `inner`; each vertex's offset is taken once.
        let p0 = p(0);
        let q0 = p0 - inner;
        let (mut p1, mut q1) = (p(1), p(1) - inner);
        for i in 2..f.len {
            let p2 = p(i);
            let q2 = p2 - inner;
            let v = q0.dot(q1.cross(q2)).abs() / 6.0;
            out.volume += v;
            out.moment += (inner + p0 + p1 + p2) * (0.25 * v);
            (p1, q1) = (p2, q2);
        }
    }
    out
}

/// `poly`'s integrals: its `measure`, each body's facet area vector and area, and its box.
fn facets(poly: &Poly, measure: Measure) -> Clipped {
    let mut out = Clipped {
        volume: measure.volume,
        moment: measure.moment,
        normal: [Vector::ZERO; 2],
        area: [0.0; 2],
        lo: Vector::splat(Real::INFINITY),
        hi: Vector::splat(Real::NEG_INFINITY),
    };
    if poly.nf == 0 {
        return out;
    }
    for f in poly.faces() {
        let Some(s) = f.body else { continue };
        let p = |i: usize| poly.verts[poly.index[f.start + i] as usize];
        let p0 = p(0);
        let (mut e1, mut a) = (p(1) - p0, Vector::ZERO);
        for i in 2..f.len {
            let e2 = p(i) - p0;
            a += e1.cross(e2);
            e1 = e2;
        }
        let area = 0.5 * a.length();
        out.normal[s] += f.normal * area;
        out.area[s] += area;
    }
    for v in poly.verts() {
        out.lo = out.lo.min(*v);
        out.hi = out.hi.max(*v);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cell cut by the plane x + y <= 1 keeps half of itself, its centroid at
    /// (1/3, 1/3, 1/2) of the prism, and one facet of area √2 along (1, 1, 0)/√2.
    #[test]
    fn a_cell_halved_by_a_diagonal_plane() {
        let n = Vector::new(1.0, 1.0, 0.0).normalize();
        let mut scratch = Scratch::new();
        scratch.planes.push(Plane { n, h: n.dot(Vector::new(0.5, 0.5, 0.0)), body: 1 });
        let c = clip_cell(Vector::ZERO, Vector::ONE, &mut scratch, false).unwrap();
        let c = scratch.integrals(c);
        assert!((c.volume - 0.5).abs() < 1e-14);
        let centroid = c.moment / c.volume;
        assert!((centroid - Vector::new(1.0 / 3.0, 1.0 / 3.0, 0.5)).length() < 1e-14);
        assert!((c.normal[1] - n * 2f64.sqrt()).length() < 1e-14 && c.area[0] == 0.0);
    }

    /// Two planes meeting in an edge through the cell (a box's edge) keep exactly the quarter
    /// they bound; a plane that misses the cell changes nothing, one beyond it empties it.
    #[test]
    fn an_edge_through_the_cell_is_kept_sharp() {
        let mut scratch = Scratch::new();
        scratch.planes.extend([
            Plane { n: Vector::X, h: 0.5, body: 0 },
            Plane { n: Vector::Y, h: 0.5, body: 0 },
            Plane { n: Vector::Z, h: 2.0, body: 1 },
        ]);
        let c = clip_cell(Vector::ZERO, Vector::ONE, &mut scratch, false).unwrap();
        let c = scratch.integrals(c);
        assert!((c.volume - 0.25).abs() < 1e-14);
        assert!((c.area[0] - 1.0).abs() < 1e-14 && c.area[1] == 0.0);
        scratch.planes.clear();
        scratch.planes.push(Plane { n: -Vector::Z, h: -1.5, body: 1 });
        assert_eq!(clip_cell(Vector::ZERO, Vector::ONE, &mut scratch, false).unwrap().volume, 0.0);
    }

    /// A second plane within round-off of the first (two nearby tangent planes of a curved
    /// side) leaves three corners of the first one's face on it and the fourth beyond it by
    /// just over the tolerance: the cell keeps its half, it does not collapse to that face.
    #[test]
    fn a_plane_within_round_off_of_a_face_keeps_the_volume() {
        let tilt = 1.5e-12;
        let n = Vector::new(1.0, tilt, tilt);
        let mut scratch = Scratch::new();
        scratch.planes.extend([
            Plane { n: Vector::X, h: 0.5, body: 1 },
            Plane { n: n / n.length(), h: 0.5 / n.length(), body: 1 },
        ]);
        let c = clip_cell(Vector::ZERO, Vector::ONE, &mut scratch, false).unwrap();
        let c = scratch.integrals(c);
        assert!((c.volume - 0.5).abs() < 1e-11, "volume {}", c.volume);
        assert!((c.normal[1] - Vector::X).length() < 1e-11, "facet {:?}", c.normal[1]);
    }
}
