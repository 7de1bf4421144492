//! Lubrication: the normal force of the liquid film between two bodies closing in (or drawn
//! in as they part), for gaps too thin for a fluid solver to resolve.
//!
//! Two smooth bodies a gap `h` apart, closing at speed `v`, squeeze the film out with the
//! force (leading order in `h/R*`)
//!
//! ```text
//! F(h) = 6π μ R*² v / h,        R* = R_A R_B / (R_A + R_B)
//! ```
//!
//! — Brenner (1961) for a sphere and a plane (`R* = R`), Cox (1974) for two spheres of
//! radii `R_A`, `R_B`. A lattice of spacing `Δx` resolves the film down to a gap of the
//! order of `Δx` and puts its own share of the force on the bodies there; below that, this
//! force stands in for what it misses, as in Kempe & Fröhlich (2012):
//!
//! ```text
//! F = 6π μ R*² v (1/h − 1/h_c)     for h_min ≤ h < h_c   (zero at and beyond the cut-off h_c)
//! F = 6π μ R*² v (1/h_min − 1/h_c) for h < h_min          (roughness: the film stops thinning)
//! ```
//!
//! so the total is Brenner's at every resolution and continuous in `h`; it never acts on a
//! body at rest relative to the other, and it always opposes the relative normal motion (it
//! dissipates, never creates energy). Below `h_min` the gap is held at `h_min`, also while the
//! bodies touch, so the film's damping carries smoothly into the contact.
//!
//! **Shapes.** `R_A`, `R_B` are the radii of curvature at the closest points: exact for balls,
//! capsules (their ends and sides alike take the capsule's radius) and half-spaces (infinite,
//! so a ball on a wall has `R* = R`). For other shapes [`film_radius`] takes the radius of the
//! bounding sphere — an approximation for the film between a curved body and another body;
//! flat faces closing face to face (a much stiffer film, `∝ 1/h³`) are not modelled.
//!
//! References: H. Brenner (1961), Chem. Eng. Sci. 16, 242–251; R. G. Cox (1974), Int. J.
//! Multiphase Flow 1, 343–371; T. Kempe & J. Fröhlich (2012), J. Fluid Mech. 709, 445–489.

use core::f64::consts::PI;
use std::ops::Bound::Excluded;

use crate::error::{check_positive, check_range, Result};
use crate::math::Real;
use crate::shape::ConvexShape;

/// The lubrication law of one liquid: viscosity, cut-off gap and minimum gap.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct Lubrication {
    viscosity: Real,
    cutoff: Real,
    min_gap: Real,
}

impl Lubrication {
    /// The film force of a liquid of dynamic viscosity `viscosity` (Pa s, > 0), acting below
    /// the gap `cutoff` (m, finite and > 0: the gap the fluid solver resolves; pairs farther
    /// apart are not looked at), with the gap held at `min_gap` (m, `0 < min_gap < cutoff`:
    /// surface roughness) below it.
    pub fn new(viscosity: Real, cutoff: Real, min_gap: Real) -> Result<Self> {
        check_positive("viscosity", viscosity)?;
        check_positive("cutoff", cutoff)?;
        check_range("min_gap", min_gap, (Excluded(0.0), Excluded(cutoff)), "0 < min_gap < cutoff")?;
        Ok(Self { viscosity, cutoff, min_gap })
    }

    /// Dynamic viscosity (Pa s).
    pub fn viscosity(&self) -> Real {
        self.viscosity
    }

    /// The gap (m) at and beyond which the film force is zero.
    pub fn cutoff(&self) -> Real {
        self.cutoff
    }

    /// The smallest gap (m) the force is computed at.
    pub fn min_gap(&self) -> Real {
        self.min_gap
    }

