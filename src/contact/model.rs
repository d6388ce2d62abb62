//! Contact coefficients of LIGGGHTS 3.8 `model hertz tangential history`, for one pair.
//!
//! This module turns material and body data into the effective quantities (Y*, G*, β, R*, m*)
//! and evaluates the overlap-dependent stiffness and damping coefficients. It does not move
//! bodies or keep the tangential history; that is [`super::solver`].
//!
//! Sources (LIGGGHTS-PUBLIC 3.8.0): `src/global_properties.cpp` (`createYeff`, `createGeff`,
//! `createBetaEff`) and `src/normal_model_hertz.h` (`surfacesIntersect`). Thesis §3.1,
//! Eq. 2–12, with Eq. 2 corrected: for two bodies of one material E* = E/(2(1−ν²)).

/// √(5/6), the prefactor of the Hertz damping coefficients (`normal_model_hertz.h`).
const SQRT_FIVE_OVER_SIX: f64 = 0.912_870_929_175_276_9;

/// Elastic constants of one body (a sphere or a wall type).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Young's modulus Y in Pa. A wall may be `f64::INFINITY` (a rigid plane; LIGGGHTS cannot
    /// express that).
    pub youngs: f64,
    /// Poisson's ratio ν, 0 ≤ ν ≤ 0.5.
    pub poisson: f64,
}

impl Material {
    /// (1 − ν²)/Y in 1/Pa: this body's share of 1/Y* (0 for a rigid body).
    fn normal_compliance(&self) -> f64 {
        (1.0 - self.poisson * self.poisson) / self.youngs
    }

    /// 2(2 − ν)(1 + ν)/Y in 1/Pa: this body's share of 1/G* (0 for a rigid body).
    fn shear_compliance(&self) -> f64 {
        2.0 * (2.0 - self.poisson) * (1.0 + self.poisson) / self.youngs
    }
}

/// Effective Young's modulus in Pa: Y* = 1/((1−νi²)/Yi + (1−νj²)/Yj)
/// (`global_properties.cpp`, `createYeff`; thesis Eq. 2 corrected).
pub fn effective_youngs(i: Material, j: Material) -> f64 {
    1.0 / (i.normal_compliance() + j.normal_compliance())
}

/// Effective shear modulus in Pa: G* = 1/(2(2−νi)(1+νi)/Yi + 2(2−νj)(1+νj)/Yj)
/// (`global_properties.cpp`, `createGeff`; thesis Eq. 3).
pub fn effective_shear(i: Material, j: Material) -> f64 {
    1.0 / (i.shear_compliance() + j.shear_compliance())
}

/// Damping ratio from the restitution coefficient: β = ln e / √(ln²e + π²), β ≤ 0
/// (`global_properties.cpp`, `createBetaEff`; thesis Eq. 6).
pub fn beta(restitution: f64) -> f64 {
    let l = restitution.ln();
    l / (l * l + std::f64::consts::PI * std::f64::consts::PI).sqrt()
}

/// The constant (overlap-independent) coefficients of one contact pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair {
    /// Y* in Pa.
    pub y_eff: f64,
    /// G* in Pa.
    pub g_eff: f64,
    /// β (dimensionless, ≤ 0).
    pub beta: f64,
    /// Coulomb friction coefficient μ.
    pub friction: f64,
    /// R* in m: ri rj/(ri + rj), or ri against a wall (`normal_model_hertz.h`).
    pub r_eff: f64,
    /// m* in kg: mi mj/(mi + mj), or mi against a wall.
    pub m_eff: f64,
}

/// Overlap-dependent coefficients, as `normal_model_hertz.h` computes them each step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stiffness {
    /// kn = 4/3 Y* √(R* δn), in N/m^1.5·m^0.5 = N/m per unit overlap (Fn = kn δn).
    pub kn: f64,
    /// kt = St = 8 G* √(R* δn), in N/m (the tangential spring acts on the total shear).
    pub kt: f64,
    /// γn = −2 √(5/6) β √(Sn m*), Sn = 2 Y* √(R* δn), in N·s/m.
    pub gamma_n: f64,
    /// γt = −2 √(5/6) β √(St m*), St = kt, in N·s/m.
    pub gamma_t: f64,
}

