//! A point run pass by pass ([`crate::scenes::Layout::by_pass`]): one engine run a pass, each
//! going on from the restart the pass before wrote, until the layout's measure of every pass so
//! far says the point is done — steady, or at its most passes.
//!
//! In the run directory, pass k leaves its deck `in.pass.k`, its log `log.pass.k` (renamed from
//! the engine's log once the pass ended well), its record `pass.k.json` (the run's hash, the
//! pass's clocks) and the restart `restart.pass.k`, kept until pass k + 1 has ended. A point that
//! is interrupted (Ctrl-C, a lost node, a kill) resumes from its last recorded pass: it loses at
//! most the pass that was running. Every pass is its own engine run whether or not the point was
//! interrupted, so an interrupted point ends where an uninterrupted one does.

use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::extend::Extended;
use super::{cut_off, PointContext, Prepared, Started, FAILURE, RESULT};
use crate::engine::{EngineRun, LogLimits, RunStatus, LOG};
use crate::outcome::{FailureClass, RunFailure, RunOutcome, RunResult, WarmStart};
use crate::scene::Scene;
use crate::scenes::{ByPass, Finished};
use crate::sys::atomic::write_json;
use crate::sys::process::CancelToken;

/// The deck of pass `k`.
pub fn pass_input(k: usize) -> String {
    format!("in.pass.{k}")
}

/// The log of pass `k`, once it ended well.
pub fn pass_log(k: usize) -> String {
    format!("log.pass.{k}")
}

/// The record of pass `k`.
pub fn pass_record(k: usize) -> String {
    format!("pass.{k}.json")
}

/// The restart pass `k` wrote.
pub fn pass_restart(k: usize) -> String {
    format!("restart.pass.{k}")
}

/// Whether `run_dir` holds a point that has finished a pass: it goes on from there, so its
/// directory is not emptied before another attempt.
pub fn has_passes(run_dir: &Path) -> bool {
    run_dir.join(pass_record(1)).is_file()
}

/// Where a point run by the pass started from, when it started from a finished neighbour: kept
/// in its run directory so that it resumes from the same whichever neighbours are done by then.
pub const WARM_START: &str = "warm-start.json";

#[derive(Debug, Clone, Serialize, Deserialize)]
struct PassWarm {
    record: WarmStart,
    /// The layout's own account of the state it started from ([`crate::scenes::Warm`]'s data).
    data: String,
}

/// The scene a point run by the pass runs, and the warm start it records: a point that has run
/// a pass goes on as it began (warm from the start it recorded, else cold); one that has not
/// starts as `fresh` says (a neighbour's state, or cold) and records a warm start.
pub(super) fn warm_start(
    ctx: &PointContext,
    p: &Prepared,
    run_dir: &Path,
    fresh: impl FnOnce() -> Started,
) -> Result<(Scene, Option<WarmStart>), String> {
    let file = run_dir.join(WARM_START);
    if has_passes(run_dir) {
        return recorded_start(ctx, &p.scene, run_dir);
    }
    let _ = std::fs::remove_file(&file);
    let Started { scene, warm, .. } = fresh();
    let Some((w, record)) = warm else { return Ok((scene, None)) };
    write_json(&file, &PassWarm { record: record.clone(), data: w.data })
        .map_err(|e| format!("cannot write {}: {e}", file.display()))?;
    Ok((scene, Some(record)))
}

/// `scene` as the point in `run_dir` began: from the warm start it recorded, else cold.
fn recorded_start(
    ctx: &PointContext,
    scene: &Scene,
    run_dir: &Path,
) -> Result<(Scene, Option<WarmStart>), String> {
    let file = run_dir.join(WARM_START);
    let Ok(text) = std::fs::read_to_string(&file) else { return Ok((scene.clone(), None)) };
    let w: PassWarm = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", file.display()))?;
    Ok((ctx.layout.warm_again(scene, &w.data)?, Some(w.record)))
}

/// What a finished pass records: whose it is and what it cost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassRecord {
    pub hash: String,
    pub k: usize,
    pub wall_time: f64,
    pub cpu_time: Option<f64>,
}

/// The record pass `k` left in `run_dir`, if it finished (and its record is whole).
pub fn read_record(run_dir: &Path, k: usize) -> Option<PassRecord> {
    std::fs::read_to_string(run_dir.join(pass_record(k))).ok().and_then(|t| serde_json::from_str(&t).ok())
}

