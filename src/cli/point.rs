//! `sweep points`, `render` and `run`: a design printed, and one point rendered or run.

use std::io::Write;
use std::path::PathBuf;

use super::check_timestep;
use super::error::{flag, CliError};
use super::pass_watch::PassWatch;
use clap::Args;
use demsweep::error::Error;
use demsweep::outcome::RunOutcome;
use demsweep::point::{self, PointContext, PointError};
use demsweep::sweep::{Scrambling, Sweep};

#[derive(Args)]
pub(super) struct PointsArgs {
    /// The sweep file (TOML) whose design to print.
    sweep: PathBuf,
    /// A lattice with L values per dimension (L^d points). Without --lattice or --lds: the
    /// sweep file's design as `sweep lds` runs it (design.lds.max points).
    #[arg(long, value_name = "L", conflicts_with = "lds")]
    lattice: Option<usize>,
    /// The first N points of the Halton sequence, scrambled as design.lds.scrambling says.
    /// Plain and Braaten–Weller Halton skip index 0 (the origin: every parameter at lo), so
    /// their first row is index 1; random scrambling starts at index 0, which it maps to a
    /// random point like any other (as scipy's Halton does). Every prefix is a design.
    #[arg(long, value_name = "N")]
    lds: Option<usize>,
    /// Plain Halton, no digit scrambling (overrides design.lds.scrambling).
    #[arg(long, conflicts_with = "lattice")]
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
pub(super) struct RenderArgs {
    /// The sweep file (TOML) whose scene and parameters the point takes.
    sweep: PathBuf,
    /// Any parameter's value, e.g. --set gap=3,diameter=1.2 (mm, m/s, MPa as in the sweep
    /// file's catalogue); swept parameters not set take the middle of their range.
    #[arg(long, value_delimiter = ',', value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Directory to write in.liggghts, blade.stl and pile.data into.
    #[arg(long)]
    out: PathBuf,
    #[arg(long, help = FORCE_HELP)]
    force: bool,
}

/// `--force` of every command that builds points.
pub(crate) const FORCE_HELP: &str =
    "Run points outside the bounds the scene is built for: a timestep above 0.5 \
     Rayleigh times (the measured safe bound, BENCHMARKS.md \"Stability edge\") or below 0.01, \
     more than 200,000 particles, a mean diameter below 10 µm or above 20 mm, a gap below 0.1 D, \
     a blade speed outside 0.001–10 m/s, a density outside 100–25,000 kg/m³.";

#[derive(Args)]
pub(super) struct RunArgs {
    /// The sweep file (TOML) whose scene and parameters the point takes.
    sweep: PathBuf,
    /// Any parameter's value, e.g. --set gap=3,diameter=1.2 (mm, m/s, MPa as in the sweep
    /// file's catalogue); swept parameters not set take the middle of their range.
    #[arg(long, value_delimiter = ',', value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Print result.json instead of a summary.
    #[arg(long)]
    json: bool,
    /// Keep the run directory here (default: a temporary directory, removed afterwards).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also write VTK files for ParaView in the run directory, every 0.02 s of the spread:
    /// particles_<step>.vtk (every particle: id, type, position, velocity, radius, mass; show
    /// with a Glyph filter scaled by radius) and blade_<step>.vtk (the blade mesh). Needs --out.
    #[arg(long, requires = "out")]
    vtk: bool,
    #[arg(long, help = FORCE_HELP)]
    force: bool,
    /// Run the point with N scene seeds (the file's `[scene] seed` and the N − 1 after it), one
    /// after another, and print each seed's MFR ± SE and their mean with the SE between seeds:
    /// the uncertainty to quote where a run's own SE falls short (slow blades with a cohesive
    /// powder, docs/statistics.md). With --out, each seed's run is kept in <OUT>/seed-<SEED>.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=100), conflicts_with = "vtk")]
    seeds: Option<u32>,
}

pub(super) fn points(a: PointsArgs) -> Result<(), Error> {
    let sweep = Sweep::load(&a.sweep)?;
    let unit = match (a.lattice, a.lds) {
        (Some(l), _) => {
            demsweep::design::lattice_size(sweep.dim(), l).map_err(|e| flag(format!("--lattice {l}"), e))?;
            demsweep::design::lattice::lattice(sweep.dim(), l)
        }
        (None, n) => {
            let lds = &sweep.file.design.lds;
            let n = n.unwrap_or(lds.max);
            demsweep::design::lds_size(n).map_err(|e| flag(format!("--lds {n}"), e))?;
            let scrambling = if a.no_scramble { Scrambling::None } else { lds.scrambling };
            demsweep::design::halton::halton(sweep.dim(), n, scrambling, lds.seed)
        }
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
        // The write's own error, so that a closed pipe stays one.
        let io = |e: csv::Error| match e.into_kind() {
            csv::ErrorKind::Io(e) => e,
            other => std::io::Error::other(format!("{other:?}")),
        };
        let mut w = csv::Writer::from_writer(out);
        let extra = screen.as_ref().map(|_| "screen");
        w.write_record(sweep.names().into_iter().chain(extra)).map_err(io)?;
        for (k, v) in values.iter().enumerate() {
            // 12 significant digits: every digit a design has, without float noise.
            let row = v.iter().map(|v| demsweep::scene::plausible::round_to(*v, 12));
            let extra = screen.as_ref().map(|c| c[k].to_string());
            w.write_record(row.chain(extra)).map_err(io)?;
        }
        w.flush()
    };
    match write(&mut out) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(e.into()),
    }
}

