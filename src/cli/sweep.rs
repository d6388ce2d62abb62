//! `sweep lattice`, `lds`, `resume`, `status` and `report`: a sweep directory from start to
//! report.

use std::path::{Path, PathBuf};

use super::error::{flag, CliError};
use super::{check_timestep, run_options, ConvergenceArgs, PoolArgs};
use clap::Args;
use demsweep::analysis::convergence::Criteria;
use demsweep::analysis::stats::Bootstrap;
use demsweep::error::Error;
use demsweep::run::adapt::AdaptWatch;
use demsweep::run::progress::ProgressMode;
use demsweep::run::{self as driver, Summary, SweepDir, Watch};
use demsweep::store::DesignRecord;
use demsweep::sweep::Sweep;
use demsweep::sys::process::CancelToken;

#[derive(Args)]
#[command(mut_arg("out", |a| a.help(
    "Sweep directory (default: runs/<sweep name>). An existing one is continued, or extended with \
     more levels"
)))]
pub(super) struct LatticeArgs {
    /// The sweep file (TOML): parameters, design, convergence rule, scene.
    sweep: PathBuf,
    /// Lattice levels (values per dimension), e.g. 5,6,7,9,10; default from the sweep file.
    /// A point shared by two levels runs once.
    #[arg(long, value_delimiter = ',')]
    levels: Option<Vec<usize>>,
    #[command(flatten)]
    run: DesignRunArgs,
}

#[derive(Args)]
#[command(mut_arg("out", |a| a.help("Sweep directory (default: runs/<sweep name>)")))]
pub(super) struct LdsArgs {
    /// The sweep file (TOML): parameters, design, convergence rule, scene.
    sweep: PathBuf,
    /// Points per batch (one nested space per batch); default design.lds.step.
    #[arg(long)]
    step: Option<usize>,
    /// Most points to run, at least the step; default design.lds.max. A larger --max on an
    /// existing directory extends it, reusing its points.
    #[arg(long)]
    max: Option<usize>,
    #[command(flatten)]
    run: DesignRunArgs,
}

#[derive(Args)]
#[command(mut_arg("plan", |a| a.help(
    "Write the sweep directory with its first batch (manifest.json, sweep.toml, results.csv with \
     every point pending) and run nothing: for `sweep submit` on a cluster, which plans each later \
     batch between the arrays, or `sweep resume` later"
)))]
pub(super) struct AdaptArgs {
    /// The sweep file (TOML): parameters, design, convergence rule, scene.
    sweep: PathBuf,
    /// Points of the first (scrambled-Halton) batch; default design.adapt.first, else 10 per
    /// swept parameter.
    #[arg(long)]
    first: Option<usize>,
    /// Points of every later batch; default design.adapt.batch, else the directory's, else --jobs.
    #[arg(long)]
    batch: Option<usize>,
    /// Most points to run; default design.adapt.max. A larger --max on an existing directory
    /// extends it and judges again past its old extent.
    #[arg(long)]
    max: Option<usize>,
    #[command(flatten)]
    run: DesignRunArgs,
}

// What `sweep lattice`, `lds` and `adapt` take after their design's own numbers: where the
// sweep directory is, the rule's overrides, the pool, and whether to write it only. (A `//`
// comment: a doc comment here would become each command's about.) `--out` and `--plan` say
// what they do in every command; a command whose design does more says it in its own help.
#[derive(Args)]
pub(super) struct DesignRunArgs {
    /// Sweep directory (default: runs/<sweep name>). An existing one is continued.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    convergence: ConvergenceArgs,
    #[command(flatten)]
    pool: PoolArgs,
    /// Write the sweep directory (manifest.json, sweep.toml, results.csv with every point
    /// pending) and run nothing: for `sweep submit` on a cluster, or `sweep resume` later.
    #[arg(long)]
    plan: bool,
    #[arg(long, help = super::point::FORCE_HELP)]
    force: bool,
}

impl DesignRunArgs {
    /// The sweep file `path` with the timestep checked (or forced) and the rule's overrides
    /// applied.
    fn load(&self, path: &Path) -> Result<Sweep, Error> {
        let mut sweep = Sweep::load(path)?;
        check_timestep(&mut sweep, self.force)?;
        self.convergence.overrides().apply(&mut sweep.file.convergence)?;
        Ok(sweep)
    }
}

#[derive(Args)]
pub(super) struct ReportArgs {
    /// A sweep directory (holding manifest.json).
    dir: PathBuf,
    /// Also print summary.json to stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    convergence: ConvergenceArgs,
}

