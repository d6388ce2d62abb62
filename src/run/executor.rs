//! The real executor: one point run through LIGGGHTS in its content-addressed run directory.

use std::path::Path;

use crate::error::Result;
use crate::outcome::RunOutcome;
use crate::point::{self, PointContext};
use crate::run::finished::FinishedPoints;
use crate::run::pool::Executor;
use crate::run::precision;
use crate::run::standin::{self, StandIn, StandInJob};
use crate::sweep::Sweep;
use crate::sys::process::CancelToken;

/// The real executor: one LIGGGHTS run per point through [`crate::point`].
///
/// A job keeps only the point's values and hash; the deck is rendered again when the run starts
/// (rendering is cheap and deterministic), so a 10,000-point sweep does not hold 10,000 decks.
pub struct PointExecutor {
    ctx: PointContext,
    /// The finished points beside a run: where it starts, the sweep's precision.
    finished: FinishedPoints,
}

/// A point to run for real.
pub struct PointJob {
    values: Vec<f64>,
    /// Its own `scene.seed`, when not the sweep's.
    seed: Option<u64>,
    hash: String,
    /// Nothing can pass under the blade here ([`crate::scene::Scene::nothing_passes`]).
    closed: bool,
}

impl PointExecutor {
    /// Find LIGGGHTS and load the template of `sweep`.
    pub fn new(sweep: Sweep) -> Result<PointExecutor> {
        Ok(PointExecutor { ctx: PointContext::new(sweep)?, finished: FinishedPoints::default() })
    }

    /// Run each LIGGGHTS job on `ranks` MPI ranks (`mpirun -np ranks`).
    pub fn with_ranks(mut self, ranks: u32) -> PointExecutor {
        self.ctx.engine.ranks = ranks.max(1);
        self
    }
}

impl Executor for PointExecutor {
    type Job = PointJob;

    fn identity(&self) -> serde_json::Value {
        self.ctx.identity()
    }

    fn prepare_seeded(&self, swept: &[f64], seed: Option<u64>) -> Result<PointJob> {
        let own = self.reseeded(seed);
        let p = point::prepare(own.as_ref().unwrap_or(&self.ctx), swept)?;
        Ok(PointJob { values: swept.to_vec(), seed, hash: p.hash, closed: p.scene.nothing_passes() })
    }

    fn hash<'a>(&self, job: &'a PointJob) -> &'a str {
        &job.hash
    }

    fn closed(&self, job: &PointJob) -> bool {
        job.closed
    }

    fn execute(&self, job: &PointJob, run_dir: &Path, cancel: &CancelToken) -> RunOutcome {
        let own = self.reseeded(job.seed);
        let ctx = own.as_ref().unwrap_or(&self.ctx);
        match point::prepare(ctx, &job.values) {
            Ok(p) if p.hash == job.hash => {
                let start = self.start(job, run_dir);
                point::execute_from(ctx, &p, run_dir, cancel, &start)
            }
            // Prepared once already, so neither can happen short of a bug; fail the run loudly.
            Ok(p) => point_failure(job, run_dir, format!("deck hash changed on re-render: {}", p.hash)),
            Err(e) => point_failure(job, run_dir, format!("cannot render the deck: {e}")),
        }
    }
}

impl PointExecutor {
    /// The point context of a run with `seed` as its `scene.seed`; `None` without one (the
    /// sweep's own context then serves).
    fn reseeded(&self, seed: Option<u64>) -> Option<PointContext> {
        seed.map(|seed| {
            let mut sweep = self.ctx.sweep.clone();
            sweep.file.scene.seed = seed;
            self.ctx.with_sweep(sweep)
        })
    }

