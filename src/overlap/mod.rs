//! Overlap geometry of two convex bodies, discretised as Marquardt et al. do: rough box → box
//! search and Algorithm-1 correction → integration on an `N_c` grid → overlap volume, contact
//! point, normal and indentation.
//!
//! Everything is computed in the frame of A or B, whichever bounds the overlap tighter, so the
//! result is exactly invariant under a rigid motion of the pair and does not depend on which
//! body is called A; the returned box is in that frame too, ready to seed the next sub-step of
//! a persistent contact.
//!
//! Two integration modes ([`IntegrationMode`]):
//! - [`Count`](IntegrationMode::Count) — the paper's: Algorithm 1 with 26-direction rays, then
//!   count grid nodes inside both bodies, average node positions, area-weighted surface-layer
//!   gradients for the normal. Order 1.
//! - [`Subcell`](IntegrationMode::Subcell) — ours: surface crossings on the cut grid edges by
//!   root finding, each cut cell's six tetrahedra clipped by both surfaces — or, in a cell an
//!   edge or a corner of a body passes through, the cell clipped by both bodies' tangent
//!   planes (`crease`); volume, centroid and facet area vectors (the normal) in closed form.
//!   Order 2.
//!
//! A first touch is bounded by cutting planes (`bound`): a box that provably holds all of the
//! overlap — thin wedges' tapering ends included, wherever they lie between grid lines — and
//! proves the bodies apart when it empties. Sub-cell mode integrates on that box; a persistent
//! contact follows its last box. Counting shrinks its box by `find_box` (from the cutting-plane
//! box, or a persistent contact's last one): axis rays, refinement while the hits fill a small
//! part of the searched box, a located seed when every ray misses, then the paper's
//! 26-direction correction.
//!
//! Two opt-in exact forms skip the grid for the pairs they cover — what the grid converges to
//! as `N_c` grows: sphere lenses and caps ([`OverlapSettings::with_closed_form_spheres`]) and
//! clipped polyhedra for cuboids, convex polyhedra and half-spaces
//! ([`OverlapSettings::with_exact_polyhedra`]).

mod bound;
mod closed_form;
mod correction;
mod count;
mod crease;
mod flux;
mod footprint;
mod grid;
mod pair;
mod polyhedra;
pub(crate) use closed_form::lens_measures;
pub use flux::Flux;
pub use footprint::Footprint;
pub(crate) use grid::Grid;
pub(crate) use pair::{crossing, Pair, Placed};
mod subcell;

use parry3d_f64::bounding_volume::Aabb;

use crate::error::{check_finite_vec, check_non_negative, check_range, Error, Result};
use crate::math::{Matrix, Pose, Real, Vector};
use crate::shape::Sdf;

/// How the overlap region is integrated on its grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub enum IntegrationMode {
    /// Node counting, as in Marquardt et al. (first order in `N_c`).
    Count,
    /// Piecewise-linear sub-cell integration (second order in `N_c`): exact surface crossings
    /// on the grid's edges, and the bodies' tangent planes in cells an edge or a corner of a
    /// body passes through, which keep flat-faced bodies' edges sharp. Relies on exact SDFs
    /// and their gradients (as [`Sdf`] requires).
    Subcell,
}

impl IntegrationMode {
    /// `"count"` or `"subcell"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Count => "count",
            Self::Subcell => "subcell",
        }
    }
}

/// Resolution and mode of the overlap integration.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "checkpoint", serde(try_from = "SettingsFields"))]
pub struct OverlapSettings {
    n_c: usize,
    mode: IntegrationMode,
    enlargement: [Real; 2],
    closed_form_spheres: bool,
    exact_polyhedra: bool,
    polyhedra_on_grid: bool,
}

impl OverlapSettings {
    /// `n_c >= 1` grid cells per direction on the overlap's box.
    pub fn new(n_c: usize, mode: IntegrationMode) -> Result<Self> {
        check_range("n_c", n_c as Real, 1.0..=1024.0, "integer 1 <= N_c <= 1024")?;
        Ok(Self {
            n_c,
            mode,
            enlargement: [0.0; 2],
            closed_form_spheres: false,
            exact_polyhedra: false,
            polyhedra_on_grid: false,
        })
    }

