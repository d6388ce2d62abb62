//! A finished point's run extended to a tighter SE target: its window continued in a new part
//! (`extension-N/` in its run directory) from where the last part ended, and its result
//! measured again over every part ([`crate::scenes::Layout::continuation`]).
//!
//! The point's `result.json` is replaced only once the new part is measured: a part that is
//! interrupted or fails leaves the point's earlier result standing (a failure is written in the
//! part's directory), and a later extension starts that part again.

use std::path::{Path, PathBuf};

use super::{PointContext, Prepared, FAILURE, RESULT};
use crate::engine::{LogLimits, RunStatus};
use crate::outcome::{FailureClass, RunFailure, RunResult};
use crate::point::deck::Deck;
use crate::scenes::Finished;
use crate::sys::atomic::write_json;
use crate::sys::process::CancelToken;

/// The directory of a run's n-th extension (n from 1), in the point's run directory.
pub fn part_dir(run_dir: &Path, n: u32) -> PathBuf {
    run_dir.join(format!("extension-{n}"))
}

/// What extending one point came to.
#[derive(Debug)]
pub enum Extended {
    /// Its SE was within the target already: nothing ran.
    Met,
    /// A new part ran; the point's result is the one over every part.
    Done {
        before: Box<RunResult>,
        after: Box<RunResult>,
    },
    /// It cannot be continued, and why (nothing ran).
    NotExtendable(String),
    /// The new part failed; the point keeps its earlier result.
    Failed(Box<RunFailure>),
    Cancelled,
}

/// Extend the finished run of `p` in `run_dir` until the SE of its MFR is at most `target`.
pub fn extend(
    ctx: &PointContext,
    p: &Prepared,
    run_dir: &Path,
    target: f64,
    cancel: &CancelToken,
) -> Extended {
    let before: RunResult = match std::fs::read_to_string(run_dir.join(RESULT))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
    {
        Some(r) => r,
        None => return Extended::NotExtendable(format!("no readable {RESULT}: the point has not finished")),
    };
    let Some(se) = before.answer.se else {
        return Extended::NotExtendable("its result has no SE of MFR".into());
    };
    // A run whose deck stopped on a target at least as tight has met this one by the deck's
    // rule, though the result's SE, widened where its blocks are correlated, may read above it.
    let stopped_on = before.steady_state.as_ref().filter(|st| st.stop == "target").and(before.mfr_se_target);
    if se <= target || stopped_on.is_some_and(|t| t <= target) {
        return Extended::Met;
    }
    let parts: Vec<PathBuf> = std::iter::once(run_dir.to_path_buf())
        .chain((1..=before.extensions).map(|n| part_dir(run_dir, n)))
        .collect();
    let Some(scene) = ctx.layout.with_precision(&p.scene, target) else {
        return Extended::NotExtendable(format!(
            "the {} layout does not run to a precision",
            ctx.layout.name()
        ));
    };
    let n = before.extensions + 1;
    let dir = part_dir(run_dir, n);
    // What an interrupted or failed attempt at this part left goes; so does the part of one
    // that turns out not to be extendable.
    let _ = std::fs::remove_dir_all(&dir);
    let not = |why: String| {
        let _ = std::fs::remove_dir_all(&dir);
        Extended::NotExtendable(why)
    };
    if let Err(e) = std::fs::create_dir_all(&dir) {
        return not(format!("cannot create {}: {e}", dir.display()));
    }
    let warm_distance = before.warm_start.as_ref().map(|w| w.distance);
    let scene = match ctx.layout.continuation(&scene, warm_distance, &parts, &dir) {
        Ok(s) => s,
        Err(why) => return not(why),
    };
    let input = match ctx.template.render(&scene) {
        Ok(input) if input.contains("read_restart") => input,
        Ok(_) => {
            return not(
                "the sweep's template (scene.template) has no read_restart: it cannot continue a run".into()
            )
        }
        Err(e) => return not(format!("cannot render the continuation: {e}")),
    };
    let fail_measured = |class, reason, log_tail, wall, measured| {
        let f = RunFailure { measured, ..RunFailure::of(&p.hash, class, reason, log_tail, wall) };
        ctx.layout.keep(&dir, false);
        let _ = write_json(&dir.join(FAILURE), &f);
        Extended::Failed(Box::new(f))
    };
    let fail = |class: FailureClass, reason: String, log_tail: String, wall: f64| {
        fail_measured(class, reason, log_tail, wall, None)
    };
    let deck = Deck { input, ..p.deck.clone() };
    if let Err(e) = deck.write(&dir) {
        return fail(
            FailureClass::CouldNotStart,
            format!("cannot write the deck in {}: {e}", dir.display()),
            String::new(),
            0.0,
        );
    }
    let limits = LogLimits { ke_limit: scene.ke_limit, atoms: ctx.layout.atoms_kept(&scene) };
    let run = ctx.engine.run(&dir, Deck::INPUT, &limits, ctx.timeout, cancel);
    match run.status {
        RunStatus::Cancelled => return Extended::Cancelled,
        RunStatus::Failed { class, reason, log_tail } => return fail(class, reason, log_tail, run.wall_time),
        RunStatus::Ok => {}
    }
    if let Some(why) = super::cut_off(&dir) {
        return fail(FailureClass::Unparsable, why, String::new(), run.wall_time);
    }
    let finished = Finished {
        scene: &scene,
        parameters: &p.parameters,
        hash: &p.hash,
        run_dir: &dir,
        run: &run,
        engine_version: &ctx.engine.version,
        earlier: &parts,
    };
    let mut after = match ctx.layout.measure(&finished) {
        Ok(r) => r,
        // An unsteady part keeps what it measured, for the record (never the point's result).
        Err(r) => return fail_measured(r.class, r.reason, String::new(), run.wall_time, r.measured),
    };
    // The point's cost is every part's.
    after.wall_time += before.wall_time;
    after.cpu_time = match (after.cpu_time, before.cpu_time) {
        (Some(a), Some(b)) => Some(a + b),
        _ => None,
    };
    after.warm_start = before.warm_start.clone();
    after.mfr_se_target = Some(target);
    after.extensions = n;
    ctx.layout.keep(&dir, true);
    if let Err(e) = write_json(&run_dir.join(RESULT), &after) {
        return fail(
            FailureClass::Unparsable,
            format!("cannot write {RESULT}: {e}"),
            String::new(),
            run.wall_time,
        );
    }
    Extended::Done { before: Box::new(before), after: Box::new(after) }
}