impl Pair {
    /// The coefficients at normal overlap `deltan` (m, > 0).
    pub fn at(&self, deltan: f64) -> Stiffness {
        let sqrtval = (self.r_eff * deltan).sqrt();
        let sn = 2.0 * self.y_eff * sqrtval;
        let st = 8.0 * self.g_eff * sqrtval;
        Stiffness {
            kn: 4.0 / 3.0 * self.y_eff * sqrtval,
            kt: st,
            gamma_n: -2.0 * SQRT_FIVE_OVER_SIX * self.beta * (sn * self.m_eff).sqrt(),
            gamma_t: -2.0 * SQRT_FIVE_OVER_SIX * self.beta * (st * self.m_eff).sqrt(),
        }
    }

    /// Hertz contact duration of an elastic impact at normal speed `vn` (m/s), in s:
    /// t_c = 2.868 (m*²/(R* Y*² vn))^(1/5) (Johnson, Contact Mechanics §11.4; the constant is
    /// 2·(15/16)^(2/5)·√π·Γ(2/5)/Γ(9/10)·(2/5)).
    pub fn hertz_time(&self, vn: f64) -> f64 {
        HERTZ_TIME_CONSTANT
            * (self.m_eff * self.m_eff / (self.r_eff * self.y_eff * self.y_eff * vn)).powf(0.2)
    }

    /// Hertz maximum overlap of an elastic impact at normal speed `vn` (m/s), in m:
    /// δmax = (15 m* vn² / (16 Y* √R*))^(2/5).
    pub fn hertz_max_overlap(&self, vn: f64) -> f64 {
        (15.0 * self.m_eff * vn * vn / (16.0 * self.y_eff * self.r_eff.sqrt())).powf(0.4)
    }
}

/// t_c·vn/δmax of the elastic Hertz impact: 2 ∫₀¹ dx/√(1 − x^(5/2)) = 2.9432 (Johnson,
/// Contact Mechanics Eq. 11.24), times (15/16)^(2/5) gives 2.8683.
const HERTZ_TIME_CONSTANT: f64 = 2.868_265;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_material_effective_youngs_is_e_over_two_one_minus_nu_squared() {
        let m = Material { youngs: 21e6, poisson: 0.3 };
        let expected = 21e6 / (2.0 * (1.0 - 0.09));
        assert!((effective_youngs(m, m) / expected - 1.0).abs() < 1e-14);
        let g_expected = 21e6 / (4.0 * (2.0 - 0.3) * 1.3);
        assert!((effective_shear(m, m) / g_expected - 1.0).abs() < 1e-14);
    }

    #[test]
    fn rigid_wall_leaves_the_particle_compliance_only() {
        let m = Material { youngs: 21e6, poisson: 0.3 };
        let wall = Material { youngs: f64::INFINITY, poisson: 0.3 };
        assert!((effective_youngs(m, wall) / (21e6 / 0.91) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn beta_is_zero_at_e_one_and_matches_ln_form() {
        assert_eq!(beta(1.0), 0.0);
        // e = exp(-π) gives β = -π/√(2π²) = -1/√2.
        let b = beta((-std::f64::consts::PI).exp());
        assert!((b + std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-14);
    }

    #[test]
    fn hertz_time_constant_matches_the_integral() {
        // 2 ∫0^1 dx / sqrt(1 - x^2.5) by the substitution x = 1 - s², midpoint rule.
        let n = 200_000;
        let mut integral = 0.0;
        for k in 0..n {
            let s = (k as f64 + 0.5) / n as f64;
            let x: f64 = 1.0 - s * s;
            integral += 2.0 * s / (1.0 - x.powf(2.5)).sqrt() / n as f64;
        }
        let constant = 2.0 * integral * (15.0f64 / 16.0).powf(0.4);
        assert!((constant / HERTZ_TIME_CONSTANT - 1.0).abs() < 1e-5, "{constant}");
    }
}
