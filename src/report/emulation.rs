//! The emulator's part of the report: cross-validation, the space's statistics from the
//! emulator beside the raw sample's with a verdict from each, the zero-MFR region and the best
//! settings per quality class ([`crate::analysis::emulator`]).

use std::collections::BTreeMap;

use serde::Serialize;

use super::{PointRow, ReportError, SpaceRow};
use crate::analysis::convergence::{self, Change, Criteria, SpaceStats};
use crate::analysis::emulator::{CrossValidation, EmulatedStatistics, Emulator};
use crate::analysis::stats::STATISTICS;
use crate::measure::quality::Quality;
use crate::outcome::PointAnswer;
use crate::sweep::Sweep;

/// Most points the report's emulator conditions on (its factorisation costs N³/3; past this
/// a seeded random subset of the points).
pub const MAX_POINTS: usize = 800;
/// Mean-surface points for the statistics, and posterior paths for their intervals.
pub const DRAWS: usize = 4096;
pub const PATHS: usize = 200;
/// MFR below this share of the largest measured MFR counts as zero for the zero region.
pub const ZERO_SHARE: f64 = 0.01;

/// One recommended setting.
#[derive(Debug, Clone, Serialize)]
pub struct Best {
    pub index: usize,
    pub parameters: BTreeMap<String, f64>,
    /// The run's own answer, under its own key (`mfr`, `relative_density`, …), and the
    /// emulator's at the same point (the noise averaged out), with SE.
    #[serde(flatten)]
    pub answer: PointAnswer,
    pub emulator_mfr: f64,
    pub emulator_se: f64,
}

/// What the emulator says about the sweep (`summary.json`'s `emulator`).
#[derive(Debug, Clone, Serialize)]
pub struct EmulatorReport {
    /// Points it was fitted to (done runs and screened zeros, thinned to MAX_POINTS).
    pub points: usize,
    /// Length scales per parameter (unit coordinates; small = MFR changes fast along it).
    pub length_scales: BTreeMap<String, f64>,
    pub cross_validation: CrossValidation,
    /// The statistics of the space from the emulator (its last complete space's fit).
    pub statistics: EmulatedStatistics,
    /// The rule applied to the emulator's statistics of the last two complete spaces (noise:
    /// the half-width of each statistic's posterior interval); `None` with fewer than two.
    pub verdict: Option<EmulatedVerdict>,
    /// Share of the space where MFR is zero to the emulator: its mean below `zero_level`
    /// (ZERO_SHARE of the largest MFR measured), and where even its upper 95 % bound is.
    pub zero_fraction: f64,
    pub zero_fraction_sure: f64,
    pub zero_level: f64,
    /// Per quality class, its done points ranked by the emulator's MFR, best five.
    pub best: BTreeMap<&'static str, Vec<Best>>,
}

#[derive(Debug, Clone, Serialize)]
pub struct EmulatedVerdict {
    pub holds: bool,
    pub changes: BTreeMap<&'static str, Change>,
}

struct Fitted {
    emulator: Emulator,
    x: Vec<Vec<f64>>,
    y: Vec<f64>,
    se: Vec<Option<f64>>,
}

/// The emulator fits a sweep directory keeps, so that the next report or `sweep predict` on it
/// recalls them instead of fitting again ([`crate::analysis::emulator::memo`]).
pub const FITS_FILE: &str = "emulator-fits.json";
/// Largest fits file read: 32 fits of a few dozen numbers are a few kB.
const FITS_CAP: u64 = 1 << 20;

/// Recall the fits `dir` keeps. A cache: a file missing, unreadable or not of its form is as
/// if empty.
pub fn recall_fits(dir: &std::path::Path) {
    let fits = crate::sys::read::read_text_capped(&dir.join(FITS_FILE), FITS_CAP)
        .ok()
        .and_then(|text| serde_json::from_str(&text).ok());
    if let Some(fits) = fits {
        crate::analysis::emulator::memo::import(fits);
    }
}

/// Keep the fits of this process in `dir` for the next. A cache: a failed write costs only the
/// next report's time.
pub fn keep_fits(dir: &std::path::Path) {
    let _ = crate::sys::atomic::write_json(&dir.join(FITS_FILE), &crate::analysis::emulator::memo::export());
}

