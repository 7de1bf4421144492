//! Runtime instruction-set dispatch. The hot loops — the sweep's row
//! ([`Lattice::sweep_row_generic`]) and the link finder's row pass ([`row_links_generic`]) —
//! are compiled once per instruction set ([`SimdLevel`]), and each call takes the best one
//! this CPU has, so a portable build still runs AVX2 or AVX-512 code where the CPU has it.

use super::links::row_links_generic;
use super::storage::Pop;
use super::sweep::{MacroPtr, Ptr};
use super::{Lattice, SlabResult};

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

impl Lattice {
    /// Sweeps one row with the best instruction set this CPU has (detected once).
    ///
    /// # Safety
    /// As [`Lattice::sweep_row_generic`].
    #[inline]
    pub(super) unsafe fn sweep_row<T: Pop>(
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
}

/// Appends to `masks` the links of the particle nodes `nodes` (`x` and body index, sorted by
/// `x`) of row `(y, z)`, read off the owner field; `span` is scratch of length `nx`. Compiled
/// for the best instruction set this CPU has (the compares vectorise: wider vectors compare
/// more nodes per instruction).
#[inline]
pub(super) fn row_links(
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
