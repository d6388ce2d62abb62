//! `sweep extend`: raise a finished sweep's precision without running its points again. Every
//! done point whose SE of MFR is above the target is continued from where its run ended
//! ([`crate::point::extend`]) until its SE meets the target or its window the cap; the warm-up,
//! most of a point's cost, is not paid twice. A sweep whose points run pass by pass (layers) is
//! extended by passes instead: each point not steady at its most goes on from its last pass
//! ([`crate::point::passes::extend`]).
//!
//! The target is `--se`, else the sweep's recorded precision (`precision.json`: an adaptive
//! sweep's first batch runs to the scene's own target, coarser than the rest). A `--se` is
//! recorded as the sweep's precision when the sweep chooses its own (`[scene] precision =
//! "sweep"`), so that the points it runs later run to it too.

use std::collections::{BTreeSet, VecDeque};
use std::path::Path;
use std::sync::Mutex;

use crate::error::Result;
use crate::point::extend::{self, Extended};
use crate::point::{self, PointContext};
use crate::run::error::RunError;
use crate::run::precision::{self, SweepPrecision, PRECISION};
use crate::store::{ClaimAttempt, Store};
use crate::sys::process::CancelToken;

/// What `sweep extend` did, point by point.
#[derive(Debug, Default)]
pub struct ExtendSummary {
    /// The SE target it extended to.
    pub target: f64,
    /// Done points to look at, and those looked at so far.
    pub points: usize,
    pub looked_at: usize,
    /// Points a new part brought nearer the target, and those of them whose window reached the
    /// cap before the deck's rule met the target.
    pub extended: usize,
    pub at_cap: usize,
    /// Their new parts' CPU time, s.
    pub cpu_s: f64,
    /// Points within the target already.
    pub met: usize,
    /// Points that cannot be continued, and points whose new part failed (they keep their
    /// earlier result); each said in its progress line.
    pub not_extendable: usize,
    pub failed: usize,
    /// Points another live process holds.
    pub busy: usize,
    pub interrupted: bool,
    /// Extended by passes (`--passes`): `met` counts the steady points, `failed` those still
    /// not steady (or failed otherwise) at their new most.
    pub by_pass: bool,
}

/// What to extend a sweep's points to.
#[derive(Debug, Clone, Copy)]
pub enum Extension {
    /// An SE of MFR (None: the sweep's recorded precision).
    Se(Option<f64>),
    /// Up to this many more passes for each point not steady at its most.
    Passes(usize),
}

/// One done point to extend.
struct Job {
    index: usize,
    values: Vec<f64>,
    seed: Option<u64>,
    hash: String,
}

