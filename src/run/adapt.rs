//! `sweep adapt`: a sequential design, run batch by batch in one sweep directory.
//!
//! The first batch is `design.adapt.first` scrambled-Halton points. Each later batch is planned
//! from the results so far by the criterion of [`crate::analysis::adapt`] and appended to the
//! manifest as one more space (`adapt N`: the first N points), so every directory tool —
//! `status`, `report`, `predict`, the joblog, `resume` — reads it as it reads an LDS sweep.
//!
//! The loop ([`super::batches`]): run the unfinished points of the manifest ([`super::resume`], with the
//! [`AdaptWatch`] as the space hook, which judges each batch by the emulator's statistics);
//! stop if the rule holds, the sweep was interrupted, a point is still unfinished, or `max`
//! points are planned; else plan the next batch and go round.
//!
//! On a cluster the loop is split between jobs: the array tasks run a batch, and the job after
//! them judges it ([`standing`]) and plans the next ([`plan_after`]) before the next array is
//! submitted ([`crate::run::cluster`]); the batches are those a local run plans.
//!
//! Several processes may share one directory. A batch is a pure function of the points and
//! results before it, so two processes that finish a batch plan the same next one; the first
//! to take the directory's lock appends it, and the other finds it there and runs its share of
//! it (the claims keep every run to one process). A resume re-runs nothing: it judges the
//! finished batches again (the same numbers) and goes on where the directory stands.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::{RunError, RunOptions, Summary, SweepDir};
use crate::analysis::adapt::{self as criterion, Choice};
use crate::analysis::convergence::{judge, Criteria, SpaceStats};
use crate::analysis::emulator::{self, Emulator};
use crate::analysis::stats::{Interval, Moments};
use crate::error::Result;
use crate::run::batches::{self, PlanFrom, Planned, Sequential};
use crate::run::pool::{Executor, Flow};
use crate::run::SpaceHook;
use crate::store::{PointRecord, PointStatus, SpaceRecord, Store};
use crate::sweep::Sweep;
use crate::sys::process::CancelToken;

/// Most points an emulator conditions on (as the report's: past it a seeded random subset).
pub const FIT_MAX: usize = 800;
/// Seed of the emulator's statistics draws (the report's).
pub const STATS_SEED: u64 = 14;

/// `batches.csv`: why each planned point went where it went.
pub const BATCHES: &str = "batches.csv";

/// The points of a space the emulator is fitted to — done runs and screened zeros, in
/// manifest order, thinned to [`FIT_MAX`] — as unit coordinates, MFR and SE.
pub fn fit_data(
    sweep: &Sweep,
    points: &[(&PointRecord, &PointStatus)],
) -> (Vec<Vec<f64>>, Vec<f64>, Vec<Option<f64>>) {
    let usable: Vec<(&PointRecord, f64, Option<f64>)> = points
        .iter()
        .filter_map(|(p, s)| match s {
            PointStatus::Done(r) if r.answer.value.is_finite() => {
                Some((*p, r.answer.value, r.answer.se.filter(|v| v.is_finite())))
            }
            PointStatus::Screened => Some((*p, 0.0, None)),
            _ => None,
        })
        .collect();
    let picked = emulator::subset(usable.len(), FIT_MAX, 2);
    let mut out = (Vec::new(), Vec::new(), Vec::new());
    for i in picked {
        let (p, y, se) = usable[i];
        out.0.push(crate::sweep::space::unit_point(sweep, &p.values));
        out.1.push(y);
        out.2.push(se);
    }
    out
}

/// `adapt-stats.json`: the emulator's statistics of each judged space, so that a resume and
/// the report read them instead of fitting every space's emulator again. Only a cache: each
/// entry holds a digest of the points and results it came from and is used only when they are
/// the same.
pub const STATS_CACHE: &str = "adapt-stats.json";

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Cached {
    digest: String,
    moments: Moments,
    intervals: [Interval; 4],
}

