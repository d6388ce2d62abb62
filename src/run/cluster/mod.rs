//! Sweeps on a cluster: PBS (PBS Pro, Torque) and Slurm array jobs over one sweep directory on
//! a shared file system (`sweep submit`), and the body of one array task (`sweep work`).
//!
//! The layout is stable: array index `i` always stands for the design points
//! `[i·per_task, (i+1)·per_task)` of `manifest.json`, with `per_task` fixed by the first
//! submission (`DIR/cluster/layout.json`) and points only ever appended to a manifest. A
//! re-submission therefore names only the indices whose points are unfinished (or failed, with
//! `--only failed`), as compact ranges (`--array=3,17-19`).
//!
//! A task runs its own points first, then helps with the unfinished points of the others that
//! nobody holds; claims ([`crate::store`], with leases across hosts) keep two tasks off one run
//! and let a task take over what a lost task left. After the array, a dependent job
//! (`afterany`) runs `sweep report`.
//!
//! Here the submission; `task` is one array task's share and body (`sweep work`).
//!
//! Not responsible for running points (that is [`crate::run`] and the pool) or for the
//! directory's formats ([`crate::store`]).

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::run::ClusterError;
use crate::store::{PointStatus, Store};

mod task;
pub use task::{held_points, refresh_results, share_order, task_points, work, WorkOptions};

/// A refused flag of `sweep submit` / `sweep work` (bad input).
fn flag(given: String, why: String) -> crate::Error {
    ClusterError::Flag { given, why }.into()
}

/// The built-in Slurm template.
pub const SLURM_TEMPLATE: &str = include_str!("../../../templates/slurm.tera");
/// The built-in PBS template (PBS Pro and Torque).
pub const PBS_TEMPLATE: &str = include_str!("../../../templates/pbs.tera");
/// Version of `cluster/layout.json`.
pub const LAYOUT_FORMAT: u32 = 1;

/// A batch scheduler and its array syntax.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheduler {
    /// `sbatch --array=3,17-19`.
    Slurm,
    /// PBS Pro / OpenPBS: `#PBS -J 0-9` (ranges only, so a sparse set is mapped in the script).
    PbsPro,
    /// Torque: `#PBS -t 3,17-19`.
    Torque,
}

impl Scheduler {
    pub fn name(self) -> &'static str {
        match self {
            Scheduler::Slurm => "slurm",
            Scheduler::PbsPro => "pbs",
            Scheduler::Torque => "torque",
        }
    }

    /// The submit command.
    pub fn submit_command(self) -> &'static str {
        match self {
            Scheduler::Slurm => "sbatch",
            Scheduler::PbsPro | Scheduler::Torque => "qsub",
        }
    }

    fn script_ext(self) -> &'static str {
        match self {
            Scheduler::Slurm => "slurm",
            Scheduler::PbsPro | Scheduler::Torque => "pbs",
        }
    }
}

/// Which points a submission covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Only {
    /// Points not finished (never run, cut off, or held by a claim).
    pub missing: bool,
    /// Points that failed; their tasks re-run them (`--retry-failed`).
    pub failed: bool,
}

/// What `sweep submit` was asked for.
#[derive(Debug, Clone)]
pub struct SubmitOptions {
    pub scheduler: Scheduler,
    /// Array tasks of the first submission (sets the layout); later ones keep the layout.
    pub tasks: Option<usize>,
    /// Concurrent LIGGGHTS runs per task.
    pub jobs_per_task: usize,
    /// MPI ranks per run; a task asks for `jobs_per_task · ranks` cores.
    pub ranks: u32,
    /// `HH:MM:SS`, or Slurm's `D-HH:MM:SS`.
    pub walltime: String,
    pub queue: Option<String>,
    pub account: Option<String>,
    pub lease: Duration,
    pub only: Only,
    /// A template to use instead of the built-in one.
    pub template: Option<PathBuf>,
    /// Tasks help with other tasks' leftovers once their own points are done.
    pub steal: bool,
    /// The `sweep` the tasks run: a path on the shared file system, or a command the node's
    /// PATH finds (`[cluster] command`).
    pub exe: PathBuf,
    /// Lines each script runs before `sweep` (`[cluster] prologue`: `module load ...`).
    pub prologue: Vec<String>,
    /// An LDS sweep submitted batch by batch; `None`: every point as one array.
    pub chain: Option<Chain>,
}

