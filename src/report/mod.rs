//! The report of a sweep directory: `convergence.csv`, `summary.json` and `report/` (plots as
//! SVG and PNG, and a self-contained `report.html`); docs/statistics.md "The report".
//!
//! [`analyse`] reads the directory (manifest, run dirs, joblog) and computes everything: the
//! statistics of each complete space with bootstrap intervals, the convergence verdict, counts,
//! timing, sensitivity indices, spreading quality and the best points. [`write`] turns that into
//! files. Reading fails before anything is written, so a bad directory changes nothing.
//!
//! Not responsible for running anything or for the statistics themselves ([`crate::analysis::stats`],
//! [`crate::analysis::convergence`], [`crate::analysis::sensitivity`], [`crate::measure::quality`]).

mod adaptive;
mod advice;
pub mod answer;
pub mod calibration;
mod calibration_map;
mod columns;
pub mod emulation;
mod error;
mod gallery;
mod html;
mod maps;
mod page;
mod passes;
mod plots;
mod setup;
pub mod show;
mod timing;
pub use columns::{read_columns, CsvColumns};
pub use error::ReportError;
pub use plots::to_png;
pub use setup::{CentreScene, Setup};
pub use timing::Timing;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::analysis::convergence::{self, Change, Criteria, Judgement, SpaceStats};
use crate::analysis::sensitivity;
use crate::analysis::stats::{self, Bootstrap, Interval, Moments, STATISTICS};
use crate::error::Result;
use crate::measure::quality::{self, Quality};
use crate::outcome::RunResult;
use crate::run::screen::{Screen, ScreenReport};
use crate::store::{DesignRecord, Manifest, PointStatus, RunState, Store};
use crate::sweep::Sweep;

/// Version of `summary.json`.
pub const SUMMARY_FORMAT: u32 = 1;
/// Points listed as the best ideal ones.
const BEST: usize = 5;

/// One design point as the report sees it.
#[derive(Debug, Clone)]
pub struct PointRow {
    pub index: usize,
    pub values: Vec<f64>,
    /// The run's hash: its directory is `DIR/runs/<hash>`.
    pub hash: String,
    pub state: PointState,
    /// The standard error of the point's answer, where its result.json records one (`mfr_se`,
    /// or the layout's own answer's: `relative_density_se`).
    pub mfr_se: Option<f64>,
}

#[derive(Debug, Clone)]
pub enum PointState {
    Done {
        result: Box<RunResult>,
        quality: Quality,
    },
    Failed {
        class: String,
        /// The failure's one-line reason (failure.json).
        reason: String,
    },
    /// Closed by a verified screen, not run: MFR = 0 ([`crate::run::screen`]).
    Screened,
    Pending,
}

impl PointRow {
    pub fn done(&self) -> Option<(&RunResult, Quality)> {
        match &self.state {
            PointState::Done { result, quality } => Some((result, *quality)),
            _ => None,
        }
    }

    /// The point's MFR for the statistics: its run's, or 0 when the screen closed it (a gap
    /// that passes nothing is a real zero, thesis Fig. 4.19).
    pub fn mfr(&self) -> Option<f64> {
        match &self.state {
            PointState::Done { result, .. } => Some(result.answer.value).filter(|v| v.is_finite()),
            PointState::Screened => Some(0.0),
            _ => None,
        }
    }
}

/// One complete space (all its points finished), as judged.
#[derive(Debug, Clone, Serialize)]
pub struct SpaceRow {
    pub label: String,
    /// Points in the space.
    pub n: usize,
    pub done: usize,
    pub failed: usize,
    /// Statistics of the done runs' MFR (weighted as `weights` says).
    pub statistics: Moments,
    /// `"trapezoid"` (a complete lattice weighted by the trapezoid rule) or `"equal"`.
    pub weights: &'static str,
    /// The equal-weight statistics beside the trapezoid ones (a complete lattice only), so the
    /// report can say how far the two differ.
    pub equal_weights: Option<Moments>,
    /// Bootstrap intervals of mean, std, skewness, kurtosis.
    pub intervals: BTreeMap<&'static str, Interval>,
    /// Changes from the previous space (`None` for the first).
    pub changes: Option<BTreeMap<&'static str, Change>>,
    pub holds: bool,
    pub converged: bool,
    /// The variance split into the parameters' share and the per-point noise (mean of
    /// `mfr_se`²); `None` when no point of the space has an `mfr_se`.
    pub noise: Option<crate::analysis::noise::NoiseSplit>,
    /// Indices (into the manifest's points) of the space's points: for plots, not the JSON.
    #[serde(skip)]
    pub members: Vec<usize>,
}

