//! The axis-aligned grid of `N_c` cells per direction that the overlap is integrated on.

use parry3d_f64::bounding_volume::Aabb;

use super::{IntegrationMode, Pair};
use crate::math::{Real, Vector};
use crate::shape::Sdf;

/// An axis-aligned grid of `n` cells per direction on a box.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grid {
    pub(super) lo: Vector,
    pub(super) h: Vector,
    pub(super) n: usize,
}

impl Grid {
    /// Eq. (20): spacing `width / n`; a zero-width direction takes the smallest other spacing.
    pub(super) fn on(b: &Aabb, n: usize) -> Option<Self> {
        let w = b.maxs - b.mins;
        let mut h = w / n as Real;
        let smallest =
            [h.x, h.y, h.z].into_iter().filter(|v| *v > 0.0).fold(Real::INFINITY, Real::min);
        if !smallest.is_finite() {
            return None;
        }
        for j in 0..3 {
            if h[j] <= 0.0 {
                h[j] = smallest;
            }
        }
        // A zero-width direction is centred on the (flat) box.
        let lo = Vector::new(
            if w.x > 0.0 { b.mins.x } else { b.mins.x - 0.5 * h.x * n as Real },
            if w.y > 0.0 { b.mins.y } else { b.mins.y - 0.5 * h.y * n as Real },
            if w.z > 0.0 { b.mins.z } else { b.mins.z - 0.5 * h.z * n as Real },
        );
        Some(Self { lo, h, n })
    }

    #[inline]
    pub(super) fn node(&self, i: usize, j: usize, k: usize) -> Vector {
        self.lo + self.h * Vector::new(i as Real, j as Real, k as Real)
    }

    #[inline]
    pub(super) fn index(&self, i: usize, j: usize, k: usize) -> usize {
        let m = self.n + 1;
        (k * m + j) * m + i
    }

    pub(super) fn bounds(&self) -> Aabb {
        Aabb::new(self.lo, self.lo + self.h * self.n as Real)
    }

    /// The same spacing with one more cell on every side.
    pub(super) fn padded(&self) -> Self {
        Self { lo: self.lo - self.h, h: self.h, n: self.n + 2 }
    }

    /// Node values `(d_A, d_B)` on all `(n+1)^3` nodes, x fastest, for integration in `mode`.
    ///
    /// In sub-cell mode, where both bodies are polyhedra bounded exactly by their faces, every
    /// cell is clipped by those faces, and the grid asks of a node only which bodies hold it
    /// and whether a body may reach into the node's cells (lies within a cell's diagonal of
    /// it). A node's largest face-plane value answers both, more loosely: it is the distance
    /// inside and a lower bound of it outside (the same sign, zero on the surface), so a few
    /// more cells are clipped to nothing. A body of more faces than a box's six (a convex hull,
    /// whose distance outside walks its faces' edges) takes that value instead of its distance.
    pub(super) fn sample<A: Sdf + ?Sized, B: Sdf + ?Sized>(
        &self,
        pair: &Pair<'_, A, B>,
        mode: IntegrationMode,
    ) -> Vec<(Real, Real)> {
        let m = self.n + 1;
        let mut out = Vec::with_capacity(m * m * m);
        let planes = match mode {
            IntegrationMode::Subcell => pair.a.exact_planes().zip(pair.b.exact_planes()),
            IntegrationMode::Count => None,
        };
        let [bound_a, bound_b] = match &planes {
            Some((a, b)) => [a, b].map(|p| (p.len() > 6).then_some(p.as_slice())),
            None => [None, None],
        };
        let largest = |planes: &[(Vector, Real)], x: Vector| {
            planes.iter().fold(Real::NEG_INFINITY, |d, (n, h)| d.max(n.dot(x) - h))
        };
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let x = self.node(i, j, k);
                    let da = bound_a.map_or_else(|| pair.a.distance(x), |p| largest(p, x));
                    let db = bound_b.map_or_else(|| pair.b.distance(x), |p| largest(p, x));
                    out.push((da, db));
                }
            }
        }
        out
    }
}
