//! The polyhedron a cell's or a box's clip works on, and its clip by one plane: each vertex
//! stored once, faces as cycles of vertex indices, in fixed buffers kept between clips.

use super::{Plane, Scratch, BOX_FACES, BOX_VERTS};
use crate::math::{Real, Vector};

/// Vertices a polyhedron's buffer holds: a clip of one within the limits adds at most one
/// per edge cut (`BOX_VERTS / 2` edges at most).
const CAP_VERTS: usize = BOX_VERTS + BOX_VERTS / 2 + 8;

/// Index entries a polyhedron's buffer holds: the clipped faces gain at most one each, and
/// the cap takes at most one per vertex.
const CAP_INDEX: usize = BOX_VERTS + BOX_FACES + CAP_VERTS + 8;

/// Faces a polyhedron's buffer holds: the clipped ones and the cap.
const CAP_FACES: usize = BOX_FACES + 1;

/// No vertex: a vertex the clip cut off.
const GONE: u16 = u16::MAX;

/// A vertex's side of the plane being clipped, as a bit (see [`Links::class`]): a face's
/// vertices' bits or-ed together tell at once whether it lies inside, beyond or across.
const INSIDE: u8 = 1;

/// On the plane (within the clip's tolerance).
const ON: u8 = 2;

/// Beyond the plane.
const BEYOND: u8 = 4;

/// A face of the clipped cell: entries `start..start + len` of its polyhedron's index list,
/// the vertices in order around its outward normal, and the body whose plane it lies on
/// (`None`: a face of the cell).
#[derive(Clone, Copy)]
pub(super) struct Face {
    pub(super) start: usize,
    pub(super) len: usize,
    pub(super) body: Option<usize>,
    pub(super) normal: Vector,
}

/// A convex polyhedron: its distinct vertices, and its faces as cycles of their indices. Each
/// vertex is stored once, so a clip measures it against the plane once, cuts each edge once
/// (both faces of the edge share the new vertex) and chains the cap from the faces' cut edges
/// instead of sorting its points by angle.
///
/// Fixed buffers with their lengths beside them: a clip keeps the lengths in locals while it
/// writes (a `Vec`'s length and capacity would be reloaded and stored at every push).
pub(super) struct Poly {
    pub(super) verts: [Vector; CAP_VERTS],
    pub(super) nv: usize,
    pub(super) index: [u16; CAP_INDEX],
    ni: usize,
    pub(super) faces: [Face; CAP_FACES],
    pub(super) nf: usize,
}

impl Poly {
    pub(super) const EMPTY: Self = Self {
        verts: [Vector::ZERO; CAP_VERTS],
        nv: 0,
        index: [0; CAP_INDEX],
        ni: 0,
        faces: [Face { start: 0, len: 0, body: None, normal: Vector::ZERO }; CAP_FACES],
        nf: 0,
    };

    pub(super) fn verts(&self) -> &[Vector] {
        &self.verts[..self.nv]
    }

    pub(super) fn faces(&self) -> &[Face] {
        &self.faces[..self.nf]
    }

    pub(super) fn clear(&mut self) {
        (self.nv, self.ni, self.nf) = (0, 0, 0);
    }
}

/// Appends `value` to `buf`, whose length is `len`; `None` when it is full.
#[inline(always)]
fn push<T, const N: usize>(buf: &mut [T; N], len: &mut usize, value: T) -> Option<()> {
    *buf.get_mut(*len)? = value;
    *len += 1;
    Some(())
}

/// What a clip measures and links per vertex and per face, kept between cells.
pub(super) struct Links {
    /// Each vertex's signed distance from the plane being clipped.
    sides: [Real; CAP_VERTS],
    /// Each vertex's side of the plane: [`INSIDE`], [`ON`] or [`BEYOND`].
    class: [u8; CAP_VERTS],
    /// Each vertex's index in the clipped polyhedron, or [`GONE`].
    kept: [u16; CAP_VERTS],
    /// The edges cut by the plane (their ends' indices, the lower first) and the new vertex.
    cut_edges: [(u16, u16, u16); CAP_VERTS],
    /// Per vertex of the clipped polyhedron: whether it lies on the plane.
    on_plane: [bool; CAP_VERTS],
    /// The cap's edges, one per clipped face, in the cap's order about the plane's normal.
    cap_edges: [(u16, u16); CAP_FACES],
    /// Per vertex of the clipped polyhedron: the cap's edge that leaves it (its index in
    /// `cap_edges`), or [`GONE`]; reset after each use.
    leaving: [u16; CAP_VERTS],
}

