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
//! **Shapes.** `R_A`, `R_B` are the radii of curvature at the closest points
//! ([`film_radius_at`]): exact for balls, capsules (their ends and sides alike take the
//! capsule's radius) and half-spaces (infinite, so a ball on a wall has `R* = R`). Other shapes
//! take the mean radius of curvature `2/(κ₁ + κ₂)` there, measured over a twentieth of the
//! body's bounding radius along the surface and at most that radius: a cylinder's side `2R`,
//! an edge or a corner a small fraction of the bounding radius (little film), a flat face the
//! bounding radius. That is an approximation twice over: Brenner's form holds for a round gap
//! (an elongated one is stated by its mean radius), and flat faces closing face to face (a
//! much stiffer film, `∝ 1/h³`) are taken as a sphere of the bounding radius.
//!
//! **Sliding and rolling** ([`Lubrication::with_shear`], off by default). Bodies moving
//! along the gap, or turning, shear the film; its force grows only as `ln(1/h)`. For a body A
//! (radius of curvature `R_A`, centre of curvature `c_A`) next to B (`λ = R_B/R_A`), in the
//! frame where B is at rest (`U` the velocity of A's centre of curvature less B's rigid motion
//! there, `Ω` the angular velocities' difference, `d` the unit normal from A to B, `P = I − d
//! d^T`), the leading-log terms of Jeffrey & Onishi (1984) give, with `L = ln(h_c/h)`:
//!
//! ```text
//! F_A = −μ L [6π R_A Y_A(λ) P U − 4π R_A² Y_B(λ) Ω × d]
//! T_A = −μ L [4π R_A² Y_B(λ) U × d + 8π R_A³ Y_C(λ) P Ω]        (about c_A)
//! Y_A = 4λ(2 + λ + 2λ²) / (15 (1+λ)³),  Y_B = −λ(4 + λ) / (5 (1+λ)²),  Y_C = 2λ / (5 (1+λ))
//! ```
//!
//! — for a plane (`λ → ∞`) Goldman, Cox & Brenner's (1967) `8/15`, `−1/5`, `2/5`. B takes `−F_A`
//! and the torque that keeps the pair's angular momentum (the film's terms at this order do;
//! for two spheres it is Jeffrey & Onishi's torque on B). The terms form a symmetric,
//! positive semi-definite resistance, so they only dissipate; they vanish for a common rigid
//! motion. The same cut-off and minimum gap as the normal force; the lattice resolves the rest.
//! A spin about the normal has no singular term and is left to the lattice.
//!
//! References: H. Brenner (1961), Chem. Eng. Sci. 16, 242–251; R. G. Cox (1974), Int. J.
//! Multiphase Flow 1, 343–371; A. J. Goldman, R. G. Cox & H. Brenner (1967), Chem. Eng. Sci. 22,
//! 637–651; D. J. Jeffrey & Y. Onishi (1984), J. Fluid Mech. 139, 261–290,
//! doi:10.1017/S0022112084000355; T. Kempe & J. Fröhlich (2012), J. Fluid Mech. 709, 445–489.

use core::f64::consts::PI;
use std::ops::Bound::Excluded;

use crate::error::{check_positive, check_range, Result};
use crate::force::BodyKinematics;
use crate::math::{Real, Vector};
use crate::shape::ConvexShape;

