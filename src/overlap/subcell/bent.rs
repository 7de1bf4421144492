//! How one cell that both bodies reach is integrated: on its six tetrahedra, or — where a
//! body's surface is bent in it (an edge, a corner, a strongly curved side, a flat face's rim)
//! — clipped by the bodies' faces and tangent planes ([`crease`]), the planes following the
//! curved sides in rounds of a cutting-plane iteration. A cell that only polyhedral surfaces
//! pass through is clipped by their faces alone.

use super::{crease, Cutter, Plane, Vert, NOT_A_NODE, TETS};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// Points per body whose tangent planes clip a bent cell: corners, centre, face centres.
const SAMPLES: usize = 15;

/// Clip rounds at most per bent cell, of [`Cutter::refine`] and
/// [`Cutter::follow_smooth_parts`] together.
const REFINE_ROUNDS: usize = 16;

/// Rounds of [`Cutter::follow_smooth_parts`] at most per bent cell. Each takes the planes to
/// the vertices that still poke out of a curved side; two bring the side's outer error to the
/// order of the interpolated cells' inner one (both second order in the cell's size), and more
/// would bring the rim's cells within [`REFINE_TOL`] of the side at several times their cost
/// while the rest of the overlap keeps its error.
const FOLLOW_ROUNDS: usize = 2;

/// A vertex of a bent cell's polyhedron farther than this fraction of the cell's diagonal
/// outside a body is cut off by the body's tangent plane there.
const REFINE_TOL: Real = 1e-3;

/// A cell is bent when the distance at its centre differs from its corners' mean by more
/// than this fraction of its diagonal.
const BENT: Real = 0.005;

/// Body `body`'s tangent plane at `x`, where its distance is `d` and its gradient `g`: the plane
/// through the nearest surface point, with `g` made unit (a user SDF's gradient may be a finite
/// difference); `None` where the gradient has no direction.
fn tangent_plane(x: Vector, d: Real, g: Vector, body: usize) -> Option<Plane> {
    let n = g.normalize_or_zero();
    (n.is_finite() && n != Vector::ZERO).then(|| Plane { n, h: n.dot(x) - d, body })
}

/// Whether two planes of the same body are one (a flat face seen from many points, or two
/// nearby points of a curved one): the clip must not get a plane twice.
fn same_plane(p: &Plane, q: &Plane, tol: Real) -> bool {
    p.body == q.body && (p.n - q.n).length() <= 1e-12 && (p.h - q.h).abs() <= tol
}

impl<A: Sdf + ?Sized, B: Sdf + ?Sized> Cutter<'_, '_, A, B> {
    /// The overlap inside one cell of size `h` with corners `c`, not all in both bodies (the
    /// last argument: each body's corner inside bits, bit `i` for corner `i`): clipped by the
    /// bodies' tangent planes ([`crease`]) when a body's surface is bent in it — an edge or a
    /// corner of the body passes through; else on its six tetrahedra.
    ///
    /// A bent cell is told by the distance at its centre: for a flat surface it is the mean of
    /// the corners' (the SDF is linear there), on a smooth one within `h²/R` of it, and an edge
    /// or corner in the cell puts it a fraction of the cell's size below; a flat face's rim on
    /// one of the cell's faces is told apart ([`rim_on_face`](Self::rim_on_face)). The rules
    /// read both bodies alike (A↔B symmetry) and distances only (rigid-motion invariance). A
    /// body whose corners all lie outside and whose centre lies farther than half the diagonal
    /// does not reach into the cell (the SDF is 1-Lipschitz).
    pub(super) fn cell(&mut self, c: &[Vert; 8], h: Vector, [in_a, in_b]: [u8; 2]) {
        let centre = c[0].x + h * 0.5;
        let diagonal = h.length();
        let inside = [in_a, in_b];
        let tested = [self.edges[0] && in_a != 0xFF, self.edges[1] && in_b != 0xFF];
        let (ca, cb) = if tested[0] || tested[1] { self.pair.both(centre) } else { (0.0, 0.0) };
        if (tested[0] && in_a == 0 && ca > 0.5 * diagonal)
            || (tested[1] && in_b == 0 && cb > 0.5 * diagonal)
        {
            return;
        }
        let bent = |s: usize, d: Real| {
            let mean = c.iter().map(|v| v.d[s]).sum::<Real>() / 8.0;
            tested[s] && ((mean - d).abs() > BENT * diagonal || self.rim_on_face(s, c))
        };
        let bends = [bent(0, ca), bent(1, cb)];
        // A body with no corner inside reaches in only with an edge or a corner: bent.
        let reaches = |s: usize, inside: u8| inside != 0 || bends[s];
        if (bends[0] || bends[1]) && reaches(0, in_a) && reaches(1, in_b) {
            // A bent body's surface by its planes at all samples; a body that holds only part of
            // the cell but is not bent in it (a flat or gently curved face) by its plane at
            // the centre, as good as interpolation there.
            let samples = |s: usize, inside: u8| {
                if inside == 0xFF {
                    0
                } else if bends[s] {
                    SAMPLES
                } else {
                    1
                }
            };
            // A polyhedron's own faces, not its tangent planes at samples; a body with flat
            // faces those and its smooth part's plane at the centre, which the clip's rounds
            // follow along the curved side ([`Cutter::follow_smooth_parts`]).
            let samples = [0, 1].map(|s| {
                if self.faces[s].is_some() {
                    0
                } else if self.flats[s].is_some() {
                    usize::from(inside[s] != 0xFF)
                } else {
                    samples(s, inside[s])
                }
            });
            self.tangent_planes(c, samples, [ca, cb]);
            if !self.face_planes(c) {
                return;
            }
            let clip_tol = crease::tolerance(c[0].x, c[7].x);
            let mut clipped = crease::clip_cell(c[0].x, c[7].x, &mut self.scratch, false);
            let mut rounds = 0;
            let mut follows = 0;
            while let Some(k) = clipped {
                // Only a cell with no corner in both bodies can hold a polyhedron that misses
                // the overlap altogether (two bodies apart by less than the planes' error).
                if k.volume > 0.0 && rounds < REFINE_ROUNDS {
                    let len = self.scratch.planes.len();
                    let centroid = k.moment / k.volume;
                    let clips = samples.map(|n| n > 0);
                    if (in_a & in_b == 0 && self.refine(clips, diagonal, centroid))
                        || (follows < FOLLOW_ROUNDS && {
                            follows += 1;
                            self.follow_smooth_parts(clips, diagonal, clip_tol)
                        })
                    {
                        clipped = crease::clip_more(len, &mut self.scratch);
                        rounds += 1;
                        continue;
                    }
                }
                self.sums.add_clipped(&self.scratch.integrals(k));
                return;
            }
        }
        if in_a == 0 || in_b == 0 {
            return;
        }
        for tet in TETS {
            self.tet(&tet.map(|i| c[i]));
        }
    }

