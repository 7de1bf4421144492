//! The one place where physical units meet lattice units.

use crate::error::{Error, Result};

/// Mach-number guard: lattice speeds above this (≈ 0.17 c_s… here 0.1 in lattice units, Ma ≈ 0.17)
/// make the compressibility error noticeable.
pub const MACH_LIMIT_LATTICE_SPEED: f64 = 0.1;

/// Converts between SI and lattice units from `Δx` (m), `Δt` (s), kinematic viscosity `ν`
/// (m²/s) and density `ρ` (kg/m³).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct UnitConverter {
    dx: f64,
    dt: f64,
    nu: f64,
    rho: f64,
    tau: f64,
}

impl UnitConverter {
    /// From `Δx`, `Δt`, `ν`, `ρ`; refuses `τ = 0.5 + 3 ν Δt / Δx² <= 0.5` or non-positive input.
    pub fn new(dx: f64, dt: f64, nu: f64, rho: f64) -> Result<Self> {
        for (name, v) in [("dx", dx), ("dt", dt), ("nu", nu), ("rho", rho)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::InvalidParameter { name, value: v, allowed: "finite and > 0" });
            }
        }
        let tau = 0.5 + 3.0 * nu * dt / (dx * dx);
        if !(tau > 0.5 + 1e-12) {
            return Err(Error::InvalidParameter {
                name: "tau",
                value: tau,
                allowed: "tau > 0.5 (raise dt or nu, or lower dx)",
            });
        }
        Ok(Self { dx, dt, nu, rho, tau })
    }

    /// From `Δx`, `τ`, `ν`, `ρ`: `Δt = (τ - 0.5) Δx² / (3 ν)`.
    pub fn from_tau(dx: f64, tau: f64, nu: f64, rho: f64) -> Result<Self> {
        if !(tau > 0.5 && tau.is_finite()) {
            return Err(Error::InvalidParameter { name: "tau", value: tau, allowed: "tau > 0.5" });
        }
        Self::new(dx, (tau - 0.5) * dx * dx / (3.0 * nu), nu, rho)
    }

    /// Relaxation time.
    pub fn tau(&self) -> f64 {
        self.tau
    }
    /// Lattice spacing (m).
    pub fn dx(&self) -> f64 {
        self.dx
    }
    /// Time step (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }
    /// Kinematic viscosity (m²/s).
    pub fn viscosity(&self) -> f64 {
        self.nu
    }
    /// Fluid density (kg/m³).
    pub fn density(&self) -> f64 {
        self.rho
    }
    /// m/s → lattice.
    pub fn velocity_to_lattice(&self, v: f64) -> f64 {
        v * self.dt / self.dx
    }
    /// lattice → m/s.
    pub fn velocity_to_physical(&self, v: f64) -> f64 {
        v * self.dx / self.dt
    }
    /// m/s² → lattice.
    pub fn acceleration_to_lattice(&self, a: f64) -> f64 {
        a * self.dt * self.dt / self.dx
    }
    /// Lattice momentum per step (ρ = 1 units) → N.
    pub fn force_to_physical(&self, f: f64) -> f64 {
        f * self.rho * self.dx.powi(4) / (self.dt * self.dt)
    }
    /// Lattice moment per step → N m.
    pub fn torque_to_physical(&self, t: f64) -> f64 {
        self.force_to_physical(t) * self.dx
    }
    /// m → lattice.
    pub fn length_to_lattice(&self, l: f64) -> f64 {
        l / self.dx
    }
    /// A warning when the physical speed `v` maps above [`MACH_LIMIT_LATTICE_SPEED`].
    pub fn mach_warning(&self, v: f64) -> Option<String> {
        let u = self.velocity_to_lattice(v).abs();
        (u > MACH_LIMIT_LATTICE_SPEED).then(|| {
            format!("lattice speed {u:.3} for {v} m/s exceeds {MACH_LIMIT_LATTICE_SPEED}: compressibility errors grow as u²; lower dt")
        })
    }
}
