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

use std::collections::BTreeMap;

use rayon::prelude::*;

use crate::d3q19::{collide, collide_at, equilibrium, for_each_pair, moments, C, LANES, OPP, Q, W};
use crate::error::{Error, Result};
use crate::particles::ParticleField;

/// Fluid or solid (wall) node: 0 is fluid, 1 a resting wall, `k > 1` a wall made by
/// [`Lattice::add_wall`].
pub type NodeKind = u8;

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
///   touching a wall lost the lattice's whole rest pressure `ρ/3` on the cut-off part and was
///   pulled into the wall (measured: a sphere hit the floor at 0.70 instead of 0.38 m/s).
///   It measures the momentum that crosses the particle's outer surface, so the inner fluid is
///   not in it — up to how rigidly that fluid really moves. The last term hands the particle
///   the body force on every node it covers, as a pressure gradient would push on its surface:
///   the lattice applies `g` to every node, and on the covered ones the forcing takes it back
///   (the node is held at `u_p`), so it must reach the particle. Weighted by `d_B` instead, the
///   fluid share `1 − d_B` of the smoothing band was lost: a periodic suspension under a
///   balance force accelerated as a whole (one sphere, D = 6 Δx, φ = 2.8 %: 10 % of its
///   settling speed per 3900 steps; measured against the total momentum, now constant).
///
///   Wen et al.'s terms for nodes that a moving particle covers and uncovers (their fluid
///   momentum handed to or taken from the particle) are left out, as OpenLB's HLBM does: with
///   a smooth `d_B` a node joins the particle at vanishing `d_B` but would hand over its whole
///   momentum at once. Measured with them, a coupled sphere of density ratio 1.06 settled with
///   6 % velocity jitter (0.2 % without); without them the mean settling speed is 1.8–3 %
///   above the forcing measure's (the momentum the moving nodes carry), see the settling tests.
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

#[derive(Clone, Copy)]
struct Ptr<T>(*mut T);
unsafe impl<T> Send for Ptr<T> {}
unsafe impl<T> Sync for Ptr<T> {}

/// How the lattice stores its populations (arithmetic is f64 either way).
///
/// [`F32`](Self::F32) halves the memory a sweep moves (152 instead of 304 B per node update)
/// and stores each population as its deviation from the rest state, `f_i − w_i` ("DDF
/// shifting", as FluidX3D does), so the 24 bits of an f32 mantissa resolve the flow rather than
/// the constant `w_i`. What it costs in accuracy and buys in speed is measured by the
/// `f32_storage_*` tests and `lbm_throughput`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Storage {
    /// f64 populations (default).
    #[default]
    F64,
    /// f32 populations, shifted by their weights.
    F32,
}

impl Storage {
    /// Bytes per stored population.
    fn bytes(self) -> usize {
        match self {
            Self::F64 => 8,
            Self::F32 => 4,
        }
    }
}

/// A stored population: f64 as is, f32 shifted by its weight. (Lane loops are written out
/// with indices, as in the sweep: the form the measured code generation came from.)
trait Pop: Copy + Send + Sync + 'static {
    /// Converts a population of direction `i` for storage.
    fn put(v: f64, i: usize) -> Self;
    /// The population of direction `i` a stored value holds.
    fn get(self, i: usize) -> f64;
    /// The populations of direction `i` of `LANES` consecutive cells from `p`.
    ///
    /// # Safety
    /// `p` points at `LANES` stored values.
    unsafe fn load_block(p: *const Self, i: usize) -> [f64; LANES];
    /// Stores `LANES` populations of direction `i` at `p`.
    ///
    /// # Safety
    /// `p` points at `LANES` stored values no one else accesses.
    unsafe fn store_block(p: *mut Self, v: &[f64; LANES], i: usize);
}

#[allow(clippy::needless_range_loop)]
impl Pop for f64 {
    #[inline(always)]
    fn put(v: f64, _: usize) -> Self {
        v
    }
    #[inline(always)]
    fn get(self, _: usize) -> f64 {
        self
    }
    #[inline(always)]
    unsafe fn load_block(p: *const Self, _: usize) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        for l in 0..LANES {
            out[l] = *p.add(l);
        }
        out
    }
    #[inline(always)]
    unsafe fn store_block(p: *mut Self, v: &[f64; LANES], _: usize) {
        for l in 0..LANES {
            *p.add(l) = v[l];
        }
    }
}

#[allow(clippy::needless_range_loop)]
impl Pop for f32 {
    #[inline(always)]
    unsafe fn load_block(p: *const Self, i: usize) -> [f64; LANES] {
        // Through a local block, so the conversion vectorises across the cells; the opaque `i`
        // keeps LLVM from vectorising the caller's loop over populations with gathers instead
        // (it did, at half the speed).
        let w = W[std::hint::black_box(i)];
        let v = (p as *const [f32; LANES]).read_unaligned();
        let mut out = [0.0; LANES];
        for l in 0..LANES {
            out[l] = v[l] as f64 + w;
        }
        out
    }
    #[inline(always)]
    unsafe fn store_block(p: *mut Self, v: &[f64; LANES], i: usize) {
        let w = W[std::hint::black_box(i)];
        let mut out = [0.0f32; LANES];
        for l in 0..LANES {
            out[l] = (v[l] - w) as f32;
        }
        (p as *mut [f32; LANES]).write_unaligned(out);
    }
    #[inline(always)]
    fn put(v: f64, i: usize) -> Self {
        (v - W[i]) as f32
    }
    #[inline(always)]
    fn get(self, i: usize) -> f64 {
        self as f64 + W[i]
    }
}

#[derive(Clone, Copy)]
struct MacroPtr(*mut f64, *mut [f64; 3]);
unsafe impl Send for MacroPtr {}
unsafe impl Sync for MacroPtr {}

/// One cache line of populations (raw bits: 8 f64 or 16 f32), aligned so a block loads as one
/// aligned vector.
#[derive(Clone, Copy)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(C, align(64))]
struct Line([u64; 8]);

/// The populations, stored in cache-line-aligned lines and viewed as one slice of the storage
/// type.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct Lines(Vec<Line>);

impl Lines {
    /// Lines for `values` stored values of `T`.
    fn new<T: Pop>(values: usize) -> Self {
        Lines(vec![Line([0; 8]); (values * std::mem::size_of::<T>()).div_ceil(64)])
    }

    fn as_slice<T: Pop>(&self) -> &[T] {
        // SAFETY: `Line` is `repr(C)` over 64 bytes with no padding, aligned to 64; f64 and f32
        // have no invalid bit patterns.
        unsafe {
            std::slice::from_raw_parts(
                self.0.as_ptr().cast(),
                self.0.len() * 64 / std::mem::size_of::<T>(),
            )
        }
    }

