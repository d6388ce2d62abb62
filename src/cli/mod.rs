//! The command line: the commands and their shared arguments, and the dispatch from a parsed
//! command to its handler. One file per command group; each turns its arguments into calls
//! of the library and prints what they return.

mod bench;
mod calibrate;
mod cluster;
mod contact;
mod error;
mod pass_watch;
mod point;
mod predict;
mod stats;
mod sweep;

use clap::{Args, Parser, Subcommand};
use demsweep::error::Error;
use demsweep::run::progress::ProgressMode;
use demsweep::run::RunOptions;
use demsweep::sweep::{Sweep, SweepError};

/// Parameter sweeps of LIGGGHTS powder-spreading simulations.
///
/// Turns a sweep file (TOML) into a design — a regular lattice or scrambled Halton points —,
/// renders one LIGGGHTS deck per point, runs them as a job pool, and reads the mass flow ratio
/// (MFR) and the v_x profile in front of the blade from the dumps — or, layer after layer, the
/// steady layer's relative density or packing.
///
/// Exit codes: 0 success; 1 a sweep finished but some runs failed; 2 bad input (nothing on disk
/// changed); 3 engine failure; 4 internal error; 130 interrupted (the directory is resumable).
#[derive(Parser)]
#[command(name = "sweep", version, max_term_width = 100)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run nested lattices (e.g. 5^d, 6^d, ...) until the answer's statistics converge; a point
    /// shared by two levels runs once.
    ///
    /// The answer is MFR, or a layers sweep's steady layer (relative density or packing). Each
    /// level is one space; after each, the answer's statistics are compared with the previous
    /// level's ([convergence] rule, or the flags below). Once the rule holds no new runs start.
    /// Ends by writing the report (as `sweep report`) and printing the verdict, naming the level.
    /// Points where nothing can pass under the blade are screened as MFR = 0 once a sample of
    /// them ran with MFR = 0 ([run] screen; `sweep points --screen` shows which).
    #[command(
        after_help = "Examples:\n  sweep lattice sweeps/quick.toml                  # levels from the file, into runs/quick/
  sweep lattice my.toml --levels 3,5,9 --out runs/lat   # nested 3^d, 5^d, 9^d"
    )]
    Lattice(sweep::LatticeArgs),
    /// Run scrambled-Halton points in batches of --step up to --max, stopping once the answer's
    /// statistics converge.
    ///
    /// The answer is MFR, or a layers sweep's steady layer (relative density or packing). Each
    /// prefix (step, 2·step, ...) is one space; after each, the answer's statistics are compared
    /// with the previous prefix's ([convergence] rule, or the flags below). Once the rule holds no
    /// new runs start. Ends by writing the report (as `sweep report`) and printing the verdict.
    /// A larger --max on a converged directory extends it and judges again past its old extent.
    /// Points where nothing can pass under the blade are screened as MFR = 0 once a sample of
    /// them ran with MFR = 0 ([run] screen; `sweep points --screen` shows which).
    #[command(
        after_help = "Examples:\n  sweep lds sweeps/quick.toml                      # 48 points, into runs/quick/
  sweep lds my.toml --max 64 --out runs/my         # extend runs/my to 64 points
  sweep lds my.toml --out /scratch/me/lds --plan   # write the directory for `sweep submit`"
    )]
    Lds(sweep::LdsArgs),
    /// Run a sequential design: a scrambled-Halton first batch, then batches placed where the
    /// emulator says the answer's statistics are least known, until they are known.
    ///
    /// After each batch a Gaussian-process emulator (each run's own SE as its noise; a jammed
    /// run's zero read as the floor of the flow, not a value) gives the four statistics of the
    /// answer (MFR, or a layers sweep's steady layer) over the space with 95% intervals from its
    /// posterior; the rule ([convergence], or the flags below) judges them batch to batch, and
    /// once it holds no new runs start. The next batch is the set of candidates that most reduces
    /// the statistics' posterior variance, each over its scale (docs/statistics.md "Adaptive
    /// design");
    /// DIR/batches.csv says why each point was chosen. A seeded adapt with the same results
    /// plans the same points; `sweep resume DIR` continues it. Ends by writing the report.
    /// On a cluster: `--plan`, then `sweep submit DIR` runs each batch as an array job and
    /// plans the next in a job after it.
    #[command(
        after_help = "Examples:\n  sweep adapt sweeps/thesis-lds.toml --out runs/ad   # here, batches of --jobs, to 480 points
  sweep adapt my.toml --out /scratch/me/ad --plan  # the first batch, for `sweep submit`"
    )]
    Adapt(sweep::AdaptArgs),
    /// Fit the sweep file's free parameters (its ranges) to measured targets, e.g. a powder's
    /// angle of repose: the posterior of each parameter with its credible interval.
    ///
    /// A scrambled-Halton first batch, then batches placed by one emulator per target where the
    /// posterior is least known (the variance of its density), until no credible interval moves
    /// by more than --tolerance of its width for --hold batches, or --max points. Writes
    /// DIR/posterior.json, DIR/calibrated.toml (the parameters as values, for a spreading sweep's
    /// `include`), DIR/calibrated-ranges.toml (the credible intervals as ranges) and
    /// DIR/report/report.html with the posterior maps. `sweep resume DIR` continues it.
    /// docs/calibration.md.
    #[command(
        after_help = "Examples:\n  sweep calibrate sweeps/calibrate-pour.toml --target angle_of_repose=34.0±1.0
  sweep calibrate my.toml --target angle_of_repose=34+-1 --target bulk_packing=0.58+-0.01 --max 60"
    )]
    Calibrate(calibrate::CalibrateArgs),
    /// Finish an interrupted sweep; every completed run is reused.
    ///
    /// Keeps the convergence rule and verdict of DIR/sweep.toml: a converged sweep runs nothing
    /// more. Ends by writing the report.
    #[command(
        after_help = "Examples:\n  sweep resume runs/quick                          # after Ctrl-C, a crash, a lost node
  sweep resume runs/quick --retry-failed           # run the failed points again"
    )]
    Resume(sweep::ResumeArgs),
    /// Raise a finished sweep's precision without running its points again: every done point
    /// whose SE of MFR is above the target continues its run from where it ended.
    ///
    /// The target is --se, else the sweep's recorded precision (DIR/precision.json; after
    /// `sweep adapt`, the first batch's points, run to the scene's own target, are brought to the
    /// sweep's). Each point continues from the restart its run wrote at its end, with no warm-up
    /// again, in DIR/runs/<hash>/extension-N/, until its SE meets the target or its window the
    /// cap; its result is measured again over every part and keeps every part's CPU time. A
    /// --se is recorded as the sweep's precision when it chooses its own, so points run later
    /// run to it too. An interrupted or failed extension leaves the point's earlier result.
    /// Then `sweep report DIR`.
    ///
    /// A layers sweep is extended by passes (--passes N): each point that was not steady at its
    /// most passes goes on from its last pass, measured after each, until it is steady or has
    /// run N more (at most twice the sweep's scene.layers in all); a steady point runs nothing.
    #[command(
        after_help = "Examples:\n  sweep extend runs/ad                             # the first batch to the sweep's precision
  sweep extend runs/quick --se 0.002               # every point to an SE of 0.002
  sweep extend runs/ti64-layers --passes 6         # layers points not yet steady: up to 6 more passes"
    )]
    Extend(sweep::ExtendArgs),
    /// Counts of a sweep directory: done, failed, running, screened, pending; the screen's verdict.
    #[command(after_help = "Examples:\n  sweep status runs/quick
  sweep status runs/quick --json")]
    Status(sweep::DirArgs),
    /// Release the claims of a sweep directory that no live process on this machine holds:
    /// another host's (a lost node, a clock far ahead, an old claim without a lease) or a dead
    /// process's. Use it once their holders are known to be gone; `status` names them.
    #[command(
        after_help = "Examples:\n  sweep unclaim /scratch/me/lds                    # after a node was lost for good"
    )]
    Unclaim(sweep::UnclaimArgs),
    /// Write convergence.csv, summary.json and report/ (plots, report.html) of a sweep directory.
    ///
    /// Also rewrites results.csv from the run directories. One row per complete space in convergence.csv (statistics of the done runs' MFR with 95%
    /// bootstrap intervals, relative changes, whether the rule holds); the verdict, counts,
    /// timing, sensitivity indices and spreading quality in summary.json; every figure as SVG and
    /// PNG and a self-contained report.html in DIR/report/. The rule is DIR/sweep.toml's
    /// [convergence] unless overridden below. Prints the verdict and the path of report.html.
    #[command(
        after_help = "Examples:\n  sweep report runs/quick                          # the rule of runs/quick/sweep.toml
  sweep report runs/quick --tolerance 0.1          # judge again at 10% of each scale"
    )]
    Report(sweep::ReportArgs),
    /// One point of a sweep directory: its parameters (swept and fixed), result or failure,
    /// spreading quality, v_x profile, run directory, and the command that reruns it with
    /// particle and blade dumps for ParaView (`sweep run ... --vtk`).
    #[command(
        after_help = "Examples:\n  sweep show runs/quick 3                          # point #3 (results.csv index 3)
  sweep show runs/quick 3 --json"
    )]
    Show(sweep::ShowArgs),
    /// Print a design as CSV (header = swept parameter names, values in their units).
    #[command(
        after_help = "Examples:\n  sweep points sweeps/quick.toml                   # the LDS design as sweep lds runs it
  sweep points my.toml --lattice 5 --screen        # a 5^d lattice, closed points marked"
    )]
    Points(point::PointsArgs),
    /// Write the deck, blade mesh and initial pile of one point without running it.
    #[command(
        after_help = "Examples:\n  sweep render sweeps/quick.toml --set gap=3 --out deck   # deck/in.liggghts, blade.stl, pile.data"
    )]
    Render(point::RenderArgs),
    /// Run one point (through LIGGGHTS, or the sweep's stand-in engine) and print the
    /// parameters it used, its MFR with the standard error, and v_x by height.
    #[command(
        after_help = "Examples:\n  sweep run sweeps/quick.toml --set gap=3          # MFR ± SE and v_x; others mid-range
  sweep run runs/quick/sweep.toml --set gap=3,blade_speed=1.4 --vtk --out view
  sweep run sweeps/ti64-machine.toml --set blade_speed=0.063 --seeds 5   # the scatter between seeds"
    )]
    Run(point::RunArgs),
    /// The statistics of a CSV column (mean, std, skewness, kurtosis) with bootstrap intervals.
    ///
    /// Mean; standard deviation with divisor N; skewness as Pearson's second coefficient
    /// 3·(mean − median)/S; kurtosis m4/S⁴ (not the excess); also the moment skewness and the
    /// median. Empty cells and cells that are not finite numbers are skipped and counted. Skewness
    /// and kurtosis are undefined (null) when every value is equal. Intervals: 95% percentile
    /// bootstrap, 1,000 resamples, seed 14.
    #[command(after_help = "Examples:\n  sweep stats runs/quick/results.csv --column mfr
  sweep stats runs/quick/results.csv --column mfr --by gap,blade_speed")]
    Stats(stats::StatsArgs),
    /// One single-contact case on the Hertz–Mindlin reference solver, as JSON.
    Contact(contact::ContactArgs),
    /// Single-contact cases through LIGGGHTS, compared with the reference solver.
    ContactCheck(contact::ContactCheckArgs),
    /// Write and submit a Slurm or PBS array job that runs a sweep directory on a cluster.
    #[command(
        after_help = "Examples:\n  sweep lds my.toml --out /scratch/me/lds --plan   # first, on the login node
  sweep submit /scratch/me/lds --scheduler slurm --tasks 50 --jobs-per-task 4 --walltime 04:00:00
  sweep submit /scratch/me/lds --scheduler pbs --tasks 50 --dry-run   # the scripts only"
    )]
    Submit(cluster::SubmitArgs),
    /// One array task of `sweep submit`: run the task's share of a sweep directory.
    #[command(hide = true)]
    Work(cluster::WorkArgs),
    /// MFR at a setting from the sweep's emulator (a Gaussian process fitted to its done
    /// points), with the predictive standard error.
    ///
    /// The same emulator as report.html's: Matérn 5/2, each point's own noise where its result
    /// records an mfr_se. Prints the leave-one-out error beside the prediction; warns when a
    /// value lies outside the swept range.
    #[command(
        after_help = "Examples:\n  sweep predict runs/quick --set gap=2.5           # blade_speed at mid-range
  sweep predict runs/quick --set gap=2.5,blade_speed=1.3 --json"
    )]
    Predict(predict::PredictArgs),
    /// Benchmarks: run time against error of the fidelity presets (`fidelity`), the scene's
    /// stability edge (`stability`), and the contact reference solver's own stability
    /// (`contact`).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

