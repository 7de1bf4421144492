//! The Nassauer–Kuna force law (Nassauer & Kuna 2013): normal force from overlap volume and
//! indentation with restitution damping, friction (the slip-speed law here, the tangential
//! spring in [`tangential`]), torques on both bodies — with the couple of the damping spread
//! over the overlap's footprint, which damps a body rocking on a face (`rocking_damping`).

use crate::error::{check_finite_vec, Result};
use crate::material::PairParameters;
use crate::math::{Matrix, Real, Vector};
use crate::overlap::OverlapGeometry;
use crate::tangential::{self, SpringForce, TangentialLaw};

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
    /// Torque on A about its centre of mass (N m): the forces' moment at the contact point
    /// plus the damping's couple over the footprint.
    pub torque_on_a: Vector,
    /// Torque on B about its centre of mass (N m), likewise.
    pub torque_on_b: Vector,
    /// Magnitude of the normal force `F_n >= 0` (N).
    pub normal_force: Real,
    /// Magnitude of the tangential (friction) force (N).
    pub tangential_force: Real,
    /// `ḋ = -v_AB·n`: positive while the bodies approach (m/s).
    pub approach_speed: Real,
    /// The undamped law's normal stiffness `dF_n/dd` here (N/m, [`normal_stiffness`]): what
    /// the time-step advice of a live contact resolves.
    pub stiffness: Real,
}

impl ContactForce {
    /// Force on B (N): `-force_on_a`.
    pub fn force_on_b(&self) -> Vector {
        -self.force_on_a
    }
}

/// Undamped normal force `E* k sqrt(V d)` (N); zero without an overlap.
pub(crate) fn elastic_force(params: &PairParameters, geometry: &OverlapGeometry) -> Real {
    let (v, d) = (geometry.volume, geometry.indentation);
    if v <= 0.0 || d <= 0.0 {
        return 0.0;
    }
    params.effective_modulus * params.stiffness.value(v, d, geometry.surface_area) * (v * d).sqrt()
}

/// Stiffness `dF/dd` (N/m) of the undamped normal law `F = E* k √(V d)` for an overlap whose
/// undamped force is `elastic_force`: `F (1 + d A/V) / (2 d)`, with the overlap's cross-section
/// `A = dV/dd` taken as half its surface area (a thin lens or cap has two faces) and `d A/V`
/// kept within [1, 2] — `1.5 F/d` for a cap (Hertz's), `F/d` for a flat punch. A missing area
/// counts as a cap; zero without an overlap.
pub fn normal_stiffness(elastic_force: Real, geometry: &OverlapGeometry) -> Real {
    let (v, d) = (geometry.volume, geometry.indentation);
    if !(v > 0.0 && d > 0.0 && elastic_force > 0.0) {
        return 0.0;
    }
    elastic_force * (1.0 + volume_exponent(v, d, geometry.surface_area).clamp(1.0, 2.0)) / (2.0 * d)
}

/// The exponent `p = d A / V` of the overlap's volume law `V ∝ d^p` near this indentation,
/// with `A = dV/dd` taken as half the surface area `s`: 2 for a cap, 1 for a flat punch, about
/// 3 or more for a corner; 2 when the area is missing. Unclamped: callers keep it within the
/// range they can use. For an overlap with `V > 0`, `d > 0`.
pub(crate) fn volume_exponent(v: Real, d: Real, s: Real) -> Real {
    if s > 0.0 && s.is_finite() {
        0.5 * d * s / v
    } else {
        2.0
    }
}

/// Normal force magnitude `F_n = max(0, E* k sqrt(V d) (1 + c ḋ))`.
pub fn normal_force(
    params: &PairParameters,
    damping: Real,
    geometry: &OverlapGeometry,
    approach_speed: Real,
) -> Real {
    (elastic_force(params, geometry) * (1.0 + damping * approach_speed)).max(0.0)
}

/// Normal, friction and torques of a contact with damping constant `damping` (s/m), for its
/// first evaluation (no tangential history: the spring law, [`TangentialLaw::Spring`], starts
/// unstretched). A persistent contact calls [`contact_force_with_history`].
pub fn contact_force(
    params: &PairParameters,
    damping: Real,
    geometry: &OverlapGeometry,
    a: &BodyKinematics,
    b: &BodyKinematics,
) -> ContactForce {
    contact_force_with_history(params, damping, geometry, a, b, Vector::ZERO, false).0
}