    fn as_mut_slice<T: Pop>(&mut self) -> &mut [T] {
        // SAFETY: as in `as_slice`.
        unsafe {
            std::slice::from_raw_parts_mut(
                self.0.as_mut_ptr().cast(),
                self.0.len() * 64 / std::mem::size_of::<T>(),
            )
        }
    }
}

/// Distance (in cells) between the arrays of two populations for `n` cells stored as `size`
/// bytes each: `n` rounded up to whole cache lines, so every population's array starts on a
/// line and a block of cells at `x0 % LANES == 0` is one aligned vector. (Measured: aligned
/// lines took the plain-fluid sweep from ~92 to ~120 MLUPs on 128³ with 2 threads; the
/// allocator's 16-byte alignment split every 64-byte load over two lines. Extra padding against
/// 4K aliasing measured no gain.)
fn population_stride(n: usize, size: usize) -> usize {
    let per_line = 64 / size;
    n.div_ceil(per_line) * per_line
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
    /// Particle nodes; filled by the coupling before each step.
    pub particles: ParticleField,
    velocity_limit: f64,
    macros: Option<Macroscopic>,
    force_method: ForceMethod,
    /// Per particle node (rows as in [`ParticleField`]): bit `i` set when the link to
    /// `x + c_i` leaves the particle ([`ForceMethod::MomentumExchange`] only; each step, rows
    /// whose neighbourhood changed are rebuilt).
    #[cfg_attr(feature = "serde", serde(skip))]
    links: Vec<Vec<u32>>,
    /// [`Lattice::find_links`]'s owner field (body index + 1 per node, [`WALL_OWNER`] on walls,
    /// 0 elsewhere; empty until first needed and after the walls change) and the `(x, body
    /// index)` of the nodes it has set, per row (to see what changed, and clear it).
    #[cfg_attr(feature = "serde", serde(skip))]
    owner: Vec<u32>,
    #[cfg_attr(feature = "serde", serde(skip))]
    owned: Vec<Vec<(u32, u32)>>,
    /// Per row: whether its nodes changed in the last [`Lattice::find_links`].
    #[cfg_attr(feature = "serde", serde(skip))]
    changed: Vec<bool>,
    /// [`Lattice::has_solid`], once scanned (reset by [`Lattice::set_solid`]): the coupling
    /// asks every step, and the scan of a 135³ lattice's kinds was 0.7 % of a suspension's run.
    #[cfg_attr(feature = "serde", serde(skip))]
    any_solid: std::sync::OnceLock<bool>,
}

/// Per-slab results, reduced in slab order (deterministic for any thread count).
#[derive(Default)]
struct SlabResult {
    max_u2: f64,
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

    /// Registers a wall moving with `velocity` (lattice units); returns its kind for
    /// [`Lattice::set_solid`].
    pub fn add_wall(&mut self, velocity: [f64; 3]) -> Result<NodeKind> {
        if self.wall_velocity.len() > 254 {
            return Err(Error::InvalidParameter {
                name: "walls",
                value: 255.0,
                allowed: "at most 254 walls",
            });
        }
        self.wall_velocity.push(velocity);
        Ok((self.wall_velocity.len() - 1) as NodeKind)
    }

