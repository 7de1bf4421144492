//! The particles in the sweep: the forcing their nodes add (`d_B (v_p − u)`), and the force and
//! moment the fluid exerts on them, measured by either [`ForceMethod`] and summed per body.

use super::{Lattice, SlabResult};
use crate::d3q19::{for_each_pair, moments, LANES, Q};
use crate::particles::{ParticleField, ParticleNode};

/// Force and moment one particle received from the fluid in one step (lattice units), measured
/// as [`Lattice::set_force_method`] chose.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ParticleForce {
    /// Momentum per step the particle received.
    pub force: [f64; 3],
    /// The moment about the particle's centre of mass: Σ over its nodes of the node's lever
    /// arm ([`ParticleField::motion`](crate::ParticleField::motion)) × the node's share of the
    /// force.
    pub moment: [f64; 3],
}

/// How the sweep measures the fluid's force on a particle (both in the same sweep, both
/// deterministic; the fluid itself evolves the same either way). The default is the momentum
/// exchange, the method of the HLBM papers.
///
/// With `V_R` the particle's nodes (`d_B > 0`), `ρ`, `Δu` the EDM velocity change of a node and
/// `g` the lattice's body acceleration:
///
/// * [`Forcing`](Self::Forcing): `F = −Σ_{V_R} ρ Δu` — exactly the momentum the particle gave the
///   fluid, so particle + fluid momentum is conserved to round-off. It includes what forcing the
///   fluid *inside* the particle along with it took; a coupling that wants the force on the
///   particle alone removes that inner-fluid share (as `discrete_contact::coupling` does).
/// * [`MomentumExchange`](Self::MomentumExchange): link-wise momentum exchange with Wen et al.'s
///   (2014) Galilean-invariant correction, over every link from a particle node `x` to a fluid
///   node `x + c_i` not covered by the same particle:
///   `F = Σ [ −c_i (f*_i(x) + f_ī(x) − 2 w_i) + u_p(x) (f*_i(x) − f_ī(x)) ] + Σ_{V_R} ρ g`,
///   with `f*_i(x)` leaving `x` after the collision and `f_ī(x)` arriving from `x + c_i`
///   (links inside one particle cancel and are skipped; links to walls are the wall's). The
///   `2 w_i` — the rest state's populations, which OpenLB keeps subtracted in storage — sums to
///   zero over a closed surface but not over one a wall cuts open: without it a particle
///   touching a wall would lose the lattice's whole rest pressure `ρ/3` on the cut-off part of
///   its surface and be pulled into the wall.
///   It measures the momentum that crosses the particle's outer surface, so the inner fluid is
///   not in it — up to how rigidly that fluid really moves. The last term hands the particle
///   the body force on every node it covers, as a pressure gradient would push on its surface:
///   the lattice applies `g` to every node, and on the covered ones the forcing takes it back
///   (the node is held at `u_p`), so it must reach the particle. It is the whole `ρ g`, not
///   `d_B ρ g`: weighted by `d_B`, the fluid share `1 − d_B` of the smoothing band would be
///   lost, and a periodic suspension under a balance force would gain momentum as a whole.
///
///   Wen et al.'s terms for nodes that a moving particle covers and uncovers (their fluid
///   momentum handed to or taken from the particle) are left out, as OpenLB's HLBM does: with
///   a smooth `d_B` a node joins the particle at vanishing `d_B` but would hand over its whole
///   momentum at once, so the force would jump whenever a node is covered or uncovered. The
///   price is the momentum those nodes carry: a settling particle's mean speed comes out
///   slightly above the forcing measure's (the settling tests check both).
///
///   Cost: finding the links takes a pass over the particle nodes of the rows that changed
///   since the last step and their neighbours; a covered node costs a few fluid nodes (the
///   figures are in `hlbm/PERFORMANCE.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ForceMethod {
    /// The EDM forcing's own momentum.
    Forcing,
    /// Link-wise momentum exchange (Wen et al. 2014; default).
    #[default]
    MomentumExchange,
}