/// Overrides of the sweep file's [convergence] table. A sweep stops at the first space where the
/// rule holds; `lattice`/`lds` record the overrides in DIR/sweep.toml, so `resume` keeps them.
#[derive(Args)]
struct ConvergenceArgs {
    /// "scaled" (default: every statistic moved by at most the tolerance times its own scale and
    /// known to within it, the half-width of its 95% interval — bootstrap for lattice and lds, the
    /// emulator's posterior for adapt — for --hold consecutive spaces), "any"
    /// (the thesis's rule: any one statistic within the tolerance relatively) or "all" (every
    /// statistic within the tolerance relatively or the floor). docs/statistics.md.
    #[arg(long)]
    rule: Option<String>,
    /// The fraction of a statistic's scale ("scaled") or of its previous value ("any", "all")
    /// that counts as converged (e.g. 0.05).
    #[arg(long, allow_negative_numbers = true)]
    tolerance: Option<f64>,
    /// Absolute change that counts as converged whatever the relative one (rule "all").
    #[arg(long, allow_negative_numbers = true)]
    floor: Option<f64>,
    /// Consecutive spaces the rule must hold for (rules "scaled" and "all").
    #[arg(long)]
    hold: Option<usize>,
}

impl ConvergenceArgs {
    fn overrides(&self) -> demsweep::analysis::convergence::Overrides {
        demsweep::analysis::convergence::Overrides {
            rule: self.rule.clone(),
            tolerance: self.tolerance,
            floor: self.floor,
            hold: self.hold,
        }
    }
}