    /// Sphere–sphere and sphere–half-space pairs get their overlap in closed form (a lens of
    /// two spherical caps, one cap on a plane) instead of on the grid: what the grid integration
    /// converges to as `N_c` grows, in a few operations instead of a grid integration. Every
    /// other pair — and a configuration the closed form does not
    /// cover, such as one sphere inside the other — is integrated on the grid as before. Off
    /// by default: the grid is the model, and the validations measure it.
    pub fn with_closed_form_spheres(mut self, on: bool) -> Self {
        self.closed_form_spheres = on;
        self
    }

    /// Whether sphere pairs are computed in closed form.
    pub fn closed_form_spheres(&self) -> bool {
        self.closed_form_spheres
    }

    /// Pairs of bodies bounded by planes — cuboids, convex polyhedra, one of them possibly a
    /// half-space — get their overlap exactly: the intersection polyhedron of both bodies' face
    /// half-spaces, its volume, centroid, facet area vectors and chord in closed form, at a
    /// fraction of a grid integration's cost. It is
    /// what the grid integration converges to as `N_c` grows, except that an enlargement moves
    /// the faces out (sharp edges) where the grid's `d <= ε` rounds edges and corners. Every
    /// other pair (a sphere, a cylinder, a rounded or custom body) is integrated on the grid as
    /// before. Without enlargement in sub-cell mode this is what the grid computes anyway
    /// (see [`with_polyhedra_on_grid`](Self::with_polyhedra_on_grid)), and such pairs take the
    /// exact form whatever this setting; it decides for enlarged pairs and in counting mode.
    /// Off by default: the grid is the model, and the validations measure it.
    pub fn with_exact_polyhedra(mut self, on: bool) -> Self {
        self.exact_polyhedra = on;
        self
    }

    /// Whether pairs of planar bodies are computed exactly.
    pub fn exact_polyhedra(&self) -> bool {
        self.exact_polyhedra
    }

    /// In sub-cell mode, a pair of bodies bounded by planes and not enlarged is integrated on
    /// the grid, its cells clipped by the bodies' faces (`true`), instead of by clipping the
    /// whole overlap polyhedron once (`false`, the default). The grid's result then equals the
    /// clipping's to round-off, at several times its cost: this is for checking the grid's
    /// face clipping (which mixed pairs, a polyhedron and a curved body, rely on) against it.
    pub fn with_polyhedra_on_grid(mut self, on: bool) -> Self {
        self.polyhedra_on_grid = on;
        self
    }

    /// Whether non-enlarged polyhedral pairs are integrated on the grid in sub-cell mode.
    pub fn polyhedra_on_grid(&self) -> bool {
        self.polyhedra_on_grid
    }

    /// Contact enlargement `ε_A, ε_B >= 0` (m): a node is inside when `d_A <= ε_A` and `d_B <= ε_B`.
    pub fn with_enlargement(mut self, eps_a: Real, eps_b: Real) -> Result<Self> {
        self.enlargement = [
            check_non_negative("enlargement_a", eps_a)?,
            check_non_negative("enlargement_b", eps_b)?,
        ];
        Ok(self)
    }

    /// Grid cells per direction.
    pub fn n_c(&self) -> usize {
        self.n_c
    }

    /// Integration mode.
    pub fn mode(&self) -> IntegrationMode {
        self.mode
    }

    /// Contact enlargement of A and B (m).
    pub fn enlargement(&self) -> [Real; 2] {
        self.enlargement
    }
}