/// The passes of a point already run in `run_dir` that it can go on from: every one from the
/// first recorded with its log, the last with its restart. `Err`: a record there is another
/// run's.
pub fn finished_passes(run_dir: &Path, hash: &str) -> Result<Vec<PassRecord>, String> {
    let mut done: Vec<PassRecord> = Vec::new();
    for k in 1.. {
        let path = run_dir.join(pass_record(k));
        let Some(record) = read_record(run_dir, k) else { break };
        if record.hash != hash {
            return Err(format!(
                "{} is run {}'s, not this point's ({hash}): remove the run directory to run the point again",
                path.display(),
                record.hash
            ));
        }
        if record.k != k || !run_dir.join(pass_log(k)).is_file() {
            break;
        }
        done.push(record);
    }
    // Only the last pass's restart is kept: without it the point starts again.
    if done.last().is_some_and(|last| !run_dir.join(pass_restart(last.k)).is_file()) {
        done.clear();
    }
    Ok(done)
}

/// Every pass's log, in order, as one.
fn joined_logs(run_dir: &Path, passes: usize) -> String {
    (1..=passes)
        .map(|k| std::fs::read_to_string(run_dir.join(pass_log(k))).unwrap_or_default())
        .collect::<Vec<_>>()
        .join("\n")
}

/// Remove what passes after `kept` left (an interrupted pass's log, dumps, deck, restart).
fn remove_after(ctx: &PointContext, run_dir: &Path, kept: usize, most: usize) {
    for k in kept + 1..=most.max(kept + 1) {
        for f in [pass_input(k), pass_log(k), pass_record(k), pass_restart(k)] {
            let _ = std::fs::remove_file(run_dir.join(f));
        }
    }
    for f in ctx.layout.pass_files(kept + 1, most) {
        let _ = std::fs::remove_file(run_dir.join(f));
    }
    let _ = std::fs::remove_file(run_dir.join(LOG));
}

