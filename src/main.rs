//! The `sweep` command line: parse arguments, call the library, map errors to exit codes.

use std::io::Write;
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use demsweep::analysis::convergence::{Criteria, Watch};
use demsweep::analysis::stats::Bootstrap;
use demsweep::error::{exit, Error};
use demsweep::outcome::RunOutcome;
use demsweep::point::{self, PointContext};
use demsweep::run::progress::ProgressMode;
use demsweep::run::{self as driver, RunOptions, Summary};
use demsweep::store::DesignRecord;
use demsweep::sweep::{Scrambling, Sweep};
use demsweep::sys::process::CancelToken;

/// Parameter sweeps of LIGGGHTS powder-spreading simulations.
///
/// Turns a sweep file (TOML) into a design — a regular lattice or scrambled Halton points —,
/// renders one LIGGGHTS deck per point, runs them as a job pool, and reads the mass flow rate
/// (MFR) and the v_x profile in front of the blade from the dumps.
///
/// Exit codes: 0 success; 1 a sweep finished but some runs failed; 2 bad input (nothing on disk
/// changed); 3 engine failure; 4 internal error; 130 interrupted (the directory is resumable).
#[derive(Parser)]
#[command(name = "sweep", version, max_term_width = 100)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run nested lattices (e.g. 5^d, 6^d, ...) until the MFR statistics converge; a point shared
    /// by two levels runs once.
    ///
    /// Each level is one space; after each, the MFR statistics are compared with the previous
    /// level's ([convergence] rule, or the flags below). Once the rule holds no new runs start.
    /// Ends by writing the report (as `sweep report`) and printing the verdict, naming the level.
    /// Points where nothing can pass under the blade are screened as MFR = 0 once a sample of
    /// them ran with MFR = 0 ([run] screen; `sweep points --screen` shows which).
    Lattice(LatticeArgs),
    /// Run scrambled-Halton points in batches of --step up to --max, stopping once the MFR
    /// statistics converge.
    ///
    /// Each prefix (step, 2·step, ...) is one space; after each, the MFR statistics are compared
    /// with the previous prefix's ([convergence] rule, or the flags below). Once the rule holds no
    /// new runs start. Ends by writing the report (as `sweep report`) and printing the verdict.
    /// A larger --max on a converged directory extends it and judges again past its old extent.
    /// Points where nothing can pass under the blade are screened as MFR = 0 once a sample of
    /// them ran with MFR = 0 ([run] screen; `sweep points --screen` shows which).
    Lds(LdsArgs),
    /// Finish an interrupted sweep; every completed run is reused.
    ///
    /// Keeps the convergence rule and verdict of DIR/sweep.toml: a converged sweep runs nothing
    /// more. Ends by writing the report.
    Resume(ResumeArgs),
    /// Counts of a sweep directory: done, failed, running, screened, pending; the screen's verdict.
    Status(DirArgs),
    /// Release the claims of a sweep directory that no live process on this machine holds:
    /// another host's (a lost node, a clock far ahead, an old claim without a lease) or a dead
    /// process's. Use it once their holders are known to be gone; `status` names them.
    Unclaim(UnclaimArgs),
    /// Write convergence.csv, summary.json and report/ (plots, report.html) of a sweep directory.
    ///
    /// Also rewrites results.csv from the run directories. One row per complete space in convergence.csv (statistics of the done runs' MFR with 95%
    /// bootstrap intervals, relative changes, whether the rule holds); the verdict, counts,
    /// timing, sensitivity indices and spreading quality in summary.json; every figure as SVG and
    /// PNG and a self-contained report.html in DIR/report/. The rule is DIR/sweep.toml's
    /// [convergence] unless overridden below. Prints the verdict and the path of report.html.
    Report(ReportArgs),
    /// Print a design as CSV (header = swept parameter names, values in their units).
    Points(PointsArgs),
    /// Write the deck, blade mesh and initial pile of one point without running it.
    Render(RenderArgs),
    /// Run one point through LIGGGHTS and print its result.
    Run(RunArgs),
    /// The statistics of a CSV column (mean, std, skewness, kurtosis) with bootstrap intervals.
    ///
    /// Mean; standard deviation with divisor N; skewness as Pearson's second coefficient
    /// 3·(mean − median)/S; kurtosis m4/S⁴ (not the excess); also the moment skewness and the
    /// median. Empty cells and cells that are not finite numbers are skipped and counted. Skewness
    /// and kurtosis are undefined (null) when every value is equal. Intervals: 95% percentile
    /// bootstrap, 1,000 resamples, seed 14.
    Stats(StatsArgs),
    /// One single-contact case on the Hertz–Mindlin reference solver, as JSON.
    Contact(ContactArgs),
    /// Single-contact cases through LIGGGHTS, compared with the reference solver.
    ContactCheck(ContactCheckArgs),
    /// Write and submit a Slurm or PBS array job that runs a sweep directory on a cluster.
    Submit(SubmitArgs),
    /// One array task of `sweep submit`: run the task's share of a sweep directory.
    #[command(hide = true)]
    Work(WorkArgs),
    /// Benchmarks: run time against error of the fidelity presets (`fidelity`), the scene's
    /// stability edge (`stability`), and the contact reference solver's own stability
    /// (`contact`).
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Subcommand)]
enum BenchCommand {
    /// The stability edge: at the harshest corner of the sweep's space, drive the timestep up
    /// and the stiffness down until runs fail or MFR drifts.
    ///
    /// The corner: the smallest particles (diameter, weibull_scale, weibull_shape at lo), the
    /// softest (youngs_modulus lo), the largest blade speed, friction, rolling friction,
    /// restitution, density and gap (hi); other swept parameters at their middle, fixed ones as
    /// given. The timestep ladder runs --fractions of the Rayleigh time at the corner's modulus;
    /// the stiffness ladder runs --moduli at the sweep's rayleigh_fraction. Each level runs
    /// --seeds pile seeds; a ladder stops at its first level where a run fails (lost atoms,
    /// exploding energy, a LIGGGHTS error, a pile that never settles) or where the mean MFR
    /// differs from the first level's by more than max(10 %, 2 SE of the difference). An
    /// unsteady flow keeps its MFR. Writes DIR/stability.csv (per level), stability-runs.csv
    /// (per run), the map stability.svg and .png, and the run directories in DIR/runs/.
    Stability(StabilityArgs),
    /// Run time against error: K points of the sweep's space under each fidelity preset.
    ///
    /// A fixed seeded draw (the first K points of the sweep's scrambled-Halton design) is run
    /// under each of --presets, and under each --variant (the fast preset with some of its
    /// numerical knobs changed: rayleigh_fraction, timestep_s, stiffness_factor,
    /// mesh_cells_across, depth_diameters, window_diameters, rest_speed, settle_min_falls,
    /// skin_diameters, full_dump_every_s, run_to_end), with --seeds pile seeds each. The
    /// presets set every knob whatever the sweep file sets; the rest of [scene] (layout,
    /// substrate, supply, window start, size distribution) is the file's. Runs are interleaved so
    /// that the machine's load falls on every variant alike; speed-ups are ratios of CPU seconds
    /// summed over the same points in the same run. Errors are against the `reference` preset:
    /// MFR (the difference of seed means, with its standard error) and the v_x profile (rms over
    /// the layers of the difference over the blade speed). Writes DIR/fidelity-runs.csv (per
    /// run), fidelity.csv (per point and variant), fidelity-summary.csv (per variant), the
    /// frontier plot fidelity.svg and .png, and the runs in DIR/runs/<hash>; a finished run
    /// found there is read back, not re-run (so an interrupted bench resumes).
    Fidelity(FidelityArgs),
    /// The contact reference solver's own stability: energy drift at e = 1 over --contacts
    /// consecutive impacts, particle against wall moduli over six decades, and a timestep ladder
    /// through the solver and LIGGGHTS.
    ///
    /// Drift: the scene's D 2 mm particle (E 21 MPa) bouncing between two walls at 1 m/s
    /// (head-on, oblique with spin, with friction μ 0.3), at t_c/1000 (the default) to t_c/10;
    /// the kinetic energy against the closed form. Stiffness: particle moduli 5 MPa, 21 MPa,
    /// 1 GPa against walls 1e-3 to 1e3 times as stiff and rigid; Y*, contact time, overlap and
    /// restitution against Hertz theory. Ladder: four impacts at t_c/10000 to 2 t_c through both,
    /// where they differ beyond 1e-9 and where each leaves the closed form by 1 %. Writes
    /// DIR/contact-drift.csv, contact-stiffness.csv and contact-timestep.csv and prints the
    /// tables (BENCHMARKS.md "Reference solver stability").
    Contact(BenchContactArgs),
}