pub(super) fn render(a: RenderArgs) -> Result<(), Error> {
    let sweep = Sweep::load(&a.sweep)?;
    let (mut sweep, values, notes) = point::with_set(&sweep, &a.set)?;
    check_timestep(&mut sweep, a.force)?;
    if a.out.exists() && !a.out.is_dir() {
        return Err(flag(format!("--out {}", a.out.display()), "exists and is not a directory"));
    }
    check_bounds(&sweep, &values, &a.set)?;
    let ctx = PointContext::new(sweep)?;
    let prepared = prepare_set(&ctx, &values, &a.set)?;
    notes.iter().for_each(|n| eprintln!("note: {n}"));
    std::fs::create_dir_all(&a.out)
        .and_then(|_| prepared.deck.write(&a.out))
        .map_err(|source| CliError::WriteTo { path: a.out.clone(), source })?;
    let s = &prepared.scene;
    eprintln!(
        "wrote {}/{{{}}}: {} on {} substrate spheres, dt = {:.3e} s, hash {}",
        a.out.display(),
        prepared.deck.file_names().join(","),
        ctx.layout.what_runs(s),
        s.substrate().map_or(0, |sub| sub.substrate_particles),
        s.timestep,
        &prepared.hash[..16]
    );
    Ok(())
}

/// [`point::prepare`], with a refusal that names the `--set` it came with.
fn prepare_set(
    ctx: &PointContext,
    values: &[f64],
    set: &[String],
) -> Result<point::Prepared, point::PointError> {
    point::prepare(ctx, values).map_err(|e| if set.is_empty() { e } else { e.with_set(&ctx.sweep.path, set) })
}