/// The particle nodes of one block of the sweep: scratch that [`RowParticles`] reuses for
/// every block with particle nodes (only its `body`, `d_b`, `links` and the exchange's sums are
/// reset; lanes without a node keep `d_b = 0` and stale but finite velocities and arms, which
/// the forcing multiplies by that zero, and the forces skip).
pub(super) struct ParticleBlock {
    d_b: [f64; LANES],
    velocity: [[f64; LANES]; 3],
    arm: [[f64; LANES]; 3],
    /// Body index per lane ([`ParticleNode::body`]), `u32::MAX` where no particle covers the
    /// node.
    body: [u32; LANES],
    /// Links leaving the particle, per lane ([`ForceMethod::MomentumExchange`] only).
    links: [u32; LANES],
    /// Whether any lane has a link (a block inside a particle has none).
    linked: bool,
    /// `Σ (f_i^out − f_ī^in)` over each lane's links: times `u_p`, the moving-boundary part
    /// of the exchange ([`exchange_half`]).
    crossing: [f64; LANES],
    /// `−Σ c_i (f_i^out + f_ī^in − 2 w_i)` over each lane's links ([`exchange_half`]).
    exchange: [[f64; LANES]; 3],
}

impl ParticleBlock {
    /// A block without particle nodes.
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self {
            d_b: [0.0; LANES],
            velocity: [[0.0; LANES]; 3],
            arm: [[0.0; LANES]; 3],
            body: [u32::MAX; LANES],
            links: [0; LANES],
            linked: false,
            crossing: [0.0; LANES],
            exchange: [[0.0; LANES]; 3],
        }
    }
}

/// The particle nodes of one row as the sweep walks it block by block: the forcing they add
/// before the collision ([`RowParticles::force`]) and the forces they receive, measured after
/// it ([`RowParticles::measure`]) and summed over each run of consecutive nodes of one body (a
/// row's nodes of one particle are mostly consecutive).
pub(super) struct RowParticles<'a> {
    field: &'a ParticleField,
    nodes: &'a [ParticleNode],
    /// Per node, its links ([`ForceMethod::MomentumExchange`] only, else empty).
    links: &'a [u32],
    /// Whether the forces are measured by the momentum exchange (and the row has nodes).
    exchange: bool,
    y: usize,
    z: usize,
    /// The first node not yet taken into a block.
    next: usize,
    /// The nodes of the block being swept.
    block: &'a mut ParticleBlock,
    /// The body whose run of nodes is being summed (`u32::MAX`: none yet) and its force so
    /// far, added to the slab's map when the body changes.
    run: (u32, ParticleForce),
}

impl<'a> RowParticles<'a> {
    /// The particle nodes of row `(y, z)` of `lat`, taken into `block` block by block.
    #[inline(always)]
    pub(super) fn new(lat: &'a Lattice, y: usize, z: usize, block: &'a mut ParticleBlock) -> Self {
        let row = z * lat.ny + y;
        let nodes = lat.particles.row(row);
        let exchange = lat.force_method == ForceMethod::MomentumExchange && !nodes.is_empty();
        let links: &[u32] = if exchange { &lat.links[row] } else { &[] };
        Self {
            field: &lat.particles,
            nodes,
            links,
            exchange,
            y,
            z,
            next: 0,
            block,
            run: (u32::MAX, ParticleForce::default()),
        }
    }

    /// Whether the block of `lanes` cells from `x0` holds a particle node (the blocks are
    /// visited in order).
    #[inline(always)]
    pub(super) fn in_block(&self, x0: usize, lanes: usize) -> bool {
        self.next < self.nodes.len() && (self.nodes[self.next].x as usize) < x0 + lanes
    }

    /// Takes the particle nodes of the block from `x0` (which [`RowParticles::in_block`] found),
    /// adds their forcing `d_B (v_p − u)` to `du` and, with links, the incoming half of the
    /// exchange (before the collision overwrites `f_ī`); returns the block's density and
    /// velocity `blk` holds before forcing.
    #[inline(always)]
    pub(super) fn force(
        &mut self,
        x0: usize,
        lanes: usize,
        blk: &[[f64; LANES]; Q],
        du: &mut [[f64; LANES]; 3],
    ) -> ([f64; LANES], [[f64; LANES]; 3]) {
        let b = &mut *self.block;
        b.body = [u32::MAX; LANES];
        b.d_b = [0.0; LANES];
        b.links = [0; LANES];
        b.crossing = [0.0; LANES];
        b.exchange = [[0.0; LANES]; 3];
        while self.next < self.nodes.len() && (self.nodes[self.next].x as usize) < x0 + lanes {
            let p = &self.nodes[self.next];
            let l = p.x as usize - x0;
            b.d_b[l] = p.d_b;
            let (_, arm, velocity) = self.field.motion(p, self.y, self.z);
            for d in 0..3 {
                b.velocity[d][l] = velocity[d];
                b.arm[d][l] = arm[d];
            }
            b.body[l] = p.body() as u32;
            if self.exchange {
                b.links[l] = self.links[self.next];
            }
            self.next += 1;
        }
        b.linked = b.links != [0; LANES];
        let (rho, u) = moments(blk);
        // Over all lanes as vector code (zero where no node): a per-lane loop with a branch,
        // writing `du` lane by lane before `collide` reads it as vectors, cost 4–8 % of the
        // forcing sweep (`lbm_profile`, one thread).
        for d in 0..3 {
            for l in 0..LANES {
                du[d][l] += b.d_b[l] * (b.velocity[d][l] - u[d][l]);
            }
        }
        if b.linked {
            // The incoming half, before the collision overwrites `f_ī`.
            exchange_half::<true>(blk, &b.links, &mut b.crossing, &mut b.exchange);
        }
        (rho, u)
    }