#[derive(Args)]
struct FidelityArgs {
    sweep: PathBuf,
    /// Points of the draw.
    #[arg(long, default_value_t = 8)]
    points: usize,
    /// Pile seeds per point and variant (the sweep's scene.seed and the next ones).
    #[arg(long, default_value_t = 2)]
    seeds: u64,
    /// Presets to run; errors need `reference`, speed-ups over the thesis need `thesis`.
    #[arg(long, value_delimiter = ',', default_value = "fast,reference,thesis")]
    presets: Vec<String>,
    /// An extra variant, NAME:key=value,key=value (knobs of the fast preset); repeatable.
    #[arg(long)]
    variant: Vec<String>,
    /// Concurrent LIGGGHTS runs (default: the machine's cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Output directory (default: runs/<sweep name>-fidelity); an existing one is continued.
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Args)]
struct BenchContactArgs {
    /// Consecutive impacts per energy-drift run.
    #[arg(long, default_value_t = 10_000)]
    contacts: usize,
    /// The LIGGGHTS executable for the timestep ladder.
    #[arg(long, default_value = "liggghts")]
    engine: PathBuf,
    /// Output directory for the CSV files (created if missing; the three files are replaced).
    #[arg(long, default_value = "runs/contact-bench")]
    out: PathBuf,
}

#[derive(Args)]
struct StabilityArgs {
    sweep: PathBuf,
    /// Timestep ladder, fractions of the Rayleigh time, increasing, each in (0, 1].
    #[arg(long, value_delimiter = ',', default_value = "0.2,0.3,0.4,0.5,0.6,0.8,1.0")]
    fractions: Vec<f64>,
    /// Stiffness ladder, Young's modulus in MPa, decreasing, each in [5, 1000] (default: the
    /// corner's modulus halved down to 5).
    #[arg(long, value_delimiter = ',')]
    moduli: Option<Vec<f64>>,
    /// Pile seeds per level (the sweep's scene.seed and the next ones).
    #[arg(long, default_value_t = 3)]
    seeds: u64,
    /// Concurrent LIGGGHTS runs (default: the machine's cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Output directory (default: runs/<sweep name>-stability); must be new or empty.
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Args)]
struct LatticeArgs {
    sweep: PathBuf,
    /// Lattice levels (values per dimension), e.g. 5,6,7,9,10; default from the sweep file.
    /// A point shared by two levels runs once.
    #[arg(long, value_delimiter = ',')]
    levels: Option<Vec<usize>>,
    /// Sweep directory (default: runs/<sweep name>). An existing one is continued, or extended
    /// with more levels.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    convergence: ConvergenceArgs,
    #[command(flatten)]
    pool: PoolArgs,
    /// Accept a timestep beyond the measured safe bound (scene.rayleigh_fraction above
    /// MAX_RAYLEIGH_FRACTION; BENCHMARKS.md "Stability edge").
    #[arg(long)]
    force: bool,
}

#[derive(Args)]
struct LdsArgs {
    sweep: PathBuf,
    /// Points per batch (one nested space per batch); default design.lds.step.
    #[arg(long)]
    step: Option<usize>,
    /// Most points to run, at least the step; default design.lds.max. A larger --max on an
    /// existing directory extends it, reusing its points.
    #[arg(long)]
    max: Option<usize>,
    /// Sweep directory (default: runs/<sweep name>).
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    convergence: ConvergenceArgs,
    #[command(flatten)]
    pool: PoolArgs,
    /// Accept a timestep beyond the measured safe bound (scene.rayleigh_fraction above
    /// MAX_RAYLEIGH_FRACTION; BENCHMARKS.md "Stability edge").
    #[arg(long)]
    force: bool,
}

