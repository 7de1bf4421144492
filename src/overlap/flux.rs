//! How the overlap changes under a small rigid motion of body A against B ([`Flux`]).
//!
//! On the grid the moments are summed cell by cell: each cell's facets of A as one area
//! vector at the centroid of the cell's part of the overlap (as the footprint sums its
//! areas), within a fraction of a cell of each facet's own centroid; the polyhedral clip sums
//! them triangle by triangle, exactly. The sums are taken about the grid's (or the box's)
//! centre and moved to the overlap's centroid at the end.

use crate::math::{Matrix, Pose, Real, Vector};

/// The moments of A's surface within B that give the overlap's first-order change under a
/// rigid motion of A, about [`origin`](Self::origin): Reynolds' transport theorem.
///
/// Only A's surface moves, so the overlap `Ω = A ∩ B` changes by the volume A's surface
/// sweeps inside B: for a displacement field `u`, `δV = ∫ u·ν dS` and `δ∫x dV = ∫ x (u·ν) dS`
/// over A's part of the overlap's boundary, `ν` out of A. A rigid motion,
/// `u(x) = δ + ω × (x − c)`, makes both linear in `(δ, ω)` with the moments of that surface
/// about a point `c`: `S = ∫ ν dS`, `T = ∫ (x − c) × ν dS`, `P = ∫ (x − c) νᵀ dS` and
/// `Q = ∫ (x − c)((x − c) × ν)ᵀ dS` ([`swept`](Self::swept)). Exact to first order for any
/// pair, edges and corners included, where the [`Footprint`](super::Footprint) holds only for
/// nearly parallel surfaces.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct Flux {
    /// The point the moments are taken about: the overlap's centroid (m).
    pub origin: Vector,
    /// `S = ∫ ν dS` (m²), `ν` A's outward normal.
    pub area: Vector,
    /// `T = ∫ (x − c) × ν dS` (m³).
    pub moment: Vector,
    /// `P = ∫ (x − c) νᵀ dS` (m³).
    pub first: Matrix,
    /// `Q = ∫ (x − c)((x − c) × ν)ᵀ dS` (m⁴).
    pub second: Matrix,
}

impl Flux {
    /// The flux in the frame `pose` maps this one's frame into.
    pub fn transformed(&self, pose: &Pose) -> Self {
        let r = Matrix::from_quat(pose.rotation);
        Self {
            origin: pose.transform_point(self.origin),
            area: pose.rotation * self.area,
            moment: pose.rotation * self.moment,
            first: r * self.first * r.transpose(),
            second: r * self.second * r.transpose(),
        }
    }

    /// The first-order change of the overlap's volume (m³) and of its first moment about
    /// [`origin`](Self::origin) (m⁴) when A moves by `displacement` at the origin and turns by
    /// the rotation vector `turn` (rad): `(δ·S + ω·T, P δ + Q ω)`.
    pub fn swept(&self, displacement: Vector, turn: Vector) -> (Real, Vector) {
        (
            displacement.dot(self.area) + turn.dot(self.moment),
            self.first * displacement + self.second * turn,
        )
    }
}

/// The moments about the grid's centre of A's facets added so far.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sums {
    centre: Vector,
    area: Vector,
    moment: Vector,
    first: Matrix,
    second: Matrix,
}

impl Sums {
    /// Empty sums about `centre`.
    pub(super) fn about(centre: Vector) -> Self {
        Self {
            centre,
            area: Vector::ZERO,
            moment: Vector::ZERO,
            first: Matrix::ZERO,
            second: Matrix::ZERO,
        }
    }

    /// Adds A's facets of area vector `a` (out of A) at `at`.
    #[inline]
    pub(super) fn add(&mut self, at: Vector, a: Vector) {
        let y = at - self.centre;
        let t = y.cross(a);
        self.area += a;
        self.moment += t;
        self.first += outer(y, a);
        self.second += outer(y, t);
    }