/// Extend the finished points of the sweep in `dir` as `how` says on `jobs` concurrent runs;
/// `progress` hears of each point as it ends.
pub fn extend_sweep(
    dir: &Path,
    how: Extension,
    jobs: usize,
    cancel: &CancelToken,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<ExtendSummary> {
    let sweep = crate::run::plan::load_dir_sweep(dir)?;
    let refuse =
        |why: String| -> crate::error::Error { RunError::Dir { path: dir.to_path_buf(), why }.into() };
    if crate::run::standin::selected(&sweep) {
        return Err(refuse("its engine is the stand-in, whose runs have no window to continue".into()));
    }
    let ctx = PointContext::new(sweep)?;
    let (manifest, _) = Store::read_manifest(dir)?;
    // Whether its points run pass by pass: the layout's answer for its first point.
    let by_pass = match manifest.points.first() {
        Some(first) => ctx.layout.by_pass(&point::prepare(&ctx, &first.values)?.scene).is_some(),
        None => false,
    };
    let target = match (how, by_pass) {
        (Extension::Passes(more), true) => {
            if more == 0 {
                return Err(refuse("--passes 0: expected at least one more pass".into()));
            }
            return run_jobs(dir, &ctx, &manifest, Mode::Passes(more), jobs, cancel, progress);
        }
        (Extension::Passes(_), false) => {
            return Err(refuse(
                "--passes extends a sweep whose points run pass by pass (scene.layout = \"layers\"); \
                 this sweep's points run to an SE: --se"
                    .into(),
            ))
        }
        (Extension::Se(_), true) => {
            return Err(refuse(
                "its points run pass by pass (scene.layout = \"layers\"): give --passes N, the most \
                 passes each point not yet steady may add"
                    .into(),
            ))
        }
        (Extension::Se(target), false) => target,
    };
    let recorded = precision::read(dir);
    let target = match (target, &recorded) {
        (Some(t), _) => t,
        (None, Some(p)) => p.mfr_abs_se,
        (None, None) => {
            return Err(refuse(format!(
                "no {PRECISION} (the sweep has not chosen its precision): give the SE to extend to, --se"
            )))
        }
    };
    // A layout whose runs have no SE target has no window to continue.
    if let Some(first) = manifest.points.first() {
        let p = point::prepare(&ctx, &first.values)?;
        if ctx.layout.with_precision(&p.scene, target).is_none() {
            let why = format!(
                "scene.layout \"{}\": its runs do not run to an SE target, so there is no window to continue",
                ctx.layout.name()
            );
            return Err(refuse(why));
        }
    }
    if let Some(p) =
        recorded_after(target, recorded.as_ref(), ctx.sweep.file.scene.own.keys().sweep_precision())
    {
        crate::sys::atomic::write_json(&dir.join(PRECISION), &p)
            .map_err(|e| refuse(format!("cannot write {PRECISION}: {e}")))?;
    }
    run_jobs(dir, &ctx, &manifest, Mode::Se(target), jobs, cancel, progress)
}

/// What one point is extended to.
#[derive(Debug, Clone, Copy)]
enum Mode {
    Se(f64),
    Passes(usize),
}

/// Extend every finished point of `manifest` as `mode` says, `jobs` at a time: an SE target
/// continues the done points, more passes the points that finished at all (a steady one runs
/// nothing, one not steady at its most goes on).
fn run_jobs(
    dir: &Path,
    ctx: &PointContext,
    manifest: &crate::store::Manifest,
    mode: Mode,
    jobs: usize,
    cancel: &CancelToken,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<ExtendSummary> {
    let store = Store::open(dir);
    let mut seen = BTreeSet::new();
    let finished = |hash: &str| {
        let run = store.run_dir(hash);
        run.join(point::RESULT).is_file()
            || (matches!(mode, Mode::Passes(_)) && run.join(point::FAILURE).is_file())
    };
    let todo: VecDeque<Job> = manifest
        .points
        .iter()
        .filter(|p| seen.insert(p.hash.clone()) && finished(&p.hash))
        .map(|p| Job { index: p.index, values: p.values.clone(), seed: p.seed, hash: p.hash.clone() })
        .collect();
    let target = match mode {
        Mode::Se(t) => t,
        Mode::Passes(_) => f64::NAN,
    };
    let by_pass = matches!(mode, Mode::Passes(_));
    let summary =
        Mutex::new(ExtendSummary { target, points: todo.len(), by_pass, ..ExtendSummary::default() });
    let queue = Mutex::new(todo);
    let _heartbeat = store.heartbeat();
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1) {
            scope.spawn(|| loop {
                if cancel.is_cancelled() {
                    return;
                }
                let Some(job) = queue.lock().unwrap().pop_front() else { return };
                let line = one(ctx, &store, &job, mode, cancel, &summary);
                if let Some(line) = line {
                    progress(&line);
                }
            });
        }
    });
    let mut summary = summary.into_inner().unwrap();
    summary.interrupted = cancel.is_cancelled();
    if summary.extended > 0 || (by_pass && summary.failed > 0) {
        crate::run::rewrite_results(dir)?;
    }
    Ok(summary)
}

/// The precision to record once the sweep's points are extended to `target`, if it changes:
/// in a sweep that chooses its own (`chooses`) and has (`recorded`), the later points run to
/// the new target too; a sweep whose precision is fixed, or not chosen yet, keeps its rule.
fn recorded_after(target: f64, recorded: Option<&SweepPrecision>, chooses: bool) -> Option<SweepPrecision> {
    let p = recorded.filter(|p| chooses && p.mfr_abs_se != target)?;
    Some(SweepPrecision { mfr_abs_se: target, ..p.clone() })
}