#[derive(Args)]
struct PoolArgs {
    /// Concurrent LIGGGHTS runs (default: the machine's cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// No progress on stderr (default: a bar on a terminal, a line every 10 s otherwise).
    #[arg(long, short)]
    quiet: bool,
}

pub fn run(cli: Cli) -> Result<(), Error> {
    match cli.command {
        Command::Points(a) => point::points(a),
        Command::Lattice(a) => sweep::lattice(a),
        Command::Lds(a) => sweep::lds(a),
        Command::Adapt(a) => sweep::adapt(a),
        Command::Calibrate(a) => calibrate::calibrate(a),
        Command::Resume(a) => sweep::resume(a),
        Command::Extend(a) => sweep::extend(a),
        Command::Status(a) => sweep::status(a),
        Command::Unclaim(a) => sweep::unclaim(a),
        Command::Report(a) => sweep::report(a),
        Command::Show(a) => sweep::show(a),
        Command::Render(a) => point::render(a),
        Command::Run(a) => point::run_one(a),
        Command::Stats(a) => stats::stats(a),
        Command::Predict(a) => predict::predict(a),
        Command::Contact(a) => contact::contact(a),
        Command::ContactCheck(a) => contact::contact_check(a),
        Command::Submit(a) => cluster::submit(a),
        Command::Work(a) => cluster::work(a),
        Command::Bench(bench::BenchCommand::Stability(a)) => bench::bench_stability(a),
        Command::Bench(bench::BenchCommand::Fidelity(a)) => bench::bench_fidelity(a),
        Command::Bench(bench::BenchCommand::Contact(a)) => bench::bench_contact(a),
        Command::Bench(bench::BenchCommand::Designs(a)) => bench::bench_designs(a),
    }
}

