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

/// Lattice weights: 1/3 at rest, 1/18 along the axes, 1/36 along the face diagonals.
pub const W: [f64; Q] = {
    let mut w = [0.0; Q];
    let mut i = 0;
    while i < Q {
        let c2 = C[i][0] * C[i][0] + C[i][1] * C[i][1] + C[i][2] * C[i][2];
        w[i] = match c2 {
            0 => 1.0 / 3.0,
            1 => 1.0 / 18.0,
            _ => 1.0 / 36.0,
        };
        i += 1;
    }
    w
};

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
        rho[l] = f(0)
            + f(1)
            + f(2)
            + f(3)
            + f(4)
            + f(5)
            + f(6)
            + f(7)
            + f(8)
            + f(9)
            + f(10)
            + f(11)
            + f(12)
            + f(13)
            + f(14)
            + f(15)
            + f(16)
            + f(17)
            + f(18);
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

/// Calls `$body!(i, opp, cx, cy, cz, w)` for each of the nine opposite pairs, with compile-time
/// constants, so the compiler unrolls and drops the zero velocity components.
macro_rules! for_each_pair {
    ($body:ident) => {
        $body!(1, 10, 1.0, 0.0, 0.0, 1.0 / 18.0);
        $body!(2, 11, 0.0, 1.0, 0.0, 1.0 / 18.0);
        $body!(3, 12, 0.0, 0.0, 1.0, 1.0 / 18.0);
        $body!(4, 13, 1.0, 1.0, 0.0, 1.0 / 36.0);
        $body!(5, 14, 1.0, -1.0, 0.0, 1.0 / 36.0);
        $body!(6, 15, 1.0, 0.0, 1.0, 1.0 / 36.0);
        $body!(7, 16, 1.0, 0.0, -1.0, 1.0 / 36.0);
        $body!(8, 17, 0.0, 1.0, 1.0, 1.0 / 36.0);
        $body!(9, 18, 0.0, 1.0, -1.0, 1.0 / 36.0);
    };
}
pub(crate) use for_each_pair;

/// BGK collision of a block in place: `f ← f + ω (f_eq(u) - f)`, plus the exact-difference
/// source `f_eq(u + Δu) - f_eq(u)` when `du` is given. Returns `(ρ, u + Δu/2)`, the physical
/// density and velocity.
///
/// The equilibrium of each opposite pair shares its even part `w ρ (1 + 4.5 (c·u)² - 1.5 u²)`
/// and differs in the sign of the odd part `3 w ρ c·u`, which halves the arithmetic. Lanes are
/// innermost, so every statement is one vector operation over the block.
#[inline(always)]
pub fn collide(
    f: &mut [[f64; LANES]; Q],
    omega: f64,
    du: Option<&[[f64; LANES]; 3]>,
) -> ([f64; LANES], [[f64; LANES]; 3]) {
    let (rho, u) = moments(f);
    collide_at(f, omega, du, rho, u)
}

/// [`collide`] with the block's [`moments`] `(ρ, u)` already taken (a block with particle
/// nodes needs `u` for its forcing term first).
#[inline(always)]
#[allow(clippy::neg_multiply)] // the velocity components are `for_each_pair!`'s constants, ±1
pub fn collide_at(
    f: &mut [[f64; LANES]; Q],
    omega: f64,
    du: Option<&[[f64; LANES]; 3]>,
    rho: [f64; LANES],
    u: [[f64; LANES]; 3],
) -> ([f64; LANES], [[f64; LANES]; 3]) {
    let mut usq = [0.0; LANES];
    for l in 0..LANES {
        usq[l] = 1.5 * (u[0][l] * u[0][l] + u[1][l] * u[1][l] + u[2][l] * u[2][l]);
    }
    match du {
        None => {
            for l in 0..LANES {
                f[0][l] += omega * (rho[l] / 3.0 * (1.0 - usq[l]) - f[0][l]);
            }
            macro_rules! pair {
                ($i:expr, $j:expr, $cx:expr, $cy:expr, $cz:expr, $w:expr) => {
                    for l in 0..LANES {
                        let cu = $cx * u[0][l] + $cy * u[1][l] + $cz * u[2][l];
                        let wr = $w * rho[l];
                        let even = wr * (1.0 - usq[l] + 4.5 * cu * cu);
                        let odd = 3.0 * wr * cu;
                        f[$i][l] += omega * (even + odd - f[$i][l]);
                        f[$j][l] += omega * (even - odd - f[$j][l]);
                    }
                };
            }
            for_each_pair!(pair);
            (rho, u)
        }
        Some(du) => {
            let mut s = [[0.0; LANES]; 3];
            let mut ssq = [0.0; LANES];
            for l in 0..LANES {
                for d in 0..3 {
                    s[d][l] = u[d][l] + du[d][l];
                }
                ssq[l] = 1.5 * (s[0][l] * s[0][l] + s[1][l] * s[1][l] + s[2][l] * s[2][l]);
            }
            // f + ω (feq(u) - f) + feq(u+Δu) - feq(u) = f (1-ω) + (ω-1) feq(u) + feq(u+Δu)
            let a = omega - 1.0;
            for l in 0..LANES {
                f[0][l] =
                    f[0][l] * (1.0 - omega) + rho[l] / 3.0 * (a * (1.0 - usq[l]) + (1.0 - ssq[l]));
            }
            macro_rules! pair {
                ($i:expr, $j:expr, $cx:expr, $cy:expr, $cz:expr, $w:expr) => {
                    for l in 0..LANES {
                        let cu = $cx * u[0][l] + $cy * u[1][l] + $cz * u[2][l];
                        let cs = $cx * s[0][l] + $cy * s[1][l] + $cz * s[2][l];
                        let wr = $w * rho[l];
                        let even = wr
                            * (a * (1.0 - usq[l] + 4.5 * cu * cu) + (1.0 - ssq[l] + 4.5 * cs * cs));
                        let odd = 3.0 * wr * (a * cu + cs);
                        f[$i][l] = f[$i][l] * (1.0 - omega) + even + odd;
                        f[$j][l] = f[$j][l] * (1.0 - omega) + even - odd;
                    }
                };
            }
            for_each_pair!(pair);
            let mut out_u = u;
            for d in 0..3 {
                for l in 0..LANES {
                    out_u[d][l] += 0.5 * du[d][l];
                }
            }
            (rho, out_u)
        }
    }
}