/// Normal, friction and torques of a contact whose tangential spring carries the displacement
/// `carried` (from [`TangentialHistory::carried`](crate::tangential::TangentialHistory::carried))
/// and was sliding (`was_sliding`) at its last evaluation; also returns the spring's new state
/// (zero and not sliding under the slip-speed law, which has no history).
pub fn contact_force_with_history(
    params: &PairParameters,
    damping: Real,
    geometry: &OverlapGeometry,
    a: &BodyKinematics,
    b: &BodyKinematics,
    carried: Vector,
    was_sliding: bool,
) -> (ContactForce, SpringForce) {
    let n = geometry.normal;
    let x_c = geometry.contact_point;
    let v_ab = a.velocity_at(x_c) - b.velocity_at(x_c);
    let v_n = v_ab.dot(n);
    let approach_speed = -v_n;
    let f_el = elastic_force(params, geometry);
    let k_n = normal_stiffness(f_el, geometry);
    let f_n = (f_el * (1.0 + damping * approach_speed)).max(0.0);
    let mut force = n * f_n;
    let mut f_t = 0.0;
    let v_t = v_ab - n * v_n;
    let mut spring =
        SpringForce { force_on_a: Vector::ZERO, displacement: Vector::ZERO, sliding: false };
    if !params.friction.is_none() && f_el > 0.0 {
        match params.tangential {
            TangentialLaw::SlipSpeed => {
                let slip = v_t.length();
                if slip > 0.0 && f_n > 0.0 {
                    f_t = params.friction.coefficient(slip) * f_n;
                    force -= v_t * (f_t / slip);
                }
            }
            TangentialLaw::Spring => {
                let k_t = params.tangential_stiffness_ratio * k_n;
                let eta_t = tangential::damping(params, k_t, damping, f_el);
                spring = tangential::spring_force(
                    &params.friction,
                    k_t,
                    eta_t,
                    f_n,
                    carried,
                    v_t,
                    was_sliding,
                );
                force += spring.force_on_a;
                f_t = spring.force_on_a.length();
            }
        }
    }
    let rocking = rocking_damping(damping, f_el, approach_speed, geometry, a.angvel - b.angvel);
    let contact = ContactForce {
        force_on_a: force,
        torque_on_a: (x_c - a.center_of_mass).cross(force) + rocking,
        torque_on_b: (x_c - b.center_of_mass).cross(-force) - rocking,
        normal_force: f_n,
        tangential_force: f_t,
        approach_speed,
        stiffness: k_n,
    };
    (contact, spring)
}

/// The couple on A (B takes its negative) of the normal damping spread over the overlap's
/// footprint ([`OverlapGeometry::footprint`]) while the bodies rock against each other.
///
/// The law's damping `F_el c ḋ` acts at the contact point on the approach there, which a
/// rocking about the contact leaves still; spread over the footprint (area `A`, central second
/// moment `J`) as the elastic pressure `F_el / A` is taken to be, uniform, each point's own
/// approach `ḋ(ρ) = ḋ − (ω × ρ)·n` (ρ from the footprint's centroid, `ω = ω_A − ω_B`) adds no
/// force and the couple
///
/// ```text
/// T_A = −(c F_el / A) n × (J (ω × n))
/// ```
///
/// — a face rocking on a face loses energy as a bounce does (`T_A·ω <= 0`: it only ever
/// dissipates), while a spin about the normal and a common rotation of both bodies take
/// nothing. Uniform pressure is exact for a face on a face. A rocking needs both surfaces flat
/// across the footprint; where one is curved the bodies roll instead (the contact point moves
/// on, the overlap keeps its shape) and the couple would be a rolling resistance the model does
/// not have: it is weighted by the overlap's volume law `V ∝ d^p`, whole for a slab (`p = 1`),
/// nothing from a strip along a cylinder's side (1.5) on to a cap or an edge (2). The pressure
/// cannot pull: where the rocking would turn it negative at the footprint's rms radius, the
/// couple is held at that rate. Zero without a footprint or damping.
fn rocking_damping(
    damping: Real,
    f_el: Real,
    approach_speed: Real,
    geometry: &OverlapGeometry,
    omega: Vector,
) -> Vector {
    let Some(f) = geometry.footprint else { return Vector::ZERO };
    if !(damping > 0.0 && f_el > 0.0 && f.area > 0.0) {
        return Vector::ZERO;
    }
    let p = volume_exponent(geometry.volume, geometry.indentation, geometry.surface_area);
    let flat = (3.0 / p - 2.0).clamp(0.0, 1.0);
    if !(flat > 0.0) {
        return Vector::ZERO;
    }
    let n = geometry.normal;
    let tilt = omega.cross(n);
    // The rocking's approach at the rms radius, `|ω × n| ρ_rms`, may at most cancel the
    // pressure there, `1 + c ḋ`.
    let rms = (f.spread.x_axis.x + f.spread.y_axis.y + f.spread.z_axis.z).max(0.0) / f.area;
    let rate = damping * tilt.length() * rms.sqrt();
    let held = (1.0 + damping * approach_speed).max(0.0);
    let scale = if rate > held { held / rate } else { 1.0 };
    -n.cross(f.spread * tilt) * (flat * damping * f_el / f.area * scale)
}

/// The rocking damping of [`rocking_damping`] as a matrix `C_r` (N·m·s, world): the couple
/// on A is `−C_r (ω_A − ω_B)`, `C_r = (flat c F_el / A) [n]ₓ J [n]ₓᵀ`, symmetric and positive
/// semi-definite, without the hold that keeps the pressure from pulling (an implicit step,
/// which takes it at the end of the step, is stable without it). Zero where
/// [`rocking_damping`] is.
pub(crate) fn rocking_damping_rate(
    damping: Real,
    f_el: Real,
    geometry: &OverlapGeometry,
) -> Matrix {
    let Some(f) = geometry.footprint else { return Matrix::ZERO };
    if !(damping > 0.0 && f_el > 0.0 && f.area > 0.0) {
        return Matrix::ZERO;
    }
    let p = volume_exponent(geometry.volume, geometry.indentation, geometry.surface_area);
    let flat = (3.0 / p - 2.0).clamp(0.0, 1.0);
    if !(flat > 0.0) {
        return Matrix::ZERO;
    }
    let n = geometry.normal;
    let cross = Matrix::from_cols(n.cross(Vector::X), n.cross(Vector::Y), n.cross(Vector::Z));
    let c = cross * f.spread * cross.transpose() * (flat * damping * f_el / f.area);
    if c.is_finite() {
        c
    } else {
        Matrix::ZERO
    }
}
