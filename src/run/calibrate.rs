//! `sweep calibrate`: the free parameters of a sweep file fitted to measured targets, batch by
//! batch, in one sweep directory.
//!
//! The directory is an adaptive sweep's ([`crate::run::adapt`]): a scrambled-Halton first batch,
//! then each batch planned from the results before it and appended to the manifest as one more
//! space (`calibrate N`: the first N points), so `status`, `resume`, the joblog and the claims read
//! it as any sweep. What makes it a calibration is [`SETTINGS`] (the targets and the stopping
//! rule), written when it is created. After each batch the [`CalibrationWatch`] fits one emulator
//! per target, computes the posterior ([`crate::analysis::calibration`]) and judges whether its
//! credible intervals have stopped moving; the next batch goes where the posterior is least
//! known. A batch is a pure function of the points and results before it: a resume, or a second
//! process, plans the same one.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{RunError, RunOptions, Summary, SweepDir};
use crate::analysis::adapt::new_run_noise;
use crate::analysis::calibration::{self as cal, Emulated, Pick, Posterior, Scatter, Target};
use crate::analysis::emulator::Emulator;
use crate::error::Result;
use crate::run::batches::{self, PlanFrom, Planned, Sequential};
use crate::run::pool::{Executor, Flow};
use crate::run::{PointExecutor, SpaceHook, SweepExecutor};
use crate::scenes::quantity::{Measured, Quantity};
use crate::store::{Manifest, PointRecord, PointStatus, SpaceRecord, Store};
use crate::sweep::Sweep;
use crate::sys::process::CancelToken;

/// `calibration.json`: the targets and the stopping rule of a calibration directory.
pub const SETTINGS: &str = "calibration.json";
/// `posterior.json`: the calibration's answer, written by its report.
pub const POSTERIOR: &str = "posterior.json";
/// `calibration-batches.csv`: why each planned point went where it went.
pub const BATCHES: &str = "calibration-batches.csv";

/// The stopping rule's defaults: no bound of a credible interval moves by more than 10 % of the
/// interval's width, two batches in a row.
pub const TOLERANCE: f64 = 0.1;
pub const HOLD: usize = 2;

/// What a calibration directory calibrates against, and when it stops.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    pub targets: Vec<Target>,
    pub tolerance: f64,
    pub hold: usize,
}

/// Runs of each setting by default for `targets` (checked): the most any of them asks.
pub fn default_repeats(targets: &[Target]) -> usize {
    targets.iter().filter_map(|t| quantity(&t.name)).map(|q| q.repeats).max().unwrap_or(1)
}

/// The quantity named `name`, of any layout.
pub fn quantity(name: &str) -> Option<&'static Quantity> {
    crate::scenes::quantity::lookup(name)
}

/// Why a sweep cannot be calibrated against its targets: the sentence after the flag.
#[derive(Debug, thiserror::Error)]
pub enum TargetsRefused {
    /// The sweep's layout is not one (refused when the sweep file is read, so internal here).
    #[error(transparent)]
    Layout(#[from] crate::scene::SceneError),
    #[error(
        "{}: no free parameter: give the parameters to calibrate as ranges in [parameters], e.g. friction = {{ lo = 0.1, hi = 0.5 }}",
        path.display()
    )]
    NoFreeParameter { path: std::path::PathBuf },
    #[error("--target: expected at least one, e.g. --target angle_of_repose=34.0±1.0")]
    NoTarget,
    /// Not a quantity of any layout (`all`: their names).
    #[error("--target {name}: not a quantity a run measures; expected one of {all}")]
    Unknown { name: String, all: String },
    /// A quantity the sweep's layout does not measure (`measured`: those it does).
    #[error("--target {name}: scene.layout \"{layout}\" does not measure it; it measures {measured}")]
    NotMeasured { name: String, layout: String, measured: String },
    #[error("--target {name}: given twice")]
    Twice { name: String },
    /// A value outside what its quantity can be, `lo`–`hi`.
    #[error(
        "--target {name}={}: outside {}{lo}, {hi}]{unit}, the values it can take",
        shown(*.value, 1e6),
        if *.lo_possible { "[" } else { "(" }
    )]
    Outside { name: String, value: f64, lo: f64, hi: f64, lo_possible: bool, unit: &'static str },
    /// An SD outside `min`–`max`, the least measurement and the whole range.
    #[error(
        "--target {name}: SD {}{unit}: expected {} to {}{unit} (the measurement's SD, at most the whole range)",
        shown_sd(*.sd),
        crate::scene::plausible::show(*.min),
        crate::scene::plausible::show(*.max)
    )]
    Sd { name: String, sd: f64, unit: &'static str, min: f64, max: f64 },
}