/// The lubrication law of one liquid: viscosity, cut-off gap and minimum gap.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct Lubrication {
    viscosity: Real,
    cutoff: Real,
    min_gap: Real,
    #[cfg_attr(feature = "checkpoint", serde(default))]
    shear: bool,
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
        Ok(Self { viscosity, cutoff, min_gap, shear: false })
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
        let Some(h) = self.acting_gap(gap) else { return 0.0 };
        6.0 * PI
            * self.viscosity
            * reduced_radius
            * reduced_radius
            * closing_speed
            * (1.0 / h - 1.0 / self.cutoff)
    }

    /// The largest damping coefficient `dF/dv` (N s/m) the film reaches, at `min_gap`: what
    /// an explicit time step must resolve (`Δt` well below `m*/c`). The sliding terms' are
    /// smaller by `~ (h_min/R*) ln(h_c/h_min)`.
    pub fn max_damping(&self, reduced_radius: Real) -> Real {
        self.normal_force(self.min_gap, 1.0, reduced_radius)
    }

    /// The same law with (`true`) or without (`false`, the default) the film's sliding and
    /// rolling terms (see the module notes).
    pub fn with_shear(mut self, on: bool) -> Self {
        self.shear = on;
        self
    }

    /// Whether the sliding and rolling terms act.
    pub fn shear(&self) -> bool {
        self.shear
    }

    /// `ln(h_c/h)` with the gap held at `min_gap`; zero at and beyond the cut-off.
    fn log_factor(&self, gap: Real) -> Real {
        self.acting_gap(gap).map_or(0.0, |h| (self.cutoff / h).ln())
    }

    /// The gap the film acts across: `gap` held at `min_gap` below it; `None` at and beyond
    /// the cut-off (and for a gap that is not a number).
    fn acting_gap(&self, gap: Real) -> Option<Real> {
        (gap < self.cutoff).then(|| gap.max(self.min_gap))
    }

    /// The film's sliding and rolling terms on a pair a gap `gap` (m) apart at the point `x`,
    /// `normal` the unit normal out of A towards B, `radii` each body's radius of curvature
    /// there (m, [`film_radius`]; infinite for a plane), `bodies` their motions: the force on
    /// A (N; B takes minus it) and the torques on A and on B about their centres of mass (N m).
    /// Zero without [`Lubrication::with_shear`], beyond the cut-off, or for two planes.
    pub fn shear_force(
        &self,
        gap: Real,
        x: Vector,
        normal: Vector,
        radii: (Real, Real),
        bodies: (&BodyKinematics, &BodyKinematics),
    ) -> (Vector, Vector, Vector) {
        let l = self.log_factor(gap);
        if !self.shear || l == 0.0 || radii.0.is_infinite() && radii.1.is_infinite() {
            return (Vector::ZERO, Vector::ZERO, Vector::ZERO);
        }
        // The terms are written for the curved body in the plane's frame; a plane as A swaps.
        let swap = radii.0.is_infinite();
        let (r, r_other, d, (a, b)) = if swap {
            (radii.1, radii.0, -normal, (bodies.1, bodies.0))
        } else {
            (radii.0, radii.1, normal, bodies)
        };
        // The centres of curvature `r` from the gap's middle on either side (not `r + h/2`: at
        // this order the gap is nothing against the radii, and so the result does not depend
        // on which body is A).
        let centre = x - r * d;
        let rigid = |k: &BodyKinematics, p: Vector| k.linvel + k.angvel.cross(p - k.center_of_mass);
        let u = rigid(a, centre) - rigid(b, centre);
        let omega = a.angvel - b.angvel;
        let tangential = |v: Vector| v - v.dot(d) * d;
        let (ya, yb, yc) = shear_coefficients(r_other / r);
        let mu_l = self.viscosity * l;
        let force =
            -mu_l * (6.0 * PI * r * ya * tangential(u) - 4.0 * PI * r * r * yb * omega.cross(d));
        let torque = -mu_l
            * (4.0 * PI * r * r * yb * u.cross(d) + 8.0 * PI * r * r * r * yc * tangential(omega));
        // About A's centre of mass; B's keeps the pair's angular momentum.
        let torque_a = torque + (centre - a.center_of_mass).cross(force);
        let torque_b = -torque_a - (a.center_of_mass - b.center_of_mass).cross(force);
        if swap {
            (-force, torque_b, torque_a)
        } else {
            (force, torque_a, torque_b)
        }
    }
}