pub(super) fn run_one(a: RunArgs) -> Result<(), Error> {
    demsweep::sys::process::install_interrupt_handler();
    let file_sweep = Sweep::load(&a.sweep)?;
    let (mut sweep, values, notes) = point::with_set(&file_sweep, &a.set)?;
    check_timestep(&mut sweep, a.force)?;
    sweep.file.scene.vtk = a.vtk;
    if let Some(out) = a.out.as_ref().filter(|o| o.exists() && !o.is_dir()) {
        return Err(flag(format!("--out {}", out.display()), "exists and is not a directory"));
    }
    // The point's bounds before the engine is looked for: a unit slip is bad input (exit 2)
    // whether or not LIGGGHTS is installed.
    let scene = check_bounds(&sweep, &values, &a.set)?;
    if let Some(n) = a.seeds {
        notes.iter().for_each(|n| eprintln!("note: {n}"));
        return run_seeds(&a, &file_sweep, &sweep, &values, n);
    }
    let standin = demsweep::run::standin::selected(&sweep);
    let ctx = if standin { None } else { Some(PointContext::new(sweep.clone())?) };
    let prepared = ctx.as_ref().map(|c| prepare_set(c, &values, &a.set)).transpose()?;
    // The stand-in checks its template here, before a line says it runs.
    let standin_exec =
        if standin { Some(demsweep::run::standin::StandIn::new(sweep.clone())?) } else { None };
    notes.iter().for_each(|n| eprintln!("note: {n}"));
    let temp;
    let dir = match &a.out {
        Some(d) => {
            std::fs::create_dir_all(d).map_err(|source| CliError::Create { path: d.clone(), source })?;
            d.clone()
        }
        None => {
            temp = tempfile::Builder::new().prefix("sweep-run-").tempdir()?;
            temp.path().to_path_buf()
        }
    };
    if !a.json {
        if standin {
            eprintln!("running the stand-in engine (a made-up model, not LIGGGHTS) in {}", dir.display());
        } else {
            let what = match &ctx {
                Some(c) => c.layout.what_runs(&scene),
                None => String::new(),
            };
            eprintln!("running {what} (dt = {:.3e} s) in {}", scene.timestep, dir.display());
        }
        if scene.nothing_passes() {
            eprintln!("the screen closes this point: nothing can pass under the blade (a sweep counts it as MFR = 0)");
        }
    }
    // Said once on Ctrl-C: what is kept and what goes on.
    let said = super::error::on_interrupt_say(match &a.out {
        Some(d) => format!(
            "{} is kept: the same command again goes on from its last finished pass (a layers point) or runs the point again",
            d.display()
        ),
        None => "nothing is kept (no --out): the same command runs the point again".into(),
    });
    let cancel = demsweep::sys::process::CancelToken::new();
    let watch = match (&ctx, &prepared) {
        (Some(c), Some(p)) if !a.json => {
            c.layout.by_pass(&p.scene).map(|by| PassWatch::start(&dir, &p.hash, by))
        }
        _ => None,
    };
    let outcome = match (&ctx, &prepared) {
        (Some(ctx), Some(p)) => point::execute(ctx, p, &dir, &cancel),
        _ => {
            use demsweep::run::pool::Executor;
            let exec = standin_exec.expect("the stand-in when no LIGGGHTS context");
            exec.execute(&exec.prepare(&values)?, &dir, &cancel)
        }
    };
    // Its last pass said before the result.
    drop(watch);
    match outcome {
        RunOutcome::Done(r) => {
            if a.json {
                println!("{}", serde_json::to_string_pretty(&r).map_err(CliError::Json)?);
            } else {
                println!("{}", used_line(&file_sweep, &a.set, &r));
                // The layout's own lines (a pour's angle of repose), on the stand-in as on LIGGGHTS.
                let own = demsweep::scenes::lookup(&sweep.file.scene.layout).and_then(|l| l.result_lines(&r));
                print_result(&r, &scene, own);
            }
            if a.vtk {
                eprintln!("ParaView: open {}/particles_*.vtk and blade_*.vtk", dir.display());
            }
            Ok(())
        }
        RunOutcome::Failed(f) => {
            if a.json {
                println!("{}", serde_json::to_string_pretty(&f).map_err(CliError::Json)?);
            }
            eprintln!("error: run failed ({}): {}", f.class.as_str(), f.reason);
            if a.out.is_none() && !f.log_tail.is_empty() {
                eprintln!("last lines of the log:\n{}", f.log_tail);
            }
            Err(Error::RunsFailed { failed: 1, total: 1 })
        }
        RunOutcome::Cancelled => Err(said(Error::Interrupted)),
    }
}

/// One seed of `sweep run --seeds`, ready to run.
enum SeedRun<'a> {
    StandIn(&'a demsweep::run::standin::StandIn, demsweep::run::standin::StandInJob),
    Engine(Box<PointContext>, Box<point::Prepared>),
}

impl SeedRun<'_> {
    fn execute(&self, dir: &std::path::Path, cancel: &demsweep::sys::process::CancelToken) -> RunOutcome {
        use demsweep::run::pool::Executor;
        match self {
            SeedRun::StandIn(exec, job) => exec.execute(job, dir, cancel),
            SeedRun::Engine(ctx, prepared) => point::execute(ctx, prepared, dir, cancel),
        }
    }
}