#[derive(Args)]
pub(super) struct ResumeArgs {
    /// The sweep directory (holding manifest.json).
    dir: PathBuf,
    /// Also re-run runs that failed.
    #[arg(long)]
    retry_failed: bool,
    /// Resume even if templates, mesh or engine changed since the manifest (changed points
    /// run again under their new hashes), and accept a timestep beyond the measured safe bound.
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    pool: PoolArgs,
}

#[derive(Args)]
pub(super) struct ExtendArgs {
    /// The sweep directory (holding manifest.json).
    dir: PathBuf,
    /// The SE of MFR to extend every point to (default: the sweep's recorded precision).
    #[arg(long, conflicts_with = "passes")]
    se: Option<f64>,
    /// A layers sweep: the most passes each point not steady at its most may add (it stops
    /// once steady; up to twice the sweep's scene.layers in all).
    #[arg(long)]
    passes: Option<usize>,
    /// Concurrent LIGGGHTS runs (default: the machine's cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// No line on stderr as each point ends (the summary on stdout stays).
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args)]
pub(super) struct UnclaimArgs {
    /// A sweep directory (holding manifest.json).
    dir: PathBuf,
}

#[derive(Args)]
pub(super) struct DirArgs {
    /// The sweep directory (holding manifest.json).
    dir: PathBuf,
    /// Print the counts as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
pub(super) struct ShowArgs {
    /// The sweep directory (holding manifest.json).
    dir: PathBuf,
    /// The point's index (results.csv's `index` column).
    index: usize,
    /// Print the page as JSON.
    #[arg(long)]
    json: bool,
}

pub(super) fn show(a: ShowArgs) -> Result<(), Error> {
    let page = demsweep::report::show::show(&a.dir, a.index)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&page).map_err(CliError::Json)?);
    } else {
        print!("{}", page.to_text());
    }
    Ok(())
}

pub(super) fn lattice(a: LatticeArgs) -> Result<(), Error> {
    let sweep = a.run.load(&a.sweep)?;
    let levels = match a.levels {
        Some(levels) => {
            check_levels(sweep.dim(), &levels, "--levels")?;
            levels
        }
        None => {
            let levels = sweep.file.design.lattice_levels.clone();
            check_levels(sweep.dim(), &levels, &format!("design.lattice_levels in {}", a.sweep.display()))?;
            levels
        }
    };
    start(sweep, DesignRecord::Lattice { levels }, a.run)
}

/// Lattice levels: at least one, each at least 2 and at most [`driver::MAX_POINTS`] points,
/// increasing (each level is a larger space than the one before).
pub(super) fn check_levels(dim: usize, levels: &[usize], source: &str) -> Result<(), Error> {
    let list = levels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(",");
    if levels.is_empty() {
        return Err(flag(source, "expected at least one level, e.g. 5,6,7"));
    }
    for &l in levels {
        demsweep::design::lattice_size(dim, l)
            .map_err(|e| flag(format!("{source} {list}"), format!("level {l}: {e}")))?;
    }
    if levels.windows(2).any(|w| w[1] <= w[0]) {
        return Err(flag(
            format!("{source} {list}"),
            "expected increasing levels (each space larger than the one before)",
        ));
    }
    Ok(())
}

pub(super) fn lds(a: LdsArgs) -> Result<(), Error> {
    let sweep = a.run.load(&a.sweep)?;
    let l = &sweep.file.design.lds;
    let file = a.sweep.display();
    let (step, step_src) = match a.step {
        Some(s) => (s, "--step".to_string()),
        None => (l.step, format!("design.lds.step in {file}")),
    };
    let (max, max_src) = match a.max {
        Some(m) => (m, "--max".to_string()),
        None => (l.max, format!("design.lds.max in {file}")),
    };
    if step == 0 {
        return Err(flag(format!("{step_src} 0"), "expected a positive number of points per batch"));
    }
    demsweep::design::lds_size(max).map_err(|e| flag(format!("{max_src} {max}"), e))?;
    if max < step {
        return Err(flag(
            format!("{max_src} {max} is less than {step_src} {step}"),
            format!(
                "expected max ≥ step (a batch of {step} points never completes); lower the step or raise max"
            ),
        ));
    }
    let design = DesignRecord::Lds { step, max, scrambling: l.scrambling, seed: l.seed };
    start(sweep, design, a.run)
}