    /// Marks cell `(x, y, z)` fluid (`0`), resting wall (`1`) or a wall `kind` returned by
    /// [`Lattice::add_wall`].
    pub fn set_solid(&mut self, x: usize, y: usize, z: usize, kind: NodeKind) {
        if kind as usize >= self.wall_velocity.len() {
            self.wall_velocity.resize(kind as usize + 1, [0.0; 3]);
        }
        let c = self.index(x, y, z);
        self.kind[c] = kind;
        self.any_solid = std::sync::OnceLock::new();
        // The owner field marks walls: rebuilt when next needed.
        self.owner.clear();
        // Blocks within one cell of a solid node take the solid-aware path.
        let (nx, ny, nz) = (self.nx as i64, self.ny as i64, self.nz as i64);
        let blocks = self.nx.div_ceil(LANES);
        for dz in -1..=1i64 {
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let (xx, yy, zz) = (
                        (x as i64 + dx).rem_euclid(nx),
                        (y as i64 + dy).rem_euclid(ny),
                        (z as i64 + dz).rem_euclid(nz),
                    );
                    self.slow_block[(zz * ny + yy) as usize * blocks + xx as usize / LANES] = true;
                }
            }
        }
    }

    /// Closes the domain with resting walls on the faces of the non-periodic axes.
    pub fn close_faces(&mut self, periodic: [bool; 3]) {
        let [nx, ny, nz] = self.dims();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let edge = (!periodic[0] && (x == 0 || x == nx - 1))
                        || (!periodic[1] && (y == 0 || y == ny - 1))
                        || (!periodic[2] && (z == 0 || z == nz - 1));
                    if edge {
                        self.set_solid(x, y, z, 1);
                    }
                }
            }
        }
    }

    /// Checks that a fluid node never reaches across a non-periodic face: the faces of those
    /// axes must be solid.
    pub fn check_closed(&self, periodic: [bool; 3]) -> Result<()> {
        let [nx, ny, nz] = self.dims();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let edge = [(x, nx), (y, ny), (z, nz)]
                        .iter()
                        .zip(periodic)
                        .any(|(&(v, n), p)| !p && (v == 0 || v == n - 1));
                    if edge && self.kind[self.index(x, y, z)] == 0 {
                        return Err(Error::OpenBoundary { x, y, z });
                    }
                }
            }
        }
        Ok(())
    }

    /// Whether any node is solid (a scan of the node kinds, ~1 B per node, the first time
    /// after a change).
    pub fn has_solid(&self) -> bool {
        *self.any_solid.get_or_init(|| self.kind.iter().any(|&k| k != 0))
    }

    /// Whether cell `c` is solid.
    pub fn is_solid(&self, c: usize) -> bool {
        self.kind[c] != 0
    }

    /// Sets every fluid node to the equilibrium of `(rho, u)` given per cell.
    pub fn initialise(&mut self, mut field: impl FnMut(usize, usize, usize) -> (f64, [f64; 3])) {
        let n = self.stride;
        // Equilibrium is stored in natural order; the next step must then be an even one.
        if self.time % 2 == 1 {
            self.time += 1;
        }
        for z in 0..self.nz {
            for y in 0..self.ny {
                for x in 0..self.nx {
                    let c = self.index(x, y, z);
                    let (rho, u) = field(x, y, z);
                    for i in 0..Q {
                        self.set(i * n + c, i, equilibrium(i, rho, u));
                    }
                }
            }
        }
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

    /// The 19 populations of cell `c` as they enter the next collision.
    pub fn populations(&self, x: usize, y: usize, z: usize) -> [f64; Q] {
        let n = self.stride;
        let c = self.index(x, y, z);
        let mut out = [0.0; Q];
        if self.time % 2 == 0 {
            for i in 0..Q {
                out[i] = self.get(i * n + c, i);
            }
        } else {
            for i in 0..Q {
                let src = self.neighbour(x, y, z, C[i], -1);
                out[i] = if self.kind[src] != 0 {
                    self.get(i * n + c, i)
                        + 6.0 * W[i] * dot(C[i], self.wall_velocity[self.kind[src] as usize])
                } else {
                    self.get(OPP[i] * n + src, i)
                };
            }
        }
        out
    }

    /// The population of direction `i` stored at `at` (an index into `f`).
    fn get(&self, at: usize, i: usize) -> f64 {
        match self.storage {
            Storage::F64 => self.f.as_slice::<f64>()[at].get(i),
            Storage::F32 => self.f.as_slice::<f32>()[at].get(i),
        }
    }

    /// Stores population `v` of direction `i` at `at`.
    fn set(&mut self, at: usize, i: usize, v: f64) {
        match self.storage {
            Storage::F64 => self.f.as_mut_slice::<f64>()[at] = f64::put(v, i),
            Storage::F32 => self.f.as_mut_slice::<f32>()[at] = f32::put(v, i),
        }
    }

    /// How the populations are stored.
    pub fn storage(&self) -> Storage {
        self.storage
    }

    /// Stores the populations as `storage` from now on, converting the present ones (f64 → f32
    /// rounds each to f32).
    pub fn set_storage(&mut self, storage: Storage) {
        if storage == self.storage {
            return;
        }
        let (n, cells) = (self.stride, self.cells());
        let old: Vec<f64> = (0..Q * n).map(|at| self.get(at, at / n)).collect();
        self.stride = population_stride(cells, storage.bytes());
        self.storage = storage;
        self.f = match storage {
            Storage::F64 => Lines::new::<f64>(Q * self.stride),
            Storage::F32 => Lines::new::<f32>(Q * self.stride),
        };
        for i in 0..Q {
            for c in 0..cells {
                self.set(i * self.stride + c, i, old[i * n + c]);
            }
        }
    }

    /// Density and velocity `Σ f c / ρ` of cell `(x, y, z)` (before forcing).
    pub fn density_velocity(&self, x: usize, y: usize, z: usize) -> (f64, [f64; 3]) {
        let f = self.populations(x, y, z);
        let rho: f64 = f.iter().sum();
        let mut j = [0.0; 3];
        for i in 0..Q {
            for d in 0..3 {
                j[d] += f[i] * C[i][d] as f64;
            }
        }
        (rho, [j[0] / rho, j[1] / rho, j[2] / rho])
    }

    /// Total mass and momentum of the fluid nodes.
    pub fn totals(&self) -> (f64, [f64; 3]) {
        if self.has_solid() {
            self.totals_by_node()
        } else {
            self.totals_without_walls()
        }
    }

    /// [`Lattice::totals`] node by node, walls and all.
    fn totals_by_node(&self) -> (f64, [f64; 3]) {
        // Per z-slab on all cores, slabs summed in order: the same sum for any thread count.
        let slabs: Vec<(f64, [f64; 3])> = (0..self.nz)
            .into_par_iter()
            .map(|z| {
                let (mut m, mut p) = (0.0, [0.0; 3]);
                for y in 0..self.ny {
                    for x in 0..self.nx {
                        if self.kind[self.index(x, y, z)] == 0 {
                            let (rho, u) = self.density_velocity(x, y, z);
                            m += rho;
                            for d in 0..3 {
                                p[d] += rho * u[d];
                            }
                        }
                    }
                }
                (m, p)
            })
            .collect();
        add_slabs(slabs)
    }

    /// [`Lattice::totals`] of a lattice without solid nodes: every stored population belongs
    /// to a fluid node, so each direction's total is one contiguous sum over its slot (slot
    /// `i` in even steps, `ī` in odd ones): at 136³ 0.024 s against 0.044 (even step) and 0.108 s
    /// (odd) node by node — in a 100-step timing with a momentum sample every 10 steps that
    /// was ~4 % of the run.
    fn totals_without_walls(&self) -> (f64, [f64; 3]) {
        fn sum<T: Pop>(f: &[T], i: usize) -> f64 {
            f.iter().map(|v| v.get(i)).sum()
        }
        let (n, slab) = (self.stride, self.nx * self.ny);
        let odd = self.time % 2 == 1;
        let slabs: Vec<(f64, [f64; 3])> = (0..self.nz)
            .into_par_iter()
            .map(|z| {
                let (mut m, mut p) = (0.0, [0.0; 3]);
                for i in 0..Q {
                    let at = (if odd { OPP[i] } else { i }) * n + z * slab;
                    let s = match self.storage {
                        Storage::F64 => sum(&self.f.as_slice::<f64>()[at..at + slab], i),
                        Storage::F32 => sum(&self.f.as_slice::<f32>()[at..at + slab], i),
                    };
                    m += s;
                    for d in 0..3 {
                        p[d] += C[i][d] as f64 * s;
                    }
                }
                (m, p)
            })
            .collect();
        add_slabs(slabs)
    }

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

    /// One sweep over all slabs on the current rayon pool, populations stored as `T`.
    fn sweep<T: Pop>(&mut self) -> Vec<SlabResult> {
        let odd = self.time % 2 == 1;
        let [_, ny, nz] = self.dims();
        let ptr = Ptr(self.f.as_mut_slice::<T>().as_mut_ptr());
        let macros = self.macros.as_mut().map(|m| MacroPtr(m.rho.as_mut_ptr(), m.u.as_mut_ptr()));
        let this = &*self;
        (0..nz)
            .into_par_iter()
            .map(|z| {
                let mut res = SlabResult::default();
                for y in 0..ny {
                    // SAFETY: in the A-A pattern every cell reads and writes only its own 19
                    // locations, so slabs never touch the same memory.
                    unsafe { this.sweep_row(ptr, macros, odd, y, z, &mut res) };
                }
                res
            })
            .collect()
    }

    /// Marks, for every particle node, the links that leave its particle: to a node that is
    /// fluid (not a wall) and not covered by the same particle.
    ///
    /// Through a dense owner field (body index + 1 per node, [`WALL_OWNER`] on walls, 0
    /// elsewhere; 4 B per node), updated sparsely slab by slab on all cores: a row whose nodes
    /// (`x` and body) are the last call's is left alone, another has the last call's nodes
    /// cleared and its own set. Then only the rows next to a changed one (or changed
    /// themselves) find their links again: per direction, one pass ([`row_links`]) compares
    /// the owners along the row's span of particle nodes with those of the neighbouring row it
    /// points into. A body moving a small fraction of a cell per step changes few of its rows
    /// in a step. (The alternatives measured slower are listed in `hlbm/PERFORMANCE.md`.)
    fn find_links(&mut self) {
        let (nx, ny, nz) = (self.nx, self.ny, self.nz);
        let kind = &self.kind;
        let rows = self.particles.rows();
        let mut owner = std::mem::take(&mut self.owner);
        let mut set = std::mem::take(&mut self.owned);
        let mut changed = std::mem::take(&mut self.changed);
        if owner.len() != kind.len() {
            // (Re)built: every row with nodes differs from the empty list.
            owner = kind.iter().map(|&k| if k != 0 { WALL_OWNER } else { 0 }).collect();
            set.clear();
        }
        set.resize(rows, Vec::new());
        changed.resize(rows, false);
        let particles = &self.particles;
        owner
            .par_chunks_mut(nx * ny)
            .zip(set.par_chunks_mut(ny))
            .zip(changed.par_chunks_mut(ny))
            .enumerate()
            .for_each(|(z, ((slab, rows), changed))| {
                for (y, (row, changed)) in rows.iter_mut().zip(changed.iter_mut()).enumerate() {
                    let nodes = particles.row(z * ny + y);
                    *changed = nodes.len() != row.len()
                        || nodes
                            .iter()
                            .zip(row.iter())
                            .any(|(n, &(x, body))| n.x != x || n.body() as u32 != body);
                    if !*changed {
                        continue;
                    }
                    // A wall node stays a wall (a particle covering one is the caller's error).
                    for &(x, _) in row.iter() {
                        let o = &mut slab[y * nx + x as usize];
                        if *o != WALL_OWNER {
                            *o = 0;
                        }
                    }
                    row.clear();
                    for n in nodes {
                        let o = &mut slab[y * nx + n.x as usize];
                        if *o != WALL_OWNER {
                            *o = n.body() as u32 + 1;
                        }
                        row.push((n.x, n.body() as u32));
                    }
                }
            });
        let mut links = std::mem::take(&mut self.links);
        links.resize(rows, Vec::new());
        // The rows' node positions from the compact list just built (the particle nodes
        // were 64 B apart then: reading them again measured a third of this pass).
        let (xs, changed_ref) = (&set, &changed);
        links.par_chunks_mut(ny).enumerate().for_each(|(z, slab)| {
            let mut span = vec![0u32; nx];
            for (y, masks) in slab.iter_mut().enumerate() {
                let near = |dy: i64, dz: i64| {
                    changed_ref[wrap_step(z, dz, nz) * ny + wrap_step(y, dy, ny)]
                };
                if !(-1..=1).any(|dz| (-1..=1).any(|dy| near(dy, dz))) {
                    continue;
                }
                masks.clear();
                row_links(&owner, &xs[z * ny + y], y, z, [nx, ny, nz], &mut span, masks);
            }
        });
        self.links = links;
        self.owner = owner;
        self.owned = set;
        self.changed = changed;
    }

    /// Runs `steps` steps; stops at the first error.
    pub fn run(&mut self, steps: usize) -> Result<StepReport> {
        let mut last = StepReport::default();
        for _ in 0..steps {
            last = self.step()?;
        }
        Ok(last)
    }

    /// Sweeps one row with the best instruction set this CPU has (detected once).
    ///
    /// # Safety
    /// As [`Lattice::sweep_row_generic`].
    #[inline]
    unsafe fn sweep_row<T: Pop>(
        &self,
        ptr: Ptr<T>,
        macros: Option<MacroPtr>,
        odd: bool,
        y: usize,
        z: usize,
        res: &mut SlabResult,
    ) {
        #[cfg(target_arch = "x86_64")]
        {
            match simd_level() {
                SimdLevel::Avx512 => return self.sweep_row_avx512(ptr, macros, odd, y, z, res),
                SimdLevel::Avx2 => return self.sweep_row_avx2(ptr, macros, odd, y, z, res),
                SimdLevel::Baseline => {}
            }
        }
        self.sweep_row_generic(ptr, macros, odd, y, z, res)
    }

    /// [`Lattice::sweep_row_generic`] compiled for AVX-512.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2,fma")]
    unsafe fn sweep_row_avx512<T: Pop>(
        &self,
        ptr: Ptr<T>,
        macros: Option<MacroPtr>,
        odd: bool,
        y: usize,
        z: usize,
        res: &mut SlabResult,
    ) {
        self.sweep_row_generic(ptr, macros, odd, y, z, res)
    }

    /// [`Lattice::sweep_row_generic`] compiled for AVX2 + FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn sweep_row_avx2<T: Pop>(
        &self,
        ptr: Ptr<T>,
        macros: Option<MacroPtr>,
        odd: bool,
        y: usize,
        z: usize,
        res: &mut SlabResult,
    ) {
        self.sweep_row_generic(ptr, macros, odd, y, z, res)
    }

    /// Sweeps one row.
    ///
    /// # Safety
    /// `ptr` points at `self.f`, stored as `T` (the lattice's [`Storage`]); no other thread works
    /// on this row's cells.
    #[inline(always)]
    unsafe fn sweep_row_generic<T: Pop>(
        &self,
        ptr: Ptr<T>,
        macros: Option<MacroPtr>,
        odd: bool,
        y: usize,
        z: usize,
        res: &mut SlabResult,
    ) {
        let (nx, ny, nz) = (self.nx, self.ny, self.nz);
        let n = self.stride;
        let row = z * ny + y;
        let base = row * nx;
        let blocks = nx.div_ceil(LANES);
        let slow_blocks = &self.slow_block[row * blocks..(row + 1) * blocks];
        let prow = self.particles.row(row);
        let exchange = self.force_method == ForceMethod::MomentumExchange && !prow.is_empty();
        let lrow: &[u32] = if exchange { &self.links[row] } else { &[] };
        let g = self.body_acceleration;
        let gravity = g != [0.0; 3];
        let f = ptr.0;
        // Where direction i of cell x is read from and written to: `rd[i] + x`, `wr[i] + x`
        // (before wrapping x). Even steps: own slots, swapped. Odd steps: pull from slot ī of
        // x - c_i, push into slot i of x + c_i.
        // Neighbouring y and z (index d + 1 for offset d), wrapped without division.
        let ys = [if y == 0 { ny - 1 } else { y - 1 }, y, if y + 1 == ny { 0 } else { y + 1 }];
        let zs = [if z == 0 { nz - 1 } else { z - 1 }, z, if z + 1 == nz { 0 } else { z + 1 }];
        let row_at = |dy: i32, dz: i32| (zs[(dz + 1) as usize] * ny + ys[(dy + 1) as usize]) * nx;
        let mut rd_row = [0usize; Q];
        let mut wr_row = [0usize; Q];
        let mut rd_dx = [0i64; Q];
        let mut wr_dx = [0i64; Q];
        for i in 0..Q {
            if odd {
                rd_row[i] = OPP[i] * n + row_at(-C[i][1], -C[i][2]);
                wr_row[i] = i * n + row_at(C[i][1], C[i][2]);
                rd_dx[i] = -C[i][0] as i64;
                wr_dx[i] = C[i][0] as i64;
            } else {
                rd_row[i] = i * n + base;
                wr_row[i] = OPP[i] * n + base;
            }
        }
        // Where population i of cell x goes (or comes from) in this sweep: slot `stored` of the
        // neighbour's row `row` at x + dx — unless that neighbour is solid in an odd step
        // (halfway bounce-back): then the cell's own slot `own`, with the moving-wall term that
        // a pull adds and a push subtracts. One rule for gather and scatter.
        let slot = |i: usize,
                    x: usize,
                    row: usize,
                    dx: i64,
                    stored: usize,
                    own: usize,
                    slow: bool|
         -> (usize, f64) {
            let sx = wrap_step(x, dx, nx);
            // Only blocks next to a solid node (`slow`) can have one as neighbour.
            let k = if odd && slow { self.kind[row - stored * n + sx] } else { 0 };
            if k != 0 {
                return (
                    own * n + base + x,
                    6.0 * W[i] * dot(C[i], self.wall_velocity[k as usize]),
                );
            }
            (row + sx, 0.0)
        };
        let lim2 = self.velocity_limit * self.velocity_limit;
        let mut pnext = 0usize;
        // Reused by every block with particle nodes (only its `body`, `d_b`, `links` and the
        // exchange's sums are reset; lanes without a node keep `d_b = 0` and stale but finite
        // velocities and arms, which the forcing multiplies by that zero, and the forces skip).
        let mut pb = ParticleBlock {
            d_b: [0.0; LANES],
            velocity: [[0.0; LANES]; 3],
            arm: [[0.0; LANES]; 3],
            body: [u32::MAX; LANES],
            links: [0; LANES],
            linked: false,
            crossing: [0.0; LANES],
            exchange: [[0.0; LANES]; 3],
        };
        // The force of the run of nodes of one particle being summed (a row's nodes of one
        // particle are mostly consecutive), added to the slab's map when the particle changes.
        let mut run = (u32::MAX, ParticleForce::default());
        let flush = |res: &mut SlabResult, run: &(u32, ParticleForce)| {
            if run.0 != u32::MAX {
                let e = res.forces.entry(run.0).or_default();
                for d in 0..3 {
                    e.force[d] += run.1.force[d];
                    e.moment[d] += run.1.moment[d];
                }
            }
        };
        let mut x0 = 0;
        while x0 < nx {
            let lanes = LANES.min(nx - x0);
            let slow = slow_blocks[x0 / LANES];
            let full = lanes == LANES && !slow;
            // No solid neighbour: vector loads and stores, with the lanes of a row's first and
            // last block that reach across the periodic x face wrapped one by one.
            let inner = !odd || (x0 >= 1 && x0 + LANES < nx);
            let fast = full && inner;
            let edge = full && !inner;
            let mut live = [true; LANES];
            for l in lanes..LANES {
                live[l] = false;
            }
            if slow {
                for l in 0..lanes {
                    live[l] = self.kind[base + x0 + l] == 0;
                }
            }
            // Built whole in each branch: filling it first with a constant cost 19 dead vector
            // stores per block (~15 % of the sweep in the profile).
            let mut blk: [[f64; LANES]; Q] = if fast {
                // Lines `PREFETCH_BLOCKS` blocks ahead in the same rows (in bounds: the row goes
                // on that far). Even steps write where they read.
                #[cfg(target_arch = "x86_64")]
                if x0 + PREFETCH_BLOCKS * LANES < nx {
                    use core::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
                    let ahead = x0 + PREFETCH_BLOCKS * LANES;
                    for i in 0..Q {
                        _mm_prefetch::<_MM_HINT_T0>(f.add(rd_row[i] + ahead) as *const i8);
                        if odd {
                            _mm_prefetch::<_MM_HINT_T0>(f.add(wr_row[i] + ahead) as *const i8);
                        }
                    }
                }
                let mut blk = [[0.0; LANES]; Q];
                for i in 0..Q {
                    blk[i] = T::load_block(f.add(rd_row[i] + x0).offset(rd_dx[i] as isize), i);
                }
                blk
            } else if edge {
                // The row's first or last block in an odd step: per direction the lanes it
                // reads are contiguous but for the one that wraps round the periodic x face —
                // seven copied as a block, that one alone (lane by lane, these blocks cost ~16 %
                // of a 64³ sweep).
                let mut blk = [[0.0; LANES]; Q];
                // Here and in the lane-by-lane paths the opaque `i` keeps LLVM from vectorising
                // across populations with gathers (measured: f32 sweep 67 → 72 MLUPs).
                for i in (0..Q).map(std::hint::black_box) {
                    let lo = x0 as i64 + rd_dx[i];
                    if lo >= 0 && lo as usize + LANES <= nx {
                        blk[i] = T::load_block(f.add(rd_row[i] + lo as usize), i);
                    } else {
                        let mut tmp = [*f.add(rd_row[i]); LANES];
                        let (lane, from, first) =
                            if lo < 0 { (0, nx - 1, 1) } else { (LANES - 1, 0, 0) };
                        std::ptr::copy_nonoverlapping(
                            f.add(rd_row[i] + (lo + first as i64) as usize),
                            tmp.as_mut_ptr().add(first),
                            LANES - 1,
                        );
                        tmp[lane] = *f.add(rd_row[i] + from);
                        blk[i] = T::load_block(tmp.as_ptr(), i);
                    }
                }
                blk
            } else {
                // Lanes that are solid or past the row's end hold a harmless resting state.
                let mut blk = [[1.0 / 19.0; LANES]; Q];
                for i in (0..Q).map(std::hint::black_box) {
                    for l in 0..lanes {
                        if live[l] {
                            let (at, wall) = slot(i, x0 + l, rd_row[i], rd_dx[i], OPP[i], i, slow);
                            blk[i][l] = (*f.add(at)).get(i) + wall;
                        }
                    }
                }
                blk
            };
            // Forcing: body acceleration plus, on particle nodes, the term d_B (v_p - u).
            let mut du = [[g[0]; LANES], [g[1]; LANES], [g[2]; LANES]];
            let has_particles = pnext < prow.len() && (prow[pnext].x as usize) < x0 + lanes;
            let mut at = None;
            if has_particles {
                let b = &mut pb;
                b.body = [u32::MAX; LANES];
                b.d_b = [0.0; LANES];
                b.links = [0; LANES];
                b.crossing = [0.0; LANES];
                b.exchange = [[0.0; LANES]; 3];
                while pnext < prow.len() && (prow[pnext].x as usize) < x0 + lanes {
                    let p = &prow[pnext];
                    let l = p.x as usize - x0;
                    b.d_b[l] = p.d_b;
                    let (_, arm, velocity) = self.particles.motion(p, y, z);
                    for d in 0..3 {
                        b.velocity[d][l] = velocity[d];
                        b.arm[d][l] = arm[d];
                    }
                    b.body[l] = p.body() as u32;
                    if exchange {
                        b.links[l] = lrow[pnext];
                    }
                    pnext += 1;
                }
                b.linked = b.links != [0; LANES];
                let (rho, u) = moments(&blk);
                at = Some((rho, u));
                // Over all lanes as vector code (zero where no node): a per-lane loop with a
                // branch, writing `du` lane by lane before `collide` reads it as vectors, cost
                // 4–8 % of the forcing sweep (`lbm_profile`, one thread).
                for d in 0..3 {
                    for l in 0..LANES {
                        du[d][l] += b.d_b[l] * (b.velocity[d][l] - u[d][l]);
                    }
                }
                if b.linked {
                    // The incoming half, before the collision overwrites `f_ī`.
                    exchange_half::<true>(&blk, &b.links, &mut b.crossing, &mut b.exchange);
                }
            }
            // Blocks with neither body force nor particle node take the plain collision
            // (measured on `lbm_profile`: 1–6 % faster than forcing every block of the row).
            let (rho, u) = match at {
                Some((rho, u)) => collide_at(&mut blk, self.omega, Some(&du), rho, u),
                None => collide(&mut blk, self.omega, gravity.then_some(&du)),
            };
            // Health: branch-free over the block; the slow search only when something is off.
            let mut u2 = [0.0; LANES];
            let mut blk_max = 0.0f64;
            let mut bad = false;
            for l in 0..LANES {
                u2[l] = if live[l] {
                    u[0][l] * u[0][l] + u[1][l] * u[1][l] + u[2][l] * u[2][l]
                } else {
                    0.0
                };
                bad |= !(u2[l] <= lim2);
                blk_max = blk_max.max(u2[l]);
            }
            res.max_u2 = res.max_u2.max(blk_max);
            if bad && res.bad.is_none() {
                let l = (0..LANES).find(|&l| !(u2[l] <= lim2)).unwrap_or(0);
                res.bad = Some((base + x0 + l, u2[l].sqrt()));
            }
            // The particles' forces.
            if has_particles {
                if pb.linked {
                    exchange_half::<false>(&blk, &pb.links, &mut pb.crossing, &mut pb.exchange);
                }
                let b = &pb;
                for l in 0..lanes {
                    if b.body[l] == u32::MAX {
                        continue;
                    }
                    let fp = if exchange {
                        // The exchange over the node's links, and the body force on the node
                        // (all of it: the forcing holds the node at `u_p`).
                        [0, 1, 2].map(|d| {
                            b.exchange[d][l] + b.velocity[d][l] * b.crossing[l] + rho[l] * g[d]
                        })
                    } else {
                        [0, 1, 2].map(|d| -rho[l] * (du[d][l] - g[d]))
                    };
                    if b.body[l] != run.0 {
                        flush(res, &run);
                        run = (b.body[l], ParticleForce::default());
                    }
                    let m = cross([b.arm[0][l], b.arm[1][l], b.arm[2][l]], fp);
                    for d in 0..3 {
                        run.1.force[d] += fp[d];
                        run.1.moment[d] += m[d];
                    }
                }
            }
            if let Some(MacroPtr(r, uu)) = macros {
                for l in 0..lanes {
                    *r.add(base + x0 + l) = rho[l];
                    *uu.add(base + x0 + l) = [u[0][l], u[1][l], u[2][l]];
                }
            }
            // Scatter.
            if fast {
                for i in 0..Q {
                    T::store_block(f.add(wr_row[i] + x0).offset(wr_dx[i] as isize), &blk[i], i);
                }
            } else if edge {
                // As the gather: seven lanes as a block, the wrapping one alone (never a vector
                // store over another cell's slot, which another thread may be writing).
                for i in (0..Q).map(std::hint::black_box) {
                    let lo = x0 as i64 + wr_dx[i];
                    if lo >= 0 && lo as usize + LANES <= nx {
                        T::store_block(f.add(wr_row[i] + lo as usize), &blk[i], i);
                    } else {
                        let mut tmp = [T::put(0.0, i); LANES];
                        T::store_block(tmp.as_mut_ptr(), &blk[i], i);
                        let (lane, to, first) =
                            if lo < 0 { (0, nx - 1, 1) } else { (LANES - 1, 0, 0) };
                        std::ptr::copy_nonoverlapping(
                            tmp.as_ptr().add(first),
                            f.add(wr_row[i] + (lo + first as i64) as usize),
                            LANES - 1,
                        );
                        *f.add(wr_row[i] + to) = tmp[lane];
                    }
                }
            } else {
                for i in (0..Q).map(std::hint::black_box) {
                    for l in 0..lanes {
                        if live[l] {
                            let (at, wall) = slot(i, x0 + l, wr_row[i], wr_dx[i], i, OPP[i], slow);
                            *f.add(at) = T::put(blk[i][l] - wall, i);
                        }
                    }
                }
            }
            x0 += LANES;
        }
        flush(res, &run);
    }
}

