//! Materials and the parameters of a contact pair, checked when built.
//!
//! All quantities are SI: Pa, m/s, s/m.

use crate::error::{check_non_negative, check_positive, check_range, Error, Result};
use crate::math::Real;
use crate::tangential::TangentialLaw;
use std::ops::Bound::{Excluded, Included};

/// An isotropic elastic material.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "checkpoint", serde(try_from = "MaterialFields"))]
pub struct Material {
    youngs_modulus: Real,
    poisson_ratio: Real,
}

impl Material {
    /// Young's modulus `E > 0` (Pa) and Poisson's ratio `0 <= nu <= 0.5`.
    pub fn new(youngs_modulus: Real, poisson_ratio: Real) -> Result<Self> {
        Ok(Self {
            youngs_modulus: check_positive("youngs_modulus", youngs_modulus)?,
            poisson_ratio: check_range(
                "poisson_ratio",
                poisson_ratio,
                0.0..=0.5,
                "0 <= nu <= 0.5",
            )?,
        })
    }

    /// Young's modulus (Pa).
    pub fn youngs_modulus(&self) -> Real {
        self.youngs_modulus
    }

    /// Poisson's ratio.
    pub fn poisson_ratio(&self) -> Real {
        self.poisson_ratio
    }

    /// `(1 - nu^2) / E`, this material's share of the pair's compliance.
    fn compliance(&self) -> Real {
        (1.0 - self.poisson_ratio * self.poisson_ratio) / self.youngs_modulus
    }
}

/// Effective modulus `E*` of a pair: `1/E* = (1 - nu_A^2)/E_A + (1 - nu_B^2)/E_B` (corrected; see `docs/design.md`).
pub fn effective_modulus(a: &Material, b: &Material) -> Real {
    1.0 / (a.compliance() + b.compliance())
}

/// The factor `k` in `F_n = E* k sqrt(V d)`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub enum StiffnessFactor {
    /// `k = 4/(3 sqrt(pi))`: reproduces Hertz for curved contacts (sphere–plane, sphere–sphere,
    /// crossed cylinders). The default.
    Curved,
    /// `k = 2/sqrt(pi)`: reproduces the flat punch `F = 2 R E* d`.
    FlatPunch,
    /// From the overlap's shape: `k = 0.6118 + 1.9001 exp(-0.6512 d S / V)` with `S` the overlap
    /// surface area (a published fit; 0.752 sphere–plane, 1.128 face–face).
    ShapeAdaptive,
    /// A fixed value (e.g. `0.62` for polyhedra).
    Custom(Real),
}

impl StiffnessFactor {
    /// The factor for an overlap of volume `v`, depth `d` and surface area `s`.
    pub fn value(&self, v: Real, d: Real, s: Real) -> Real {
        match *self {
            Self::Curved => 4.0 / (3.0 * core::f64::consts::PI.sqrt()),
            Self::FlatPunch => 2.0 / core::f64::consts::PI.sqrt(),
            Self::ShapeAdaptive => {
                if v > 0.0 {
                    0.6118 + 1.9001 * (-0.6512 * d * s / v).exp()
                } else {
                    0.6118
                }
            }
            Self::Custom(k) => k,
        }
    }
}

/// Static/kinetic friction coefficients, applied by either tangential law
/// ([`TangentialLaw`]); the transition speed is Nassauer & Kuna's slip-speed law's.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "checkpoint", serde(try_from = "FrictionFields"))]
pub struct Friction {
    /// Static coefficient `mu_s >= mu_k`.
    pub static_coefficient: Real,
    /// Kinetic coefficient `mu_k >= 0`.
    pub kinetic_coefficient: Real,
    /// Static-to-kinetic transition speed `v_s > 0` (m/s).
    pub transition_speed: Real,
}

impl Friction {
    /// No friction: the tangential force is skipped entirely.
    pub const NONE: Friction =
        Friction { static_coefficient: 0.0, kinetic_coefficient: 0.0, transition_speed: 1.0 };

