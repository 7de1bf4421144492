//! The per-node particle field of HLBM: which nodes a particle covers, how much (`d_B`), and
//! the particle's velocity there — from its rigid motion, stored once per particle
//! ([`ParticleBody`]). Stored per row and sparse, so fluid-only rows pay nothing.

use crate::error::{Error, Result};

/// One node covered by a particle: 16 bytes. The particle's rigid motion is stored once, in
/// the field's [`ParticleBody`] table; the node keeps which body it belongs to and on which
/// periodic image of the lattice that body sees it (so a body straddling a periodic face gets
/// the right lever arm on both sides).
/// Kept small (16 bytes) because the mapping writes and the sweep and the links read every
/// node each step: velocities and lever arms are looked up per body, not stored per node.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ParticleNode {
    /// `x` index of the node in its row.
    pub x: u32,
    /// The body's index in the field's table (low 26 bits) and the image (2 bits per axis).
    body: u32,
    /// Solid fraction `d_B` in `(0, 1]`.
    pub d_b: f64,
}

/// Bits of [`ParticleNode`]'s body index; the six above hold the periodic image.
const BODY_BITS: u32 = 26;
/// Most bodies a field holds.
pub const MAX_BODIES: usize = 1 << BODY_BITS;

impl ParticleNode {
    /// Node `x` of its row, covered by body `body` (an index into the field's body table, below
    /// [`MAX_BODIES`]) with solid fraction `d_b`; `image` (each −1, 0 or 1) is the periodic
    /// image on which the body sees the node: its unwrapped position is `(x, y, z) + image ×
    /// (nx, ny, nz)`.
    #[inline]
    pub fn new(x: usize, body: usize, image: [i8; 3], d_b: f64) -> Self {
        debug_assert!(body < MAX_BODIES && image.iter().all(|i| (-1..=1).contains(i)));
        let bits =
            image.iter().enumerate().fold(0u32, |acc, (d, &i)| acc | (((i + 1) as u32) << (2 * d)));
        Self { x: x as u32, body: body as u32 | bits << BODY_BITS, d_b }
    }

    /// The index of the node's body in [`ParticleField::bodies`].
    #[inline]
    pub fn body(&self) -> usize {
        (self.body & (MAX_BODIES as u32 - 1)) as usize
    }

    /// The periodic image on which the body sees the node (each −1, 0 or 1).
    #[inline]
    pub fn image(&self) -> [i8; 3] {
        [0, 1, 2].map(|d| ((self.body >> (BODY_BITS + 2 * d)) & 3) as i8 - 1)
    }
}

/// A particle's rigid motion, in lattice units: the velocity of a node it covers is
/// `velocity + spin × (node − centre)`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ParticleBody {
    /// Id reported back with the particle's force; any value, one body per id.
    pub id: u32,
    /// Centre of mass, in node coordinates (node `(i, j, k)` lies at `(i, j, k)`).
    pub centre: [f64; 3],
    /// Velocity of the centre of mass (lattice units).
    pub velocity: [f64; 3],
    /// Angular velocity (radians per time step).
    pub spin: [f64; 3],
}

impl ParticleBody {
    /// Velocity at lever arm `arm` (node − centre): `velocity + spin × arm`.
    #[inline(always)]
    pub fn velocity_at(&self, arm: [f64; 3]) -> [f64; 3] {
        let (w, v) = (self.spin, self.velocity);
        [
            v[0] + w[1] * arm[2] - w[2] * arm[1],
            v[1] + w[2] * arm[0] - w[0] * arm[2],
            v[2] + w[0] * arm[1] - w[1] * arm[0],
        ]
    }
}

/// Particle nodes of every row, sorted by `x`, and the bodies they belong to.
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ParticleField {
    rows: Vec<Vec<ParticleNode>>,
    bodies: Vec<ParticleBody>,
    nx: usize,
    ny: usize,
    nz: usize,
    count: usize,
}

impl ParticleField {
    /// An empty field for an `nx × ny × nz` lattice.
    pub fn new(nx: usize, ny: usize, nz: usize) -> Self {
        Self { rows: vec![Vec::new(); ny * nz], bodies: Vec::new(), nx, ny, nz, count: 0 }
    }

