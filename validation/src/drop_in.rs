//! An ordinary rapier scene for the drop-in demonstration and its benchmark: a bin (half-space
//! floor and four cuboid walls on a fixed body) filled from above with a mix of spheres,
//! cylinders, cubes and convex polyhedra, and a see-saw plank on a revolute joint in the middle
//! of the floor. Nothing in it knows about the discrete contact: the same world runs with
//! rapier's own contacts or with the drop-in's `DiscreteContacts`.
//!
//! The scene and its run exist for both rapier builds: rapier3d-f64 (the items re-exported
//! here) and rapier3d, f32 ([`mod@f32`]).

use discrete_contact::error::Result;
use discrete_contact::material::Material;
use discrete_contact::math::{Real, Vector};

/// Size of the bodies (m): spheres of this radius; the other shapes have similar volume.
pub const BODY_RADIUS: Real = 0.01;
/// Density of every body (kg/m³).
pub const DENSITY: Real = 1000.0;
/// Friction coefficient of rapier's own contacts (the discrete run sets its own law).
pub const RAPIER_FRICTION: Real = 0.4;
/// Restitution of rapier's own contacts.
pub const RAPIER_RESTITUTION: Real = 0.5;

/// Restitution of the discrete contacts.
pub const RESTITUTION: Real = 0.5;

/// The bodies' material for the discrete contacts: a rubber, E = 5 MPa, ν = 0.4.
pub fn rubber() -> Result<Material> {
    Material::new(5e6, 0.4)
}

/// A uniform sequence on [0, 1) from xorshift64 started at `seed`: portable and fixed, so a
/// scene is the same on every machine.
pub fn xorshift(mut seed: u64) -> impl FnMut() -> Real {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as Real / (1u64 << 53) as Real
    }
}

/// The scene's rock about its centre: twelve points in directions drawn from `random`, each at
/// 0.85–1.15 `r` (their convex hull is the rock).
pub fn rock_points(r: Real, random: &mut impl FnMut() -> Real) -> Vec<Vector> {
    (0..12)
        .map(|_| {
            let p = Vector::new(random() - 0.5, random() - 0.5, random() - 0.5);
            p.normalize_or(Vector::X) * r * (0.85 + 0.3 * random())
        })
        .collect()
}

/// What a run of the scene does: bodies, simulated time and the discrete contact's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Falling bodies.
    pub bodies: usize,
    /// Simulated time (s).
    pub seconds: Real,
    /// Sub-steps per Hertz contact time.
    pub per_contact: Real,
    /// Sub-cell grid resolution `N_c`.
    pub n_c: usize,
    /// The exact forms where they exist (closed-form spheres, exact polyhedra).
    pub exact: bool,
    /// The balls' facet layer (`OverlapSettings::with_facet_bulge`; on by default).
    pub facet_bulge: bool,
    /// Geometry reuse fraction (0: every evaluation in full).
    pub reuse: Real,
    /// Rapier's `integration_parameters.length_unit` (m) in both runs: its broad phase fattens
    /// every collider's box by 4 % of it, so at the default 1 m each of the centimetre bodies
    /// is paired with most others (~14 000 pairs) and every rapier step walks them all.
    pub length_unit: Real,
}

/// What a run measured: rapier's own contacts and the discrete ones, and the discrete run's
/// report rows (`t, KE, contacts, sub-steps per step, full evaluations per contact and step,
/// largest overlap, wall time`, comma-separated).
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Kinetic energy at the end with rapier's own contacts (J).
    pub rapier_ke: Real,
    /// Largest penetration of rapier's own contacts (m).
    pub rapier_penetration: Real,
    /// Wall time with rapier's own contacts (s).
    pub rapier_wall: Real,
    /// Colliders handed to the discrete contact.
    pub handled: usize,
    /// Kinetic energy at the end with the discrete contacts (J).
    pub ke: Real,
    /// Largest overlap of the discrete contacts (m).
    pub max_indentation: Real,
    /// Sub-steps in all.
    pub substeps: usize,
    /// Contact evaluations in all.
    pub evaluations: usize,
    /// The full evaluations among them, by why each was full (`refreshes.total()` in all).
    pub refreshes: discrete_contact::contact::Refreshes,
    /// Wall time with the discrete contacts (s).
    pub wall: Real,
    /// The discrete run's report rows.
    pub rows: Vec<String>,
}

/// The scene in rapier3d-f64.
mod in_f64;
pub use in_f64::scene::*;

/// The scene in rapier3d (f32): the same items as for rapier3d-f64.
pub mod f32 {
    pub use super::in_f32::scene::*;
}
mod in_f32;
