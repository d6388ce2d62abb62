//! The sweep drivers: `sweep lattice`, `sweep lds`, `sweep resume` and `sweep status`.
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

pub mod cluster;
pub mod pool;
pub mod progress;
pub mod screen;
pub mod standin;

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::design::{halton::halton, lattice::lattice};
use crate::error::{Error, Result};
use crate::outcome::RunOutcome;
use crate::point::{self, PointContext};
use crate::run::pool::{Event, Executor, Flow, PoolOptions};
use crate::run::progress::{Counts, Progress, ProgressMode};
use crate::run::screen::{Screen, ScreenReport, Verdict};
use crate::store::{
    self, DesignRecord, Manifest, PointRecord, PointStatus, RunState, SpaceRecord, Store, MANIFEST_FORMAT,
};
use crate::sweep::Sweep;
use crate::sys::process::CancelToken;

/// Most points one design may have.
pub const MAX_POINTS: usize = 1_000_000;
/// Least time between two rewrites of results.csv while points finish.
const RESULTS_EVERY: std::time::Duration = std::time::Duration::from_secs(1);

/// The real executor: one LIGGGHTS run per point through [`crate::point`].
///
/// A job keeps only the point's values and hash; the deck is rendered again when the run starts
/// (rendering is cheap and deterministic), so a 10,000-point sweep does not hold 10,000 decks.
pub struct PointExecutor {
    ctx: PointContext,
}

/// A point to run for real.
pub struct PointJob {
    values: Vec<f64>,
    hash: String,
    /// Nothing can pass under the blade here ([`crate::scene::Scene::nothing_passes`]).
    closed: bool,
}

impl PointExecutor {
    /// Find LIGGGHTS and load the template of `sweep`.
    pub fn new(sweep: Sweep) -> Result<PointExecutor> {
        Ok(PointExecutor { ctx: PointContext::new(sweep)? })
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

    fn prepare(&self, swept: &[f64]) -> Result<PointJob> {
        let p = point::prepare(&self.ctx, swept)?;
        Ok(PointJob { values: swept.to_vec(), hash: p.hash, closed: p.scene.nothing_passes() })
    }

    fn hash<'a>(&self, job: &'a PointJob) -> &'a str {
        &job.hash
    }

    fn closed(&self, job: &PointJob) -> bool {
        job.closed
    }

    fn execute(&self, job: &PointJob, run_dir: &Path, cancel: &CancelToken) -> RunOutcome {
        match point::prepare(&self.ctx, &job.values) {
            Ok(p) if p.hash == job.hash => point::execute(&self.ctx, &p, run_dir, cancel),
            // Prepared once already, so neither can happen short of a bug; fail the run loudly.
            Ok(p) => point_failure(job, run_dir, format!("deck hash changed on re-render: {}", p.hash)),
            Err(e) => point_failure(job, run_dir, format!("cannot render the deck: {e}")),
        }
    }
}

fn point_failure(job: &PointJob, run_dir: &Path, reason: String) -> RunOutcome {
    let f = crate::outcome::RunFailure {
        format: crate::outcome::RESULT_FORMAT,
        hash: job.hash.clone(),
        class: crate::outcome::FailureClass::CouldNotStart,
        reason,
        log_tail: String::new(),
        wall_time: 0.0,
        measured: None,
    };
    let _ = crate::outcome::write_json_atomic(&run_dir.join(point::FAILURE), &f);
    RunOutcome::Failed(f)
}

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

/// Called after each nested space has all its points finished, in space order, with that
/// space's points. Convergence checking (a later issue) implements it; `Flow::Drain` stops
/// starting new runs.
pub trait SpaceHook {
    fn space_complete(&mut self, space: &SpaceRecord, points: &[(&PointRecord, &PointStatus)]) -> Flow;
}

/// The hook that never stops a sweep.
pub struct RunAll;

impl SpaceHook for RunAll {
    fn space_complete(&mut self, _: &SpaceRecord, _: &[(&PointRecord, &PointStatus)]) -> Flow {
        Flow::Continue
    }
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
    /// 130 interrupted, 1 when runs failed, else 0 (DESIGN §4).
    pub fn exit_code(&self) -> i32 {
        use crate::error::exit;
        if self.interrupted {
            // Death by signal n is 128 + n; a cancel without a signal reads as Ctrl-C.
            crate::sys::process::interrupt_signal().map_or(exit::INTERRUPTED, |s| 128 + s)
        } else if self.failed > 0 {
            exit::RUNS_FAILED
        } else {
            exit::SUCCESS
        }
    }
}

/// The default sweep directory, `runs/<sweep name>`.
pub fn default_out(sweep: &Sweep) -> PathBuf {
    Path::new("runs").join(&sweep.file.name)
}

/// A design laid out for running.
pub struct Plan<J> {
    pub spaces: Vec<SpaceRecord>,
    /// Distinct points (by hash), in order of first appearance.
    pub points: Vec<PointRecord>,
    /// The prepared job of each point.
    pub jobs: Vec<J>,
}

