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
mod on_grid;
mod pair;
mod polyhedra;
mod search;
mod settings;
pub(crate) use closed_form::lens_measures;
pub use flux::Flux;
pub use footprint::Footprint;
pub(crate) use grid::Grid;
pub(crate) use pair::{crossing, Pair, Placed};
mod subcell;

use on_grid::{first_touch, follow, overlap_in_box};
use search::find_box;
pub use settings::{IntegrationMode, OverlapSettings};

use parry3d_f64::bounding_volume::Aabb;

use crate::error::{check_finite_vec, Error, Result};
use crate::math::{Matrix, Pose, Real, Vector};
use crate::shape::Sdf;

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
            facet_bulge: settings.facet_bulge,
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