/// What the overlap integration found. Points and vectors are in the world frame.
#[derive(Clone, Debug, PartialEq)]
pub struct OverlapGeometry {
    /// Overlap volume `V` (m³).
    pub volume: Real,
    /// Contact point `x_c`: the overlap's centroid (m, world).
    pub contact_point: Vector,
    /// Unit contact normal, pointing from B to A (world).
    pub normal: Vector,
    /// Indentation `d`: the overlap's extent through `x_c` along the normal (m).
    pub indentation: Real,
    /// Estimated area of the overlap region's surface (m²), for [`StiffnessFactor::ShapeAdaptive`](crate::StiffnessFactor::ShapeAdaptive).
    pub surface_area: Real,
    /// The corrected box, in the body frame the overlap was computed in (A's or B's, whichever
    /// bounds the pair tighter; B's for the closed-form spheres): pass it back as
    /// `previous_box` next sub-step.
    pub corrected_box: Aabb,
    /// The overlap's footprint (world frame): the area where the surfaces meet, its centroid
    /// and second moment of area — how the overlap changes when the surfaces tilt against
    /// each other. From the grid and the clipped polyhedra; `None` from the closed-form
    /// spheres.
    pub footprint: Option<Footprint>,
    /// How the overlap changes to first order when A moves against B (world frame; see
    /// [`Flux`]): the moments of A's surface within B. From the sub-cell grid and the clipped
    /// polyhedra; `None` from counting and the closed-form spheres.
    pub flux: Option<Flux>,
}

/// The overlap's B→A normal (un-normalised) from the area vectors of its A facets (out of A)
/// and B facets (out of B) and their areas: `n_B − n_A`, each part weighted with the *other*
/// part's area, so the smaller, better-resolved part counts most (see [`subcell`]); equal parts
/// give the plain mean, and swapping the bodies negates it. Zero without facets.
///
/// Where one body's facets all lie in one plane (a flat face, within [`FLAT_FACETS`]) and the
/// other's do not, the normal is that face's alone: the overlap's surface is closed, so the
/// other part's area vector is exactly minus the face's, and only the discretisation's gaps
/// (between cells integrated differently) would tilt it — by a few millionths, enough to push
/// a cylinder lying on a floor sideways and roll it away.
fn blended_normal(area_vectors: [Vector; 2], areas: [Real; 2]) -> Vector {
    let total = areas[0] + areas[1];
    if !(total > 0.0) {
        return Vector::ZERO;
    }
    let flat =
        |s: usize| areas[s] > 0.0 && area_vectors[s].length() >= (1.0 - FLAT_FACETS) * areas[s];
    match (flat(0), flat(1)) {
        (false, true) => area_vectors[1] * (2.0 * areas[0] / total),
        (true, false) => -area_vectors[0] * (2.0 * areas[1] / total),
        _ => (area_vectors[1] * areas[0] - area_vectors[0] * areas[1]) * (2.0 / total),
    }
}

/// `1 − |Σ a| / Σ |a|` over a body's facet area vectors `a` below which they lie in one plane
/// ([`blended_normal`]): round-off of a face's crossings, far below a curved surface's spread
/// of normals over any overlap the grid resolves.
const FLAT_FACETS: Real = 1e-9;

/// What an exact form (closed-form spheres, clipped polyhedra) says of a pair.
// Returned by value once per evaluation and unpacked at once: boxing the large variant would
// allocate on every evaluation.
#[allow(clippy::large_enum_variant)]
pub(crate) enum Exact {
    /// They overlap: the overlap's geometry.
    Overlap(OverlapGeometry),
    /// They are apart.
    Apart,
    /// The form does not cover this pair or this configuration: integrate on the grid.
    Uncovered,
}

/// Result of integrating the overlap on the corrected box, before the indentation.
pub(crate) struct Integral {
    volume: Real,
    centroid: Vector,
    /// Un-normalised B→A normal (zero when the grid saw no surface).
    normal: Vector,
    surface_area: Real,
    /// The footprint (pair frame).
    footprint: Option<Footprint>,
    /// A's flux (pair frame).
    flux: Option<Flux>,
    /// Box of the integrated pieces (sub-cell mode; `None` for counting).
    bounds: Option<Aabb>,
}

fn intersect(a: &Aabb, b: &Aabb) -> Option<Aabb> {
    let mins = a.mins.max(b.mins);
    let maxs = a.maxs.min(b.maxs);
    (mins.cmple(maxs).all()).then(|| Aabb::new(mins, maxs))
}

fn pose_check(what: &'static str, p: &Pose) -> Result<()> {
    if p.is_finite() && (p.rotation.length() - 1.0).abs() < 1e-6 {
        Ok(())
    } else {
        Err(Error::NonFinite {
            what,
            detail: format!("{p:?} (needs finite values and a unit quaternion)"),
        })
    }
}