pub(super) fn adapt(a: AdaptArgs) -> Result<(), Error> {
    let mut sweep = a.run.load(&a.sweep)?;
    let opts = run_options(&a.run.pool, false, false)?;
    let ad = &sweep.file.design.adapt;
    let file = a.sweep.display();
    // Where a number came from: the flag, the file, or the default the file left in place.
    let default = demsweep::sweep::AdaptSettings::default();
    let source = |flag: &str, key: &str, given: Option<usize>, from_file: usize, unset: usize| match given {
        Some(v) => (v, flag.to_string()),
        None if from_file == unset => (from_file, format!("the default design.adapt.{key}")),
        None => (from_file, format!("design.adapt.{key} in {file}")),
    };
    let (first, first_src) = source("--first", "first", a.first, ad.first, default.first);
    let (first, first_src) = if first == 0 && a.first.is_none() {
        (10 * sweep.dim(), "the default first batch (10 per swept parameter)".to_string())
    } else {
        (first, first_src)
    };
    let (max, max_src) = source("--max", "max", a.max, ad.max, default.max);
    let out = a.run.out.unwrap_or_else(|| driver::default_out(&sweep));
    // The batch size is part of the design: an existing directory keeps its own unless told.
    let existing = demsweep::store::Store::read_manifest(&out).ok().and_then(|(m, _)| match m.design {
        DesignRecord::Adapt { batch, .. } => Some(batch),
        _ => None,
    });
    let batch = match (a.batch, ad.batch, existing) {
        (Some(b), ..) => b,
        (None, b, _) if b > 0 => b,
        (None, _, Some(b)) => b,
        _ => opts.jobs,
    };
    if first == 0 {
        return Err(flag(format!("{first_src} 0"), "expected a positive number of points"));
    }
    if batch == 0 {
        return Err(flag("--batch 0", "expected a positive number of points per batch"));
    }
    demsweep::design::lds_size(max).map_err(|e| flag(format!("{max_src} {max}"), e))?;
    if max < first {
        return Err(flag(
            format!("{max_src} {max} is less than {first_src} {first}"),
            "expected max ≥ first; lower the first batch or raise max",
        ));
    }
    let design = DesignRecord::Adapt { first, batch, max, seed: ad.seed, repeats: 1 };
    prepare_dir(&mut sweep, &design, &out)?;
    if a.run.plan {
        return plan(&sweep, design, &out, &opts);
    }
    let mut watch = AdaptWatch::new(&out, &sweep, Criteria::from_settings(&sweep.file.convergence));
    let cancel = CancelToken::new();
    let exec = driver::SweepExecutor::for_sweep(&sweep)?;
    let summary =
        driver::adapt::start(SweepDir::new(&sweep, design, &out), &exec, &opts, &mut watch, &cancel)?;
    finish(&summary, &sweep, opts.progress)
}

fn start(mut sweep: Sweep, design: DesignRecord, a: DesignRunArgs) -> Result<(), Error> {
    let opts = run_options(&a.pool, false, false)?;
    let out = a.out.unwrap_or_else(|| driver::default_out(&sweep));
    prepare_dir(&mut sweep, &design, &out)?;
    if a.plan {
        return plan(&sweep, design, &out, &opts);
    }
    let lattice = matches!(design, DesignRecord::Lattice { .. });
    let mut watch = Watch::new(Criteria::from_settings(&sweep.file.convergence).for_design(lattice));
    let cancel = CancelToken::new();
    let exec = driver::SweepExecutor::for_sweep(&sweep)?;
    let summary = driver::start(SweepDir::new(&sweep, design, &out), &exec, &opts, &mut watch, &cancel)?;
    finish(&summary, &sweep, opts.progress)
}

/// Check the directory `out` and judge the design from where it stands (every input is checked
/// before LIGGGHTS is looked at), then take Ctrl-C from here on.
fn prepare_dir(sweep: &mut Sweep, design: &DesignRecord, out: &Path) -> Result<(), Error> {
    driver::check_out_dir(out)?;
    sweep.file.convergence.min_points = driver::judge_from(out, sweep, design)?;
    demsweep::sys::process::install_interrupt_handler();
    Ok(())
}

/// `--plan`: the directory written, nothing run; say what to do with it.
fn plan(
    sweep: &Sweep,
    design: DesignRecord,
    out: &std::path::Path,
    opts: &driver::RunOptions,
) -> Result<(), Error> {
    let cancel = CancelToken::new();
    let exec = driver::SweepExecutor::for_sweep(sweep)?;
    let (points, unfinished) =
        driver::plan_dir(SweepDir::new(sweep, design, out), &exec, opts.progress, &cancel)?;
    let dir = demsweep::sys::shell::quote_path(out).into_owned();
    eprintln!("planned {points} points in {dir}, {unfinished} to run; nothing run");
    eprintln!(
        "run them here: `sweep resume {dir}`; on a cluster: `sweep submit {dir} --scheduler slurm --tasks N`"
    );
    Ok(())
}

