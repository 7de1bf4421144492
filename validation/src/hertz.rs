//! The eight static Hertz cases of Marquardt et al. §4.1 / Fig. 3.
//!
//! Body A is elastic (`E_A = 0.01 GPa, ν_A = 0.5`), body B stiff (`E_B = 200 GPa, ν_B = 0.3`).
//! A is pushed into B along `+y` by the indentation `d`; the force is compared with Hertz
//! (sphere–half-space, sphere–sphere, crossed cylinders) or the flat punch.
//! The rough box is the intersection of the bodies' bounding boxes, as at first touch.

use std::f64::consts::FRAC_PI_2;

use discrete_contact::error::Result;
use discrete_contact::force::normal_force;
use discrete_contact::material::{effective_modulus, Material, PairParameters, StiffnessFactor};
use discrete_contact::math::{Pose, Real, Rotation, Vector};
use discrete_contact::overlap::{compute_overlap, OverlapGeometry, OverlapSettings};
use discrete_contact::shape::ConvexShape;

/// Largest indentation of the sweep (m).
pub const MAX_INDENTATION: Real = 0.05;
/// Number of indentations in the sweep (`d = 0` excluded).
pub const SWEEP_POINTS: usize = 20;

/// One of the Hertz validation cases.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HertzCase {
    /// Sphere of radius `r` on a half-space: `F = 4/3 E* sqrt(r) d^1.5`.
    SphereHalfSpace {
        /// Sphere radius (m).
        r: Real,
    },
    /// Two spheres: as above with `R = (1/r1 + 1/r2)^-1`.
    SphereSphere {
        /// Radius of A (m).
        r1: Real,
        /// Radius of B (m).
        r2: Real,
    },
    /// Flat cylindrical punch of radius `r` on a half-space: `F = 2 r E* d`.
    Punch {
        /// Punch radius (m).
        r: Real,
    },
    /// Two perpendicular cylinders of equal radius `r`: as sphere–half-space with `r`.
    CrossedCylinders {
        /// Cylinder radius (m).
        r: Real,
    },
}

impl HertzCase {
    /// The eight cases of Marquardt et al. Fig. 3, in its order.
    pub fn all() -> [HertzCase; 8] {
        [
            Self::SphereHalfSpace { r: 1.0 },
            Self::SphereHalfSpace { r: 2.0 },
            Self::SphereSphere { r1: 1.0, r2: 1.0 },
            Self::SphereSphere { r1: 1.0, r2: 2.0 },
            Self::Punch { r: 1.0 },
            Self::Punch { r: 2.0 },
            Self::CrossedCylinders { r: 1.0 },
            Self::CrossedCylinders { r: 2.0 },
        ]
    }

    /// The case's name in the CSV files, e.g. `sphere_sphere_r1_r2`.
    pub fn name(&self) -> String {
        match *self {
            Self::SphereHalfSpace { r } => format!("sphere_halfspace_r{r}"),
            Self::SphereSphere { r1, r2 } => format!("sphere_sphere_r{r1}_r{r2}"),
            Self::Punch { r } => format!("punch_r{r}"),
            Self::CrossedCylinders { r } => format!("crossed_cyl_r{r}"),
        }
    }

    /// The materials of Marquardt et al. §4.1: (A, B).
    pub fn materials() -> (Material, Material) {
        (Material::new(0.01e9, 0.5).expect("valid"), Material::new(200e9, 0.3).expect("valid"))
    }

    /// Effective modulus of the case's materials (Pa).
    pub fn effective_modulus() -> Real {
        let (a, b) = Self::materials();
        effective_modulus(&a, &b)
    }

    /// `k`: flat punch for the punch, curved otherwise.
    pub fn stiffness(&self) -> StiffnessFactor {
        match self {
            Self::Punch { .. } => StiffnessFactor::FlatPunch,
            _ => StiffnessFactor::Curved,
        }
    }