/// The conservative rough box of the pair in its frame (intersection of the bounds), or `None`
/// when the bounds do not meet.
fn conservative_box<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
) -> Result<Option<Aabb>> {
    let Some(b) = intersect(&pair.a.bounds(), &pair.b.bounds()) else { return Ok(None) };
    if !(b.mins.is_finite() && b.maxs.is_finite()) {
        return Err(Error::UnboundedOverlap { a: "body A".into(), b: "body B".into() });
    }
    Ok(Some(b))
}

fn placed<'a, S: Sdf + ?Sized>(shape: &'a S, rel: Pose, eps: Real) -> Placed<'a, S> {
    let rot = Matrix::from_quat(rel.rotation);
    Placed { shape, rot, rot_t: rot.transpose(), origin: rel.translation, eps }
}

/// Whether `settings` compute the pair in an exact form rather than on the grid: two balls or
/// a ball and a half-space with closed-form spheres, two bodies with face planes with exact
/// polyhedra. (An exact form may still fall back to the grid, at deep engulfment.)
pub(crate) fn has_exact_form<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    a: &A,
    b: &B,
    settings: &OverlapSettings,
) -> bool {
    let (ball_a, ball_b) = (a.sphere_radius().is_some(), b.sphere_radius().is_some());
    let (plane_a, plane_b) = (a.half_space_normal().is_some(), b.half_space_normal().is_some());
    let spheres = (ball_a && (ball_b || plane_b)) || (ball_b && plane_a);
    (settings.closed_form_spheres && spheres)
        || (settings.exact_polyhedra && a.face_planes().is_some() && b.face_planes().is_some())
}