/// Overrides of the sweep file's [convergence] table. A sweep stops at the first space where the
/// rule holds; `lattice`/`lds` record the overrides in DIR/sweep.toml, so `resume` keeps them.
#[derive(Args)]
struct ConvergenceArgs {
    /// "all" (default: every statistic within the tolerance or the floor, for --hold
    /// consecutive spaces) or "any" (the thesis's rule: any one statistic within the tolerance).
    #[arg(long)]
    rule: Option<String>,
    /// Relative change between consecutive spaces that counts as converged (e.g. 0.05).
    #[arg(long, allow_negative_numbers = true)]
    tolerance: Option<f64>,
    /// Absolute change that counts as converged whatever the relative one (rule "all").
    #[arg(long, allow_negative_numbers = true)]
    floor: Option<f64>,
    /// Consecutive spaces the rule must hold for (rule "all").
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
struct ReportArgs {
    /// A sweep directory (holding manifest.json).
    dir: PathBuf,
    /// Also print summary.json to stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    convergence: ConvergenceArgs,
}

#[derive(Args)]
struct ResumeArgs {
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
struct PoolArgs {
    /// Concurrent LIGGGHTS runs (default: the machine's cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// No progress on stderr (default: a bar on a terminal, a line every 10 s otherwise).
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum SchedulerArg {
    /// Slurm: `sbatch --array=...`.
    Slurm,
    /// PBS Pro / OpenPBS: `#PBS -J ...`.
    Pbs,
    /// Torque: `#PBS -t ...`.
    Torque,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum OnlyArg {
    /// Points not finished: never run, cut off, or held by a claim.
    Missing,
    /// Points that failed; their tasks re-run them.
    Failed,
}

/// Render templates/slurm.tera or templates/pbs.tera into DIR/cluster/ and submit it: an array
/// whose task i runs design points [i*P, (i+1)*P) of the sweep directory (P fixed by the first
/// submission, so an index always means the same points), then helps with what other tasks
/// left; and a job after the array (afterany) that runs `sweep report DIR`. DIR must be on a
/// file system every node sees. Submitting again is the cluster's resume: only the indices
/// whose points are unfinished are submitted (e.g. --array=3,17-19).
#[derive(Args)]
struct SubmitArgs {
    dir: PathBuf,
    #[arg(long, value_enum)]
    scheduler: SchedulerArg,
    /// Array tasks sharing the points; required at the first submission, which fixes the
    /// points per task for good.
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
}

#[derive(Args)]
struct WorkArgs {
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
    /// Name claims after this host instead of the machine's.
    #[arg(long)]
    host: Option<String>,
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args)]
struct UnclaimArgs {
    /// A sweep directory (holding manifest.json).
    dir: PathBuf,
}

#[derive(Args)]
struct DirArgs {
    dir: PathBuf,
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct PointsArgs {
    sweep: PathBuf,
    /// A lattice with L values per dimension (L^d points).
    #[arg(long, value_name = "L", conflicts_with = "lds", required_unless_present = "lds")]
    lattice: Option<usize>,
    /// The first N points of the Halton sequence, scrambled as design.lds.scrambling says.
    /// Plain and Braaten–Weller Halton skip index 0 (the origin: every parameter at lo), so
    /// their first row is index 1; random scrambling starts at index 0, which it maps to a
    /// random point like any other (as scipy's Halton does). Every prefix is a design.
    #[arg(long, value_name = "N")]
    lds: Option<usize>,
    /// Plain Halton, no digit scrambling (overrides design.lds.scrambling).
    #[arg(long, requires = "lds")]
    no_scramble: bool,
    /// Also print the design's squared centred L2 discrepancy CD² (Hickernell 1998; scipy's
    /// qmc.discrepancy(method="CD") convention) in unit coordinates to stderr.
    #[arg(long)]
    discrepancy: bool,
    /// Add a `screen` column: `closed` where nothing can pass under the blade (skipped as
    /// MFR = 0 once the screen is verified), `verification` for its verification sample (run
    /// anyway), empty where the point runs; and a count on stderr.
    #[arg(long)]
    screen: bool,
}

#[derive(Args)]
struct RenderArgs {
    sweep: PathBuf,
    /// Parameter values, e.g. --set diameter=2,gap=4 (units of the sweep file).
    #[arg(long, value_delimiter = ',')]
    set: Vec<String>,
    #[arg(long)]
    out: PathBuf,
    /// Accept a timestep beyond the measured safe bound (BENCHMARKS.md "Stability edge").
    #[arg(long)]
    force: bool,
}

#[derive(Args)]
struct RunArgs {
    sweep: PathBuf,
    #[arg(long, value_delimiter = ',')]
    set: Vec<String>,
    /// Print result.json instead of a summary.
    #[arg(long)]
    json: bool,
    /// Keep the run directory here (default: a temporary directory, removed afterwards).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Accept a timestep beyond the measured safe bound (BENCHMARKS.md "Stability edge").
    #[arg(long)]
    force: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum ContactCase {
    SphereWall,
    SphereSphere,
}

/// One impact (SI units). The contact normal is +z, tangential velocity +x, spin about +y.
/// `--case`, `--radius`, `--density`, `--youngs`, `--poisson`, `--restitution`, `--friction`
/// and `--vn` are required (checked by [`CaseArgs::case`], so that `contact-check` can take
/// the same flags optionally).
#[derive(Args)]
struct CaseArgs {
    #[arg(long, value_enum)]
    case: Option<ContactCase>,
    /// Radius of sphere 1, m.
    #[arg(long)]
    radius: Option<f64>,
    /// Radius of sphere 2, m (sphere-sphere; default: --radius).
    #[arg(long)]
    radius2: Option<f64>,
    /// Density, kg/m^3.
    #[arg(long)]
    density: Option<f64>,
    /// Density of sphere 2, kg/m^3 (sphere-sphere; default: --density).
    #[arg(long)]
    density2: Option<f64>,
    /// Young's modulus, Pa.
    #[arg(long)]
    youngs: Option<f64>,
    /// Poisson's ratio.
    #[arg(long)]
    poisson: Option<f64>,
    /// Wall Young's modulus, Pa (sphere-wall; default: --youngs, a same-material wall as a
    /// LIGGGHTS wall type; `inf` for a rigid plane).
    #[arg(long)]
    wall_youngs: Option<f64>,
    /// Wall Poisson's ratio (sphere-wall; default: --poisson).
    #[arg(long)]
    wall_poisson: Option<f64>,
    /// Nominal restitution coefficient, 0.05 < e <= 1.
    #[arg(long)]
    restitution: Option<f64>,
    /// Coulomb friction coefficient.
    #[arg(long)]
    friction: Option<f64>,
    /// Normal approach speed, m/s (sphere-sphere: relative).
    #[arg(long)]
    vn: Option<f64>,
    /// Tangential speed, m/s (sphere-sphere: relative).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    vt: f64,
    /// Initial angular velocity of sphere 1 about +y, rad/s.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    spin: f64,
    /// Timestep, s (default: the Hertz contact time / 1000).
    #[arg(long)]
    dt: Option<f64>,
}

impl CaseArgs {
    /// Whether any flag that defines a case was given.
    fn given(&self) -> bool {
        self.case.is_some()
            || [
                self.radius,
                self.radius2,
                self.density,
                self.density2,
                self.youngs,
                self.poisson,
                self.wall_youngs,
                self.wall_poisson,
                self.restitution,
                self.friction,
                self.vn,
                self.dt,
            ]
            .iter()
            .any(Option::is_some)
            || self.vt != 0.0
            || self.spin != 0.0
    }