/// Appends to `masks` the links of the particle nodes `nodes` (`x` and body index, sorted by
/// `x`) of row `(y, z)`, read off the owner field; `span` is scratch of length `nx`. Compiled
/// for the best instruction set this CPU has (the compares vectorise: measured 4 → 16 lanes).
fn row_links(
    owner: &[u32],
    nodes: &[(u32, u32)],
    y: usize,
    z: usize,
    dims: [usize; 3],
    span: &mut [u32],
    masks: &mut Vec<u32>,
) {
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx512f,avx2")]
        unsafe fn avx512(
            owner: &[u32],
            nodes: &[(u32, u32)],
            y: usize,
            z: usize,
            dims: [usize; 3],
            span: &mut [u32],
            masks: &mut Vec<u32>,
        ) {
            row_links_generic(owner, nodes, y, z, dims, span, masks)
        }
        #[target_feature(enable = "avx2")]
        unsafe fn avx2(
            owner: &[u32],
            nodes: &[(u32, u32)],
            y: usize,
            z: usize,
            dims: [usize; 3],
            span: &mut [u32],
            masks: &mut Vec<u32>,
        ) {
            row_links_generic(owner, nodes, y, z, dims, span, masks)
        }
        // SAFETY: the instruction sets were detected on this CPU.
        match simd_level() {
            SimdLevel::Avx512 => return unsafe { avx512(owner, nodes, y, z, dims, span, masks) },
            SimdLevel::Avx2 => return unsafe { avx2(owner, nodes, y, z, dims, span, masks) },
            SimdLevel::Baseline => {}
        }
    }
    row_links_generic(owner, nodes, y, z, dims, span, masks)
}