/// Computes the overlap of body A (`a` at `pose_a`) and body B (`b` at `pose_b`).
///
/// `previous_box` is last sub-step's [`OverlapGeometry::corrected_box`] of the same pair; it is
/// grown a little and used as the rough box when it still contains the overlap.
/// Returns `Ok(None)` when the bodies do not overlap (as far as the grid can tell), and an
/// error for non-finite poses or two unbounded bodies.
pub fn compute_overlap<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    a: &A,
    pose_a: &Pose,
    b: &B,
    pose_b: &Pose,
    settings: &OverlapSettings,
    previous_box: Option<&Aabb>,
) -> Result<Option<OverlapGeometry>> {
    pose_check("pose of body A", pose_a)?;
    pose_check("pose of body B", pose_b)?;
    if settings.closed_form_spheres {
        match closed_form::overlap(a, pose_a, b, pose_b, settings.enlargement) {
            Exact::Overlap(g) => return Ok(Some(g)),
            Exact::Apart => return Ok(None),
            Exact::Uncovered => {}
        }
    }
    // The grid lives in A's or B's frame, whichever gives the smaller rough box: it moves
    // rigidly with the pair, does not depend on which body is called A, and keeps elongated
    // bodies' boxes tight (a half-space's own frame is the only one bounding it).
    let in_frame = |frame: Pose| -> Result<(Pose, Pair<'_, A, B>, Option<Aabb>)> {
        let inv = frame.inverse();
        let pair = Pair {
            a: placed(a, inv * *pose_a, settings.enlargement[0]),
            b: placed(b, inv * *pose_b, settings.enlargement[1]),
        };
        let rough = conservative_box(&pair);
        match rough {
            Ok(r) => Ok((frame, pair, r)),
            Err(e) => Err(e),
        }
    };
    let volume = |r: &Result<(Pose, Pair<'_, A, B>, Option<Aabb>)>| match r {
        Ok((_, _, Some(b))) => (b.maxs - b.mins).max(Vector::splat(0.0)).element_product(),
        Ok((_, _, None)) => 0.0,
        Err(_) => Real::INFINITY,
    };
    let (fa, fb) = (in_frame(*pose_a), in_frame(*pose_b));
    let (frame, pair, rough) = if volume(&fa) < volume(&fb) { fa? } else { fb? };
    let Some(rough) = rough else { return Ok(None) };
    let to_world = |g: OverlapGeometry| OverlapGeometry {
        contact_point: frame.transform_point(g.contact_point),
        normal: frame.rotation * g.normal,
        footprint: g.footprint.map(|f| f.transformed(&frame)),
        flux: g.flux.map(|f| f.transformed(&frame)),
        ..g
    };
    // Two polyhedra without enlargement: the grid's cells would be clipped by their faces,
    // which sums to the overlap polyhedron exactly; clipping that polyhedron once is the same
    // result at a fraction of the cost. (Other pairs come back uncovered.)
    let faces_only = settings.mode == IntegrationMode::Subcell
        && !settings.polyhedra_on_grid
        && settings.enlargement == [0.0; 2];
    if settings.exact_polyhedra || faces_only {
        match polyhedra::overlap(&pair, &rough) {
            Exact::Overlap(g) => return Ok(Some(to_world(g))),
            Exact::Apart => return Ok(None),
            Exact::Uncovered => {}
        }
    }
    let reused = previous_box.and_then(|p| {
        check_finite_vec("previous box", p.mins).ok()?;
        check_finite_vec("previous box", p.maxs).ok()?;
        let grow = (p.maxs - p.mins).max_element() * 0.25;
        intersect(&Aabb::new(p.mins - Vector::splat(grow), p.maxs + Vector::splat(grow)), &rough)
    });
    let search = |seed: &Aabb| {
        find_box(&pair, seed, &rough, settings.n_c, settings.mode)
            .and_then(|corrected| overlap_in_box(&pair, &corrected, &rough, settings))
    };
    // A persistent contact starts from its last box: sub-cell mode integrates it padded by a
    // cell (`follow`), counting searches from it (growing it when the overlap reaches its
    // faces).
    let persistent = reused.as_ref().and_then(|r| match settings.mode {
        IntegrationMode::Subcell => follow(&pair, previous_box?, &rough, settings.n_c),
        IntegrationMode::Count => search(r),
    });
    if let Some(found) = persistent {
        return Ok(Some(to_world(found)));
    }
    // A first touch, or a contact its box lost, starts from the cutting-plane box (`bound`),
    // which holds all of the overlap and proves the bodies apart when it empties. Sub-cell mode
    // integrates on it; counting searches it (from the rough box, the axis rays stepped over
    // thin overlaps and reported overlapping bodies apart) and, when the rays find nothing
    // there, counts the nodes on the cutting-plane box itself. A search from the rough box
    // decides only what those grids find nothing in: an overlap far thinner than the box is
    // tight, such as a touch 1e-18 m deep.
    let Some(bounds) = bound::overlap_box(&pair, &rough, reused.as_ref(), settings.n_c) else {
        return Ok(None);
    };
    let found = match settings.mode {
        IntegrationMode::Subcell => first_touch(&pair, &bounds, &rough, settings),
        IntegrationMode::Count => find_box(&pair, &bounds, &bounds, settings.n_c, settings.mode)
            .and_then(|corrected| overlap_in_box(&pair, &corrected, &bounds, settings))
            .or_else(|| overlap_in_box(&pair, &bounds, &bounds, settings)),
    }
    .or_else(|| search(&rough));
    Ok(found.map(to_world))
}

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
fn find_box<A: Sdf + ?Sized, B: Sdf + ?Sized>(
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
fn locate<A: Sdf + ?Sized, B: Sdf + ?Sized>(
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
fn shortest_step(ga: Vector, ra: Real, gb: Vector, rb: Real) -> Vector {
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

fn overlap_in_box<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    corrected: &Aabb,
    rough: &Aabb,
    settings: &OverlapSettings,
) -> Option<OverlapGeometry> {
    let n = settings.n_c;
    let grid = Grid::on(corrected, n)?;
    let integral = match settings.mode {
        IntegrationMode::Count => {
            // One more node layer around the box: the surface layer of the paper's normal lies
            // outside the overlap, also where the overlap fills the box up to a face.
            let outer = grid.padded();
            count::integrate(pair, &outer, &outer.sample(pair, IntegrationMode::Count))
        }
        IntegrationMode::Subcell => {
            // A quarter cell of padding: flat faces on the box's faces become facets.
            let pad = grid.h * 0.25;
            let padded = Grid::on(&Aabb::new(corrected.mins - pad, corrected.maxs + pad), n)?;
            subcell::integrate(pair, &padded, &padded.sample(pair, IntegrationMode::Subcell))
        }
    };
    finish(pair, integral, &grid, rough, *corrected)
}

/// A first sub-cell touch: the grid on `bounds` (the cutting-plane box that holds the whole
/// overlap), then again on the box of the pieces it found — a quarter cell larger, as a
/// searched box is: the pieces' box is tight where `bounds` is loose (a lens's rim), so the
/// second grid is the finer one; its nodes do not lie on the pieces' extreme faces (a flat
/// face there would lie on a node layer, where which cell's facet counts is decided by
/// round-off). Where no side of the pieces' box lies more than [`SAME_BOX`] of a cell inside
/// `bounds` (the cutting planes met the overlap's extremes: flat faces, edges, a cylinder's
/// rim), the second grid would not be finer, and the first's integral is kept, with `bounds`
/// as the box the next sub-step follows (so that a contact at rest lays the same grid again).
/// Pieces beyond `bounds`, which holds all of the overlap, are the tangent planes' outer error
/// in bent cells: a grid laid on their box would only be coarser.
fn first_touch<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    bounds: &Aabb,
    rough: &Aabb,
    settings: &OverlapSettings,
) -> Option<OverlapGeometry> {
    let grid = Grid::on(bounds, settings.n_c)?;
    let pad = grid.h * 0.25;
    let padded = Grid::on(&Aabb::new(bounds.mins - pad, bounds.maxs + pad), settings.n_c)?;
    let integral =
        subcell::integrate(pair, &padded, &padded.sample(pair, IntegrationMode::Subcell));
    let pieces = integral.bounds?;
    let slack = grid.h * SAME_BOX;
    let same = (pieces.mins - bounds.mins).cmple(slack).all()
        && (bounds.maxs - pieces.maxs).cmple(slack).all();
    if same {
        return finish(pair, integral, &grid, rough, *bounds);
    }
    overlap_in_box(pair, &pieces, rough, settings)
        .or_else(|| finish(pair, integral, &grid, rough, pieces))
}

/// How far (per cell) the pieces' box of a first touch may lie inside its cutting-plane box on
/// any side for the first grid's integral to stand ([`first_touch`]).
const SAME_BOX: Real = 1.0 / 16.0;

/// A persistent sub-cell contact without a box search, on the grid a first touch builds from
/// the box of its pieces: last sub-step's box of the overlap's pieces a quarter cell larger on
/// every side, `N_c` cells across. Where the overlap reaches that grid's boundary
/// ([`meets_boundary`]), the box padded by one cell on every side at its own spacing (`N_c + 2`
/// cells); `None` when the overlap reaches the padding's outer node layer too (it moved by more
/// than a cell): then the search runs. The new pieces' box is next sub-step's.
///
/// The overlap of two convex bodies is convex, so connected: a part of it beyond the box joins
/// the part inside across the box's boundary. Between most sub-steps an overlap moves and grows
/// by far less than a quarter cell, and then the padding's cells — most of a padded grid's,
/// each costly where an edge or a curved side passes it by — are not integrated at all. The
/// pieces' box of the first grid is not the test: where a body's tangent plane holds a smooth
/// side within a cell, the pieces reach the cell's faces although the overlap does not.
fn follow<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    previous: &Aabb,
    rough: &Aabb,
    n: usize,
) -> Option<OverlapGeometry> {
    let inner = Grid::on(&intersect(previous, rough)?, n)?;
    let (b, pad) = (inner.bounds(), inner.h * 0.25);
    let snug = Grid::on(&Aabb::new(b.mins - pad, b.maxs + pad), n)?;
    within(pair, &snug, rough, meets_boundary).or_else(|| {
        within(pair, &inner.padded(), rough, |grid, values| {
            boundary_nodes(grid).any(|(node, _)| in_both(values[node]))
        })
    })
}