pub(super) fn resume(a: ResumeArgs) -> Result<(), Error> {
    let opts = run_options(&a.pool, a.retry_failed, a.force)?;
    if let Some(settings) = driver::calibrate::settings(&a.dir) {
        return super::calibrate::resume(&a.dir, &opts, settings);
    }
    let mut sweep = driver::load_dir_sweep(&a.dir)?;
    sweep.file.scene.force_bounds = a.force;
    demsweep::sys::process::install_interrupt_handler();
    // The same rule as the run that made the directory (DIR/sweep.toml), so a converged sweep
    // stays stopped where it converged.
    let criteria = Criteria::from_settings(&sweep.file.convergence);
    let cancel = CancelToken::new();
    let exec = driver::SweepExecutor::for_sweep(&sweep)?;
    let (manifest, _) = demsweep::store::Store::read_manifest(&a.dir)?;
    let summary = if let DesignRecord::Adapt { .. } = manifest.design {
        let mut watch = AdaptWatch::new(&a.dir, &sweep, criteria);
        driver::batches::run(&a.dir, &exec, &opts, &mut watch, &cancel)?
    } else {
        let lattice = matches!(manifest.design, DesignRecord::Lattice { .. });
        let mut watch = Watch::new(criteria.for_design(lattice));
        driver::resume(&a.dir, &exec, &opts, &mut watch, &cancel)?
    };
    finish(&summary, &sweep, opts.progress)
}

pub(super) fn extend(a: ExtendArgs) -> Result<(), Error> {
    if let Some(se) = a.se {
        if !(se.is_finite() && se > 0.0) {
            return Err(flag(format!("--se {se}"), "expected a positive SE of MFR, e.g. 0.002"));
        }
    }
    let jobs = super::jobs(a.jobs)?;
    demsweep::sys::process::install_interrupt_handler();
    let dir = demsweep::sys::shell::quote_path(&a.dir).into_owned();
    // The same extension goes on: the points extended keep their extension.
    let again = match (a.passes, a.se) {
        (Some(n), _) => format!("sweep extend {dir} --passes {n}"),
        (None, Some(se)) => format!("sweep extend {dir} --se {se}"),
        (None, None) => format!("sweep extend {dir}"),
    };
    let said = super::error::on_interrupt_say(format!(
        "the points not extended keep their results; `{again}` goes on"
    ));
    let cancel = CancelToken::new();
    let quiet = a.quiet;
    let say = |line: &str| {
        if !quiet {
            eprintln!("{line}");
        }
    };
    use demsweep::run::extend::{extend_sweep, Extension};
    let how = match a.passes {
        Some(n) => Extension::Passes(n),
        None => Extension::Se(a.se),
    };
    let s = extend_sweep(&a.dir, how, jobs, &cancel, &say).map_err(&said)?;
    let mut parts = if s.by_pass {
        vec![format!("{} steady now ({:.0} CPU s)", s.extended, s.cpu_s), format!("{} steady already", s.met)]
    } else {
        vec![
            format!("{} extended ({:.0} CPU s)", s.extended, s.cpu_s),
            format!("{} within it already", s.met),
        ]
    };
    if s.not_extendable > 0 {
        parts.push(format!("{} not extendable", s.not_extendable));
    }
    if s.failed > 0 && s.by_pass {
        parts.push(format!("{} still not steady or failed", s.failed));
    } else if s.failed > 0 {
        parts.push(format!("{} failed (they keep their earlier result)", s.failed));
    }
    if s.busy > 0 {
        parts.push(format!("{} held by another process", s.busy));
    }
    if s.by_pass {
        println!(
            "extend by up to {} passes: {} finished points; {}",
            a.passes.unwrap_or(0),
            s.points,
            parts.join(", ")
        );
    } else {
        println!("extend to SE {}: {} done points; {}", s.target, s.points, parts.join(", "));
    }
    if s.at_cap > 0 {
        println!(
            "{} of those extended reached the window cap first (a longer window: a larger scene.window_cap_diameters)",
            s.at_cap
        );
    }
    if s.interrupted {
        return Err(said(Error::Interrupted));
    }
    println!("next: sweep report {dir}");
    if s.failed > 0 {
        return Err(Error::RunsFailed { failed: s.failed, total: s.points });
    }
    Ok(())
}

