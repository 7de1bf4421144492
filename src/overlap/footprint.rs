//! The overlap's footprint: the surfaces where the bodies meet, seen as an area spread across
//! the contact — its area, centroid and second moment of area. It tells how the overlap's
//! volume and centroid change when the surfaces tilt against each other, so that an update
//! between full evaluations can follow a rocking body ([`contact`](crate::contact)'s geometry
//! reuse).
//!
//! For an exact polyhedral overlap it is summed face by face (half of each body's faces,
//! exactly). On the grid it is summed cell by cell: each cell's facets (the mean of the two bodies'
//! areas, both of which span the footprint) at the centroid of the cell's part of the overlap,
//! with a whole cell's own spread — within `(h/w)²` of the exact moment for an overlap `w`
//! across, and far cheaper than facet by facet. The sums are taken about the pair frame's
//! origin (a body's centre), so the central moment loses `(ρ/w)²` of the relative precision
//! for an overlap at `ρ` from the origin: ten digits remain for one a thousandth of the body's
//! size.

use crate::math::{Matrix, Pose, Real, Vector};

/// An overlap's footprint: area, centroid and central second moment of area.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct Footprint {
    /// Area (m²): the mean of the two bodies' surface areas within the overlap.
    pub area: Real,
    /// Centroid (m).
    pub centroid: Vector,
    /// Central second moment of area `∫ (x − c)(x − c)ᵀ dA` (m⁴).
    pub spread: Matrix,
}

impl Footprint {
    /// The footprint in the frame `pose` maps this one's frame into.
    pub fn transformed(&self, pose: &Pose) -> Self {
        let r = Matrix::from_quat(pose.rotation);
        Self {
            area: self.area,
            centroid: pose.transform_point(self.centroid),
            spread: r * self.spread * r.transpose(),
        }
    }
}

/// Area, first moment and `∫ x xᵀ dA` (its diagonal and `(xy, xz, yz)` entries) of the
/// footprint's pieces added so far.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Sums {
    area: Real,
    moment: Vector,
    diagonal: Vector,
    off: Vector,
}

impl Sums {
    /// Adds `a aᵀ w`.
    #[inline]
    fn add_outer(&mut self, a: Vector, w: Real) {
        self.diagonal += a * a * w;
        self.off += Vector::new(a.x * a.y, a.x * a.z, a.y * a.z) * w;
    }

    /// Adds an area `area` at `at`, spread over a cell of sides `h` (its own second moment
    /// `area h²/12` on each axis).
    #[inline]
    pub(super) fn add(&mut self, at: Vector, h: Vector, area: Real) {
        self.area += area;
        self.moment += at * area;
        self.add_outer(at, area);
        self.diagonal += h * h * (area / 12.0);
    }

    /// Adds the triangle `a b c` with its area times `weight`, its moments exact:
    /// `∫ x xᵀ dA = A/12 (s sᵀ + a aᵀ + b bᵀ + c cᵀ)`, `s = a + b + c`.
    pub(super) fn add_triangle(&mut self, [a, b, c]: [Vector; 3], weight: Real) {
        let area = 0.5 * (b - a).cross(c - a).length() * weight;
        let s = a + b + c;
        self.area += area;
        self.moment += s * (area / 3.0);
        for v in [s, a, b, c] {
            self.add_outer(v, area / 12.0);
        }
    }

    /// The footprint, if any area was added.
    pub(super) fn finish(&self) -> Option<Footprint> {
        if !(self.area > 0.0) {
            return None;
        }
        let centroid = self.moment / self.area;
        let mut c = *self;
        c.add_outer(centroid, -self.area);
        let Sums { diagonal: d, off: o, .. } = c;
        let spread = Matrix::from_cols(
            Vector::new(d.x, o.x, o.y),
            Vector::new(o.x, d.y, o.z),
            Vector::new(o.y, o.z, d.z),
        );
        Some(Footprint { area: self.area, centroid, spread })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four quarter squares, each spread over its cell, make the whole square's moment, and a
    /// rigid motion carries it along.
    /// Two triangles make a rectangle's exact moments, with a weight.
    #[test]
    fn triangles_make_the_rectangle() {
        let (w, h, centre) = (0.6, 0.2, Vector::new(-0.3, 0.4, 2.0));
        let corner = |i: Real, j: Real| centre + Vector::new((i - 0.5) * w, 0.0, (j - 0.5) * h);
        let mut sums = Sums::default();
        sums.add_triangle([corner(0.0, 0.0), corner(1.0, 0.0), corner(1.0, 1.0)], 0.5);
        sums.add_triangle([corner(0.0, 0.0), corner(1.0, 1.0), corner(0.0, 1.0)], 0.5);
        let f = sums.finish().unwrap();
        let expected = Matrix::from_diagonal(Vector::new(w.powi(3) * h, 0.0, w * h.powi(3)) / 24.0);
        let err =
            (f.spread - expected).to_cols_array().iter().fold(0.0, |e: Real, x| e.max(x.abs()));
        assert!((f.area - 0.5 * w * h).abs() < 1e-15 && (f.centroid - centre).length() < 1e-14);
        assert!(err < 1e-15, "{:?}", f.spread);
    }

    #[test]
    fn quarters_make_the_square_and_move_with_it() {
        let (side, centre) = (0.4, Vector::new(1.0, -2.0, 0.5));
        let h = Vector::new(side / 2.0, side / 2.0, 0.0);
        let mut sums = Sums::default();
        for (i, j) in [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)] {
            let at = centre + Vector::new((i - 0.5) * h.x, (j - 0.5) * h.y, 0.0);
            sums.add(at, h, h.x * h.y);
        }
        let f = sums.finish().unwrap();
        let second = side.powi(4) / 12.0;
        let expected = Matrix::from_diagonal(Vector::new(second, second, 0.0));
        let err = |m: Matrix| {
            (m - expected).to_cols_array().iter().fold(0.0, |e: Real, x| e.max(x.abs()))
        };
        assert!((f.area - side * side).abs() < 1e-15 && (f.centroid - centre).length() < 1e-14);
        assert!(err(f.spread) < 1e-15, "{:?}", f.spread);
        let turn = Pose::from_parts(
            Vector::new(0.3, 0.0, -1.0),
            crate::math::Rotation::from_rotation_x(0.7),
        );
        let moved = f.transformed(&turn);
        let r = Matrix::from_quat(turn.rotation);
        assert!((moved.centroid - turn.transform_point(centre)).length() < 1e-14);
        let back = r.transpose() * moved.spread * r;
        assert!(err(back) < 1e-15);
    }
}
