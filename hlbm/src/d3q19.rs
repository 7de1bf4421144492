//! The D3Q19 velocity set and the BGK collision with EDM forcing on blocks of `LANES` cells.

/// Number of discrete velocities.
pub const Q: usize = 19;

/// Cells processed together (8 f64 = one AVX-512 register).
pub const LANES: usize = 8;

/// Discrete velocities; `OPP[i] = i + 9` for `1 <= i <= 9`.
pub const C: [[i32; 3]; Q] = [
    [0, 0, 0],
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 1, 0],
    [1, -1, 0],
    [1, 0, 1],
    [1, 0, -1],
    [0, 1, 1],
    [0, 1, -1],
    [-1, 0, 0],
    [0, -1, 0],
    [0, 0, -1],
    [-1, -1, 0],
    [-1, 1, 0],
    [-1, 0, -1],
    [-1, 0, 1],
    [0, -1, -1],
    [0, -1, 1],
];

/// Opposite direction.
pub const OPP: [usize; Q] = [0, 10, 11, 12, 13, 14, 15, 16, 17, 18, 1, 2, 3, 4, 5, 6, 7, 8, 9];

/// Lattice weights.
pub const W: [f64; Q] = [
    1.0 / 3.0,
    1.0 / 18.0,
    1.0 / 18.0,
    1.0 / 18.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 18.0,
    1.0 / 18.0,
    1.0 / 18.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
];

/// Second-order equilibrium `w_i ρ (1 + 3 c·u + 4.5 (c·u)² - 1.5 u²)`.
#[inline(always)]
pub fn equilibrium(i: usize, rho: f64, u: [f64; 3]) -> f64 {
    let c = C[i];
    let cu = c[0] as f64 * u[0] + c[1] as f64 * u[1] + c[2] as f64 * u[2];
    let u2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    W[i] * rho * (1.0 + 3.0 * cu + 4.5 * cu * cu - 1.5 * u2)
}

/// Moments of a block: density and velocity `Σ f c / ρ`.
#[inline(always)]
pub fn moments(f: &[[f64; LANES]; Q]) -> ([f64; LANES], [[f64; LANES]; 3]) {
    let mut rho = [0.0; LANES];
    let mut j = [[0.0; LANES]; 3];
    for l in 0..LANES {
        // Written out: the compiler keeps all of it in registers and vectorises over `l`.
        let f = |i: usize| f[i][l];
        rho[l] = f(0) + f(1) + f(2) + f(3) + f(4) + f(5) + f(6) + f(7) + f(8) + f(9) + f(10) + f(11) + f(12) + f(13) + f(14) + f(15) + f(16) + f(17) + f(18);
        j[0][l] = f(1) - f(10) + f(4) - f(13) + f(5) - f(14) + f(6) - f(15) + f(7) - f(16);
        j[1][l] = f(2) - f(11) + f(4) - f(13) - f(5) + f(14) + f(8) - f(17) + f(9) - f(18);
        j[2][l] = f(3) - f(12) + f(6) - f(15) - f(7) + f(16) + f(8) - f(17) - f(9) + f(18);
    }
    let mut u = [[0.0; LANES]; 3];
    for l in 0..LANES {
        let inv = 1.0 / rho[l];
        for d in 0..3 {
            u[d][l] = j[d][l] * inv;
        }
    }
    (rho, u)
}

/// BGK collision of a block in place: `f ← f + ω (f_eq(u) - f)`, plus the exact-difference
/// source `f_eq(u + Δu) - f_eq(u)` when `du` is given. Returns `(ρ, u + Δu/2)`, the physical
/// density and velocity.
#[inline(always)]
pub fn collide(f: &mut [[f64; LANES]; Q], omega: f64, du: Option<&[[f64; LANES]; 3]>) -> ([f64; LANES], [[f64; LANES]; 3]) {
    let (rho, u) = moments(f);
    let mut out_u = u;
    match du {
        None => {
            for i in 0..Q {
                for l in 0..LANES {
                    let feq = equilibrium(i, rho[l], [u[0][l], u[1][l], u[2][l]]);
                    f[i][l] += omega * (feq - f[i][l]);
                }
            }
        }
        Some(du) => {
            for i in 0..Q {
                for l in 0..LANES {
                    let ul = [u[0][l], u[1][l], u[2][l]];
                    let us = [ul[0] + du[0][l], ul[1] + du[1][l], ul[2] + du[2][l]];
                    let feq = equilibrium(i, rho[l], ul);
                    f[i][l] += omega * (feq - f[i][l]) + equilibrium(i, rho[l], us) - feq;
                }
            }
            for d in 0..3 {
                for l in 0..LANES {
                    out_u[d][l] += 0.5 * du[d][l];
                }
            }
        }
    }
    (rho, out_u)
}