    /// After the collision of the block [`RowParticles::force`] took (`lanes` cells, collided
    /// populations `blk`, density `rho`, velocity change `du`, body acceleration `g`): each
    /// node's force — the exchange over its links plus its body force, or the forcing's
    /// momentum — and moment, added to its body's run.
    #[inline(always)]
    pub(super) fn measure(
        &mut self,
        blk: &[[f64; LANES]; Q],
        lanes: usize,
        rho: &[f64; LANES],
        du: &[[f64; LANES]; 3],
        g: [f64; 3],
        res: &mut SlabResult,
    ) {
        if self.block.linked {
            let b = &mut *self.block;
            exchange_half::<false>(blk, &b.links, &mut b.crossing, &mut b.exchange);
        }
        let b = &*self.block;
        for l in 0..lanes {
            if b.body[l] == u32::MAX {
                continue;
            }
            let fp = if self.exchange {
                // The exchange over the node's links, and the body force on the node (all of
                // it: the forcing holds the node at `u_p`).
                [0, 1, 2]
                    .map(|d| b.exchange[d][l] + b.velocity[d][l] * b.crossing[l] + rho[l] * g[d])
            } else {
                [0, 1, 2].map(|d| -rho[l] * (du[d][l] - g[d]))
            };
            if b.body[l] != self.run.0 {
                flush(res, &self.run);
                self.run = (b.body[l], ParticleForce::default());
            }
            let m = cross([b.arm[0][l], b.arm[1][l], b.arm[2][l]], fp);
            for d in 0..3 {
                self.run.1.force[d] += fp[d];
                self.run.1.moment[d] += m[d];
            }
        }
    }

    /// Adds the row's last run to `res`.
    #[inline(always)]
    pub(super) fn finish(&self, res: &mut SlabResult) {
        flush(res, &self.run);
    }
}

/// Adds the force of a run of one body's nodes to the slab's map.
#[inline(always)]
fn flush(res: &mut SlabResult, run: &(u32, ParticleForce)) {
    if run.0 != u32::MAX {
        let e = res.forces.entry(run.0).or_default();
        for d in 0..3 {
            e.force[d] += run.1.force[d];
            e.moment[d] += run.1.moment[d];
        }
    }
}

