//! One design point end to end: values → scene → deck → LIGGGHTS → dump → metrics → result.json.
//!
//! [`prepare`] is pure and fast (render and hash in memory); [`execute`] does the I/O and the
//! run in a directory it is given. The pool calls both; `sweep render` and `sweep run` too.

pub mod deck;

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;

use crate::engine::{Engine, LogLimits, RunStatus};
use crate::error::{hint, Error, Result};
use crate::measure::metrics::Frame;
use crate::measure::{layer, metrics, plausible, steady};
use crate::outcome::{FailureClass, RunFailure, RunOutcome, RunResult, RESULT_FORMAT};
use crate::point::deck::{Deck, Template};
use crate::scene::{mesh, params, Scene};
use crate::sweep::{ParamKind, Parameter, Sweep};
use crate::sys::atomic::write_json;
use crate::sys::process::CancelToken;

/// File names in a run directory.
pub const RESULT: &str = "result.json";
pub const FAILURE: &str = "failure.json";
pub const DUMP: &str = "dump.spread";
/// The conveyor's one snapshot of the deposit behind the blade at the end.
pub const STRIP_DUMP: &str = "dump.strip";

/// What every point of a sweep shares: the sweep, the engine, the template.
pub struct PointContext {
    pub sweep: Sweep,
    pub engine: Engine,
    pub template: Template,
    pub timeout: Duration,
}

impl PointContext {
    pub fn new(sweep: Sweep) -> Result<PointContext> {
        // The template first: a bad one is bad input, found before the engine is run.
        let template =
            Template::load(sweep.template_path().as_deref()).map_err(|e| Error::input(e.to_string()))?;
        // Under the process's interrupt flag (Ctrl-C, SIGTERM), like every run.
        let engine =
            Engine::locate(sweep.file.run.engine.as_deref(), &CancelToken::new()).map_err(|e| match e {
                crate::engine::EngineError::Interrupted => Error::Interrupted,
                e => Error::Engine(e.to_string()),
            })?;
        let timeout = Duration::from_secs_f64(sweep.file.run.timeout_s);
        Ok(PointContext { sweep, engine, template, timeout })
    }

    /// What a run's outcome depends on besides its parameters: for the manifest, and for
    /// refusing to resume a sweep whose template, mesh or engine changed.
    pub fn identity(&self) -> serde_json::Value {
        serde_json::json!({
            "template_hash": self.template.hash(),
            "mesh_version": mesh::MESH_VERSION,
            "engine_path": self.engine.path.display().to_string(),
            "engine_version": self.engine.version,
            "engine_sha256": self.engine.binary_hash,
        })
    }
}

/// A point ready to run: its scene, deck and hash.
#[derive(Debug, Clone)]
pub struct Prepared {
    pub hash: String,
    /// Every catalogue parameter, in catalogue units.
    pub parameters: BTreeMap<String, f64>,
    pub scene: Scene,
    pub deck: Deck,
}

/// All catalogue parameters for a point: defaults, then the sweep's fixed values, then the
/// swept values (in file order, sweep units).
pub fn resolve(sweep: &Sweep, swept_values: &[f64]) -> BTreeMap<String, f64> {
    let mut values: BTreeMap<String, f64> =
        params::CATALOGUE.iter().map(|p| (p.name.to_string(), p.default)).collect();
    for p in &sweep.fixed {
        if let ParamKind::Fixed(v) = p.kind {
            values.insert(p.name.clone(), v);
        }
    }
    for (p, v) in sweep.swept.iter().zip(swept_values) {
        values.insert(p.name.clone(), *v);
    }
    values
}

/// A catalogue parameter the design does not sweep, as every point of the sweep uses it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FixedValue {
    pub name: String,
    pub value: f64,
    pub unit: &'static str,
    /// True when the sweep file sets it; false for the catalogue's default.
    pub written: bool,
    pub description: &'static str,
}

/// Every catalogue parameter the sweep does not sweep, in catalogue order: the sweep file's
/// value where it gives one, else the default (which the user may never have written).
pub fn fixed_values(sweep: &Sweep) -> Vec<FixedValue> {
    params::CATALOGUE
        .iter()
        .filter(|p| !sweep.swept.iter().any(|s| s.name == p.name))
        .map(|p| {
            let written = sweep.fixed.iter().find_map(|f| match f.kind {
                ParamKind::Fixed(v) if f.name == p.name => Some(v),
                _ => None,
            });
            FixedValue {
                name: p.name.to_string(),
                value: written.unwrap_or(p.default),
                unit: p.unit,
                written: written.is_some(),
                description: p.description,
            }
        })
        .collect()
}

