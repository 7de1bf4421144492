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
/// A [`CellGrid`] of cell size the largest diameter: `O(n)` for bodies of similar size. The
/// pairs come sorted by `(i, j)`, whatever the hash order, so callers that sum forces in this
/// order get the same result on every run.
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
    let mut grid = CellGrid::new(h, periodic);
    for (i, s) in spheres.iter().enumerate() {
        grid.insert(i, s.centre);
    }
    let mut pairs = Vec::new();
    for (i, a) in spheres.iter().enumerate() {
        for j in grid.near(a.centre).filter(|&j| j > i) {
            let b = &spheres[j];
            let shift =
                periodic.map_or(Vector::ZERO, |p| p.nearest_image_shift(a.centre, b.centre));
            if (b.centre + shift - a.centre).length() <= a.radius + b.radius {
                pairs.push((i, j, shift));
            }
        }
    }
    pairs.sort_by_key(|&(i, j, _)| (i, j));
    pairs
}

/// A uniform grid of cubic cells over space, periodic where a box is: items are filed under
/// the cell of a point, and [`near`](Self::near) lists the items of the cells around a point,
/// each cell once. With cells at least as wide as the largest reach asked for, every item
/// within that reach of the point (through the periodic faces) is among them.
///
/// The one cell list of the crate: the pair search ([`overlapping_spheres`]) fills it at once,
/// random sequential placement fills it one item at a time.
///
/// ```
/// use discrete_contact::math::Vector;
/// use discrete_contact::periodic::{CellGrid, PeriodicBox};
/// let b = PeriodicBox::new(Vector::ZERO, Vector::splat(1.0), [true; 3])?;
/// let mut grid = CellGrid::new(0.2, Some(&b));
/// grid.insert(0, Vector::new(0.05, 0.5, 0.5));
/// grid.insert(1, Vector::new(0.5, 0.5, 0.5));
/// // Item 0 is 0.1 away from x = 0.95 through the face x = 1; item 1 is far.
/// assert_eq!(grid.near(Vector::new(0.95, 0.5, 0.5)).collect::<Vec<_>>(), vec![0]);
/// # Ok::<(), discrete_contact::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct CellGrid {
    /// Cell width (m) along an open axis.
    width: Real,
    /// Cells along each axis: the box's length split into cells of at least `width` along a
    /// periodic axis (one cell where fewer than three fit, so no cell is visited twice), `0`
    /// along an open axis (unbounded).
    cells: [i64; 3],
    origin: Vector,
    lengths: Vector,
    /// Items per cell: a dense array in a box periodic along every axis (no hashing), else a
    /// map of the occupied cells.
    buckets: Buckets,
}

#[derive(Clone, Debug)]
enum Buckets {
    Dense(Vec<Vec<usize>>),
    Sparse(HashMap<[i64; 3], Vec<usize>>),
}

impl CellGrid {
    /// An empty grid of cells at least `width` wide (m, positive and finite), periodic along
    /// `periodic`'s periodic axes.
    pub fn new(width: Real, periodic: Option<&PeriodicBox>) -> Self {
        let lengths = periodic.map_or(Vector::ONE, |b| b.lengths());
        let cells: [i64; 3] = std::array::from_fn(|d| match periodic {
            Some(b) if b.periodic[d] => {
                let n = (lengths[d] / width).floor() as i64;
                if n >= 3 {
                    n
                } else {
                    1
                }
            }
            _ => 0,
        });
        let buckets = if cells.iter().all(|&c| c > 0) {
            Buckets::Dense(vec![Vec::new(); (cells[0] * cells[1] * cells[2]) as usize])
        } else {
            Buckets::Sparse(HashMap::new())
        };
        Self { width, cells, origin: periodic.map_or(Vector::ZERO, |b| b.min), lengths, buckets }
    }

    /// Files `item` under the cell of `point` (m).
    pub fn insert(&mut self, item: usize, point: Vector) {
        let k = self.key(point, [0; 3]);
        match &mut self.buckets {
            Buckets::Dense(cells) => cells[Self::dense_index(self.cells, k)].push(item),
            Buckets::Sparse(map) => map.entry(k).or_default().push(item),
        }
    }

    /// The items filed in the cell of `point` and its neighbours (each cell once), cell by
    /// cell in a fixed order and in insertion order within a cell.
    pub fn near(&self, point: Vector) -> impl Iterator<Item = usize> + '_ {
        let range = |d: usize| if self.cells[d] == 1 { 0..=0 } else { -1..=1 };
        range(2)
            .flat_map(move |z| range(1).flat_map(move |y| range(0).map(move |x| [x, y, z])))
            .flat_map(move |offset| self.get(self.key(point, offset)).iter().copied())
    }

    /// Removes every item (keeping the cells).
    pub fn clear(&mut self) {
        match &mut self.buckets {
            Buckets::Dense(cells) => cells.iter_mut().for_each(Vec::clear),
            Buckets::Sparse(map) => map.clear(),
        }
    }

    /// The cell `offset` cells away from `point`'s, wrapped along periodic axes.
    fn key(&self, p: Vector, offset: [i64; 3]) -> [i64; 3] {
        std::array::from_fn(|d| {
            let n = self.cells[d];
            if n > 0 {
                let f = ((p[d] - self.origin[d]) / self.lengths[d]).rem_euclid(1.0);
                (((f * n as Real).floor() as i64).min(n - 1) + offset[d]).rem_euclid(n)
            } else {
                ((p[d] - self.origin[d]) / self.width).floor() as i64 + offset[d]
            }
        })
    }

    /// Index of cell `k` in the dense array of a `cells` grid.
    fn dense_index(cells: [i64; 3], k: [i64; 3]) -> usize {
        ((k[2] * cells[1] + k[1]) * cells[0] + k[0]) as usize
    }

    /// The items in cell `k`.
    fn get(&self, k: [i64; 3]) -> &[usize] {
        match &self.buckets {
            Buckets::Dense(cells) => &cells[Self::dense_index(self.cells, k)],
            Buckets::Sparse(map) => map.get(&k).map_or(&[], |v| v.as_slice()),
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