/// The spaces and distinct points of a design, with the prepared job of each point.
///
/// Stops with [`Error::Interrupted`] (nothing written) when `cancel` fires.
pub fn plan<E: Executor>(
    exec: &E,
    sweep: &Sweep,
    design: &DesignRecord,
    cancel: &CancelToken,
) -> Result<Plan<E::Job>> {
    plan_with_progress(exec, sweep, design, cancel, ProgressMode::Quiet)
}

/// Time planning may take before it says how far it is.
const PLAN_QUIET_FOR: std::time::Duration = std::time::Duration::from_secs(1);

/// Prepare (render and hash) every point on all cores; unless `progress` is quiet, say how
/// many are done once this takes longer than [`PLAN_QUIET_FOR`], then every
/// [`crate::run::progress::LINE_EVERY`] (a 10⁶-point lattice takes minutes).
fn prepare_all<E: Executor>(
    exec: &E,
    values: &[Vec<f64>],
    cancel: &CancelToken,
    progress: ProgressMode,
) -> Result<Vec<E::Job>> {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let done = AtomicUsize::new(0);
    let over = AtomicBool::new(false);
    let total = values.len();
    std::thread::scope(|scope| {
        if progress != ProgressMode::Quiet {
            scope.spawn(|| {
                let start = Instant::now();
                let mut next = PLAN_QUIET_FOR;
                while !over.load(Ordering::SeqCst) {
                    std::thread::sleep(std::time::Duration::from_millis(50));
                    if start.elapsed() >= next && !over.load(Ordering::SeqCst) {
                        eprintln!(
                            "sweep: planning: {} of {total} decks rendered and hashed",
                            done.load(Ordering::Relaxed)
                        );
                        next = start.elapsed() + crate::run::progress::LINE_EVERY;
                    }
                }
            });
        }
        let jobs = values
            .par_iter()
            .map(|v| {
                if cancel.is_cancelled() {
                    return Err(Error::Interrupted);
                }
                let job = exec.prepare(v);
                done.fetch_add(1, Ordering::Relaxed);
                job
            })
            .collect::<Result<Vec<_>>>();
        over.store(true, Ordering::SeqCst);
        jobs
    })
}

/// [`plan`], showing progress on stderr as `progress` says.
pub fn plan_with_progress<E: Executor>(
    exec: &E,
    sweep: &Sweep,
    design: &DesignRecord,
    cancel: &CancelToken,
    progress: ProgressMode,
) -> Result<Plan<E::Job>> {
    let dim = sweep.dim();
    // Each space as a list of unit points.
    let spaces: Vec<(String, Vec<Vec<f64>>)> = match design {
        DesignRecord::Lattice { levels } => {
            let mut out = Vec::new();
            for &l in levels {
                if l < 2 {
                    return Err(Error::input(format!(
                        "lattice level {l}: expected at least 2 values per dimension"
                    )));
                }
                let n = l.checked_pow(dim as u32).filter(|&n| n <= MAX_POINTS);
                if n.is_none() {
                    return Err(Error::input(format!(
                        "lattice level {l} in {dim} dimensions: more than {MAX_POINTS} points"
                    )));
                }
                out.push((format!("lattice {l}"), lattice(dim, l)));
            }
            out
        }
        DesignRecord::Lds { step, max, scrambling, seed } => {
            if *step == 0 || *max == 0 || *max > MAX_POINTS || max < step {
                return Err(Error::input(format!(
                    "lds step {step}, max {max}: expected 1 ≤ step ≤ max ≤ {MAX_POINTS}"
                )));
            }
            let all = halton(dim, *max, *scrambling, *seed);
            let mut ends: Vec<usize> = (1..).map(|k| k * step).take_while(|&n| n < *max).collect();
            ends.push(*max);
            ends.into_iter().map(|n| (format!("lds {n}"), all[..n].to_vec())).collect()
        }
    };
    // Distinct values first (LDS prefixes and nested lattices repeat points), each prepared
    // once, on every core: rendering and hashing 10,000 decks takes tens of seconds on one.
    let mut distinct: Vec<Vec<f64>> = Vec::new();
    let mut by_bits: HashMap<Vec<u64>, usize> = HashMap::new();
    let space_values: Vec<(String, Vec<usize>)> = spaces
        .into_iter()
        .map(|(label, unit)| {
            let members = unit
                .iter()
                .map(|u| {
                    let values = crate::sweep::space::scale_point(sweep, u);
                    let bits = values.iter().map(|v| v.to_bits()).collect();
                    *by_bits.entry(bits).or_insert_with(|| {
                        distinct.push(values);
                        distinct.len() - 1
                    })
                })
                .collect();
            (label, members)
        })
        .collect();
    let prepared = prepare_all(exec, &distinct, cancel, progress)?;
    // Then distinct runs: two values may render the same deck.
    let mut points: Vec<PointRecord> = Vec::new();
    let mut jobs = Vec::new();
    let mut by_hash: HashMap<String, usize> = HashMap::new();
    let mut point_of_value = Vec::with_capacity(distinct.len());
    for (values, job) in distinct.into_iter().zip(prepared) {
        let hash = exec.hash(&job).to_string();
        let closed = sweep.file.run.screen && exec.closed(&job);
        let index = *by_hash.entry(hash.clone()).or_insert_with(|| {
            points.push(PointRecord { index: points.len(), values, hash, closed });
            jobs.push(job);
            points.len() - 1
        });
        point_of_value.push(index);
    }
    let records = space_values
        .into_iter()
        .map(|(label, members)| SpaceRecord {
            label,
            points: members.into_iter().map(|v| point_of_value[v]).collect(),
        })
        .collect();
    Ok(Plan { spaces: records, points, jobs })
}