/// The overlap on `grid`, or `None` where it `reaches` the grid's boundary (as the nodes'
/// distances tell) or holds no piece.
fn within<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    grid: &Grid,
    rough: &Aabb,
    reaches: impl FnOnce(&Grid, &[(Real, Real)]) -> bool,
) -> Option<OverlapGeometry> {
    let values = grid.sample(pair, IntegrationMode::Subcell);
    if reaches(grid, &values) {
        return None;
    }
    let integral = subcell::integrate(pair, grid, &values);
    let pieces = integral.bounds?;
    finish(pair, integral, grid, rough, pieces)
}

/// Whether the overlap reaches the grid's boundary, as its nodes' distances (`values`) tell: a
/// node on the boundary lies in both bodies, or on an edge of the grid in the boundary with
/// one end in A and the other in B the parts of the edge inside each meet (by linear
/// interpolation).
fn meets_boundary(grid: &Grid, values: &[(Real, Real)]) -> bool {
    // Where a body's part of an edge ends, as a fraction of the edge from its end `d0`.
    let cross = |d0: Real, d1: Real| d0 / (d0 - d1);
    let meet = |(a0, b0): (Real, Real), (a1, b1): (Real, Real)| {
        (a0 <= 0.0 && b1 <= 0.0 && a1 > 0.0 && b0 > 0.0 && cross(b0, b1) <= cross(a0, a1))
            || (a1 <= 0.0 && b0 <= 0.0 && a0 > 0.0 && b1 > 0.0 && cross(a0, a1) <= cross(b0, b1))
    };
    let m = grid.n + 1;
    let steps = [1, m, m * m];
    boundary_nodes(grid).any(|(node, (idx, on))| {
        in_both(values[node])
            || (0..3).any(|axis| {
                // An edge lies in the boundary where another of its coordinates is on it.
                idx[axis] + 1 < m
                    && (0..3).any(|o| o != axis && on[o])
                    && meet(values[node], values[node + steps[axis]])
            })
    })
}

