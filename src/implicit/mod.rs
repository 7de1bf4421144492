//! The implicit step of an island of touching bodies: their velocities at the end of a step
//! of length `h` such that every contact's force law, taken where the step leaves the contact,
//! balances the change of momentum — one convex problem per island, solved by Newton's method.
//!
//! Explicit integration of a stiff contact needs steps well inside its period (microseconds
//! for steel), whatever the scene. Taking the forces at the end of the step instead keeps the
//! step stable at any stiffness: a contact compressed too far in one step is pushed out at
//! most at the speed that undoes the compression within the step, never with the spring's
//! whole stored energy. Following Castro, Permenter & Han (2022, "An unconstrained convex
//! formulation of compliant contact", doi:10.1109/TRO.2022.3157039) the end-of-step
//! velocities `v` minimise
//!
//! ```text
//! ℓ(v) = ½ (v − v*)ᵀ M (v − v*) + Σ_c ℓ_c(J_c v)
//! ```
//!
//! where `v*` is where gravity and the other forces alone would take the bodies, `J_c` gives
//! contact `c`'s relative motion and `−∇ℓ_c` is its impulse over the step ([`law`]): each
//! contact's impulse falls monotonically as its bodies separate faster, so each `ℓ_c` is
//! convex and so is `ℓ`. Its minimum is unique; Newton's method with an exact line search
//! along each direction (the line's slope rises monotonically) reaches it from any start.
//! Each Newton system `(M + Σ J_cᵀ G_c J_c) Δ = −∇ℓ` is a block matrix on the island's body
//! graph ([`cholesky`]).
//!
//! Friction's disc is fixed during a solve (the normal force of the solve before); a solve
//! whose normal forces move the discs is repeated from where it ended until they settle.

mod cholesky;
pub(crate) mod law;

use crate::math::{Matrix, Real, Vector};
use cholesky::{Block, BlockCholesky, Column, ZERO};
pub(crate) use law::{JointLaw, Law, Motion, NormalLaw, Response, SpringLaw, StepLaw};

/// A body of an island.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct IslandBody {
    /// Inverse mass per axis (1/kg, world; zero on a locked axis).
    pub inverse_mass: Vector,
    /// Inverse inertia tensor (world; rows and columns of locked axes zero).
    pub inverse_inertia: Matrix,
    /// Velocity at the start of the step: where the search starts.
    pub start: Motion,
    /// Velocity at the end of the step without the island's contacts (`v*`).
    pub free: Motion,
}

impl IslandBody {
    /// The mass matrix over the free axes (zero rows and columns on locked ones) and which
    /// axes are free (translations, then rotations).
    fn mass(&self) -> (Block, [bool; 6]) {
        let mut m = ZERO;
        let mut free = [false; 6];
        for a in 0..3 {
            let inv = self.inverse_mass[a];
            if inv > 0.0 {
                m[a][a] = 1.0 / inv;
                free[a] = true;
            }
        }
        let j = self.inverse_inertia;
        let axes: Vec<usize> = (0..3).filter(|&a| j.col(a)[a] > 0.0).collect();
        // The inertia over the free rotation axes: the inverse of the inverse's block there.
        let sub = |r: usize, c: usize| j.col(axes[c])[axes[r]];
        let inverse: Vec<Vec<Real>> = match axes.len() {
            1 => vec![vec![1.0 / sub(0, 0)]],
            2 => {
                let det = sub(0, 0) * sub(1, 1) - sub(0, 1) * sub(1, 0);
                vec![
                    vec![sub(1, 1) / det, -sub(0, 1) / det],
                    vec![-sub(1, 0) / det, sub(0, 0) / det],
                ]
            }
            3 => {
                let i = j.inverse();
                (0..3).map(|r| (0..3).map(|c| i.col(c)[r]).collect()).collect()
            }
            _ => Vec::new(),
        };
        for (x, &r) in axes.iter().enumerate() {
            free[3 + r] = true;
            for (y, &c) in axes.iter().enumerate() {
                m[3 + r][3 + c] = inverse[x][y];
            }
        }
        (m, free)
    }

    /// `M⁻¹ p`.
    fn yield_to(&self, (f, t): Motion) -> Motion {
        (f * self.inverse_mass, self.inverse_inertia * t)
    }
}

/// Why an island's step could not be solved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Failure {
    /// Newton's method did not reach the tolerance in [`MAX_NEWTON_ITERATIONS`]: the residual
    /// left, relative to the island's impulses.
    NotConverged { residual: Real },
    /// A Newton system was not positive definite (a body without mass, a non-finite law).
    Singular,
}