/// The verdict in words and numbers.
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    /// `converged`, `not-converged` (every space finished, the rule never held) or `unfinished`
    /// (spaces still have pending points: an interrupted or stopped sweep).
    pub status: &'static str,
    pub converged: bool,
    /// The first space where the rule held.
    pub space: Option<String>,
    pub n: Option<usize>,
    /// One sentence: where and by which rule, or the last changes.
    pub reason: String,
    /// Relative changes of the last judged space from the one before (null where undefined).
    pub last_changes: Option<BTreeMap<&'static str, Option<f64>>>,
}

#[derive(Debug, Clone, Serialize)]
pub struct SummaryCounts {
    pub points: usize,
    pub done: usize,
    pub failed: usize,
    /// Closed points skipped by a verified screen, counted as MFR = 0.
    pub screened: usize,
    pub pending: usize,
    pub failures_by_class: BTreeMap<String, usize>,
    /// Spaces whose every point finished, of all spaces.
    pub spaces_complete: usize,
    pub spaces: usize,
}

/// A failed point: where it is, why it failed, where its files are.
#[derive(Debug, Clone, Serialize)]
pub struct FailedPoint {
    pub index: usize,
    pub parameters: BTreeMap<String, f64>,
    pub class: String,
    pub reason: String,
    pub run_dir: PathBuf,
}

/// A point worth recommending.
#[derive(Debug, Clone, Serialize)]
pub struct BestPoint {
    pub index: usize,
    pub parameters: BTreeMap<String, f64>,
    /// Its answer, under its own key (`mfr`, `relative_density`, …).
    #[serde(flatten)]
    pub answer: crate::outcome::PointAnswer,
    pub quality: Quality,
}

/// Everything the report says: `summary.json` is this, serialised.
#[derive(Debug, Clone, Serialize)]
pub struct Analysis {
    pub format: u32,
    pub tool: String,
    pub name: String,
    pub description: String,
    #[serde(skip)]
    pub dir: PathBuf,
    pub design: DesignRecord,
    pub parameters: Vec<String>,
    /// Units of the parameters, in the same order.
    pub units: Vec<String>,
    pub engine: String,
    pub setup: Setup,
    pub criteria: Criteria,
    pub verdict: Verdict,
    /// What the screen did: closed points, its verification sample, verified or refuted.
    pub screen: ScreenReport,
    /// Statistics of the converged space, or of the last complete one.
    pub statistics: Option<Moments>,
    pub counts: SummaryCounts,
    pub timing: Timing,
    pub spaces: Vec<SpaceRow>,
    /// First-order indices of MFR over every done point, largest first.
    pub sensitivity: Vec<sensitivity::Index>,
    /// Whether the ranking can be trusted yet, and why (or why not) in words.
    pub sensitivity_reliable: bool,
    pub sensitivity_note: String,
    /// The emulator fitted to the last complete space: cross-validation, statistics, verdict,
    /// zero region, best settings; `None` with too few points or no spread in MFR.
    pub emulator: Option<emulation::EmulatorReport>,
    /// Done points per spreading-quality class.
    pub quality: BTreeMap<&'static str, usize>,
    /// Highest MFR among the ideal points.
    pub best_ideal: Vec<BestPoint>,
    /// Every failed point, by index.
    pub failures: Vec<FailedPoint>,
    /// The v_x classes against the layer, the recommended settings, the thesis's conclusions.
    pub advice: advice::Advice,
    /// The answer first: recommended settings, layer warning, what matters, verdict, next step.
    pub answer: Option<answer::Answer>,
    #[serde(skip)]
    pub points: Vec<PointRow>,
}

impl Analysis {
    /// What each point answers with, in words (`MFR` unless the layout says otherwise).
    pub fn answer_name(&self) -> &'static str {
        answer_kind(&self.setup.scene).words()
    }

    /// Its key (`mfr`, `steady_packing`, …), as its map files are named.
    pub fn answer_key(&self) -> &'static str {
        answer_kind(&self.setup.scene).key()
    }
}