    /// The lattice's dimensions `[nx, ny, nz]`.
    fn dims(&self) -> [usize; 3] {
        [self.nx, self.ny, self.nz]
    }

    /// Removes every particle node and body (keeps the memory).
    pub fn clear(&mut self) {
        for r in &mut self.rows {
            r.clear();
        }
        self.bodies.clear();
        self.count = 0;
    }

    /// Adds a body with id `id`, centre of mass `centre` (node coordinates; anywhere),
    /// `velocity` and `spin` (lattice units); returns its index for [`add`](Self::add).
    /// Refuses non-finite values and more than [`MAX_BODIES`] bodies, naming the parameter.
    pub fn add_body(
        &mut self,
        id: u32,
        centre: [f64; 3],
        velocity: [f64; 3],
        spin: [f64; 3],
    ) -> Result<usize> {
        let bad = |name, value, allowed| Err(Error::InvalidParameter { name, value, allowed });
        for (name, v) in [("centre", centre), ("velocity", velocity), ("spin", spin)] {
            if let Some(&c) = v.iter().find(|c| !c.is_finite()) {
                return bad(name, c, "finite components");
            }
        }
        if self.bodies.len() >= MAX_BODIES {
            return bad(
                "bodies",
                self.bodies.len() as f64,
                "at most hlbm::particles::MAX_BODIES bodies in a field",
            );
        }
        self.bodies.push(ParticleBody { id, centre, velocity, spin });
        Ok(self.bodies.len() - 1)
    }

