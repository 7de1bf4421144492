//! Streaming in the A-A pattern: where the populations of one row's cells are read from
//! before the collision and written to after it ([`RowAccess`]), block by block — as aligned
//! vectors where a block has no solid neighbour, lane by lane with halfway bounce-back where
//! it has one.

use super::storage::Pop;
use super::walls::NodeKind;
use super::{dot, wrap_step, Lattice};
use crate::d3q19::{C, LANES, OPP, Q, W};

/// How many blocks ahead the sweep prefetches its 19 read (and, in odd steps, 19 write)
/// streams: the hardware prefetchers do not follow 38 streams alone. A short distance: far
/// enough ahead to cover the latency of a line's load, near enough that the lines are still
/// in the first-level cache when their block is swept.
const PREFETCH_BLOCKS: usize = 2;

/// How a block of [`LANES`] cells is gathered and scattered.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Path {
    /// Vector loads and stores: a whole block without solid neighbours whose lanes, in odd
    /// steps, all stay inside the row.
    Vector,
    /// A whole block without solid neighbours, the row's first or last in an odd step: per
    /// direction seven lanes as a block and the one that wraps round the periodic x face alone.
    Edge,
    /// Lane by lane: a block next to a solid node, or the row's last block when it is short.
    Lanes,
}

/// Where the populations of one row's cells are read from and written to in this sweep:
/// direction `i` of cell `x` at `rd_row[i] + x + rd_dx[i]` and `wr_row[i] + x + wr_dx[i]`
/// (before wrapping `x + dx` round the periodic x face). Even steps: own slots, swapped. Odd
/// steps: pull from slot `ī` of `x - c_i`, push into slot `i` of `x + c_i`.
pub(super) struct RowAccess<'a, T> {
    f: *mut T,
    odd: bool,
    nx: usize,
    /// Distance between two populations' arrays (the lattice's `stride`).
    n: usize,
    /// The row's first cell.
    base: usize,
    rd_row: [usize; Q],
    wr_row: [usize; Q],
    rd_dx: [i64; Q],
    wr_dx: [i64; Q],
    kind: &'a [NodeKind],
    wall_velocity: &'a [[f64; 3]],
}

impl<'a, T: Pop> RowAccess<'a, T> {
    /// Row `(y, z)` of `lat`, whose populations `f` points at.
    #[inline(always)]
    pub(super) fn new(lat: &'a Lattice, f: *mut T, odd: bool, y: usize, z: usize) -> Self {
        let (nx, ny, nz) = (lat.nx, lat.ny, lat.nz);
        let n = lat.stride;
        let base = (z * ny + y) * nx;
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
        Self {
            f,
            odd,
            nx,
            n,
            base,
            rd_row,
            wr_row,
            rd_dx,
            wr_dx,
            kind: &lat.kind,
            wall_velocity: &lat.wall_velocity,
        }
    }

    /// How the block of `lanes` cells from `x0` is gathered and scattered (`slow` as in the
    /// lattice's `slow_block`).
    #[inline(always)]
    pub(super) fn path(&self, x0: usize, lanes: usize, slow: bool) -> Path {
        // No solid neighbour: vector loads and stores, with the lanes of a row's first and
        // last block that reach across the periodic x face wrapped one by one.
        let inner = !self.odd || (x0 >= 1 && x0 + LANES < self.nx);
        match (lanes == LANES && !slow, inner) {
            (true, true) => Path::Vector,
            (true, false) => Path::Edge,
            (false, _) => Path::Lanes,
        }
    }

    /// Which lanes of the block of `lanes` cells from `x0` are fluid nodes of the row (only a
    /// `slow` block can hold solid ones).
    #[inline(always)]
    pub(super) fn live(&self, x0: usize, lanes: usize, slow: bool) -> [bool; LANES] {
        let mut live = [true; LANES];
        for l in lanes..LANES {
            live[l] = false;
        }
        if slow {
            for l in 0..lanes {
                live[l] = self.kind[self.base + x0 + l] == 0;
            }
        }
        live
    }

