//! The lattice: storage, boundaries and the fused stream–collide sweep (A-A pattern).
//!
//! **Layout.** Structure of arrays: `f[i * n + cell]`, `cell = (z * ny + y) * nx + x`, so each
//! population is contiguous along `x` and a block of [`LANES`] cells loads as one vector.
//!
//! **A-A pattern** (Bailey et al. 2009): one array, updated in place. Even steps read the 19
//! populations of a cell from its own slots and write the post-collision values back swapped
//! (`f*_i` into slot `ī`). Odd steps pull `f_i` from slot `ī` of `x - c_i` and push `f*_i`
//! into slot `i` of `x + c_i`. Every cell reads and writes only its own 19 locations, so a sweep
//! needs no second lattice (304 B of traffic per cell update, no write-allocate; 152 B with
//! [`Storage::F32`]) and cells can be processed in any order or in parallel with identical
//! results.
//!
//! **Walls** are solid nodes (halfway bounce-back, optionally moving): in odd steps a
//! population that would come from or go to a solid node is taken from or put into the cell's
//! own opposite slot. Only rows next to a solid node take this slower path.
//!
//! **Periodic** boundaries are index wrap-around; a non-periodic axis must be closed by solid
//! layers, which [`Lattice::check_closed`] verifies.
//!
//! **Code.** This file holds the [`Lattice`] itself (construction, settings, `step`); the rest
//! is one concept per file: `storage` (how populations are stored and read), `walls` (solid
//! nodes), `sweep` (the fused stream–collide sweep, block by block), `stream` (where a block's
//! populations are read from and written to), `forces` (the particles' forcing and force
//! measures), `links` (finding the links the momentum exchange needs), `totals` (mass and
//! momentum reductions) and `simd` (the runtime instruction-set dispatch).

use std::collections::BTreeMap;

use crate::d3q19::{LANES, Q, W};
use crate::error::{Error, Result};
use crate::particles::ParticleField;

mod forces;
mod links;
mod simd;
mod storage;
mod stream;
mod sweep;
mod totals;
mod walls;

pub use forces::{ForceMethod, ParticleForce};
pub use simd::{simd_level, SimdLevel};
pub use storage::Storage;
pub use walls::NodeKind;

use storage::{population_stride, Lines};

/// What one step reports.
#[derive(Clone, Debug, Default)]
pub struct StepReport {
    /// Largest `|u|` of any fluid node (lattice units).
    pub max_velocity: f64,
    /// Hydrodynamic force per particle id, in id order.
    pub particle_forces: BTreeMap<u32, ParticleForce>,
}

/// Density and velocity fields written during a sweep when asked for.
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Macroscopic {
    /// Density per cell.
    pub rho: Vec<f64>,
    /// Velocity per cell (`u + Δu/2`, the physical velocity of the forcing scheme).
    pub u: Vec<[f64; 3]>,
}

/// A D3Q19 BGK lattice with HLBM particle forcing.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Lattice {
    nx: usize,
    ny: usize,
    nz: usize,
    /// Distance between two populations' arrays in `f` (cells, see [`population_stride`]).
    stride: usize,
    f: Lines,
    storage: Storage,
    omega: f64,
    kind: Vec<NodeKind>,
    wall_velocity: Vec<[f64; 3]>,
    /// Per block of `LANES` cells: a solid node lies within one cell (3×3 neighbouring rows).
    slow_block: Vec<bool>,
    body_acceleration: [f64; 3],
    time: u64,
    /// Particle nodes; filled by the coupling before each step (also reachable through
    /// [`Lattice::particles`] and [`Lattice::particles_mut`]).
    particles: ParticleField,
    velocity_limit: f64,
    macros: Option<Macroscopic>,
    force_method: ForceMethod,
    /// Per particle node (rows as in [`ParticleField`]): bit `i` set when the link to
    /// `x + c_i` leaves the particle ([`ForceMethod::MomentumExchange`] only; each step, rows
    /// whose neighbourhood changed are rebuilt).
    #[cfg_attr(feature = "serde", serde(skip))]
    links: Vec<Vec<u32>>,
    /// [`Lattice::find_links`]'s owner field (body index + 1 per node,
    /// [`WALL_OWNER`](links::WALL_OWNER) on walls, 0 elsewhere; empty until first needed and
    /// after the walls change) and the `(x, body index)` of the nodes it has set, per row (to
    /// see what changed, and clear it).
    #[cfg_attr(feature = "serde", serde(skip))]
    owner: Vec<u32>,
    #[cfg_attr(feature = "serde", serde(skip))]
    owned: Vec<Vec<(u32, u32)>>,
    /// Per row: whether its nodes changed in the last [`Lattice::find_links`].
    #[cfg_attr(feature = "serde", serde(skip))]
    changed: Vec<bool>,
    /// [`Lattice::has_solid`], once scanned (reset by [`Lattice::set_solid`]): the coupling
    /// asks every step, and the scan reads every node's kind.
    #[cfg_attr(feature = "serde", serde(skip))]
    any_solid: std::sync::OnceLock<bool>,
}

