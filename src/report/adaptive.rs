//! The report of an adaptive sweep (`sweep adapt`): its points are not a uniform sample, so its
//! statistics and sensitivity indices come from the emulator over the whole space
//! ([`crate::analysis::adapt`]), fitted to the same points as the running sweep's
//! ([`crate::run::adapt::fit_data`]).

use super::{PointRow, SpaceRow};
use crate::analysis::convergence::SpaceStats;
use crate::analysis::sensitivity::{self, Index};
use crate::analysis::stats::{Bootstrap, Interval};
use crate::store::Manifest;
use crate::sweep::Sweep;

/// The sensitivity indices of the report: of the emulator's surface for an adaptive sweep, of
/// the sample (`x`, `y`) otherwise; whether the ranking is reliable, and the note saying so.
pub(super) fn sensitivity(
    sweep: &Sweep,
    manifest: &Manifest,
    points: &[PointRow],
    x: &[Vec<f64>],
    y: &[f64],
    sboot: &Bootstrap,
) -> (Vec<Index>, bool, String) {
    match surface(sweep, manifest, points) {
        // An adaptive design crowds its points where MFR varies: indices from its sample
        // would weigh those regions too much; the emulator's surface covers the space evenly.
        Some((sx, sy)) => {
            let ranked =
                sensitivity::ranked(sensitivity::with_intervals(&manifest.parameters, &sx, &sy, sboot));
            let (reliable, note) = sensitivity::reliability(y.len(), &ranked);
            let note = format!(
                "{note}. An adaptive design: the indices are those of the emulator's mean surface on {} \
                     scrambled-Halton points (their intervals hold that sample's noise, not the emulator's)",
                sy.len()
            );
            (ranked, reliable, note)
        }
        None => {
            let ranked = sensitivity::ranked(sensitivity::with_intervals(&manifest.parameters, x, y, sboot));
            let (reliable, note) = sensitivity::reliability(y.len(), &ranked);
            (ranked, reliable, note)
        }
    }
}

/// The emulator's mean surface (clamped at 0) on the statistics' scrambled-Halton points, in
/// the sweep's units, fitted to every done point of an adaptive sweep; `None` for other designs
/// or without an emulator.
fn surface(sweep: &Sweep, manifest: &Manifest, points: &[PointRow]) -> Option<(Vec<Vec<f64>>, Vec<f64>)> {
    if !manifest.design.is_adaptive() {
        return None;
    }
    let usable: Vec<&PointRow> = points.iter().filter(|p| p.mfr().is_some()).collect();
    let picked = crate::analysis::emulator::subset(usable.len(), crate::run::adapt::FIT_MAX, 2);
    let x: Vec<Vec<f64>> =
        picked.iter().map(|&i| crate::sweep::space::unit_point(sweep, &usable[i].values)).collect();
    let y: Vec<f64> = picked.iter().map(|&i| usable[i].mfr().expect("filtered")).collect();
    let se: Vec<Option<f64>> = picked.iter().map(|&i| usable[i].mfr_se).collect();
    let em = crate::analysis::emulator::Emulator::fit_censored(&x, &y, &se)?;
    let pts = crate::design::halton::halton(
        sweep.dim(),
        crate::analysis::adapt::DRAWS,
        crate::sweep::Scrambling::Random,
        15,
    );
    let sy = pts.iter().map(|u| em.mean(u).max(0.0)).collect();
    Some((pts.iter().map(|u| crate::sweep::space::scale_point(sweep, u)).collect(), sy))
}

/// The emulator's statistics of an adaptive space and their posterior intervals, fitted to
/// the same points in the same order as the running sweep's (`run::adapt::fit_data`).
pub(super) fn emulated_space(
    dir: &std::path::Path,
    sweep: &Sweep,
    label: &str,
    members: &[&PointRow],
) -> (SpaceStats, [Interval; 4]) {
    let usable: Vec<&&PointRow> = members.iter().filter(|p| p.mfr().is_some()).collect();
    let picked = crate::analysis::emulator::subset(usable.len(), crate::run::adapt::FIT_MAX, 2);
    let x: Vec<Vec<f64>> =
        picked.iter().map(|&i| crate::sweep::space::unit_point(sweep, &usable[i].values)).collect();
    let y: Vec<f64> = picked.iter().map(|&i| usable[i].mfr().expect("filtered")).collect();
    let se: Vec<Option<f64>> = picked.iter().map(|&i| usable[i].mfr_se).collect();
    let (st, intervals, _) = crate::run::adapt::space_statistics(dir, label, members.len(), &x, &y, &se);
    (st, intervals)
}

/// The `weights` of an adaptive space's row in convergence.csv and summary.json.
pub(super) const WEIGHTS: &str = "emulator";

/// How a space's points were weighted: by the emulator (adaptive), the trapezoid rule (a
/// complete lattice) or equally.
pub(super) fn weights_label(adaptive: bool, trapezoid: bool) -> &'static str {
    match (adaptive, trapezoid) {
        (true, _) => WEIGHTS,
        (false, true) => "trapezoid",
        (false, false) => "equal",
    }
}

pub(super) fn weights_sentence(s: &SpaceRow) -> String {
    format!(
        "{}: an adaptive design; the statistics are the emulator's over the whole space, with \
         intervals from its posterior.",
        s.label
    )
}