impl Links {
    /// Empty buffers, every `leaving` entry [`GONE`] as a clip expects.
    pub(super) fn new() -> Self {
        Self {
            sides: [0.0; CAP_VERTS],
            class: [0; CAP_VERTS],
            kept: [0; CAP_VERTS],
            cut_edges: [(0, 0, 0); CAP_VERTS],
            on_plane: [false; CAP_VERTS],
            cap_edges: [(0, 0); CAP_FACES],
            leaving: [GONE; CAP_VERTS],
        }
    }
}

/// The six faces of the box `lo`–`hi`.
pub(super) fn cell_faces(lo: Vector, hi: Vector, poly: &mut Poly) {
    // Corner indices of each face, counter-clockwise seen from outside.
    const QUADS: [([u16; 4], [Real; 3]); 6] = [
        ([0, 4, 6, 2], [-1.0, 0.0, 0.0]),
        ([1, 3, 7, 5], [1.0, 0.0, 0.0]),
        ([0, 1, 5, 4], [0.0, -1.0, 0.0]),
        ([2, 6, 7, 3], [0.0, 1.0, 0.0]),
        ([0, 2, 3, 1], [0.0, 0.0, -1.0]),
        ([4, 5, 7, 6], [0.0, 0.0, 1.0]),
    ];
    for c in 0..8 {
        poly.verts[c] = Vector::new(
            if c & 1 == 0 { lo.x } else { hi.x },
            if c & 2 == 0 { lo.y } else { hi.y },
            if c & 4 == 0 { lo.z } else { hi.z },
        );
    }
    for (k, (quad, n)) in QUADS.into_iter().enumerate() {
        poly.faces[k] = Face { start: 4 * k, len: 4, body: None, normal: Vector::from_array(n) };
        poly.index[4 * k..4 * k + 4].copy_from_slice(&quad);
    }
    (poly.nv, poly.ni, poly.nf) = (8, 24, 6);
}

