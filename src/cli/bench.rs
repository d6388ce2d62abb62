//! `sweep bench`: the fidelity, stability and contact benchmarks.

use std::path::PathBuf;

use super::error::{flag, on_interrupt_say, this_command};
use super::jobs;
use clap::{Args, Subcommand};
use demsweep::bench::BenchError;
use demsweep::error::Error;
use demsweep::point::{self, PointContext};
use demsweep::run::{self as driver, RunError};
use demsweep::sweep::Sweep;
use demsweep::sys::process::CancelToken;

#[derive(Subcommand)]
pub(super) enum BenchCommand {
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
    /// The designs against a known answer: `sweep adapt` against the LDS and the trapezoid
    /// lattice, runs needed until the answer is within tolerance of the truth.
    ///
    /// The surface is the stand-in engine's model over the sweep file's space, or with
    /// --replay RESULTS.csv a recorded sweep of that space replayed (an emulator of all its done
    /// runs; each run its mean plus noise at the SE of the nearest recorded run). The truth: the noiseless surface
    /// on 20,000 scrambled-Halton points. Targets: mean within 2 %, std within 3 %, skewness and
    /// kurtosis within 5 % of their scale, the first-order sensitivity ranking the truth's (every
    /// pair whose indices the truth tells apart, by non-overlapping 95 % intervals, in its order), the
    /// recommended run's true MFR within one SE of the truth's best. Runs in process (no sweep
    /// directory) with the functions the sweeps use; prints the tables of BENCHMARKS.md, and on
    /// stderr the time its emulator fits took ("emulator fits: N in T s of W s wall").
    Designs(DesignsArgs),
}

#[derive(Args)]
pub(super) struct DesignsArgs {
    /// The sweep file whose space is compared (the stand-in model over it, unless --replay).
    sweep: PathBuf,
    /// Replay these recorded runs instead: a results.csv of a sweep of this space (columns
    /// named as its parameters, status, mfr, mfr_se).
    #[arg(long)]
    replay: Option<PathBuf>,
    /// Seeds of the LDS and the adaptive design.
    #[arg(long, value_delimiter = ',', default_value = "14,15,16")]
    seeds: Vec<u64>,
    /// The adaptive design's first batch (default 10 per parameter), batch and max.
    #[arg(long)]
    first: Option<usize>,
    #[arg(long, default_value_t = 20)]
    batch: usize,
    #[arg(long, default_value_t = 240)]
    max: usize,
    /// The share of each adaptive batch placed for coverage (default: the design's).
    #[arg(long, default_value_t = demsweep::analysis::adapt::EXPLORE)]
    explore: f64,
    /// LDS checkpoints (runs).
    #[arg(long, value_delimiter = ',', default_value = "40,80,120,160,200,240,400,800,1600,2400")]
    lds: Vec<usize>,
    /// LDS checkpoints up to this many runs are also read through the emulator.
    #[arg(long, default_value_t = 800)]
    emulate_to: usize,
    /// Lattice levels (values per parameter).
    #[arg(long, value_delimiter = ',', default_value = "3,4,5,6,7")]
    levels: Vec<usize>,
    /// Every run's noise and SE times this: the runs of a sweep whose precision target is this
    /// fraction of the surface's (0.5: half the SE, for a measuring window four times as long).
    /// The targets stay those of the unscaled runs.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    noise_scale: f64,
    /// The adaptive design chooses each run's SE target (1, 1/2 or 1/4 of the sweep's) by the
    /// criterion's gain per CPU (a run at f times the target costs 0.73 + 0.27/f² of one at
    /// it); the tables then give each design's CPU in runs at the target.
    #[arg(long)]
    precision_per_run: bool,
}