    /// How the run in `run_dir` starts, from the finished points beside it: the nearest one's
    /// steady state (`[scene] warm_start`), and the sweep's precision (`[scene] precision`).
    fn start(&self, job: &PointJob, run_dir: &Path) -> point::Start {
        let settings = &self.ctx.sweep.file.scene;
        let (Some(runs), Some(sweep_dir)) = (run_dir.parent(), run_dir.parent().and_then(Path::parent))
        else {
            return point::Start::default();
        };
        let sweep = &self.ctx.sweep;
        let mfr_se_target = settings
            .own
            .keys()
            .sweep_precision()
            .then(|| {
                precision::read(sweep_dir).or_else(|| {
                    precision::settle(
                        sweep_dir,
                        sweep.dim(),
                        sweep.file.convergence.tolerance,
                        precision::is_adaptive_sweep(sweep_dir),
                        &self.finished.mfrs(sweep, runs),
                    )
                })
            })
            .flatten()
            .map(|p| p.mfr_abs_se);
        let neighbour = settings
            .own
            .keys()
            .warm_start()
            .then(|| self.finished.nearest(sweep, runs, &job.values, &job.hash))
            .flatten();
        point::Start { neighbour, mfr_se_target }
    }
}

fn point_failure(job: &PointJob, run_dir: &Path, reason: String) -> RunOutcome {
    use crate::outcome::{FailureClass, RunFailure};
    let f = RunFailure::of(&job.hash, FailureClass::CouldNotStart, reason, String::new(), 0.0);
    let _ = crate::sys::atomic::write_json(&run_dir.join(point::FAILURE), &f);
    RunOutcome::Failed(f)
}

/// The executor a sweep file asks for, chosen once: LIGGGHTS, or the stand-in
/// (`run.engine = "stand-in"`).
pub enum SweepExecutor {
    Real(Box<PointExecutor>),
    StandIn(Box<StandIn>),
}

/// A job of a [`SweepExecutor`].
pub enum SweepJob {
    Real(PointJob),
    StandIn(StandInJob),
}

impl SweepExecutor {
    /// The stand-in when the sweep selects it, else LIGGGHTS (found and identified here).
    pub fn for_sweep(sweep: &Sweep) -> Result<SweepExecutor> {
        let layout = &sweep.file.scene.layout;
        if let Some(why) = crate::scenes::lookup(layout).and_then(|l| l.refuses_sweeps()) {
            let why = format!("scene.layout \"{layout}\": {why}");
            return Err(crate::run::error::RunError::Dir { path: sweep.path.clone(), why }.into());
        }
        if standin::selected(sweep) {
            Ok(SweepExecutor::StandIn(Box::new(StandIn::new(sweep.clone())?)))
        } else {
            Ok(SweepExecutor::Real(Box::new(PointExecutor::new(sweep.clone())?)))
        }
    }
}

impl Executor for SweepExecutor {
    type Job = SweepJob;

    fn identity(&self) -> serde_json::Value {
        match self {
            SweepExecutor::Real(e) => e.identity(),
            SweepExecutor::StandIn(e) => e.identity(),
        }
    }

    fn prepare_seeded(&self, swept: &[f64], seed: Option<u64>) -> Result<SweepJob> {
        match self {
            SweepExecutor::Real(e) => e.prepare_seeded(swept, seed).map(SweepJob::Real),
            SweepExecutor::StandIn(e) => e.prepare_seeded(swept, seed).map(SweepJob::StandIn),
        }
    }

    fn hash<'a>(&self, job: &'a SweepJob) -> &'a str {
        match (self, job) {
            (SweepExecutor::Real(e), SweepJob::Real(j)) => e.hash(j),
            (SweepExecutor::StandIn(e), SweepJob::StandIn(j)) => e.hash(j),
            _ => unreachable!("a job is prepared by the executor that runs it"),
        }
    }

    fn closed(&self, job: &SweepJob) -> bool {
        match (self, job) {
            (SweepExecutor::Real(e), SweepJob::Real(j)) => e.closed(j),
            (SweepExecutor::StandIn(e), SweepJob::StandIn(j)) => e.closed(j),
            _ => unreachable!("a job is prepared by the executor that runs it"),
        }
    }

    fn execute(&self, job: &SweepJob, run_dir: &Path, cancel: &CancelToken) -> RunOutcome {
        match (self, job) {
            (SweepExecutor::Real(e), SweepJob::Real(j)) => e.execute(j, run_dir, cancel),
            (SweepExecutor::StandIn(e), SweepJob::StandIn(j)) => e.execute(j, run_dir, cancel),
            _ => unreachable!("a job is prepared by the executor that runs it"),
        }
    }
}
