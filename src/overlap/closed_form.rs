//! Exact overlap geometry where it has a closed form: two spheres (a lens of two spherical
//! caps) and a sphere on a half-space (one cap). Opt-in through
//! [`OverlapSettings::with_closed_form_spheres`](super::OverlapSettings::with_closed_form_spheres):
//! it returns what the grid integration converges to as `N_c` grows, at the cost of a few
//! arithmetic operations instead of a grid integration (costs in `docs/performance.md`).
//!
//! With `V_cap(h, R) = π h² (3R − h) / 3` and the centroid of a cap `3 (2R − h)² / (4 (3R − h))`
//! from its sphere's centre, the overlap is the sum of the caps; its indentation is the caps'
//! heights added along the line of centres (which passes through the centroid), and its surface
//! the caps' areas `2π R h` (plus the flat disc on a half-space).

use parry3d_f64::bounding_volume::Aabb;

use super::{Exact, OverlapGeometry};
use crate::math::{Pose, Real, Vector};
use crate::shape::Sdf;

use std::f64::consts::PI;

/// Volume of a cap of height `h` cut from a sphere of radius `r`.
fn cap_volume(h: Real, r: Real) -> Real {
    PI * h * h * (3.0 * r - h) / 3.0
}

/// Distance from the sphere's centre to the centroid of a cap of height `h`.
fn cap_centroid(h: Real, r: Real) -> Real {
    3.0 * (2.0 * r - h).powi(2) / (4.0 * (3.0 * r - h))
}

/// Heights of the caps of two spheres of radii `a` and `b` whose centres are `d` apart (A's
/// towards B, B's towards A), free of cancellation.
fn cap_heights(a: Real, b: Real, d: Real) -> (Real, Real) {
    let s = a + b - d;
    (s * (b - a + d) / (2.0 * d), s * (a - b + d) / (2.0 * d))
}

/// Volume and surface area of a sphere of radius `r`'s cap of height `h` on a plane (its curved
/// surface and the flat disc).
fn plane_cap(r: Real, h: Real) -> (Real, Real) {
    (cap_volume(h, r), 2.0 * PI * r * h + PI * h * (2.0 * r - h))
}

/// Volume and surface area of the overlap of two spheres of `radii` that overlap by `s` along
/// the line of their centres; an infinite radius is a plane (a cap). What geometry reuse
/// scales a grid evaluation of such a pair by.
pub(crate) fn lens_measures(radii: [Real; 2], s: Real) -> (Real, Real) {
    match radii.map(Real::is_finite) {
        [true, true] => {
            let [a, b] = radii;
            let (ha, hb) = cap_heights(a, b, a + b - s);
            (cap_volume(ha, a) + cap_volume(hb, b), 2.0 * PI * (a * ha + b * hb))
        }
        [true, false] => plane_cap(radii[0], s),
        [false, true] => plane_cap(radii[1], s),
        [false, false] => (Real::NAN, Real::NAN),
    }
}

/// The overlap of `a` and `b` (dilated by `eps`) when both are spheres, or one a sphere and the
/// other a half-space: [`Exact::Overlap`] when they overlap partly, [`Exact::Apart`] when they
/// are apart, [`Exact::Uncovered`] when the pair is of another kind or the configuration is one
/// the closed form does not cover (one body inside the other, concentric spheres): the caller
/// integrates on the grid then.
pub(super) fn overlap<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    a: &A,
    pose_a: &Pose,
    b: &B,
    pose_b: &Pose,
    eps: [Real; 2],
) -> Exact {
    match (a.sphere_radius(), b.sphere_radius()) {
        (Some(ra), Some(rb)) => {
            lens(pose_a.translation, ra + eps[0], pose_b.translation, rb + eps[1], pose_b)
        }
        (Some(ra), None) => {
            let Some(normal) = b.half_space_normal() else { return Exact::Uncovered };
            let n = pose_b.rotation * normal;
            // The half-space `n·(x − t_B) <= eps_B`; A's cap beyond it, normal from B to A.
            cap_on_plane(
                pose_a.translation,
                ra + eps[0],
                n,
                n.dot(pose_b.translation) + eps[1],
                n,
                pose_b,
            )
        }
        (None, Some(rb)) => {
            let Some(normal) = a.half_space_normal() else { return Exact::Uncovered };
            let n = pose_a.rotation * normal;
            cap_on_plane(
                pose_b.translation,
                rb + eps[1],
                n,
                n.dot(pose_a.translation) + eps[0],
                -n,
                pose_b,
            )
        }
        (None, None) => Exact::Uncovered,
    }
}

/// Two spheres: A of radius `a` at `ca`, B of radius `b` at `cb`.
fn lens(ca: Vector, a: Real, cb: Vector, b: Real, pose_b: &Pose) -> Exact {
    let d = (ca - cb).length();
    if d >= a + b {
        return Exact::Apart;
    }
    if !(d > (a - b).abs() && d > 0.0) {
        return Exact::Uncovered;
    }
    let n = (ca - cb) / d;
    let s = a + b - d;
    let (ha, hb) = cap_heights(a, b, d);
    let (va, vb) = (cap_volume(ha, a), cap_volume(hb, b));
    let volume = va + vb;
    let contact_point =
        ((ca - n * cap_centroid(ha, a)) * va + (cb + n * cap_centroid(hb, b)) * vb) / volume;
    let geometry = OverlapGeometry {
        volume,
        contact_point,
        normal: n,
        indentation: s,
        surface_area: 2.0 * PI * (a * ha + b * hb),
        corrected_box: sphere_box(contact_point, a.min(b), pose_b),
        footprint: None,
        flux: None,
    };
    decided(volume, geometry)
}

/// A sphere of radius `r` at `c` cut by the plane `m·x = offset` (the half-space below it);
/// `normal` is the contact normal from B to A.
fn cap_on_plane(
    c: Vector,
    r: Real,
    m: Vector,
    offset: Real,
    normal: Vector,
    pose_b: &Pose,
) -> Exact {
    let h = r - (m.dot(c) - offset);
    if h <= 0.0 {
        return Exact::Apart;
    }
    // Sunk past its far side (or NaN): the grid decides.
    if h >= 2.0 * r || h.is_nan() {
        return Exact::Uncovered;
    }
    let (volume, surface_area) = plane_cap(r, h);
    let contact_point = c - m * cap_centroid(h, r);
    let geometry = OverlapGeometry {
        volume,
        contact_point,
        normal,
        indentation: h,
        surface_area,
        corrected_box: sphere_box(contact_point, r, pose_b),
        footprint: None,
        flux: None,
    };
    decided(volume, geometry)
}

/// The overlap `geometry` of a finite, positive `volume`; apart at zero; uncovered when the
/// arithmetic broke down (NaN).
fn decided(volume: Real, geometry: OverlapGeometry) -> Exact {
    if !volume.is_finite() {
        Exact::Uncovered
    } else if volume > 0.0 {
        Exact::Overlap(geometry)
    } else {
        Exact::Apart
    }
}

/// A box in B's frame holding the overlap (a sphere of radius `r` about a point of it): the
/// grid search's seed should a later sub-step fall back to it.
fn sphere_box(at: Vector, r: Real, pose_b: &Pose) -> Aabb {
    let local = pose_b.inverse().transform_point(at);
    Aabb::new(local - Vector::splat(r), local + Vector::splat(r))
}
