//! Kinetic-energy drift at e = 1 over many consecutive contacts ([`bounce`]).
//!
//! Closed form: without friction the kinetic energy after every contact equals the initial one.
//! With friction the box of [`bounce`] sheds all tangential and rotational energy — rolling
//! without slip on both walls at once needs v_t = 0 and ω = 0 — and keeps the normal ½ m vn²
//! (at e = 1 the normal force is conservative and does not see the tangential state). Whatever
//! else the energy does is the integrator's error.

use std::time::Instant;

use serde::Serialize;

use super::scene_case;
use crate::bench::cell;
use crate::contact::bounce::{bounce, kinetic_energy};
use crate::contact::solver::initial_state;
use crate::contact::{Case, ContactError};

/// The cases: the scene's D 2 mm particle on a same-material wall at 1 m/s, e = 1 — head-on,
/// oblique with spin (frictionless, so v_t and ω must not change), and with friction μ = 0.3
/// (the tangential spring and the Coulomb limit at work).
pub fn default_cases() -> Vec<(&'static str, Case)> {
    let base = scene_case();
    vec![
        ("normal", base),
        ("oblique-spin", Case { vt: 1.0, spin: 300.0, ..base }),
        ("friction", Case { friction: 0.3, vt: 0.5, ..base }),
    ]
}

/// Steps per elastic Hertz contact time: the default (1000) and coarser.
pub const DEFAULT_LADDER: [f64; 5] = [1000.0, 300.0, 100.0, 30.0, 10.0];

/// The kinetic energy after many contacts by closed form, J (see the module doc).
pub fn closed_form_energy(case: &Case) -> f64 {
    if case.friction == 0.0 {
        kinetic_energy(case, &initial_state(case, case.timestep()))
    } else {
        0.5 * case.mass() * case.vn * case.vn
    }
}

/// One case at one timestep.
#[derive(Debug, Clone, Serialize)]
pub struct DriftRow {
    pub case: String,
    /// Elastic Hertz contact time / dt.
    pub steps_per_contact: f64,
    pub dt_s: f64,
    pub contacts: usize,
    /// E_N / E_0 by closed form (1 without friction).
    pub closed_form_ratio: f64,
    /// E_N / E_N(closed form) − 1 after all contacts: the cumulative drift.
    pub drift: f64,
    /// `drift` / contacts: the systematic part per contact.
    pub drift_per_contact: f64,
    /// RMS of E_k/E_(k−1) − 1 over the second half of the contacts (by then the frictional
    /// case has shed its tangential energy; without friction every contact is alike).
    pub change_rms: f64,
    /// Largest |E_k/E_(k−1) − 1| over the second half of the contacts.
    pub change_max: f64,
    /// Integration steps over all contacts.
    pub steps: usize,
    pub wall_s: f64,
}

/// Runs every case at every `ladder` entry (steps per Hertz time) for `contacts` contacts.
pub fn run(cases: &[(&str, Case)], ladder: &[f64], contacts: usize) -> Result<Vec<DriftRow>, ContactError> {
    let mut rows = Vec::new();
    for (name, case) in cases {
        let hertz_time = case.pair().hertz_time(case.vn);
        let expected = closed_form_energy(case);
        for &n in ladder {
            let dt = hertz_time / n;
            let start = Instant::now();
            let b = bounce(case, dt, contacts)?;
            let wall_s = start.elapsed().as_secs_f64();
            let last = *b.energy.last().unwrap_or(&b.initial_energy);
            let drift = last / expected - 1.0;
            let changes: Vec<f64> =
                b.energy.windows(2).skip(contacts / 2).map(|w| (w[1] / w[0] - 1.0).abs()).collect();
            let rms = (changes.iter().map(|c| c * c).sum::<f64>() / changes.len().max(1) as f64).sqrt();
            rows.push(DriftRow {
                case: name.to_string(),
                steps_per_contact: n,
                dt_s: dt,
                contacts,
                closed_form_ratio: expected / b.initial_energy,
                drift,
                drift_per_contact: drift / contacts as f64,
                change_rms: rms,
                change_max: changes.iter().copied().fold(0.0, f64::max),
                steps: b.steps,
                wall_s,
            });
        }
    }
    Ok(rows)
}

/// A fixed-width table of the rows.
pub fn table(rows: &[DriftRow]) -> String {
    let mut out = format!(
        "{:<13} {:>7} {:>10} {:>8} {:>9} {:>10} {:>10} {:>9} {:>9} {:>7}\n",
        "case", "t_c/dt", "dt s", "contacts", "E_N/E_0*", "drift", "per cont.", "rms", "max", "wall s"
    );
    for r in rows {
        out += &format!(
            "{:<13} {:>7} {:>10.3e} {:>8} {:>9.6} {:>10} {:>10} {:>9} {:>9} {:>7.2}\n",
            r.case,
            r.steps_per_contact,
            r.dt_s,
            r.contacts,
            r.closed_form_ratio,
            format!("{:+.2e}", r.drift),
            format!("{:+.2e}", r.drift_per_contact),
            cell(Some(r.change_rms)),
            cell(Some(r.change_max)),
            r.wall_s
        );
    }
    out
}