/// An LDS or adaptive sweep on a cluster, batch by batch: the array runs the first batch
/// (nested space) with unfinished points, and the job after it writes the report and runs
/// `next`, which judges convergence and submits the following batch only if the rule has not
/// held (an adaptive sweep's next batch is planned there, [`crate::run::adapt::plan_after`]).
#[derive(Debug, Clone)]
pub struct Chain {
    /// Points per batch (`design.lds.step`, `design.adapt.batch`): the layout gives each batch
    /// `--tasks` tasks (an adaptive sweep's first batch, `design.adapt.first` points, as many
    /// as its points need at the same points per task).
    pub step: usize,
    /// The shell command the job after the array runs once the report is written; it ends
    /// with `--after-batch`, to which the end of the batch's points is appended.
    pub next: String,
}

/// `DIR/cluster/layout.json`: the stable map from array index to design points.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct Layout {
    pub format: u32,
    /// Array index `i` runs points `[i·per_task, (i+1)·per_task)`.
    pub per_task: usize,
}

impl Layout {
    pub fn path(dir: &Path) -> PathBuf {
        dir.join("cluster").join("layout.json")
    }

    /// The layout of `dir`, if it was ever submitted.
    pub fn read(dir: &Path) -> Result<Option<Layout>> {
        let path = Self::path(dir);
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(source) => return Err(ClusterError::Io { path, source }.into()),
        };
        let l: Layout = serde_json::from_str(&text).map_err(|e| ClusterError::File {
            path: path.clone(),
            why: format!("unreadable ({e}); it fixes which points each array index runs"),
        })?;
        if l.format != LAYOUT_FORMAT || l.per_task == 0 {
            let why = format!(
                "format {}, per_task {}: expected format {LAYOUT_FORMAT}, per_task ≥ 1",
                l.format, l.per_task
            );
            return Err(ClusterError::File { path, why }.into());
        }
        Ok(Some(l))
    }

    /// Array indices whose points include one of `points`.
    pub fn tasks_of(&self, points: impl IntoIterator<Item = usize>) -> Vec<usize> {
        points.into_iter().map(|p| p / self.per_task).collect::<BTreeSet<_>>().into_iter().collect()
    }
}

/// Indices as compact ranges: `[3, 17, 18, 19]` → `"3,17-19"`.
pub fn ranges(indices: &[usize]) -> String {
    let mut out = String::new();
    let mut i = 0;
    while i < indices.len() {
        let start = indices[i];
        let mut end = start;
        while i + 1 < indices.len() && indices[i + 1] == end + 1 {
            i += 1;
            end = indices[i];
        }
        if !out.is_empty() {
            out.push(',');
        }
        match end - start {
            0 => write!(out, "{start}"),
            _ => write!(out, "{start}-{end}"),
        }
        .expect("writing to a String");
        i += 1;
    }
    out
}

/// A rendered submission: the array script, the report script, and what to submit.
#[derive(Debug, Clone)]
pub struct Rendered {
    pub scheduler: Scheduler,
    pub layout: Layout,
    /// Array indices (tasks of the layout) this submission runs.
    pub tasks: Vec<usize>,
    pub array_script: String,
    pub report_script: String,
    /// Points the tasks cover: unfinished, and failed when re-running failures.
    pub points: usize,
    /// What a `--tasks` that differs from the directory's layout did (kept it, or laid the
    /// points out again), to be said.
    pub layout_note: Option<String>,
    /// In a chain: the space this array runs and the end of its points.
    pub batch: Option<(String, usize)>,
}