/// What a point of a sweep with these scene settings answers with (MFR unless its layout says
/// otherwise).
pub fn answer_kind(scene: &crate::scene::settings::SceneSettings) -> crate::outcome::AnswerKind {
    crate::scenes::lookup(&scene.layout).map_or(crate::outcome::AnswerKind::Mfr, |l| l.answer(scene))
}

/// A sweep directory's manifest, sweep file and points (with their states and `mfr_se`), and
/// what the screen did.
pub fn read_points(dir: &Path) -> Result<(Manifest, Sweep, Vec<PointRow>, ScreenReport)> {
    let (manifest, toml) = Store::read_manifest(dir)?;
    let sweep = Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    let store = Store::open(dir);
    store.check_pairing(&manifest)?;
    for p in &manifest.points {
        if let Some(RunState::Damaged { file, reason }) = store.point_finished(&manifest, p) {
            eprintln!(
                "warning: {}: {reason}; point {} is left out (`sweep resume` runs it again)",
                file.display(),
                p.index
            );
        }
    }
    let (statuses, _, screen) = Screen::of(&sweep).statuses(&store, &manifest);
    let points: Vec<PointRow> = manifest
        .points
        .iter()
        .zip(statuses)
        .map(|(p, s)| PointRow {
            index: p.index,
            values: p.values.clone(),
            hash: p.hash.clone(),
            mfr_se: match &s {
                PointStatus::Done(r) => r.answer.se.filter(|se| se.is_finite() && *se >= 0.0),
                _ => None,
            },
            state: match s {
                PointStatus::Done(r) => {
                    let quality = quality::of_result(&r);
                    PointState::Done { result: r, quality }
                }
                PointStatus::Failed(f) => {
                    PointState::Failed { class: f.class.as_str().to_string(), reason: f.reason.clone() }
                }
                PointStatus::Screened => PointState::Screened,
                PointStatus::Pending => PointState::Pending,
            },
        })
        .collect();
    Ok((manifest, sweep, points, screen))
}

/// Read a sweep directory and analyse it with `criteria`.
pub fn analyse(dir: &Path, criteria: &Criteria, boot: &Bootstrap) -> Result<Analysis> {
    let (manifest, sweep, points, screen) = read_points(dir)?;
    let spaces = judge_spaces(dir, &sweep, &manifest, &points, criteria, boot);
    emulation::recall_fits(dir);
    let emulator = emulation::analyse(&sweep, &points, &spaces, criteria);
    let counts = count(&manifest, &points, spaces.len());
    let verdict = verdict(&spaces, &counts, criteria);
    let statistics = spaces.iter().find(|s| s.converged).or(spaces.last()).map(|s| s.statistics);
    let done: Vec<(&PointRow, &RunResult, Quality)> =
        points.iter().filter_map(|p| p.done().map(|(r, q)| (p, r, q))).collect();
    // Screened points are real zeros of MFR, and part of how it depends on the parameters.
    let (x, y): (Vec<Vec<f64>>, Vec<f64>) =
        points.iter().filter_map(|p| p.mfr().map(|m| (p.values.clone(), m))).unzip();
    let sboot = Bootstrap { resamples: boot.resamples.min(500), ..*boot };
    let (sensitivity, sensitivity_reliable, sensitivity_note) =
        adaptive::sensitivity(&sweep, &manifest, &points, &x, &y, &sboot);
    let mut quality: BTreeMap<&'static str, usize> = Quality::ALL.iter().map(|q| (q.as_str(), 0)).collect();
    for (_, _, q) in &done {
        *quality.entry(q.as_str()).or_default() += 1;
    }
    let mut ideal: Vec<&(&PointRow, &RunResult, Quality)> =
        done.iter().filter(|(_, _, q)| *q == Quality::Ideal).collect();
    ideal.sort_by(|a, b| b.1.answer.value.total_cmp(&a.1.answer.value));
    let best_ideal = ideal
        .iter()
        .take(BEST)
        .map(|(p, r, q)| BestPoint {
            index: p.index,
            parameters: manifest.parameters.iter().cloned().zip(p.values.iter().copied()).collect(),
            answer: crate::outcome::PointAnswer { se: None, ..r.answer },
            quality: *q,
        })
        .collect();
    let units = sweep.swept.iter().map(|p| p.unit.to_string()).collect();
    let failures = points
        .iter()
        .filter_map(|p| match &p.state {
            PointState::Failed { class, reason } => Some(FailedPoint {
                index: p.index,
                parameters: manifest.parameters.iter().cloned().zip(p.values.iter().copied()).collect(),
                class: class.clone(),
                reason: reason.clone(),
                run_dir: crate::store::Store::open(dir).run_dir(&p.hash),
            }),
            _ => None,
        })
        .collect();
    let done_results: Vec<&RunResult> = done.iter().map(|(_, r, _)| *r).collect();
    let setup = Setup::of(&sweep, &manifest, dir, &done_results);
    let layout = crate::scenes::lookup(&sweep.file.scene.layout);
    let advice = advice::advise(
        &manifest.parameters,
        &points,
        &sensitivity,
        layout,
        answer_kind(&sweep.file.scene).words(),
    );
    let engine = manifest
        .identity
        .get("engine")
        .or_else(|| manifest.identity.get("engine_version"))
        .map(|v| v.as_str().map(String::from).unwrap_or_else(|| v.to_string()))
        .unwrap_or_else(|| "unknown".into());
    let mut a = Analysis {
        format: SUMMARY_FORMAT,
        tool: format!("demsweep {}", env!("CARGO_PKG_VERSION")),
        name: manifest.name.clone(),
        description: sweep.file.description.clone(),
        dir: dir.to_path_buf(),
        design: manifest.design.clone(),
        parameters: manifest.parameters.clone(),
        units,
        engine,
        setup,
        criteria: *criteria,
        verdict,
        screen,
        statistics,
        counts,
        timing: timing::of(dir, &done_results),
        spaces,
        sensitivity,
        sensitivity_reliable,
        sensitivity_note,
        emulator,
        quality,
        best_ideal,
        failures,
        advice,
        answer: None,
        points,
    };
    a.answer = Some(answer::answer(&a));
    emulation::keep_fits(dir);
    Ok(a)
}

