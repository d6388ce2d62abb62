//! The sweep drivers: `sweep lattice`, `sweep lds`, `sweep resume` and `sweep status`, and what
//! they are built from: the executor ([`SweepExecutor`]: LIGGGHTS or the stand-in), the plan
//! (manifest and directory checks), the job [`pool`], the reporter of its events, the status of a
//! directory, the [`screen`] policy, [`progress`], and cluster arrays ([`cluster`]). Knows what
//! to run and in which order; how a point is computed is [`crate::point`]'s, and what the
//! results say is [`crate::analysis`]'s.
//!
//! A driver turns a sweep and a design into the directory's manifest (every distinct point with
//! its content hash, every nested space as a list of points), checks an existing directory
//! before touching it, queues the points that are not finished, and consumes the pool's events
//! with one reporter: joblog lines, results.csv (rewritten as points finish), progress, and the
//! per-space hook where convergence checking plugs in ([`SpaceHook`]).
//!
//! Spaces are not run as batches with a barrier between them: all points go into one queue in
//! design order (an LDS prefix, a lattice level, comes first), so no slot idles at the end of a
//! batch; the hook fires as soon as a space's last point finishes, and if it stops the sweep only
//! the runs already started past that space finish.
//!
//! Everything that can be refused (bad design, changed engine, a directory of another sweep) is
//! refused before anything is written.
//!
//! Not responsible for running one point (the [`Executor`]), for scheduling ([`crate::run::pool`]) or
//! for the directory's formats ([`crate::store`]); no statistics here.

pub mod adapt;
pub mod batches;
pub mod calibrate;
pub mod cluster;
mod error;
mod executor;
pub mod extend;
#[cfg(any(test, feature = "test-support"))]
pub mod fake;
mod finished;
mod plan;
pub mod pool;
pub mod precision;
pub mod progress;
mod reporter;
pub mod screen;
pub mod standin;
mod status;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::run::pool::{Executor, Flow, PoolOptions};
use crate::run::progress::ProgressMode;
use crate::run::screen::{Screen, ScreenReport, Verdict};
use crate::store::{self, DesignRecord, Manifest, PointStatus, RunState, Store, MANIFEST_FORMAT};
use crate::sweep::Sweep;
use crate::sys::process::CancelToken;

pub use error::{ClusterError, RunError};
pub use executor::{PointExecutor, PointJob, SweepExecutor, SweepJob};
use plan::{check_extension, check_parameters};
pub use plan::{
    check_out_dir, default_out, identity_diff, judge_from, load_dir_sweep, plan, plan_with_progress,
    resolved_toml, SweepPlan,
};
use reporter::Reporter;
pub use reporter::{RunAll, SpaceHook, Watch};
pub use status::{rewrite_results, status, FailureGroup, FailureNote, StatusReport};

/// Most points one design may have.
pub const MAX_POINTS: usize = 1_000_000;
/// Options shared by the running commands.
#[derive(Debug, Clone)]
pub struct RunOptions {
    pub jobs: usize,
    pub progress: ProgressMode,
    /// Re-run runs that failed (`sweep resume --retry-failed`).
    pub retry_failed: bool,
    /// Resume although the identity (template, mesh, engine) changed (`--force`).
    pub force: bool,
}

/// How a sweep ended.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    pub dir: PathBuf,
    pub points: usize,
    pub done: usize,
    pub failed: usize,
    /// Closed points skipped by a verified screen (MFR = 0).
    pub screened: usize,
    pub pending: usize,
    /// Runs executed by this process (not counting retries).
    pub ran: usize,
    /// Points already finished when it started.
    pub reused: usize,
    pub interrupted: bool,
    /// The space after which the hook stopped the sweep.
    pub stopped_after: Option<String>,
    /// What the screen did.
    pub screen: ScreenReport,
}

