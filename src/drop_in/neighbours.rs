//! A Verlet list of bounding-sphere pairs: the cell-list search of [`overlapping_spheres`] run
//! once with a *skin*, then reused for as long as no body can have closed the skin.
//!
//! At a build, every pair whose bounding spheres are closer than the skin `s` is kept. A later
//! query asks for the pairs with gap `≤ reach_i + reach_j`; a pair left out had a gap above `s`
//! at the build, so it still has a gap above `s − |d_i| − |d_j|` (`d` the displacement of a
//! sphere's centre since the build, through the periodic faces). The list therefore answers
//! exactly while every sphere keeps `|d_i| + reach_i ≤ s/2` — checked on every query, `O(n)`;
//! when it fails, the list is rebuilt. The answer does not depend on when the list was built
//! (the pairs come in index order, filtered by the same test), so a run resumed from a
//! checkpoint, which starts with an empty list, gives the same pairs.
//!
//! A skin of a fifth of the smallest bounding radius lets a list last many steps in a settling
//! suspension, whose bodies move a small fraction of a lattice spacing per step.

use crate::error::Result;
use crate::math::{Real, Vector};
use crate::periodic::{overlapping_spheres, PeriodicBox, Sphere};

/// Skin of a build, as a fraction of the smallest bounding radius (at least four times the
/// largest reach asked for, so the list answers at least the query that built it and the
/// next steps).
const SKIN_FRACTION: Real = 0.2;

/// Pairs of spheres within the skin at the last build, and where the spheres were then.
#[derive(Clone, Debug, Default)]
pub(crate) struct NeighbourList {
    anchors: Vec<Vector>,
    pairs: Vec<(usize, usize)>,
    skin: Real,
    builds: usize,
}

impl NeighbourList {
    /// Puts into `out` (cleared first) the pairs `(i, j, shift)`, `i < j`, of `spheres` whose
    /// gap is at most `reach[i] + reach[j]` (through the periodic faces when a box is given,
    /// `shift` moving `j` to its image nearest `i`), in index order; rebuilds the list first
    /// when it cannot answer. The spheres must be the same bodies, in the same order, at every
    /// call (a caller that changes them starts a new list).
    pub(crate) fn query(
        &mut self,
        spheres: &[Sphere],
        reach: &[Real],
        periodic: Option<&PeriodicBox>,
        out: &mut Vec<(usize, usize, Vector)>,
    ) -> Result<()> {
        if !self.answers(spheres, reach, periodic) {
            self.build(spheres, reach, periodic)?;
        }
        out.clear();
        out.extend(self.pairs.iter().filter_map(|&(i, j)| {
            let (a, b) = (&spheres[i], &spheres[j]);
            let shift =
                periodic.map_or(Vector::ZERO, |p| p.nearest_image_shift(a.centre, b.centre));
            ((b.centre + shift - a.centre).length() <= a.radius + b.radius + reach[i] + reach[j])
                .then_some((i, j, shift))
        }));
        Ok(())
    }

    /// How many times the list has been built (its predecessors' builds included, see
    /// [`restart`](Self::restart)).
    pub(crate) fn builds(&self) -> usize {
        self.builds
    }

    /// Forgets the list, for other spheres, keeping the count of builds.
    pub(crate) fn restart(&mut self) {
        *self = Self { builds: self.builds, ..Self::default() };
    }

    /// Whether every sphere is still within `skin/2` of its anchor, its reach included.
    fn answers(&self, spheres: &[Sphere], reach: &[Real], periodic: Option<&PeriodicBox>) -> bool {
        self.anchors.len() == spheres.len()
            && spheres.iter().zip(reach).zip(&self.anchors).all(|((s, &r), &anchor)| {
                let moved = anchor
                    + periodic.map_or(Vector::ZERO, |p| p.nearest_image_shift(s.centre, anchor))
                    - s.centre;
                moved.length() + r <= 0.5 * self.skin
            })
    }