/// One z-slab's share of a sweep, reduced in slab order (deterministic for any thread count).
#[derive(Default)]
struct SlabResult {
    /// Largest `|u|²` of the slab's fluid nodes.
    max_u2: f64,
    /// The first node whose velocity is NaN or over the limit, and that velocity.
    bad: Option<(usize, f64)>,
    /// Per body index (the step reports them by the bodies' ids).
    forces: BTreeMap<u32, ParticleForce>,
}

impl Lattice {
    /// A periodic `nx × ny × nz` lattice at rest with density 1 and relaxation time `tau > 0.5`.
    pub fn new(nx: usize, ny: usize, nz: usize, tau: f64) -> Result<Self> {
        if !(tau > 0.5 && tau.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "tau",
                value: tau,
                allowed: "tau > 0.5 (finite)",
            });
        }
        for (name, v) in [("nx", nx), ("ny", ny), ("nz", nz)] {
            if v == 0 || v > 1 << 20 {
                return Err(Error::InvalidParameter {
                    name,
                    value: v as f64,
                    allowed: "1 <= n <= 2^20",
                });
            }
        }
        let n = nx * ny * nz;
        let stride = population_stride(n, Storage::F64.bytes());
        let mut f = Lines::new::<f64>(Q * stride);
        for i in 0..Q {
            f.as_mut_slice::<f64>()[i * stride..i * stride + n].fill(W[i]);
        }
        Ok(Self {
            nx,
            ny,
            nz,
            stride,
            f,
            storage: Storage::F64,
            omega: 1.0 / tau,
            kind: vec![0; n],
            // Kind 0: fluid; kind 1: the resting wall.
            wall_velocity: vec![[0.0; 3], [0.0; 3]],
            slow_block: vec![false; ny * nz * nx.div_ceil(LANES)],
            body_acceleration: [0.0; 3],
            time: 0,
            particles: ParticleField::new(nx, ny, nz),
            velocity_limit: 0.5,
            macros: None,
            force_method: ForceMethod::default(),
            links: Vec::new(),
            owner: Vec::new(),
            owned: Vec::new(),
            changed: Vec::new(),
            any_solid: std::sync::OnceLock::new(),
        })
    }

    /// Lattice size.
    pub fn dims(&self) -> [usize; 3] {
        [self.nx, self.ny, self.nz]
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.nx * self.ny * self.nz
    }

    /// Steps done.
    pub fn time(&self) -> u64 {
        self.time
    }

    /// Relaxation time.
    pub fn tau(&self) -> f64 {
        1.0 / self.omega
    }

    /// Index of cell `(x, y, z)`.
    #[inline]
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.ny + y) * self.nx + x
    }

    /// A body acceleration (lattice units) on every fluid node: gravity, a pressure gradient or
    /// a balance force.
    pub fn set_body_acceleration(&mut self, a: [f64; 3]) {
        self.body_acceleration = a;
    }

    /// The largest `|u|` (lattice units) a step accepts before reporting [`Error::Unstable`].
    pub fn set_velocity_limit(&mut self, limit: f64) {
        self.velocity_limit = limit;
    }

    /// How the next steps measure the particles' forces (default
    /// [`ForceMethod::MomentumExchange`]).
    pub fn set_force_method(&mut self, method: ForceMethod) {
        self.force_method = method;
    }

    /// How the particles' forces are measured.
    pub fn force_method(&self) -> ForceMethod {
        self.force_method
    }

    /// The particle nodes the next step forces the fluid with and measures the forces on.
    pub fn particles(&self) -> &ParticleField {
        &self.particles
    }

    /// The particle nodes, to be mapped (cleared and filled) before the next step.
    pub fn particles_mut(&mut self) -> &mut ParticleField {
        &mut self.particles
    }

    /// Asks the next sweeps to store density and velocity (read them with [`Lattice::macroscopic`]).
    pub fn store_macroscopic(&mut self, on: bool) {
        self.macros = on
            .then(|| Macroscopic { rho: vec![1.0; self.cells()], u: vec![[0.0; 3]; self.cells()] });
    }

    /// Density and velocity of the last sweep, if stored.
    pub fn macroscopic(&self) -> Option<&Macroscopic> {
        self.macros.as_ref()
    }

    /// The cell at `(x, y, z) + sign · c`, wrapped round the periodic faces (`|c| <= 1` per
    /// axis, `sign` ±1).
    #[inline]
    fn neighbour(&self, x: usize, y: usize, z: usize, c: [i32; 3], sign: i64) -> usize {
        // (An integer division per axis here made `totals` ~3× slower.)
        let w = |v: usize, d: i32, n: usize| wrap_step(v, sign * d as i64, n);
        self.index(w(x, c[0], self.nx), w(y, c[1], self.ny), w(z, c[2], self.nz))
    }

    /// One fused stream–collide step over all fluid nodes, on the current rayon pool.
    ///
    /// Fails with [`Error::Unstable`] (naming the step and the node) when a velocity is NaN or
    /// exceeds the limit; the lattice is then left as it was after the failed sweep.
    pub fn step(&mut self) -> Result<StepReport> {
        if self.force_method == ForceMethod::MomentumExchange {
            self.find_links();
        }
        let [nx, ny, _] = self.dims();
        let slabs = match self.storage {
            Storage::F64 => self.sweep::<f64>(),
            Storage::F32 => self.sweep::<f32>(),
        };
        let mut report = StepReport::default();
        let mut max_u2 = 0.0f64;
        for s in slabs {
            if let Some((cell, u)) = s.bad {
                let (x, y, z) = (cell % nx, (cell / nx) % ny, cell / (nx * ny));
                let step = self.time;
                self.time += 1;
                return Err(Error::Unstable { step, x, y, z, velocity: u });
            }
            max_u2 = max_u2.max(s.max_u2);
            for (body, pf) in s.forces {
                let e = report
                    .particle_forces
                    .entry(self.particles.bodies()[body as usize].id)
                    .or_default();
                for d in 0..3 {
                    e.force[d] += pf.force[d];
                    e.moment[d] += pf.moment[d];
                }
            }
        }
        report.max_velocity = max_u2.sqrt();
        self.time += 1;
        Ok(report)
    }

    /// Runs `steps` steps; stops at the first error.
    pub fn run(&mut self, steps: usize) -> Result<StepReport> {
        let mut last = StepReport::default();
        for _ in 0..steps {
            last = self.step()?;
        }
        Ok(last)
    }
}

/// `v + d` wrapped into `0..n` for a step `|d| <= 1`: one compare, no integer division.
#[inline(always)]
fn wrap_step(v: usize, d: i64, n: usize) -> usize {
    match v as i64 + d {
        -1 => n - 1,
        w if w == n as i64 => 0,
        w => w as usize,
    }
}

#[inline]
fn dot(c: [i32; 3], v: [f64; 3]) -> f64 {
    c[0] as f64 * v[0] + c[1] as f64 * v[1] + c[2] as f64 * v[2]
}