    fn case(&self) -> Result<demsweep::contact::Case, Error> {
        use demsweep::contact::{Case, Material, Target};
        fn need<T: Copy>(v: Option<T>, flag: &str, what: &str) -> Result<T, Error> {
            v.ok_or_else(|| Error::input(format!("{flag}: required, expected {what}")))
        }
        let radius = need(self.radius, "--radius", "a radius in m")?;
        let density = need(self.density, "--density", "a density in kg/m^3")?;
        let material = Material {
            youngs: need(self.youngs, "--youngs", "a Young's modulus in Pa")?,
            poisson: need(self.poisson, "--poisson", "a Poisson's ratio")?,
        };
        let target = match need(self.case, "--case", "sphere-wall or sphere-sphere")? {
            ContactCase::SphereWall => Target::Wall(Material {
                youngs: self.wall_youngs.unwrap_or(material.youngs),
                poisson: self.wall_poisson.unwrap_or(material.poisson),
            }),
            ContactCase::SphereSphere => Target::Sphere {
                radius: self.radius2.unwrap_or(radius),
                density: self.density2.unwrap_or(density),
            },
        };
        Ok(Case {
            target,
            radius,
            density,
            material,
            restitution: need(self.restitution, "--restitution", "0.05 < e <= 1")?,
            friction: need(self.friction, "--friction", "a friction coefficient")?,
            vn: need(self.vn, "--vn", "an approach speed in m/s")?,
            vt: self.vt,
            spin: self.spin,
            dt: self.dt,
        })
    }
}

#[derive(Args)]
struct ContactArgs {
    #[command(flatten)]
    case: CaseArgs,
}

#[derive(Args)]
struct ContactCheckArgs {
    /// Check this one case instead of the built-in set spanning the spreading scene's materials.
    #[command(flatten)]
    case: CaseArgs,
    /// The LIGGGHTS executable.
    #[arg(long, default_value = "liggghts")]
    engine: PathBuf,
    /// Keep each case's deck and output under this directory (default: temporary, removed).
    #[arg(long)]
    keep: Option<PathBuf>,
}

#[derive(Args)]
struct StatsArgs {
    /// A CSV file with a header row (e.g. DIR/results.csv).
    file: PathBuf,
    /// The column to describe, by header name (e.g. mfr).
    #[arg(long)]
    column: String,
    /// Also the first-order sensitivity indices of the column to these columns (adjusted
    /// correlation ratio, as in `sweep report`), on the rows where all are numbers.
    #[arg(long, value_delimiter = ',', value_name = "COLUMNS")]
    by: Vec<String>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

fn main() {
    let cli = Cli::parse();
    let code = match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            e.code()
        }
    };
    std::process::exit(code);
}

fn run(cli: Cli) -> Result<i32, Error> {
    match cli.command {
        Command::Points(a) => points(a),
        Command::Lattice(a) => lattice(a),
        Command::Lds(a) => lds(a),
        Command::Resume(a) => resume(a),
        Command::Status(a) => status(a),
        Command::Unclaim(a) => unclaim(a),
        Command::Report(a) => report(a),
        Command::Render(a) => render(a),
        Command::Run(a) => run_one(a),
        Command::Stats(a) => stats(a),
        Command::Contact(a) => contact(a),
        Command::ContactCheck(a) => contact_check(a),
        Command::Submit(a) => submit(a),
        Command::Work(a) => work(a),
        Command::Bench(BenchCommand::Stability(a)) => bench_stability(a),
        Command::Bench(BenchCommand::Fidelity(a)) => bench_fidelity(a),
        Command::Bench(BenchCommand::Contact(a)) => bench_contact(a),
    }
}

/// Refuse a sweep whose timestep fraction is beyond the measured safe bound, before anything is
/// written; `--force` accepts it (and any point's, for the thesis fidelity's fixed step).
fn check_timestep(sweep: &mut Sweep, force: bool) -> Result<(), Error> {
    if force {
        sweep.file.scene.force_timestep = true;
        return Ok(());
    }
    if sweep.file.scene.timestep_s == 0.0 {
        demsweep::scene::check_rayleigh_fraction(sweep.file.scene.rayleigh_fraction)
            .map_err(|e| Error::input(format!("{}: scene.rayleigh_fraction: {e}", sweep.path.display())))?;
    }
    Ok(())
}

fn bench_fidelity(a: FidelityArgs) -> Result<i32, Error> {
    use demsweep::bench::fidelity;
    let sweep = Sweep::load(&a.sweep)?;
    let bad = |m: String| Err(Error::input(m));
    if a.points == 0 {
        return bad("--points 0: expected at least 1".into());
    }
    if a.seeds == 0 {
        return bad("--seeds 0: expected at least 1".into());
    }
    let jobs = match a.jobs {
        Some(0) => return bad("--jobs 0: expected at least 1".into()),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let variants = fidelity::variants(&sweep, &a.presets, &a.variant)?;
    if variants.is_empty() {
        return bad("--presets: expected at least one preset or --variant".into());
    }
    let lds = &sweep.file.design.lds;
    let unit = demsweep::design::halton::halton(sweep.dim(), a.points, lds.scrambling, lds.seed);
    let points: Vec<Vec<f64>> = unit.iter().map(|p| demsweep::sweep::space::scale_point(&sweep, p)).collect();
    let out = a.out.unwrap_or_else(|| PathBuf::from("runs").join(format!("{}-fidelity", sweep.file.name)));
    driver::check_out_dir(&out)?;
    demsweep::sys::process::install_interrupt_handler();
    let mut contexts = Vec::new();
    for v in &variants {
        contexts.push(PointContext::new(v.sweep.clone())?);
    }
    let plan = fidelity::Plan { points, seeds: a.seeds, jobs, out };
    let cancel = CancelToken::new();
    let started = std::time::Instant::now();
    let show = |r: &fidelity::Run, n: usize, total: usize| {
        eprintln!(
            "[{n}/{total} {:.0} s] point {} {} seed {}: {} MFR {} cpu {:.1} s{}",
            started.elapsed().as_secs_f64(),
            r.point,
            variants[r.variant].name,
            r.seed,
            r.status,
            r.mfr().map(|m| format!("{m:.4}")).unwrap_or_else(|| "-".into()),
            r.cpu,
            if r.reused { " (read back)" } else { "" }
        )
    };
    let runs = fidelity::run(&variants, &contexts, &plan, &cancel, &show)?;
    let find = |n: &str| variants.iter().position(|v| v.name == n);
    let (cells, summaries) =
        fidelity::analyse(&runs, &variants, plan.points.len(), find("reference"), find("thesis"));
    let names = sweep.names();
    let title = format!("{}: {} points × {} seeds", sweep.file.name, plan.points.len(), plan.seeds);
    let files = fidelity::write(&plan, &runs, &cells, &summaries, &variants, &names, &title)?;
    let x = |v: Option<f64>, d: usize| v.map(|v| format!("{v:.d$}")).unwrap_or_else(|| "-".into());
    println!(
        "{:<14} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>7}",
        "variant", "cpu s/pt", "×thesis", "×ref", "worst|e|", "mean|e|", "noise", "vx err", "failed"
    );
    for m in &summaries {
        println!(
            "{:<14} {:>9.2} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>7}",
            variants[m.variant].name,
            m.cpu_per_point,
            x(m.speedup_vs_thesis, 2),
            x(m.speedup_vs_reference, 2),
            x(m.worst_error, 4),
            x(m.mean_abs_error, 4),
            x(m.mean_error_se, 4),
            x(m.mean_vx_error, 4),
            m.failed
        );
    }
    for f in files {
        eprintln!("wrote {}", f.display());
    }
    Ok(exit::SUCCESS)
}

fn bench_stability(a: StabilityArgs) -> Result<i32, Error> {
    use demsweep::bench::stability;
    let sweep = Sweep::load(&a.sweep)?;
    let bad = |m: String| Err(Error::input(m));
    if sweep.file.scene.timestep_s > 0.0 {
        return bad(format!(
            "{}: scene.timestep_s = {} fixes the timestep (fidelity \"{}\"); the stability bench drives \
             scene.rayleigh_fraction, so use a fidelity without a fixed step (\"fast\" or \"reference\")",
            a.sweep.display(),
            sweep.file.scene.timestep_s,
            sweep.file.scene.fidelity
        ));
    }
    if a.fractions.is_empty() || a.fractions.iter().any(|f| !(f.is_finite() && *f > 0.0 && *f <= 1.0)) {
        return bad(format!(
            "--fractions {:?}: expected fractions of the Rayleigh time in (0, 1]",
            a.fractions
        ));
    }
    if a.fractions.windows(2).any(|w| w[1] <= w[0]) {
        return bad(format!("--fractions {:?}: expected increasing fractions", a.fractions));
    }
    let corner = stability::harshest_corner(&sweep);
    let e0 = point::resolve(&sweep, &corner)["youngs_modulus"];
    let moduli = a.moduli.unwrap_or_else(|| stability::default_moduli(e0));
    if moduli.is_empty() || moduli.iter().any(|e| !(e.is_finite() && (5.0..=1000.0).contains(e))) {
        return bad(format!("--moduli {moduli:?}: expected Young's moduli in [5, 1000] MPa"));
    }
    if moduli.windows(2).any(|w| w[1] >= w[0]) {
        return bad(format!("--moduli {moduli:?}: expected decreasing moduli"));
    }
    if a.seeds == 0 {
        return bad("--seeds 0: expected at least 1".into());
    }
    let jobs = match a.jobs {
        Some(0) => return bad("--jobs 0: expected at least 1".into()),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let out = a.out.unwrap_or_else(|| PathBuf::from("runs").join(format!("{}-stability", sweep.file.name)));
    driver::check_out_dir(&out)?;
    if std::fs::read_dir(&out).map(|mut d| d.next().is_some()).unwrap_or(false) {
        return bad(format!("{}: not empty; choose another --out", out.display()));
    }
    demsweep::sys::process::install_interrupt_handler();
    let ctx = PointContext::new(sweep)?;
    // Every level's scene must build (the bound aside) before anything is written.
    let plan = stability::Plan { corner, fractions: a.fractions, moduli, seeds: a.seeds, jobs, out };
    stability::check(&ctx, &plan)?;
    let heading = stability::describe_corner(&ctx.sweep, &plan.corner);
    std::fs::create_dir_all(&plan.out)
        .map_err(|e| Error::Internal(format!("cannot create {}: {e}", plan.out.display())))?;
    println!("harshest corner: {heading}; {} seeds per level", plan.seeds);
    println!(
        "{:<9} {:>8} {:>8} {:>10} {:>8} {:>7} {:>8} {:>7} {:>7}  verdict",
        "ladder", "dt/T_R", "E MPa", "dt s", "MFR", "SE", "drift", "bound", "wall s"
    );
    let cancel = CancelToken::new();
    let show = |r: &stability::LevelResult| {
        let pct = |v: Option<f64>| v.map(|v| format!("{:+.1}%", 100.0 * v)).unwrap_or_else(|| "-".into());
        println!(
            "{:<9} {:>8} {:>8} {:>10.3e} {:>8} {:>7} {:>8} {:>7} {:>7.1}  {}",
            r.ladder,
            r.level.fraction,
            r.level.youngs_mpa,
            r.runs.first().map_or(f64::NAN, |x| x.timestep),
            r.mfr_mean.map(|v| format!("{v:.4}")).unwrap_or_else(|| "-".into()),
            r.mfr_se.map(|v| format!("{v:.4}")).unwrap_or_else(|| "-".into()),
            pct(r.drift),
            r.bound.map(|v| format!("±{:.1}%", 100.0 * v)).unwrap_or_else(|| "-".into()),
            r.runs.iter().map(|x| x.wall).sum::<f64>(),
            r.verdict
        );
    };
    let results = stability::run(&ctx, &plan, &cancel, &show)?;
    let files = stability::write(&plan.out, &results, &format!("Stability map at {heading}"))?;
    let default = ctx.sweep.file.scene.rayleigh_fraction;
    let (safe, edge) = stability::edge(&results, "timestep");
    match (safe, edge) {
        (Some(s), e) => println!(
            "timestep: safe up to {} × T_R ({:.2}× the default {default}); edge {}",
            s.level.fraction,
            s.level.fraction / default,
            e.map(|e| format!(
                "{} × T_R ({:.2}× the default): {}",
                e.level.fraction,
                e.level.fraction / default,
                e.verdict
            ))
            .unwrap_or_else(|| "not reached".into())
        ),
        (None, _) => println!("timestep: even the first level failed"),
    }
    let (safe, edge) = stability::edge(&results, "stiffness");
    match (safe, edge) {
        (Some(s), e) => println!(
            "stiffness: safe down to {} MPa at {default} × T_R; edge {}",
            s.level.youngs_mpa,
            e.map(|e| format!("{} MPa: {}", e.level.youngs_mpa, e.verdict))
                .unwrap_or_else(|| "not reached".into())
        ),
        (None, _) => println!("stiffness: even the first level failed"),
    }
    for f in files {
        eprintln!("wrote {}", f.display());
    }
    Ok(exit::SUCCESS)
}

fn bench_contact(a: BenchContactArgs) -> Result<i32, Error> {
    use demsweep::bench::contact::{drift, stiffness, timestep, to_csv};
    if a.contacts == 0 {
        return Err(Error::input("--contacts 0: expected at least 1"));
    }
    if a.out.exists() && !a.out.is_dir() {
        return Err(Error::input(format!("--out {}: not a directory", a.out.display())));
    }
    std::fs::create_dir_all(&a.out)
        .map_err(|e| Error::Internal(format!("cannot create {}: {e}", a.out.display())))?;
    let write = |name: &str, text: String| -> Result<(), Error> {
        let path = a.out.join(name);
        demsweep::sys::atomic::write(&path, text.as_bytes())
            .map_err(|e| Error::Internal(format!("cannot write {}: {e}", path.display())))?;
        eprintln!("wrote {}", path.display());
        Ok(())
    };

    println!("Energy drift at e = 1 over {} contacts (E_N/E_0* = closed form)", a.contacts);
    let rows =
        drift::run(&drift::default_cases(), &drift::DEFAULT_LADDER, a.contacts).map_err(contact_error)?;
    print!("{}", drift::table(&rows));
    write("contact-drift.csv", to_csv(&rows).map_err(contact_error)?)?;

    println!("\nStiffness ratios (q = wall/particle modulus; errors against Hertz theory)");
    let rows = stiffness::run(&stiffness::PARTICLE_MODULI, &stiffness::RATIOS);
    print!("{}", stiffness::table(&rows));
    write("contact-stiffness.csv", to_csv(&rows).map_err(contact_error)?)?;

    println!("\nTimestep ladder, reference solver against {}", a.engine.display());
    let rows = timestep::run(&timestep::default_cases(), &timestep::DEFAULT_LADDER, &a.engine)
        .map_err(contact_error)?;
    print!("{}", timestep::table(&rows));
    write("contact-timestep.csv", to_csv(&rows).map_err(contact_error)?)?;
    if rows.iter().all(|r| r.liggghts_restitution_n.is_none()) {
        let first = rows.first().map_or("", |r| r.error.as_str());
        return Err(Error::Engine(format!("LIGGGHTS failed on every ladder case: {first}")));
    }
    Ok(exit::SUCCESS)
}

fn run_options(p: &PoolArgs, retry_failed: bool, force: bool) -> Result<RunOptions, Error> {
    let jobs = match p.jobs {
        Some(0) => return Err(Error::input("--jobs 0: expected at least 1")),
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    Ok(RunOptions { jobs, progress: ProgressMode::detect(p.quiet), retry_failed, force })
}

fn lattice(a: LatticeArgs) -> Result<i32, Error> {
    let mut sweep = Sweep::load(&a.sweep)?;
    check_timestep(&mut sweep, a.force)?;
    a.convergence.overrides().apply(&mut sweep.file.convergence)?;
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
    start(sweep, DesignRecord::Lattice { levels }, a.out, &a.pool)
}

/// Lattice levels: at least one, each at least 2 and at most [`driver::MAX_POINTS`] points,
/// increasing (each level is a larger space than the one before).
fn check_levels(dim: usize, levels: &[usize], source: &str) -> Result<(), Error> {
    let list = levels.iter().map(|l| l.to_string()).collect::<Vec<_>>().join(",");
    if levels.is_empty() {
        return Err(Error::input(format!("{source}: expected at least one level, e.g. 5,6,7")));
    }
    for &l in levels {
        demsweep::design::lattice_size(dim, l)
            .map_err(|e| Error::input(format!("{source} {list}: level {l}: {e}")))?;
    }
    if levels.windows(2).any(|w| w[1] <= w[0]) {
        return Err(Error::input(format!(
            "{source} {list}: expected increasing levels (each space larger than the one before)"
        )));
    }
    Ok(())
}

fn lds(a: LdsArgs) -> Result<i32, Error> {
    let mut sweep = Sweep::load(&a.sweep)?;
    check_timestep(&mut sweep, a.force)?;
    a.convergence.overrides().apply(&mut sweep.file.convergence)?;
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
        return Err(Error::input(format!("{step_src} 0: expected a positive number of points per batch")));
    }
    demsweep::design::lds_size(max).map_err(|e| Error::input(format!("{max_src} {max}: {e}")))?;
    if max < step {
        return Err(Error::input(format!(
            "{max_src} {max} is less than {step_src} {step}: expected max ≥ step (a batch of \
             {step} points never completes); lower the step or raise max"
        )));
    }
    let design = DesignRecord::Lds { step, max, scrambling: l.scrambling, seed: l.seed };
    start(sweep, design, a.out, &a.pool)
}

fn start(mut sweep: Sweep, design: DesignRecord, out: Option<PathBuf>, p: &PoolArgs) -> Result<i32, Error> {
    let opts = run_options(p, false, false)?;
    let out = out.unwrap_or_else(|| driver::default_out(&sweep));
    // Every input is checked before LIGGGHTS is looked at.
    driver::check_out_dir(&out)?;
    sweep.file.convergence.min_points = driver::judge_from(&out, &sweep, &design)?;
    demsweep::sys::process::install_interrupt_handler();
    let mut watch = Watch::new(Criteria::from_settings(&sweep.file.convergence));
    let cancel = CancelToken::new();
    let summary = if demsweep::run::standin::selected(&sweep) {
        let exec = demsweep::run::standin::StandIn::new(sweep.clone());
        driver::start(&sweep, design, &out, &exec, &opts, &mut watch, &cancel)?
    } else {
        let exec = driver::PointExecutor::new(sweep.clone())?;
        driver::start(&sweep, design, &out, &exec, &opts, &mut watch, &cancel)?
    };
    finish(&summary, &sweep)
}

fn resume(a: ResumeArgs) -> Result<i32, Error> {
    let opts = run_options(&a.pool, a.retry_failed, a.force)?;
    let mut sweep = driver::load_dir_sweep(&a.dir)?;
    sweep.file.scene.force_timestep = a.force;
    demsweep::sys::process::install_interrupt_handler();
    // The same rule as the run that made the directory (DIR/sweep.toml), so a converged sweep
    // stays stopped where it converged.
    let mut watch = Watch::new(Criteria::from_settings(&sweep.file.convergence));
    let cancel = CancelToken::new();
    let summary = if demsweep::run::standin::selected(&sweep) {
        let exec = demsweep::run::standin::StandIn::new(sweep.clone());
        driver::resume(&a.dir, &exec, &opts, &mut watch, &cancel)?
    } else {
        let exec = driver::PointExecutor::new(sweep.clone())?;
        driver::resume(&a.dir, &exec, &opts, &mut watch, &cancel)?
    };
    finish(&summary, &sweep)
}

/// Write the report, say what happened and what to do next, and return the exit code.
fn finish(s: &Summary, sweep: &Sweep) -> Result<i32, Error> {
    let criteria = Criteria::from_settings(&sweep.file.convergence);
    let analysis = demsweep::report::analyse(&s.dir, &criteria, &Bootstrap::default())?;
    let html = demsweep::report::write(&analysis)?;
    let code = finish_runs(s);
    eprintln!("{}: {}", analysis.verdict.status, analysis.verdict.reason);
    eprintln!("report: {}", html.display());
    Ok(code)
}

/// Say what to do next about the runs and return the exit code.
fn finish_runs(s: &Summary) -> i32 {
    let dir = s.dir.display();
    if let Some(line) = s.screen.sentence() {
        let warning =
            if s.screen.verdict == demsweep::run::screen::Verdict::Refuted { "warning: " } else { "" };
        eprintln!("{warning}{line}");
    }
    if s.interrupted {
        eprintln!(
            "interrupted: {} of {} points finished; continue with `sweep resume {dir}`",
            s.done + s.failed,
            s.points
        );
    } else if s.failed > 0 {
        eprintln!("{} of {} runs failed; reasons: `sweep status {dir}`; re-run them: `sweep resume {dir} --retry-failed`", s.failed, s.points);
    }
    if let Some(space) = &s.stopped_after {
        eprintln!("the rule held after {space}: no new runs started");
    }
    s.exit_code()
}

fn submit(a: SubmitArgs) -> Result<i32, Error> {
    use demsweep::run::cluster::{self, Only, Scheduler, SubmitOptions};
    if a.jobs_per_task == 0 {
        return Err(Error::input("--jobs-per-task 0: expected at least 1"));
    }
    if a.ranks == 0 {
        return Err(Error::input("--ranks 0: expected at least 1"));
    }
    if a.lease == 0 {
        return Err(Error::input("--lease 0: expected seconds, at least 1"));
    }
    let scheduler = match a.scheduler {
        SchedulerArg::Slurm => Scheduler::Slurm,
        SchedulerArg::Pbs => Scheduler::PbsPro,
        SchedulerArg::Torque => Scheduler::Torque,
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
        exe: std::env::current_exe()?,
    };
    let cmd = scheduler.submit_command();
    if !a.dry_run && !cluster::on_path(cmd) {
        return Err(Error::input(format!(
            "--scheduler {}: `{cmd}` is not on PATH (not a {} login node?); --dry-run writes the scripts only",
            scheduler.name(),
            scheduler.name()
        )));
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
            return Ok(exit::SUCCESS);
        }
    };
    let (array, report) = cluster::write(&a.dir, &rendered)?;
    if opts.only.failed {
        // The tasks retry each failure once between them, however far apart they start.
        demsweep::store::retry::begin_submission_round(&a.dir)?;
    }
    let what = format!(
        "{} points as array tasks {} ({} per task)",
        rendered.points,
        cluster::ranges(&rendered.tasks),
        rendered.layout.per_task
    );
    if a.dry_run {
        eprintln!(
            "wrote {} and {}: {what}; submit with `{cmd} {}`",
            array.display(),
            report.display(),
            array.display()
        );
        println!("{}", array.display());
        return Ok(exit::SUCCESS);
    }
    let (job, report_job) = cluster::submit(&a.dir, &rendered, &array, &report)?;
    eprintln!(
        "submitted {what}: job {job}; `sweep report` runs after it as job {report_job}; logs in {}",
        cluster::cluster_dir(&a.dir).join("logs").display()
    );
    println!("{job}");
    Ok(exit::SUCCESS)
}

fn work(a: WorkArgs) -> Result<i32, Error> {
    if a.per_task == 0 {
        return Err(Error::input("--per-task 0: expected at least 1"));
    }
    if a.ranks == 0 {
        return Err(Error::input("--ranks 0: expected at least 1"));
    }
    let cores = a.jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if cores < a.ranks as usize {
        return Err(Error::input(format!(
            "--jobs {cores} --ranks {}: a run needs {} cores; give --jobs at least --ranks",
            a.ranks, a.ranks
        )));
    }
    if a.lease == 0 {
        return Err(Error::input("--lease 0: expected seconds, at least 1"));
    }
    demsweep::store::set_default_lease(std::time::Duration::from_secs(a.lease));
    if let Some(h) = &a.host {
        demsweep::store::set_host_name(h);
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
        ranks: a.ranks,
    };
    let summary = demsweep::run::cluster::work(&a.dir, &w, &opts, &CancelToken::new())?;
    eprintln!(
        "task {}: ran {} runs; the sweep has {} of {} points done, {} screened, {} failed",
        a.task, summary.ran, summary.done, summary.points, summary.screened, summary.failed
    );
    // A task writes no report: the dependent report job does, once every task has ended.
    Ok(finish_runs(&summary))
}

fn status(a: DirArgs) -> Result<i32, Error> {
    let report = demsweep::run::status(&a.dir)?;
    if a.json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| Error::Internal(e.to_string()))?;
        println!("{text}");
    } else {
        print!("{}", report.to_text());
    }
    Ok(exit::SUCCESS)
}

fn unclaim(a: UnclaimArgs) -> Result<i32, Error> {
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
        a.dir.display()
    );
    Ok(exit::SUCCESS)
}

fn report(a: ReportArgs) -> Result<i32, Error> {
    let sweep = driver::load_dir_sweep(&a.dir)?;
    let mut settings = sweep.file.convergence.clone();
    a.convergence.overrides().apply(&mut settings)?;
    let analysis =
        demsweep::report::analyse(&a.dir, &Criteria::from_settings(&settings), &Bootstrap::default())?;
    demsweep::report::rewrite_results(&a.dir)?;
    let html = demsweep::report::write(&analysis)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&analysis).map_err(|e| Error::Internal(e.to_string()))?);
    }
    eprintln!("{}: {}", analysis.verdict.status, analysis.verdict.reason);
    eprintln!("report: {}", html.display());
    Ok(exit::SUCCESS)
}