/// One half of the link-wise momentum exchange (Wen et al. 2014) of a block, over every lane
/// at once: for each direction `i` set in a lane's `links`, the population crossing that link
/// — `f_ī` before the collision (`INCOMING`), `f_i` after it — is subtracted from (incoming)
/// or added to (outgoing) `crossing`, and `c_i (f − w_i)` subtracted from `exchange`. The
/// force on the node is then `exchange + u_p crossing`:
/// `Σ_links [u_p (f_i^out − f_ī^in) − c_i (f_i^out − w_i) − c_i (f_ī^in − w_i)]`.
///
/// Per direction a masked vector select over the block (a lane-by-lane walk over each node's
/// link bits mispredicts a branch per link), the selected terms then added pairwise:
/// accumulated direction after direction, the four sums would be chains of 18 and 10
/// dependent adds, each waiting on the last.
#[inline(always)]
fn exchange_half<const INCOMING: bool>(
    blk: &[[f64; LANES]; Q],
    links: &[u32; LANES],
    crossing: &mut [f64; LANES],
    exchange: &mut [[f64; LANES]; 3],
) {
    // Per moving direction i: the population crossing where i is a link, else 0; and (the
    // incoming half only, for both) 2 w_i where i is a link. One select per loop: so each
    // stays a masked vector move.
    let mut f = [[0.0; LANES]; Q];
    let mut w = [[0.0; LANES]; Q];
    macro_rules! pair {
        ($i:expr, $j:expr, $cx:expr, $cy:expr, $cz:expr, $w:expr) => {
            // Direction i reads f_ī = f_j before the collision and f_i after; j the reverse.
            let (pi, pj) = if INCOMING { (&blk[$j], &blk[$i]) } else { (&blk[$i], &blk[$j]) };
            for l in 0..LANES {
                f[$i][l] = if (links[l] >> $i) & 1 != 0 { pi[l] } else { 0.0 };
            }
            for l in 0..LANES {
                f[$j][l] = if (links[l] >> $j) & 1 != 0 { pj[l] } else { 0.0 };
            }
            if INCOMING {
                for l in 0..LANES {
                    w[$i][l] = if (links[l] >> $i) & 1 != 0 { 2.0 * $w } else { 0.0 };
                }
                for l in 0..LANES {
                    w[$j][l] = if (links[l] >> $j) & 1 != 0 { 2.0 * $w } else { 0.0 };
                }
            }
        };
    }
    for_each_pair!(pair);
    // Added pairwise. The exchange by pairs (i, ī), as `c_i (g_i − g_ī)` with `g = f − w`:
    // c_i of pairs 1–9 is x, y, z, (1,1,0), (1,−1,0), (1,0,1), (1,0,−1), (0,1,1), (0,1,−1).
    for l in 0..LANES {
        let g = |i: usize| f[i][l] - w[i][l];
        let d = |k: usize| g(k) - g(k + 9);
        let total = (((f[1][l] + f[10][l]) + (f[2][l] + f[11][l]))
            + ((f[3][l] + f[12][l]) + (f[4][l] + f[13][l])))
            + (((f[5][l] + f[14][l]) + (f[6][l] + f[15][l]))
                + ((f[7][l] + f[16][l]) + (f[8][l] + f[17][l])))
            + (f[9][l] + f[18][l]);
        crossing[l] += if INCOMING { -total } else { total };
        exchange[0][l] -= ((d(1) + d(4)) + (d(5) + d(6))) + d(7);
        exchange[1][l] -= ((d(2) + d(4)) - d(5)) + (d(8) + d(9));
        exchange[2][l] -= ((d(3) + d(6)) - d(7)) + (d(8) - d(9));
    }
}

#[inline]
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::d3q19::{C, OPP, W};

    /// Both halves of the vectorised exchange against its definition, link by link: per lane
    /// `F = Σ_links [u_p (f_i^out − f_ī^in) − c_i (f_i^out − w_i) − c_i (f_ī^in − w_i)]`, for
    /// random populations, velocities and link masks (every direction, none, all).
    #[test]
    fn the_block_exchange_is_the_sum_over_each_nodes_links() {
        let mut seed = 99u64;
        let mut rand = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for round in 0..50 {
            let before: [[f64; LANES]; Q] =
                std::array::from_fn(|_| std::array::from_fn(|_| rand()));
            let after: [[f64; LANES]; Q] = std::array::from_fn(|_| std::array::from_fn(|_| rand()));
            let velocity: [[f64; 3]; LANES] =
                std::array::from_fn(|_| std::array::from_fn(|_| rand() - 0.5));
            let links: [u32; LANES] = std::array::from_fn(|l| match (round, l) {
                (0, _) => 0,
                (1, _) => (1 << Q) - 2,
                _ => (rand() * (1 << Q) as f64) as u32 & !1,
            });
            let (mut crossing, mut exchange) = ([0.0; LANES], [[0.0; LANES]; 3]);
            exchange_half::<true>(&before, &links, &mut crossing, &mut exchange);
            exchange_half::<false>(&after, &links, &mut crossing, &mut exchange);
            for l in 0..LANES {
                let mut expected = [0.0; 3];
                for i in (1..Q).filter(|&i| links[l] >> i & 1 != 0) {
                    let (out, inc) = (after[i][l], before[OPP[i]][l]);
                    for d in 0..3 {
                        expected[d] += velocity[l][d] * (out - inc)
                            - C[i][d] as f64 * (out - W[i] + inc - W[i]);
                    }
                }
                for d in 0..3 {
                    let got = exchange[d][l] + velocity[l][d] * crossing[l];
                    assert!(
                        (got - expected[d]).abs() < 1e-12,
                        "round {round} lane {l} axis {d}: {got} vs {expected:?}"
                    );
                }
            }
        }
    }
}