/// SubmitCounts of a directory, for the message when there is nothing to submit.
#[derive(Debug, Clone, Copy, Default)]
pub struct SubmitCounts {
    pub points: usize,
    pub done: usize,
    pub failed: usize,
    /// Skipped by a verified screen.
    pub screened: usize,
    pub missing: usize,
}

/// Plan a submission of `dir`: the layout (read, or made from `--tasks`), the array indices to
/// run, and both scripts. Writes nothing. `Ok(Err(counts))` when no point needs running.
pub fn plan(dir: &Path, o: &SubmitOptions) -> Result<std::result::Result<Rendered, SubmitCounts>> {
    let (manifest, toml) = Store::read_manifest(dir)?;
    let sweep = crate::sweep::Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    let dir = std::path::absolute(dir)
        .map_err(|e| ClusterError::File { path: dir.to_path_buf(), why: e.to_string() })?;
    check_word("DIR", &dir.display().to_string())?;
    check_word("the sweep executable", &o.exe.display().to_string())?;
    check_walltime(&o.walltime)?;
    for (flag, v) in [("--queue", &o.queue), ("--account", &o.account)] {
        if let Some(v) = v {
            check_word(flag, v)?;
        }
    }
    let n = manifest.points.len();
    // In a chain each batch, not the whole design, is shared by the tasks.
    let span = o.chain.as_ref().map_or(n, |c| c.step.min(n)).max(1);
    let fresh = |t: usize| Layout { format: LAYOUT_FORMAT, per_task: span.div_ceil(t.min(span).max(1)) };
    let mut layout_note = None;
    let layout = match (Layout::read(&dir)?, o.tasks) {
        (_, Some(0)) => return Err(flag("--tasks 0".into(), "expected at least 1".into())),
        (Some(old), Some(t)) if fresh(t).per_task != old.per_task => {
            // Another --tasks: lay the points out again only when no task of the old layout
            // still runs, since a running task's index means the old block of points.
            let held = held_points(&manifest, &Store::open(&dir)).len();
            if held > 0 {
                layout_note = Some(format!(
                    "--tasks {t}: keeping the layout of {} points per task (cluster/layout.json): \
                     tasks of an earlier submission still hold {held} runs; submit with --tasks \
                     again once they have ended to lay the points out anew",
                    old.per_task
                ));
                old
            } else {
                let new = fresh(t);
                layout_note = Some(format!(
                    "--tasks {t}: no task holds a run, so the {n} points are laid out again: {} per \
                     task instead of {} (cluster/layout.json rewritten)",
                    new.per_task, old.per_task
                ));
                new
            }
        }
        (Some(l), _) => l,
        (None, Some(t)) => fresh(t),
        (None, None) => {
            return Err(flag(
                "--tasks".into(),
                format!(
                    "required for the first submission of {} ({n} points): how many array tasks share them",
                    dir.display()
                ),
            ))
        }
    };
    // Points a verified screen skipped need no task; while it is pending, the closed points do
    // (their tasks run them if the sample refutes it).
    let (status, _, _) = crate::run::screen::Screen::of(&sweep).statuses(&Store::open(&dir), &manifest);
    let counts = counts(&status);
    let mut wanted: Vec<usize> = status
        .iter()
        .enumerate()
        .filter(|(_, s)| match s {
            PointStatus::Done(_) | PointStatus::Screened => false,
            PointStatus::Failed(_) => o.only.failed,
            PointStatus::Pending => o.only.missing,
        })
        .map(|(i, _)| i)
        .collect();
    if wanted.is_empty() {
        return Ok(Err(counts));
    }
    // A chain runs the first space (an LDS prefix) that has points to run: points below `upto`.
    let mut batch = None;
    if o.chain.is_some() {
        if let Some(space) = manifest.spaces.iter().find(|s| s.points.iter().any(|p| wanted.contains(p))) {
            let upto = space.points.iter().max().map_or(0, |m| m + 1);
            wanted.retain(|&p| p < upto);
            batch = Some((space.label.clone(), upto));
        }
    }
    let tasks = layout.tasks_of(wanted.iter().copied());
    let template = match &o.template {
        Some(p) => crate::sys::read::read_capped(p, crate::sweep::FILE_CAP)
            .map_err(|e| e.to_string())
            .and_then(|b| String::from_utf8(b).map_err(|_| "not UTF-8 text".to_string()))
            .map_err(|why| flag(format!("--template {}", p.display()), why))?,
        None => match o.scheduler {
            Scheduler::Slurm => SLURM_TEMPLATE.to_string(),
            _ => PBS_TEMPLATE.to_string(),
        },
    };
    let mut ctx = tera::Context::new();
    ctx.insert("tool", &format!("demsweep {}", env!("CARGO_PKG_VERSION")));
    ctx.insert("name", &job_name(&manifest.name));
    ctx.insert("dir", &dir.display().to_string());
    ctx.insert("sweep", &o.exe.display().to_string());
    ctx.insert("prologue", &o.prologue.join("\n"));
    ctx.insert("per_task", &layout.per_task);
    ctx.insert("cpus", &(o.jobs_per_task * o.ranks as usize));
    ctx.insert("ranks", &o.ranks);
    ctx.insert("walltime", &o.walltime);
    ctx.insert("queue", &o.queue.clone().unwrap_or_default());
    ctx.insert("account", &o.account.clone().unwrap_or_default());
    ctx.insert("lease", &o.lease.as_secs());
    ctx.insert("retry_failed", &o.only.failed);
    ctx.insert("no_steal", &!o.steal);
    ctx.insert("torque", &(o.scheduler == Scheduler::Torque));
    ctx.insert("upto", &batch.as_ref().map_or(0, |b| b.1));
    // The job after the batch judges it: `next` ends with `--after-batch`, given the batch's end.
    let next = match (&o.chain, &batch) {
        (Some(c), Some((_, upto))) => format!("{} {upto}", c.next),
        _ => String::new(),
    };
    ctx.insert("chain", &next);
    let (array, index_map) = array_spec(o.scheduler, &tasks);
    ctx.insert("array", &array);
    ctx.insert("index_map", &index_map);
    let render = |report: bool| -> Result<String> {
        let mut c = ctx.clone();
        c.insert("report", &report);
        let mut tera = tera::Tera::default();
        tera.autoescape_on(vec![]);
        let name = format!("{}.tera", o.scheduler.script_ext());
        tera.add_raw_template(&name, &template)
            .and_then(|_| tera.render(&name, &c))
            .map_err(|e| ClusterError::Template { name: name.clone(), why: tera_chain(&e) }.into())
    };
    let points = wanted.len();
    Ok(Ok(Rendered {
        scheduler: o.scheduler,
        layout,
        tasks,
        array_script: render(false)?,
        report_script: render(true)?,
        points,
        layout_note,
        batch,
    }))
}