fn stats(a: StatsArgs) -> Result<i32, Error> {
    let table = demsweep::report::read_columns(&a.file, &a.column, &a.by)?;
    let column = &table.column;
    let m = demsweep::analysis::stats::moments(&column.values);
    let sensitivity = if a.by.is_empty() {
        Vec::new()
    } else {
        let (x, y): (Vec<Vec<f64>>, Vec<f64>) = table.xy.iter().cloned().unzip();
        demsweep::analysis::sensitivity::ranked(demsweep::analysis::sensitivity::first_order(&a.by, &x, &y))
    };
    let iv = demsweep::analysis::stats::bootstrap(&column.values, &Bootstrap::default());
    if a.json {
        let intervals: serde_json::Map<String, serde_json::Value> = demsweep::analysis::stats::STATISTICS
            .iter()
            .zip(iv)
            .map(|(s, i)| (s.name().to_string(), serde_json::json!(i)))
            .collect();
        let out = serde_json::json!({
            "file": a.file.display().to_string(),
            "column": a.column,
            "n": m.n,
            "skipped_empty": column.empty,
            "skipped_non_numeric": column.non_numeric,
            "mean": m.mean,
            "std": m.std,
            "skewness": m.skewness,
            "kurtosis": m.kurtosis,
            "moment_skewness": m.moment_skewness,
            "median": m.median,
            "intervals": intervals,
            "sensitivity": sensitivity,
        });
        println!("{}", serde_json::to_string_pretty(&out).map_err(|e| Error::Internal(e.to_string()))?);
    } else {
        let f = |v: Option<f64>| v.map_or("undefined".to_string(), |v| format!("{v:.6}"));
        println!(
            "{} column {}: n = {} ({} empty, {} not numbers skipped)",
            a.file.display(),
            a.column,
            m.n,
            column.empty,
            column.non_numeric
        );
        for (s, i) in demsweep::analysis::stats::STATISTICS.iter().zip(iv) {
            println!("  {:<16} {:>12}   95% interval [{}, {}]", s.name(), f(s.of(&m)), f(i.lo), f(i.hi));
        }
        println!("  {:<16} {:>12}", "moment_skewness", f(m.moment_skewness));
        println!("  {:<16} {:>12}", "median", f(m.median));
        if !sensitivity.is_empty() {
            println!("first-order sensitivity of {} ({} rows):", a.column, table.xy.len());
            for s in &sensitivity {
                println!("  {:<16} {:>12}", s.parameter, f(s.first_order));
            }
        }
    }
    Ok(exit::SUCCESS)
}