    /// Where population `i` of cell `x` is read from (`PULL`) or written to in this sweep: slot
    /// `ī` (pull) or `i` (push) of the neighbour's row at `x + dx` — unless that neighbour is
    /// solid in an odd step (halfway bounce-back): then the cell's own slot `i` (pull) or `ī`
    /// (push), with the moving-wall term that a pull adds and a push subtracts. One rule for
    /// gather and scatter; `slow` as in the lattice's `slow_block`.
    #[inline(always)]
    fn slot<const PULL: bool>(&self, i: usize, x: usize, slow: bool) -> (usize, f64) {
        let (row, dx, stored, own) = if PULL {
            (self.rd_row[i], self.rd_dx[i], OPP[i], i)
        } else {
            (self.wr_row[i], self.wr_dx[i], i, OPP[i])
        };
        let n = self.n;
        let sx = wrap_step(x, dx, self.nx);
        // Only blocks next to a solid node (`slow`) can have one as neighbour.
        let k = if self.odd && slow { self.kind[row - stored * n + sx] } else { 0 };
        if k != 0 {
            return (
                own * n + self.base + x,
                6.0 * W[i] * dot(C[i], self.wall_velocity[k as usize]),
            );
        }
        (row + sx, 0.0)
    }

    /// The populations of the block of `lanes` cells from `x0` as they enter the collision
    /// (streamed in odd steps); lanes that are not `live` hold a harmless resting state.
    ///
    /// # Safety
    /// As [`Lattice::sweep_row_generic`].
    #[inline(always)]
    pub(super) unsafe fn gather(
        &self,
        path: Path,
        x0: usize,
        lanes: usize,
        slow: bool,
        live: &[bool; LANES],
    ) -> [[f64; LANES]; Q] {
        let (f, nx, odd) = (self.f, self.nx, self.odd);
        let (rd_row, rd_dx) = (&self.rd_row, &self.rd_dx);
        // Built whole in each branch: filling it first with a constant cost 19 dead vector
        // stores per block (~15 % of the sweep in the profile).
        match path {
            Path::Vector => {
                // Lines `PREFETCH_BLOCKS` blocks ahead in the same rows (in bounds: the row goes
                // on that far). Even steps write where they read.
                #[cfg(target_arch = "x86_64")]
                if x0 + PREFETCH_BLOCKS * LANES < nx {
                    use core::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
                    let ahead = x0 + PREFETCH_BLOCKS * LANES;
                    for i in 0..Q {
                        _mm_prefetch::<_MM_HINT_T0>(f.add(rd_row[i] + ahead) as *const i8);
                        if odd {
                            _mm_prefetch::<_MM_HINT_T0>(f.add(self.wr_row[i] + ahead) as *const i8);
                        }
                    }
                }
                let mut blk = [[0.0; LANES]; Q];
                for i in 0..Q {
                    blk[i] = T::load_block(f.add(rd_row[i] + x0).offset(rd_dx[i] as isize), i);
                }
                blk
            }
            Path::Edge => {
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
            }
            Path::Lanes => {
                // Lanes that are solid or past the row's end hold a harmless resting state.
                let mut blk = [[1.0 / 19.0; LANES]; Q];
                for i in (0..Q).map(std::hint::black_box) {
                    for l in 0..lanes {
                        if live[l] {
                            let (at, wall) = self.slot::<true>(i, x0 + l, slow);
                            blk[i][l] = (*f.add(at)).get(i) + wall;
                        }
                    }
                }
                blk
            }
        }
    }

    /// Stores the collided populations `blk` of the block of `lanes` cells from `x0` where
    /// they go (streamed in odd steps); lanes that are not `live` are left alone.
    ///
    /// # Safety
    /// As [`Lattice::sweep_row_generic`].
    #[inline(always)]
    pub(super) unsafe fn scatter(
        &self,
        path: Path,
        x0: usize,
        lanes: usize,
        slow: bool,
        live: &[bool; LANES],
        blk: &[[f64; LANES]; Q],
    ) {
        let (f, nx) = (self.f, self.nx);
        let (wr_row, wr_dx) = (&self.wr_row, &self.wr_dx);
        match path {
            Path::Vector => {
                for i in 0..Q {
                    T::store_block(f.add(wr_row[i] + x0).offset(wr_dx[i] as isize), &blk[i], i);
                }
            }
            Path::Edge => {
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
            }
            Path::Lanes => {
                for i in (0..Q).map(std::hint::black_box) {
                    for l in 0..lanes {
                        if live[l] {
                            let (at, wall) = self.slot::<false>(i, x0 + l, slow);
                            *f.add(at) = T::put(blk[i][l] - wall, i);
                        }
                    }
                }
            }
        }
    }
}
