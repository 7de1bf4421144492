//! One contact's force law over an implicit step: the impulse it gives body A for the bodies'
//! velocities at the end of the step, and how that impulse changes with them.
//!
//! Over a step of length `h` the bodies move with their end-of-step velocities (symplectic
//! Euler, as rapier integrates), so the relative velocity `u` at the contact point decides
//! where the contact ends the step: the indentation `d + h ḋ` (`ḋ = −n·u`, the approach
//! speed) and the tangential spring's stretch `ξ + h u_t`. Each part of the law is a
//! monotone function of these, the negative gradient of a convex potential of `u`, so that
//! the step is one convex problem (see the parent module):
//!
//! - **normal**: Nassauer & Kuna's `F = F_el(d) (1 + c ḋ)`, at most zero, with the elastic
//!   force `F_el = a d^q` of the contact's own volume law (`V ∝ d^p`, `q = (1 + p)/2`: a face
//!   pressed evenly `q = 1`, a cap Hertz's `3/2`), taken at the indentation the step ends
//!   with;
//! - **tangential**: the spring `−k_t (ξ + h u_t) − η u_t` held within the friction disc of
//!   radius `μ F_n`, `F_n` the normal force of the solve before (a fixed radius keeps the
//!   projection the gradient of a convex function, as in Castro, Permenter & Han's lagged
//!   friction, 2022, doi:10.1109/TRO.2022.3157039);
//! - **rocking**: the overlap's resistance to tilting `K_r` and its damping `C_r`, linear in
//!   the relative turn over the step.

use crate::math::{Matrix, Real, Vector};

/// A body's velocity, or a load on it: (linear, angular).
pub(crate) type Motion = (Vector, Vector);

/// The normal part of a contact's law over a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NormalLaw {
    /// Indentation at the start of the step (m); negative: the gap of a pair not yet touching.
    pub depth: Real,
    /// `a` in `F_el = a d^q` (N/m^q).
    pub coefficient: Real,
    /// `q`, at least 1.
    pub exponent: Real,
    /// Nassauer & Kuna's damping constant `c` (s/m).
    pub damping: Real,
}

impl NormalLaw {
    /// The normal impulse over step `h` for the separation speed `s = n·u` at its end, and
    /// its rate of fall `−dγ/ds >= 0`.
    fn impulse(&self, s: Real, h: Real) -> (Real, Real) {
        let d = self.depth - h * s;
        let damped = 1.0 - self.damping * s;
        if !(d > 0.0 && damped > 0.0) {
            return (0.0, 0.0);
        }
        let f_el = self.coefficient * d.powf(self.exponent);
        let stiffness = self.exponent * f_el / d;
        (h * f_el * damped, h * (h * stiffness * damped + self.damping * f_el))
    }
}

/// The tangential spring's part of a contact's law over a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SpringLaw {
    /// Stiffness `k_t` (N/m).
    pub stiffness: Real,
    /// Viscous coefficient `η_t` (N s/m).
    pub viscosity: Real,
    /// The stretch carried into the step, in the tangent plane (m).
    pub carried: Vector,
    /// The friction coefficient that caps it: static while the contact sticks, kinetic while
    /// it slides.
    pub coefficient: Real,
    /// The normal force the cap is taken from (N).
    pub normal_force: Real,
}

/// One contact's law over a step between two bodies of an island (or one and a body whose
/// motion is given).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StepLaw {
    /// The island's bodies at either end; `None`: a body the island does not move.
    pub bodies: [Option<usize>; 2],
    /// Either end's velocity where it is not an island body (a fixed body's zero, a
    /// kinematic body's own).
    pub given: [Motion; 2],
    /// From each body's centre of mass to the contact point (m, world).
    pub levers: [Vector; 2],
    /// Unit normal, from B towards A: A is pushed along it.
    pub normal: Vector,
    /// The normal law.
    pub normal_law: NormalLaw,
    /// The tangential spring, when friction acts through it.
    pub spring: Option<SpringLaw>,
    /// Resistance to tilting `K_r` (N m/rad, world).
    pub rocking: Matrix,
    /// Damping of the tilting `C_r` (N m s/rad, world).
    pub rocking_damping: Matrix,
}

/// What a law gives for a relative motion: the impulse on A (force impulse at the contact
/// point, couple impulse), and the rate at which it falls as the relative motion grows
/// (`G = −∂γ/∂w`, 6 × 6, symmetric and positive semi-definite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Response {
    /// Impulse on A (N s): along the normal, across it, and the couple's (N m s).
    pub normal: Real,
    pub tangential: Vector,
    pub couple: Vector,
    /// Whether the tangential impulse lies on the friction disc's rim (the contact slides).
    pub sliding: bool,
    /// `G`'s blocks: the force's against the relative velocity, the couple's against the
    /// relative turn rate.
    pub force_rate: Matrix,
    pub couple_rate: Matrix,
}