impl Summary {
    /// How the sweep ended: an interruption, or failed runs, is the error (the driver has
    /// written them to the joblog; `sweep status` lists them).
    pub fn ended(&self) -> Result<()> {
        if self.interrupted {
            Err(Error::SweepInterrupted { finished: self.done + self.failed, total: self.points })
        } else if self.failed > 0 {
            Err(Error::RunsFailed { failed: self.failed, total: self.points })
        } else {
            Ok(())
        }
    }

    /// The exit code of [`Summary::ended`]: 0, or what [`Error::code`] makes of its error.
    pub fn exit_code(&self) -> i32 {
        self.ended().map_or_else(|e| e.code(), |()| crate::error::exit::SUCCESS)
    }
}

/// The sweep directory a driver creates, or checks and extends: the sweep, the design its points
/// come from, and where it is.
pub struct SweepDir<'a> {
    pub sweep: &'a Sweep,
    pub design: DesignRecord,
    pub out: &'a Path,
}

impl<'a> SweepDir<'a> {
    pub fn new(sweep: &'a Sweep, design: DesignRecord, out: &'a Path) -> SweepDir<'a> {
        SweepDir { sweep, design, out }
    }
}

/// `sweep lattice` / `sweep lds`: create (or extend) the sweep directory `dir.out` and run it.
pub fn start<E: Executor>(
    dir: SweepDir,
    exec: &E,
    opts: &RunOptions,
    hook: &mut dyn SpaceHook,
    cancel: &CancelToken,
) -> Result<Summary> {
    let sweep = dir.sweep;
    let (store, manifest, jobs) = create(dir, exec, opts.progress, cancel)?;
    execute(&store, &manifest, exec, jobs, sweep, opts, None, hook, cancel)
}

/// `sweep lattice|lds --plan`: create (or extend) the sweep directory `dir.out` — manifest,
/// sweep.toml, results.csv with every unfinished point pending — and run nothing. Returns the
/// number of points and how many of them are unfinished.
pub fn plan_dir<E: Executor>(
    dir: SweepDir,
    exec: &E,
    progress: ProgressMode,
    cancel: &CancelToken,
) -> Result<(usize, usize)> {
    let out = dir.out;
    let (store, manifest, _) = create(dir, exec, progress, cancel)?;
    rewrite_results(out)?;
    let unfinished = manifest.points.iter().filter(|p| store.finished(&p.hash).is_none()).count();
    Ok((manifest.points.len(), unfinished))
}

/// Plan the design and write (or check and extend) the directory's manifest, under its lock.
fn create<E: Executor>(
    dir: SweepDir,
    exec: &E,
    progress: ProgressMode,
    cancel: &CancelToken,
) -> Result<(Store, Manifest, Vec<E::Job>)> {
    let SweepDir { sweep, design, out } = dir;
    check_out_dir(out)?;
    if !Store::manifest_path(out).exists() {
        // Another `sweep` may write the manifest while we look: only a stranger with no
        // manifest after it is one.
        if let Some(stranger) = store::foreign_entry(out).filter(|_| !Store::manifest_path(out).exists()) {
            let why =
                format!("exists and is not a sweep directory (no manifest.json, and it holds {stranger:?})");
            return Err(RunError::OutDir { dir: out.to_path_buf(), why }.into());
        }
    }
    let SweepPlan { spaces, points, jobs } = plan_with_progress(exec, sweep, &design, cancel, progress)?;
    let toml = resolved_toml(sweep, &design)?;
    let manifest = Manifest {
        format: MANIFEST_FORMAT,
        tool: format!("demsweep {}", env!("CARGO_PKG_VERSION")),
        name: sweep.file.name.clone(),
        parameters: sweep.names().iter().map(|s| s.to_string()).collect(),
        design,
        spaces,
        points,
        identity: exec.identity(),
    };
    // Created, or checked and extended, under the directory's lock: a second `sweep` on the
    // same new directory waits, then finds the manifest and shares the work.
    let store = Store::open(out);
    let in_force = store.update_manifest(|old| -> Result<Option<(Manifest, String)>> {
        let Some((old, old_toml)) = old else {
            return Ok(Some((manifest.clone(), toml.clone())));
        };
        check_extension(out, &old, &old_toml, &manifest, &toml)?;
        if old.points.len() > manifest.points.len() {
            // An adaptive sweep's later batches, which its design alone does not give.
            Ok(Some((Manifest { design: manifest.design.clone(), ..old }, toml.clone())))
        } else {
            Ok(Some((manifest.clone(), toml.clone())))
        }
    })?;
    let manifest = in_force.map_or(manifest, |(m, _)| m);
    crate::sys::process::on_interrupt_say(continue_with(out));
    Ok((store, manifest, jobs))
}