/// Newton iterations per solve at most.
pub(crate) const MAX_NEWTON_ITERATIONS: usize = 60;

/// Solves of one step at most while friction's discs settle.
const MAX_FRICTION_PASSES: usize = 4;

/// The residual momentum, relative to the island's impulses (both in the norm of the
/// inverse mass), below which a solve has converged. Tight, since a stiff contact's
/// indentation at the end of the step is the small difference of a long step's travel and
/// where it started: a residual of `ε` moves it by `ε` times the travel. Newton's method
/// reaches it in an iteration or two more than a loose tolerance would.
pub(crate) const TOLERANCE: Real = 1e-10;

/// The residual, relative, that a solve accepts where round-off stops Newton's method
/// before [`TOLERANCE`] (its line search finds no lower point).
const ROUND_OFF_TOLERANCE: Real = 1e-6;

/// The disc radius change, relative, below which friction's discs have settled.
const DISC_TOLERANCE: Real = 1e-3;

/// An island's solution.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Solution {
    /// The bodies' velocities at the end of the step.
    pub velocities: Vec<Motion>,
    /// Each law's response at those velocities.
    pub responses: Vec<Response>,
    /// Newton iterations taken, over all friction passes.
    pub iterations: usize,
}

/// Solves the island of `bodies` joined by `laws` (with friction's discs set from their last
/// normal force, and updated) over a step of `h`. `structure` keeps the analysed block
/// structure between calls of the same graph.
pub(crate) fn solve(
    bodies: &[IslandBody],
    laws: &mut [Law],
    h: Real,
    structure: &mut Option<(Vec<(usize, usize)>, BlockCholesky)>,
) -> Result<Solution, Failure> {
    let edges: Vec<(usize, usize)> = laws
        .iter()
        .filter_map(|l| match l.bodies() {
            [Some(a), Some(b)] if a != b => Some((a.min(b), a.max(b))),
            _ => None,
        })
        .collect();
    if structure.as_ref().is_none_or(|(e, _)| *e != edges) {
        *structure = Some((edges.clone(), BlockCholesky::analyse(bodies.len(), &edges)));
    }
    let factor = &mut structure.as_mut().expect("set above").1;
    let masses: Vec<(Block, [bool; 6])> = bodies.iter().map(IslandBody::mass).collect();
    let mut v: Vec<Motion> = bodies.iter().map(|b| b.start).collect();
    let mut iterations = 0;
    for pass in 0..MAX_FRICTION_PASSES {
        iterations += newton(bodies, &masses, laws, h, factor, &mut v)?;
        // Friction's discs from the normal forces found; settled when none moved.
        let mut moved = false;
        for law in laws.iter_mut() {
            let r = law.response(law.relative(&v), h);
            let Law::Contact(law) = law else { continue };
            if let Some(spring) = law.spring.as_mut() {
                let f_n = r.normal / h;
                if (f_n - spring.normal_force).abs() > DISC_TOLERANCE * f_n.max(spring.normal_force)
                {
                    moved = true;
                }
                spring.normal_force = f_n;
            }
        }
        if !moved || pass + 1 == MAX_FRICTION_PASSES {
            break;
        }
    }
    let responses = laws.iter().map(|l| l.response(l.relative(&v), h)).collect();
    Ok(Solution { velocities: v, responses, iterations })
}

/// The gradient `M (v − v*) − Σ J_cᵀ γ_c` by body (zero on locked axes), and the norms (of the
/// inverse mass) of the residual and of the impulses, for the convergence test.
fn gradient(
    bodies: &[IslandBody],
    masses: &[(Block, [bool; 6])],
    laws: &[Law],
    h: Real,
    v: &[Motion],
) -> (Vec<Column>, Real, Real) {
    let mut impulses: Vec<Motion> = vec![(Vector::ZERO, Vector::ZERO); bodies.len()];
    for law in laws {
        let r = law.response(law.relative(v), h);
        for (end, load) in law.on_bodies(&r).into_iter().enumerate() {
            if let Some(b) = law.bodies()[end] {
                impulses[b].0 += load.0;
                impulses[b].1 += load.1;
            }
        }
    }
    let mut g = Vec::with_capacity(bodies.len());
    let (mut residual, mut scale, mut momentum) = (0.0, 0.0, 0.0);
    for (b, body) in bodies.iter().enumerate() {
        let (m, free) = &masses[b];
        let dv = column(&(v[b].0 - body.free.0, v[b].1 - body.free.1));
        let mut gb = cholesky::multiply(m, &dv);
        let j = column(&impulses[b]);
        for k in 0..6 {
            gb[k] = if free[k] { gb[k] - j[k] } else { 0.0 };
        }
        let norm = |x: &Column| {
            let (f, t) = motion(x);
            let (a, w) = body.yield_to((f, t));
            f.dot(a) + t.dot(w)
        };
        residual += norm(&gb);
        scale += norm(&j).max(norm(&cholesky::multiply(m, &dv)));
        let (v_b, free_b) = (column(&v[b]), column(&body.free));
        momentum += norm(&cholesky::multiply(m, &v_b)).max(norm(&cholesky::multiply(m, &free_b)));
        g.push(gb);
    }
    // The round-off in `M (v − v*)` of the bodies' momenta: no solve resolves less.
    let floor = ROUND_OFF * momentum.max(0.0).sqrt();
    (g, residual.max(0.0).sqrt(), scale.max(0.0).sqrt() + floor / TOLERANCE)
}