impl StepLaw {
    /// The relative motion at the contact for the bodies' `velocities`: A's contact point's
    /// velocity against B's, and A's turn rate against B's.
    pub(crate) fn relative(&self, velocities: &[Motion]) -> Motion {
        let at = |end: usize| {
            let (v, w) = self.bodies[end].map_or(self.given[end], |b| velocities[b]);
            (v + w.cross(self.levers[end]), w)
        };
        let ((ua, wa), (ub, wb)) = (at(0), at(1));
        (ua - ub, wa - wb)
    }

    /// The law's response over step `h` to the relative motion `(u, turn)`.
    pub(crate) fn response(&self, (u, turn): Motion, h: Real) -> Response {
        let n = self.normal;
        let s = n.dot(u);
        let (normal, rate_n) = self.normal_law.impulse(s, h);
        let mut force_rate = Matrix::from_cols(n * n.x, n * n.y, n * n.z) * rate_n;
        let (mut tangential, mut sliding) = (Vector::ZERO, false);
        if let Some(spring) = &self.spring {
            let u_t = u - n * s;
            let b = spring.stiffness * h + spring.viscosity;
            let trial = -(spring.carried * spring.stiffness + u_t * b) * h;
            let radius = spring.coefficient * spring.normal_force.max(0.0) * h;
            let across = Matrix::IDENTITY - Matrix::from_cols(n * n.x, n * n.y, n * n.z);
            let length = trial.length();
            if length <= radius {
                tangential = trial;
                force_rate += across * (h * b);
            } else if length > 0.0 {
                let t = trial / length;
                tangential = t * radius;
                sliding = true;
                let on_rim = across - Matrix::from_cols(t * t.x, t * t.y, t * t.z);
                force_rate += on_rim * (h * b * radius / length);
            }
        }
        let couple_rate = (self.rocking * h + self.rocking_damping) * h;
        Response {
            normal,
            tangential,
            couple: -(couple_rate * turn),
            sliding,
            force_rate,
            couple_rate,
        }
    }

    /// The impulses a response puts on the law's two ends (each about its centre of mass).
    pub(crate) fn on_bodies(&self, r: &Response) -> [Motion; 2] {
        let f = self.normal * r.normal + r.tangential;
        [(f, self.levers[0].cross(f) + r.couple), (-f, -self.levers[1].cross(f) - r.couple)]
    }
}

/// A joint between two bodies of an island (or one and a body whose motion is given), held
/// as a stiff spring on the axes it locks: the anchor points kept together along its locked
/// translations, the frames kept aligned about its locked rotations. Linear in the relative
/// motion, so its part of the step's problem is a quadratic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct JointLaw {
    /// The island's bodies at either end; `None`: a body the island does not move.
    pub bodies: [Option<usize>; 2],
    /// Either end's velocity where it is not an island body.
    pub given: [Motion; 2],
    /// From each body's centre of mass to its anchor point (m, world).
    pub levers: [Vector; 2],
    /// The locked translation axes and rotation axes (world unit vectors; zero where free).
    pub linear: [Vector; 3],
    pub angular: [Vector; 3],
    /// A's anchor less B's (m), and A's frame's turn from B's (rad, small-angle vector).
    pub offset: Vector,
    pub turn: Vector,
    /// Stiffness along the locked translations (N/m) and about the locked rotations (N m/rad).
    pub stiffness: (Real, Real),
}

impl JointLaw {
    /// The relative motion at the anchors, as [`StepLaw::relative`].
    fn relative(&self, velocities: &[Motion]) -> Motion {
        let at = |end: usize| {
            let (v, w) = self.bodies[end].map_or(self.given[end], |b| velocities[b]);
            (v + w.cross(self.levers[end]), w)
        };
        let ((ua, wa), (ub, wb)) = (at(0), at(1));
        (ua - ub, wa - wb)
    }

    /// The impulse on A over a step of `h` for the relative motion `(u, turn)`, and its rates.
    fn response(&self, (u, w): Motion, h: Real) -> Response {
        let (k, k_turn) = self.stiffness;
        let (mut force, mut couple) = (Vector::ZERO, Vector::ZERO);
        let (mut force_rate, mut couple_rate) = (Matrix::ZERO, Matrix::ZERO);
        for a in self.linear.iter().filter(|a| **a != Vector::ZERO) {
            force -= *a * (k * h * (self.offset.dot(*a) + h * u.dot(*a)));
            force_rate += Matrix::from_cols(*a * a.x, *a * a.y, *a * a.z) * (k * h * h);
        }
        for a in self.angular.iter().filter(|a| **a != Vector::ZERO) {
            couple -= *a * (k_turn * h * (self.turn.dot(*a) + h * w.dot(*a)));
            couple_rate += Matrix::from_cols(*a * a.x, *a * a.y, *a * a.z) * (k_turn * h * h);
        }
        Response { normal: 0.0, tangential: force, couple, sliding: false, force_rate, couple_rate }
    }
}

/// A law of an island: a contact's or a joint's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Law {
    Contact(StepLaw),
    Joint(JointLaw),
}

impl Law {
    /// The island's bodies at either end.
    pub(crate) fn bodies(&self) -> [Option<usize>; 2] {
        match self {
            Law::Contact(l) => l.bodies,
            Law::Joint(l) => l.bodies,
        }
    }