/// `v` as written below `big`, in exponent form beyond it.
fn shown(v: f64, big: f64) -> String {
    if v.abs() < big {
        v.to_string()
    } else {
        format!("{v:e}")
    }
}

/// An SD as written between 1e-4 and 1e6, in exponent form outside.
fn shown_sd(sd: f64) -> String {
    if (1e-4..1e6).contains(&sd) {
        sd.to_string()
    } else {
        format!("{sd:e}")
    }
}

/// Refuse targets the sweep cannot be calibrated against: a sweep with no free parameter, a
/// quantity nobody measures or its layout does not, a target given twice. The error is the
/// sentence after the flag.
pub fn check(sweep: &Sweep, targets: &[Target]) -> std::result::Result<(), TargetsRefused> {
    let layout = &sweep.file.scene.layout;
    let measures = crate::scenes::of(&sweep.file.scene)?.calibration_targets();
    if sweep.dim() == 0 {
        return Err(TargetsRefused::NoFreeParameter { path: sweep.path.clone() });
    }
    if targets.is_empty() {
        return Err(TargetsRefused::NoTarget);
    }
    let measured: Vec<&str> = measures.iter().map(|q| q.name).collect();
    for (k, t) in targets.iter().enumerate() {
        match quantity(&t.name) {
            None => {
                let all: Vec<&str> = crate::scenes::quantity::every().map(|q| q.name).collect();
                return Err(TargetsRefused::Unknown { name: t.name.clone(), all: all.join(", ") });
            }
            Some(q) if !measured.contains(&q.name) => {
                return Err(TargetsRefused::NotMeasured {
                    name: t.name.clone(),
                    layout: layout.clone(),
                    measured: measured.join(", "),
                })
            }
            Some(q) => check_possible(q, t)?,
        }
        if targets[..k].iter().any(|o| o.name == t.name) {
            return Err(TargetsRefused::Twice { name: t.name.clone() });
        }
    }
    Ok(())
}

/// Smallest SD of a target, as a fraction of its quantity's possible range: no measurement is
/// finer, and below it the posterior's numbers are rounding.
const MIN_SD_OF_RANGE: f64 = 1e-6;

/// A target inside what its quantity can be, with an SD between [`MIN_SD_OF_RANGE`] of that
/// range and the whole range.
fn check_possible(q: &Quantity, t: &Target) -> std::result::Result<(), TargetsRefused> {
    let (lo, hi) = q.possible;
    let unit = if q.unit == "-" { "" } else { q.unit };
    let above_lo = if q.lo_possible { t.value >= lo } else { t.value > lo };
    if !(above_lo && t.value <= hi) {
        let lo_possible = q.lo_possible;
        return Err(TargetsRefused::Outside {
            name: t.name.clone(),
            value: t.value,
            lo,
            hi,
            lo_possible,
            unit,
        });
    }
    let (min_sd, max_sd) = ((hi - lo) * MIN_SD_OF_RANGE, hi - lo);
    if !(t.sd >= min_sd && t.sd <= max_sd) {
        return Err(TargetsRefused::Sd { name: t.name.clone(), sd: t.sd, unit, min: min_sd, max: max_sd });
    }
    Ok(())
}

/// The executor of a calibration: LIGGGHTS, or the stand-in. A pour, whose single runs a
/// plain sweep refuses (its statistics read MFR), is what a calibration is made of.
pub fn executor(sweep: &Sweep) -> Result<SweepExecutor> {
    if super::standin::selected(sweep) {
        Ok(SweepExecutor::StandIn(Box::new(super::standin::StandIn::new(sweep.clone())?)))
    } else {
        Ok(SweepExecutor::Real(Box::new(PointExecutor::new(sweep.clone())?)))
    }
}

/// The settings of the calibration directory `dir`; `None` when it is not one.
pub fn settings(dir: &Path) -> Option<Settings> {
    serde_json::from_str(&std::fs::read_to_string(dir.join(SETTINGS)).ok()?).ok()
}

/// Per target: the unit points of the settings whose done runs measured it, each setting's
/// mean over its runs (its repeats, one per seed) and the SE of that mean the emulator takes
/// ([`Scatter::means`]).
pub type Data = Vec<(Vec<Vec<f64>>, Vec<f64>, Vec<Option<f64>>)>;