    /// Whether the rim of one of body `s`'s flat faces ([`Sdf::flat_faces`]) passes through
    /// cell `c`: the face's plane reaches the cell, and of the cell's corners some take their
    /// distance from the face (the distance is the plane's) and some from the rest of the body
    /// (it is greater). The distance test of [`cell`](Self::cell) misses a rim where the face
    /// lies near a node layer: the face's distance there is near zero at the corners on the
    /// layer, so hardly a kink shows at the cell's centre against the cell's diagonal, and
    /// crossings along the edges in the layer miss the rim. On a thin overlap's flat cells (a
    /// cylinder lying on a floor, whose caps the persistent grid puts on its end layers) such
    /// a cell interpolated across the rim loses a fifth of its volume.
    fn rim_on_face(&self, s: usize, c: &[Vert; 8]) -> bool {
        let Some(flats) = &self.flats[s] else { return false };
        let (lo, hi) = (c[0].x, c[7].x);
        let (mid, tol) = ((lo + hi) * 0.5, crease::tolerance(lo, hi));
        flats.iter().any(|(p, spread)| {
            if (p.n.dot(mid) - p.h).abs() > spread + tol {
                return false;
            }
            let (mut on, mut beyond) = (false, false);
            for v in c {
                let plane = p.n.dot(v.x) - p.h;
                on |= (v.d[s] - plane).abs() <= tol;
                beyond |= v.d[s] > plane + tol;
            }
            on && beyond
        })
    }

    /// The overlap in a cell `c` that only polyhedral surfaces may pass through: the cell
    /// clipped by their faces. `false` when the clip outgrew its buffers (the caller integrates
    /// the cell otherwise).
    pub(super) fn polyhedral_cell(&mut self, c: &[Vert; 8]) -> bool {
        self.scratch.planes.clear();
        if !self.face_planes(c) {
            return true;
        }
        match crease::clip_cell(c[0].x, c[7].x, &mut self.scratch, true) {
            Some(k) => {
                self.sums.add_clipped(&self.scratch.integrals(k));
                true
            }
            None => false,
        }
    }