    /// `mu_s >= mu_k >= 0`, `v_s > 0`.
    pub fn new(
        static_coefficient: Real,
        kinetic_coefficient: Real,
        transition_speed: Real,
    ) -> Result<Self> {
        let mu_k = check_non_negative("kinetic_coefficient", kinetic_coefficient)?;
        let mu_s = check_non_negative("static_coefficient", static_coefficient)?;
        if mu_s < mu_k {
            return Err(Error::InvalidParameter {
                name: "static_coefficient",
                value: mu_s,
                allowed: "finite and >= kinetic_coefficient",
            });
        }
        Ok(Self {
            static_coefficient: mu_s,
            kinetic_coefficient: mu_k,
            transition_speed: check_positive("transition_speed", transition_speed)?,
        })
    }

    /// Whether this friction does nothing (`mu_s = 0`).
    pub fn is_none(&self) -> bool {
        self.static_coefficient == 0.0
    }

    /// `|F_t| / F_n` at tangential slip speed `slip` (m/s):
    /// `(2 mu_s* - mu_k) s^2/(s^4+1) + mu_k - mu_k/(s^2+1)`, `s = slip/v_s`,
    /// `mu_s* = mu_s (1 - 0.09 (mu_k/mu_s)^4)`.
    pub fn coefficient(&self, slip: Real) -> Real {
        if self.is_none() || slip <= 0.0 {
            return 0.0;
        }
        let (mu_s, mu_k) = (self.static_coefficient, self.kinetic_coefficient);
        let mu_s_star = mu_s * (1.0 - 0.09 * (mu_k / mu_s).powi(4));
        let s2 = (slip / self.transition_speed).powi(2);
        if !s2.is_finite() {
            return mu_k;
        }
        (2.0 * mu_s_star - mu_k) * s2 / (s2 * s2 + 1.0) + mu_k - mu_k / (s2 + 1.0)
    }
}

/// Duration (s) of an elastic Hertz impact, `t_H = 2.87 (m*² / (R* E*² v0))^(1/5)`, for the
/// effective mass `m*` (kg), radius `R*` (m), modulus `E*` (Pa) and approach speed `v0` (m/s):
/// the time scale the contact sub-steps resolve (see
/// [`DiscreteContacts::substeps`](crate::rapier::DiscreteContacts::substeps)).
pub fn hertz_contact_time(m_star: Real, r_star: Real, e_star: Real, v0: Real) -> Real {
    2.87 * (m_star * m_star / (r_star * e_star * e_star * v0)).powf(0.2)
}

/// Deepest indentation (m) of an elastic Hertz impact, `d_max = (15 m* v0² / (16 E* √R*))^(2/5)`,
/// for the same quantities as [`hertz_contact_time`]: what the drop-in compares with a body's
/// size before it lets an impact happen (`Error::ContactTooSoft`).
pub fn hertz_max_indentation(m_star: Real, r_star: Real, e_star: Real, v0: Real) -> Real {
    (15.0 * m_star * v0 * v0 / (16.0 * e_star * r_star.sqrt())).powf(0.4)
}

/// Damping constant `c` (s/m) that gives restitution `e` for an impact at normal speed `v0`
/// under any force `f(x) (1 + c x')` (Carvalho & Martins 2019).
///
/// Solves `a - ln(1 + a) = -a e - ln(1 - a e)` for `0 < a < 1/e` and returns `c = a / v0`;
/// `e = 1` gives `c = 0`.
pub fn damping_from_restitution(restitution: Real, approach_speed: Real) -> Result<Real> {
    let e = check_range("restitution", restitution, (Excluded(0.0), Included(1.0)), "0 < e <= 1")?;
    let v0 = check_positive("approach_speed", approach_speed)?;
    Ok(restitution_parameter(e) / v0)
}

