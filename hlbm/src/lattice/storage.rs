//! How the populations are stored: f64 or weight-shifted f32 ([`Storage`], [`Pop`]), in
//! cache-line-aligned arrays ([`Lines`], [`population_stride`]); and reading and writing single
//! populations in the A-A layout (initialisation, inspection, conversion between storages).

use super::{dot, Lattice};
use crate::d3q19::{equilibrium, C, LANES, OPP, Q, W};

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
    pub(super) fn bytes(self) -> usize {
        match self {
            Self::F64 => 8,
            Self::F32 => 4,
        }
    }
}

/// A stored population: f64 as is, f32 shifted by its weight. (Lane loops are written out
/// with indices, as in the sweep: that form vectorises across the lanes.)
pub(super) trait Pop: Copy + Send + Sync + 'static {
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

/// One cache line of populations (raw bits: 8 f64 or 16 f32), aligned so a block loads as one
/// aligned vector.
#[derive(Clone, Copy)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(C, align(64))]
struct Line([u64; 8]);

/// The populations, stored in cache-line-aligned lines and viewed as one slice of the storage
/// type.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(super) struct Lines(Vec<Line>);

impl Lines {
    /// Lines for `values` stored values of `T`.
    pub(super) fn new<T: Pop>(values: usize) -> Self {
        Lines(vec![Line([0; 8]); (values * std::mem::size_of::<T>()).div_ceil(64)])
    }

    /// The stored values, as `T`.
    pub(super) fn as_slice<T: Pop>(&self) -> &[T] {
        // SAFETY: `Line` is `repr(C)` over 64 bytes with no padding, aligned to 64; f64 and f32
        // have no invalid bit patterns.
        unsafe {
            std::slice::from_raw_parts(
                self.0.as_ptr().cast(),
                self.0.len() * 64 / std::mem::size_of::<T>(),
            )
        }
    }

    /// The stored values, as `T`, to write.
    pub(super) fn as_mut_slice<T: Pop>(&mut self) -> &mut [T] {
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
/// line and a block of cells at `x0 % LANES == 0` is one aligned vector. (With the allocator's
/// 16-byte alignment alone, every 64-byte vector load would straddle two lines.)
pub(super) fn population_stride(n: usize, size: usize) -> usize {
    let per_line = 64 / size;
    n.div_ceil(per_line) * per_line
}

impl Lattice {
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
}