/// Fit to the members of a space (done runs and screened zeros), thinned to MAX_POINTS.
fn fit(sweep: &Sweep, rows: &[&PointRow]) -> Option<Fitted> {
    let usable: Vec<&&PointRow> = rows.iter().filter(|p| p.mfr().is_some()).collect();
    // A seeded random subset: a stride through a Halton sequence would sit in one slice.
    let picked: Vec<&&PointRow> = crate::analysis::emulator::subset(usable.len(), MAX_POINTS, 2)
        .into_iter()
        .map(|i| usable[i])
        .collect();
    let x: Vec<Vec<f64>> = picked.iter().map(|p| crate::sweep::space::unit_point(sweep, &p.values)).collect();
    let y: Vec<f64> = picked.iter().map(|p| p.mfr().expect("filtered")).collect();
    let se: Vec<Option<f64>> = picked.iter().map(|p| p.mfr_se).collect();
    let emulator = Emulator::fit_censored(&x, &y, &se)?;
    Some(Fitted { emulator, x, y, se })
}

/// The emulator's report on the complete spaces `spaces` of `points`; `None` when there are too
/// few done points or MFR does not vary.
pub fn analyse(
    sweep: &Sweep,
    points: &[PointRow],
    spaces: &[SpaceRow],
    c: &Criteria,
) -> Option<EmulatorReport> {
    let last = spaces.last()?;
    let members = |s: &SpaceRow| s.members.iter().map(|&i| &points[i]).collect::<Vec<&PointRow>>();
    let f = fit(sweep, &members(last))?;
    let cross_validation = f.emulator.loo(&f.y, &f.se);
    let statistics = f.emulator.space_statistics(DRAWS, PATHS, 14);
    let as_space = |e: &EmulatedStatistics, n: usize| SpaceStats {
        n,
        moments: e.statistics,
        noise: e.intervals.map(|i| i.lo.zip(i.hi).map(|(lo, hi)| (hi - lo) / 2.0)),
    };
    let verdict = spaces.len().checked_sub(2).and_then(|k| {
        let prev = fit(sweep, &members(&spaces[k]))?;
        let ps = prev.emulator.space_statistics(DRAWS, PATHS, 14);
        let j = convergence::judge(&[as_space(&ps, spaces[k].n), as_space(&statistics, last.n)], c);
        let j = j.last()?;
        let changes = j.changes.clone()?;
        Some(EmulatedVerdict {
            holds: j.holds,
            changes: STATISTICS.iter().zip(changes).map(|(s, ch)| (s.name(), ch)).collect(),
        })
    });
    let top = f.y.iter().fold(0.0f64, |a, v| a.max(*v));
    let zero_level = ZERO_SHARE * top;
    let grid = crate::design::halton::halton(sweep.swept.len(), DRAWS, crate::sweep::Scrambling::Random, 15);
    let (zero_fraction, zero_fraction_sure) = f.emulator.zero_fraction(&grid, zero_level);
    let mut best = BTreeMap::new();
    for q in Quality::ALL {
        let done: Vec<&PointRow> =
            points.iter().filter(|p| p.done().is_some_and(|(_, pq)| pq == q)).collect();
        let units: Vec<Vec<f64>> =
            done.iter().map(|p| crate::sweep::space::unit_point(sweep, &p.values)).collect();
        let ranked = f.emulator.rank(&units, 5);
        let list: Vec<Best> = ranked
            .into_iter()
            .map(|(i, m, s)| Best {
                index: done[i].index,
                parameters: sweep
                    .swept
                    .iter()
                    .map(|p| p.name.clone())
                    .zip(done[i].values.iter().copied())
                    .collect(),
                answer: PointAnswer {
                    kind: super::answer_kind(&sweep.file.scene),
                    value: done[i].mfr().unwrap_or(f64::NAN),
                    se: None,
                },
                emulator_mfr: m,
                emulator_se: s,
            })
            .collect();
        best.insert(q.as_str(), list);
    }
    Some(EmulatorReport {
        points: f.x.len(),
        length_scales: sweep
            .swept
            .iter()
            .map(|p| p.name.clone())
            .zip(f.emulator.theta.iter().copied())
            .collect(),
        cross_validation,
        statistics,
        verdict,
        zero_fraction,
        zero_fraction_sure,
        zero_level,
        best,
    })
}