fn points(a: PointsArgs) -> Result<i32, Error> {
    let sweep = Sweep::load(&a.sweep)?;
    let unit = match (a.lattice, a.lds) {
        (Some(l), _) => {
            demsweep::design::lattice_size(sweep.dim(), l)
                .map_err(|e| Error::input(format!("--lattice {l}: {e}")))?;
            demsweep::design::lattice::lattice(sweep.dim(), l)
        }
        (None, Some(n)) => {
            demsweep::design::lds_size(n).map_err(|e| Error::input(format!("--lds {n}: {e}")))?;
            let lds = &sweep.file.design.lds;
            let scrambling = if a.no_scramble { Scrambling::None } else { lds.scrambling };
            demsweep::design::halton::halton(sweep.dim(), n, scrambling, lds.seed)
        }
        (None, None) => unreachable!("clap requires --lattice or --lds"),
    };
    if a.discrepancy {
        eprintln!(
            "centred L2 discrepancy (squared) of {} points in {}-D: {:.6e}",
            unit.len(),
            sweep.dim(),
            demsweep::design::discrepancy::centred_l2(&unit)
        );
    }
    let values: Vec<Vec<f64>> = unit.iter().map(|p| demsweep::sweep::space::scale_point(&sweep, p)).collect();
    let screen = if a.screen { Some(demsweep::run::screen::preview(&sweep, &values)?) } else { None };
    if let Some(col) = &screen {
        let count = |w: &str| col.iter().filter(|c| **c == w).count();
        match count("closed") + count("verification") {
            0 => eprintln!("screen: none of the {} points is closed", col.len()),
            closed => eprintln!(
                "screen: {closed} of {} points closed; {} skipped as MFR = 0 once the {} of the verification sample give MFR = 0",
                col.len(),
                count("closed"),
                count("verification")
            ),
        }
    }
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let write = |out: &mut dyn Write| -> std::io::Result<()> {
        let extra = if screen.is_some() { ",screen" } else { "" };
        writeln!(out, "{}{extra}", sweep.names().join(","))?;
        for (k, v) in values.iter().enumerate() {
            let row: Vec<String> = v.iter().map(|v| format!("{v}")).collect();
            let extra = screen.as_ref().map_or(String::new(), |c| format!(",{}", c[k]));
            writeln!(out, "{}{extra}", row.join(","))?;
        }
        out.flush()
    };
    match write(&mut out) {
        Ok(()) => Ok(exit::SUCCESS),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(exit::SUCCESS),
        Err(e) => Err(e.into()),
    }
}

