//! Particle against wall moduli over six decades, against closed form.
//!
//! Hertz contact has no stiffness scale of its own: at a timestep that is a fixed fraction of
//! the contact time the whole impact is self-similar in Y*, so t_c/t_Hertz, δmax/δHertz and the
//! achieved restitution must come out the same for every modulus ratio. What changes is (a) the
//! overlap against the radius, δ/R = (Y*_cross/Y*)^(2/5) with Y*_cross = (5π/4) ρ vn² (from
//! δmax = (15 m vn²/(16 Y* √R))^(2/5) and m = 4/3 π R³ ρ): past δ/R ≈ 0.1 small-strain Hertz is
//! out of its range, and at Y* ≤ Y*_cross the centre crosses the wall plane and the contact law
//! means nothing; (b) at the scene's fixed timestep (a fraction of the PARTICLE's Rayleigh
//! time) the steps per contact, which a stiffer wall lowers by at most 2^(2/5) (Y* can at most
//! double over a same-material wall).

use serde::Serialize;

use super::{scene_case, SCENE_MATERIAL};
use crate::bench::cell;
use crate::contact::{Case, ContactError, Material, Target};

/// δmax/R above which a row is flagged: Hertz assumes a contact radius a = √(Rδ) ≪ R; here
/// a/R > 0.32.
pub const SMALL_STRAIN_OVERLAP: f64 = 0.1;

/// LIGGGHTS' modulus range in SI units without `soft_particles yes` / `hard_particles yes`
/// (`global_properties.cpp`).
pub const LIGGGHTS_MODULI: (f64, f64) = (5e6, 1e9);

/// What a LIGGGHTS deck needs to hold the two moduli (`global_properties.cpp`, checked on the
/// installed 3.8.0: below the floor it asks for `soft_particles yes`, above the ceiling for
/// `hard_particles yes`); a rigid wall it cannot hold.
pub fn liggghts_flags(particle: f64, wall: f64) -> &'static str {
    let (lo, hi) = LIGGGHTS_MODULI;
    if wall.is_infinite() {
        return "no (rigid)";
    }
    let soft = particle < lo || wall < lo;
    let hard = particle > hi || wall > hi;
    match (soft, hard) {
        (false, false) => "yes",
        (true, false) => "soft_particles yes",
        (false, true) => "hard_particles yes",
        (true, true) => "soft+hard_particles",
    }
}

/// Particle moduli: LIGGGHTS' floor, the scene's, LIGGGHTS' ceiling (Pa).
pub const PARTICLE_MODULI: [f64; 3] = [5e6, SCENE_MATERIAL.youngs, 1e9];

/// Wall / particle modulus ratios; infinity is a rigid wall.
pub const RATIOS: [f64; 8] = [1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3, f64::INFINITY];

/// The nominal restitution of the damped runs.
pub const DAMPED_RESTITUTION: f64 = 0.5;

/// Y* of a particle of modulus `e_p` on a wall of modulus q·e_p, both of Poisson's ratio ν:
/// E_p q / ((1 + q)(1 − ν²)), E_p/(1 − ν²) for a rigid wall.
pub fn closed_form_youngs(e_p: f64, q: f64, nu: f64) -> f64 {
    let share = if q.is_infinite() { 1.0 } else { q / (1.0 + q) };
    e_p * share / (1.0 - nu * nu)
}

/// One particle modulus and wall ratio.
#[derive(Debug, Clone, Serialize)]
pub struct StiffnessRow {
    pub particle_youngs_pa: f64,
    /// Infinite for a rigid wall (written `inf`).
    pub wall_youngs_pa: f64,
    pub ratio: f64,
    /// What a LIGGGHTS deck needs for the two moduli ([`liggghts_flags`]).
    pub liggghts: &'static str,
    /// The solver's Y*, Pa.
    pub y_eff_pa: f64,
    /// Solver Y* / [`closed_form_youngs`] − 1.
    pub y_eff_error: f64,
    /// Elastic Hertz δmax/R from the closed-form Y*.
    pub overlap_ratio: f64,
    /// e = 1, default dt: measured contact time / Hertz − 1.
    pub contact_time_error: Option<f64>,
    /// e = 1, default dt: measured δmax / Hertz − 1.
    pub max_overlap_error: Option<f64>,
    /// e = 1, default dt: achieved restitution − 1.
    pub elastic_restitution_error: Option<f64>,
    /// e = [`DAMPED_RESTITUTION`], default dt: achieved − nominal.
    pub damped_restitution_error: Option<f64>,
    /// Hertz contact time / the scene's timestep (0.2 × the particle's Rayleigh time).
    pub scene_steps_per_contact: f64,
    /// e = [`DAMPED_RESTITUTION`] at the scene's timestep: achieved − nominal.
    pub scene_restitution_error: Option<f64>,
    /// "ok", "beyond small strain", or why a run failed.
    pub verdict: String,
}

/// Runs every particle modulus against every wall ratio: the scene's D 2 mm particle
/// (ρ 7980 kg/m³, ν 0.3) at 1 m/s, e = 1 and e = 0.5, at the default timestep and at the
/// scene's.
pub fn run(particle_moduli: &[f64], ratios: &[f64]) -> Vec<StiffnessRow> {
    let mut rows = Vec::new();
    for &e_p in particle_moduli {
        for &q in ratios {
            rows.push(row(e_p, q));
        }
    }
    rows
}