/// Whether a node with distances `(d_A, d_B)` lies in both bodies.
fn in_both((a, b): (Real, Real)) -> bool {
    a.max(b) <= 0.0
}

/// The grid's nodes on its boundary: each node's index in the grid's values, its `(i, j, k)`
/// and whether each coordinate lies on the boundary.
fn boundary_nodes(grid: &Grid) -> impl Iterator<Item = (usize, ([usize; 3], [bool; 3]))> + '_ {
    let m = grid.n + 1;
    let on = move |i: usize| i == 0 || i == m - 1;
    (0..m)
        .flat_map(move |k| (0..m).flat_map(move |j| (0..m).map(move |i| [i, j, k])))
        .filter(move |idx| idx.iter().any(|&i| on(i)))
        .map(move |idx| (grid.index(idx[0], idx[1], idx[2]), (idx, idx.map(on))))
}

/// Normal, indentation and the output from an integral; `None` when it found no overlap.
fn finish<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    pair: &Pair<'_, A, B>,
    integral: Integral,
    grid: &Grid,
    rough: &Aabb,
    corrected_box: Aabb,
) -> Option<OverlapGeometry> {
    if integral.volume <= 0.0 {
        return None;
    }
    let x_c = integral.centroid;
    let mut normal = integral.normal.normalize_or_zero();
    if normal == Vector::ZERO {
        normal = pair.gradient_normal(x_c);
    }
    if normal == Vector::ZERO || !normal.is_finite() {
        return None;
    }
    let t_max = (rough.maxs - rough.mins).length().max(grid.h.max_element());
    let indentation =
        pair.exit_distance(x_c, normal, t_max) + pair.exit_distance(x_c, -normal, t_max);
    Some(OverlapGeometry {
        volume: integral.volume,
        contact_point: x_c,
        normal,
        indentation,
        surface_area: integral.surface_area,
        corrected_box,
        footprint: integral.footprint,
        flux: integral.flux,
    })
}

deserialize_checked!(OverlapSettings via SettingsFields { n_c: usize, mode: IntegrationMode, enlargement: [Real; 2], closed_form_spheres: bool, exact_polyhedra: bool, #[serde(default)] polyhedra_on_grid: bool }
    => |f| OverlapSettings::new(f.n_c, f.mode)
        .and_then(|s| s.with_enlargement(f.enlargement[0], f.enlargement[1]))
        .map(|s| s.with_closed_form_spheres(f.closed_form_spheres).with_exact_polyhedra(f.exact_polyhedra).with_polyhedra_on_grid(f.polyhedra_on_grid)));