/// How the scheduler names the array's indices, and (PBS Pro with a set that is not one
/// range) the task each index stands for, for the script to map.
fn array_spec(s: Scheduler, tasks: &[usize]) -> (String, String) {
    let contiguous = tasks.windows(2).all(|w| w[1] == w[0] + 1);
    match s {
        Scheduler::Slurm | Scheduler::Torque => (ranges(tasks), String::new()),
        // PBS Pro's -J takes one range of at least two indices.
        Scheduler::PbsPro if contiguous && tasks.len() >= 2 => (ranges(tasks), String::new()),
        Scheduler::PbsPro => {
            let map = tasks.iter().map(|t| t.to_string()).collect::<Vec<_>>().join(" ");
            let array = if tasks.len() >= 2 { format!("0-{}", tasks.len() - 1) } else { String::new() };
            (array, map)
        }
    }
}

/// A job name from the sweep name: schedulers take letters, digits, `-`, `_`, `.`.
fn job_name(name: &str) -> String {
    let clean: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' }).collect();
    // PBS allows 15 characters in older versions; keep it short everywhere.
    format!("sweep-{}", clean.chars().take(9).collect::<String>())
}

/// Scheduler directives and the task's command line are written without quoting: refuse
/// what would need it.
fn check_word(what: &str, v: &str) -> Result<()> {
    let ok = !v.is_empty() && v.chars().all(|c| c.is_ascii_alphanumeric() || "/._-+@,=:~".contains(c));
    if ok {
        Ok(())
    } else {
        Err(flag(
            format!("{what} {v:?}"),
            "expected letters, digits and / . _ - + @ , = : ~ only (it goes into #SBATCH/#PBS lines unquoted)".into(),
        ))
    }
}