/// Run `p` (whose scene is `scene`) in `run_dir` pass by pass, from its last recorded pass, until
/// its layout says it is done or it has run `by.most` passes. Writes `result.json` or
/// `failure.json` (removing the other); a cancelled run writes neither and keeps its passes and
/// what an earlier attempt concluded.
pub fn execute(
    ctx: &PointContext,
    p: &Prepared,
    scene: &Scene,
    by: ByPass,
    run_dir: &Path,
    cancel: &CancelToken,
    warm: Option<&WarmStart>,
) -> RunOutcome {
    let fail_measured = |class, reason, log_tail, wall, measured| {
        let f = RunFailure { measured, ..RunFailure::of(&p.hash, class, reason, log_tail, wall) };
        let _ = std::fs::remove_file(run_dir.join(RESULT));
        let _ = write_json(&run_dir.join(FAILURE), &f);
        RunOutcome::Failed(f)
    };
    let fail = |class, reason, log_tail, wall| fail_measured(class, reason, log_tail, wall, None);
    let mut done = match finished_passes(run_dir, &p.hash) {
        Ok(d) => d,
        Err(why) => return fail(FailureClass::CouldNotStart, why, String::new(), 0.0),
    };
    remove_after(ctx, run_dir, done.len(), by.most.max(done.len()));
    let limits = LogLimits { ke_limit: scene.ke_limit, atoms: ctx.layout.atoms_kept(scene) };
    let spent = |done: &[PassRecord]| done.iter().map(|r| r.wall_time).sum::<f64>();
    let mut k = done.len();
    // The timeout bounds this attempt's passes: a point resumed after an interruption (a lost
    // node, a new Slurm job, a stopped session) gets the whole of it again, as a fresh job gets
    // its walltime; the passes it already has are not run again.
    let resumed_from = done.len();
    loop {
        // Measured from the least on: after each pass, and at once when a point goes on from
        // passes that already reach it (a run cut off before its result was written, more
        // passes allowed by `sweep extend`).
        if k >= by.least {
            match measure(ctx, p, scene, k, run_dir, &done) {
                Ok(mut result) => {
                    result.warm_start = warm.cloned();
                    if let Err(e) = write_json(&run_dir.join(RESULT), &result) {
                        let why = format!("cannot write {RESULT}: {e}");
                        return fail(FailureClass::Unparsable, why, String::new(), spent(&done));
                    }
                    let _ = std::fs::remove_file(run_dir.join(FAILURE));
                    return RunOutcome::Done(result);
                }
                // Not steady yet: the next pass, if the point may run one.
                Err(r) if r.class == FailureClass::Unsteady && k < by.most => {}
                Err(r) => {
                    let measured = r.measured.map(|mut m| {
                        m.warm_start = warm.cloned();
                        m
                    });
                    return fail_measured(r.class, r.reason, String::new(), spent(&done), measured);
                }
            }
        }
        if k >= by.most {
            return fail(
                FailureClass::Unparsable,
                format!("no pass measured: {k} of at most {} run", by.most),
                String::new(),
                spent(&done),
            );
        }
        k += 1;
        let before = (k > 1).then(|| {
            (pass_restart(k - 1), std::fs::read_to_string(run_dir.join(pass_log(k - 1))).unwrap_or_default())
        });
        let pass = match ctx
            .layout
            .ready_pass(scene, k, run_dir)
            .and_then(|_| {
                ctx.layout.pass_scene(scene, k, before.as_ref().map(|(r, l)| (r.as_str(), l.as_str())))
            })
            .map_err(|e| e.to_string())
            .and_then(|s| ctx.template.render(&s).map_err(|e| e.to_string()))
        {
            Ok(input) => input,
            Err(why) => {
                return fail(
                    FailureClass::CouldNotStart,
                    format!("pass {k}: {why}"),
                    String::new(),
                    spent(&done),
                )
            }
        };
        if let Err(e) = std::fs::write(run_dir.join(pass_input(k)), pass) {
            let why = format!("cannot write {} in {}: {e}", pass_input(k), run_dir.display());
            return fail(FailureClass::CouldNotStart, why, String::new(), spent(&done));
        }
        let left = ctx.timeout.saturating_sub(Duration::from_secs_f64(spent(&done[resumed_from..])));
        let run = ctx.engine.run(run_dir, &pass_input(k), &limits, left, cancel);
        match run.status {
            RunStatus::Cancelled => return RunOutcome::Cancelled,
            RunStatus::Failed { class, reason, log_tail } => {
                return fail(class, format!("pass {k}: {reason}"), log_tail, spent(&done) + run.wall_time)
            }
            RunStatus::Ok => {}
        }
        if let Some(reason) = cut_off(run_dir) {
            let f = RunFailure::of(&p.hash, FailureClass::Unparsable, reason, String::new(), run.wall_time);
            return RunOutcome::Failed(f);
        }
        // LIGGGHTS stopped from outside may end without an error and without the pass's restart
        // (it writes `restart_forced_*` instead): the pass did not end, and is not recorded, so
        // the point goes on from the pass before it.
        if !run_dir.join(pass_restart(k)).is_file() {
            let why = format!(
                "pass {k}: LIGGGHTS ended without writing {} (stopped from outside?); the point goes on from pass {} when run again",
                pass_restart(k),
                k - 1
            );
            return fail(FailureClass::Signalled, why, String::new(), spent(&done) + run.wall_time);
        }
        let record = PassRecord { hash: p.hash.clone(), k, wall_time: run.wall_time, cpu_time: run.cpu_time };
        let kept = std::fs::rename(run_dir.join(LOG), run_dir.join(pass_log(k)))
            .and_then(|_| write_json(&run_dir.join(pass_record(k)), &record));
        if let Err(e) = kept {
            let why = format!("cannot keep pass {k}'s log in {}: {e}", run_dir.display());
            return fail(FailureClass::Unparsable, why, String::new(), spent(&done) + run.wall_time);
        }
        if k > 1 {
            let _ = std::fs::remove_file(run_dir.join(pass_restart(k - 1)));
        }
        done.push(record);
    }
}