    /// Force-law parameters (frictionless, `e = 1`: the static sweep has no velocity).
    pub fn parameters(&self) -> PairParameters {
        let (a, b) = Self::materials();
        PairParameters::new(&a, &b, 1.0)
            .expect("valid")
            .with_stiffness(self.stiffness())
            .expect("valid")
    }

    /// Shapes of A and B.
    pub fn shapes(&self) -> (ConvexShape, ConvexShape) {
        let ok = |s: Result<ConvexShape>| s.expect("valid case geometry");
        match *self {
            Self::SphereHalfSpace { r } => {
                (ok(ConvexShape::ball(r)), ok(ConvexShape::half_space(Vector::Y)))
            }
            Self::SphereSphere { r1, r2 } => (ok(ConvexShape::ball(r1)), ok(ConvexShape::ball(r2))),
            Self::Punch { r } => {
                (ok(ConvexShape::cylinder(r, r)), ok(ConvexShape::half_space(Vector::Y)))
            }
            Self::CrossedCylinders { r } => {
                (ok(ConvexShape::cylinder(4.0 * r, r)), ok(ConvexShape::cylinder(4.0 * r, r)))
            }
        }
    }

    /// Poses of A and B at indentation `d`; B sits at the origin, A above it along `+y`.
    pub fn poses(&self, d: Real) -> (Pose, Pose) {
        let up = |h: Real| Vector::new(0.0, h - d, 0.0);
        match *self {
            Self::SphereHalfSpace { r } | Self::Punch { r } => {
                (Pose::from_translation(up(r)), Pose::IDENTITY)
            }
            Self::SphereSphere { r1, r2 } => (Pose::from_translation(up(r1 + r2)), Pose::IDENTITY),
            Self::CrossedCylinders { r } => (
                Pose::from_parts(up(2.0 * r), Rotation::from_rotation_z(FRAC_PI_2)),
                Pose::from_parts(Vector::ZERO, Rotation::from_rotation_x(FRAC_PI_2)),
            ),
        }
    }

    /// The analytical force at indentation `d` (N).
    pub fn analytic_force(&self, d: Real) -> Real {
        let e = Self::effective_modulus();
        let hertz = |r: Real| 4.0 / 3.0 * e * r.sqrt() * d.powf(1.5);
        match *self {
            Self::SphereHalfSpace { r } | Self::CrossedCylinders { r } => hertz(r),
            Self::SphereSphere { r1, r2 } => hertz(1.0 / (1.0 / r1 + 1.0 / r2)),
            Self::Punch { r } => 2.0 * r * e * d,
        }
    }

    /// The indentation sweep: `SWEEP_POINTS` values up to `MAX_INDENTATION`, `d = 0` left out.
    pub fn indentations() -> Vec<Real> {
        (1..=SWEEP_POINTS).map(|i| MAX_INDENTATION * i as Real / SWEEP_POINTS as Real).collect()
    }

    /// Overlap geometry at indentation `d` from the bodies' bounding boxes.
    pub fn geometry(&self, settings: &OverlapSettings, d: Real) -> Result<Option<OverlapGeometry>> {
        let (a, b) = self.shapes();
        let (pa, pb) = self.poses(d);
        compute_overlap(&a, &pa, &b, &pb, settings, None)
    }

    /// The model's static force at indentation `d` (N); zero when the grid finds no overlap.
    pub fn force(&self, settings: &OverlapSettings, d: Real) -> Result<Real> {
        let params = self.parameters();
        Ok(self.geometry(settings, d)?.map_or(0.0, |g| normal_force(&params, 0.0, &g, 0.0)))
    }

    /// RMS relative error of the force over the sweep.
    pub fn rms_relative_error(&self, settings: &OverlapSettings) -> Result<Real> {
        let ds = Self::indentations();
        let mut sum = 0.0;
        for &d in &ds {
            let f = self.force(settings, d)?;
            let rel = (f - self.analytic_force(d)) / self.analytic_force(d);
            sum += rel * rel;
        }
        Ok((sum / ds.len() as Real).sqrt())
    }
}