/// Extend one point under its claim; the progress line to print, if any.
fn one(
    ctx: &PointContext,
    store: &Store,
    job: &Job,
    mode: Mode,
    cancel: &CancelToken,
    summary: &Mutex<ExtendSummary>,
) -> Option<String> {
    let claim = match store.claim(&job.hash) {
        Ok(ClaimAttempt::Claimed(c, _)) => c,
        Ok(ClaimAttempt::Busy(_)) => {
            summary.lock().unwrap().busy += 1;
            return Some(format!("#{}: another process holds it; left as it is", job.index));
        }
        Err(e) => {
            summary.lock().unwrap().failed += 1;
            return Some(format!("#{}: {e}", job.index));
        }
    };
    let own;
    let ctx = match job.seed {
        Some(seed) => {
            let mut sweep = ctx.sweep.clone();
            sweep.file.scene.seed = seed;
            own = ctx.with_sweep(sweep);
            &own
        }
        None => ctx,
    };
    let outcome = match point::prepare(ctx, &job.values) {
        Ok(p) if p.hash == job.hash => match mode {
            Mode::Se(target) => extend::extend(ctx, &p, &store.run_dir(&job.hash), target, cancel),
            Mode::Passes(more) => point::passes::extend(ctx, &p, &store.run_dir(&job.hash), more, cancel),
        },
        Ok(p) => Extended::NotExtendable(format!("its deck renders to another hash now ({})", p.hash)),
        Err(e) => Extended::NotExtendable(format!("cannot render its deck: {e}")),
    };
    let _ = store.release(claim);
    let mut s = summary.lock().unwrap();
    s.looked_at += 1;
    let of = format!("[{}/{}] #{}", s.looked_at, s.points, job.index);
    match outcome {
        Extended::Met => {
            s.met += 1;
            let Mode::Passes(_) = mode else { return None };
            let r: Option<crate::outcome::RunResult> =
                std::fs::read_to_string(store.run_dir(&job.hash).join(point::RESULT))
                    .ok()
                    .and_then(|t| serde_json::from_str(&t).ok());
            Some(format!("{of}: steady already: {}", r.map_or(String::new(), |r| answer(ctx, &r))))
        }
        Extended::Done { before, after } if matches!(mode, Mode::Passes(_)) => {
            let cpu = after.cpu_time.unwrap_or(0.0) - before.cpu_time.unwrap_or(0.0);
            s.cpu_s += cpu;
            s.extended += 1;
            Some(format!("{of}: steady now, {} ({cpu:.0} CPU s more)", answer(ctx, &after)))
        }
        Extended::Failed(f) if matches!(mode, Mode::Passes(_)) => {
            s.failed += 1;
            let still =
                if f.class == crate::outcome::FailureClass::Unsteady { "still not steady" } else { "failed" };
            Some(format!("{of}: {still}: {}", f.reason))
        }
        Extended::Done { before, after } => {
            let (a, b) = (before.answer.se.unwrap_or(f64::NAN), after.answer.se.unwrap_or(f64::NAN));
            let cpu = after.cpu_time.unwrap_or(0.0) - before.cpu_time.unwrap_or(0.0);
            s.cpu_s += cpu;
            let at_cap = after.steady_state.as_ref().is_some_and(|st| st.stop == "cap");
            s.extended += 1;
            s.at_cap += usize::from(at_cap);
            let blocks =
                |r: &crate::outcome::RunResult| r.steady_state.as_ref().map_or(0, |st| st.block_mfr.len());
            Some(format!(
                "{of}: MFR {:.4} ± {a:.4} → {:.4} ± {b:.4} ({} more blocks, {cpu:.1} CPU s{})",
                before.answer.value,
                after.answer.value,
                blocks(&after) - blocks(&before),
                if at_cap { "; at the window cap" } else { "" },
            ))
        }
        Extended::NotExtendable(why) => {
            let line = format!("{of}: not extended: {why}");
            s.not_extendable += 1;
            Some(line)
        }
        Extended::Failed(f) => {
            let line = format!(
                "{of}: the extension failed ({}): {}; the point keeps its result",
                f.class.as_str(),
                f.reason
            );
            s.failed += 1;
            Some(line)
        }
        Extended::Cancelled => None,
    }
}

/// A pass-by-pass point's answer in its own terms: the layout's quantity with its SE, and its
/// detail (where its steady layer starts, of how many passes).
fn answer(ctx: &PointContext, r: &crate::outcome::RunResult) -> String {
    let name = r.answer.kind.words();
    let detail = ctx.layout.answer_detail(r).map_or(String::new(), |d| format!("; {d}"));
    format!("{name} {:.3} ± {:.3}{detail}", r.answer.value, r.answer.se.unwrap_or(f64::NAN))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_target_is_recorded_only_where_the_sweep_chooses_its_precision() {
        let p = SweepPrecision { mfr_abs_se: 0.004, spread: 0.03, points: 16, adaptive: true };
        let after = recorded_after(0.002, Some(&p), true).unwrap();
        assert_eq!(after, SweepPrecision { mfr_abs_se: 0.002, ..p.clone() });
        assert_eq!(recorded_after(0.004, Some(&p), true), None, "the same target");
        assert_eq!(recorded_after(0.002, Some(&p), false), None, "a fixed precision");
        assert_eq!(recorded_after(0.002, None, true), None, "none chosen yet");
    }
}