/// The digest of an emulator's inputs (and of the settings of its statistics).
fn digest(x: &[Vec<f64>], y: &[f64], se: &[Option<f64>]) -> String {
    let mut h = Sha256::new();
    h.update(format!("{} {} {} {}\n", criterion::DRAWS, criterion::PATHS, STATS_SEED, emulator::FIT_POINTS));
    for ((u, v), s) in x.iter().zip(y).zip(se) {
        for c in u.iter().chain([v]) {
            h.update(c.to_bits().to_le_bytes());
        }
        h.update(s.map_or([0xff; 8], |s| s.to_bits().to_le_bytes()));
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

fn read_cache(dir: &Path) -> BTreeMap<String, Cached> {
    std::fs::read_to_string(dir.join(STATS_CACHE))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default()
}

/// The emulator's statistics of a space (`n` points) whose usable points are `x`, `y`, `se`,
/// and their posterior intervals: from `DIR/adapt-stats.json` when it holds them for these
/// inputs, else computed (and the emulator returned) and recorded there.
pub fn space_statistics(
    dir: &Path,
    label: &str,
    n: usize,
    x: &[Vec<f64>],
    y: &[f64],
    se: &[Option<f64>],
) -> (SpaceStats, [Interval; 4], Option<Emulator>) {
    let key = digest(x, y, se);
    if let Some(c) = read_cache(dir).get(label).filter(|c| c.digest == key) {
        let noise = c.intervals.map(|i| i.lo.zip(i.hi).map(|(lo, hi)| (hi - lo) / 2.0));
        return (SpaceStats { n, moments: c.moments, noise }, c.intervals, None);
    }
    let em = Emulator::fit_censored(x, y, se);
    let (st, e) = criterion::space_stats(n, em.as_ref(), STATS_SEED);
    let intervals = e.map_or([Interval::UNDEFINED; 4], |e| e.intervals);
    // Another process may write it meanwhile: the last writer wins, and a lost entry is only
    // computed again.
    let mut cache = read_cache(dir);
    cache.insert(label.to_string(), Cached { digest: key, moments: st.moments, intervals });
    if let Ok(text) = serde_json::to_string(&cache) {
        let _ = crate::sys::atomic::write(&dir.join(STATS_CACHE), text.as_bytes());
    }
    (st, intervals, em)
}

/// The rule applied to an adaptive sweep: the [`SpaceHook`] that judges each batch by the
/// emulator's statistics of the space, and keeps the last emulator for planning the next batch.
pub struct AdaptWatch {
    dir: PathBuf,
    sweep: Sweep,
    criteria: Criteria,
    spaces: Vec<SpaceStats>,
    labels: Vec<String>,
    /// The space the sweep converged at, once it has.
    pub converged_at: Option<(String, usize)>,
    /// The last judged space's label, its emulator if this process fitted it, and the points
    /// it is fitted to.
    last: Option<(String, Option<Emulator>, Fit)>,
    /// A line per batch judged since [`Sequential::take_lines`] was last called ([`batch_line`]).
    lines: Vec<String>,
}

/// Unit points, MFR and SE of the points an emulator is fitted to.
type Fit = (Vec<Vec<f64>>, Vec<f64>, Vec<Option<f64>>);

impl AdaptWatch {
    /// The watch of the adaptive sweep in `dir`.
    pub fn new(dir: &Path, sweep: &Sweep, criteria: Criteria) -> AdaptWatch {
        AdaptWatch {
            dir: dir.to_path_buf(),
            sweep: sweep.clone(),
            criteria,
            spaces: Vec::new(),
            labels: Vec::new(),
            converged_at: None,
            last: None,
            lines: Vec::new(),
        }
    }
}

/// One judged batch in words: `batch 2 (adapt 12, 12 points): mean 0.0465 [0.0447, 0.0486],
/// ...; the rule holds (1 in a row of 1): converged`.
pub fn batch_line(
    batch: usize,
    label: &str,
    st: &SpaceStats,
    iv: &[Interval; 4],
    j: &crate::analysis::convergence::Judgement,
    hold: usize,
) -> String {
    let num = |v: Option<f64>| v.map_or("undefined".to_string(), |v| format!("{v:.4}"));
    let stats: Vec<String> = crate::analysis::stats::STATISTICS
        .iter()
        .zip(iv)
        .map(|(s, i)| format!("{} {} [{}, {}]", s.name(), num(s.of(&st.moments)), num(i.lo), num(i.hi)))
        .collect();
    let verdict = match &j.changes {
        None => "the first batch, nothing to compare with yet".to_string(),
        Some(_) if j.converged => format!("the rule holds ({} in a row of {hold}): converged", j.streak),
        Some(_) if j.holds => format!("the rule holds ({} in a row of {hold})", j.streak),
        Some(ch) => {
            let off: Vec<&str> = crate::analysis::stats::STATISTICS
                .iter()
                .zip(ch)
                .filter(|(_, c)| !c.within)
                .map(|(s, _)| s.name())
                .collect();
            format!("the rule does not hold ({} not within it)", off.join(", "))
        }
    };
    format!("batch {batch} ({label}, {} points): {}; {verdict}", st.n, stats.join(", "))
}

impl SpaceHook for AdaptWatch {
    fn space_complete(&mut self, space: &SpaceRecord, points: &[(&PointRecord, &PointStatus)]) -> Flow {
        // A resume or a later batch fires the spaces judged before again: the same points and
        // results, so the same numbers.
        let k = match self.labels.iter().position(|l| *l == space.label) {
            Some(k) => k,
            None => {
                let (x, y, se) = fit_data(&self.sweep, points);
                let (st, iv, em) = space_statistics(&self.dir, &space.label, points.len(), &x, &y, &se);
                self.spaces.push(st);
                self.labels.push(space.label.clone());
                self.last = Some((space.label.clone(), em, (x, y, se)));
                let k = self.spaces.len() - 1;
                if let Some(j) = judge(&self.spaces, &self.criteria).last() {
                    let line = batch_line(k + 1, &space.label, &self.spaces[k], &iv, j, self.criteria.hold);
                    self.lines.push(line);
                }
                k
            }
        };
        match judge(&self.spaces[..=k], &self.criteria).last() {
            Some(j) if j.converged => {
                self.converged_at = Some((space.label.clone(), points.len()));
                Flow::Drain
            }
            _ => Flow::Continue,
        }
    }
}

/// `sweep adapt SWEEP`: create the directory with the first batch (or check an existing one
/// and take its batches as they are), then run it batch by batch ([`batches::run`]).
pub fn start<E: Executor>(
    dir: SweepDir,
    exec: &E,
    opts: &RunOptions,
    watch: &mut AdaptWatch,
    cancel: &CancelToken,
) -> Result<Summary> {
    let out = dir.out;
    super::create(dir, exec, opts.progress, cancel)?;
    batches::run(out, exec, opts, watch, cancel)
}

impl Sequential for AdaptWatch {
    const DESIGN: &'static str = "an adaptive sweep";
    /// Each batch's statistics with their intervals and what the rule made of them.
    fn take_lines(&mut self) -> Vec<String> {
        std::mem::take(&mut self.lines)
    }
    fn converged(&self) -> bool {
        self.converged_at.is_some()
    }
    /// Planned from the last emulator: the candidates that most reduce the statistics'
    /// posterior variance.
    fn plan_next<E: Executor>(&self, exec: &E, from: &PlanFrom) -> Result<bool> {
        let PlanFrom { dir, manifest, sweep, last, size, seed, .. } = *from;
        let Some((label, em, (x, y, se))) = self.last.as_ref().filter(|(l, ..)| l == last) else {
            return Ok(false);
        };
        // Judged from the cache: fitted now (the same inputs, so the same emulator).
        let fitted;
        let em = match em {
            Some(em) => Some(em),
            None => {
                fitted = Emulator::fit_censored(x, y, se);
                fitted.as_ref()
            }
        };
        let k = manifest.spaces.len() - 1;
        let cands =
            untaken(criterion::batch_candidates(sweep.dim(), k, seed, em, x), sweep, &manifest.points);
        let (chosen, j_before) = match em.and_then(|em| {
            let noise = criterion::RunNoise::of(em, se, &[]);
            let refs = criterion::reference(sweep.dim(), seed);
            criterion::next_batch(
                em,
                &noise,
                &cands,
                &refs,
                x,
                size,
                criterion::Split::of(size, criterion::EXPLORE),
            )
        }) {
            Some(c) => c,
            // No emulator yet (too few done points, or MFR the same everywhere): the candidates in
            // their quasi-random order, which fill the space.
            None => (
                cands[..size.min(cands.len())]
                    .iter()
                    .map(|u| Choice {
                        point: u.clone(),
                        mfr: f64::NAN,
                        se: f64::NAN,
                        gain: 0.0,
                        se_scale: 1.0,
                    })
                    .collect(),
                f64::NAN,
            ),
        };
        let planned: Vec<Planned<Choice>> = chosen
            .iter()
            .map(|c| Planned {
                values: crate::sweep::space::scale_point(sweep, &c.point),
                seed: None,
                note: c,
            })
            .collect();
        let screen = sweep.file.run.screen;
        batches::append(
            dir,
            exec,
            manifest,
            &planned,
            "adapt",
            |job| screen && exec.closed(job),
            |rows| write_batches(dir, sweep, label, k + 1, j_before, rows),
        )
    }
}

/// Where an adaptive sweep directory stands, judged from its finished batches alone.
#[derive(Debug, Clone, PartialEq)]
pub enum Standing {
    /// The rule held after the batch that ends the space `label` (`points` points).
    Converged { label: String, points: usize },
    /// This many planned points are not finished (not yet run, cut off, or held by a claim).
    Unfinished(usize),
    /// Every planned point is finished and the rule has not held: the next batch is due.
    Open,
}

/// Judge the finished batches of the adaptive sweep in `dir` as [`batches::run`] does, without running
/// anything: the step of a cluster chain between two arrays, where the runs are the array
/// tasks' ([`crate::run::cluster`]). `watch` then holds the last batch's emulator for
/// [`plan_after`].
pub fn standing(dir: &Path, watch: &mut AdaptWatch) -> Result<Standing> {
    let (manifest, toml) = Store::read_manifest(dir)?;
    let sweep = Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    let (status, _, _) = crate::run::screen::Screen::of(&sweep).statuses(&Store::open(dir), &manifest);
    if let Some(space) = batches::judge_finished(&manifest, &status, watch) {
        return Ok(Standing::Converged { label: space.label.clone(), points: space.points.len() });
    }
    match status.iter().filter(|s| !s.is_finished()).count() {
        0 => Ok(Standing::Open),
        n => Ok(Standing::Unfinished(n)),
    }
}

/// After [`standing`] said [`Standing::Open`]: append the next batch to the manifest, as [`batches::run`]
/// would. `false` when `max` points are planned already.
pub fn plan_after<E: Executor>(dir: &Path, exec: &E, watch: &AdaptWatch) -> Result<bool> {
    // Every point of the manifest counts as run.
    batches::plan_next(dir, exec, watch, usize::MAX)
}

/// `cands` without the points the design holds already ([`batches::taken`]) and without
/// repeats: a batch that chose only such points would add nothing and end the design short of
/// its max. Near a best run on a face the candidates clipped to the cube, and the upper bound's
/// peak, are that run itself (in one dimension the criterion chose the slowest blade twice and
/// the sweep stopped at 11 of 480 points).
fn untaken(cands: Vec<Vec<f64>>, sweep: &Sweep, points: &[PointRecord]) -> Vec<Vec<f64>> {
    let same = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(a, b)| (a - b).abs() <= 1e-9);
    let mut taken = batches::taken(sweep, points);
    let mut kept = Vec::with_capacity(cands.len());
    for c in cands {
        if !taken.iter().any(|t| same(t, &c)) {
            taken.push(c.clone());
            kept.push(c);
        }
    }
    kept
}

/// Append the rows of one batch to `DIR/batches.csv` (written whole, atomically, under the
/// directory's lock): each planned point, the emulator's MFR and SE there before the batch, and
/// the share of the criterion it was expected to remove.
fn write_batches(
    dir: &Path,
    sweep: &Sweep,
    from: &str,
    batch: usize,
    j_before: f64,
    rows: &[(usize, &Choice)],
) -> Result<()> {
    let path = dir.join(BATCHES);
    // Rows a kill left of a batch planned again are replaced, not repeated.
    let text = super::batches::without_replanned(std::fs::read_to_string(&path).unwrap_or_default(), rows);
    let mut w = csv::Writer::from_writer(text.into_bytes());
    let csv_error = |e: csv::Error| RunError::Write { path: path.clone(), source: e.into() };
    let io_error = |e: std::io::Error| RunError::Write { path: path.clone(), source: e };
    if w.get_ref().is_empty() {
        let head =
            ["batch", "index", "planned_from", "criterion_before", "gain", "emulator_mfr", "emulator_se"];
        let names = sweep.swept.iter().map(|p| p.name.as_str());
        w.write_record(head.iter().copied().chain(names)).map_err(csv_error)?;
    }
    let num = |v: f64| if v.is_finite() { format!("{v}") } else { String::new() };
    for (index, c) in rows {
        let values = crate::sweep::space::scale_point(sweep, &c.point);
        let head = [
            batch.to_string(),
            index.to_string(),
            from.to_string(),
            num(j_before),
            num(c.gain),
            num(c.mfr),
            num(c.se),
        ];
        w.write_record(head.into_iter().chain(values.iter().map(|v| v.to_string()))).map_err(csv_error)?;
    }
    let text = w.into_inner().map_err(|e| io_error(e.into_error()))?;
    crate::sys::atomic::write(&path, &text)
        .map_err(|e| RunError::Write { path: path.clone(), source: e }.into())
}