/// Replaces the scratch's current polyhedron by its part with `n·x <= h`, closed by a face on
/// the plane (written into the other polyhedron); returns `Some(false)` (and changes nothing)
/// when the plane cuts nothing off, `None` when the result would outgrow the buffers.
pub(super) fn clip(scratch: &mut Scratch, plane: Plane) -> Option<bool> {
    let Scratch { polys, links, cap, current, tol, limits, .. } = scratch;
    let Links { sides, class, kept, cut_edges, on_plane, cap_edges, leaving } = &mut **links;
    let tol = *tol;
    // Every vertex's side once: the faces below read it as bits.
    let mut seen = 0u8;
    {
        let from = &polys[*current];
        for ((s, c), &x) in sides.iter_mut().zip(class.iter_mut()).zip(from.verts()) {
            let d = plane.n.dot(x) - plane.h;
            (*s, *c) = if d.abs() <= tol {
                (0.0, ON)
            } else if d > 0.0 {
                (d, BEYOND)
            } else {
                (d, INSIDE)
            };
            seen |= *c;
        }
    }
    if seen & BEYOND == 0 {
        // A face on the plane lies on that body's surface (a body's face on a node layer,
        // with the corners there outside the body: the plane was added as one that touches).
        let from = &mut polys[*current];
        let Poly { index, faces, nf, .. } = from;
        for f in &mut faces[..*nf] {
            let on = |k: &u16| class[*k as usize] == ON;
            if f.body.is_none() && index[f.start..f.start + f.len].iter().all(on) {
                (f.body, f.normal) = (Some(plane.body), plane.n);
            }
        }
        return Some(false);
    }
    let (a, b) = polys.split_at_mut(1);
    let (from, to) = if *current == 0 { (&a[0], &mut b[0]) } else { (&b[0], &mut a[0]) };
    // The result's lengths, kept in locals while it is written.
    let (mut nv, mut ni, mut nf) = (0, 0, 0);
    for (k, (&x, &c)) in from.verts().iter().zip(class.iter()).enumerate() {
        kept[k] = if c != BEYOND {
            push(&mut to.verts, &mut nv, x)?;
            on_plane[nv - 1] = c == ON;
            (nv - 1) as u16
        } else {
            GONE
        };
    }
    // Whether part of the polyhedron lies strictly inside the plane: then a face left wholly
    // on the plane is a sliver of a face nearly on it, not all that is left.
    let inside_part = seen & INSIDE != 0;
    let (mut n_cut, mut n_cap) = (0, 0);
    // A face whose cut leaves other than one edge on the plane (a degenerate cut, within
    // `tol`): the cap is then ordered by angle.
    let mut chained = true;
    for f in from.faces() {
        let start = ni;
        let idx = &from.index[f.start..f.start + f.len];
        let sides_of_face = idx.iter().fold(0u8, |m, &i| m | class[i as usize]);
        if sides_of_face == BEYOND {
            continue;
        }
        if sides_of_face == INSIDE {
            for &i in idx {
                push(&mut to.index, &mut ni, kept[i as usize])?;
            }
            push(&mut to.faces, &mut nf, Face { start, ..*f })?;
            continue;
        }
        // Where the face leaves the half-space and where it comes back.
        let (mut exit, mut entry) = (GONE, GONE);
        let mut i = idx[idx.len() - 1] as usize;
        for &j in idx {
            let j = j as usize;
            let (ci, cj) = (class[i], class[j]);
            if ci | cj == INSIDE | BEYOND {
                // Each edge is cut once, from its inside end, for both of its faces.
                let key = (i.min(j) as u16, i.max(j) as u16);
                let v = match cut_edges[..n_cut].iter().find(|e| (e.0, e.1) == key) {
                    Some(e) => e.2,
                    None => {
                        let (p, q) = if ci == INSIDE { (i, j) } else { (j, i) };
                        let (xp, xq) = (from.verts[p], from.verts[q]);
                        let x = xp + (xq - xp) * (sides[p] / (sides[p] - sides[q]));
                        push(&mut to.verts, &mut nv, x)?;
                        on_plane[nv - 1] = true;
                        let v = (nv - 1) as u16;
                        push(cut_edges, &mut n_cut, (key.0, key.1, v))?;
                        v
                    }
                };
                push(&mut to.index, &mut ni, v)?;
                if ci == INSIDE {
                    exit = v;
                } else {
                    entry = v;
                }
            }
            if cj != BEYOND {
                push(&mut to.index, &mut ni, kept[j])?;
            }
            i = j;
        }
        let len = ni - start;
        if len < 3 {
            ni = start;
            continue;
        }
        if sides_of_face & ON == 0 {
            // A clean cut: its edge on the plane runs from the exit to the entry (the faces
            // are counter-clockwise about their outward normals); the cap walks it backwards.
            push(cap_edges, &mut n_cap, (entry, exit))?;
            push(&mut to.faces, &mut nf, Face { start, len, ..*f })?;
            continue;
        }
        let face = &to.index[start..ni];
        let mut on_edges = 0;
        for k in 0..len {
            let (u, w) = (face[k], face[if k + 1 == len { 0 } else { k + 1 }]);
            if on_plane[u as usize] && on_plane[w as usize] {
                on_edges += 1;
                if on_edges == 1 {
                    push(cap_edges, &mut n_cap, (w, u))?;
                }
            }
        }
        if on_edges == len && inside_part {
            // A face nearly on the plane (another body's plane within round-off of it), cut
            // to the plane: the cap, ordered by angle, takes its place.
            ni = start;
            chained = false;
            continue;
        }
        if on_edges == len {
            // A face on the plane with a vertex beyond it: the polyhedron lies beyond the
            // plane, and what is left is that face alone — no volume, but a facet of the
            // plane's body (where a body's face lies on a node layer, the cell beyond it holds
            // the facet, as the tetrahedra do).
            cap.clear();
            cap.extend(to.index[start..ni].iter().map(|&v| to.verts[v as usize]));
            for (k, &x) in cap.iter().enumerate() {
                to.verts[k] = x;
                to.index[k] = k as u16;
            }
            to.faces[0] = Face { start: 0, len, body: Some(plane.body), normal: plane.n };
            (to.nv, to.ni, to.nf) = (len, len, 1);
            return Some(true);
        }
        chained &= on_edges <= 1;
        push(&mut to.faces, &mut nf, Face { start, len, ..*f })?;
    }
    if nf == 0 {
        (to.nv, to.ni, to.nf) = (nv, ni, nf);
        return Some(true);
    }
    let start = ni;
    // The cap is the chain of the faces' cut edges, or else its points ordered by angle.
    if !(chained && chain(&cap_edges[..n_cap], leaving, &mut to.index, &mut ni)) {
        ni = start;
        cap.clear();
        let on = to.verts[..nv].iter().zip(on_plane.iter()).filter(|v| *v.1).map(|v| *v.0);
        cap.extend(on);
        cap_polygon(cap, plane.n, tol);
        // Each point is one of the vertices it was taken from.
        for x in cap.iter() {
            if let Some(v) = to.verts[..nv].iter().position(|y| y == x) {
                push(&mut to.index, &mut ni, v as u16)?;
            }
        }
    }
    let len = ni - start;
    if len >= 3 {
        push(&mut to.faces, &mut nf, Face { start, len, body: Some(plane.body), normal: plane.n })?;
    } else {
        ni = start;
    }
    (to.nv, to.ni, to.nf) = (nv, ni, nf);
    (ni <= limits.0 && nf <= limits.1).then_some(true)
}