/// Statistics, intervals and judgements of the complete spaces, in order, up to the first
/// space that still has pending points.
///
/// An adaptive design is not a uniform sample: its spaces' statistics are the emulator's over
/// the whole space, with the posterior's intervals ([`crate::analysis::adapt`]), as the sweep
/// judged them while it ran.
fn judge_spaces(
    dir: &Path,
    sweep: &Sweep,
    manifest: &Manifest,
    points: &[PointRow],
    c: &Criteria,
    boot: &Bootstrap,
) -> Vec<SpaceRow> {
    let adaptive = manifest.design.is_adaptive();
    let lattice = matches!(manifest.design, DesignRecord::Lattice { .. });
    // The spaces up to the first with a pending point, each with its MFR values and weights.
    type Complete<'a> = (&'a crate::store::SpaceRecord, Vec<&'a PointRow>, Vec<f64>, Option<Vec<f64>>);
    let complete: Vec<Complete> = manifest
        .spaces
        .iter()
        .map(|space| (space, space.points.iter().map(|&i| &points[i]).collect::<Vec<&PointRow>>()))
        .take_while(|(_, members)| !members.iter().any(|p| matches!(p.state, PointState::Pending)))
        .map(|(space, members)| {
            let values: Vec<&[f64]> = members.iter().map(|p| p.values.as_slice()).collect();
            let all_mfr: Vec<Option<f64>> = members.iter().map(|p| p.mfr()).collect();
            let (mfr, w) =
                convergence::space_values(&values, &all_mfr, c.for_design(lattice).lattice_weights);
            (space, members, mfr, w)
        })
        .collect();
    // A sample's spaces are bootstrapped on every core: each bootstrap is seeded alone, so the
    // intervals are those of one space after another. An adaptive design's are its emulator's.
    let statistics: Vec<(SpaceStats, [Interval; 4])> = if adaptive {
        complete
            .iter()
            .map(|(space, members, _, _)| adaptive::emulated_space(dir, sweep, &space.label, members))
            .collect()
    } else {
        use rayon::prelude::*;
        complete
            .par_iter()
            .map(|(_, members, mfr, w)| SpaceStats::with_intervals(members.len(), mfr, w.as_deref(), boot))
            .collect()
    };
    let mut rows = Vec::new();
    let mut judged: Vec<SpaceStats> = Vec::new();
    for ((space, members, mfr, w), (st, iv)) in complete.into_iter().zip(statistics) {
        let se: Vec<Option<f64>> = members.iter().filter(|p| p.mfr().is_some()).map(|p| p.mfr_se).collect();
        let noise = crate::analysis::noise::split(&mfr, &se, w.as_deref());
        let m = st.moments;
        judged.push(st);
        rows.push(SpaceRow {
            label: space.label.clone(),
            n: members.len(),
            // Done runs and screened points: the MFR values judged.
            done: mfr.len(),
            failed: members.iter().filter(|p| matches!(p.state, PointState::Failed { .. })).count(),
            statistics: m,
            weights: adaptive::weights_label(adaptive, w.is_some()),
            equal_weights: w.as_ref().map(|_| stats::moments(&mfr)),
            noise,
            intervals: STATISTICS.iter().zip(iv).map(|(s, i)| (s.name(), i)).collect(),
            changes: None,
            holds: false,
            converged: false,
            members: space.points.clone(),
        });
    }
    let j: Vec<Judgement> = convergence::judge(&judged, c);
    for (row, j) in rows.iter_mut().zip(j) {
        row.changes = j.changes.map(|ch| STATISTICS.iter().zip(ch).map(|(s, c)| (s.name(), c)).collect());
        row.holds = j.holds;
        row.converged = j.converged;
    }
    rows
}

