//! The overlap's spread: the second moment of its volume, `∫ x xᵀ dV`, summed in the pair's
//! frame — on the grid cell by cell (each cell's part of the overlap at its centroid, with a
//! whole cell's own spread; counted nodes as whole cells), for the exact polyhedra
//! tetrahedron by tetrahedron — and made central about the centroid at the end. It tells how far the overlap reaches across the contact plane, so
//! that an update between full evaluations can move the centroid as a tilt of the surfaces
//! moves it ([`contact`](crate::contact)'s geometry reuse).
//!
//! The sums are taken about the pair frame's origin (a body's centre), so the central moment
//! loses `(ρ/e)²` of the relative precision for an overlap `e` across at `ρ` from the origin:
//! ten digits remain for an overlap a thousandth of the body's size.

use crate::math::{Matrix, Real, Vector};

/// `∫ x xᵀ dV` of the pieces added so far: its diagonal and its `(xy, xz, yz)` entries.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Spread {
    diagonal: Vector,
    off: Vector,
}

impl Spread {
    /// Adds `a aᵀ w`.
    #[inline]
    fn add_outer(&mut self, a: Vector, w: Real) {
        self.diagonal += a * a * w;
        self.off += Vector::new(a.x * a.y, a.x * a.z, a.y * a.z) * w;
    }

    /// Adds a tetrahedron of volume `volume` with corners `p`:
    /// `∫ x xᵀ dV = V/20 (Σ pᵢ pᵢᵀ + s sᵀ)`, `s = Σ pᵢ`.
    #[inline]
    pub(super) fn add_tetrahedron(&mut self, p: [Vector; 4], volume: Real) {
        let w = volume / 20.0;
        for x in p {
            self.add_outer(x, w);
        }
        self.add_outer(p[0] + p[1] + p[2] + p[3], w);
    }

    /// Adds a box of volume `volume` centred at `centre` with sides `h`:
    /// `V (c cᵀ + diag(h²)/12)`.
    #[inline]
    pub(super) fn add_box(&mut self, centre: Vector, h: Vector, volume: Real) {
        self.add_outer(centre, volume);
        self.diagonal += h * h * (volume / 12.0);
    }

    /// The central second moment `∫ (x − c)(x − c)ᵀ dV` of a volume `volume` with centroid
    /// `centroid` whose sum this is.
    pub(super) fn central(&self, volume: Real, centroid: Vector) -> Matrix {
        let mut c = *self;
        c.add_outer(centroid, -volume);
        let Spread { diagonal: d, off: o } = c;
        Matrix::from_cols(
            Vector::new(d.x, o.x, o.y),
            Vector::new(o.x, d.y, o.z),
            Vector::new(o.y, o.z, d.z),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box cut into the six Kuhn tetrahedra has the box's second moment.
    #[test]
    fn six_tetrahedra_make_the_box() {
        let (lo, h) = (Vector::new(0.3, -1.2, 2.0), Vector::new(0.5, 0.25, 2.0));
        let corner = |c: usize| {
            lo + h * Vector::new((c & 1) as Real, ((c >> 1) & 1) as Real, ((c >> 2) & 1) as Real)
        };
        let tets =
            [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];
        let mut pieces = Spread::default();
        for t in tets {
            pieces.add_tetrahedron(t.map(corner), h.element_product() / 6.0);
        }
        let mut whole = Spread::default();
        let (volume, centre) = (h.element_product(), lo + h * 0.5);
        whole.add_box(centre, h, volume);
        let (p, w) = (pieces.central(volume, centre), whole.central(volume, centre));
        let expected = Matrix::from_diagonal(h * h * (volume / 12.0));
        for (m, what) in [(p, "tetrahedra"), (w, "box")] {
            let err = (m - expected).to_cols_array().iter().fold(0.0, |e: Real, x| e.max(x.abs()));
            assert!(err < 1e-12, "{what}: {m:?} against {expected:?}");
        }
    }
}