/// MFR at one setting from a sweep directory's emulator.
#[derive(Debug, Clone, Serialize)]
pub struct Prediction {
    pub parameters: BTreeMap<String, f64>,
    /// The emulator's answer (0 where its surface dips below zero) under its own key (`mfr`,
    /// `relative_density`, …), and its predictive SE (`se`).
    #[serde(flatten)]
    pub answer: PointAnswer,
    pub se: f64,
    /// Points the emulator was fitted to, and its leave-one-out RMSE.
    pub points: usize,
    pub loo_rmse: f64,
    /// Parameters outside the range the sweep sampled (the prediction extrapolates there).
    pub outside: Vec<String>,
}

/// Parse `--set name=value,...` for a prediction: every name a swept parameter, every value a
/// finite number (outside the swept range allowed, and named in [`Prediction::outside`]);
/// unset parameters at the middle of their range.
pub fn parse_setting(sweep: &Sweep, sets: &[String]) -> Result<Vec<f64>, ReportError> {
    use crate::sweep::ParamKind;
    let mut values: Vec<Option<f64>> = vec![None; sweep.swept.len()];
    let mut given: Vec<Option<String>> = vec![None; sweep.swept.len()];
    for item in sets.iter().filter(|s| !s.trim().is_empty()) {
        let (name, value) = item
            .split_once('=')
            .ok_or_else(|| ReportError::Set { item: item.clone(), why: "expected name=value".into() })?;
        let (name, value) = (name.trim(), value.trim());
        let i = sweep.swept.iter().position(|p| p.name == name).ok_or_else(|| {
            let why = format!(
                "not a swept parameter of the sweep{}; swept: {}",
                crate::error::hint(name, sweep.names()),
                sweep.names().join(", ")
            );
            ReportError::Set { item: name.into(), why }
        })?;
        let v = value.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| ReportError::Set {
            item: format!("{name}={value}"),
            why: "expected a finite number".into(),
        })?;
        // A value no point can have is refused as `sweep run --set` refuses it, not
        // extrapolated to.
        if let Some(info) = crate::scene::params::lookup(name).filter(|info| !info.accepts(v)) {
            return Err(ReportError::Set {
                item: format!("{name}={value}"),
                why: format!("outside {}", info.domain()),
            });
        }
        if let Some(first) = &given[i] {
            return Err(ReportError::Set {
                item: name.into(),
                why: format!("given twice ({first} and {value}); give each parameter once"),
            });
        }
        given[i] = Some(value.to_string());
        values[i] = Some(v);
    }
    Ok(sweep
        .swept
        .iter()
        .zip(values)
        .map(|(p, v)| match (v, &p.kind) {
            (Some(v), _) => v,
            (None, ParamKind::Swept { lo, hi, scale }) => crate::sweep::space::scale(0.5, *lo, *hi, *scale),
            (None, ParamKind::Fixed(v)) => *v,
        })
        .collect())
}

/// The emulator of the sweep in `dir` (fitted to every done or screened point, thinned to
/// MAX_POINTS) evaluated at `values` (swept parameters in file order, their units).
pub fn predict(dir: &std::path::Path, sets: &[String]) -> crate::error::Result<Prediction> {
    let (_, sweep, points, _) = super::read_points(dir)?;
    let values = parse_setting(&sweep, sets)?;
    recall_fits(dir);
    let rows: Vec<&PointRow> = points.iter().collect();
    let f = fit(&sweep, &rows).ok_or_else(|| ReportError::NoEmulator {
        dir: dir.to_path_buf(),
        min: crate::analysis::emulator::MIN_POINTS,
    })?;
    let u = crate::sweep::space::unit_point(&sweep, &values);
    let (m, se) = f.emulator.predict(&u);
    let cv = f.emulator.loo(&f.y, &f.se);
    let outside = sweep
        .swept
        .iter()
        .zip(&u)
        .filter(|(_, x)| !(0.0..=1.0).contains(*x))
        .map(|(p, _)| p.name.clone())
        .collect();
    Ok(Prediction {
        parameters: sweep.swept.iter().map(|p| p.name.clone()).zip(values).collect(),
        answer: PointAnswer { kind: super::answer_kind(&sweep.file.scene), value: m.max(0.0), se: None },
        se,
        points: f.x.len(),
        loo_rmse: cv.rmse,
        outside,
    })
}
