//! Periodic boundaries for bodies and contacts, and the bounding-sphere neighbour search that
//! finds candidate pairs across them.
//!
//! A body lives once, in the box `[min, max)`: when its centre of mass leaves through a
//! periodic face it is moved back by one box length (velocities untouched). Near a face it is
//! *seen* on both sides — a pair is evaluated between A and the **nearest image** of B
//! (the minimum-image convention), on A's side, A being the body that comes first in a fixed
//! order (Marquardt, Hafen & Krause take the lower id); B's pose is shifted there for the evaluation and the
//! force, which does not depend on where the pair sits, is applied to B where it is. A
//! persistent contact keeps its state across the shift: its box lives in a body frame, so it is
//! unchanged when either body is moved back into the box.
//!
//! The nearest image is unique only when every periodic length is at least twice the reach of
//! a pair (the sum of two bounding radii and the margin); [`PeriodicBox::check_reach`] refuses
//! smaller boxes.
//!
//! ```
//! use discrete_contact::periodic::PeriodicBox;
//! use discrete_contact::math::Vector;
//! let b = PeriodicBox::new(Vector::ZERO, Vector::splat(1.0), [true, true, false])?;
//! // A body at x = 0.95 and one at x = 0.05 are 0.1 apart through the face x = 1.
//! let shift = b.nearest_image_shift(Vector::new(0.95, 0.5, 0.5), Vector::new(0.05, 0.5, 0.5));
//! assert_eq!(shift, Vector::new(1.0, 0.0, 0.0));
//! // A body that left through x = 1 comes back at x = 0.02.
//! assert_eq!(b.wrap_shift(Vector::new(1.02, 0.5, 3.0)), Vector::new(-1.0, 0.0, 0.0));
//! # Ok::<(), discrete_contact::Error>(())
//! ```

use std::collections::HashMap;

use crate::error::{check_finite_vec, Error, Result};
use crate::math::{Real, Vector};

/// An axis-aligned box, periodic along some axes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "checkpoint", serde(try_from = "BoxFields"))]
pub struct PeriodicBox {
    min: Vector,
    max: Vector,
    periodic: [bool; 3],
}

impl PeriodicBox {
    /// The box `[min, max)` (m), periodic along the axes marked `true`; refuses non-finite
    /// corners and a periodic axis with `max <= min`.
    pub fn new(min: Vector, max: Vector, periodic: [bool; 3]) -> Result<Self> {
        check_finite_vec("periodic box min", min)?;
        check_finite_vec("periodic box max", max)?;
        for d in 0..3 {
            if periodic[d] && max[d] <= min[d] {
                return Err(Error::InvalidParameter {
                    name: "periodic box size (max - min)",
                    value: max[d] - min[d],
                    allowed: "> 0 along every periodic axis",
                });
            }
        }
        Ok(Self { min, max, periodic })
    }

    /// Lower corner (m).
    pub fn min(&self) -> Vector {
        self.min
    }

    /// Upper corner (m).
    pub fn max(&self) -> Vector {
        self.max
    }

    /// Which axes are periodic.
    pub fn periodic(&self) -> [bool; 3] {
        self.periodic
    }

    /// Box lengths (m).
    pub fn lengths(&self) -> Vector {
        self.max - self.min
    }

    /// Whether any axis is periodic.
    pub fn is_periodic(&self) -> bool {
        self.periodic.iter().any(|&p| p)
    }

    /// The shift (whole box lengths along periodic axes, zero along the others) that moves `b`
    /// to its image nearest to `a`.
    pub fn nearest_image_shift(&self, a: Vector, b: Vector) -> Vector {
        let l = self.lengths();
        let delta = b - a;
        Vector::from_array(std::array::from_fn(|d| {
            if self.periodic[d] {
                -(delta[d] / l[d]).round() * l[d]
            } else {
                0.0
            }
        }))
    }

    /// The shift that moves `p` back into `[min, max)` along the periodic axes (zero when it is
    /// inside).
    pub fn wrap_shift(&self, p: Vector) -> Vector {
        let l = self.lengths();
        Vector::from_array(std::array::from_fn(|d| {
            if self.periodic[d] {
                -((p[d] - self.min[d]) / l[d]).floor() * l[d]
            } else {
                0.0
            }
        }))
    }