/// Jeffrey & Onishi's (1984) leading-log coefficients `(Y_A, Y_B, Y_C)` of the film's
/// tangential resistance on a sphere next to one `λ` times its radius (`λ = ∞`: a plane).
fn shear_coefficients(lambda: Real) -> (Real, Real, Real) {
    if lambda.is_infinite() {
        return (8.0 / 15.0, -1.0 / 5.0, 2.0 / 5.0);
    }
    let p = 1.0 + lambda;
    (
        4.0 * lambda * (2.0 + lambda + 2.0 * lambda * lambda) / (15.0 * p * p * p),
        -lambda * (4.0 + lambda) / (5.0 * p * p),
        2.0 * lambda / (5.0 * p),
    )
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

/// The radius of curvature (m) a body's film sees at `point` (body frame, on its surface):
/// a ball's and a capsule's radius, infinite for a half-space; for other shapes the mean radius
/// of curvature there, at most the bounding radius (see the module notes). Never more than
/// [`film_radius`], so the time-step advice taken from that holds.
pub fn film_radius_at(shape: &ConvexShape, point: Vector) -> Real {
    use crate::shape::Sdf;
    let bound = film_radius(shape);
    if matches!(
        shape,
        ConvexShape::Ball { .. } | ConvexShape::Capsule { .. } | ConvexShape::HalfSpace { .. }
    ) {
        return bound;
    }
    let n = shape.gradient(point);
    if !n.is_finite() || n == Vector::ZERO {
        return bound;
    }
    let (t1, t2) = n.any_orthonormal_pair();
    let step = CURVATURE_STEP * bound;
    // The normal's slope against `t` a step away along `t`: `tan θ = step/R` on a circle of
    // radius `R` (exact there), unbounded where the normal has turned by a right angle.
    let slope = |t: Vector, at: Vector| {
        let g = shape.gradient(at);
        let along = g.dot(n);
        if along > 1e-9 {
            g.dot(t) / along
        } else {
            Real::INFINITY
        }
    };
    let bend = |t: Vector| slope(t, point + step * t) + slope(-t, point - step * t);
    // κ₁ + κ₂: each direction's two slopes are its curvature times 2 step.
    let twice_mean = (bend(t1) + bend(t2)) / (2.0 * step);
    if twice_mean * bound > 2.0 {
        2.0 / twice_mean
    } else {
        bound
    }
}

/// The step along the surface over which [`film_radius_at`] measures the curvature, as a
/// fraction of the bounding radius: the film reaches `√(2 R h_c)` from the gap, a sizeable
/// part of a particle at the gaps a lattice hands over.
const CURVATURE_STEP: Real = 0.05;

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

    fn moving(com: Vector, linvel: Vector, angvel: Vector) -> BodyKinematics {
        BodyKinematics { center_of_mass: com, linvel, angvel }
    }

    /// A ball over a plane, sliding and turning: Goldman, Cox & Brenner's leading-log force
    /// and torque, with the plane as A or as B.
    #[test]
    fn a_ball_over_a_plane_feels_goldman_cox_and_brenners_shear() {
        let (mu, r, h, hc) = (0.05, 2e-3, 1e-5, 1e-4);
        let lub = Lubrication::new(mu, hc, 1e-7).unwrap().with_shear(true);
        let l = (hc / h).ln();
        let plane = BodyKinematics::at_rest(Vector::new(0.3, -2.0, 0.1));
        // The gap's middle one radius below the centre (the terms' convention, see above).
        let centre = Vector::new(0.0, r + h, 0.0);
        let x = centre - r * Vector::Y;
        let (u, w) = (0.2, 30.0);
        let ball = moving(centre, Vector::new(u, 0.0, 0.0), Vector::new(0.0, 0.0, w));
        // Sliding along x drags the ball back and turns it as if rolling (about −z); turning
        // about +z drives it along −x.
        let force_x = -6.0 * PI * mu * r * l * (8.0 / 15.0) * u - 0.8 * PI * mu * r * r * l * w;
        let torque_z = -0.8 * PI * mu * r * r * l * u - 8.0 * PI * mu * r.powi(3) * l * 0.4 * w;
        let (f, ta, _) = lub.shear_force(h, x, Vector::NEG_Y, (r, Real::INFINITY), (&ball, &plane));
        let (g, _, tb) = lub.shear_force(h, x, Vector::Y, (Real::INFINITY, r), (&plane, &ball));
        for (f, t) in [(f, ta), (-g, tb)] {
            assert!((f.x - force_x).abs() <= 1e-12 * force_x.abs(), "{f} vs {force_x}");
            assert!((t.z - torque_z).abs() <= 1e-12 * torque_z.abs(), "{t} vs {torque_z}");
            assert!(f.y.abs() + f.z.abs() + t.x.abs() + t.y.abs() <= 1e-15);
        }
    }

    /// Two bodies of any radii in any motion: the film takes energy out (never in), a common
    /// rigid motion feels nothing, and the result does not depend on which body is A — which
    /// holds only because Jeffrey & Onishi's terms keep the pair's angular momentum.
    #[test]
    fn the_shear_terms_dissipate_and_do_not_depend_on_the_order() {
        let lub = Lubrication::new(0.1, 1e-4, 1e-6).unwrap().with_shear(true);
        let mut seed = 12345_u64;
        let mut rand = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as Real / (1u64 << 53) as Real * 2.0 - 1.0
        };
        for _ in 0..500 {
            let mut v = || Vector::new(rand(), rand(), rand());
            let n = v().normalize();
            let (x, va, wa, vb, wb, ca, cb) = (v(), v(), v() * 50.0, v(), v() * 50.0, v(), v());
            let r = (3e-3 * (1.5 + rand()), 3e-3 * (1.5 + rand()));
            let gap = 5e-5 * (1.0 + rand());
            let radii = if rand() > 0.6 { (r.0, Real::INFINITY) } else { r };
            let a = moving(x - (radii.0.min(1.0) + 0.5 * gap) * n + 1e-3 * ca, va, wa);
            let b = moving(x + 1e-3 * cb, vb, wb);
            let (f, ta, tb) = lub.shear_force(gap, x, n, radii, (&a, &b));
            let power = f.dot(va) + ta.dot(wa) - f.dot(vb) + tb.dot(wb);
            let scale = f.length() * (va.length() + vb.length()) + 1e-30;
            assert!(power <= 1e-12 * scale, "power {power}");
            let (g, sb, sa) = lub.shear_force(gap, x, -n, (radii.1, radii.0), (&b, &a));
            for (p, q) in [(f, -g), (ta, sa), (tb, sb)] {
                assert!((p - q).length() <= 1e-9 * (p.length() + q.length() + 1e-30), "{p} {q}");
            }
            // A common rigid motion: B moves with A.
            let with_a =
                moving(b.center_of_mass, va + wa.cross(b.center_of_mass - a.center_of_mass), wa);
            let (f, ta, tb) = lub.shear_force(gap, x, n, radii, (&a, &with_a));
            assert!(f.length() + ta.length() + tb.length() <= 1e-12 * scale, "{f} {ta} {tb}");
        }
        // Off, beyond the cut-off, two planes: nothing.
        let a = moving(Vector::ZERO, Vector::X, Vector::Y);
        let b = BodyKinematics::at_rest(Vector::Z);
        let none = (Vector::ZERO, Vector::ZERO, Vector::ZERO);
        let off = lub.with_shear(false);
        assert_eq!(off.shear_force(1e-5, Vector::ZERO, Vector::Z, (1e-3, 1e-3), (&a, &b)), none);
        assert_eq!(lub.shear_force(1e-4, Vector::ZERO, Vector::Z, (1e-3, 1e-3), (&a, &b)), none);
        let planes = (Real::INFINITY, Real::INFINITY);
        assert_eq!(lub.shear_force(1e-5, Vector::ZERO, Vector::Z, planes, (&a, &b)), none);
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

    /// The local radius: exact for a ball, the mean radius `2R` on a cylinder's side, the
    /// bounding radius on a flat face, little at an edge or a corner; never above the bound.
    #[test]
    fn local_radii_of_curvature() {
        use crate::math::Vector;
        let ball = ConvexShape::ball(0.002).unwrap();
        assert_eq!(film_radius_at(&ball, Vector::new(0.0, 0.002, 0.0)), 0.002);
        let (r, h) = (0.001, 0.003);
        let cylinder = ConvexShape::cylinder(h, r).unwrap();
        let bound = film_radius(&cylinder);
        let side = film_radius_at(&cylinder, Vector::new(r, 0.0, 0.0));
        assert!((side - 2.0 * r).abs() < 0.01 * r, "side {side} against {}", 2.0 * r);
        assert_eq!(film_radius_at(&cylinder, Vector::new(0.0, h, 0.0)), bound);
        let cube = ConvexShape::cuboid(Vector::splat(0.001)).unwrap();
        let bound = film_radius(&cube);
        assert_eq!(film_radius_at(&cube, Vector::new(0.0, 0.0, 0.001)), bound);
        for at in [Vector::new(0.001, 0.0, 0.001), Vector::splat(0.001)] {
            let edge = film_radius_at(&cube, at);
            assert!(edge < 0.2 * bound, "{at}: {edge} of {bound}");
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