    /// The film's normal force (N) at gap `gap` (m; negative while the bodies overlap) for
    /// bodies closing at `closing_speed` (m/s; negative while they part) with reduced radius
    /// `reduced_radius` (m, see [`reduced_radius`]): positive pushes them apart, negative
    /// pulls them together. Zero for `gap >= cutoff`.
    pub fn normal_force(&self, gap: Real, closing_speed: Real, reduced_radius: Real) -> Real {
        if !(gap < self.cutoff) {
            return 0.0;
        }
        let h = gap.max(self.min_gap);
        6.0 * PI
            * self.viscosity
            * reduced_radius
            * reduced_radius
            * closing_speed
            * (1.0 / h - 1.0 / self.cutoff)
    }

    /// The largest damping coefficient `dF/dv` (N s/m) the film reaches, at `min_gap`: what
    /// an explicit time step must resolve (`Δt` well below `m*/c`).
    pub fn max_damping(&self, reduced_radius: Real) -> Real {
        self.normal_force(self.min_gap, 1.0, reduced_radius)
    }
}

/// The radius of curvature (m) a body's film sees at its surface: a ball's and a capsule's
/// radius, infinite for a half-space; for other shapes the bounding radius (see the module
/// notes).
pub fn film_radius(shape: &ConvexShape) -> Real {
    match shape {
        ConvexShape::Ball { radius } | ConvexShape::Capsule { radius, .. } => *radius,
        ConvexShape::HalfSpace { .. } => Real::INFINITY,
        other => crate::shape::Sdf::bounding_sphere(other).1,
    }
}

/// `R* = R_A R_B / (R_A + R_B)` (m) of two radii of curvature, either possibly infinite (a
/// plane): `R_B` for `R_A = ∞`, infinite for two planes.
pub fn reduced_radius(r_a: Real, r_b: Real) -> Real {
    1.0 / (1.0 / r_a + 1.0 / r_b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brenner's force less its value at the cut-off, zero beyond it, held below the minimum
    /// gap; odd in the closing speed (it always opposes the motion).
    #[test]
    fn the_film_force_is_brenners_less_the_resolved_part() {
        let (mu, r) = (0.1, 3e-3);
        let lub = Lubrication::new(mu, 1e-4, 1e-6).unwrap();
        for h in [2e-6, 1e-5, 5e-5, 9e-5] {
            let brenner = 6.0 * PI * mu * r * r * 0.3 / h;
            let at_cutoff = 6.0 * PI * mu * r * r * 0.3 / 1e-4;
            let f = lub.normal_force(h, 0.3, r);
            assert!((f - (brenner - at_cutoff)).abs() <= 1e-12 * brenner, "h = {h}: {f}");
            assert_eq!(lub.normal_force(h, -0.3, r), -f);
        }
        assert_eq!(lub.normal_force(1e-4, 0.3, r), 0.0);
        assert_eq!(lub.normal_force(1.0, 0.3, r), 0.0);
        assert_eq!(lub.normal_force(-1e-5, 0.3, r), lub.normal_force(1e-6, 0.3, r));
        assert_eq!(lub.max_damping(r), lub.normal_force(1e-6, 1.0, r));
        // Continuous at the cut-off.
        assert!(lub.normal_force(1e-4 * (1.0 - 1e-9), 0.3, r).abs() < 1e-6);
    }

    #[test]
    fn bad_parameters_are_refused_by_name() {
        for (args, name) in [
            ((0.0, 1e-4, 1e-6), "viscosity"),
            ((0.1, -1.0, 1e-6), "cutoff"),
            ((0.1, 1e-4, 1e-4), "min_gap"),
            ((0.1, 1e-4, 0.0), "min_gap"),
            ((0.1, Real::NAN, 1e-6), "cutoff"),
            ((0.1, Real::INFINITY, 1e-6), "cutoff"),
        ] {
            match Lubrication::new(args.0, args.1, args.2) {
                Err(crate::Error::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{args:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn radii_of_curvature() {
        let ball = ConvexShape::ball(0.002).unwrap();
        let wall = ConvexShape::half_space(crate::math::Vector::Z).unwrap();
        assert_eq!(reduced_radius(film_radius(&ball), film_radius(&wall)), 0.002);
        assert_eq!(reduced_radius(film_radius(&ball), film_radius(&ball)), 0.001);
    }
}