/// [`fixed_values`] as results.csv's columns: (name, value).
pub fn fixed_columns(sweep: &Sweep) -> Vec<(String, f64)> {
    fixed_values(sweep).into_iter().map(|f| (f.name, f.value)).collect()
}

/// One point of `sweep run` / `render`: `--set name=value,...` may set any catalogue parameter
/// (each once, in its catalogue unit, inside its physical domain). A set parameter becomes fixed
/// at its value; the swept parameters not set take the middle of their range. Returns the sweep
/// so changed, its swept values, and a note for each value outside the sweep's own range.
pub fn with_set(sweep: &Sweep, sets: &[String]) -> Result<(Sweep, Vec<f64>, Vec<String>)> {
    let mut out = sweep.clone();
    let mut seen: Vec<(String, String)> = Vec::new();
    let mut notes = Vec::new();
    for item in sets.iter().filter(|s| !s.trim().is_empty()) {
        if item.chars().any(char::is_control) {
            return Err(Error::input(format!(
                "--set {item:?}: expected name=value without control characters (newline, tab)"
            )));
        }
        let (name, value) =
            item.split_once('=').ok_or_else(|| Error::input(format!("--set {item}: expected name=value")))?;
        let (name, value) = (name.trim(), value.trim());
        let Some(info) = params::lookup(name) else {
            let known: Vec<&str> = params::CATALOGUE.iter().map(|p| p.name).collect();
            return Err(Error::input(format!(
                "--set {name}: unknown parameter{}; known: {}",
                hint(name, known.iter().copied()),
                known.join(", ")
            )));
        };
        if let Some((_, first)) = seen.iter().find(|(n, _)| n == name) {
            return Err(Error::input(format!(
                "--set {name}: given twice ({first} and {value}); give each parameter once"
            )));
        }
        let v: f64 = value
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| Error::input(format!("--set {name}={value}: expected a finite number")))?;
        if !info.accepts(v) {
            return Err(Error::input(format!("--set {name}={value}: outside {}", info.domain())));
        }
        seen.push((name.to_string(), value.to_string()));
        if let Some(p) = out.swept.iter().find(|p| p.name == name) {
            if let ParamKind::Swept { lo, hi, .. } = p.kind {
                if v < lo || v > hi {
                    notes.push(format!(
                        "--set {name}={value}: outside the sweep's range [{lo}, {hi}] {}",
                        info.unit
                    ));
                }
            }
        }
        out.swept.retain(|p| p.name != name);
        out.fixed.retain(|p| p.name != name);
        out.fixed.push(Parameter { name: name.to_string(), unit: info.unit, kind: ParamKind::Fixed(v) });
    }
    let values = out
        .swept
        .iter()
        .map(|p| match p.kind {
            ParamKind::Swept { lo, hi, .. } => 0.5 * (lo + hi),
            ParamKind::Fixed(f) => f,
        })
        .collect();
    Ok((out, values, notes))
}

/// Build the scene and deck of one point and hash it. Pure: touches no file.
pub fn prepare(ctx: &PointContext, swept_values: &[f64]) -> Result<Prepared> {
    let parameters = resolve(&ctx.sweep, swept_values);
    let scene = Scene::new(&parameters, &ctx.sweep.file.scene)
        .map_err(|e| Error::input(format!("{}: {e}", ctx.sweep.path.display())))?;
    let mut deck =
        Deck::new(&ctx.template, &scene, &ctx.engine.identity()).map_err(|e| Error::input(e.to_string()))?;
    deck.header = header(&parameters, &deck.hash);
    Ok(Prepared { hash: deck.hash.clone(), parameters, scene, deck })
}

/// The deck's first lines: every parameter of the point with its unit, and the run's hash.
fn header(parameters: &BTreeMap<String, f64>, hash: &str) -> String {
    let values: Vec<String> = params::CATALOGUE
        .iter()
        .filter_map(|p| {
            let v = crate::scene::plausible::show(*parameters.get(p.name)?);
            Some(if p.unit == "-" {
                format!("{} = {v}", p.name)
            } else {
                format!("{} = {v} {}", p.name, p.unit)
            })
        })
        .collect();
    format!("# point: {}\n# run {hash}\n", values.join(", "))
}