/// The sweep file as resolved for `DIR/sweep.toml`: defaults filled in, the design actually run,
/// and the template path made absolute (the directory may be resumed from anywhere).
pub fn resolved_toml(sweep: &Sweep, design: &DesignRecord) -> Result<String> {
    let mut f = sweep.file.clone();
    if let Some(t) = sweep.template_path() {
        f.scene.template = Some(std::path::absolute(&t).unwrap_or(t));
    }
    match design {
        DesignRecord::Lattice { levels } => f.design.lattice_levels = levels.clone(),
        DesignRecord::Lds { step, max, scrambling, seed } => {
            f.design.lds.step = *step;
            f.design.lds.max = *max;
            f.design.lds.scrambling = *scrambling;
            f.design.lds.seed = *seed;
        }
    }
    let body = toml::to_string(&f).map_err(|e| Error::Internal(format!("resolved sweep: {e}")))?;
    Ok(format!(
        "# The sweep as resolved by demsweep {} (resolved-sweep format {}).\n{body}",
        env!("CARGO_PKG_VERSION"),
        crate::sweep::SWEEP_FORMAT
    ))
}

/// `sweep lattice` / `sweep lds`: create (or extend) the sweep directory `out` and run it.
pub fn start<E: Executor>(
    sweep: &Sweep,
    design: DesignRecord,
    out: &Path,
    exec: &E,
    opts: &RunOptions,
    hook: &mut dyn SpaceHook,
    cancel: &CancelToken,
) -> Result<Summary> {
    check_out_dir(out)?;
    if !Store::manifest_path(out).exists() {
        if let Some(stranger) = store::foreign_entry(out) {
            return Err(Error::input(format!(
                "{}: exists and is not a sweep directory (no manifest.json, and it holds {stranger:?}); \
                 choose another --out",
                out.display()
            )));
        }
    }
    let Plan { spaces, points, jobs } = plan_with_progress(exec, sweep, &design, cancel, opts.progress)?;
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
    store.write_manifest_checked(&toml, &manifest, |old| match old {
        Some((old, old_toml)) => check_extension(out, &old, &old_toml, &manifest, &toml),
        None => Ok(()),
    })?;
    execute(&store, &manifest, exec, jobs, sweep, opts, None, hook, cancel)
}

/// Whether `out` can be a sweep directory: an existing directory we may write in, or a path
/// whose nearest existing ancestor is one. Checked before anything is written or run; the
/// message names the path and what is wrong with it.
pub fn check_out_dir(out: &Path) -> Result<()> {
    let d = out.display();
    let bad = |what: String| Err(Error::input(format!("{d}: {what}; choose another --out")));
    match std::fs::metadata(out) {
        Ok(m) if !m.is_dir() => bad("exists and is not a directory".into()),
        Ok(_) => match writable(out) {
            Ok(()) => Ok(()),
            Err(e) => bad(format!("cannot write in it ({})", plain_io(&e))),
        },
        Err(e) if matches!(e.kind(), std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory) => {
            let abs = std::path::absolute(out).map_err(|e| Error::input(format!("{d}: {e}")))?;
            let mut up = abs.parent();
            while let Some(p) = up {
                match std::fs::metadata(p) {
                    Ok(m) if m.is_dir() => {
                        return match writable(p) {
                            Ok(()) => Ok(()),
                            Err(e) => bad(format!(
                                "cannot create it: {} is not writable ({})",
                                p.display(),
                                plain_io(&e)
                            )),
                        }
                    }
                    Ok(_) => return bad(format!("cannot create it: {} is not a directory", p.display())),
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => up = p.parent(),
                    Err(e) => return bad(format!("cannot create it: {}: {}", p.display(), plain_io(&e))),
                }
            }
            Ok(())
        }
        Err(e) => bad(plain_io(&e)),
    }
}

/// `access(2)` for writing and entering a directory (honours read-only mounts and, for root,
/// nothing else, exactly as a later `mkdir` would).
fn writable(dir: &Path) -> std::io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).map_err(std::io::Error::other)?;
    // SAFETY: access(2) on a NUL-terminated path we own.
    if unsafe { libc::access(c.as_ptr(), libc::W_OK | libc::X_OK) } == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// "permission denied" rather than "Permission denied (os error 13)".
fn plain_io(e: &std::io::Error) -> String {
    let s = e.to_string();
    let s = s.split(" (os error").next().unwrap_or(&s).to_string();
    let mut c = s.chars();
    c.next().map(|f| f.to_lowercase().chain(c).collect()).unwrap_or(s)
}

