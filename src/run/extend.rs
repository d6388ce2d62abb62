//! `sweep extend`: raise a finished sweep's precision without running its points again. Every
//! done point whose SE of MFR is above the target is continued from where its run ended
//! ([`crate::point::extend`]) until its SE meets the target or its window the cap; the warm-up,
//! most of a point's cost, is not paid twice.
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
}

/// One done point to extend.
struct Job {
    index: usize,
    values: Vec<f64>,
    seed: Option<u64>,
    hash: String,
}

/// Extend the done points of the sweep in `dir` to `target` (None: the sweep's recorded
/// precision) on `jobs` concurrent runs; `progress` hears of each point as it ends.
pub fn extend_sweep(
    dir: &Path,
    target: Option<f64>,
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
    let ctx = PointContext::new(sweep)?;
    let store = Store::open(dir);
    let (manifest, _) = Store::read_manifest(dir)?;
    let mut seen = BTreeSet::new();
    let todo: VecDeque<Job> = manifest
        .points
        .iter()
        .filter(|p| seen.insert(p.hash.clone()) && store.run_dir(&p.hash).join(point::RESULT).is_file())
        .map(|p| Job { index: p.index, values: p.values.clone(), seed: p.seed, hash: p.hash.clone() })
        .collect();
    // A layout whose runs have no SE target has no window to continue.
    if let Some(first) = todo.front() {
        let p = point::prepare(&ctx, &first.values)?;
        if ctx.layout.with_precision(&p.scene, target).is_none() {
            let why = format!(
                "scene.layout \"{}\": its runs do not run to an SE target, so there is no window to continue",
                ctx.layout.name()
            );
            return Err(refuse(why));
        }
    }
    if let Some(p) = recorded_after(target, recorded.as_ref(), ctx.sweep.file.scene.precision == "sweep") {
        crate::sys::atomic::write_json(&dir.join(PRECISION), &p)
            .map_err(|e| refuse(format!("cannot write {PRECISION}: {e}")))?;
    }
    let summary = Mutex::new(ExtendSummary { target, points: todo.len(), ..ExtendSummary::default() });
    let queue = Mutex::new(todo);
    let _heartbeat = store.heartbeat();
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1) {
            scope.spawn(|| loop {
                if cancel.is_cancelled() {
                    return;
                }
                let Some(job) = queue.lock().unwrap().pop_front() else { return };
                let line = one(&ctx, &store, &job, target, cancel, &summary);
                if let Some(line) = line {
                    progress(&line);
                }
            });
        }
    });
    let mut summary = summary.into_inner().unwrap();
    summary.interrupted = cancel.is_cancelled();
    if summary.extended > 0 {
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
    target: f64,
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
        Ok(p) if p.hash == job.hash => extend::extend(ctx, &p, &store.run_dir(&job.hash), target, cancel),
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
            None
        }
        Extended::Done { before, after } => {
            let (a, b) = (before.mfr_se.unwrap_or(f64::NAN), after.mfr_se.unwrap_or(f64::NAN));
            let cpu = after.cpu_time.unwrap_or(0.0) - before.cpu_time.unwrap_or(0.0);
            s.cpu_s += cpu;
            let at_cap = after.steady_state.as_ref().is_some_and(|st| st.stop == "cap");
            s.extended += 1;
            s.at_cap += usize::from(at_cap);
            let blocks =
                |r: &crate::outcome::RunResult| r.steady_state.as_ref().map_or(0, |st| st.block_mfr.len());
            Some(format!(
                "{of}: MFR {:.4} ± {a:.4} → {:.4} ± {b:.4} ({} more blocks, {cpu:.1} CPU s{})",
                before.mfr,
                after.mfr,
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