fn render(a: RenderArgs) -> Result<i32, Error> {
    let mut sweep = Sweep::load(&a.sweep)?;
    check_timestep(&mut sweep, a.force)?;
    let values = point::swept_values_from_set(&sweep, &a.set)?;
    if a.out.exists() && !a.out.is_dir() {
        return Err(Error::input(format!("--out {}: exists and is not a directory", a.out.display())));
    }
    let ctx = PointContext::new(sweep)?;
    let prepared = point::prepare(&ctx, &values)?;
    std::fs::create_dir_all(&a.out)
        .and_then(|_| prepared.deck.write(&a.out))
        .map_err(|e| Error::Internal(format!("cannot write to {}: {e}", a.out.display())))?;
    let s = &prepared.scene;
    eprintln!(
        "wrote {}/{{in.liggghts,blade.stl,pile.data}}: {} particles ({} substrate), dt = {:.3e} s, settle + {} steps, hash {}",
        a.out.display(),
        s.particles,
        s.substrate_particles,
        s.timestep,
        s.spread_steps(),
        &prepared.hash[..16]
    );
    Ok(exit::SUCCESS)
}

fn run_one(a: RunArgs) -> Result<i32, Error> {
    demsweep::sys::process::install_interrupt_handler();
    let mut sweep = Sweep::load(&a.sweep)?;
    check_timestep(&mut sweep, a.force)?;
    let values = point::swept_values_from_set(&sweep, &a.set)?;
    if let Some(out) = a.out.as_ref().filter(|o| o.exists() && !o.is_dir()) {
        return Err(Error::input(format!("--out {}: exists and is not a directory", out.display())));
    }
    let ctx = PointContext::new(sweep)?;
    let prepared = point::prepare(&ctx, &values)?;
    let temp;
    let dir = match &a.out {
        Some(d) => d.clone(),
        None => {
            temp = tempfile::Builder::new().prefix("sweep-run-").tempdir()?;
            temp.path().to_path_buf()
        }
    };
    if !a.json {
        eprintln!(
            "running {} particles, settle + {} steps (dt = {:.3e} s) in {}",
            prepared.scene.particles,
            prepared.scene.spread_steps(),
            prepared.scene.timestep,
            dir.display()
        );
        if prepared.scene.nothing_passes() {
            eprintln!("the screen closes this point: nothing can pass under the blade (a sweep counts it as MFR = 0)");
        }
    }
    let cancel = demsweep::sys::process::CancelToken::new();
    match point::execute(&ctx, &prepared, &dir, &cancel) {
        RunOutcome::Done(r) => {
            if a.json {
                println!("{}", serde_json::to_string_pretty(&r).map_err(|e| Error::Internal(e.to_string()))?);
            } else {
                let vx: Vec<String> =
                    r.vx.iter().map(|v| v.map(|v| format!("{v:.3}")).unwrap_or_else(|| "-".into())).collect();
                println!(
                    "MFR        {:.4}  ({} particles; flux cross-check {:.4}, {})",
                    r.mfr,
                    r.mfr_particles,
                    r.mfr_flux,
                    if r.steady { "steady" } else { "NOT steady" }
                );
                println!("v_x (m/s)  {}", vx.join(" "));
                println!(
                    "particles  {}   steps {}   simulated {:.4} s   wall {:.1} s",
                    r.particles, r.steps, r.simulated_time, r.wall_time
                );
                for w in &r.warnings {
                    println!("warning    {w}");
                }
            }
            Ok(exit::SUCCESS)
        }
        RunOutcome::Failed(f) => {
            if a.json {
                println!("{}", serde_json::to_string_pretty(&f).map_err(|e| Error::Internal(e.to_string()))?);
            }
            eprintln!("error: run failed ({}): {}", f.class.as_str(), f.reason);
            if a.out.is_none() && !f.log_tail.is_empty() {
                eprintln!("last lines of the log:\n{}", f.log_tail);
            }
            Ok(exit::RUNS_FAILED)
        }
        RunOutcome::Cancelled => Err(Error::Interrupted),
    }
}

