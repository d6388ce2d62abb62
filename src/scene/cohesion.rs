//! Cohesion: a powder's surface energy as LIGGGHTS's simplified JKR model (`cohesion sjkr`).
//!
//! SJKR adds an attraction F = k·A to every contact, A the area of the circle where the two
//! spheres' surfaces intersect (≈ 2π R* δ at overlap δ), k the cohesion energy density in J/m³.
//! Published powders state a surface energy γ in J/m² instead. The mapping keeps the force that
//! pulls two spheres apart: with a Hertz repulsion (4/3) E* √R* δ^{3/2}, the net attraction
//! k·2πR*δ − (4/3)E*√R*δ^{3/2} peaks at √δ = πk√R*/E* with (2/3) π³ k³ R*² / E*²; setting that
//! to the JKR pull-off force 3πγR* (Johnson, Kendall & Roberts 1971, γ per surface, work of
//! adhesion 2γ) gives
//!
//! k = (9 γ E*² / (2 π² R*))^{1/3},
//!
//! with R* = D/4 for two spheres of the number-mean diameter D and E* = E / (2(1 − ν²)).
//!
//! A softened Young's modulus makes contacts wider. The default (`pull-off`) computes k with the
//! deck's modulus, so the pull-off force stays that of the real surface energy (the attraction
//! force is what is kept, as Washino, Chan & Tanaka 2018, Powder Technol. 325, argue for reduced
//! stiffness). `haervig` first scales the surface energy by (E_deck / E_material)^{2/5}, which
//! keeps the adhesive energy dissipated in a collision (Hærvig et al. 2017, Powder Technol. 319).

use serde::{Deserialize, Serialize};

/// How the surface energy is carried to a softened contact.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CohesionScaling {
    /// The JKR pull-off force of the real surface energy, at the deck's modulus.
    #[default]
    PullOff,
    /// The surface energy scaled by (E_deck / E_material)^{2/5} (needs the material's modulus).
    Haervig,
}

/// SJKR's cohesion energy density, J/m³, for surface energy `gamma` (J/m²) between spheres of
/// diameter `d` (m) with Young's modulus `youngs` (Pa) and Poisson ratio `poisson`.
pub fn sjkr_energy_density(gamma: f64, d: f64, youngs: f64, poisson: f64) -> f64 {
    let r_star = d / 4.0;
    let e_star = youngs / (2.0 * (1.0 - poisson * poisson));
    (9.0 * gamma * e_star * e_star / (2.0 * std::f64::consts::PI.powi(2) * r_star)).cbrt()
}

/// The surface energy the deck's modulus stands for under `scaling` (`material_youngs`: the
/// powder's real modulus, Pa).
pub fn scaled_surface_energy(gamma: f64, scaling: CohesionScaling, youngs: f64, material_youngs: f64) -> f64 {
    match scaling {
        CohesionScaling::PullOff => gamma,
        CohesionScaling::Haervig => gamma * (youngs / material_youngs).powf(0.4),
    }
}

/// The JKR pull-off force of two spheres of diameter `d`, N: 3πγR*.
pub fn jkr_pull_off(gamma: f64, d: f64) -> f64 {
    3.0 * std::f64::consts::PI * gamma * d / 4.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest net attraction of SJKR + Hertz at one contact, N, found by scanning the
    /// overlap (independent of the closed form above).
    fn sjkr_pull_off(k: f64, d: f64, youngs: f64, poisson: f64) -> f64 {
        let r = d / 2.0;
        let e_star = youngs / (2.0 * (1.0 - poisson * poisson));
        let r_star = d / 4.0;
        (1..200_000)
            .map(|i| {
                let delta = i as f64 * 1e-6 * d * 0.01;
                let dist = 2.0 * r - delta;
                // The intersection circle's area, as LIGGGHTS's cohesion_model_sjkr computes it.
                let area = std::f64::consts::PI / 4.0
                    * ((dist - 2.0 * r) * dist * dist * (dist + 2.0 * r)).abs()
                    / (dist * dist);
                k * area - 4.0 / 3.0 * e_star * r_star.sqrt() * delta.powf(1.5)
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn the_sjkr_density_pulls_off_with_the_jkr_force() {
        // Ti-6Al-4V at 35 µm, 0.1 mJ/m², at the thesis's reduced modulus and at 1 GPa.
        for youngs in [21e6, 1e9] {
            let (gamma, d) = (1e-4, 35e-6);
            let k = sjkr_energy_density(gamma, d, youngs, 0.3);
            let got = sjkr_pull_off(k, d, youngs, 0.3);
            let want = jkr_pull_off(gamma, d);
            assert!((got / want - 1.0).abs() < 0.01, "E {youngs}: {got} N against JKR {want} N");
        }
    }

    #[test]
    fn cohesion_of_fine_titanium_outweighs_gravity() {
        // 0.1 mJ/m² at D 17 µm: the pull-off force is tens of times the weight (Meier et al.
        // 2019 state about 100 times for their adhesion force, 4πγR).
        let d: f64 = 17e-6;
        let weight = 4430.0 * std::f64::consts::PI / 6.0 * d.powi(3) * 9.81;
        let ratio = jkr_pull_off(1e-4, d) / weight;
        assert!((20.0..200.0).contains(&ratio), "{ratio}");
    }

    #[test]
    fn haervig_scaling_lowers_the_surface_energy_of_a_softened_contact() {
        let g = scaled_surface_energy(1e-4, CohesionScaling::Haervig, 21e6, 110e9);
        // (21e6 / 110e9)^0.4 = 0.0328
        assert!((g / 1e-4 - 0.0328).abs() < 5e-4, "{g}");
        assert_eq!(scaled_surface_energy(1e-4, CohesionScaling::PullOff, 21e6, 110e9), 1e-4);
    }
}
