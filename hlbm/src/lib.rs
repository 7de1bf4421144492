//! # hlbm
//!
//! A minimal, fast D3Q19 homogenized lattice Boltzmann solver for particle-resolved flows:
//! BGK collision fused with streaming in the in-place A-A pattern, exact-difference (EDM)
//! forcing for a body force and for particles given as a solid-fraction field `d_B`, the
//! particles' hydrodynamic force and moment gathered in the same sweep (Wen et al.'s link-wise
//! momentum exchange, or the forcing's own momentum: [`ForceMethod`]), halfway bounce-back
//! walls (moving allowed), periodic boundaries, one unit converter, NaN/runaway detection and
//! VTK output. Populations are f64 by default; [`Storage::F32`] stores them as shifted f32
//! (half the memory and bandwidth, as accurate for these flows; see `hlbm/PERFORMANCE.md`).
//!
//! ```
//! use hlbm::{Lattice, UnitConverter};
//! let units = UnitConverter::from_tau(1e-3, 0.8, 1e-6, 1000.0)?;
//! let mut lat = Lattice::new(16, 16, 16, units.tau())?;
//! lat.set_body_acceleration([units.acceleration_to_lattice(1e-5), 0.0, 0.0]); // 1e-4 per step
//! lat.close_faces([true, true, false]);           // walls at z = 0 and z = 15
//! lat.run(10)?;
//! # Ok::<(), hlbm::Error>(())
//! ```

#![warn(missing_docs)]

pub mod correlations;
pub mod d3q19;
pub mod error;
pub mod lattice;
pub mod particles;
pub mod units;
pub mod vtk;

pub use error::{Error, Result};
pub use lattice::{
    simd_level, ForceMethod, Lattice, Macroscopic, NodeKind, ParticleForce, SimdLevel, StepReport,
    Storage,
};
pub use particles::{solid_fraction, ParticleBody, ParticleField, ParticleNode, SlabRows};
pub use units::UnitConverter;
