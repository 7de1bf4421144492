//! The fused stream–collide sweep: per z-slab on all cores, per row block by block of [`LANES`]
//! cells — gather the block's populations ([`RowAccess::gather`], streaming them in odd
//! steps), add the forcing ([`RowParticles::force`]), collide, check the velocities
//! ([`check_health`]), measure the particles' forces ([`RowParticles::measure`]), scatter
//! ([`RowAccess::scatter`]).

use rayon::prelude::*;

use super::forces::{ParticleBlock, RowParticles};
use super::storage::Pop;
use super::stream::RowAccess;
use super::{Lattice, SlabResult};
use crate::d3q19::{collide, collide_at, LANES};

/// The populations, shared by the threads that sweep the slabs.
#[derive(Clone, Copy)]
pub(super) struct Ptr<T>(*mut T);
unsafe impl<T> Send for Ptr<T> {}
unsafe impl<T> Sync for Ptr<T> {}

/// The density and velocity fields of [`Macroscopic`](super::Macroscopic), shared by the
/// threads that sweep the slabs.
#[derive(Clone, Copy)]
pub(super) struct MacroPtr(*mut f64, *mut [f64; 3]);
unsafe impl Send for MacroPtr {}
unsafe impl Sync for MacroPtr {}

impl MacroPtr {
    /// Writes density and velocity of the `lanes` cells from `at`.
    ///
    /// # Safety
    /// The cells lie in the fields and no other thread accesses them.
    #[inline(always)]
    unsafe fn store(self, at: usize, lanes: usize, rho: &[f64; LANES], u: &[[f64; LANES]; 3]) {
        for l in 0..lanes {
            *self.0.add(at + l) = rho[l];
            *self.1.add(at + l) = [u[0][l], u[1][l], u[2][l]];
        }
    }
}

impl Lattice {
    /// One sweep over all slabs on the current rayon pool, populations stored as `T`.
    pub(super) fn sweep<T: Pop>(&mut self) -> Vec<SlabResult> {
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

    /// Sweeps one row, block by block: gather, forcing, collision, health check, the particles'
    /// forces, the macroscopic fields, scatter.
    ///
    /// # Safety
    /// `ptr` points at `self.f`, stored as `T` (the lattice's [`Storage`](super::Storage)); no
    /// other thread works on this row's cells.
    #[inline(always)]
    pub(super) unsafe fn sweep_row_generic<T: Pop>(
        &self,
        ptr: Ptr<T>,
        macros: Option<MacroPtr>,
        odd: bool,
        y: usize,
        z: usize,
        res: &mut SlabResult,
    ) {
        let nx = self.nx;
        let row = z * self.ny + y;
        let base = row * nx;
        let blocks = nx.div_ceil(LANES);
        let slow_blocks = &self.slow_block[row * blocks..(row + 1) * blocks];
        let g = self.body_acceleration;
        let gravity = g != [0.0; 3];
        let lim2 = self.velocity_limit * self.velocity_limit;
        let access = RowAccess::new(self, ptr.0, odd, y, z);
        let mut block = ParticleBlock::new();
        let mut particles = RowParticles::new(self, y, z, &mut block);
        let mut x0 = 0;
        while x0 < nx {
            let lanes = LANES.min(nx - x0);
            let slow = slow_blocks[x0 / LANES];
            let path = access.path(x0, lanes, slow);
            let live = access.live(x0, lanes, slow);
            let mut blk = access.gather(path, x0, lanes, slow, &live);
            // Forcing: body acceleration plus, on particle nodes, the term d_B (v_p - u).
            let mut du = [[g[0]; LANES], [g[1]; LANES], [g[2]; LANES]];
            let has_particles = particles.in_block(x0, lanes);
            let at =
                if has_particles { Some(particles.force(x0, lanes, &blk, &mut du)) } else { None };
            // Blocks with neither body force nor particle node take the plain collision
            // (measured on `lbm_profile`: 1–6 % faster than forcing every block of the row).
            let (rho, u) = match at {
                Some((rho, u)) => collide_at(&mut blk, self.omega, Some(&du), rho, u),
                None => collide(&mut blk, self.omega, gravity.then_some(&du)),
            };
            check_health(res, &live, &u, lim2, base + x0);
            if has_particles {
                particles.measure(&blk, lanes, &rho, &du, g, res);
            }
            if let Some(m) = macros {
                m.store(base + x0, lanes, &rho, &u);
            }
            access.scatter(path, x0, lanes, slow, &live, &blk);
            x0 += LANES;
        }
        particles.finish(res);
    }
}

/// Folds the block's velocities `u` into the slab's largest `|u|²` and records the first
/// `live` lane whose `|u|²` is NaN or over `lim2` (`cell`: the block's first cell).
#[inline(always)]
fn check_health(
    res: &mut SlabResult,
    live: &[bool; LANES],
    u: &[[f64; LANES]; 3],
    lim2: f64,
    cell: usize,
) {
    // Branch-free over the block; the slow search only when something is off.
    let mut u2 = [0.0; LANES];
    let mut blk_max = 0.0f64;
    let mut bad = false;
    for l in 0..LANES {
        u2[l] =
            if live[l] { u[0][l] * u[0][l] + u[1][l] * u[1][l] + u[2][l] * u[2][l] } else { 0.0 };
        bad |= !(u2[l] <= lim2);
        blk_max = blk_max.max(u2[l]);
    }
    res.max_u2 = res.max_u2.max(blk_max);
    if bad && res.bad.is_none() {
        let l = (0..LANES).find(|&l| !(u2[l] <= lim2)).unwrap_or(0);
        res.bad = Some((cell + l, u2[l].sqrt()));
    }
}