fn count(manifest: &Manifest, points: &[PointRow], complete: usize) -> SummaryCounts {
    let mut c = SummaryCounts {
        points: points.len(),
        done: 0,
        failed: 0,
        screened: 0,
        pending: 0,
        failures_by_class: BTreeMap::new(),
        spaces_complete: complete,
        spaces: manifest.spaces.len(),
    };
    for p in points {
        match &p.state {
            PointState::Done { .. } => c.done += 1,
            PointState::Failed { class, .. } => {
                c.failed += 1;
                *c.failures_by_class.entry(class.clone()).or_default() += 1;
            }
            PointState::Screened => c.screened += 1,
            PointState::Pending => c.pending += 1,
        }
    }
    c
}

/// Which weights a space's statistics used and, for a lattice, how far the thesis's equal
/// weights would move the mean and the std.
pub fn weights_sentence(s: &SpaceRow) -> String {
    match &s.equal_weights {
        None if s.weights == adaptive::WEIGHTS => adaptive::weights_sentence(s),
        None => format!("{}: every point weighted equally.", s.label),
        Some(eq) => {
            let rel = |a: Option<f64>, b: Option<f64>| match (a, b) {
                (Some(a), Some(b)) if a != 0.0 => format!("{:+.1}%", (b - a) / a.abs() * 100.0),
                _ => "undefined".into(),
            };
            format!(
                "{}: lattice points weighted by the trapezoid rule (½ per coordinate on a face of the box); \
                 equal weights (the thesis) would give mean {} ({}) and std {} ({}).",
                s.label,
                eq.mean.map_or("–".into(), |v| format!("{v:.4}")),
                rel(s.statistics.mean, eq.mean),
                eq.std.map_or("–".into(), |v| format!("{v:.4}")),
                rel(s.statistics.std, eq.std),
            )
        }
    }
}

fn pct(v: Option<f64>) -> String {
    v.map_or("undefined".into(), |v| format!("{:.1}%", v * 100.0))
}

fn verdict(spaces: &[SpaceRow], counts: &SummaryCounts, c: &Criteria) -> Verdict {
    let last_changes = spaces
        .last()
        .and_then(|s| s.changes.as_ref())
        .map(|ch| ch.iter().map(|(k, v)| (*k, v.rel)).collect::<BTreeMap<_, _>>());
    let failures = |s: &SpaceRow| {
        if s.failed > 0 {
            format!(" ({} failed run(s) left out; judged on {} done)", s.failed, s.done)
        } else {
            String::new()
        }
    };
    if let Some(s) = spaces.iter().find(|s| s.converged) {
        return Verdict {
            status: "converged",
            converged: true,
            space: Some(s.label.clone()),
            n: Some(s.n),
            reason: format!("converged at N = {} ({}) by {}{}", s.n, s.label, c.describe(), failures(s)),
            last_changes,
        };
    }
    let changes = |ch: &BTreeMap<&'static str, Option<f64>>| {
        STATISTICS
            .iter()
            .map(|s| format!("{} {}", s.name(), pct(ch.get(s.name()).copied().flatten())))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let last = match (spaces.last(), &last_changes) {
        (Some(s), Some(ch)) if c.rule == convergence::Rule::Scaled => {
            let tests = s.changes.as_ref().map_or(String::new(), |t| {
                STATISTICS
                    .iter()
                    .map(|st| format!("{} {}", st.name(), t[st.name()].test))
                    .collect::<Vec<_>>()
                    .join("; ")
            });
            let _ = ch;
            format!("; last space ({}): {tests}", s.label)
        }
        (Some(s), Some(ch)) => format!("; last changes ({}): {}", s.label, changes(ch)),
        _ => String::new(),
    };
    if counts.spaces_complete < counts.spaces {
        Verdict {
            status: "unfinished",
            converged: false,
            space: None,
            n: None,
            reason: format!(
                "not converged so far: {} of {} spaces complete, {} point(s) pending{last}",
                counts.spaces_complete, counts.spaces, counts.pending
            ),
            last_changes,
        }
    } else {
        Verdict {
            status: "not-converged",
            converged: false,
            space: None,
            n: None,
            reason: format!(
                "not converged after N = {} by {}{last}",
                spaces.last().map_or(0, |s| s.n),
                c.describe()
            ),
            last_changes,
        }
    }
}