    /// Adds to the cell's planes the faces of each polyhedral body, and the flat faces of a body
    /// that has them ([`Sdf::flat_faces`]), that cut the cell `c`, and
    /// those on its boundary whose facet the cell holds; `false` when a body does not reach
    /// into the cell (a face has the whole cell beyond it).
    ///
    /// A face lying on a node layer (as the persistent grid puts them, within round-off) is a
    /// facet of exactly one of the two cells it separates. Where both bodies are polyhedra,
    /// every cell is clipped, and the facet goes to the cell on the body's side: the face
    /// touches it, and the clip makes the cell's face on the plane the body's facet (see
    /// [`crease`]); the cell beyond holds nothing of the body and is skipped. Where the other
    /// body is round, the cells it is not bent in are integrated on tetrahedra, which give the
    /// facet to the cell on the body's side when a corner on the layer counts as outside the
    /// body (its distance's round-off), else to the cell beyond (a flat facet); the clip
    /// follows the same rule there.
    fn face_planes(&mut self, c: &[Vert; 8]) -> bool {
        let (lo, hi) = (c[0].x, c[7].x);
        let (mid, tol) = ((lo + hi) * 0.5, crease::tolerance(lo, hi));
        let pure = self.faces.iter().all(Option::is_some);
        let lists = self.faces.iter().enumerate().chain(self.flats.iter().enumerate());
        for (s, faces) in lists {
            let Some(faces) = faces else { continue };
            for (p, spread) in faces {
                let centre = p.n.dot(mid) - p.h;
                let (near, reach) = (centre - spread, centre + spread);
                if near > tol {
                    return false;
                }
                // The cell on the body's side holds the facet (a corner on the plane counts as
                // outside the body).
                let inner_side =
                    || pure || c.iter().any(|v| v.d[s] > 0.0 && (p.n.dot(v.x) - p.h).abs() <= tol);
                if near >= -tol {
                    // The cell lies beyond the face, its own face on the plane.
                    if inner_side() {
                        return false;
                    }
                    self.scratch.planes.push(*p);
                } else if reach > tol || (reach >= -tol && inner_side()) {
                    self.scratch.planes.push(*p);
                }
            }
        }
        true
    }

    /// Adds to the cell's planes the tangent plane of each clipping body (`clips`) at every
    /// vertex of the last clipped polyhedron that lies outside it by more than [`REFINE_TOL`]
    /// of the cell's `diagonal` or, when no vertex does, at the polyhedron's `centroid` if that
    /// lies outside it; whether it added any. None when a vertex or the centroid lies in both
    /// bodies (the overlap is real) or when the planes would not all fit: the cell keeps its
    /// last clip then.
    ///
    /// The sample planes hold the overlap with the surfaces' curvature error; on a strongly
    /// curved face (a cylinder's rim in a coarse cell) that error can exceed a thin gap and
    /// join two bodies that are apart. A plane at a vertex beyond the surface cuts that vertex
    /// off (a cutting-plane iteration), so each round brings the polyhedron closer to the true
    /// overlap, until it holds a point of both bodies or vanishes. The vertex planes stop at a
    /// tolerance of the cell's size, which in a coarse cell can exceed the gap; the plane at
    /// the centroid takes at least ~0.42 of the volume off (Grünbaum, 1960,
    /// doi:10.2140/pjm.1960.10.1257), whatever the gap, so two bodies apart leave nothing
    /// within a few rounds. Where the overlap is real the planes' outer error stays: it
    /// balances the interpolated cells' inner one. Both bodies are tested alike at every
    /// point and all planes found are added (the clip sorts them), so either labelling adds
    /// the same planes.
    fn refine(&mut self, clips: [bool; 2], diagonal: Real, centroid: Vector) -> bool {
        let tol = REFINE_TOL * diagonal;
        let pair = self.pair;
        self.scratch.gather_vertices();
        let crease::Scratch { vertices, planes, .. } = &mut self.scratch;
        let len = planes.len();
        let cut = |x: Vector, d: [Real; 2], tol: Real, planes: &mut Vec<Plane>| {
            for s in (0..2).filter(|&s| clips[s] && d[s] > tol) {
                let g = if s == 0 { pair.a.gradient(x) } else { pair.b.gradient(x) };
                let Some(plane) = tangent_plane(x, d[s], g, s) else { continue };
                if planes.len() == crease::MAX_PLANES {
                    return false;
                }
                planes.push(plane);
            }
            true
        };
        for &x in vertices.iter() {
            let d = pair.both(x);
            // A point of the overlap: the bodies do overlap in the cell.
            if (d.0 <= 0.0 && d.1 <= 0.0) || !cut(x, [d.0, d.1], tol, planes) {
                planes.truncate(len);
                return false;
            }
        }
        if planes.len() == len {
            let d = pair.both(centroid);
            if (d.0 <= 0.0 && d.1 <= 0.0) || !cut(centroid, [d.0, d.1], 0.0, planes) {
                planes.truncate(len);
                return false;
            }
        }
        planes.len() > len
    }