/// What to do after an interrupt that cut a sweep in `dir` short.
fn continue_with(dir: &Path) -> String {
    format!("every finished run is kept; continue with `sweep resume {}`", crate::sys::shell::quote_path(dir))
}

/// `sweep resume DIR`: re-prepare the manifest's points, refuse if their decks changed (the
/// engine, the template or the sweep file; unless `--force`), and run what is not finished.
pub fn resume<E: Executor>(
    dir: &Path,
    exec: &E,
    opts: &RunOptions,
    hook: &mut dyn SpaceHook,
    cancel: &CancelToken,
) -> Result<Summary> {
    resume_share(dir, exec, opts, None, hook, cancel)
}

/// Which unfinished points a process runs, and in what order: given their indices in manifest
/// order, the indices to queue. One array task's share of a sweep ([`crate::run::cluster`]).
pub type Order<'a> = &'a dyn Fn(&[usize]) -> Vec<usize>;

/// [`resume`] of the unfinished points `order` picks, in its order (all, in manifest order,
/// without one).
pub fn resume_share<E: Executor>(
    dir: &Path,
    exec: &E,
    opts: &RunOptions,
    order: Option<Order>,
    hook: &mut dyn SpaceHook,
    cancel: &CancelToken,
) -> Result<Summary> {
    let (mut manifest, toml) = Store::read_manifest(dir)?;
    crate::sys::process::on_interrupt_say(continue_with(dir));
    let sweep = Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    check_parameters(dir, &manifest, &sweep)?;
    Store::open(dir).check_joblog()?;
    // A directory that cannot be written is said so before anything is looked at.
    Store::open(dir).check_writable()?;
    let jobs: Vec<E::Job> = manifest
        .points
        .par_iter()
        .map(|p| {
            if cancel.is_cancelled() {
                Err(Error::Interrupted)
            } else {
                exec.prepare_seeded(&p.values, p.seed)
            }
        })
        .collect::<Result<_>>()?;
    let changed = manifest.points.iter().zip(&jobs).filter(|(p, j)| exec.hash(j) != p.hash).count();
    if changed > 0 {
        refuse_swapped(dir, &manifest, &jobs.iter().map(|j| exec.hash(j)).collect::<Vec<_>>())?;
    }
    Store::open(dir).check_pairing(&manifest)?;
    let identity = exec.identity();
    let diff = identity_diff(&manifest.identity, &identity);
    if !opts.force && changed > 0 {
        refuse_edited_sweep_toml(dir, &toml, changed, manifest.points.len())?;
    }
    // A point's hash is its deck's, mesh's and engine's: when every point hashes as before, a
    // changed template (a comment, a reordered block) or mesh version ran nothing differently,
    // and the directory takes the new identity below.
    if !opts.force && changed > 0 {
        let what = if diff.is_empty() {
            format!("{changed} of {} decks render differently", manifest.points.len())
        } else {
            format!("{}; {changed} of {} decks render differently", diff.join("; "), manifest.points.len())
        };
        let why = format!(
            "the engine or templates changed since the sweep started ({what}); \
             `--force` re-runs the changed points with the new ones"
        );
        return Err(RunError::Dir { path: dir.to_path_buf(), why }.into());
    }
    let store = Store::open(dir);
    // The screen is decided again from each point (a pure function of the point and the
    // settings); a directory written before the screen gains it here.
    let reclosed = manifest
        .points
        .iter()
        .zip(&jobs)
        .filter(|(p, j)| p.closed != (sweep.file.run.screen && exec.closed(j)))
        .count();
    if changed > 0 || !diff.is_empty() || reclosed > 0 {
        manifest.identity = identity;
        for (p, j) in manifest.points.iter_mut().zip(&jobs) {
            p.hash = exec.hash(j).to_string();
            p.closed = sweep.file.run.screen && exec.closed(j);
        }
        store.write_manifest(&toml, &manifest)?;
    }
    execute(&store, &manifest, exec, jobs, &sweep, opts, order, hook, cancel)
}