    /// The levers from each body's centre of mass to where the law acts.
    pub(crate) fn levers(&self) -> [Vector; 2] {
        match self {
            Law::Contact(l) => l.levers,
            Law::Joint(l) => l.levers,
        }
    }

    /// The relative motion where the law acts.
    pub(crate) fn relative(&self, velocities: &[Motion]) -> Motion {
        match self {
            Law::Contact(l) => l.relative(velocities),
            Law::Joint(l) => l.relative(velocities),
        }
    }

    /// The law's response over step `h` to the relative motion.
    pub(crate) fn response(&self, relative: Motion, h: Real) -> Response {
        match self {
            Law::Contact(l) => l.response(relative, h),
            Law::Joint(l) => l.response(relative, h),
        }
    }

    /// The impulses a response puts on the law's two ends (each about its centre of mass).
    pub(crate) fn on_bodies(&self, r: &Response) -> [Motion; 2] {
        let (n, levers) = match self {
            Law::Contact(l) => (l.normal, l.levers),
            Law::Joint(l) => (Vector::ZERO, l.levers),
        };
        let f = n * r.normal + r.tangential;
        [(f, levers[0].cross(f) + r.couple), (-f, -levers[1].cross(f) - r.couple)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> StepLaw {
        StepLaw {
            bodies: [Some(0), None],
            given: [(Vector::ZERO, Vector::ZERO); 2],
            levers: [Vector::new(0.01, -0.05, 0.02), Vector::new(0.3, 0.1, -0.2)],
            normal: Vector::new(0.1, 1.0, -0.2).normalize(),
            normal_law: NormalLaw { depth: 2e-5, coefficient: 3e7, exponent: 1.5, damping: 0.4 },
            spring: Some(SpringLaw {
                stiffness: 4e5,
                viscosity: 30.0,
                carried: Vector::ZERO,
                coefficient: 0.5,
                normal_force: 2.0,
            }),
            rocking: Matrix::from_diagonal(Vector::new(3.0, 0.0, 2.0)),
            rocking_damping: Matrix::from_diagonal(Vector::new(0.1, 0.0, 0.2)),
        }
    }

    /// The rate the law reports is minus the derivative of its impulse (central differences),
    /// for a contact sticking and one sliding, approaching and separating, and it is symmetric
    /// and positive semi-definite: what makes the step's problem convex.
    #[test]
    fn the_rate_is_the_impulses_derivative_and_positive() {
        let h = 1e-3;
        for (u, turn) in [
            (Vector::new(1e-3, -2e-3, 5e-4), Vector::new(0.2, -0.1, 0.05)),
            (Vector::new(0.2, 5e-3, -0.1), Vector::new(0.0, 1.0, 0.0)),
            (Vector::new(-1e-4, 1e-3, 2e-4), Vector::ZERO),
        ] {
            let l = law();
            let r = l.response((u, turn), h);
            let impulse = |u: Vector, t: Vector| {
                let r = l.response((u, t), h);
                (l.normal * r.normal + r.tangential, r.couple)
            };
            for axis in 0..3 {
                let e = Vector::from_array(std::array::from_fn(|k| (k == axis) as u8 as Real));
                let step = 1e-8;
                let (fp, _) = impulse(u + e * step, turn);
                let (fm, _) = impulse(u - e * step, turn);
                let numeric = -(fp - fm) / (2.0 * step);
                let column = r.force_rate.col(axis);
                assert!(
                    (numeric - column).length() <= 1e-5 * column.length().max(1e-9),
                    "{numeric} against {column} (sliding {})",
                    r.sliding
                );
                let (_, cp) = impulse(u, turn + e * step);
                let (_, cm) = impulse(u, turn - e * step);
                let numeric = -(cp - cm) / (2.0 * step);
                assert!((numeric - r.couple_rate.col(axis)).length() < 1e-9);
            }
            for g in [r.force_rate, r.couple_rate] {
                let largest =
                    |m: Matrix| m.to_cols_array().iter().fold(0.0, |a: Real, x| a.max(x.abs()));
                assert!(largest(g - g.transpose()) <= 1e-12 * largest(g));
                for x in [Vector::X, Vector::Y, Vector::Z, Vector::new(0.3, -0.7, 0.2)] {
                    assert!(x.dot(g * x) >= -1e-12 * largest(g));
                }
            }
        }
        // The second case slides: its impulse lies on the disc's rim.
        let r = law().response((Vector::new(0.2, 5e-3, -0.1), Vector::ZERO), h);
        assert!(r.sliding);
        assert!((r.tangential.length() - 0.5 * 2.0 * h).abs() < 1e-15);
    }

    /// A pair separating faster than its indentation can follow, or than its damping lets
    /// it push, gives no impulse: the law never pulls.
    #[test]
    fn the_law_never_pulls() {
        let l = law();
        for s in [2.1e-2, 2.6, 100.0] {
            let r = l.response((l.normal * s, Vector::ZERO), 1e-3);
            assert_eq!(r.normal, 0.0, "separating at {s} m/s");
        }
    }
}