/// Run a prepared point in `run_dir` (created if missing; stale files from an interrupted
/// attempt are overwritten). Writes `result.json` or `failure.json` atomically and returns the
/// outcome; a cancelled run writes neither, so it stays pending.
pub fn execute(ctx: &PointContext, p: &Prepared, run_dir: &Path, cancel: &CancelToken) -> RunOutcome {
    let fail_measured = |class: FailureClass, reason: String, log_tail: String, wall: f64, measured| {
        let f = RunFailure {
            format: RESULT_FORMAT,
            hash: p.hash.clone(),
            class,
            reason,
            log_tail,
            wall_time: wall,
            measured,
        };
        crate::engine::remove_forced_restarts(run_dir);
        let _ = write_json(&run_dir.join(FAILURE), &f);
        RunOutcome::Failed(f)
    };
    let fail = |class, reason, log_tail, wall| fail_measured(class, reason, log_tail, wall, None);
    for stale in [RESULT, FAILURE, DUMP, crate::engine::LOG] {
        let _ = std::fs::remove_file(run_dir.join(stale));
    }
    if let Err(e) = std::fs::create_dir_all(run_dir).and_then(|_| p.deck.write(run_dir)) {
        return fail(
            FailureClass::CouldNotStart,
            format!("cannot write the deck in {}: {e}", run_dir.display()),
            String::new(),
            0.0,
        );
    }
    let atoms = (!p.scene.is_conveyor()).then_some(p.scene.atoms() as u64);
    let limits = LogLimits { ke_limit: p.scene.ke_limit, atoms };
    let run = ctx.engine.run(run_dir, Deck::INPUT, &limits, ctx.timeout, cancel);
    let wall = run.wall_time;
    match run.status {
        RunStatus::Cancelled => return RunOutcome::Cancelled,
        RunStatus::Failed { class, reason, log_tail } => return fail(class, reason, log_tail, wall),
        RunStatus::Ok => {}
    }
    let settle_steps = match crate::engine::settled_at(&run.log) {
        Ok(steps) => steps,
        Err((class, reason)) => return fail(class, reason, String::new(), wall),
    };
    let frames: Vec<Frame> = match crate::engine::dump::read_dump(run_dir.join(DUMP), &metrics::COLUMNS)
        .and_then(|snaps| snaps.iter().map(Frame::from_snapshot).collect())
    {
        Ok(f) => f,
        Err(e) => return fail(FailureClass::Unparsable, e.to_string(), String::new(), wall),
    };
    // What the engine wrote must be possible before the metrics read it.
    let blade_speed = p.parameters.get("blade_speed").copied().unwrap_or(f64::NAN);
    if let Some(e) = frames.iter().find_map(|f| plausible::check_frame(f, blade_speed).err()) {
        return fail(FailureClass::Implausible, format!("{DUMP}: {e}"), String::new(), wall);
    }
    if p.scene.is_conveyor() {
        return finish_conveyor(ctx, p, run_dir, &run, &frames, fail_measured);
    }
    let m = match metrics::compute(&p.scene, &frames) {
        Ok(m) => m,
        Err(e) => return fail(FailureClass::Unparsable, e.to_string(), String::new(), wall),
    };
    let steps = settle_steps + p.scene.spread_steps();
    let result = RunResult {
        format: RESULT_FORMAT,
        hash: p.hash.clone(),
        parameters: p.parameters.clone(),
        mfr: m.mfr,
        mfr_flux: m.mfr_flux,
        mfr_particles: m.mfr_particles,
        mfr_se: None,
        steady_state: None,
        vx_se: Vec::new(),
        mfr_windows: m.mfr_windows,
        steady: m.steady,
        steady_p: m.steady_p,
        vx: m.vx,
        particles: m.particles,
        layer: m.layer,
        settle_steps,
        steps,
        simulated_time: steps as f64 * p.scene.timestep,
        wall_time: wall,
        cpu_time: run.cpu_time,
        engine_version: ctx.engine.version.clone(),
        warnings: run.warnings,
    };
    if !result.steady {
        let reason = format!(
            "MFR not steady over the window: halves differ beyond counting noise (p = {:.2e} < {}), sub-window MFR {:?}",
            result.steady_p,
            metrics::STEADY_ALPHA,
            result.mfr_windows.iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>()
        );
        return fail_measured(FailureClass::Unsteady, reason, String::new(), wall, Some(Box::new(result)));
    }
    if let Err(e) = plausible::check_squeezed(&p.scene, result.mfr) {
        return fail_measured(FailureClass::Implausible, e, String::new(), wall, Some(Box::new(result)));
    }
    if let Err(e) = plausible::check_result(&result) {
        return fail(FailureClass::Implausible, e, String::new(), wall);
    }
    if let Err(e) = write_json(&run_dir.join(RESULT), &result) {
        return fail(FailureClass::Unparsable, format!("cannot write {RESULT}: {e}"), String::new(), wall);
    }
    RunOutcome::Done(result)
}