pub(super) fn bench_designs(a: DesignsArgs) -> Result<(), Error> {
    use demsweep::bench::designs::{self, Plan, ReplaySurface, StandInSurface, Surface};
    if !(a.noise_scale > 0.0 && a.noise_scale.is_finite()) {
        return Err(flag("--noise-scale", format!("{} is not a positive number", a.noise_scale)));
    }
    let sweep = Sweep::load(&a.sweep)?;
    let surface: Box<dyn Surface> = match &a.replay {
        Some(csv) => {
            let (x, y, se) = replay_runs(&sweep, csv)?;
            let emulator =
                demsweep::analysis::emulator::Emulator::fit_censored(&x, &y, &se).ok_or_else(|| {
                    flag(
                        csv.display().to_string(),
                        "too few done runs to replay (or MFR the same everywhere)",
                    )
                })?;
            let recorded = x.into_iter().zip(se).filter_map(|(u, s)| Some((u, s?))).collect();
            Box::new(ReplaySurface { emulator, recorded })
        }
        None => Box::new(StandInSurface { sweep: sweep.clone() }),
    };
    let names: Vec<String> = sweep.names().iter().map(|s| s.to_string()).collect();
    let plan = Plan {
        seeds: a.seeds,
        first: a.first.unwrap_or(10 * names.len()),
        batch: a.batch.max(1),
        max: a.max,
        explore: a.explore,
        lds: a.lds,
        emulate_to: a.emulate_to,
        levels: a.levels,
        noise_scale: a.noise_scale,
        per_run: a.precision_per_run,
    };
    let scaled = designs::Scaled { inner: surface.as_ref(), scale: a.noise_scale };
    let started = std::time::Instant::now();
    let truth = designs::truth(&scaled, &names);
    let rows = designs::compare(&scaled, &names, &plan);
    print!("{}", designs::tables(&truth, &rows));
    let (fits, fit) = designs::fit_time();
    eprintln!(
        "emulator fits: {fits} in {:.2} s of {:.2} s wall",
        fit.as_secs_f64(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Unit points, MFR and SE of a set of runs.
type Runs = (Vec<Vec<f64>>, Vec<f64>, Vec<Option<f64>>);

/// The done runs (and screened zeros) of a results.csv as unit points, MFR and SE.
fn replay_runs(sweep: &Sweep, path: &std::path::Path) -> Result<Runs, Error> {
    let bad = |why: String| flag(path.display().to_string(), why);
    let mut r = csv::Reader::from_path(path).map_err(|e| bad(e.to_string()))?;
    let h = r.headers().map_err(|e| bad(e.to_string()))?.clone();
    let col = |n: &str| h.iter().position(|c| c == n).ok_or_else(|| bad(format!("no column `{n}`")));
    let names = sweep.names();
    let cols: Vec<usize> = names.iter().map(|n| col(n)).collect::<Result<_, _>>()?;
    let (status, mfr, se) = (col("status")?, col("mfr")?, col("mfr_se")?);
    let mut out = (Vec::new(), Vec::new(), Vec::new());
    for rec in r.records() {
        let rec = rec.map_err(|e| bad(e.to_string()))?;
        let y = match &rec[status] {
            "done" => rec[mfr].parse::<f64>().ok().filter(|v| v.is_finite()),
            "screened" => Some(0.0),
            _ => None,
        };
        let Some(y) = y else { continue };
        let values: Vec<f64> = cols.iter().map(|&c| rec[c].parse::<f64>().unwrap_or(f64::NAN)).collect();
        out.0.push(demsweep::sweep::space::unit_point(sweep, &values));
        out.1.push(y);
        out.2.push(rec[se].parse::<f64>().ok().filter(|v| v.is_finite() && *v >= 0.0));
    }
    Ok(out)
}

#[derive(Args)]
pub(super) struct FidelityArgs {
    sweep: PathBuf,
    /// Points of the draw.
    #[arg(long, default_value_t = 8)]
    points: usize,
    /// Pile seeds per point and variant (the sweep's scene.seed and the next ones), 1 to 1000.
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
pub(super) struct BenchContactArgs {
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

/// The ladders `sweep bench stability` runs.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum LadderChoice {
    Both,
    Timestep,
    Stiffness,
}

#[derive(Args)]
pub(super) struct StabilityArgs {
    sweep: PathBuf,
    /// Timestep ladder, fractions of the Rayleigh time, increasing, each in (0, 1] (default
    /// 0.2,0.3,0.4,0.5,0.6,0.8,1.0).
    #[arg(long, value_delimiter = ',')]
    fractions: Option<Vec<f64>>,
    /// Stiffness ladder, Young's modulus in MPa, decreasing, each in [5, 1000] (default: the
    /// corner's modulus halved down to 5).
    #[arg(long, value_delimiter = ',')]
    moduli: Option<Vec<f64>>,
    /// Pile seeds per level (the sweep's scene.seed and the next ones), 1 to 1000.
    #[arg(long, default_value_t = 3)]
    seeds: u64,
    /// Which ladder to run: both, or the timestep or the stiffness ladder alone.
    #[arg(long, value_enum, default_value = "both")]
    ladder: LadderChoice,
    /// Concurrent LIGGGHTS runs (default: the machine's cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Output directory (default: runs/<sweep name>-stability); must be new or empty.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// The stability and fidelity benches measure LIGGGHTS runs: a sweep on the stand-in is
/// refused by its key (it read "LIGGGHTS not found: stand-in is not a file").
fn refuse_stand_in(sweep: &Sweep, file: &std::path::Path) -> Result<(), Error> {
    if demsweep::run::standin::selected(sweep) {
        return Err(flag(
            file.display().to_string(),
            "run.engine = \"stand-in\": the benches measure LIGGGHTS runs, and the stand-in is a made-up model; \
             remove run.engine (liggghts on PATH) or give a LIGGGHTS executable",
        ));
    }
    Ok(())
}

pub(super) fn bench_fidelity(a: FidelityArgs) -> Result<(), Error> {
    use demsweep::bench::fidelity;
    let sweep = Sweep::load(&a.sweep)?;
    refuse_stand_in(&sweep, &a.sweep)?;
    if a.points == 0 {
        return Err(flag("--points 0", "expected at least 1"));
    }
    check_seeds(a.seeds)?;
    if a.points > MAX_POINTS {
        return Err(flag(format!("--points {}", a.points), format!("expected 1 to {MAX_POINTS}")));
    }
    let jobs = jobs(a.jobs)?;
    let variants = fidelity::variants(&sweep, &a.presets, &a.variant)?;
    if variants.is_empty() {
        return Err(flag("--presets", "expected at least one preset or --variant"));
    }
    let lds = &sweep.file.design.lds;
    let unit = demsweep::design::halton::halton(sweep.dim(), a.points, lds.scrambling, lds.seed);
    let points: Vec<Vec<f64>> = unit.iter().map(|p| demsweep::sweep::space::scale_point(&sweep, p)).collect();
    let out = a.out.unwrap_or_else(|| PathBuf::from("runs").join(format!("{}-fidelity", sweep.file.name)));
    driver::check_out_dir(&out)?;
    demsweep::sys::process::install_interrupt_handler();
    // The bench reads the runs it finds back: the same command goes on.
    let said = on_interrupt_say(format!(
        "the runs finished so far are kept in {}; `{}` goes on, reading them back",
        demsweep::sys::shell::quote_path(&out),
        this_command()
    ));
    let mut contexts = Vec::new();
    for v in &variants {
        contexts.push(PointContext::new(v.sweep.clone()).map_err(&said)?);
    }
    let plan = fidelity::FidelityPlan { points, seeds: a.seeds, jobs, out };
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
    let runs = fidelity::run(&variants, &contexts, &plan, &cancel, &show).map_err(&said)?;
    let find = |n: &str| variants.iter().position(|v| v.name == n);
    let (cells, summaries) =
        fidelity::analyse(&runs, &variants, plan.points.len(), find("reference"), find("thesis"));
    let names = sweep.names();
    let title = format!("{}: {} points × {} seeds", sweep.file.name, plan.points.len(), plan.seeds);
    let files = fidelity::write(&plan, &runs, &cells, &summaries, &variants, &names, &title)?;
    println!(
        "{:<14} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>7}",
        "variant", "cpu s/pt", "×thesis", "×ref", "worst|e|", "mean|e|", "noise", "vx err", "failed"
    );
    for m in &summaries {
        // Every measure but the worst v_x error (the CSV has it).
        let cells: String = m.measure_cells("-")[..6].iter().map(|c| format!(" {c:>9}")).collect();
        println!("{:<14} {:>9.2}{cells} {:>7}", variants[m.variant].name, m.cpu_per_point, m.failed);
    }
    for f in files {
        eprintln!("wrote {}", f.display());
    }
    Ok(())
}

/// Most pile seeds a bench runs per level or variant: each is a LIGGGHTS run, and more than this
/// is a slip (99999999999 asked for an 800 GB list before anything ran).
const MAX_SEEDS: u64 = 1000;
/// Most points of a fidelity bench's draw.
const MAX_POINTS: usize = 10_000;

fn check_seeds(seeds: u64) -> Result<(), Error> {
    if !(1..=MAX_SEEDS).contains(&seeds) {
        return Err(flag(format!("--seeds {seeds}"), format!("expected 1 to {MAX_SEEDS}")));
    }
    Ok(())
}

/// The default timestep ladder, fractions of the Rayleigh time.
const FRACTIONS: [f64; 7] = [0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0];

pub(super) fn bench_stability(a: StabilityArgs) -> Result<(), Error> {
    use demsweep::bench::stability;
    check_seeds(a.seeds)?;
    // A flag of the ladder that does not run would be ignored without a word.
    match (a.ladder, &a.fractions, &a.moduli) {
        (LadderChoice::Stiffness, Some(f), _) => {
            return Err(flag(
                format!("--fractions {}", list(f)),
                "only the timestep ladder reads it, and --ladder stiffness runs the stiffness ladder alone",
            ))
        }
        (LadderChoice::Timestep, _, Some(m)) => {
            return Err(flag(
                format!("--moduli {}", list(m)),
                "only the stiffness ladder reads it, and --ladder timestep runs the timestep ladder alone \
                 (at the corner's modulus)",
            ))
        }
        _ => {}
    }
    let fractions = a.fractions.unwrap_or_else(|| FRACTIONS.to_vec());
    let sweep = Sweep::load(&a.sweep)?;
    refuse_stand_in(&sweep, &a.sweep)?;
    if let Some(why) = demsweep::scenes::lookup(&sweep.file.scene.layout).and_then(|l| l.refuses_sweeps()) {
        let why = format!(
            "scene.layout = \"{}\": the stability bench compares MFR between levels, and {why}",
            sweep.file.scene.layout
        );
        return Err(flag(a.sweep.display().to_string(), why));
    }
    if sweep.file.scene.timestep_s > 0.0 {
        let why = format!(
            "scene.timestep_s = {} fixes the timestep (fidelity \"{}\"); the stability bench drives \
             scene.rayleigh_fraction, so use a fidelity without a fixed step (\"fast\" or \"reference\")",
            sweep.file.scene.timestep_s, sweep.file.scene.fidelity
        );
        return Err(flag(a.sweep.display().to_string(), why));
    }
    if fractions.is_empty() || fractions.iter().any(|f| !(f.is_finite() && *f > 0.0 && *f <= 1.0)) {
        return Err(flag(
            format!("--fractions {}", list(&fractions)),
            "expected fractions of the Rayleigh time in (0, 1]",
        ));
    }
    if fractions.windows(2).any(|w| w[1] <= w[0]) {
        return Err(flag(format!("--fractions {}", list(&fractions)), "expected increasing fractions"));
    }
    let corner = stability::harshest_corner(&sweep);
    let e0 = point::resolve(&sweep, &corner)["youngs_modulus"];
    let moduli = a.moduli.unwrap_or_else(|| stability::default_moduli(e0));
    if moduli.is_empty() || moduli.iter().any(|e| !(e.is_finite() && (5.0..=1000.0).contains(e))) {
        return Err(flag(format!("--moduli {moduli:?}"), "expected Young's moduli in [5, 1000] MPa"));
    }
    if moduli.windows(2).any(|w| w[1] >= w[0]) {
        return Err(flag(format!("--moduli {moduli:?}"), "expected decreasing moduli"));
    }
    let jobs = jobs(a.jobs)?;
    let out = a.out.unwrap_or_else(|| PathBuf::from("runs").join(format!("{}-stability", sweep.file.name)));
    driver::check_out_dir(&out)?;
    if std::fs::read_dir(&out).map(|mut d| d.next().is_some()).unwrap_or(false) {
        return Err(RunError::OutDir { dir: out, why: "not empty".into() }.into());
    }
    demsweep::sys::process::install_interrupt_handler();
    // A stability bench refuses a directory that is not empty: it starts again, it does not go on.
    let said = on_interrupt_say(format!(
        "the stability map was not written; its runs so far are in {0}, which a bench does not go on from: remove {0} and run `{1}` again",
        demsweep::sys::shell::quote_path(&out),
        this_command()
    ));
    let ctx = PointContext::new(sweep).map_err(&said)?;
    // Every level's scene must build (the bound aside) before anything is written.
    let plan = stability::StabilityPlan {
        corner,
        corner_youngs_mpa: e0,
        fractions,
        moduli,
        seeds: a.seeds,
        timestep_ladder: a.ladder != LadderChoice::Stiffness,
        stiffness_ladder: a.ladder != LadderChoice::Timestep,
        jobs,
        out,
    };
    stability::check(&ctx, &plan)?;
    let heading = stability::describe_corner(&ctx.sweep, &plan.corner);
    std::fs::create_dir_all(&plan.out)
        .map_err(|source| BenchError::Create { path: plan.out.clone(), source })?;
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
    let results = stability::run(&ctx, &plan, &cancel, &show).map_err(&said)?;
    let files = stability::write(&plan.out, &results, &format!("Stability map at {heading}"))?;
    let default = ctx.sweep.file.scene.rayleigh_fraction;
    let (safe, edge) = stability::edge(&results, "timestep");
    match (safe, edge) {
        _ if !plan.timestep_ladder => {}
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
        _ if !plan.stiffness_ladder => {}
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
    Ok(())
}

/// `10,5`: a list of a flag as written.
fn list(v: &[f64]) -> String {
    v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(",")
}

pub(super) fn bench_contact(a: BenchContactArgs) -> Result<(), Error> {
    use demsweep::bench::contact::{drift, stiffness, timestep, to_csv};
    if a.contacts == 0 {
        return Err(flag("--contacts 0", "expected at least 1"));
    }
    if a.out.exists() && !a.out.is_dir() {
        return Err(flag(format!("--out {}", a.out.display()), "not a directory"));
    }
    std::fs::create_dir_all(&a.out).map_err(|source| BenchError::Create { path: a.out.clone(), source })?;
    let write = |name: &str, text: String| -> Result<(), Error> {
        let path = a.out.join(name);
        demsweep::sys::atomic::write(&path, text.as_bytes())
            .map_err(|source| BenchError::Write { path: path.clone(), source })?;
        eprintln!("wrote {}", path.display());
        Ok(())
    };

    println!("Energy drift at e = 1 over {} contacts (E_N/E_0* = closed form)", a.contacts);
    let rows = drift::run(&drift::default_cases(), &drift::DEFAULT_LADDER, a.contacts)?;
    print!("{}", drift::table(&rows));
    write("contact-drift.csv", to_csv(&rows)?)?;

    println!("\nStiffness ratios (q = wall/particle modulus; errors against Hertz theory)");
    let rows = stiffness::run(&stiffness::PARTICLE_MODULI, &stiffness::RATIOS);
    print!("{}", stiffness::table(&rows));
    write("contact-stiffness.csv", to_csv(&rows)?)?;

    println!("\nTimestep ladder, reference solver against {}", a.engine.display());
    let rows = timestep::run(&timestep::default_cases(), &timestep::DEFAULT_LADDER, &a.engine)?;
    print!("{}", timestep::table(&rows));
    write("contact-timestep.csv", to_csv(&rows)?)?;
    if rows.iter().all(|r| r.liggghts_restitution_n.is_none()) {
        let first = rows.first().map_or("", |r| r.error.as_str());
        return Err(BenchError::NoLadderCase { first: first.to_string() }.into());
    }
    Ok(())
}