/// Refuse a sweep whose timestep fraction is beyond the measured safe bound, before anything is
/// written; `--force` accepts it (and any point's, for the thesis fidelity's fixed step).
fn check_timestep(sweep: &mut Sweep, force: bool) -> Result<(), Error> {
    if force {
        sweep.file.scene.force_bounds = true;
        return Ok(());
    }
    if sweep.file.scene.timestep_s == 0.0 {
        demsweep::scene::check_rayleigh_fraction(sweep.file.scene.rayleigh_fraction).map_err(|why| {
            SweepError::Key {
                path: sweep.path.clone(),
                key: "scene.rayleigh_fraction".into(),
                why: why.to_string(),
            }
        })?;
    }
    Ok(())
}

fn run_options(p: &PoolArgs, retry_failed: bool, force: bool) -> Result<RunOptions, Error> {
    let jobs = jobs(p.jobs)?;
    Ok(RunOptions { jobs, progress: ProgressMode::detect(p.quiet), retry_failed, force })
}

/// The `--jobs` default: the machine's cores.
fn default_jobs() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The value of a `--jobs` flag: at least 1, the machine's cores when not given.
fn jobs(flag: Option<usize>) -> Result<usize, Error> {
    match flag {
        Some(0) => Err(error::flag("--jobs 0", "expected at least 1")),
        Some(n) => Ok(n),
        None => Ok(default_jobs()),
    }
}

/// Say on stderr how a sweep directory's run was left, if not whole: interrupted (how many
/// points finished, and how to continue, then `interrupted_aside`) or with failed runs (where
/// their reasons are and how to run them again; `failed_aside` says what became of them).
fn say_unfinished(s: &demsweep::run::Summary, dir: &str, interrupted_aside: &str, failed_aside: &str) {
    if s.interrupted {
        eprintln!(
            "interrupted: {} of {} points finished; continue with `sweep resume {dir}`{interrupted_aside}",
            s.done + s.failed,
            s.points
        );
    } else if s.failed > 0 {
        eprintln!(
            "{} of {} runs failed{failed_aside}; reasons: `sweep status {dir}`; re-run them: `sweep resume {dir} --retry-failed`",
            s.failed, s.points
        );
    }
}