/// [`row_links`] for any instruction set: per direction one pass over the row's whole span of
/// particle nodes, comparing contiguous owners (the first and last node of the row, whose
/// links can wrap round the x face, one by one).
#[inline(always)]
fn row_links_generic(
    owner: &[u32],
    nodes: &[(u32, u32)],
    y: usize,
    z: usize,
    dims: [usize; 3],
    span: &mut [u32],
    masks: &mut Vec<u32>,
) {
    let [nx, ny, nz] = dims;
    let (Some(&(first, _)), Some(&(last, _))) = (nodes.first(), nodes.last()) else { return };
    let own = (z * ny + y) * nx;
    let lo = (first as usize).max(1);
    let hi = (last as usize + 1).min(nx - 1).max(lo);
    span[lo..hi].fill(0);
    let mut ends = [0u32; 2];
    for (dy, dz, dirs) in NEIGHBOUR_ROWS {
        let base = (wrap_step(z, dz, nz) * ny + wrap_step(y, dy, ny)) * nx;
        for &(dx, i) in dirs {
            let from = (base + lo) as i64 + dx;
            let theirs = &owner[from as usize..from as usize + (hi - lo)];
            for ((m, &mine), &o) in
                span[lo..hi].iter_mut().zip(&owner[own + lo..own + hi]).zip(theirs)
            {
                *m |= (((o != mine) & (o != WALL_OWNER)) as u32) << i;
            }
            for (e, x) in [0, nx - 1].into_iter().enumerate() {
                let n = base + wrap_step(x, dx, nx);
                if owner[n] != owner[own + x] && owner[n] != WALL_OWNER {
                    ends[e] |= 1 << i;
                }
            }
        }
    }
    masks.extend(nodes.iter().map(|&(x, _)| match x as usize {
        0 => ends[0],
        x if x == nx - 1 => ends[1],
        x => span[x],
    }));
}