fn row(e_p: f64, q: f64) -> StiffnessRow {
    let base = scene_case();
    let particle = Material { youngs: e_p, ..SCENE_MATERIAL };
    let wall = Material { youngs: q * e_p, ..SCENE_MATERIAL };
    let elastic = Case { material: particle, target: Target::Wall(wall), ..base };
    let damped = Case { restitution: DAMPED_RESTITUTION, ..elastic };
    let y_closed = closed_form_youngs(e_p, q, SCENE_MATERIAL.poisson);
    let pair = elastic.pair();
    let hertz_time = pair.hertz_time(elastic.vn);
    let hertz_overlap = pair.hertz_max_overlap(elastic.vn);
    let settings = crate::scene::settings::SceneSettings::default();
    let scene_dt = settings.rayleigh_fraction
        * crate::scene::rayleigh_time(base.radius, base.density, e_p, SCENE_MATERIAL.poisson);

    let mut failures: Vec<String> = Vec::new();
    let mut outcome = |c: &Case| match crate::contact::run(c) {
        Ok(o) => Some(o),
        Err(e) => {
            let e: ContactError = e;
            let text = e.to_string();
            if !failures.contains(&text) {
                failures.push(text);
            }
            None
        }
    };
    let el = outcome(&elastic);
    let da = outcome(&damped);
    let sc = outcome(&Case { dt: Some(scene_dt), ..damped });

    let liggghts = liggghts_flags(e_p, q * e_p);
    let overlap_ratio =
        (15.0 * elastic.mass() * elastic.vn.powi(2) / (16.0 * y_closed * elastic.radius.sqrt())).powf(0.4)
            / elastic.radius;
    let verdict = if !failures.is_empty() {
        failures.join("; ")
    } else if overlap_ratio > SMALL_STRAIN_OVERLAP {
        format!("beyond small strain (delta/R > {SMALL_STRAIN_OVERLAP})")
    } else {
        "ok".to_string()
    };
    StiffnessRow {
        particle_youngs_pa: e_p,
        wall_youngs_pa: q * e_p,
        ratio: q,
        liggghts,
        y_eff_pa: pair.y_eff,
        y_eff_error: pair.y_eff / y_closed - 1.0,
        overlap_ratio,
        contact_time_error: el.map(|o| o.contact_time / hertz_time - 1.0),
        max_overlap_error: el.map(|o| o.max_overlap / hertz_overlap - 1.0),
        elastic_restitution_error: el.map(|o| o.restitution_n - 1.0),
        damped_restitution_error: da.map(|o| o.restitution_n - DAMPED_RESTITUTION),
        scene_steps_per_contact: hertz_time / scene_dt,
        scene_restitution_error: sc.map(|o| o.restitution_n - DAMPED_RESTITUTION),
        verdict,
    }
}

/// A fixed-width table of the rows.
pub fn table(rows: &[StiffnessRow]) -> String {
    let mut out = format!(
        "{:>8} {:>8} {:>18} {:>9} {:>7} {:>9} {:>9} {:>9} {:>9} {:>6} {:>9}  verdict\n",
        "E_p Pa",
        "q",
        "LIGGGHTS",
        "Y* err",
        "dmax/R",
        "t_c err",
        "e=1 err",
        "e=.5 err",
        "dmax err",
        "scn n",
        "scn e err"
    );
    for r in rows {
        out += &format!(
            "{:>8.1e} {:>8.0e} {:>18} {:>9} {:>7.4} {:>9} {:>9} {:>9} {:>9} {:>6.1} {:>9}  {}\n",
            r.particle_youngs_pa,
            r.ratio,
            r.liggghts,
            cell(Some(r.y_eff_error)),
            r.overlap_ratio,
            cell(r.contact_time_error),
            cell(r.elastic_restitution_error),
            cell(r.damped_restitution_error),
            cell(r.max_overlap_error),
            r.scene_steps_per_contact,
            cell(r.scene_restitution_error),
            r.verdict
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn liggghts_flags_follow_its_modulus_range() {
        assert_eq!(liggghts_flags(21e6, 21e6), "yes");
        assert_eq!(liggghts_flags(21e6, 2.1e4), "soft_particles yes");
        assert_eq!(liggghts_flags(21e6, 2.1e10), "hard_particles yes");
        assert_eq!(liggghts_flags(1e6, 2e9), "soft+hard_particles");
        assert_eq!(liggghts_flags(21e6, f64::INFINITY), "no (rigid)");
    }

    #[test]
    fn closed_form_youngs_spans_same_material_to_rigid() {
        let same = closed_form_youngs(21e6, 1.0, 0.3);
        assert!((same / (21e6 / (2.0 * 0.91)) - 1.0).abs() < 1e-15);
        let rigid = closed_form_youngs(21e6, f64::INFINITY, 0.3);
        assert!((rigid / (21e6 / 0.91) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn a_wall_soft_enough_to_be_crossed_is_a_verdict_not_a_number() {
        // ρ 7980, 1 m/s: Y*_cross = 3.13e4 Pa; 21 MPa on 21 kPa gives Y* = 2.3e4.
        let r = row(21e6, 1e-3);
        assert!(r.contact_time_error.is_none(), "{r:?}");
        assert!(r.verdict.contains("passed through"), "{}", r.verdict);
        assert!(r.overlap_ratio > 1.0);
        let r = row(21e6, 1.0);
        assert_eq!(r.verdict, "ok");
    }
}
