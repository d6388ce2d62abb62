//! A deterministic stand-in for LIGGGHTS, for demos, end-to-end tests and benchmarks of the
//! sweep logic: `[run] engine = "stand-in"` in a sweep file.
//!
//! It runs no physics. Each point's result comes from its layout's closed-form model
//! ([`crate::scenes::Layout::stand_in`]; docs/statistics.md "The stand-in engine"), plus noise
//! drawn from the point's own parameters, so the same point gives the same numbers on every
//! machine: a flow under the blade for the moving-blade layouts and the conveyor
//! ([`crate::scenes::stand_in::flow`]), a heap for the pour, every pass and the steady layer for
//! the layers. A made-up result is checked as a read-back one is ([`crate::store::counts`]): one
//! that would not count is written as the point's failure, so a sweep ends rather than running
//! the point again on every resume.
//!
//! Not a substitute for LIGGGHTS in any result that is about powder: its numbers are made up.

use std::collections::BTreeMap;
use std::path::Path;

use sha2::{Digest, Sha256};

use crate::error::Result;
use crate::outcome::{FailureClass, RunFailure, RunOutcome, RunResult};
use crate::point::deck::Template;
use crate::point::{resolve, PointError, FAILURE, RESULT};
use crate::run::pool::Executor;
use crate::scenes::stand_in::{Noise, StandInPoint};
use crate::scenes::{Layout, Rejected};
use crate::sweep::{Sweep, SweepError};
use crate::sys::atomic::write_json;
use crate::sys::process::CancelToken;

/// The `run.engine` value that selects the stand-in.
pub const NAME: &str = "stand-in";
/// Changes whenever a layout's model changes, so a resume of a stand-in sweep notices.
pub const MODEL_VERSION: u32 = 3;
/// The version whose run hash seeds a point's noise: kept when a model changes, so that a
/// layout whose closed form stayed keeps its numbers (version 3 modelled the layers and slow
/// blades, and left the thesis's flow and the pour's heap as version 2 drew them).
const NOISE_VERSION: u32 = 2;

/// Whether a sweep asks for the stand-in.
pub fn selected(sweep: &Sweep) -> bool {
    sweep.file.run.engine.as_deref().is_some_and(|p| p == Path::new(NAME))
}

/// The stand-in executor.
pub struct StandIn {
    sweep: Sweep,
    /// The sweep's layout, whose model it runs.
    layout: &'static dyn Layout,
}

/// A point for the stand-in: every scene parameter and the hash.
pub struct StandInJob {
    parameters: BTreeMap<String, f64>,
    hash: String,
    /// What its noise is seeded with ([`NOISE_VERSION`]).
    noise: String,
}

impl StandIn {
    /// The stand-in for `sweep`, refusing what LIGGGHTS's executor refuses before it runs: a
    /// template that does not load. (Each point's bounds are checked as it is prepared.)
    pub fn new(sweep: Sweep) -> Result<StandIn> {
        let layout = crate::scenes::of(&sweep.file.scene).map_err(PointError::Layout)?;
        if let Some(path) = sweep.template_path() {
            Template::load(Some(&path), layout).map_err(|e| SweepError::Key {
                path: sweep.path.clone(),
                key: "scene.template".into(),
                why: e.to_string(),
            })?;
        }
        Ok(StandIn { layout, sweep })
    }
}

impl Executor for StandIn {
    type Job = StandInJob;

    fn identity(&self) -> serde_json::Value {
        serde_json::json!({ "engine": NAME, "model_version": MODEL_VERSION })
    }

    fn prepare_seeded(&self, swept: &[f64], seed: Option<u64>) -> Result<StandInJob> {
        let parameters = resolve(&self.sweep, swept);
        // The scene's bounds and unit slips, as a LIGGGHTS point is refused.
        crate::scenes::build(&parameters, &self.sweep.file.scene)
            .map_err(|source| PointError::Scene { path: self.sweep.path.clone(), source })?;
        let hash_of = |version: u32| {
            let mut h = Sha256::new();
            h.update(format!("{NAME} {version}\n"));
            // A parameter the point does not read (a roller's speed ratio on a blade) is left
            // out, so that every other point draws the noise it drew before it existed.
            for (k, v) in parameters.iter().filter(|(k, _)| crate::scenes::shown(&self.sweep.file.scene, k)) {
                h.update(format!("{k}={:016x}\n", v.to_bits()));
            }
            // A repeat with its own seed draws its own noise.
            if let Some(seed) = seed {
                h.update(format!("seed={seed}\n"));
            }
            h.finalize().iter().map(|b| format!("{b:02x}")).collect::<String>()
        };
        let (hash, noise) = (hash_of(MODEL_VERSION), hash_of(NOISE_VERSION));
        Ok(StandInJob { parameters, hash, noise })
    }

    fn hash<'a>(&self, job: &'a StandInJob) -> &'a str {
        &job.hash
    }

    fn execute(&self, job: &StandInJob, run_dir: &Path, _cancel: &CancelToken) -> RunOutcome {
        for stale in [RESULT, FAILURE] {
            let _ = std::fs::remove_file(run_dir.join(stale));
        }
        // Built once already when the job was prepared, so this cannot fail short of a bug.
        let scene = match crate::scenes::build(&job.parameters, &self.sweep.file.scene) {
            Ok(scene) => scene,
            Err(e) => return fail(job, run_dir, FailureClass::CouldNotStart, format!("{NAME}: {e}"), None),
        };
        let mut point =
            StandInPoint { scene: &scene, parameters: &job.parameters, noise: Noise::new(&job.noise) };
        let made_up = |r: RunResult| RunResult {
            hash: job.hash.clone(),
            parameters: job.parameters.clone(),
            engine_version: format!("{NAME} {MODEL_VERSION}"),
            warnings: vec![format!("{NAME}: a made-up model, not LIGGGHTS")],
            ..r
        };
        let r = match self.layout.stand_in(&mut point) {
            Ok(r) => made_up(r),
            Err(Rejected { class, reason, measured }) => {
                let measured = measured.map(|r| Box::new(made_up(*r)));
                return fail(job, run_dir, class, format!("{NAME}: {reason}"), measured);
            }
        };
        if let Err(why) = crate::store::counts(self.layout, &r) {
            let reason = format!(
                "{NAME}: the {} layout's model made a result its checks refuse: {why}",
                self.layout.name()
            );
            return fail(job, run_dir, FailureClass::Implausible, reason, Some(Box::new(r)));
        }
        match write_json(&run_dir.join(RESULT), &r) {
            Ok(()) => RunOutcome::Done(r),
            Err(e) => {
                let reason = format!("cannot write {}: {e}", run_dir.join(RESULT).display());
                fail(job, run_dir, FailureClass::CouldNotStart, reason, None)
            }
        }
    }
}

/// The point's failure, written to `failure.json` where it can be.
fn fail(
    job: &StandInJob,
    run_dir: &Path,
    class: FailureClass,
    reason: String,
    measured: Option<Box<RunResult>>,
) -> RunOutcome {
    let f = RunFailure { measured, ..RunFailure::of(&job.hash, class, reason, String::new(), 0.0) };
    let _ = write_json(&run_dir.join(FAILURE), &f);
    RunOutcome::Failed(f)
}