    fn build(
        &mut self,
        spheres: &[Sphere],
        reach: &[Real],
        periodic: Option<&PeriodicBox>,
    ) -> Result<()> {
        let smallest = spheres.iter().map(|s| s.radius).fold(Real::INFINITY, Real::min);
        let largest = spheres.iter().map(|s| s.radius).fold(0.0, Real::max);
        let farthest = reach.iter().copied().fold(0.0, Real::max);
        let mut skin = SKIN_FRACTION * smallest;
        if let Some(p) = periodic {
            // Keep the skin inside what the box allows (the nearest image must stay unique).
            let shortest = (0..3)
                .filter(|&d| p.periodic()[d])
                .map(|d| p.lengths()[d])
                .fold(Real::INFINITY, Real::min);
            skin = skin.min(0.5 * shortest - 2.0 * largest);
        }
        skin = skin.max(4.0 * farthest);
        if let Some(p) = periodic {
            p.check_reach(2.0 * largest + skin)?;
        }
        let grown: Vec<Sphere> = spheres
            .iter()
            .map(|s| Sphere { centre: s.centre, radius: s.radius + 0.5 * skin })
            .collect();
        self.pairs =
            overlapping_spheres(&grown, periodic).into_iter().map(|(i, j, _)| (i, j)).collect();
        self.anchors = spheres.iter().map(|s| s.centre).collect();
        self.skin = skin;
        self.builds += 1;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: every pair within reach, through the periodic faces.
    fn brute(
        spheres: &[Sphere],
        reach: &[Real],
        periodic: Option<&PeriodicBox>,
    ) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for i in 0..spheres.len() {
            for j in i + 1..spheres.len() {
                let (a, b) = (&spheres[i], &spheres[j]);
                let shift =
                    periodic.map_or(Vector::ZERO, |p| p.nearest_image_shift(a.centre, b.centre));
                if (b.centre + shift - a.centre).length()
                    <= a.radius + b.radius + reach[i] + reach[j]
                {
                    out.push((i, j));
                }
            }
        }
        out
    }

    /// Random walkers in a periodic box and in an open one: at every step the list gives
    /// exactly the brute-force pairs, while rebuilding far less often than it is asked.
    #[test]
    fn verlet_list_matches_brute_force_while_bodies_move() {
        let mut seed = 12345u64;
        let mut rand = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as Real / (1u64 << 53) as Real
        };
        for periodic in [
            Some(PeriodicBox::new(Vector::ZERO, Vector::splat(1.0), [true, true, false]).unwrap()),
            None,
        ] {
            let mut spheres: Vec<Sphere> = (0..300)
                .map(|_| Sphere {
                    centre: Vector::new(rand(), rand(), rand()),
                    radius: 0.02 + 0.02 * rand(),
                })
                .collect();
            let velocity: Vec<Vector> = (0..300)
                .map(|_| Vector::new(rand() - 0.5, rand() - 0.5, rand() - 0.5) * 4e-4)
                .collect();
            let mut list = NeighbourList::default();
            let mut found = 0;
            for step in 0..200 {
                let reach: Vec<Real> = (0..300)
                    .map(|i| if step % 2 == 0 { 1e-3 } else { 1e-3 + velocity[i].length() })
                    .collect();
                let mut pairs = Vec::new();
                list.query(&spheres, &reach, periodic.as_ref(), &mut pairs).unwrap();
                let expected = brute(&spheres, &reach, periodic.as_ref());
                assert_eq!(
                    pairs.iter().map(|&(i, j, _)| (i, j)).collect::<Vec<_>>(),
                    expected,
                    "step {step}"
                );
                for &(i, j, shift) in &pairs {
                    let image = spheres[j].centre + shift;
                    let direct = periodic.map_or(Vector::ZERO, |p| {
                        p.nearest_image_shift(spheres[i].centre, spheres[j].centre)
                    });
                    assert_eq!(image, spheres[j].centre + direct);
                }
                found += pairs.len();
                for (s, v) in spheres.iter_mut().zip(&velocity) {
                    s.centre += *v;
                    if let Some(p) = &periodic {
                        s.centre += p.wrap_shift(s.centre);
                    }
                }
            }
            assert!(found > 1000, "too few pairs to test anything: {found}");
            assert!(list.builds() < 40, "{} builds for 200 queries", list.builds());
        }
    }
}