/// The finished point of `p` in `run_dir` given up to `more` passes beyond those it ran (`sweep
/// extend --passes`): a point that was not steady at its most goes on from its last pass,
/// measured after each, until it is steady or at its new most. Its earlier outcome stands until
/// the new one is written; a steady point runs nothing.
pub fn extend(
    ctx: &PointContext,
    p: &Prepared,
    run_dir: &Path,
    more: usize,
    cancel: &CancelToken,
) -> Extended {
    let read = |file: &str| std::fs::read_to_string(run_dir.join(file)).ok();
    if read(RESULT).and_then(|t| serde_json::from_str::<RunResult>(&t).ok()).is_some() {
        return Extended::Met;
    }
    let Some(failure) = read(FAILURE).and_then(|t| serde_json::from_str::<RunFailure>(&t).ok()) else {
        return Extended::NotExtendable("it has not finished: `sweep resume` runs it".into());
    };
    let before = match failure.measured {
        Some(m) if failure.class == FailureClass::Unsteady => m,
        _ => {
            return Extended::NotExtendable(format!(
                "it failed ({}), not for want of passes: {}",
                failure.class.as_str(),
                failure.reason
            ))
        }
    };
    let ran = match finished_passes(run_dir, &p.hash) {
        Ok(done) if !done.is_empty() => done.len(),
        Ok(_) => {
            return Extended::NotExtendable("its last pass's restart is gone: run the point again".into())
        }
        Err(why) => return Extended::NotExtendable(why),
    };
    let (began, warm) = match recorded_start(ctx, &p.scene, run_dir) {
        Ok(s) => s,
        Err(why) => return Extended::NotExtendable(why),
    };
    let scene = match ctx.layout.with_most_passes(&began, ran + more) {
        Ok(s) => s,
        Err(why) => return Extended::NotExtendable(format!("no room for {more} more passes: {why}")),
    };
    let Some(by) = ctx.layout.by_pass(&scene) else {
        return Extended::NotExtendable(format!(
            "the {} layout does not run pass by pass",
            ctx.layout.name()
        ));
    };
    match execute(ctx, p, &scene, by, run_dir, cancel, warm.as_ref()) {
        RunOutcome::Done(after) => Extended::Done { before, after: Box::new(after) },
        RunOutcome::Failed(f) => Extended::Failed(Box::new(f)),
        RunOutcome::Cancelled => Extended::Cancelled,
    }
}

/// The layout's measure of passes 1 to `k`.
fn measure(
    ctx: &PointContext,
    p: &Prepared,
    scene: &Scene,
    k: usize,
    run_dir: &Path,
    done: &[PassRecord],
) -> Result<RunResult, crate::scenes::Rejected> {
    let cpu: Option<f64> = done.iter().map(|r| r.cpu_time).sum();
    let log = joined_logs(run_dir, k);
    let all = EngineRun {
        status: RunStatus::Ok,
        wall_time: done.iter().map(|r| r.wall_time).sum(),
        cpu_time: cpu,
        warnings: crate::engine::distinct_warnings(&log),
        log,
    };
    let earlier: [PathBuf; 0] = [];
    ctx.layout.measure(&Finished {
        scene: &ctx.layout.measured_through(scene, k),
        parameters: &p.parameters,
        hash: &p.hash,
        run_dir,
        run: &all,
        engine_version: &ctx.engine.version,
        earlier: &earlier,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `dir` holding passes 1..=n of run `hash` as a finished pass leaves them, the last one's
    /// restart kept.
    fn passes_in(dir: &Path, hash: &str, n: usize) {
        for k in 1..=n {
            let record = PassRecord { hash: hash.into(), k, wall_time: 1.0, cpu_time: Some(1.0) };
            write_json(&dir.join(pass_record(k)), &record).unwrap();
            std::fs::write(dir.join(pass_log(k)), "log").unwrap();
        }
        std::fs::write(dir.join(pass_restart(n)), "restart").unwrap();
    }

    #[test]
    fn a_point_goes_on_from_its_last_pass_with_a_restart_and_starts_again_without_one() {
        let dir = tempfile::tempdir().unwrap();
        passes_in(dir.path(), "h", 3);
        assert_eq!(finished_passes(dir.path(), "h").unwrap().len(), 3);
        // A pass whose log was never kept is not finished: the passes stop before it, and the
        // restart of the pass before was removed once the later one ended.
        std::fs::remove_file(dir.path().join(pass_log(3))).unwrap();
        assert!(finished_passes(dir.path(), "h").unwrap().is_empty());
        // The last pass's restart lost (a copy without its largest files): run again from pass 1.
        let dir = tempfile::tempdir().unwrap();
        passes_in(dir.path(), "h", 2);
        std::fs::remove_file(dir.path().join(pass_restart(2))).unwrap();
        assert!(finished_passes(dir.path(), "h").unwrap().is_empty());
    }

    #[test]
    fn another_runs_pass_record_is_refused_naming_its_file() {
        let dir = tempfile::tempdir().unwrap();
        passes_in(dir.path(), "other", 1);
        let why = finished_passes(dir.path(), "mine").unwrap_err();
        assert!(why.contains("pass.1.json") && why.contains("other") && why.contains("mine"), "{why}");
    }
}
