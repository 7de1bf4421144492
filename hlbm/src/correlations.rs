//! Drag correlations for a settling sphere, the references the settling tests (and the
//! coupling's) compare with.

/// Terminal velocity (any consistent units) of a sphere of diameter `d` and density ratio
/// `ratio = ρ_p/ρ_f > 1` in a fluid of kinematic viscosity `nu` under gravity `g`, from the
/// Schiller–Naumann drag law `C_D = 24/Re (1 + 0.15 Re^0.687)` (Re < 1000): the balance
/// `(ratio − 1) g = 3/4 C_D(Re) U² / d`, solved by damped fixed-point iteration from the Stokes
/// velocity.
pub fn schiller_naumann_terminal_velocity(d: f64, nu: f64, ratio: f64, g: f64) -> f64 {
    let mut u = (ratio - 1.0) * g * d * d / (18.0 * nu);
    for _ in 0..200 {
        let re = u * d / nu;
        let cd = 24.0 / re * (1.0 + 0.15 * re.powf(0.687));
        u = 0.5 * u + 0.5 * ((ratio - 1.0) * g * d * 4.0 / (3.0 * cd)).sqrt();
    }
    u
}

/// Di Felice (1996): terminal velocity in a tube or box of width `W` over the unbounded one,
/// `((1 − λ)/(1 − 0.33 λ))^α` with `λ = d / W` and `α = (3.3 + 0.085 Re)/(1 + 0.1 Re)`.
pub fn di_felice_wall_factor(lambda: f64, re: f64) -> f64 {
    let alpha = (3.3 + 0.085 * re) / (1.0 + 0.1 * re);
    ((1.0 - lambda) / (1.0 - 0.33 * lambda)).powf(alpha)
}

/// Richardson & Zaki (1954) exponent `n` of the hindered settling law `⟨v⟩/v_s = (1 − φ)^n`,
/// with `Re = v_s d / ν` of the single sphere: 4.65 for Re ≤ 0.2, `4.35 Re^−0.03` up to 1,
/// `4.45 Re^−0.1` up to 500, 2.39 above.
pub fn richardson_zaki_exponent(re: f64) -> f64 {
    if re <= 0.2 {
        4.65
    } else if re <= 1.0 {
        4.35 * re.powf(-0.03)
    } else if re <= 500.0 {
        4.45 * re.powf(-0.1)
    } else {
        2.39
    }
}

/// Garside & Al-Dibouni (1977) exponent `n = (5.1 + 0.27 Re^0.9)/(1 + 0.1 Re^0.9)` of the
/// same law.
pub fn garside_al_dibouni_exponent(re: f64) -> f64 {
    let r = re.powf(0.9);
    (5.1 + 0.27 * r) / (1.0 + 0.1 * r)
}

/// Hasimoto (1959) and Sangani & Acrivos (1982): drag factor `K = F / (6π μ a U)` of a simple
/// cubic array of spheres at volume fraction `φ` in Stokes flow, `U` the spheres' velocity
/// relative to the zero-volume-flux frame and `F` the whole force the fluid exerts on a sphere
/// (the array's mean pressure gradient included):
/// `1/K = 1 − 1.7601 φ^(1/3) + φ − 1.5593 φ² + 3.9799 φ^(8/3) − 3.0734 φ^(10/3)`
/// (the series of the periodic Stokeslet sum; within ~1 % of the exact values up to φ ≈ 0.1).
/// A sphere alone in a triply periodic cubic box is such an array: it settles at `U_stokes/K`.
pub fn cubic_array_drag_factor(phi: f64) -> f64 {
    let s = phi.cbrt();
    1.0 / (1.0 - 1.7601 * s + phi - 1.5593 * phi * phi + 3.9799 * phi.powf(8.0 / 3.0)
        - 3.0734 * phi.powf(10.0 / 3.0))
}
