//! The history-dependent tangential force: an elastic tangential spring capped by Coulomb's law
//! (Cundall & Strack 1979, doi:10.1680/geot.1979.29.1.47; with the sliding rule of Luding 2008,
//! doi:10.1007/s10035-008-0099-x, and Mindlin's tangential stiffness, Mindlin 1949,
//! doi:10.1115/1.4009973).
//!
//! A velocity-only friction law (Nassauer & Kuna's, [`TangentialLaw::SlipSpeed`]) vanishes at
//! zero slip, so nothing at rest can carry a tangential load: a box on a ramp creeps, a stack
//! drifts. The spring remembers the contact's elastic tangential displacement `ξ` instead:
//!
//! - **stick**: `F_t = −k_t ξ − η_t v_t` while `|F_t| <= μ_s F_n`;
//! - **slide**: beyond, `F_t = μ_k F_n` along the trial force, and `ξ` is set back to what that
//!   force needs, `ξ = −(F_t + η_t v_t) / k_t`; a sliding contact stays at `μ_k` until its
//!   trial force falls below `μ_k F_n` (it sticks again), so `μ_s > μ_k` does not make a steady
//!   slide stick and slip.
//!
//! `ξ` is carried between evaluations by material points: the contact point is recorded in
//! both bodies' frames (the *anchors*); at the next evaluation the anchors' relative
//! displacement, taken into the current tangent plane, is added to the last `ξ` rotated into
//! that plane (its length kept). The history is thus a function of the poses, not of a time
//! step: evaluating a state twice gives the same force, and a rigid motion of the pair
//! carries `ξ` with it.
//!
//! **Stiffness** from the materials, so a user sets no extra number: Mindlin's ratio of
//! tangential to normal contact stiffness, `κ = k_t / k_n = 4 G* / E*` with
//! `1/G* = (2 − ν_A)/G_A + (2 − ν_B)/G_B` (`2(1 − ν)/(2 − ν)` for equal materials, 0.67–1), times
//! the normal law's own stiffness `k_n = dF_n/dd` ([`crate::force::normal_stiffness`]: Hertz's
//! `1.5 F/d` for a cap, `F/d` for a flat punch). **Damping** to the pair's restitution: the damping ratio that gives a
//! linear oscillator restitution `e`, from the pair's tangential mass (see [`damping`]).

use crate::material::{Friction, Material, PairParameters};
use crate::math::{Pose, Real, Vector};

/// Which tangential force law a pair uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub enum TangentialLaw {
    /// Nassauer & Kuna's regularised Coulomb law: the force is a function of the slip speed
    /// alone ([`Friction::coefficient`]), zero at zero slip. The papers' model, kept for the
    /// validations that use it; a body at rest under a tangential load creeps.
    SlipSpeed,
    /// The tangential spring of this module: sticks below `μ_s F_n`, slides at `μ_k F_n`; a box
    /// stays on a ramp below `atan μ_s`. [`Friction::transition_speed`] is not used.
    Spring,
}

/// Mindlin's ratio `κ = k_t / k_n = 4 G* / E*` of a pair of materials (see the module docs).
pub fn stiffness_ratio(a: &Material, b: &Material) -> Real {
    let shear_compliance = |m: &Material| {
        let nu = m.poisson_ratio();
        (2.0 - nu) * 2.0 * (1.0 + nu) / m.youngs_modulus()
    };
    let normal_compliance = |m: &Material| (1.0 - m.poisson_ratio().powi(2)) / m.youngs_modulus();
    4.0 * (normal_compliance(a) + normal_compliance(b))
        / (shear_compliance(a) + shear_compliance(b))
}

/// What a live contact's tangential spring remembers between evaluations.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub struct TangentialHistory {
    /// Elastic tangential displacement of A relative to B at the last evaluation (world, m).
    pub displacement: Vector,
    /// The last contact point in A's and in B's body frame; `None` before the first evaluation.
    pub anchors: Option<[Vector; 2]>,
    /// Whether the contact was sliding at the last evaluation.
    pub sliding: bool,
}

