//! What an update asks of the bodies' surfaces near the contact: the part of a surface a
//! gradient belongs to ([`Feature`]), the gradients, whether a surface is flat there, and how far
//! a cap may glide over a face.

use crate::math::{Pose, Real, Vector};
use crate::shape::Sdf;

/// The part of a body's surface whose distance gives its gradient at a contact point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub enum Feature {
    /// The whole body's distance (a smooth body, or a point where no single part was found).
    #[default]
    Whole,
    /// A flat face, by its outward unit normal in the body's frame: a polyhedron's face
    /// ([`Sdf::face_planes`]) or a flat face of a smooth body ([`Sdf::flat_faces`]).
    Face(Vector),
    /// The smooth part of a body with flat faces ([`Sdf::smooth_part`]): a cylinder's side.
    Smooth,
}

impl Feature {
    /// The part of `shape` whose distance gives its gradient `g` at `p` (both in the body's
    /// frame): the face whose normal `g` is, else the smooth part when its gradient is `g`,
    /// else the whole body.
    pub(super) fn at<S: Sdf + ?Sized>(shape: &S, p: Vector, g: Vector) -> Self {
        let flats = shape.flat_faces();
        let faces = shape.face_planes().or_else(|| flats.clone()).unwrap_or_default();
        if let Some(n) =
            faces.iter().map(|(n, _)| n.normalize_or_zero()).find(|n| (*n - g).length() <= FLAT)
        {
            return Feature::Face(n);
        }
        if flats.is_some() && (shape.smooth_part(p).1 - g).length() <= FLAT {
            return Feature::Smooth;
        }
        Feature::Whole
    }

    /// This part's outward unit gradient at `p` (the body's frame) on `shape`.
    pub(super) fn gradient<S: Sdf + ?Sized>(&self, shape: &S, p: Vector) -> Vector {
        match *self {
            Feature::Whole => shape.gradient(p),
            Feature::Face(n) => n,
            Feature::Smooth => shape.smooth_part(p).1,
        }
    }
}

/// The bodies' distance gradients at `x` (B's frame, A at `relative` in it): A's, then B's.
pub(super) fn surface_gradients<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    shapes: (&A, &B),
    relative: &Pose,
    x: Vector,
) -> [Vector; 2] {
    [0, 1].map(|s| gradient_on(shapes, relative, s, Feature::Whole, x))
}

/// Body `s`'s (0: A, 1: B) outward unit gradient on the part `feature` of its surface at `x`
/// (B's frame, A at `relative` in it).
pub(super) fn gradient_on<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    (a, b): (&A, &B),
    relative: &Pose,
    s: usize,
    feature: Feature,
    x: Vector,
) -> Vector {
    if s == 0 {
        relative.rotation * feature.gradient(a, relative.inverse_transform_point(x))
    } else {
        feature.gradient(b, x)
    }
}

/// Whether each body (A, B) is flat at `x` (B's frame, A at `relative` in it), where its
/// distance gradients are `gradients`: whether they stay the same (within round-off) at the
/// points `step` away from `x` along two directions across the `normal` — a polyhedron's or
/// a cylinder's face, not a ball, a curved side, or an edge within `step`.
pub(super) fn flat_at<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    shapes: (&A, &B),
    relative: &Pose,
    x: Vector,
    normal: Vector,
    step: Real,
    gradients: [Vector; 2],
) -> [bool; 2] {
    let (u, v) = normal.any_orthonormal_pair();
    let mut flat = [step > 0.0; 2];
    for y in [x + u * step, x + v * step] {
        let g = surface_gradients(shapes, relative, y);
        for s in 0..2 {
            flat[s] &= (g[s] - gradients[s]).length() <= FLAT;
        }
    }
    flat
}

/// How far a cap, within `reach` of the contact point `x` (B's frame, across the `normal`),
/// may travel over the face of body `s` beneath it with all of it staying on the face: the
/// first of four times `reach`, halved up to [`GLIDE_HALVINGS`] − 1 times, that the face is
/// found to allow, or 0. (An unbounded body is probed too: it need not be a half-space.)
///
/// Where the body's distance gradient at the points `x ± √2 (reach + T) u` and `x ± √2
/// (reach + T) v` (`u`, `v` across the normal) is its gradient at `x`, those points' nearest
/// surface points lie on the face (inside a convex body the gradient is the normal of the
/// nearest face, and a point's projection onto its nearest face's plane lies within every
/// other face's half-space); the face is convex, so it holds their square and the disc of
/// radius `reach + T` about `x` in it: a cap that travels by `T` stays on it.
pub(super) fn glide<A: Sdf + ?Sized, B: Sdf + ?Sized>(
    shapes: (&A, &B),
    relative: &Pose,
    (x, normal): (Vector, Vector),
    reach: Real,
    gradients: [Vector; 2],
    s: usize,
) -> Real {
    let (u, v) = normal.any_orthonormal_pair();
    let on_face = |step: Real| {
        [u, -u, v, -v].into_iter().all(|w| {
            let g = gradient_on(shapes, relative, s, Feature::Whole, x + w * step);
            (g - gradients[s]).length() <= FLAT
        })
    };
    (0..GLIDE_HALVINGS)
        .map(|k| 4.0 * reach / (1 << k) as Real)
        .find(|&travel| on_face(core::f64::consts::SQRT_2 * (reach + travel)))
        .unwrap_or(0.0)
}

/// Travels a cap's [`glide`] tries: four times its reach, halved until one fits on the face.
pub(super) const GLIDE_HALVINGS: u32 = 6;

/// Change of a unit gradient below which two points lie on one flat face (round-off of the
/// frame transform).
pub(super) const FLAT: Real = 1e-9;