/// `MM`, `HH:MM:SS`, `D-HH:MM:SS` and similar: digits, colons, one dash after the days.
fn check_walltime(w: &str) -> Result<()> {
    let (days, rest) = w.split_once('-').unwrap_or(("0", w));
    let parts: Vec<&str> = rest.split(':').collect();
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let bad = || {
        Err(flag(
            format!("--walltime {w:?}"),
            "expected HH:MM:SS (or D-HH:MM:SS, or minutes), longer than zero, with minutes and seconds below 60".into(),
        ))
    };
    if !(digits(days) && parts.len() <= 3 && parts.iter().all(|p| digits(p))) {
        return bad();
    }
    let n: Vec<u64> = parts.iter().map(|p| p.parse().unwrap_or(u64::MAX)).collect();
    // Below the leading field (hours, or minutes in MM:SS), minutes and seconds stop at 59.
    if n[1..].iter().any(|&v| v >= 60) || n.iter().all(|&v| v == 0) && days.bytes().all(|b| b == b'0') {
        return bad();
    }
    Ok(())
}

fn tera_chain(e: &tera::Error) -> String {
    let mut s = e.to_string();
    let mut src = std::error::Error::source(e);
    while let Some(inner) = src {
        s.push_str(": ");
        s.push_str(&inner.to_string());
        src = inner.source();
    }
    s
}

fn counts(status: &[PointStatus]) -> SubmitCounts {
    let mut c = SubmitCounts { points: status.len(), ..SubmitCounts::default() };
    for s in status {
        match s {
            PointStatus::Done(_) => c.done += 1,
            PointStatus::Failed(_) => c.failed += 1,
            PointStatus::Screened => c.screened += 1,
            PointStatus::Pending => c.missing += 1,
        }
    }
    c
}

/// Where a submission's files go: `DIR/cluster/`.
pub fn cluster_dir(dir: &Path) -> PathBuf {
    dir.join("cluster")
}

/// Write the scripts (and the layout, at the first submission) into `DIR/cluster/`; returns
/// the array script's path and the report script's.
pub fn write(dir: &Path, r: &Rendered) -> Result<(PathBuf, PathBuf)> {
    let cdir = cluster_dir(dir);
    let io = |p: &Path, source: std::io::Error| ClusterError::Io { path: p.to_path_buf(), source };
    std::fs::create_dir_all(cdir.join("logs")).map_err(|e| io(&cdir, e))?;
    let lpath = Layout::path(dir);
    let existing = Layout::read(dir)?;
    if existing.is_none_or(|l| l.per_task != r.layout.per_task) {
        let text = serde_json::to_string_pretty(&r.layout).expect("layout serialises");
        crate::sys::atomic::write(&lpath, text.as_bytes()).map_err(|e| io(&lpath, e))?;
    }
    let ext = r.scheduler.script_ext();
    let array = cdir.join(format!("array.{ext}"));
    let report = cdir.join(format!("report.{ext}"));
    for (p, text) in [(&array, &r.array_script), (&report, &r.report_script)] {
        crate::sys::atomic::write(p, text.as_bytes()).map_err(|e| io(p, e))?;
    }
    Ok((array, report))
}