/// Refuse to resume when `DIR/sweep.toml` was edited since the manifest was written in a way
/// that changes the points' decks, naming the keys.
fn refuse_edited_sweep_toml(dir: &Path, toml: &str, changed: usize, points: usize) -> Result<()> {
    let edits = Store::sweep_toml_changes(dir, toml);
    if edits.is_empty() {
        return Ok(());
    }
    let why = format!(
        "{}: edited since the sweep started, so {changed} of {points} points render differently; \
         restore it, or `--force` re-runs the changed points with the new value",
        edits.join("; ")
    );
    Err(RunError::Dir { path: dir.join("sweep.toml"), why }.into())
}

/// Refuse a manifest whose hashes are those its points render to, but paired with the wrong
/// points: an edit (two hashes swapped), not a changed engine or template, which `--force`
/// must not paper over.
fn refuse_swapped(dir: &Path, manifest: &Manifest, rendered: &[&str]) -> Result<()> {
    let mut theirs: Vec<&str> = manifest.points.iter().map(|p| p.hash.as_str()).collect();
    let mut ours = rendered.to_vec();
    theirs.sort_unstable();
    ours.sort_unstable();
    if theirs != ours {
        return Ok(());
    }
    let wrong: Vec<usize> =
        manifest.points.iter().zip(rendered).filter(|(p, h)| p.hash != **h).map(|(p, _)| p.index).collect();
    let pair = match wrong.as_slice() {
        [i, j] => format!("points {i} and {j}"),
        w => format!("{} points (first {:?})", w.len(), &w[..w.len().min(4)]),
    };
    let why = format!(
        "the hashes of {pair} are swapped: each point names the run another point renders to; \
         the manifest was edited or is damaged (swap them back, or start the sweep in a new directory)"
    );
    Err(RunError::Dir { path: Store::manifest_path(dir), why }.into())
}