/// Appends to `out` (of length `len`) the cycle the cap's `edges` form, each vertex once,
/// starting at the first edge's start; whether they form one (every edge used once, each
/// vertex left by one edge), else `out` may hold part of it. `leaving` is all [`GONE`] for
/// the edges' vertices, and is left so.
fn chain(
    edges: &[(u16, u16)],
    leaving: &mut [u16; CAP_VERTS],
    out: &mut [u16; CAP_INDEX],
    len: &mut usize,
) -> bool {
    if edges.len() < 3 {
        return false;
    }
    // Each vertex's edge that leaves it; two edges leaving one vertex form no cycle.
    let mut single = true;
    for (k, e) in edges.iter().enumerate() {
        let slot = &mut leaving[e.0 as usize];
        single &= *slot == GONE;
        *slot = k as u16;
    }
    let mut closed = false;
    if single {
        // Walks from the first edge's start: the cap when it comes back there after every
        // edge (sooner, the edges hold more than one cycle).
        let first = edges[0].0;
        let mut at = first;
        for step in 1..=edges.len() {
            let k = leaving[at as usize];
            if k == GONE || push(out, len, at).is_none() {
                break;
            }
            at = edges[k as usize].1;
            if at == first {
                closed = step == edges.len();
                break;
            }
        }
    }
    for e in edges {
        leaving[e.0 as usize] = GONE;
    }
    closed
}

/// A cut's cap from the points the clipped faces left on the plane normal to `n`: the distinct
/// ones (within `4 tol`), ordered counter-clockwise about `n`.
fn cap_polygon(points: &mut Vec<Vector>, n: Vector, tol: Real) {
    let mut distinct = 0;
    for i in 0..points.len() {
        let p = points[i];
        if !points[..distinct].iter().any(|q| (*q - p).length_squared() <= 16.0 * tol * tol) {
            points[distinct] = p;
            distinct += 1;
        }
    }
    points.truncate(distinct);
    if distinct >= 3 {
        order_around(points, n);
    }
}

/// Orders the points of a convex polygon in the plane normal to `n` counter-clockwise about
/// `n`.
fn order_around(points: &mut [Vector], n: Vector) {
    let c = points.iter().copied().sum::<Vector>() / points.len() as Real;
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    // A pseudo-angle: in the same order as `atan2(y, x)` on (−π, π], without the atan2.
    let angle = |p: &Vector| {
        let (x, y) = ((*p - c).dot(u), (*p - c).dot(v));
        let r = y / (x.abs() + y.abs());
        if x >= 0.0 {
            r
        } else if y >= 0.0 {
            2.0 - r
        } else {
            -2.0 - r
        }
    };
    // Each point's angle once, not once per comparison.
    const KEYED: usize = 32;
    if points.len() <= KEYED {
        let mut keys = [(0.0, Vector::ZERO); KEYED];
        for (k, p) in keys.iter_mut().zip(points.iter()) {
            *k = (angle(p), *p);
        }
        let keys = &mut keys[..points.len()];
        keys.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        for (p, k) in points.iter_mut().zip(keys.iter()) {
            *p = k.1;
        }
    } else {
        points.sort_by(|a, b| angle(a).total_cmp(&angle(b)));
    }
}