/// The mass and momentum of all slabs, added in slab order (the same sum for any thread
/// count).
fn add_slabs(slabs: Vec<(f64, [f64; 3])>) -> (f64, [f64; 3]) {
    slabs.into_iter().fold((0.0, [0.0; 3]), |(m, p), (ms, ps)| {
        (m + ms, [p[0] + ps[0], p[1] + ps[1], p[2] + ps[2]])
    })
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

/// The owner field's mark for a wall node (no body index + 1 reaches it).
const WALL_OWNER: u32 = u32::MAX;

/// A neighbouring row `(dy, dz)` and the directions `(dx, i)` that point into it.
type NeighbourRow = (i64, i64, &'static [(i64, usize)]);

/// The nine rows a row's links reach, as `(dy, dz, [(dx, direction)])`: D3Q19's 18 moving
/// directions grouped by the row they point into.
const NEIGHBOUR_ROWS: [NeighbourRow; 9] = {
    const fn dirs(dy: i32, dz: i32) -> [(i64, usize); 3] {
        let mut out = [(0, 0); 3];
        let mut n = 0;
        let mut i = 1;
        while i < Q {
            if C[i][1] == dy && C[i][2] == dz {
                out[n] = (C[i][0] as i64, i);
                n += 1;
            }
            i += 1;
        }
        out
    }
    const R00: [(i64, usize); 3] = dirs(0, 0);
    const RP0: [(i64, usize); 3] = dirs(1, 0);
    const RM0: [(i64, usize); 3] = dirs(-1, 0);
    const R0P: [(i64, usize); 3] = dirs(0, 1);
    const R0M: [(i64, usize); 3] = dirs(0, -1);
    const RPP: [(i64, usize); 3] = dirs(1, 1);
    const RPM: [(i64, usize); 3] = dirs(1, -1);
    const RMP: [(i64, usize); 3] = dirs(-1, 1);
    const RMM: [(i64, usize); 3] = dirs(-1, -1);
    [
        (0, 0, R00.split_at(2).0),
        (1, 0, &RP0),
        (-1, 0, &RM0),
        (0, 1, &R0P),
        (0, -1, &R0M),
        (1, 1, RPP.split_at(1).0),
        (1, -1, RPM.split_at(1).0),
        (-1, 1, RMP.split_at(1).0),
        (-1, -1, RMM.split_at(1).0),
    ]
};

/// The particle nodes of one block of the sweep.
struct ParticleBlock {
    d_b: [f64; LANES],
    velocity: [[f64; LANES]; 3],
    arm: [[f64; LANES]; 3],
    /// Body index per lane ([`ParticleNode::body`](crate::ParticleNode::body)), `u32::MAX`
    /// where no particle covers the node.
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

/// One half of the link-wise momentum exchange (Wen et al. 2014) of a block, over every lane
/// at once: for each direction `i` set in a lane's `links`, the population crossing that link
/// — `f_ī` before the collision (`INCOMING`), `f_i` after it — is subtracted from (incoming)
/// or added to (outgoing) `crossing`, and `c_i (f − w_i)` subtracted from `exchange`. The
/// force on the node is then `exchange + u_p crossing`:
/// `Σ_links [u_p (f_i^out − f_ī^in) − c_i (f_i^out − w_i) − c_i (f_ī^in − w_i)]`.
///
/// Per direction a masked vector select over the block (a lane-by-lane walk over each node's
/// link bits mispredicts a branch per link), the selected terms then added pairwise:
/// accumulated direction after direction, the four sums were chains of 18 and 10 dependent
/// adds, each waiting on the last (+1–3 % on `lbm_profile` with the exchange).
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

/// How many blocks ahead the sweep prefetches its 19 read (and, in odd steps, 19 write)
/// streams: the hardware prefetchers do not follow 38 streams alone. Two blocks measured best
/// (`hlbm/PERFORMANCE.md`).
const PREFETCH_BLOCKS: usize = 2;

/// Instruction sets the sweep is compiled for, best first.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum SimdLevel {
    /// AVX-512F (8 f64 lanes).
    Avx512,
    /// AVX2 + FMA (4 f64 lanes).
    Avx2,
    /// The build's baseline (SSE2 on a portable x86-64 build).
    Baseline,
}

/// The instruction set the sweep uses on this CPU; `HLBM_SIMD=baseline|avx2|avx512` caps it.
pub fn simd_level() -> SimdLevel {
    static LEVEL: std::sync::OnceLock<SimdLevel> = std::sync::OnceLock::new();
    *LEVEL.get_or_init(|| {
        let cap = std::env::var("HLBM_SIMD").unwrap_or_default();
        #[cfg(target_arch = "x86_64")]
        {
            if cap != "baseline"
                && cap != "avx2"
                && std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return SimdLevel::Avx512;
            }
            if cap != "baseline"
                && std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return SimdLevel::Avx2;
            }
        }
        let _ = cap;
        SimdLevel::Baseline
    })
}