/// The data of every target and the scatter of its runs between seeds.
fn data(sweep: &Sweep, targets: &[Target], points: &[(&PointRecord, &PointStatus)]) -> (Data, Vec<Scatter>) {
    targets
        .iter()
        .map(|t| {
            let q = quantity(&t.name).expect("targets are checked");
            // The runs of each setting (the same values, any seed), in the order first run.
            let mut settings: Vec<(&[f64], Vec<Measured>)> = Vec::new();
            for (p, s) in points {
                let PointStatus::Done(r) = s else { continue };
                let Some((v, se)) = q.read(r).filter(|(v, _)| v.is_finite()) else { continue };
                let run = (v, se.filter(|s| s.is_finite()));
                let same = |u: &&mut (&[f64], Vec<Measured>)| {
                    u.0.len() == p.values.len()
                        && u.0.iter().zip(&p.values).all(|(a, b)| a.to_bits() == b.to_bits())
                };
                match settings.iter_mut().find(same) {
                    Some(g) => g.1.push(run),
                    None => settings.push((&p.values, vec![run])),
                }
            }
            let runs: Vec<Vec<Measured>> = settings.iter().map(|g| g.1.clone()).collect();
            let scatter = Scatter::of(&t.name, &runs);
            let means = scatter.means(&runs);
            let x = settings.iter().map(|g| crate::sweep::space::unit_point(sweep, g.0)).collect();
            ((x, means.iter().map(|m| m.0).collect(), means.iter().map(|m| m.1).collect()), scatter)
        })
        .unzip()
}

/// One judged batch.
#[derive(Debug, Clone, Serialize)]
pub struct Batch {
    pub label: String,
    pub points: usize,
    /// Points whose runs measured every target.
    pub measured: usize,
    pub posterior: Option<Posterior>,
    /// The rule's change against the batch before ([`cal::interval_change`]).
    pub change: Option<f64>,
    /// Per target: the scatter of its runs between seeds and the noise the emulator takes.
    pub scatter: Vec<Scatter>,
    /// Per target: the emulator's fitted nugget as an SD, the noise beyond what it was given
    /// (`None` without an emulator).
    pub nugget_sd: Vec<Option<f64>>,
}

/// The [`SpaceHook`] of a calibration: judges each batch by its posterior and keeps the last
/// batch's emulators for planning the next.
pub struct CalibrationWatch {
    sweep: Sweep,
    settings: Settings,
    seed: u64,
    pub batches: Vec<Batch>,
    /// The batch (index into `batches`) at which the credible region stopped shrinking.
    pub converged_at: Option<usize>,
    /// The last judged batch's label, emulators (one per target, `None` for all when one could
    /// not be fitted) and data.
    last: Option<(String, Option<Vec<Emulator>>, Data)>,
    lines: Vec<String>,
}

impl CalibrationWatch {
    pub fn new(sweep: &Sweep, settings: Settings, seed: u64) -> CalibrationWatch {
        CalibrationWatch {
            sweep: sweep.clone(),
            settings,
            seed,
            batches: Vec::new(),
            converged_at: None,
            last: None,
            lines: Vec::new(),
        }
    }

    /// The last batch's emulators, one per target, when it had them.
    pub fn emulators(&self) -> Option<&[Emulator]> {
        self.last.as_ref().and_then(|(_, e, _)| e.as_deref())
    }