/// An existing directory may be run again with the same sweep, or extended: the same design
/// kind and sweep apart from the design, the same identity, and its points a prefix of ours.
fn check_extension(dir: &Path, old: &Manifest, old_toml: &str, new: &Manifest, new_toml: &str) -> Result<()> {
    let d = dir.display();
    // The design may grow; the convergence rule may change (it decides when to stop, not what
    // a run gives).
    // Compared with defaults filled in, so that a key added since (such as `run.screen`) does
    // not make an older directory's sweep file look different.
    let without_design = |t: &str| -> Option<toml::Table> {
        let file: crate::sweep::SweepFile = toml::from_str(t).ok()?;
        let mut v = toml::Table::try_from(&file).ok()?;
        v.remove("design");
        v.remove("convergence");
        Some(v)
    };
    if std::mem::discriminant(&old.design) != std::mem::discriminant(&new.design) {
        return Err(Error::input(format!(
            "{d}: holds a {} sweep, not a {} one; choose another --out",
            design_kind(&old.design),
            design_kind(&new.design)
        )));
    }
    if without_design(old_toml) != without_design(new_toml) {
        return Err(Error::input(format!(
            "{d}: holds sweep `{}` made from a different sweep file (compare {d}/sweep.toml); \
             choose another --out",
            old.name
        )));
    }
    let diff = identity_diff(&old.identity, &new.identity);
    if !diff.is_empty() {
        return Err(Error::input(format!(
            "{d}: the engine or templates changed since it was made ({}); choose another --out, \
             or `sweep resume {d} --force` to re-run its points",
            diff.join("; ")
        )));
    }
    let prefix = old.points.len() <= new.points.len()
        && old.points.iter().zip(&new.points).all(|(a, b)| a.hash == b.hash);
    if !prefix {
        return Err(Error::input(format!(
            "{d}: its {} points are not the first points of this design ({}); a design can \
             only be extended (larger --max, more levels); choose another --out",
            old.points.len(),
            design_label(&new.design)
        )));
    }
    Ok(())
}

fn design_kind(d: &DesignRecord) -> &'static str {
    match d {
        DesignRecord::Lattice { .. } => "lattice",
        DesignRecord::Lds { .. } => "lds",
    }
}

fn design_label(d: &DesignRecord) -> String {
    match d {
        DesignRecord::Lattice { levels } => {
            format!("lattice levels {}", levels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(","))
        }
        DesignRecord::Lds { step, max, .. } => format!("lds step {step}, max {max}"),
    }
}

/// Identity keys recorded for the reader but not compared: where the engine was found (the
/// same binary through a symlink or another PATH is the same engine; its content and version
/// are what identify it).
const NOT_COMPARED: &[&str] = &["engine_path"];