fn contact(a: ContactArgs) -> Result<i32, Error> {
    let outcome = demsweep::contact::run(&a.case.case()?).map_err(contact_error)?;
    let json = serde_json::to_string_pretty(&outcome).map_err(|e| Error::Internal(e.to_string()))?;
    println!("{json}");
    Ok(exit::SUCCESS)
}

fn contact_check(a: ContactCheckArgs) -> Result<i32, Error> {
    use demsweep::contact::check;
    let cases =
        if a.case.given() { vec![("cli".to_string(), a.case.case()?)] } else { check::default_cases() };
    let report = check::run_cases(&cases, &a.engine, a.keep.as_deref()).map_err(contact_error)?;
    print!("{}", report.table());
    Ok(if report.passed() { exit::SUCCESS } else { exit::RUNS_FAILED })
}

/// Bad case parameters are input errors (exit 2); LIGGGHTS failures are engine errors (3).
fn contact_error(e: demsweep::contact::ContactError) -> Error {
    use demsweep::contact::ContactError as C;
    match e {
        C::Input { .. } | C::PassedThrough { .. } => Error::Input(e.to_string()),
        C::Engine(_) | C::Output { .. } => Error::Engine(e.to_string()),
        C::NoSeparation { .. } | C::Analysis(_) | C::Unsupported(_) | C::Io(_) => {
            Error::Internal(e.to_string())
        }
    }
}