    /// The last batch's data: per target, the unit points, values and SEs of its runs.
    pub fn data(&self) -> Option<&Data> {
        self.last.as_ref().map(|(_, _, d)| d)
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    fn line(&self, k: usize) -> String {
        let b = &self.batches[k];
        let head = format!("batch {} ({}, {} points)", k + 1, b.label, b.points);
        let Some(p) = &b.posterior else {
            return format!(
                "{head}: too few measured runs for an emulator of every target ({} measured)",
                b.measured
            );
        };
        let params: Vec<String> = self
            .sweep
            .swept
            .iter()
            .enumerate()
            .map(|(j, par)| {
                let v = |u: f64| fmt(unit_value(&self.sweep, j, u));
                let m = &p.marginals[j];
                format!("{} {} [{}, {}]", par.name, v(m.median), v(m.lo), v(m.hi))
            })
            .collect();
        // The rule needs `hold` batches in a row within the tolerance: one is not enough.
        let within = |b: &Batch| b.change.is_some_and(|c| c <= self.settings.tolerance);
        let in_a_row = self.batches[..=k].iter().rev().take_while(|b| within(b)).count();
        let hold = self.settings.hold.max(1);
        let verdict = match b.change {
            None => "nothing to compare with yet".to_string(),
            Some(c) if in_a_row >= hold => {
                format!("intervals moved {:.0} % of their width: the rule holds", 100.0 * c)
            }
            Some(c) if in_a_row > 0 => format!(
                "intervals moved {:.0} % of their width, within {:.0} % ({in_a_row} of {hold} batches in a row)",
                100.0 * c,
                100.0 * self.settings.tolerance
            ),
            Some(c) => format!("intervals moved {:.0} % of their width", 100.0 * c),
        };
        let conv = if self.converged_at == Some(k) { "; converged" } else { "" };
        format!("{head}: {}; {verdict}{conv}", params.join(", "))
    }
}

/// A number in four significant figures.
pub fn fmt(v: f64) -> String {
    crate::scene::plausible::round_to(v, 4)
}

/// The value of swept parameter `j` at unit coordinate `u`.
pub fn unit_value(sweep: &Sweep, j: usize, u: f64) -> f64 {
    match sweep.swept[j].kind {
        crate::sweep::ParamKind::Swept { lo, hi, scale } => crate::sweep::space::scale(u, lo, hi, scale),
        crate::sweep::ParamKind::Fixed(v) => v,
    }
}

impl SpaceHook for CalibrationWatch {
    fn space_complete(&mut self, space: &SpaceRecord, points: &[(&PointRecord, &PointStatus)]) -> Flow {
        let k = match self.batches.iter().position(|b| b.label == space.label) {
            Some(k) => k,
            None => {
                let (d, scatter) = data(&self.sweep, &self.settings.targets, points);
                let ems: Option<Vec<Emulator>> = d.iter().map(|(x, y, se)| Emulator::fit(x, y, se)).collect();
                let nugget_sd = match &ems {
                    Some(ems) => ems.iter().map(|e| Some(e.nugget_variance().sqrt())).collect(),
                    None => vec![None; scatter.len()],
                };
                let posterior = ems.as_ref().and_then(|ems| {
                    let outs = Emulated::pair(&self.settings.targets, ems);
                    cal::posterior(&outs, self.sweep.dim(), self.seed)
                });
                let measured = scatter.iter().map(|s| s.runs).min().unwrap_or(0);
                self.batches.push(Batch {
                    label: space.label.clone(),
                    points: points.len(),
                    measured,
                    posterior,
                    change: None,
                    scatter,
                    nugget_sd,
                });
                self.last = Some((space.label.clone(), ems, d));
                let ivs: Vec<Option<Vec<(f64, f64)>>> =
                    self.batches.iter().map(|b| b.posterior.as_ref().map(|p| p.intervals())).collect();
                let (changes, conv) = cal::judge(&ivs, self.settings.tolerance, self.settings.hold);
                let k = self.batches.len() - 1;
                self.batches[k].change = changes[k];
                self.converged_at = conv;
                self.lines.push(self.line(k));
                k
            }
        };
        if self.converged_at.is_some_and(|c| c <= k) {
            Flow::Drain
        } else {
            Flow::Continue
        }
    }
}

/// `sweep calibrate SWEEP`: create the directory with its first batch and its settings (or
/// check an existing one), then run it batch by batch ([`batches::run`]).
pub fn start<E: Executor>(
    dir: SweepDir,
    settings: &Settings,
    exec: &E,
    opts: &RunOptions,
    watch: &mut CalibrationWatch,
    cancel: &CancelToken,
) -> Result<Summary> {
    let out = dir.out;
    if let Some(old) = self::settings(out).filter(|old| old != settings) {
        let why = format!(
            "holds a calibration against {}",
            old.targets
                .iter()
                .map(|t| format!("{}={}±{}", t.name, t.value, t.sd))
                .collect::<Vec<_>>()
                .join(", ")
        );
        return Err(RunError::OutDir { dir: out.to_path_buf(), why }.into());
    }
    super::create(dir, exec, opts.progress, cancel)?;
    name_first_batch(out)?;
    let text = serde_json::to_string_pretty(settings).expect("settings serialise");
    crate::sys::atomic::write(&out.join(SETTINGS), text.as_bytes())
        .map_err(|e| RunError::Write { path: out.join(SETTINGS), source: e })?;
    batches::run(out, exec, opts, watch, cancel)
}

/// What a calibration's batches are labelled: `calibrate 44`, the space of its first 44 points.
const BATCH: &str = "calibrate";

/// Name the first batch as the later ones are named, `calibrate N`, not `adapt N` after the
/// adaptive design that plans it (a calibration's first batch was shown as "adapt 40"). A
/// directory made before is renamed alike when it runs again: a label is shown and matched
/// within one process, never parsed, so nothing read from it changes.
fn name_first_batch(out: &Path) -> Result<()> {
    Store::open(out).update_manifest(|now| -> Result<Option<(Manifest, String)>> {
        let Some((mut m, toml)) = now else { return Ok(None) };
        let Some(first) = m.spaces.first_mut() else { return Ok(None) };
        let Some(n) = first.label.strip_prefix("adapt ") else { return Ok(None) };
        first.label = format!("{BATCH} {n}");
        Ok(Some((m, toml)))
    })?;
    Ok(())
}

impl Sequential for CalibrationWatch {
    const DESIGN: &'static str = "a calibration";
    fn take_lines(&mut self) -> Vec<String> {
        std::mem::take(&mut self.lines)
    }
    fn converged(&self) -> bool {
        self.converged_at.is_some()
    }
    /// Planned from the last batch's emulators: the settings that most reduce the variance of
    /// the posterior's density, each run `repeats` times.
    fn plan_next<E: Executor>(&self, exec: &E, from: &PlanFrom) -> Result<bool> {
        let PlanFrom { dir, manifest, sweep, last, size, seed, repeats } = *from;
        let Some((label, ems, d)) = self.last.as_ref().filter(|(l, ..)| l == last) else {
            return Ok(false);
        };
        let k = manifest.spaces.len() - 1;
        let post = self.batches.last().and_then(|b| b.posterior.as_ref());
        let cands = cal::candidates(sweep.dim(), k, seed, post);
        let existing = batches::taken(sweep, &manifest.points);
        let picks: Vec<Pick> = match ems {
            Some(ems) => {
                let outs = Emulated::pair(&self.settings.targets, ems);
                let noise: Vec<f64> =
                    ems.iter().zip(d).map(|(em, (_, _, se))| new_run_noise(em, se)).collect();
                cal::next_batch(&outs, &noise, &cands, &existing, size)
            }
            // No emulator yet: the candidates in their quasi-random order, which fill the space.
            None => cands[..size.min(cands.len())]
                .iter()
                .map(|u| Pick { point: u.clone(), why: "coverage", log_var: f64::NAN })
                .collect(),
        };
        let seeds = crate::run::plan::repeat_seeds(sweep, repeats);
        let planned: Vec<Planned<Pick>> = picks
            .iter()
            .flat_map(|c| {
                let values = crate::sweep::space::scale_point(sweep, &c.point);
                seeds.iter().map(move |&seed| Planned { values: values.clone(), seed, note: c })
            })
            .collect();
        batches::append(
            dir,
            exec,
            manifest,
            &planned,
            BATCH,
            |_| false,
            |rows| write_batches(dir, sweep, label, k + 1, rows),
        )
    }
}

/// Append the rows of one batch to [`BATCHES`] (written whole, under the directory's lock).
fn write_batches(dir: &Path, sweep: &Sweep, from: &str, batch: usize, rows: &[(usize, &Pick)]) -> Result<()> {
    let path: PathBuf = dir.join(BATCHES);
    // Rows a kill left of a batch planned again are replaced, not repeated.
    let text = batches::without_replanned(std::fs::read_to_string(&path).unwrap_or_default(), rows);
    let mut w = csv::Writer::from_writer(text.into_bytes());
    let csv_error = |e: csv::Error| RunError::Write { path: path.clone(), source: e.into() };
    let io_error = |e: std::io::Error| RunError::Write { path: path.clone(), source: e };
    if w.get_ref().is_empty() {
        let head = ["batch", "index", "planned_from", "why", "log_var_density"];
        w.write_record(head.iter().copied().chain(sweep.names())).map_err(csv_error)?;
    }
    for (index, c) in rows {
        let values = crate::sweep::space::scale_point(sweep, &c.point);
        let lv = if c.log_var.is_finite() { c.log_var.to_string() } else { String::new() };
        let head = [batch.to_string(), index.to_string(), from.to_string(), c.why.to_string(), lv];
        w.write_record(head.into_iter().chain(values.iter().map(|v| v.to_string()))).map_err(csv_error)?;
    }
    let text = w.into_inner().map_err(|e| io_error(e.into_error()))?;
    crate::sys::atomic::write(&path, &text)
        .map_err(|e| RunError::Write { path: path.clone(), source: e }.into())
}

/// Judge the finished batches of the calibration in `dir` without running anything (for
/// `sweep report`): `watch` then holds every judged batch and the last batch's emulators.
pub fn judge_dir(dir: &Path, watch: &mut CalibrationWatch) -> Result<(Manifest, Vec<PointStatus>)> {
    let (manifest, _) = Store::read_manifest(dir)?;
    let (status, _, _) = crate::run::screen::Screen::of(&watch.sweep).statuses(&Store::open(dir), &manifest);
    batches::judge_finished(&manifest, &status, watch);
    Ok((manifest, status))
}