/// `key: old → new` for every leaf that differs between two identity records.
pub fn identity_diff(old: &serde_json::Value, new: &serde_json::Value) -> Vec<String> {
    fn walk(path: &str, a: &serde_json::Value, b: &serde_json::Value, out: &mut Vec<String>) {
        match (a, b) {
            (serde_json::Value::Object(x), serde_json::Value::Object(y)) => {
                let keys: std::collections::BTreeSet<&String> = x.keys().chain(y.keys()).collect();
                let null = serde_json::Value::Null;
                for k in keys.into_iter().filter(|k| !NOT_COMPARED.contains(&k.as_str())) {
                    let p = if path.is_empty() { k.clone() } else { format!("{path}.{k}") };
                    walk(&p, x.get(k).unwrap_or(&null), y.get(k).unwrap_or(&null), out);
                }
            }
            _ if a != b => out.push(format!("{path}: {a} → {b}")),
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk("", old, new, &mut out);
    out
}

/// The `min_points` a run of `design` into `out` judges convergence from.
///
/// Extending an existing directory (a larger `--max`, more levels) is asked for on purpose, so
/// no space it already had may stop the extension: judging starts past its largest space. Running
/// the same design again keeps the directory's own `min_points`. A new directory (or one that is
/// not a sweep: `start` refuses it) uses the sweep file's.
pub fn judge_from(out: &Path, sweep: &Sweep, design: &DesignRecord) -> Result<usize> {
    let own = sweep.file.convergence.min_points;
    let Ok((old, old_toml)) = Store::read_manifest(out) else {
        return Ok(own);
    };
    let old_min =
        Sweep::parse(&old_toml, &out.join("sweep.toml")).map_or(0, |s| s.file.convergence.min_points);
    let extends = match (&old.design, design) {
        (DesignRecord::Lds { max: a, .. }, DesignRecord::Lds { max: b, .. }) => b > a,
        (DesignRecord::Lattice { levels: a }, DesignRecord::Lattice { levels: b }) => {
            b.len() > a.len() && b.starts_with(a)
        }
        _ => false,
    };
    let extent = old.spaces.iter().map(|s| s.points.len()).max().unwrap_or(0);
    Ok(if extends { own.max(extent + 1) } else { own.max(old_min) })
}

/// Read the sweep of an existing directory (its resolved `sweep.toml`), checked against its
/// manifest.
pub fn load_dir_sweep(dir: &Path) -> Result<Sweep> {
    let (manifest, text) = Store::read_manifest(dir)?;
    let sweep = Sweep::parse(&text, &dir.join("sweep.toml"))?;
    check_parameters(dir, &manifest, &sweep)?;
    Ok(sweep)
}

/// The manifest's `parameters` are the swept parameters of the directory's `sweep.toml`.
fn check_parameters(dir: &Path, manifest: &Manifest, sweep: &Sweep) -> Result<()> {
    if sweep.names() != manifest.parameters {
        return Err(Error::input(format!(
            "{}: parameters [{}] are not the swept parameters of {} [{}]; the manifest or the \
             sweep file was edited",
            Store::manifest_path(dir).display(),
            manifest.parameters.join(", "),
            dir.join("sweep.toml").display(),
            sweep.names().join(", ")
        )));
    }
    Ok(())
}

/// `sweep resume DIR`: re-prepare the manifest's points, refuse if the identity or the decks
/// changed (unless `--force`), and run what is not finished.
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
    let sweep = Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    check_parameters(dir, &manifest, &sweep)?;
    let jobs: Vec<E::Job> = manifest
        .points
        .par_iter()
        .map(|p| if cancel.is_cancelled() { Err(Error::Interrupted) } else { exec.prepare(&p.values) })
        .collect::<Result<_>>()?;
    let changed = manifest.points.iter().zip(&jobs).filter(|(p, j)| exec.hash(j) != p.hash).count();
    if changed > 0 {
        refuse_swapped(dir, &manifest, &jobs.iter().map(|j| exec.hash(j)).collect::<Vec<_>>())?;
    }
    Store::open(dir).check_pairing(&manifest)?;
    let identity = exec.identity();
    let diff = identity_diff(&manifest.identity, &identity);
    if !opts.force && (!diff.is_empty() || changed > 0) {
        let what = if diff.is_empty() {
            format!("{changed} of {} decks render differently", manifest.points.len())
        } else {
            diff.join("; ")
        };
        return Err(Error::input(format!(
            "{}: the engine or templates changed since the sweep started ({what}); \
             `--force` re-runs the changed points with the new ones",
            dir.display()
        )));
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
    Err(Error::input(format!(
        "{}: the hashes of {pair} are swapped: each point names the run another point renders to; \
         the manifest was edited or is damaged (swap them back, or start the sweep in a new directory)",
        Store::manifest_path(dir).display()
    )))
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
    // Leftovers of atomic writes cut off by a kill or a full disk.
    store.remove_stale_temporaries()?;
    let screen = Screen::of(sweep);
    let sample = screen.sample(&manifest.points);
    let mut status = Vec::with_capacity(manifest.points.len());
    let mut recovered: Vec<(String, store::ClaimInfo)> = Vec::new();
    let mut queued: BTreeMap<usize, E::Job> = BTreeMap::new();
    let mut held: BTreeMap<usize, E::Job> = BTreeMap::new();
    for (p, job) in manifest.points.iter().zip(jobs) {
        let state = store.point_state(manifest, p);
        if let RunState::Damaged { file, reason } = &state {
            eprintln!("warning: {}: {reason}; point {} runs again", file.display(), p.index);
        }
        if matches!(state, RunState::Done(_) | RunState::Failed(_)) {
            // Killed between its outcome and its joblog line: the claim is still there.
            if let Some(c) = store.remove_dead_claim_of_finished(&p.hash)? {
                recovered.push((p.hash.clone(), c));
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
    let mut rep =
        Reporter::new(store, manifest, status, opts.progress, hook, screen, sample.clone(), awaiting)?;
    if !recovered.is_empty() {
        rep.log_recovered(store, &recovered)?;
    }
    if rep.verdict == Verdict::Refuted {
        queued.append(&mut held);
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
    };
    pool::run(exec, store, queue, &popts, cancel, |e| rep.event(e));
    // Refuted while the pool ran: the held-back closed points run now, for real.
    let go_on = !cancel.is_cancelled() && rep.stopped_after.is_none() && rep.errors.is_empty();
    if go_on && rep.verdict == Verdict::Refuted && !held.is_empty() {
        let queue = pick(&mut held, false);
        pool::run(exec, store, queue, &popts, cancel, |e| rep.event(e));
    }
    rep.finish(cancel.is_cancelled())
}

/// The one consumer of pool events: joblog, results.csv, progress, spaces, the screen's verdict.
struct Reporter<'a> {
    store: &'a Store,
    manifest: &'a Manifest,
    status: Vec<PointStatus>,
    by_hash: BTreeMap<&'a str, usize>,
    /// Unfinished points per space, and the spaces each point is in.
    unfinished: Vec<usize>,
    member_of: Vec<Vec<usize>>,
    next_space: usize,
    hook: &'a mut dyn SpaceHook,
    stopped_after: Option<String>,
    joblog: store::Joblog,
    counts: Counts,
    ran: usize,
    progress: Progress,
    results_dirty: bool,
    results_written: Instant,
    errors: Vec<String>,
    screen: Screen,
    /// The screen's verification sample (point indices).
    sample: BTreeSet<usize>,
    /// Closed points queued to run (again) and not finished yet.
    awaiting: BTreeSet<usize>,
    verdict: Verdict,
}

impl<'a> Reporter<'a> {
    /// Write the joblog line of each finished run whose process was killed before writing it
    /// (its dead claim was still in the run directory), unless a line is there.
    fn log_recovered(&mut self, store: &Store, recovered: &[(String, store::ClaimInfo)]) -> Result<()> {
        let logged: BTreeSet<String> = store::read_joblog(store.dir())?
            .into_iter()
            .filter(|l| l.status == "done" || l.status == "failed")
            .map(|l| l.hash)
            .collect();
        for (hash, claim) in recovered.iter().filter(|(h, _)| !logged.contains(h)) {
            let (status, class, runtime_s) = match store.finished(hash) {
                Some(RunState::Done(r)) => ("done", None, r.wall_time),
                Some(RunState::Failed(f)) => ("failed", Some(f.class.as_str()), f.wall_time),
                _ => continue,
            };
            let start = std::time::UNIX_EPOCH + std::time::Duration::from_secs_f64(claim.claimed_at.max(0.0));
            self.joblog.append(&store::AttemptRecord {
                hash: hash.clone(),
                start,
                runtime_s,
                status,
                class,
            })?;
        }
        Ok(())
    }

    #[expect(clippy::too_many_arguments, reason = "the reporter's whole starting state, one call site")]
    fn new(
        store: &'a Store,
        manifest: &'a Manifest,
        status: Vec<PointStatus>,
        mode: ProgressMode,
        hook: &'a mut dyn SpaceHook,
        screen: Screen,
        sample: BTreeSet<usize>,
        awaiting: BTreeSet<usize>,
    ) -> Result<Reporter<'a>> {
        let mut member_of = vec![Vec::new(); manifest.points.len()];
        for (k, s) in manifest.spaces.iter().enumerate() {
            for &i in &s.points {
                member_of[i].push(k);
            }
        }
        let done = status.iter().filter(|s| matches!(s, PointStatus::Done(_))).count();
        let failed = status.iter().filter(|s| matches!(s, PointStatus::Failed(_))).count();
        let counts =
            Counts { total: status.len(), done, failed, running: 0, reused: done + failed, screened: 0 };
        let mut rep = Reporter {
            store,
            manifest,
            by_hash: manifest.points.iter().map(|p| (p.hash.as_str(), p.index)).collect(),
            status,
            unfinished: vec![0; manifest.spaces.len()],
            member_of,
            next_space: 0,
            hook,
            stopped_after: None,
            joblog: store.joblog()?,
            counts,
            ran: 0,
            progress: Progress::new(mode, manifest.points.len()),
            results_dirty: true,
            results_written: Instant::now(),
            errors: Vec::new(),
            screen,
            sample,
            awaiting,
            verdict: Verdict::Pending,
        };
        rep.judge_screen();
        for (k, s) in manifest.spaces.iter().enumerate() {
            rep.unfinished[k] = s.points.iter().filter(|&&i| !rep.status[i].is_finished()).count();
        }
        store::write_results(store.dir(), &manifest.parameters, &manifest.points, &rep.status, &rep.sample)?;
        Ok(rep)
    }

    /// Judge the screen while it is pending; once verified, screen the held-back closed points
    /// (they finish, as MFR = 0); once refuted, say so loudly (the driver runs them). Both
    /// verdicts are final for the session: after either no closed point's outcome is awaited.
    fn judge_screen(&mut self) {
        if self.verdict != Verdict::Pending {
            return;
        }
        let (verdict, refuted_by) =
            self.screen.judge(&self.manifest.points, &self.status, &self.sample, &self.awaiting);
        match verdict {
            Verdict::Verified if self.awaiting.is_empty() => {
                let before: Vec<bool> = self.status.iter().map(PointStatus::is_finished).collect();
                self.counts.screened = self.screen.apply(verdict, &self.manifest.points, &mut self.status);
                for (i, was) in before.into_iter().enumerate() {
                    if !was && self.status[i].is_finished() {
                        for &k in &self.member_of[i] {
                            self.unfinished[k] = self.unfinished[k].saturating_sub(1);
                        }
                    }
                }
                self.results_dirty = true;
                self.verdict = verdict;
            }
            // A closed point still queued may yet contradict it.
            Verdict::Verified | Verdict::Pending => {}
            Verdict::Refuted => {
                let held = (self.manifest.points.iter())
                    .filter(|p| p.closed && !self.awaiting.contains(&p.index))
                    .filter(|p| matches!(self.status[p.index], PointStatus::Pending))
                    .count();
                self.progress.warn(&format!(
                    "warning: SCREEN REFUTED: {}; it is not trusted in this sweep: the {held} closed \
                     point(s) it would skip run for real",
                    crate::run::screen::refutation(&refuted_by)
                ));
                self.verdict = verdict;
            }
            Verdict::Off | Verdict::NoneClosed => self.verdict = verdict,
        }
    }

    /// Call the hook for every space, in order, whose points have all finished.
    fn fire_spaces(&mut self) -> Flow {
        while self.stopped_after.is_none()
            && self.next_space < self.manifest.spaces.len()
            && self.unfinished[self.next_space] == 0
        {
            let space = &self.manifest.spaces[self.next_space];
            let rows: Vec<(&PointRecord, &PointStatus)> =
                space.points.iter().map(|&i| (&self.manifest.points[i], &self.status[i])).collect();
            if self.hook.space_complete(space, &rows) == Flow::Drain {
                self.stopped_after = Some(space.label.clone());
            }
            self.next_space += 1;
        }
        if self.stopped_after.is_some() {
            Flow::Drain
        } else {
            Flow::Continue
        }
    }

    fn event(&mut self, e: &Event) -> Flow {
        match e {
            Event::Started { .. } => {
                self.counts.running += 1;
                self.ran += 1;
            }
            Event::Attempt { record, .. } => {
                if let Err(err) = self.joblog.append(record) {
                    self.errors.push(err.to_string());
                }
            }
            Event::Finished { hash, outcome, ran } => {
                if *ran {
                    self.counts.running -= 1;
                }
                if let Some(&i) = self.by_hash.get(hash.as_str()) {
                    let new = match outcome {
                        RunOutcome::Done(r) => Some(PointStatus::Done(Box::new(r.clone()))),
                        RunOutcome::Failed(f) => Some(PointStatus::Failed(Box::new(f.clone()))),
                        RunOutcome::Cancelled => None,
                    };
                    if let Some(new) = new {
                        let was_finished = self.status[i].is_finished();
                        match &self.status[i] {
                            PointStatus::Done(_) => self.counts.done -= 1,
                            PointStatus::Failed(_) => self.counts.failed -= 1,
                            PointStatus::Screened => self.counts.screened -= 1,
                            PointStatus::Pending => {}
                        }
                        match &new {
                            PointStatus::Done(_) => self.counts.done += 1,
                            PointStatus::Failed(_) => self.counts.failed += 1,
                            PointStatus::Screened => self.counts.screened += 1,
                            PointStatus::Pending => {}
                        }
                        self.status[i] = new;
                        self.results_dirty = true;
                        if !was_finished {
                            for &k in &self.member_of[i] {
                                self.unfinished[k] -= 1;
                            }
                        }
                        if self.awaiting.remove(&i) || self.manifest.points[i].closed {
                            self.judge_screen();
                        }
                    }
                }
            }
            Event::StoreError { hash, error } => {
                self.errors.push(format!("{error} (run {})", &hash[..12.min(hash.len())]));
            }
            Event::Busy { .. } | Event::Tick => {}
        }
        self.progress.update(&self.counts);
        if self.results_dirty && self.results_written.elapsed() >= RESULTS_EVERY {
            self.write_results();
        }
        let flow = self.fire_spaces();
        // A write error of the sweep directory stops new starts: their outcomes could not be
        // kept either.
        if self.errors.is_empty() {
            flow
        } else {
            Flow::Drain
        }
    }

    fn write_results(&mut self) {
        match store::write_results(
            self.store.dir(),
            &self.manifest.parameters,
            &self.manifest.points,
            &self.status,
            &self.sample,
        ) {
            Ok(()) => {
                self.results_dirty = false;
                self.results_written = Instant::now();
            }
            Err(e) => self.errors.push(e.to_string()),
        }
    }

    fn finish(mut self, interrupted: bool) -> Result<Summary> {
        self.write_results();
        self.progress.finish(&self.counts);
        if let Some(e) = self.errors.first() {
            let more = match self.errors.len() {
                1 => String::new(),
                n => format!(" ({n} write errors in all)"),
            };
            return Err(Error::Internal(format!(
                "{e}{more}; started no run after it; once that is fixed, `sweep resume {}` finishes the sweep",
                self.store.dir().display()
            )));
        }
        let c = self.counts;
        let judged = self.screen.judge(&self.manifest.points, &self.status, &self.sample, &BTreeSet::new());
        let screen = self.screen.report(&self.manifest.points, &self.status, &self.sample, judged);
        Ok(Summary {
            dir: self.store.dir().to_path_buf(),
            points: c.total,
            done: c.done,
            failed: c.failed,
            screened: c.screened,
            pending: c.total - c.done - c.failed - c.screened,
            ran: self.ran,
            reused: c.reused,
            interrupted,
            stopped_after: self.stopped_after,
            screen,
        })
    }
}

/// `sweep status DIR`.
#[derive(Debug, Clone, Serialize)]
pub struct StatusReport {
    pub dir: PathBuf,
    pub name: String,
    pub design: DesignRecord,
    pub points: usize,
    pub done: usize,
    pub failed: usize,
    /// Claimed by a live process.
    pub running: usize,
    /// Closed points skipped by a verified screen (MFR = 0, no run).
    pub screened: usize,
    pub pending: usize,
    /// Of the pending runs, those whose last attempt was cut off: killed (a claim left by a
    /// process that is gone) or cancelled (Ctrl-C, SIGTERM).
    pub interrupted: usize,
    /// Result files that cannot be read (their runs count as pending and run again).
    pub damaged: Vec<String>,
    /// Who holds each running claim: point, hash, holder, age and lease (the first few).
    pub holders: Vec<String>,
    /// Failures by class: count and the first few (by point index) with their reasons.
    pub failures: BTreeMap<String, FailureGroup>,
    /// Convergence verdict of the last report (summary.json); `None` before the first.
    pub converged: Option<bool>,
    /// What the screen did.
    pub screen: ScreenReport,
}

#[derive(Debug, Clone, Default, Serialize)]
pub struct FailureGroup {
    pub count: usize,
    pub first: Vec<FailureNote>,
}

#[derive(Debug, Clone, Serialize)]
pub struct FailureNote {
    pub index: usize,
    pub hash: String,
    pub reason: String,
}

/// Failures listed per class in `sweep status`.
const FIRST_FAILURES: usize = 3;

pub fn status(dir: &Path) -> Result<StatusReport> {
    let (manifest, toml) = Store::read_manifest(dir)?;
    let sweep = Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    let store = Store::open(dir);
    let (statuses, _, screen) = Screen::of(&sweep).statuses(&store, &manifest);
    let mut r = StatusReport {
        dir: dir.to_path_buf(),
        name: manifest.name.clone(),
        design: manifest.design.clone(),
        points: manifest.points.len(),
        done: 0,
        failed: 0,
        running: 0,
        screened: 0,
        pending: 0,
        interrupted: 0,
        damaged: Vec::new(),
        holders: Vec::new(),
        failures: BTreeMap::new(),
        converged: read_verdict(dir),
        screen,
    };
    // The last attempt of each run, for runs cancelled part-way.
    let mut last: HashMap<String, String> = HashMap::new();
    if let Ok(lines) = store::read_joblog(dir) {
        for l in lines {
            last.insert(l.hash, l.status);
        }
    }
    let cut_off = |h: &str| last.get(h).is_some_and(|s| s == "cancelled" || s == "interrupted");
    for p in &manifest.points {
        match store.point_state(&manifest, p) {
            RunState::Done(_) => r.done += 1,
            RunState::Failed(f) => {
                r.failed += 1;
                let g = r.failures.entry(f.class.as_str().to_string()).or_default();
                g.count += 1;
                if g.first.len() < FIRST_FAILURES {
                    g.first.push(FailureNote {
                        index: p.index,
                        hash: p.hash.clone(),
                        reason: f.reason.clone(),
                    });
                }
            }
            RunState::Running(c) => {
                r.running += 1;
                if r.holders.len() < FIRST_FAILURES {
                    let h = store::short(&p.hash);
                    r.holders.push(format!("point {} ({h}): {}", p.index, store::holders::describe(&c)));
                }
            }
            RunState::Interrupted(_) => {
                r.pending += 1;
                r.interrupted += 1;
            }
            RunState::Damaged { file, reason } => {
                r.pending += 1;
                r.damaged.push(format!("{}: {reason}", file.display()));
            }
            RunState::Incomplete | RunState::Pending
                if matches!(statuses[p.index], PointStatus::Screened) =>
            {
                r.screened += 1
            }
            RunState::Incomplete | RunState::Pending => {
                r.pending += 1;
                if cut_off(&p.hash) {
                    r.interrupted += 1;
                }
            }
        }
    }
    Ok(r)
}

/// The verdict of the last report (`DIR/summary.json`), if one was written.
fn read_verdict(dir: &Path) -> Option<bool> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v.get("verdict")?.get("converged")?.as_bool()
}

impl StatusReport {
    /// The human-readable form.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "{} ({}, {}): {} points\n  done     {}\n  failed   {}\n  running  {}\n",
            self.dir.display(),
            self.name,
            design_label(&self.design),
            self.points,
            self.done,
            self.failed,
            self.running,
        );
        if self.screened > 0 {
            s.push_str(&format!("  screened {} (closed, MFR = 0 without a run)\n", self.screened));
        }
        s.push_str(&format!("  pending  {}\n", self.pending));
        if self.interrupted > 0 {
            s.insert_str(
                s.len() - 1,
                &format!("  ({} interrupted: killed or cancelled part-way)", self.interrupted),
            );
        }
        for h in &self.holders {
            s.push_str(&format!("    {h}\n"));
        }
        if self.running > self.holders.len() {
            s.push_str(&format!("    and {} more\n", self.running - self.holders.len()));
        }
        if self.running > 0 {
            s.push_str(&format!(
                "    a claim whose holder is gone for good (a lost node, a clock far ahead): `sweep unclaim {}` releases it\n",
                self.dir.display()
            ));
        }
        for d in &self.damaged {
            s.push_str(&format!("  warning: {d}\n"));
        }
        for (class, g) in &self.failures {
            s.push_str(&format!("  {class}: {}\n", g.count));
            for n in &g.first {
                s.push_str(&format!(
                    "    point {} ({}): {}\n",
                    n.index,
                    &n.hash[..12.min(n.hash.len())],
                    n.reason
                ));
            }
            if g.count > g.first.len() {
                s.push_str(&format!("    and {} more\n", g.count - g.first.len()));
            }
        }
        if let Some(line) = self.screen.sentence() {
            s.push_str(&format!("  {line}\n"));
        }
        s.push_str(&format!(
            "  converged: {}\n",
            self.converged.map_or("unknown", |c| if c { "yes" } else { "no" })
        ));
        s
    }
}