/// `sweep run --seeds N`: the point with N scene seeds, one after another; each seed's answer
/// (MFR, or its layout's own quantity), and their mean with the SE between seeds. A failed seed
/// is named and left out of the mean.
fn run_seeds(a: &RunArgs, file_sweep: &Sweep, sweep: &Sweep, values: &[f64], n: u32) -> Result<(), Error> {
    use demsweep::run::pool::Executor;
    let base = sweep.file.scene.seed;
    let kind = demsweep::report::answer_kind(&sweep.file.scene);
    let seeds: Vec<u64> = (0..n as u64).map(|k| base + k).collect();
    // Each seed from rest at the file's own precision, as `sweep run` runs one point: not the
    // sweep executor, which would warm-start a seed from another's state or settle a sweep's
    // precision from the seeds' directories.
    let standin = demsweep::run::standin::selected(sweep);
    let standin_exec =
        if standin { Some(demsweep::run::standin::StandIn::new(sweep.clone())?) } else { None };
    let mut runs = Vec::new();
    for &seed in &seeds {
        match &standin_exec {
            Some(exec) => runs.push(SeedRun::StandIn(exec, exec.prepare_seeded(values, Some(seed))?)),
            None => {
                let mut own = sweep.clone();
                own.file.scene.seed = seed;
                let ctx = PointContext::new(own)?;
                let prepared = prepare_set(&ctx, values, &a.set)?;
                runs.push(SeedRun::Engine(Box::new(ctx), Box::new(prepared)));
            }
        }
    }
    let temp;
    let root = match &a.out {
        Some(d) => d.clone(),
        None => {
            temp = tempfile::Builder::new().prefix("sweep-run-").tempdir()?;
            temp.path().to_path_buf()
        }
    };
    let cancel = demsweep::sys::process::CancelToken::new();
    let mut done = Vec::new();
    for (seed, run) in seeds.iter().zip(&runs) {
        let dir = root.join(format!("seed-{seed}"));
        std::fs::create_dir_all(&dir).map_err(|source| CliError::Create { path: dir.clone(), source })?;
        if !a.json {
            eprintln!("seed {seed}: running in {}", dir.display());
        }
        match run.execute(&dir, &cancel) {
            RunOutcome::Done(r) => {
                if !a.json {
                    let se = r.answer.se.map_or(String::new(), |se| format!(" ± {se:.4} (SE)"));
                    println!("seed {seed}: {} {:.4}{se}", kind.words(), r.answer.value);
                }
                done.push((*seed, r));
            }
            RunOutcome::Failed(f) => {
                eprintln!("seed {seed}: run failed ({}): {}", f.class.as_str(), f.reason)
            }
            RunOutcome::Cancelled => return Err(Error::Interrupted),
        }
    }
    let failed = seeds.len() - done.len();
    // Mean, SD (divisor k − 1) and the SE of the mean, over the seeds that finished: two at least.
    let mfr: Vec<f64> = done.iter().map(|(_, r)| r.answer.value).collect();
    let k = mfr.len() as f64;
    let between = (mfr.len() >= 2).then(|| {
        let mean = mfr.iter().sum::<f64>() / k;
        let sd = (mfr.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
        (mean, sd, sd / k.sqrt())
    });
    if a.json {
        let runs: Vec<&demsweep::outcome::RunResult> = done.iter().map(|(_, r)| r).collect();
        // Named for the answer: `mfr_mean`, `relative_density_mean`, ….
        let key = kind.key();
        let mut summary = serde_json::Map::new();
        summary.insert("seeds".into(), serde_json::json!(done.iter().map(|(s, _)| s).collect::<Vec<_>>()));
        summary.insert(format!("{key}_mean"), serde_json::json!(between.map(|b| b.0)));
        summary.insert(format!("{key}_sd_between_seeds"), serde_json::json!(between.map(|b| b.1)));
        summary.insert(format!("{key}_se_between_seeds"), serde_json::json!(between.map(|b| b.2)));
        summary.insert("failed".into(), serde_json::json!(failed));
        summary.insert("runs".into(), serde_json::to_value(&runs).map_err(CliError::Json)?);
        println!("{}", serde_json::to_string_pretty(&summary).map_err(CliError::Json)?);
    } else if let Some((mean, sd, se)) = between {
        println!("{}", used_line(file_sweep, &a.set, &done[0].1));
        let own: Vec<f64> = done.iter().filter_map(|(_, r)| r.answer.se).collect();
        let own_mean = own.iter().sum::<f64>() / own.len().max(1) as f64;
        let ratio = if own_mean > 0.0 {
            format!("; SD between seeds / their mean SE {:.2}", sd / own_mean)
        } else {
            String::new()
        };
        println!(
            "mean of {} seeds: {} {mean:.4} ± {se:.4} (SE between seeds; SD {sd:.4}){ratio}",
            done.len(),
            kind.words()
        );
    }
    if between.is_none() {
        eprintln!("error: {} of {} seeds done: a scatter between seeds needs two", done.len(), seeds.len());
    }
    if failed > 0 {
        return Err(Error::RunsFailed { failed, total: seeds.len() });
    }
    Ok(())
}

/// The scene of the point, or the refusal of a value outside its bounds, naming the `--set`.
fn check_bounds(sweep: &Sweep, values: &[f64], set: &[String]) -> Result<demsweep::scene::Scene, PointError> {
    let parameters = point::resolve(sweep, values);
    demsweep::scenes::build(&parameters, &sweep.file.scene).map_err(|source| {
        let e = PointError::Scene { path: sweep.path.clone(), source };
        if set.is_empty() {
            e
        } else {
            e.with_set(&sweep.path, set)
        }
    })
}

/// `point      gap = 3 mm (--set), blade_speed = 1.4 m/s (middle of 1.2–1.6)`: the swept
/// parameters the run used and where each value came from, and any other `--set`.
fn used_line(file_sweep: &Sweep, set: &[String], r: &demsweep::outcome::RunResult) -> String {
    use demsweep::scene::plausible::show;
    use demsweep::sweep::ParamKind;
    let given: Vec<&str> = set.iter().filter_map(|s| s.split_once('=')).map(|(n, _)| n.trim()).collect();
    let value = |name: &str, unit: &str| {
        let v = r.parameters.get(name).map_or("?".to_string(), |v| show(*v));
        if unit == "-" {
            format!("{name} = {v}")
        } else {
            format!("{name} = {v} {unit}")
        }
    };
    let mut parts: Vec<String> = file_sweep
        .swept
        .iter()
        .map(|p| match p.kind {
            _ if given.contains(&p.name.as_str()) => format!("{} (--set)", value(&p.name, p.unit)),
            ParamKind::Swept { lo, hi, .. } => {
                format!("{} (middle of {}–{})", value(&p.name, p.unit), show(lo), show(hi))
            }
            ParamKind::Fixed(_) => value(&p.name, p.unit),
        })
        .collect();
    for name in given.iter().filter(|n| !file_sweep.swept.iter().any(|p| p.name == **n)) {
        let unit = demsweep::scene::params::lookup(name).map_or("", |i| i.unit);
        parts.push(format!("{} (--set)", value(name, unit)));
    }
    format!("point      {}; the others as in {}", parts.join(", "), file_sweep.path.display())
}

/// A finished point for the terminal: MFR with its standard error, v_x by height, the run.
fn print_result(r: &demsweep::outcome::RunResult, scene: &demsweep::scene::Scene, own: Option<Vec<String>>) {
    own.iter().flatten().for_each(|line| println!("{line}"));
    if own.is_none() {
        print_flow(r, scene);
    }
    println!(
        "particles  {}   steps {}   simulated {:.4} s   wall {:.1} s",
        r.particles, r.steps, r.simulated_time, r.wall_time
    );
    if let Some(z) = &r.sizes {
        let um = |m: f64| format!("{:.1}", m * 1e6);
        let fit = z
            .fit_residual
            .map_or(String::new(), |f| format!("; the lognormal misses the datasheet by {:.1} %", f * 100.0));
        println!(
            "sizes      D10/D50/D90 {}/{}/{} µm by volume, mean {} µm by number, span {:.2}, {} classes{fit}",
            um(z.d10),
            um(z.d50),
            um(z.d90),
            um(z.mean_diameter),
            z.span,
            z.classes
        );
    }
    let mut notes: Vec<&str> = Vec::new();
    for w in &r.warnings {
        match demsweep::engine::chatter(w) {
            Some(note) if !notes.contains(&note) => notes.push(note),
            Some(_) => {}
            None => println!("warning    {w}"),
        }
    }
    for n in notes {
        println!("note       {n}");
    }
}

/// MFR and the v_x profile of a spreading layout's result.
fn print_flow(r: &demsweep::outcome::RunResult, scene: &demsweep::scene::Scene) {
    let se = r.answer.se.map_or(String::new(), |se| format!(" ± {se:.4} (SE)"));
    println!(
        "MFR        {:.4}{se}  ({} particles; flux cross-check {:.4}, {})",
        r.answer.value,
        r.answer_particles,
        r.mfr_flux,
        if r.steady { "steady" } else { "NOT steady" }
    );
    let cell = |s: String| format!("{s:>6}");
    let heights: Vec<String> = (1..=r.vx.len())
        .map(|k| cell(scene.layer_height(k).map_or("-".into(), |z| format!("{:.2}", z * 1e3))))
        .collect();
    let vx: Vec<String> =
        r.vx.iter().map(|v| cell(v.map(|v| format!("{v:.3}")).unwrap_or_else(|| "-".into()))).collect();
    println!("v_x in front of the blade, layer k at z = gap + k·D/2 above the plate:");
    println!("  z (mm)     {}", heights.join(" "));
    println!("  v_x (m/s)  {}", vx.join(" "));
}