/// Submit the array script, then the report script depending on it (`afterany`); returns both
/// job ids, as the scheduler printed them. Each submission is appended to
/// `DIR/cluster/submissions.tsv`.
pub fn submit(dir: &Path, r: &Rendered, array: &Path, report: &Path) -> Result<(String, String)> {
    let cmd = r.scheduler.submit_command();
    let job = run_submit(cmd, array, &[])?;
    let depend = match r.scheduler {
        Scheduler::Slurm => vec!["--dependency".to_string(), format!("afterany:{job}")],
        Scheduler::PbsPro => vec!["-W".into(), format!("depend=afterany:{job}")],
        // Torque waits on a whole array with its own dependency type.
        Scheduler::Torque => vec!["-W".into(), format!("depend=afteranyarray:{job}")],
    };
    let report_job = run_submit(cmd, report, &depend)?;
    let line = format!(
        "{:.0}\t{}\t{job}\t{report_job}\t{}\n",
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64()),
        r.scheduler.name(),
        ranges(&r.tasks)
    );
    let log = cluster_dir(dir).join("submissions.tsv");
    let appended = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&log)
        .and_then(|mut f| std::io::Write::write_all(&mut f, line.as_bytes()));
    if let Err(e) = appended {
        eprintln!("warning: {}: {e}", log.display());
    }
    Ok((job, report_job))
}

/// Run `sbatch --parsable` or `qsub` on a script; the job id it printed.
fn run_submit(cmd: &str, script: &Path, extra: &[String]) -> Result<String> {
    let mut c = Command::new(cmd);
    if cmd == "sbatch" {
        c.arg("--parsable");
    }
    c.args(extra).arg(script);
    let out = c.output().map_err(|source| ClusterError::Start { cmd: cmd.into(), source })?;
    let stdout = String::from_utf8_lossy(&out.stdout).trim().to_string();
    if !out.status.success() || stdout.is_empty() {
        return Err(ClusterError::Submit {
            cmd: cmd.into(),
            script: script.to_path_buf(),
            status: out.status.to_string(),
            stderr: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        }
        .into());
    }
    // `sbatch --parsable` prints `id` or `id;cluster`.
    Ok(stdout.lines().last().unwrap_or("").split(';').next().unwrap_or("").to_string())
}

/// Whether `cmd` is on PATH.
pub fn on_path(cmd: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|p| std::env::split_paths(&p).any(|d| d.join(cmd).is_file()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_compact() {
        assert_eq!(ranges(&[]), "");
        assert_eq!(ranges(&[3]), "3");
        assert_eq!(ranges(&[3, 17, 18, 19]), "3,17-19");
        assert_eq!(ranges(&[0, 1, 2, 3]), "0-3");
        assert_eq!(ranges(&[1, 3, 5, 6]), "1,3,5-6");
    }

    #[test]
    fn pbs_pro_maps_a_sparse_set_in_the_script() {
        assert_eq!(array_spec(Scheduler::PbsPro, &[2, 3, 4]), ("2-4".into(), String::new()));
        assert_eq!(array_spec(Scheduler::PbsPro, &[3, 17, 18]), ("0-2".into(), "3 17 18".into()));
        assert_eq!(array_spec(Scheduler::PbsPro, &[5]), (String::new(), "5".into()));
        assert_eq!(array_spec(Scheduler::Torque, &[3, 17, 18]), ("3,17-18".into(), String::new()));
    }

    #[test]
    fn walltimes() {
        for ok in ["30", "01:00:00", "2-00:00:00", "90:00"] {
            assert!(check_walltime(ok).is_ok(), "{ok}");
        }
        for bad in ["", "1h", "01:00:00:00", "-1", "1:a"] {
            assert!(check_walltime(bad).is_err(), "{bad}");
        }
    }
}