    /// Adds to the cell's planes the smooth part's tangent plane of each clipping body with flat
    /// faces (`clips`) at every vertex of the last clipped polyhedron that lies outside that
    /// part by more than [`REFINE_TOL`] of the cell's `diagonal` (`clip_tol` apart at least, so
    /// the clip never gets one plane twice); whether it added any (none when they would not
    /// all fit).
    ///
    /// The clip starts from the smooth part's plane at the cell's centre, which holds the part
    /// with its curvature error; each round cuts off the vertices beyond it (a cutting-plane
    /// iteration, as [`refine`](Self::refine)), so the polyhedron follows the curved side with
    /// the planes it needs ([`FOLLOW_ROUNDS`] rounds), while the flat faces keep the edges
    /// sharp. Both bodies are tested alike at every vertex and the clip sorts the planes, so
    /// either labelling adds the same planes.
    fn follow_smooth_parts(&mut self, clips: [bool; 2], diagonal: Real, clip_tol: Real) -> bool {
        let curved = [0, 1].map(|s| clips[s] && self.flats[s].is_some());
        if curved == [false; 2] {
            return false;
        }
        let tol = REFINE_TOL * diagonal;
        self.scratch.gather_vertices();
        let mut planes = std::mem::take(&mut self.scratch.planes);
        let len = planes.len();
        let mut fits = true;
        'vertices: for &x in &self.scratch.vertices {
            for s in (0..2).filter(|&s| curved[s]) {
                let (d, g) = self.smooth_part(s, x);
                if d <= tol {
                    continue;
                }
                let Some(plane) = tangent_plane(x, d, g, s) else { continue };
                if planes[len..].iter().any(|q| same_plane(q, &plane, clip_tol)) {
                    continue;
                }
                if planes.len() == crease::MAX_PLANES {
                    fits = false;
                    break 'vertices;
                }
                planes.push(plane);
            }
        }
        if !fits {
            planes.truncate(len);
        }
        self.scratch.planes = planes;
        self.scratch.planes.len() > len
    }

    /// Distance and gradient of body `s`'s smooth part at `x` ([`Sdf::smooth_part`]).
    fn smooth_part(&self, s: usize, x: Vector) -> (Real, Vector) {
        if s == 0 {
            self.pair.a.smooth_part(x)
        } else {
            self.pair.b.smooth_part(x)
        }
    }

    /// The tangent planes of each body at the first `samples` of the cell's centre (distances
    /// `centre`), its eight corners and its six face centres: an edge through the cell has
    /// points on each of its faces' sides among them, and a corner reaching in has its faces'
    /// nearest points. A body with flat faces gives its smooth part's planes
    /// ([`Sdf::smooth_part`]). They replace the scratch's planes.
    fn tangent_planes(&mut self, c: &[Vert; 8], samples: [usize; 2], centre: [Real; 2]) {
        let mid = (c[0].x + c[7].x) * 0.5;
        let mut points = [(mid, centre); SAMPLES];
        for (i, v) in c.iter().enumerate() {
            points[1 + i] = (v.x, v.d);
        }
        // The face centres' distances come with their gradients (one call each).
        let mut face_gradients = [[Vector::ZERO; 6]; 2];
        for f in 0..6 {
            let mut x = mid;
            x[f % 3] = if f < 3 { c[0].x[f % 3] } else { c[7].x[f % 3] };
            let mut d = [Real::NAN; 2];
            for s in 0..2 {
                if samples[s] == SAMPLES {
                    let (ds, gs) = self.distance_and_gradient(s, x);
                    d[s] = ds;
                    face_gradients[s][f] = gs;
                }
            }
            points[9 + f] = (x, d);
        }
        let mut planes = std::mem::take(&mut self.scratch.planes);
        planes.clear();
        let tol = crease::tolerance(c[0].x, c[7].x);
        for s in 0..2 {
            let smooth = self.flats[s].is_some();
            for (k, &(x, d)) in points[..samples[s]].iter().enumerate() {
                let gradient = |x: Vector| {
                    if s == 0 {
                        self.pair.a.gradient(x)
                    } else {
                        self.pair.b.gradient(x)
                    }
                };
                let (d, g) = if smooth {
                    self.smooth_part(s, x)
                } else if k >= 9 {
                    (d[s], face_gradients[s][k - 9])
                } else if (1..9).contains(&k) && c[k - 1].node() != NOT_A_NODE {
                    (d[s], self.cache.node_gradient(s, c[k - 1].node() as usize, || gradient(x)))
                } else {
                    (d[s], gradient(x))
                };
                let Some(plane) = tangent_plane(x, d, g, s) else { continue };
                // Only planes that cut the cell, each once per body (a flat face is seen from
                // many points): the same set whichever body is called A.
                if crease::cuts(&plane, c[0].x, c[7].x, tol)
                    && !planes.iter().any(|q| same_plane(q, &plane, tol))
                {
                    planes.push(plane);
                }
            }
        }
        self.scratch.planes = planes;
    }
}
