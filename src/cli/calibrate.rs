//! `sweep calibrate`: the sweep file's free parameters fitted to measured targets.

use std::path::PathBuf;

use super::error::flag;
use super::{check_timestep, run_options, PoolArgs};
use clap::Args;
use demsweep::analysis::calibration::Target;
use demsweep::error::Error;
use demsweep::run::calibrate::{self as driver, CalibrationWatch, Settings};
use demsweep::run::{Summary, SweepDir};
use demsweep::store::DesignRecord;
use demsweep::sweep::Sweep;
use demsweep::sys::process::CancelToken;

#[derive(Args)]
pub(super) struct CalibrateArgs {
    /// The sweep file (TOML): its ranges in [parameters] are the free parameters, its fixed
    /// values and [scene] the rest of the test (e.g. layout "pour" for an angle of repose).
    sweep: PathBuf,
    /// A measured value to reproduce, NAME=VALUE±SD (or +-): angle_of_repose (degrees),
    /// bulk_packing or apparent_density (g/cm³, ASTM B212: the packing times the density) of a
    /// pour, mfr of a spreading layout. Repeat for several.
    #[arg(long = "target", required = true)]
    targets: Vec<String>,
    /// Settings of the first (scrambled-Halton) batch; default design.adapt.first, else 10 per
    /// free parameter.
    #[arg(long)]
    first: Option<usize>,
    /// Settings of every later batch; default design.adapt.batch, else --jobs.
    #[arg(long)]
    batch: Option<usize>,
    /// Most runs (settings × repeats) to run; default design.adapt.max.
    #[arg(long)]
    max: Option<usize>,
    /// Runs of each setting, each with its own scene.seed (the sweep's, then the next ones):
    /// their scatter is each run's noise in the emulator. Default 2 for a pour's targets (one
    /// heap's SE over its sectors understates the scatter between seeds), 1 for MFR.
    #[arg(long)]
    repeats: Option<usize>,
    /// Stop once no bound of a credible interval moves by more than this share of the
    /// interval's width from one batch to the next, --hold batches in a row.
    #[arg(long, default_value_t = driver::TOLERANCE)]
    tolerance: f64,
    #[arg(long, default_value_t = driver::HOLD)]
    hold: usize,
    /// Sweep directory (default: runs/<sweep name>). An existing one is continued.
    #[arg(long)]
    out: Option<PathBuf>,
    #[command(flatten)]
    pool: PoolArgs,
    #[arg(long, help = super::point::FORCE_HELP)]
    force: bool,
}

pub(super) fn calibrate(a: CalibrateArgs) -> Result<(), Error> {
    let mut targets = Vec::new();
    for t in &a.targets {
        targets.push(Target::parse(t).map_err(|why| flag(format!("--target {t}"), why.to_string()))?);
    }
    let mut sweep = Sweep::load(&a.sweep)?;
    check_timestep(&mut sweep, a.force)?;
    driver::check(&sweep, &targets).map_err(|why| flag("sweep calibrate", why))?;
    if !(a.tolerance.is_finite() && a.tolerance > 0.0) {
        return Err(flag(format!("--tolerance {}", a.tolerance), "expected a positive share, e.g. 0.1"));
    }
    if a.hold == 0 {
        return Err(flag("--hold 0", "expected at least 1 batch"));
    }
    let opts = run_options(&a.pool, false, false)?;
    let ad = &sweep.file.design.adapt;
    let file = a.sweep.display();
    let first = a.first.unwrap_or(if ad.first > 0 { ad.first } else { 10 * sweep.dim() });
    let max = a.max.unwrap_or(ad.max);
    let batch = a.batch.unwrap_or(if ad.batch > 0 { ad.batch } else { opts.jobs });
    if first == 0 {
        return Err(flag("--first 0", "expected a positive number of points"));
    }
    if batch == 0 {
        return Err(flag("--batch 0", "expected a positive number of points per batch"));
    }
    let repeats = a.repeats.unwrap_or_else(|| driver::default_repeats(&targets));
    if repeats == 0 {
        return Err(flag("--repeats 0", "expected at least 1 run per setting"));
    }
    // A first batch past what any sweep runs is named by its own flag, not by the max.
    let runs = first.saturating_mul(repeats);
    demsweep::design::lds_size(runs).map_err(|e| {
        let flag_name = if a.first.is_some() {
            format!("--first {first}")
        } else {
            format!("design.adapt.first {first}")
        };
        flag(format!("{flag_name} (× {repeats} repeats)"), e)
    })?;
    let max_src = if a.max.is_some() { "--max".to_string() } else { format!("design.adapt.max in {file}") };
    demsweep::design::lds_size(max).map_err(|e| flag(format!("{max_src} {max}"), e))?;
    if max < first * repeats {
        return Err(flag(
            format!("{max_src} {max} is less than the first batch, {first} settings × {repeats} repeats"),
            "expected max ≥ first × repeats; lower --first or --repeats, or raise --max",
        ));
    }
    let settings = Settings { targets, tolerance: a.tolerance, hold: a.hold };
    let design = DesignRecord::Adapt { first, batch, max, seed: ad.seed, repeats };
    let out = a.out.unwrap_or_else(|| demsweep::run::default_out(&sweep));
    demsweep::run::check_out_dir(&out)?;
    demsweep::sys::process::install_interrupt_handler();
    let mut watch = CalibrationWatch::new(&sweep, settings.clone(), ad.seed);
    let cancel = CancelToken::new();
    let exec = driver::executor(&sweep)?;
    let summary =
        driver::start(SweepDir::new(&sweep, design, &out), &settings, &exec, &opts, &mut watch, &cancel)?;
    finish(&summary)
}

/// `sweep resume DIR` of a calibration directory.
pub(super) fn resume(
    dir: &std::path::Path,
    opts: &demsweep::run::RunOptions,
    settings: Settings,
) -> Result<(), Error> {
    let mut sweep = demsweep::run::load_dir_sweep(dir)?;
    sweep.file.scene.force_bounds = opts.force;
    demsweep::sys::process::install_interrupt_handler();
    let (manifest, _) = demsweep::store::Store::read_manifest(dir)?;
    let DesignRecord::Adapt { seed, .. } = manifest.design else {
        return Err(flag(
            dir.display().to_string(),
            "holds calibration.json but is not a calibration's directory",
        ));
    };
    let mut watch = CalibrationWatch::new(&sweep, settings, seed);
    let exec = driver::executor(&sweep)?;
    let summary = demsweep::run::batches::run(dir, &exec, opts, &mut watch, &CancelToken::new())?;
    finish(&summary)
}

/// Write the calibration's report, print its answer, and say what to do about the runs.
fn finish(s: &Summary) -> Result<(), Error> {
    let dir = demsweep::sys::shell::quote_path(&s.dir).into_owned();
    // Told to stop: stop now, and leave the report of what is done to `sweep report`.
    if !s.interrupted {
        demsweep::sys::process::on_interrupt_say(format!(
            "the runs are kept; the report was not finished: `sweep report {dir}` writes it"
        ));
        let c = demsweep::report::calibration::write(&s.dir)?;
        for line in c.lines() {
            println!("{line}");
        }
    }
    super::say_unfinished(s, &dir, "", " (left out of the posterior)");
    s.ended()
}

/// `sweep report DIR` of a calibration directory.
pub(super) fn report(dir: &std::path::Path, json: bool) -> Result<(), Error> {
    let c = demsweep::report::calibration::write(dir)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&c).map_err(super::error::CliError::Json)?);
    } else {
        for line in c.lines() {
            println!("{line}");
        }
    }
    Ok(())
}
