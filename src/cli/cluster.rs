//! `sweep submit` and `sweep work`: a sweep directory run as a cluster array job.

use std::path::PathBuf;

use super::error::flag;
use super::sweep::finish_runs;
use super::{run_options, PoolArgs};
use clap::Args;
use demsweep::error::Error;
use demsweep::sys::process::CancelToken;

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum SchedulerArg {
    /// Slurm: `sbatch --array=...`.
    Slurm,
    /// PBS Pro / OpenPBS: `#PBS -J ...`.
    Pbs,
    /// Torque: `#PBS -t ...`.
    Torque,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum OnlyArg {
    /// Points not finished: never run, cut off, or held by a claim.
    Missing,
    /// Points that failed; their tasks re-run them.
    Failed,
}

/// Render templates/slurm.tera or templates/pbs.tera into DIR/cluster/ and submit it: an array
/// whose task i runs design points [i*P, (i+1)*P) of the sweep directory (P fixed by the first
/// submission, so an index always means the same points), then helps with what other tasks
/// left; and a job after the array (afterany) that runs `sweep report DIR`. An LDS sweep goes
/// batch by batch (design.lds.step points per array): the job after each batch writes the
/// report and submits the next batch only if the convergence rule has not held, so the chain
/// stops where a local `sweep lds` would (--all-at-once: one array of every point). An adaptive
/// sweep (`sweep adapt --plan`) goes the same way, batch by batch (design.adapt.batch points,
/// the first design.adapt.first), the job after each batch planning the next from the results
/// as a local `sweep adapt` would. DIR must be
/// on a file system every node sees. Submitting again is the cluster's resume: only the indices
/// whose points are unfinished are submitted (e.g. --array=3,17-19).
#[derive(Args)]
pub(super) struct SubmitArgs {
    /// The sweep directory (from `sweep lds|lattice ... --plan`, or a started sweep), on a file
    /// system every node sees.
    dir: PathBuf,
    /// The batch system.
    #[arg(long, value_enum)]
    scheduler: SchedulerArg,
    /// Array tasks sharing the points; required at the first submission, which fixes the
    /// points per task (cluster/layout.json). Given again with another value, it lays the
    /// points out anew if no task holds a run, and otherwise keeps the layout; it says which.
    #[arg(long)]
    tasks: Option<usize>,
    /// Concurrent LIGGGHTS runs in each task.
    #[arg(long, default_value_t = 1)]
    jobs_per_task: usize,
    /// Wall time of each task: HH:MM:SS (Slurm also D-HH:MM:SS). A task stopped at its limit
    /// leaves its runs to a re-submission.
    #[arg(long, default_value = "01:00:00")]
    walltime: String,
    /// Queue (PBS) or partition (Slurm).
    #[arg(long, visible_alias = "partition")]
    queue: Option<String>,
    /// Account to charge.
    #[arg(long)]
    account: Option<String>,
    /// MPI ranks per LIGGGHTS run (mpirun -np R); a task asks for jobs-per-task × R cores.
    #[arg(long, default_value_t = 1)]
    ranks: u32,
    /// Which points to submit: missing (the default), failed (re-run them), or both.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "missing")]
    only: Vec<OnlyArg>,
    /// Seconds a claim stands without its heartbeat: a lost node's runs are taken over after it.
    #[arg(long, default_value_t = 120)]
    lease: u64,
    /// A template to use instead of the built-in one.
    #[arg(long)]
    template: Option<PathBuf>,
    /// Tasks run only their own points, and do not help with what other tasks left.
    #[arg(long)]
    no_steal: bool,
    /// Write the scripts into DIR/cluster/ but do not submit them.
    #[arg(long)]
    dry_run: bool,
    /// An LDS sweep: submit every point as one array, instead of one batch (design.lds.step
    /// points) at a time with a job after each that stops the chain once the rule holds. Not
    /// for an adaptive sweep, whose batches are planned from the results.
    #[arg(long)]
    all_at_once: bool,
    /// The job after a batch: the batch ended points below N; submit the next batch only if
    /// every one of them finished and the rule has not held.
    #[arg(long, hide = true, value_name = "N")]
    after_batch: Option<usize>,
}

#[derive(Args)]
pub(super) struct WorkArgs {
    dir: PathBuf,
    /// The array index.
    #[arg(long)]
    task: usize,
    /// Design points per array index (from DIR/cluster/layout.json).
    #[arg(long)]
    per_task: usize,
    /// Cores to use; runs at once = jobs / ranks.
    #[arg(long)]
    jobs: Option<usize>,
    #[arg(long, default_value_t = 1)]
    ranks: u32,
    /// Seconds a claim stands without its heartbeat.
    #[arg(long, default_value_t = 120)]
    lease: u64,
    #[arg(long)]
    retry_failed: bool,
    /// Run only this task's points, not other tasks' leftovers.
    #[arg(long)]
    no_steal: bool,
    /// Run only points below this index (one batch of an LDS sweep).
    #[arg(long)]
    upto: Option<usize>,
    /// Name claims after this host instead of the machine's.
    #[arg(long)]
    host: Option<String>,
    #[arg(long, short)]
    quiet: bool,
}

pub(super) fn submit(a: SubmitArgs) -> Result<(), Error> {
    use demsweep::run::cluster::{self, Only, Scheduler, SubmitOptions};
    if demsweep::run::calibrate::settings(&a.dir).is_some() {
        let dir = demsweep::sys::shell::quote_path(&a.dir).into_owned();
        return Err(flag(
            format!("sweep submit {dir}"),
            format!("a calibration plans each batch from the last on one machine; run it with `sweep resume {dir}`"),
        ));
    }
    if a.jobs_per_task == 0 {
        return Err(flag("--jobs-per-task 0", "expected at least 1"));
    }
    if a.ranks == 0 {
        return Err(flag("--ranks 0", "expected at least 1"));
    }
    if a.lease == 0 {
        return Err(flag("--lease 0", "expected seconds, at least 1"));
    }
    let scheduler = match a.scheduler {
        SchedulerArg::Slurm => Scheduler::Slurm,
        SchedulerArg::Pbs => Scheduler::PbsPro,
        SchedulerArg::Torque => Scheduler::Torque,
    };
    // How a node starts `sweep`: the sweep file's [cluster] keys, else this very executable.
    let cluster = demsweep::run::load_dir_sweep(&a.dir)?.file.cluster;
    let exe = match cluster.command {
        Some(c) => std::path::PathBuf::from(c),
        None => std::env::current_exe()?,
    };
    let opts = SubmitOptions {
        scheduler,
        tasks: a.tasks,
        jobs_per_task: a.jobs_per_task,
        ranks: a.ranks,
        walltime: a.walltime,
        queue: a.queue,
        account: a.account,
        lease: std::time::Duration::from_secs(a.lease),
        only: Only { missing: a.only.contains(&OnlyArg::Missing), failed: a.only.contains(&OnlyArg::Failed) },
        template: a.template,
        steal: !a.no_steal,
        exe,
        prologue: cluster.prologue,
        chain: None,
    };
    let (manifest, _) = demsweep::store::Store::read_manifest(&a.dir)?;
    let adaptive = matches!(manifest.design, demsweep::store::DesignRecord::Adapt { .. });
    if adaptive && a.all_at_once {
        return Err(flag(
            "--all-at-once",
            "an adaptive sweep plans each batch from the results of the last one; it is submitted batch by batch",
        ));
    }
    let step = match manifest.design {
        demsweep::store::DesignRecord::Lds { step, .. } if !a.all_at_once => Some(step),
        demsweep::store::DesignRecord::Adapt { batch, .. } => Some(batch),
        _ => None,
    };
    let mut opts = opts;
    if let Some(step) = step {
        if chain_stops(&a.dir, a.after_batch)? || adaptive && !next_adaptive_batch(&a.dir)? {
            return Ok(());
        }
        opts.chain = Some(cluster::Chain { step, next: next_command(&a.dir, &opts)? });
    }
    let cmd = scheduler.submit_command();
    if !a.dry_run && !cluster::on_path(cmd) {
        return Err(flag(
            format!("--scheduler {}", scheduler.name()),
            format!(
                "`{cmd}` is not on PATH (not a {} login node?); --dry-run writes the scripts only",
                scheduler.name()
            ),
        ));
    }
    let rendered = match cluster::plan(&a.dir, &opts)? {
        Ok(r) => r,
        Err(c) => {
            eprintln!(
                "nothing to submit: {} of {} points done, {} screened, {} failed{}",
                c.done,
                c.points,
                c.screened,
                c.failed,
                if c.failed > 0 && !opts.only.failed { " (`--only failed` re-runs them)" } else { "" }
            );
            return Ok(());
        }
    };
    if let Some(note) = &rendered.layout_note {
        eprintln!("{note}");
    }
    let (array, report) = cluster::write(&a.dir, &rendered)?;
    if opts.only.failed {
        // The tasks retry each failure once between them, however far apart they start.
        demsweep::store::retry::begin_submission_round(&a.dir)?;
    }
    let batch = rendered.batch.as_ref().map_or(String::new(), |(label, _)| format!(" of the batch {label}"));
    let what = format!(
        "{} points{batch} as array tasks {} ({} per task)",
        rendered.points,
        cluster::ranges(&rendered.tasks),
        rendered.layout.per_task
    );
    if a.dry_run {
        let after = match scheduler {
            Scheduler::Slurm => "--dependency=afterany:JOB",
            Scheduler::PbsPro => "-W depend=afterany:JOB",
            Scheduler::Torque => "-W depend=afteranyarray:JOB",
        };
        eprintln!(
            "wrote {} and {}: {what}; `sweep submit` without --dry-run submits both, or by hand: \
             `{cmd} {}`, then `{cmd} {after} {}` with the array's JOB id (the report runs once \
             every task has ended)",
            array.display(),
            report.display(),
            array.display(),
            report.display()
        );
        println!("{}", array.display());
        return Ok(());
    }
    let (job, report_job) = cluster::submit(&a.dir, &rendered, &array, &report)?;
    let after = if rendered.batch.is_some() {
        "`sweep report`, then the next batch unless the rule has held,"
    } else {
        "`sweep report`"
    };
    eprintln!(
        "submitted {what}: job {job}; {after} runs after it as job {report_job}; logs in {}",
        cluster::cluster_dir(&a.dir).join("logs").display()
    );
    println!("{job}");
    Ok(())
}

/// Whether a chain (LDS or adaptive) ends here: the MFR statistics converged (say so, submit nothing), or,
/// for the job after a batch, the batch left points unfinished (cut off: a re-submission by
/// hand decides).
fn chain_stops(dir: &std::path::Path, after_batch: Option<usize>) -> Result<bool, Error> {
    use demsweep::analysis::convergence::Criteria;
    let sweep = demsweep::run::load_dir_sweep(dir)?;
    let criteria = Criteria::from_settings(&sweep.file.convergence);
    let analysis =
        demsweep::report::analyse(dir, &criteria, &demsweep::analysis::stats::Bootstrap::default())?;
    if analysis.verdict.converged {
        eprintln!("nothing to submit: {}: {}", analysis.verdict.status, analysis.verdict.reason);
        return Ok(true);
    }
    if let Some(upto) = after_batch {
        let (manifest, _) = demsweep::store::Store::read_manifest(dir)?;
        let store = demsweep::store::Store::open(dir);
        let (status, _, _) = demsweep::run::screen::Screen::of(&sweep).statuses(&store, &manifest);
        let left =
            status.iter().take(upto).filter(|s| matches!(s, demsweep::store::PointStatus::Pending)).count();
        if left > 0 {
            eprintln!(
                "the batch ended with {left} of its {upto} points unfinished (tasks cut off?): no next batch; \
                 `sweep submit {}` re-submits them and carries the chain on",
                demsweep::sys::shell::quote_path(dir)
            );
            return Ok(true);
        }
    }
    Ok(false)
}

/// An adaptive chain between two arrays: judge the finished batches (as `sweep adapt` does) and,
/// once every planned point is finished and the rule has not held, plan the next batch into the
/// manifest (also under `--dry-run`: the batch is what a local `sweep adapt` would plan next,
/// and its scripts are then written). `false` (said) when there is nothing to submit: converged,
/// or `max` points planned.
fn next_adaptive_batch(dir: &std::path::Path) -> Result<bool, Error> {
    use demsweep::analysis::convergence::Criteria;
    use demsweep::run::adapt::{self, AdaptWatch, Standing};
    use demsweep::run::batches::Sequential;
    let sweep = demsweep::run::load_dir_sweep(dir)?;
    let mut watch = AdaptWatch::new(dir, &sweep, Criteria::from_settings(&sweep.file.convergence));
    let (manifest, _) = demsweep::store::Store::read_manifest(dir)?;
    let n = manifest.points.len();
    let standing = adapt::standing(dir, &mut watch)?;
    for line in watch.take_lines() {
        eprintln!("{line}");
    }
    match standing {
        Standing::Unfinished(_) => Ok(true),
        Standing::Converged { label, points } => {
            eprintln!("nothing to submit: converged after {label} ({points} points)");
            Ok(false)
        }
        Standing::Open => {
            let exec = demsweep::run::SweepExecutor::for_sweep(&sweep)?;
            if adapt::plan_after(dir, &exec, &watch)? {
                let (now, _) = demsweep::store::Store::read_manifest(dir)?;
                eprintln!(
                    "the rule has not held after {n} points: planned the next batch, points {n}-{} \
                     ({}, batches.csv says why)",
                    now.points.len() - 1,
                    now.spaces.last().map_or("", |s| s.label.as_str())
                );
                Ok(true)
            } else {
                eprintln!(
                    "nothing to submit: the rule has not held by design.adapt.max ({n} points); \
                     `sweep adapt {} --max M --out {}` raises it",
                    demsweep::sys::shell::quote_path(&dir.join("sweep.toml")),
                    demsweep::sys::shell::quote_path(dir)
                );
                Ok(false)
            }
        }
    }
}

/// The command the job after a batch runs: this submission again, as the judge of the batch.
fn next_command(dir: &std::path::Path, o: &demsweep::run::cluster::SubmitOptions) -> Result<String, Error> {
    let dir = std::path::absolute(dir).map_err(|e| flag(dir.display().to_string(), e.to_string()))?;
    let quote = |s: &str| format!("'{}'", s.replace('\'', "'\\''"));
    let mut cmd = vec![
        quote(&o.exe.display().to_string()),
        "submit".into(),
        quote(&dir.display().to_string()),
        "--scheduler".into(),
        o.scheduler.name().into(),
        "--jobs-per-task".into(),
        o.jobs_per_task.to_string(),
        "--walltime".into(),
        quote(&o.walltime),
        "--ranks".into(),
        o.ranks.to_string(),
        "--lease".into(),
        o.lease.as_secs().to_string(),
    ];
    for (flag, v) in [("--queue", &o.queue), ("--account", &o.account)] {
        if let Some(v) = v {
            cmd.extend([flag.to_string(), quote(v)]);
        }
    }
    if let Some(t) = &o.template {
        let t =
            std::path::absolute(t).map_err(|e| flag(format!("--template {}", t.display()), e.to_string()))?;
        cmd.extend(["--template".into(), quote(&t.display().to_string())]);
    }
    let only: Vec<&str> = [(o.only.missing, "missing"), (o.only.failed, "failed")]
        .iter()
        .filter(|(on, _)| *on)
        .map(|(_, n)| *n)
        .collect();
    cmd.extend(["--only".into(), only.join(",")]);
    if !o.steal {
        cmd.push("--no-steal".into());
    }
    // The end of the batch's points follows, once the batch is known (`cluster::plan`).
    cmd.push("--after-batch".into());
    Ok(cmd.join(" "))
}

pub(super) fn work(a: WorkArgs) -> Result<(), Error> {
    if a.per_task == 0 {
        return Err(flag("--per-task 0", "expected at least 1"));
    }
    if a.ranks == 0 {
        return Err(flag("--ranks 0", "expected at least 1"));
    }
    let cores = a.jobs.unwrap_or_else(super::default_jobs);
    if cores < a.ranks as usize {
        return Err(flag(
            format!("--jobs {cores} --ranks {}", a.ranks),
            format!("a run needs {} cores; give --jobs at least --ranks", a.ranks),
        ));
    }
    if a.lease == 0 {
        return Err(flag("--lease 0", "expected seconds, at least 1"));
    }
    demsweep::store::set_default_lease(std::time::Duration::from_secs(a.lease));
    if let Some(h) = &a.host {
        demsweep::sys::host::set_host_name(h);
    }
    let pool = PoolArgs { jobs: Some(cores / a.ranks as usize), quiet: a.quiet };
    let opts = run_options(&pool, a.retry_failed, false)?;
    if a.retry_failed {
        demsweep::store::retry::join_submission_round(&a.dir);
    }
    demsweep::sys::process::install_interrupt_handler();
    let w = demsweep::run::cluster::WorkOptions {
        task: a.task,
        per_task: a.per_task,
        steal: !a.no_steal,
        upto: a.upto,
        ranks: a.ranks,
    };
    let summary = demsweep::run::cluster::work(&a.dir, &w, &opts, &CancelToken::new())?;
    eprintln!(
        "task {}: ran {} runs; the sweep has {} of {} points done, {} screened, {} failed",
        a.task, summary.ran, summary.done, summary.points, summary.screened, summary.failed
    );
    // A task writes no report: the dependent report job does, once every task has ended.
    finish_runs(&summary)
}