/// The residual's floor, relative to the bodies' momenta: a few units of round-off.
const ROUND_OFF: Real = 64.0 * Real::EPSILON;

/// Newton's method from `v` (left at the minimum); the iterations it took.
fn newton(
    bodies: &[IslandBody],
    masses: &[(Block, [bool; 6])],
    laws: &[Law],
    h: Real,
    factor: &mut BlockCholesky,
    v: &mut [Motion],
) -> Result<usize, Failure> {
    let n = bodies.len();
    let mut residual = Real::INFINITY;
    for iteration in 0..MAX_NEWTON_ITERATIONS {
        let (g, r, scale) = gradient(bodies, masses, laws, h, v);
        let previous = residual;
        residual = r / scale.max(Real::MIN_POSITIVE);
        if !residual.is_finite() {
            return Err(Failure::Singular);
        }
        // Converged; or stalled at round-off (Newton's method, which halves the residual's
        // digits each step near the minimum, no longer halves the residual itself).
        let stalled = residual <= ROUND_OFF_TOLERANCE && residual > 0.5 * previous;
        if r <= TOLERANCE * scale || r == 0.0 || stalled {
            return Ok(iteration);
        }
        // The Newton system: M plus each law's J_cᵀ G_c J_c.
        let mut diagonal: Vec<Block> = masses.iter().map(|(m, _)| *m).collect();
        let mut off: Vec<((usize, usize), Block)> = Vec::new();
        for law in laws {
            let w = law.relative(v);
            let resp = law.response(w, h);
            let (ends, levers) = (law.bodies(), law.levers());
            let block = |e: usize, f: usize| {
                let sign = if e == f { 1.0 } else { -1.0 };
                coupling(&resp, levers[e], levers[f], sign)
            };
            for e in 0..2 {
                let Some(a) = ends[e] else { continue };
                cholesky::add_to(&mut diagonal[a], &block(e, e));
                if e == 0 {
                    if let Some(b) = ends[1] {
                        if a == b {
                            cholesky::add_to(&mut diagonal[a], &block(0, 1));
                            cholesky::add_to(&mut diagonal[a], &block(1, 0));
                        } else {
                            off.push(((a, b), block(0, 1)));
                        }
                    }
                }
            }
        }
        // Locked axes: the identity, no coupling.
        for (b, (_, free)) in masses.iter().enumerate() {
            for k in (0..6).filter(|&k| !free[k]) {
                for c in 0..6 {
                    diagonal[b][k][c] = 0.0;
                    diagonal[b][c][k] = 0.0;
                }
                diagonal[b][k][k] = 1.0;
            }
        }
        for ((a, b), block) in off.iter_mut() {
            for k in 0..6 {
                for c in 0..6 {
                    if !masses[*a].1[k] || !masses[*b].1[c] {
                        block[k][c] = 0.0;
                    }
                }
            }
        }
        factor.factor(&diagonal, &off).map_err(|_| Failure::Singular)?;
        let mut step: Vec<Column> = g.iter().map(|g| g.map(|x| -x)).collect();
        factor.solve(&mut step);
        let direction: Vec<Motion> = step.iter().map(motion).collect();
        let alpha = line_search(bodies, masses, laws, h, v, &direction);
        if alpha == 0.0 {
            return if residual <= ROUND_OFF_TOLERANCE {
                Ok(iteration)
            } else {
                Err(Failure::NotConverged { residual })
            };
        }
        for b in 0..n {
            v[b].0 += direction[b].0 * alpha;
            v[b].1 += direction[b].1 * alpha;
        }
    }
    Err(Failure::NotConverged { residual })
}

