//! The per-node particle field of HLBM: which nodes a particle covers, how much (`d_B`), and
//! the particle's velocity there. Stored per row and sparse, so fluid-only rows pay nothing.

use crate::error::{Error, Result};

/// One node covered by a particle.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ParticleNode {
    /// `x` index of the node in its row.
    pub x: u32,
    /// Solid fraction `d_B` in `(0, 1]`.
    pub d_b: f64,
    /// Particle velocity at the node, `v + ω × (x - x_cm)` (lattice units).
    pub velocity: [f64; 3],
    /// Lever arm: the node's position minus the particle's centre of mass (lattice units),
    /// taken on the particle's side of a periodic face, so the moment is right for a particle
    /// that straddles one.
    pub arm: [f64; 3],
    /// Particle id (reported back with its force), below `u32::MAX - 1` (the two largest
    /// values mark "no particle" and walls inside the lattice).
    pub id: u32,
}

/// Particle nodes of every row, sorted by `x`.
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ParticleField {
    rows: Vec<Vec<ParticleNode>>,
    nx: usize,
    ny: usize,
    count: usize,
}

impl ParticleField {
    /// An empty field for an `nx × ny × nz` lattice.
    pub fn new(nx: usize, ny: usize, nz: usize) -> Self {
        Self { rows: vec![Vec::new(); ny * nz], nx, ny, count: 0 }
    }

    /// Removes every particle node (keeps the memory).
    pub fn clear(&mut self) {
        for r in &mut self.rows {
            r.clear();
        }
        self.count = 0;
    }

    /// Adds (or, for two particles on one node, superposes) node `(x, y, z)` of particle `id`
    /// with solid fraction `d_b`, particle velocity `velocity` there and lever arm `arm` (node
    /// minus centre of mass), all in lattice units.
    ///
    /// Nodes must be added with `d_b > 0`; a node already covered keeps the larger `d_B` and the
    /// `d_B`-weighted velocity, and reports its force to the particle with the larger `d_B`.
    #[allow(clippy::too_many_arguments)]
    pub fn add(&mut self, x: usize, y: usize, z: usize, d_b: f64, velocity: [f64; 3], arm: [f64; 3], id: u32) {
        debug_assert!(x < self.nx);
        let row = &mut self.rows[z * self.ny + y];
        let node = ParticleNode { x: x as u32, d_b, velocity, arm, id };
        match row.binary_search_by_key(&(x as u32), |n| n.x) {
            Ok(i) => superpose(&mut row[i], &node),
            Err(i) => {
                row.insert(i, node);
                self.count += 1;
            }
        }
    }