    /// Adds A's triangle `p q r` (counter-clockwise about A's outward normal), its moments
    /// exact: `∫ x (x × ν)ᵀ dS = (∫ x xᵀ dS)[ν]×`, with
    /// `∫ x xᵀ dS = A/12 (s sᵀ + p pᵀ + q qᵀ + r rᵀ)`, `s = p + q + r`.
    pub(super) fn add_triangle(&mut self, [p, q, r]: [Vector; 3]) {
        let [p, q, r] = [p, q, r].map(|v| v - self.centre);
        let a = 0.5 * (q - p).cross(r - p);
        let s = p + q + r;
        let y = s / 3.0;
        let spread = outer(s, s) + outer(p, p) + outer(q, q) + outer(r, r);
        self.area += a;
        self.moment += y.cross(a);
        self.first += outer(y, a);
        self.second += spread * skew(a) / 12.0;
    }

    /// The flux about `centroid`, if any of A's surface was added.
    pub(super) fn finish(&self, centroid: Vector) -> Option<Flux> {
        if self.area == Vector::ZERO {
            return None;
        }
        // About `c = centre + e`: `S` stays, `T − e × S`, `P − e Sᵀ`, and
        // `Σ (y − e)((y − e) × a)ᵀ = (Q − e Tᵀ) − Σ (y − e)(e × a)ᵀ`.
        let e = centroid - self.centre;
        let first = self.first - outer(e, self.area);
        let moment = self.moment - e.cross(self.area);
        // `(e × a)ᵀ = −aᵀ[e]×`, so `Σ (y − e)(e × a)ᵀ = −P_c [e]×`.
        let second = self.second - outer(e, self.moment) + first * skew(e);
        Some(Flux { origin: centroid, area: self.area, moment, first, second })
    }
}

/// `a bᵀ`.
fn outer(a: Vector, b: Vector) -> Matrix {
    Matrix::from_cols(a * b.x, a * b.y, a * b.z)
}

/// `[e]×`: the matrix of `x ↦ e × x`.
fn skew(e: Vector) -> Matrix {
    Matrix::from_cols(
        Vector::new(0.0, e.z, -e.y),
        Vector::new(-e.z, 0.0, e.x),
        Vector::new(e.y, -e.x, 0.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Facets summed about one point and moved to another give the sums taken about that
    /// other point directly, and a rigid motion carries them along.
    #[test]
    fn moments_move_to_the_centroid_and_with_the_frame() {
        let facets = [
            (Vector::new(0.3, -0.2, 0.1), Vector::new(0.0, 0.0, -0.02)),
            (Vector::new(-0.1, 0.4, 0.2), Vector::new(0.01, 0.0, -0.01)),
            (Vector::new(0.2, 0.1, -0.3), Vector::new(-0.005, 0.02, 0.0)),
        ];
        let (far, centroid) = (Vector::new(5.0, -3.0, 2.0), Vector::new(0.1, 0.05, -0.02));
        let (mut moved, mut direct) = (Sums::about(far), Sums::about(centroid));
        for (x, a) in facets {
            moved.add(x, a);
            direct.add(x, a);
        }
        let (m, d) = (moved.finish(centroid).unwrap(), direct.finish(centroid).unwrap());
        let close = |p: Matrix, q: Matrix| (p - q).to_cols_array().iter().all(|x| x.abs() < 1e-13);
        assert!((m.moment - d.moment).length() < 1e-13);
        assert!(close(m.first, d.first) && close(m.second, d.second), "{m:?}\n{d:?}");
        // A motion's effect on the volume and the moment is the same in either frame.
        let pose = Pose::from_parts(
            Vector::new(0.3, -1.0, 2.0),
            crate::math::Rotation::from_rotation_y(0.8),
        );
        let (shift, turn) = (Vector::new(1e-4, -2e-4, 3e-5), Vector::new(2e-3, 1e-3, -4e-3));
        let (dv, dm) = d.swept(shift, turn);
        let t = d.transformed(&pose);
        let (dv_t, dm_t) = t.swept(pose.rotation * shift, pose.rotation * turn);
        assert!((dv - dv_t).abs() < 1e-18 && (pose.rotation * dm - dm_t).length() < 1e-18);
    }
}