/// The step length `α` along `direction` that minimises `ℓ(v + α Δ)`, at most 1: where the
/// slope `φ'(α) = Δᵀ ∇ℓ(v + α Δ)`, which rises monotonically, crosses zero (Newton's method
/// on `φ'` kept within a bracket).
fn line_search(
    bodies: &[IslandBody],
    masses: &[(Block, [bool; 6])],
    laws: &[Law],
    h: Real,
    v: &[Motion],
    direction: &[Motion],
) -> Real {
    // Per body: Δᵀ M Δ and Δᵀ M (v − v*); per law: its relative motion and that of Δ.
    let (mut curvature, mut offset) = (0.0, 0.0);
    for (b, body) in bodies.iter().enumerate() {
        let d = column(&direction[b]);
        let md = cholesky::multiply(&masses[b].0, &d);
        let dv = column(&(v[b].0 - body.free.0, v[b].1 - body.free.1));
        curvature += dot(&d, &md);
        offset += dot(&dv, &md);
    }
    let relative: Vec<(Motion, Motion)> =
        laws.iter().map(|l| (l.relative(v), l.relative_of(direction))).collect();
    let slope = |alpha: Real| {
        let (mut s, mut c) = (offset + alpha * curvature, curvature);
        for (law, ((u, w), (du, dw))) in laws.iter().zip(&relative) {
            let r = law.response((*u + *du * alpha, *w + *dw * alpha), h);
            let f = law.on_bodies(&r)[0].0;
            s -= f.dot(*du) + r.couple.dot(*dw);
            c += du.dot(r.force_rate * *du) + dw.dot(r.couple_rate * *dw);
        }
        (s, c)
    };
    let (s0, _) = slope(0.0);
    if !(s0 < 0.0) {
        return 0.0;
    }
    let (s1, c1) = slope(1.0);
    if s1 <= 0.0 {
        return 1.0;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    let (mut alpha, mut s, mut c) = (1.0, s1, c1);
    for _ in 0..40 {
        if s.abs() <= 1e-9 * s0.abs() {
            break;
        }
        if s > 0.0 {
            hi = alpha;
        } else {
            lo = alpha;
        }
        let newton = alpha - s / c;
        alpha = if c > 0.0 && newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
        (s, c) = slope(alpha);
    }
    alpha
}

impl Law {
    /// [`relative`](Self::relative) of a change of velocities `dv` (the given ends do not
    /// change).
    fn relative_of(&self, dv: &[Motion]) -> Motion {
        let (ends, levers) = (self.bodies(), self.levers());
        let at = |end: usize| {
            ends[end].map_or((Vector::ZERO, Vector::ZERO), |b| {
                let (v, w) = dv[b];
                (v + w.cross(levers[end]), w)
            })
        };
        let ((ua, wa), (ub, wb)) = (at(0), at(1));
        (ua - ub, wa - wb)
    }
}

/// The block `sign · J̃_eᵀ G J̃_f` that a law with rates `r` adds between its ends `e` and `f`
/// (levers `re`, `rf`), `J̃ = [[I, −[r]ₓ], [0, I]]`: `[[G_f, −G_f [r_f]ₓ], [[r_e]ₓ G_f,
/// −[r_e]ₓ G_f [r_f]ₓ + G_τ]]`.
fn coupling(r: &Response, re: Vector, rf: Vector, sign: Real) -> Block {
    let cross =
        |x: Vector| Matrix::from_cols(x.cross(Vector::X), x.cross(Vector::Y), x.cross(Vector::Z));
    let (ce, cf) = (cross(re), cross(rf));
    let g = r.force_rate;
    let parts = [[g, -(g * cf)], [ce * g, r.couple_rate - ce * g * cf]];
    let mut out = ZERO;
    for (bi, row) in parts.iter().enumerate() {
        for (bj, m) in row.iter().enumerate() {
            for i in 0..3 {
                for j in 0..3 {
                    out[3 * bi + i][3 * bj + j] = sign * m.col(j)[i];
                }
            }
        }
    }
    out
}

fn column((f, t): &Motion) -> Column {
    [f.x, f.y, f.z, t.x, t.y, t.z]
}

fn motion(c: &Column) -> Motion {
    (Vector::new(c[0], c[1], c[2]), Vector::new(c[3], c[4], c[5]))
}

fn dot(a: &Column, b: &Column) -> Real {
    (0..6).map(|k| a[k] * b[k]).sum()
}

#[cfg(test)]
mod tests;