#[inline]
fn dot(c: [i32; 3], v: [f64; 3]) -> f64 {
    c[0] as f64 * v[0] + c[1] as f64 * v[1] + c[2] as f64 * v[2]
}

#[inline]
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// Every link `find_links` marks, and only those, against the definition checked node by
    /// node: from a particle node along `c_i` to a node that is not a wall and not covered by
    /// the same particle — with a wall under the particles, a second particle beside the first,
    /// nodes on the periodic x faces, a wall added after the owner field was built, and then
    /// the particles moved (the rows that changed and their neighbours found again, the rest
    /// kept from the call before).
    #[test]
    fn links_leave_the_particle_to_fluid_and_other_particles_never_into_walls() {
        let mut lat = Lattice::new(16, 12, 10, 0.8).unwrap();
        for (x, y) in (0..16).flat_map(|x| (0..12).map(move |y| (x, y))) {
            lat.set_solid(x, y, 0, 1);
        }
        // Body 0: a 2 × 2 × 2 cube, shifted by `dx` and grown by `grow` cells along y; the
        // rest single nodes, some on the x faces.
        let fill = |lat: &mut Lattice, dx: i64, grow: i64| {
            lat.particles.clear();
            for id in 0..4 {
                lat.particles.add_body(id, [8.0, 6.0, 2.0], [0.0; 3], [0.0; 3]).unwrap();
            }
            let mut add = |x: i64, y: i64, z: i64, body: usize| {
                lat.particles.add(body, [x, y, z], 1.0).unwrap()
            };
            for (x, y, z) in
                (7..9).flat_map(|x| (5..7 + grow).flat_map(move |y| (1..3).map(move |z| (x, y, z))))
            {
                add(x + dx, y, z, 0);
            }
            add(9, 5, 1, 1);
            add(0, 3, 1, 2);
            add(15, 3, 1, 2);
            add(15, 8, 2, 3);
        };
        let check = |lat: &Lattice| {
            let owner = |c: usize| {
                (0..lat.particles.rows())
                    .flat_map(|r| {
                        lat.particles
                            .row(r)
                            .iter()
                            .map(move |n| (r * lat.nx + n.x as usize, n.body()))
                    })
                    .find(|&(at, _)| at == c)
                    .map(|(_, body)| body)
            };
            let mut links = 0;
            for (z, y) in (0..lat.nz).flat_map(|z| (0..lat.ny).map(move |y| (z, y))) {
                let row = z * lat.ny + y;
                for (k, n) in lat.particles.row(row).iter().enumerate() {
                    let x = n.x as usize;
                    let mut expected = 0u32;
                    for (i, &c) in C.iter().enumerate().skip(1) {
                        let to = lat.neighbour(x, y, z, c, 1);
                        if !lat.is_solid(to) && owner(to) != Some(n.body()) {
                            expected |= 1 << i;
                        }
                    }
                    assert_eq!(
                        lat.links[row][k],
                        expected,
                        "node ({x}, {y}, {z}) of particle {}",
                        n.body()
                    );
                    links += expected.count_ones();
                }
            }
            links
        };
        fill(&mut lat, 0, 0);
        lat.find_links();
        let before = check(&lat);
        // A wall beside particle 0: the owner field is rebuilt and the links into it go.
        lat.set_solid(6, 5, 1, 1);
        lat.find_links();
        let after = check(&lat);
        assert!(before > 100 && after < before, "{before} links, then {after}");
        // Refilled as it was: nothing changed, everything kept.
        fill(&mut lat, 0, 0);
        lat.find_links();
        assert!(lat.changed.iter().all(|&c| !c));
        assert_eq!(check(&lat), after);
        // Particle 0 one cell along x onto particle 1's node (which it takes: same d_B, added
        // first), then grown along y into rows of its own: the links of the unchanged rows
        // around them change too.
        for (dx, grow) in [(1, 0), (1, 1)] {
            fill(&mut lat, dx, grow);
            lat.find_links();
            let changed = lat.changed.iter().filter(|&&c| c).count();
            assert!(changed > 0 && changed < lat.particles.rows(), "{changed} rows changed");
            check(&lat);
        }
    }

    /// The contiguous sums of a lattice without walls give the node-by-node totals (even and
    /// odd steps, both storages) to round-off.
    #[test]
    fn totals_without_walls_are_the_node_by_node_totals() {
        for storage in [Storage::F64, Storage::F32] {
            let mut lat = Lattice::new(12, 10, 8, 0.7).unwrap();
            lat.set_storage(storage);
            lat.initialise(|x, y, z| {
                (
                    1.0 + 0.01 * (x as f64 * 0.7 + y as f64 * 0.3).sin(),
                    [0.02 * (z as f64).cos(), -0.01, 0.03 * (y as f64 * 0.5).sin()],
                )
            });
            lat.set_body_acceleration([1e-5, 2e-5, -3e-5]);
            for _ in 0..2 {
                lat.step().unwrap();
                let (m, p) = lat.totals_without_walls();
                let (m0, p0) = lat.totals_by_node();
                assert!(
                    (m - m0).abs() < 1e-10 * m0,
                    "{storage:?}, step {}: mass {m} vs {m0}",
                    lat.time()
                );
                for d in 0..3 {
                    assert!(
                        (p[d] - p0[d]).abs() < 1e-10 * m0,
                        "{storage:?}, step {}: momentum {p:?} vs {p0:?}",
                        lat.time()
                    );
                }
                assert!(
                    p0.iter().all(|c| c.abs() > 1.0),
                    "a flow with momentum on every axis: {p0:?}"
                );
            }
        }
    }
}