    /// Refuses a box whose periodic lengths are below `2 reach`: two images of one body would
    /// both be in reach and the nearest image would not be unique.
    pub fn check_reach(&self, reach: Real) -> Result<()> {
        let l = self.lengths();
        for d in 0..3 {
            if self.periodic[d] && l[d] < 2.0 * reach {
                return Err(Error::InvalidParameter {
                    name: "periodic box size (max - min)",
                    value: l[d],
                    allowed: "at least twice the largest pair reach (two bounding diameters plus the contact margin)",
                });
            }
        }
        Ok(())
    }
}

/// A bounding sphere for the neighbour search: centre (m) and radius (m), already grown by
/// whatever margin the caller needs (contact enlargement, distance travelled in a step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre (m).
    pub centre: Vector,
    /// Radius (m), finite.
    pub radius: Real,
}

/// Pairs `(i, j, shift)`, `i < j`, of spheres that overlap — through periodic faces when a box
/// is given, `shift` then moving sphere `j` to its image nearest to `i` (zero without a box).
///
/// A uniform cell list of cell size the largest diameter: `O(n)` for bodies of similar size.
/// The pairs come sorted by `(i, j)`, whatever the hash order, so callers that sum forces in
/// this order get the same result on every run.
pub fn overlapping_spheres(
    spheres: &[Sphere],
    periodic: Option<&PeriodicBox>,
) -> Vec<(usize, usize, Vector)> {
    let Some(h) = spheres
        .iter()
        .map(|s| 2.0 * s.radius)
        .reduce(Real::max)
        .filter(|&h| h > 0.0 && h.is_finite())
    else {
        return Vec::new();
    };
    // Along a periodic axis with fewer than 3 cells, every body is every body's neighbour
    // along it: one cell there, so no pair is visited twice.
    let cells: [i64; 3] = std::array::from_fn(|d| match periodic {
        Some(b) if b.periodic[d] => {
            let n = (b.lengths()[d] / h).floor() as i64;
            if n >= 3 {
                n
            } else {
                1
            }
        }
        _ => 0,
    });
    let origin = periodic.map_or(Vector::ZERO, |b| b.min);
    let key = |p: Vector, offset: [i64; 3]| -> [i64; 3] {
        std::array::from_fn(|d| {
            if cells[d] > 0 {
                let l = periodic.map_or(1.0, |b| b.lengths()[d]);
                let i =
                    (((p[d] - origin[d]) / l).rem_euclid(1.0) * cells[d] as Real).floor() as i64;
                (i.min(cells[d] - 1) + offset[d]).rem_euclid(cells[d])
            } else {
                ((p[d] - origin[d]) / h).floor() as i64 + offset[d]
            }
        })
    };
    let buckets = Buckets::new(spheres.len(), cells, spheres.iter().map(|s| key(s.centre, [0; 3])));
    let range = |d: usize| if cells[d] == 1 { 0..=0 } else { -1..=1 };
    let mut pairs = Vec::new();
    for (i, a) in spheres.iter().enumerate() {
        for oz in range(2) {
            for oy in range(1) {
                for ox in range(0) {
                    let list = buckets.get(key(a.centre, [ox, oy, oz]));
                    for &j in list.iter().filter(|&&j| j > i) {
                        let b = &spheres[j];
                        let shift = periodic
                            .map_or(Vector::ZERO, |p| p.nearest_image_shift(a.centre, b.centre));
                        if (b.centre + shift - a.centre).length() <= a.radius + b.radius {
                            pairs.push((i, j, shift));
                        }
                    }
                }
            }
        }
    }
    pairs.sort_by_key(|&(i, j, _)| (i, j));
    pairs
}

/// The cell list's buckets: in a box periodic along every axis a dense array of cells, filled
/// by counting sort (no hashing; measured the larger part of a dense suspension's pair search
/// with hashing); otherwise a hash map of the occupied cells.
enum Buckets {
    Dense { cells: [i64; 3], start: Vec<usize>, members: Vec<usize> },
    Sparse(HashMap<[i64; 3], Vec<usize>>),
}

impl Buckets {
    /// Index of cell `k` in the dense array of a `cells` grid.
    fn dense_index(cells: [i64; 3], k: [i64; 3]) -> usize {
        ((k[2] * cells[1] + k[1]) * cells[0] + k[0]) as usize
    }