/// Write `convergence.csv`, `summary.json` and `report/` into the analysed directory; returns
/// the path of `report.html`.
pub fn write(a: &Analysis) -> Result<PathBuf, ReportError> {
    let io = |p: &Path, source: std::io::Error| ReportError::Write { path: p.to_path_buf(), source };
    let csv_path = a.dir.join("convergence.csv");
    crate::sys::atomic::write(&csv_path, convergence_csv(a).as_bytes()).map_err(|e| io(&csv_path, e))?;
    let json_path = a.dir.join("summary.json");
    crate::sys::atomic::write_json(&json_path, a).map_err(|e| io(&json_path, e))?;
    let out = a.dir.join("report");
    std::fs::create_dir_all(&out).map_err(|e| io(&out, e))?;
    let figures = gallery::draw_all(a).map_err(|e| ReportError::Draw(e.to_string()))?;
    for f in &figures {
        for (ext, bytes) in [("svg", f.svg.as_bytes()), ("png", f.png.as_slice())] {
            let p = out.join(format!("{}.{ext}", f.name));
            crate::sys::atomic::write(&p, bytes).map_err(|e| io(&p, e))?;
        }
    }
    let html_path = out.join("report.html");
    crate::sys::atomic::write(&html_path, html::render(a, &figures).as_bytes())
        .map_err(|e| io(&html_path, e))?;
    Ok(html_path)
}

/// `convergence.csv`: one row per complete space. Empty cells where a value is undefined.
pub fn convergence_csv(a: &Analysis) -> String {
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header: Vec<String> = ["space", "n", "done", "failed"].map(String::from).to_vec();
    for s in STATISTICS {
        header.extend([s.name().to_string(), format!("{}_lo", s.name()), format!("{}_hi", s.name())]);
    }
    header.extend(["moment_skewness", "median"].map(String::from));
    header.extend(STATISTICS.iter().map(|s| format!("change_{}", s.name())));
    for s in STATISTICS {
        let n = s.name();
        header.extend([
            format!("delta_{n}"),
            format!("scale_{n}"),
            format!("noise_{n}"),
            format!("test_{n}"),
        ]);
    }
    header.extend(["holds", "converged", "weights"].map(String::from));
    w.write_record(&header).expect("in-memory csv");
    for s in &a.spaces {
        let mut row = vec![s.label.clone(), s.n.to_string(), s.done.to_string(), s.failed.to_string()];
        for st in STATISTICS {
            let iv = s.intervals[st.name()];
            row.extend([opt(st.of(&s.statistics)), opt(iv.lo), opt(iv.hi)]);
        }
        row.extend([opt(s.statistics.moment_skewness), opt(s.statistics.median)]);
        for st in STATISTICS {
            row.push(opt(s.changes.as_ref().and_then(|c| c[st.name()].rel)));
        }
        for st in STATISTICS {
            match s.changes.as_ref().map(|c| &c[st.name()]) {
                Some(c) => row.extend([opt(c.abs), opt(c.scale), opt(c.noise), c.test.clone()]),
                None => row.extend([String::new(), String::new(), String::new(), String::new()]),
            }
        }
        row.extend([s.holds.to_string(), s.converged.to_string(), s.weights.to_string()]);
        w.write_record(&row).expect("in-memory csv");
    }
    String::from_utf8(w.into_inner().expect("in-memory csv")).expect("utf-8")
}