impl TangentialHistory {
    /// The displacement carried to the current evaluation, in the tangent plane of `normal`:
    /// the last one rotated into the plane (its length kept) plus the anchors' relative
    /// tangential displacement since. Zero for a new contact.
    pub fn carried(&self, pose_a: &Pose, pose_b: &Pose, normal: Vector) -> Vector {
        let Some([a, b]) = self.anchors else { return Vector::ZERO };
        let tangential = |v: Vector| v - normal * v.dot(normal);
        let last = tangential(self.displacement);
        let length = self.displacement.length();
        let rotated = if length > 0.0 && last.length() > 0.0 {
            last * (length / last.length())
        } else {
            last
        };
        rotated + tangential(pose_a.transform_point(a) - pose_b.transform_point(b))
    }

    /// Records an evaluation: the new displacement, whether it slid, and the contact point as
    /// material points of both bodies.
    pub fn record(
        &mut self,
        displacement: Vector,
        sliding: bool,
        contact_point: Vector,
        pose_a: &Pose,
        pose_b: &Pose,
    ) {
        self.displacement = displacement;
        self.sliding = sliding;
        self.anchors = Some([
            pose_a.inverse_transform_point(contact_point),
            pose_b.inverse_transform_point(contact_point),
        ]);
    }
}

/// The spring's viscous coefficient `η_t` (N s/m) for stiffness `k_t`, the normal law's damping
/// constant `c` and undamped normal force `f_el`: with the pair's tangential mass known, the
/// damping ratio of a linear oscillator with the pair's restitution `e`,
/// `ζ = −ln e / √(π² + ln² e)`, so `η_t = 2 ζ √(k_t m_t)`; without it, `κ c F_el`.
///
/// The mass-based form is the one to use in a time-stepped run: `c` is set from the approach
/// speed at first touch and is very large for a contact that began at rest, and a dashpot
/// far above critical damping is unstable under explicit integration.
pub fn damping(params: &PairParameters, k_t: Real, c: Real, f_el: Real) -> Real {
    match params.tangential_mass {
        Some(m_t) if m_t.is_finite() => {
            let log_e = params.restitution.ln();
            let zeta = -log_e / (core::f64::consts::PI.powi(2) + log_e * log_e).sqrt();
            2.0 * zeta * (k_t * m_t).sqrt()
        }
        Some(_) => 0.0,
        None => params.tangential_stiffness_ratio * c * f_el,
    }
}

/// The spring's force on A and its new state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringForce {
    /// Tangential force on A (N).
    pub force_on_a: Vector,
    /// Elastic displacement to carry to the next evaluation (m).
    pub displacement: Vector,
    /// Whether the contact slides.
    pub sliding: bool,
}

/// The tangential force for a carried displacement `xi` (in the tangent plane), tangential
/// slip velocity `v_t` of A relative to B, stiffness `k_t`, viscous coefficient `eta_t` and
/// normal force `f_n`; `was_sliding` from the contact's history.
pub fn spring_force(
    friction: &Friction,
    k_t: Real,
    eta_t: Real,
    f_n: Real,
    xi: Vector,
    v_t: Vector,
    was_sliding: bool,
) -> SpringForce {
    if friction.is_none() || k_t <= 0.0 {
        return SpringForce {
            force_on_a: Vector::ZERO,
            displacement: Vector::ZERO,
            sliding: false,
        };
    }
    let trial = -(xi * k_t) - v_t * eta_t;
    let magnitude = trial.length();
    let limit =
        if was_sliding { friction.kinetic_coefficient } else { friction.static_coefficient }
            * f_n.max(0.0);
    if magnitude <= limit {
        return SpringForce { force_on_a: trial, displacement: xi, sliding: false };
    }
    let force = if magnitude > 0.0 {
        trial * (friction.kinetic_coefficient * f_n.max(0.0) / magnitude)
    } else {
        Vector::ZERO
    };
    SpringForce { force_on_a: force, displacement: -(force + v_t * eta_t) / k_t, sliding: true }
}