/// The conveyor's spread layer: coverage and roughness from the strip behind the blade at the
/// end (`dump.strip`), uniformity from the mass each block of the steady window deposited.
fn conveyor_layer(
    scene: &crate::scene::Scene,
    frame: &Frame,
    st: &crate::outcome::steady::SteadyState,
) -> Option<crate::outcome::layer::Layer> {
    let c = &scene.conveyor;
    let mut l = layer::measure(scene, frame, c.delete_x1, scene.blade_x0)?;
    let particle_mass = |d: f64| scene.density * std::f64::consts::PI / 6.0 * d.powi(3);
    let weighted: f64 = c.feed.iter().map(|f| f.mass_fraction * particle_mass(f.diameter)).sum::<f64>()
        / c.feed.iter().map(|f| f.mass_fraction).sum::<f64>();
    let block_mass: Vec<f64> =
        st.block_mfr[st.transient_blocks..].iter().map(|y| y * c.ideal_block_mass).collect();
    (l.layer_cv, l.layer_cv_noise) = layer::along_travel(&block_mass, weighted);
    Some(l)
}

/// The conveyor layout's result: the block series from the log, the steady window, MFR with its
/// SE; a run that did not become steady fails as `unsteady` with its numbers kept.
fn finish_conveyor(
    ctx: &PointContext,
    p: &Prepared,
    run_dir: &Path,
    run: &crate::engine::EngineRun,
    frames: &[Frame],
    fail: impl Fn(FailureClass, String, String, f64, Option<Box<RunResult>>) -> RunOutcome,
) -> RunOutcome {
    let wall = run.wall_time;
    let (blocks, stop) = match steady::parse_log(&run.log) {
        Ok(b) => b,
        Err(e) => return fail(FailureClass::Unparsable, e.to_string(), String::new(), wall, None),
    };
    let st = steady::compute(&p.scene, &blocks, &stop, frames);
    // The steady window in quarters (the gated scene's sub-windows, for the same readers).
    let w = &st.state.block_mfr[st.state.transient_blocks..];
    let quarter = w.len().div_ceil(4).max(1);
    let mfr_windows = w.chunks(quarter).map(|c| c.iter().sum::<f64>() / c.len() as f64).collect();
    let steps = blocks.last().map(|b| b.step).unwrap_or(0);
    let strip = crate::engine::dump::read_dump(run_dir.join(STRIP_DUMP), &metrics::COLUMNS)
        .ok()
        .and_then(|snaps| snaps.last().and_then(|s| Frame::from_snapshot(s).ok()));
    let layer = strip.as_ref().and_then(|f| conveyor_layer(&p.scene, f, &st.state));
    let result = RunResult {
        format: RESULT_FORMAT,
        hash: p.hash.clone(),
        parameters: p.parameters.clone(),
        mfr: st.mfr,
        mfr_flux: st.mfr_deleted,
        mfr_particles: st.particles,
        mfr_se: Some(st.mfr_se),
        steady_state: Some(Box::new(st.state)),
        vx_se: st.vx_se,
        mfr_windows,
        steady: st.unsteady.is_none(),
        steady_p: 1.0,
        vx: st.vx,
        particles: p.scene.conveyor.heap_particles,
        layer,
        settle_steps: 0,
        steps,
        simulated_time: steps as f64 * p.scene.timestep,
        wall_time: wall,
        cpu_time: run.cpu_time,
        engine_version: ctx.engine.version.clone(),
        warnings: run.warnings.clone(),
    };
    if let Some(why) = st.unsteady {
        let reason = format!("MFR not steady: {why}");
        return fail(FailureClass::Unsteady, reason, String::new(), wall, Some(Box::new(result)));
    }
    if let Err(e) = plausible::check_squeezed(&p.scene, result.mfr) {
        return fail(FailureClass::Implausible, e, String::new(), wall, Some(Box::new(result)));
    }
    if let Err(e) = plausible::check_result(&result) {
        return fail(FailureClass::Implausible, e, String::new(), wall, None);
    }
    if let Err(e) = write_json(&run_dir.join(RESULT), &result) {
        return fail(
            FailureClass::Unparsable,
            format!("cannot write {RESULT}: {e}"),
            String::new(),
            wall,
            None,
        );
    }
    RunOutcome::Done(result)
}