/// Run the unfinished points of a manifest.
///
/// The screen ([`crate::run::screen`]): the unfinished points of its verification sample go first in
/// the queue, whatever `order` picks (an array task waits for them before it trusts the screen);
/// the other closed points are held back. Once the sample has run with MFR = 0 they are screened;
/// if any closed point's run contradicts the screen, they run after the rest.
#[expect(clippy::too_many_arguments, reason = "one call site each in start and resume_share")]
fn execute<E: Executor>(
    store: &Store,
    manifest: &Manifest,
    exec: &E,
    jobs: Vec<E::Job>,
    sweep: &Sweep,
    opts: &RunOptions,
    order: Option<Order>,
    hook: &mut dyn SpaceHook,
    cancel: &CancelToken,
) -> Result<Summary> {
    store.check_run_dirs(manifest)?;
    // Leftovers of atomic writes cut off by a kill or a full disk.
    store.remove_stale_temporaries()?;
    let screen = Screen::of(sweep);
    let sample = screen.sample(&manifest.points);
    let mut status = Vec::with_capacity(manifest.points.len());
    let mut recovered: Vec<(String, Option<f64>)> = Vec::new();
    let mut queued: BTreeMap<usize, E::Job> = BTreeMap::new();
    let mut held: BTreeMap<usize, E::Job> = BTreeMap::new();
    let mut not_theirs = std::collections::HashMap::new();
    for (p, job) in manifest.points.iter().zip(jobs) {
        let state = store.point_state(manifest, p);
        if let RunState::Damaged { file, reason } = &state {
            eprintln!("warning: {}: {reason}; point {} runs again", file.display(), p.index);
            // A readable result of another point: the pool must not take it for this one's.
            if let (Some(RunState::Done(_)), Some(t)) = (store.finished(&p.hash), store.outcome_time(&p.hash))
            {
                not_theirs.insert(p.hash.clone(), t);
            }
        }
        if matches!(state, RunState::Done(_) | RunState::Failed(_)) {
            // A process killed between its outcome and its joblog line left its claim, or
            // none: if no live process holds the run, the line it owed is written below.
            if let store::holders::FinishedHolder::Nobody { claimed_at } = store.free_finished(&p.hash)? {
                recovered.push((p.hash.clone(), claimed_at));
            }
        }
        let s = match state {
            RunState::Done(r) => PointStatus::Done(r),
            RunState::Failed(f) => {
                if opts.retry_failed {
                    queued.insert(p.index, job);
                }
                PointStatus::Failed(f)
            }
            _ => {
                if p.closed && !sample.contains(&p.index) {
                    held.insert(p.index, job);
                } else {
                    queued.insert(p.index, job);
                }
                PointStatus::Pending
            }
        };
        status.push(s);
    }
    // Closed points about to run (again): their present status is no evidence.
    let awaiting: BTreeSet<usize> = queued.keys().copied().filter(|&i| manifest.points[i].closed).collect();
    let columns = crate::store::Columns {
        fixed: crate::point::fixed_columns(sweep),
        layout: crate::scenes::of(&sweep.file.scene).map_err(crate::point::PointError::Layout)?,
    };
    let mut rep = Reporter::new(
        store,
        manifest,
        status,
        opts.progress,
        hook,
        screen,
        sample.clone(),
        awaiting,
        columns,
    )?;
    if rep.verdict == Verdict::Refuted {
        queued.append(&mut held);
    }
    if !recovered.is_empty() {
        rep.log_recovered(store, &recovered)?;
    }
    let pick = |all: &mut BTreeMap<usize, E::Job>, sample_first: bool| -> Vec<E::Job> {
        let (first, rest): (Vec<usize>, Vec<usize>) =
            all.keys().copied().partition(|i| sample_first && sample.contains(i));
        let rest = match order {
            Some(order) => order(&rest),
            None => rest,
        };
        first.into_iter().chain(rest).filter_map(|i| all.remove(&i)).collect()
    };
    let mut queue = pick(&mut queued, true);
    if rep.fire_spaces() == Flow::Drain {
        queue.clear();
    }
    let popts = PoolOptions {
        slots: opts.jobs.max(1),
        retries: sweep.file.run.retries,
        retry_failed_before: if opts.retry_failed { Some(store.retry_round()?) } else { None },
        not_theirs,
    };
    let joblog = || -> Result<store::Joblog> {
        Ok(store.joblog()?.with_indices(manifest.points.iter().map(|p| (p.hash.clone(), p.index)).collect()))
    };
    pool::run(exec, store, joblog()?, queue, &popts, cancel, |e| rep.event(e));
    // Refuted while the pool ran: the held-back closed points run now, for real.
    let go_on = !cancel.is_cancelled() && rep.stopped_after.is_none() && rep.errors.is_empty();
    if go_on && rep.verdict == Verdict::Refuted && !held.is_empty() {
        let queue = pick(&mut held, false);
        pool::run(exec, store, joblog()?, queue, &popts, cancel, |e| rep.event(e));
    }
    rep.finish(cancel.is_cancelled())
}