    /// Covers node `node` — unwrapped node coordinates, within one lattice length of the
    /// lattice on every axis — by body `body` (from [`add_body`](Self::add_body)) with solid
    /// fraction `0 < d_b <= 1`. The node is wrapped into the lattice; its lever arm stays
    /// `node − centre`. Refuses, naming it, a parameter out of these ranges.
    ///
    /// A node already covered keeps the larger `d_B` with its body (velocity, lever arm and
    /// force).
    pub fn add(&mut self, body: usize, node: [i64; 3], d_b: f64) -> Result<()> {
        let dims = self.dims();
        if body >= self.bodies.len() {
            return Err(Error::InvalidParameter {
                name: "body",
                value: body as f64,
                allowed: "an index returned by add_body",
            });
        }
        if !(d_b > 0.0 && d_b <= 1.0) {
            return Err(Error::InvalidParameter {
                name: "d_b",
                value: d_b,
                allowed: "0 < d_b <= 1",
            });
        }
        let mut at = [0usize; 3];
        let mut image = [0i8; 3];
        for d in 0..3 {
            let n = dims[d] as i64;
            if !(-n..2 * n).contains(&node[d]) {
                return Err(Error::InvalidParameter {
                    name: "node",
                    value: node[d] as f64,
                    allowed: "-n <= coordinate < 2n (within one lattice length)",
                });
            }
            image[d] = node[d].div_euclid(n) as i8;
            at[d] = node[d].rem_euclid(n) as usize;
        }
        let row = &mut self.rows[at[2] * self.ny + at[1]];
        let new = ParticleNode::new(at[0], body, image, d_b);
        match row.binary_search_by_key(&(at[0] as u32), |n| n.x) {
            Ok(i) => superpose(&mut row[i], &new),
            Err(i) => {
                row.insert(i, new);
                self.count += 1;
            }
        }
        Ok(())
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
    pub fn add_sphere(
        &mut self,
        centre: [f64; 3],
        radius: f64,
        smoothing: f64,
        velocity: [f64; 3],
        id: u32,
    ) -> Result<()> {
        let bad = |name, value, allowed| Err(Error::InvalidParameter { name, value, allowed });
        let dims = self.dims();
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
        // The centre wrapped into the lattice: the nodes then lie within one length of it.
        let centre = [0, 1, 2].map(|d| centre[d].rem_euclid(dims[d] as f64));
        let body = self.add_body(id, centre, velocity, [0.0; 3])?;
        let (lo, hi) =
            (centre.map(|c| (c - reach).floor() as i64), centre.map(|c| (c + reach).ceil() as i64));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let arm = [x as f64 - centre[0], y as f64 - centre[1], z as f64 - centre[2]];
                    let d_b = solid_fraction(
                        (arm[0] * arm[0] + arm[1] * arm[1] + arm[2] * arm[2]).sqrt() - radius,
                        smoothing,
                    );
                    if d_b > 0.0 {
                        self.add(body, [x, y, z], d_b)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// Refills the whole field slab by slab, on all cores, with the bodies `bodies` (their
    /// indices are the nodes' [`ParticleNode::body`]): `fill(z, rows)` calls
    /// [`rows.push(y, node)`](SlabRows::push) for the nodes of slab `z`, in any order; every
    /// row is then sorted by `x`, and nodes pushed twice are superposed as [`add`](Self::add)
    /// does, in the order pushed — so the field does not depend on the thread count. Returns
    /// what each `fill` returned, in slab order.
    ///
    /// Refuses, naming it, a body with a non-finite centre, velocity or spin, and more than
    /// [`MAX_BODIES`] bodies (the field is left empty).
    pub fn fill_slabs<R: Send>(
        &mut self,
        bodies: Vec<ParticleBody>,
        fill: impl Fn(usize, &mut SlabRows) -> R + Sync,
    ) -> Result<Vec<R>> {
        use rayon::prelude::*;
        // The rows are cleared slab by slab below; only a refused body clears them here.
        self.bodies.clear();
        self.count = 0;
        for b in &bodies {
            if let Err(e) = self.add_body(b.id, b.centre, b.velocity, b.spin) {
                self.clear();
                return Err(e);
            }
        }
        let ny = self.ny;
        let results: Vec<(R, usize)> = self
            .rows
            .par_chunks_mut(ny)
            .enumerate()
            .map(|(z, slab)| {
                for row in slab.iter_mut() {
                    row.clear();
                }
                let r = fill(z, &mut SlabRows(slab));
                let mut count = 0;
                for row in slab.iter_mut() {
                    // Most rows come in order, each node once: one pass tells.
                    if !row.is_sorted_by(|a, b| a.x < b.x) {
                        row.sort_by_key(|n| n.x);
                        row.dedup_by(|later, kept| {
                            later.x == kept.x && {
                                superpose(kept, later);
                                true
                            }
                        });
                    }
                    count += row.len();
                }
                (r, count)
            })
            .collect();
        self.count = results.iter().map(|r| r.1).sum();
        Ok(results.into_iter().map(|r| r.0).collect())
    }

    /// The nodes of row `row = z * ny + y`, sorted by `x`.
    pub fn row(&self, row: usize) -> &[ParticleNode] {
        &self.rows[row]
    }

    /// The bodies, indexed by [`ParticleNode::body`].
    pub fn bodies(&self) -> &[ParticleBody] {
        &self.bodies
    }

    /// The body covering `node` of row `(y, z)`, the node's lever arm (node − centre, on the
    /// body's side of a periodic face) and its velocity there (lattice units).
    #[inline(always)]
    pub fn motion(
        &self,
        node: &ParticleNode,
        y: usize,
        z: usize,
    ) -> (&ParticleBody, [f64; 3], [f64; 3]) {
        let b = &self.bodies[node.body()];
        let image = node.image();
        let dims = self.dims();
        let at = [node.x as usize, y, z];
        let arm = [0, 1, 2]
            .map(|d| (at[d] as i64 + image[d] as i64 * dims[d] as i64) as f64 - b.centre[d]);
        (b, arm, b.velocity_at(arm))
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

/// The rows of one z-slab of a [`ParticleField`] that [`ParticleField::fill_slabs`] is
/// filling. (A concrete type rather than a `dyn FnMut`: a call through a pointer per node was
/// the mapping's every push.)
pub struct SlabRows<'a>(&'a mut [Vec<ParticleNode>]);

impl SlabRows<'_> {
    /// Adds `node` to row `y` of the slab.
    #[inline(always)]
    pub fn push(&mut self, y: usize, node: ParticleNode) {
        self.0[y].push(node);
    }
}

/// Two particles on one node: the larger `d_B` is kept with its body — the node moves with
/// that particle and its force goes to it. (With a node's velocity stored per node it was the
/// `d_B`-weighted mean of both; nodes are shared only where two smoothing bands overlap, in a
/// contact.)
fn superpose(kept: &mut ParticleNode, later: &ParticleNode) {
    if later.d_b > kept.d_b {
        *kept = ParticleNode { x: kept.x, ..*later };
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