    /// Adds a sphere of `radius` about `centre` with smoothing width `smoothing`, translating
    /// with `velocity`, as particle `id` (lattice units): every node where its `d_B`
    /// ([`solid_fraction`]) is positive, with the lever arm node − centre. The centre may lie
    /// anywhere; node indices wrap periodically (a wall node is covered like any other — leave
    /// the walls out of its reach).
    ///
    /// Refuses, naming the parameter, a radius or smoothing width that is not finite and
    /// positive, a non-finite centre or velocity, and a sphere whose reach `2 (radius +
    /// smoothing/2)` is not below every dimension of the lattice (it would cover nodes twice).
    pub fn add_sphere(&mut self, centre: [f64; 3], radius: f64, smoothing: f64, velocity: [f64; 3], id: u32) -> Result<()> {
        let bad = |name, value, allowed| Err(Error::InvalidParameter { name, value, allowed });
        let dims = [self.nx, self.ny, self.rows.len() / self.ny];
        if !(radius > 0.0 && radius.is_finite()) {
            return bad("radius", radius, "0 < radius (finite)");
        }
        if !(smoothing > 0.0 && smoothing.is_finite()) {
            return bad("smoothing", smoothing, "0 < smoothing (finite)");
        }
        if let Some(&c) = centre.iter().find(|c| !c.is_finite()) {
            return bad("centre", c, "finite coordinates");
        }
        if let Some(&v) = velocity.iter().find(|v| !v.is_finite()) {
            return bad("velocity", v, "finite components");
        }
        let reach = radius + 0.5 * smoothing;
        if dims.iter().any(|&n| 2.0 * reach >= n as f64) {
            return bad("radius", radius, "2 (radius + smoothing/2) below every lattice dimension");
        }
        let (lo, hi) = (centre.map(|c| (c - reach).floor() as i64), centre.map(|c| (c + reach).ceil() as i64));
        let wrap = |i: i64, d: usize| i.rem_euclid(dims[d] as i64) as usize;
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let arm = [x as f64 - centre[0], y as f64 - centre[1], z as f64 - centre[2]];
                    let d_b = solid_fraction((arm[0] * arm[0] + arm[1] * arm[1] + arm[2] * arm[2]).sqrt() - radius, smoothing);
                    if d_b > 0.0 {
                        self.add(wrap(x, 0), wrap(y, 1), wrap(z, 2), d_b, velocity, arm, id);
                    }
                }
            }
        }
        Ok(())
    }

    /// Refills the whole field slab by slab, on all cores: `fill(z, push)` calls
    /// `push(y, node)` for the nodes of slab `z`, in any order; every row is then sorted by `x`,
    /// and nodes pushed twice are superposed as [`add`](Self::add) does, in the order pushed —
    /// so the field does not depend on the thread count. Returns what each `fill` returned, in
    /// slab order.
    pub fn fill_slabs<R: Send>(&mut self, fill: impl Fn(usize, &mut dyn FnMut(usize, ParticleNode)) -> R + Sync) -> Vec<R> {
        use rayon::prelude::*;
        let ny = self.ny;
        let results: Vec<(R, usize)> = self
            .rows
            .par_chunks_mut(ny)
            .enumerate()
            .map(|(z, slab)| {
                for row in slab.iter_mut() {
                    row.clear();
                }
                let r = fill(z, &mut |y, node| slab[y].push(node));
                let mut count = 0;
                for row in slab.iter_mut() {
                    // Most rows come in order, each node once: one pass tells.
                    if !row.is_sorted_by(|a, b| a.x < b.x) {
                        row.sort_by_key(|n| n.x);
                        row.dedup_by(|later, kept| later.x == kept.x && {
                            superpose(kept, later);
                            true
                        });
                    }
                    count += row.len();
                }
                (r, count)
            })
            .collect();
        self.count = results.iter().map(|r| r.1).sum();
        results.into_iter().map(|r| r.0).collect()
    }

    /// The nodes of row `row = z * ny + y`, sorted by `x`.
    pub fn row(&self, row: usize) -> &[ParticleNode] {
        &self.rows[row]
    }

    /// Number of rows (`ny * nz`).
    pub fn rows(&self) -> usize {
        self.rows.len()
    }

    /// Number of particle nodes.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether no node is covered.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

/// Two particles on one node: the larger `d_B` is kept with its particle's id and lever arm
/// (the force goes to that particle), the velocity is the `d_B`-weighted mean.
fn superpose(kept: &mut ParticleNode, later: &ParticleNode) {
    let w = kept.d_b + later.d_b;
    kept.velocity = [0, 1, 2].map(|d| (kept.velocity[d] * kept.d_b + later.velocity[d] * later.d_b) / w);
    if later.d_b > kept.d_b {
        (kept.d_b, kept.arm, kept.id) = (later.d_b, later.arm, later.id);
    }
}

/// `d_B` of a node at signed distance `d` from a particle's surface with smoothing width `eps`:
/// 1 for `d <= -eps/2`, `cos²(π/2 (d/eps + 1/2))` in between (½ on the surface), 0 for
/// `d >= eps/2`.
///
/// Seed 000 eq. (18) prints `cos²(π (d/eps + 1/2))`, which is not monotone across the band
/// (1, then 0 on the surface, back to nearly 1 just before `+eps/2`, then 0); the factor ½
/// here is the one OpenLB's HLBM uses and the one that makes `d_B` fall smoothly from 1 to 0.
pub fn solid_fraction(d: f64, eps: f64) -> f64 {
    if d <= -0.5 * eps {
        1.0
    } else if d >= 0.5 * eps {
        0.0
    } else {
        (std::f64::consts::FRAC_PI_2 * (d / eps + 0.5)).cos().powi(2)
    }
}