/// The dimensionless `a = c v0` of [`damping_from_restitution`] for `0 < e <= 1`.
fn restitution_parameter(e: Real) -> Real {
    if 1.0 - e < 1e-7 {
        // Leading order of the series a ~ 3(1-e²)/(2(1+e³)), exact as e -> 1.
        return 1.5 * (1.0 - e * e) / (1.0 + e * e * e);
    }
    // g > 0 on (0, a*), g < 0 on (a*, 1/e).
    let g = |a: Real| a - a.ln_1p() + a * e + (-a * e).ln_1p();
    let mut lo = 1.5 * (1.0 - e) * (11.0 - e) / (1.0 + 9.0 * e);
    while g(lo) <= 0.0 {
        lo *= 0.5;
    }
    let mut hi = (lo * 2.0).min(1.0 / e);
    while hi < 1.0 / e && g(hi) > 0.0 {
        hi = (hi * 2.0).min(1.0 / e);
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if g(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Everything the force law needs for one pair of materials.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairParameters {
    /// `E*` (Pa).
    pub effective_modulus: Real,
    /// The factor `k`.
    pub stiffness: StiffnessFactor,
    /// Coefficient of restitution `0 < e <= 1`.
    pub restitution: Real,
    /// Friction; [`Friction::NONE`] skips the tangential force.
    pub friction: Friction,
    /// Which tangential law applies the friction; [`TangentialLaw::SlipSpeed`] (the papers')
    /// unless set.
    pub tangential: TangentialLaw,
    /// Mindlin's `κ = k_t / k_n` of the two materials, the tangential spring's stiffness ratio
    /// ([`crate::tangential::stiffness_ratio`]).
    pub tangential_stiffness_ratio: Real,
    /// Effective mass (kg) of the pair against a tangential load at the contact, rotation
    /// included (`2/7 m*` for two spheres); sets the tangential spring's damping. `None`:
    /// the spring is damped with the normal law's constant instead (see [`crate::tangential`]).
    pub tangential_mass: Option<Real>,
    /// Approach speeds below this (m/s) count as this when the damping is fixed at first touch,
    /// so a contact that starts at rest gets a finite damping constant.
    pub min_approach_speed: Real,
}

impl PairParameters {
    /// Frictionless pair with the curved-contact `k` and restitution `e`.
    pub fn new(a: &Material, b: &Material, restitution: Real) -> Result<Self> {
        Ok(Self {
            effective_modulus: effective_modulus(a, b),
            stiffness: StiffnessFactor::Curved,
            restitution: check_range(
                "restitution",
                restitution,
                (Excluded(0.0), Included(1.0)),
                "0 < e <= 1",
            )?,
            friction: Friction::NONE,
            tangential: TangentialLaw::SlipSpeed,
            tangential_stiffness_ratio: crate::tangential::stiffness_ratio(a, b),
            tangential_mass: None,
            min_approach_speed: 1e-3,
        })
    }

    /// With friction.
    pub fn with_friction(mut self, friction: Friction) -> Self {
        self.friction = friction;
        self
    }

    /// With another tangential law for the friction.
    pub fn with_tangential_law(mut self, law: TangentialLaw) -> Self {
        self.tangential = law;
        self
    }

    /// With the pair's effective tangential mass `m_t > 0` (kg; infinite for two bodies that do
    /// not move): the tangential spring is then damped to the restitution's damping ratio.
    pub fn with_tangential_mass(mut self, m_t: Real) -> Result<Self> {
        if !(m_t > 0.0) {
            return Err(Error::InvalidParameter {
                name: "tangential_mass",
                value: m_t,
                allowed: "> 0 (kg), infinite allowed",
            });
        }
        self.tangential_mass = Some(m_t);
        Ok(self)
    }

    /// With another stiffness factor; a custom `k` must be finite and positive.
    pub fn with_stiffness(mut self, stiffness: StiffnessFactor) -> Result<Self> {
        if let StiffnessFactor::Custom(k) = stiffness {
            check_positive("stiffness factor k", k)?;
        }
        self.stiffness = stiffness;
        Ok(self)
    }

    /// With another floor for the approach speed at first touch (m/s, > 0).
    pub fn with_min_approach_speed(mut self, v: Real) -> Result<Self> {
        self.min_approach_speed = check_positive("min_approach_speed", v)?;
        Ok(self)
    }

    /// Damping constant for a contact first seen at normal approach speed `v0`.
    pub fn damping_for(&self, v0: Real) -> Real {
        let v =
            if v0.is_finite() { v0.max(self.min_approach_speed) } else { self.min_approach_speed };
        restitution_parameter(self.restitution) / v
    }
}

deserialize_checked!(Material via MaterialFields { youngs_modulus: Real, poisson_ratio: Real }
    => |f| Material::new(f.youngs_modulus, f.poisson_ratio));

deserialize_checked!(Friction via FrictionFields { static_coefficient: Real, kinetic_coefficient: Real, transition_speed: Real }
    => |f| Friction::new(f.static_coefficient, f.kinetic_coefficient, f.transition_speed));