/// Write the report, say what happened and what to do next; failed runs or an interruption are
/// the error returned.
pub(super) fn finish(s: &Summary, sweep: &Sweep, progress: ProgressMode) -> Result<(), Error> {
    // Told to stop: stop now, and leave the report of what is done to `sweep report`.
    if s.interrupted {
        return finish_runs(s);
    }
    let dir = demsweep::sys::shell::quote_path(&s.dir).into_owned();
    demsweep::sys::process::on_interrupt_say(format!(
        "the runs are kept; the report was not finished: `sweep report {dir}` writes it"
    ));
    // A large sweep's report takes seconds: say what is going on.
    if progress != ProgressMode::Quiet {
        eprintln!("writing the report of {} points…", s.points);
    }
    let criteria = Criteria::from_settings(&sweep.file.convergence);
    let analysis = demsweep::report::analyse(&s.dir, &criteria, &Bootstrap::default())?;
    // A report faster than the interrupt's grace still ends as told.
    demsweep::sys::process::end_if_interrupted();
    let html = demsweep::report::write(&analysis)?;
    demsweep::sys::process::on_interrupt_say(format!(
        "the runs are kept and the report written: {}",
        html.display()
    ));
    demsweep::sys::process::end_if_interrupted();
    let ended = finish_runs(s);
    eprintln!("{}: {}", analysis.verdict.status, analysis.verdict.reason);
    eprintln!("report: {}", html.display());
    print_answer(&analysis);
    ended
}

/// The answer on stdout: recommended settings, layer warning, what matters, verdict, next step.
fn print_answer(analysis: &demsweep::report::Analysis) {
    if let Some(a) = &analysis.answer {
        for line in a.lines() {
            println!("{line}");
        }
    }
}

/// Say what to do next about the runs; failed runs or an interruption are the error returned.
pub(super) fn finish_runs(s: &Summary) -> Result<(), Error> {
    let dir = demsweep::sys::shell::quote_path(&s.dir).into_owned();
    if let Some(line) = s.screen.sentence() {
        let warning =
            if s.screen.verdict == demsweep::run::screen::Verdict::Refuted { "warning: " } else { "" };
        eprintln!("{warning}{line}");
    }
    super::say_unfinished(s, &dir, &format!(" (`sweep report {dir}` reports what is done)"), "");
    if let Some(space) = &s.stopped_after {
        eprintln!("the rule held after {space}: no new runs started");
    }
    s.ended()
}

pub(super) fn status(a: DirArgs) -> Result<(), Error> {
    let report = demsweep::run::status(&a.dir)?;
    if a.json {
        let text = serde_json::to_string_pretty(&report).map_err(CliError::Json)?;
        println!("{text}");
    } else {
        print!("{}", report.to_text());
    }
    Ok(())
}

pub(super) fn unclaim(a: UnclaimArgs) -> Result<(), Error> {
    let (manifest, _) = demsweep::store::Store::read_manifest(&a.dir)?;
    let store = demsweep::store::Store::open(&a.dir);
    let hashes: Vec<String> = manifest.points.iter().map(|p| p.hash.clone()).collect();
    let (released, kept) = store.unclaim(&hashes)?;
    for (hash, c) in &released {
        eprintln!("released {} ({})", demsweep::store::short(hash), demsweep::store::holders::describe(c));
    }
    eprintln!(
        "released {} claims; kept {kept} held by live processes here; `sweep resume {}` runs the released points",
        released.len(),
        demsweep::sys::shell::quote_path(&a.dir)
    );
    Ok(())
}

pub(super) fn report(a: ReportArgs) -> Result<(), Error> {
    if driver::calibrate::settings(&a.dir).is_some() {
        return super::calibrate::report(&a.dir, a.json);
    }
    let sweep = driver::load_dir_sweep(&a.dir)?;
    let mut settings = sweep.file.convergence.clone();
    a.convergence.overrides().apply(&mut settings)?;
    let analysis =
        demsweep::report::analyse(&a.dir, &Criteria::from_settings(&settings), &Bootstrap::default())?;
    demsweep::run::rewrite_results(&a.dir)?;
    let html = demsweep::report::write(&analysis)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&analysis).map_err(CliError::Json)?);
    }
    eprintln!("{}: {}", analysis.verdict.status, analysis.verdict.reason);
    eprintln!("report: {}", html.display());
    if !a.json {
        print_answer(&analysis);
    }
    Ok(())
}