    /// Buckets of `n` items whose cells are `homes`, on a grid of `cells` (0 along an open axis).
    fn new(n: usize, cells: [i64; 3], homes: impl Iterator<Item = [i64; 3]>) -> Self {
        if cells.iter().all(|&c| c > 0) {
            let homes: Vec<usize> = homes.map(|k| Self::dense_index(cells, k)).collect();
            let mut start = vec![0usize; (cells[0] * cells[1] * cells[2]) as usize + 1];
            for &c in &homes {
                start[c + 1] += 1;
            }
            for c in 1..start.len() {
                start[c] += start[c - 1];
            }
            let mut fill = start.clone();
            let mut members = vec![0; n];
            for (i, &c) in homes.iter().enumerate() {
                members[fill[c]] = i;
                fill[c] += 1;
            }
            Self::Dense { cells, start, members }
        } else {
            let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::with_capacity(n);
            for (i, k) in homes.enumerate() {
                grid.entry(k).or_default().push(i);
            }
            Self::Sparse(grid)
        }
    }

    /// The items in cell `k`, in the order given.
    fn get(&self, k: [i64; 3]) -> &[usize] {
        match self {
            Self::Dense { cells, start, members } => {
                let c = Self::dense_index(*cells, k);
                &members[start[c]..start[c + 1]]
            }
            Self::Sparse(grid) => grid.get(&k).map_or(&[], |v| v.as_slice()),
        }
    }
}

deserialize_checked!(PeriodicBox via BoxFields { min: Vector, max: Vector, periodic: [bool; 3] }
    => |f| PeriodicBox::new(f.min, f.max, f.periodic));

#[cfg(test)]
mod tests {
    use super::*;

    /// The cell list finds exactly the pairs a brute-force minimum-image search finds.
    #[test]
    fn cell_list_matches_brute_force() {
        let b = PeriodicBox::new(
            Vector::new(-1.0, 0.0, 2.0),
            Vector::new(2.0, 1.5, 4.5),
            [true, true, false],
        )
        .unwrap();
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as Real / (1u64 << 53) as Real
        };
        let spheres: Vec<Sphere> = (0..300)
            .map(|_| Sphere {
                centre: Vector::new(
                    -1.0 + 3.0 * next(),
                    1.5 * next(),
                    2.0 + 2.5 * next() + if next() < 0.1 { 3.0 } else { 0.0 },
                ),
                radius: 0.05 + 0.1 * next(),
            })
            .collect();
        let all =
            PeriodicBox::new(Vector::new(-1.0, 0.0, 2.0), Vector::new(2.0, 1.5, 4.5), [true; 3])
                .unwrap();
        for periodic in [Some(&b), Some(&all), None] {
            let fast = overlapping_spheres(&spheres, periodic);
            let mut brute = Vec::new();
            for i in 0..spheres.len() {
                for j in i + 1..spheres.len() {
                    let (a, c) = (spheres[i], spheres[j]);
                    let s = periodic
                        .map_or(Vector::ZERO, |p| p.nearest_image_shift(a.centre, c.centre));
                    if (c.centre + s - a.centre).length() <= a.radius + c.radius {
                        brute.push((i, j, s));
                    }
                }
            }
            assert!(!brute.is_empty());
            assert_eq!(fast, brute);
        }
    }

    #[test]
    fn wrap_and_images() {
        let b = PeriodicBox::new(Vector::ZERO, Vector::new(2.0, 1.0, 1.0), [true, false, true])
            .unwrap();
        assert_eq!(b.wrap_shift(Vector::new(-0.5, 7.0, 0.5)), Vector::new(2.0, 0.0, 0.0));
        assert_eq!(b.wrap_shift(Vector::new(2.0, -7.0, 2.5)), Vector::new(-2.0, 0.0, -2.0));
        assert_eq!(
            b.nearest_image_shift(Vector::new(0.1, 0.0, 0.9), Vector::new(1.9, 0.9, 0.1)),
            Vector::new(-2.0, 0.0, 1.0)
        );
        assert!(b.check_reach(0.6).is_err());
        assert!(b.check_reach(0.5).is_ok());
        assert!(PeriodicBox::new(Vector::ZERO, Vector::new(1.0, -1.0, 1.0), [true; 3]).is_err());
        assert!(PeriodicBox::new(Vector::ZERO, Vector::new(1.0, -1.0, 1.0), [true, false, true])
            .is_ok());
    }
}
