//! The Nassauer–Kuna force law (DESIGN §3): normal force from overlap volume and indentation
//! with restitution damping, static/kinetic friction, torques on both bodies.

use crate::error::{check_finite_vec, Result};
use crate::material::PairParameters;
use crate::math::{Real, Vector};
use crate::overlap::OverlapGeometry;

/// Where a body is and how it moves (world frame, SI).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyKinematics {
    /// Centre of mass (m).
    pub center_of_mass: Vector,
    /// Linear velocity of the centre of mass (m/s).
    pub linvel: Vector,
    /// Angular velocity (rad/s).
    pub angvel: Vector,
}

impl BodyKinematics {
    /// A body at rest with its centre of mass at `center_of_mass`.
    pub fn at_rest(center_of_mass: Vector) -> Self {
        Self { center_of_mass, linvel: Vector::ZERO, angvel: Vector::ZERO }
    }

    /// Velocity of the material point at `x`: `v + ω × (x - x_cm)`.
    pub fn velocity_at(&self, x: Vector) -> Vector {
        self.linvel + self.angvel.cross(x - self.center_of_mass)
    }

    /// Refuses NaN or infinite components.
    pub fn check(&self, what: &'static str) -> Result<()> {
        check_finite_vec(what, self.center_of_mass)?;
        check_finite_vec(what, self.linvel)?;
        check_finite_vec(what, self.angvel)
    }
}

/// The force of one contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactForce {
    /// Total force on A (N); B receives its negative.
    pub force_on_a: Vector,
    /// Torque on A about its centre of mass (N m).
    pub torque_on_a: Vector,
    /// Torque on B about its centre of mass (N m).
    pub torque_on_b: Vector,
    /// Magnitude of the normal force `F_n >= 0` (N).
    pub normal_force: Real,
    /// Magnitude of the tangential (friction) force (N).
    pub tangential_force: Real,
    /// `ḋ = -v_AB·n`: positive while the bodies approach (m/s).
    pub approach_speed: Real,
}

impl ContactForce {
    /// Force on B (N): `-force_on_a`.
    pub fn force_on_b(&self) -> Vector {
        -self.force_on_a
    }
}

/// Normal force magnitude `F_n = max(0, E* k sqrt(V d) (1 + c ḋ))`.
pub fn normal_force(params: &PairParameters, damping: Real, geometry: &OverlapGeometry, approach_speed: Real) -> Real {
    let (v, d) = (geometry.volume, geometry.indentation);
    if v <= 0.0 || d <= 0.0 {
        return 0.0;
    }
    let k = params.stiffness.value(v, d, geometry.surface_area);
    (params.effective_modulus * k * (v * d).sqrt() * (1.0 + damping * approach_speed)).max(0.0)
}

/// Normal, friction and torques of a contact with damping constant `damping` (s/m).
pub fn contact_force(
    params: &PairParameters,
    damping: Real,
    geometry: &OverlapGeometry,
    a: &BodyKinematics,
    b: &BodyKinematics,
) -> ContactForce {
    let n = geometry.normal;
    let x_c = geometry.contact_point;
    let v_ab = a.velocity_at(x_c) - b.velocity_at(x_c);
    let v_n = v_ab.dot(n);
    let approach_speed = -v_n;
    let f_n = normal_force(params, damping, geometry, approach_speed);
    let mut force = n * f_n;
    let mut f_t = 0.0;
    if !params.friction.is_none() && f_n > 0.0 {
        let v_t = v_ab - n * v_n;
        let slip = v_t.length();
        if slip > 0.0 {
            f_t = params.friction.coefficient(slip) * f_n;
            force -= v_t * (f_t / slip);
        }
    }
    ContactForce {
        force_on_a: force,
        torque_on_a: (x_c - a.center_of_mass).cross(force),
        torque_on_b: (x_c - b.center_of_mass).cross(-force),
        normal_force: f_n,
        tangential_force: f_t,
        approach_speed,
    }
}
