//! One design point end to end: values → scene → deck → LIGGGHTS → dump → metrics → result.json.
//!
//! [`prepare`] is pure and fast (render and hash in memory); [`execute`] does the I/O and the
//! run in a directory it is given. The pool calls both; `sweep render` and `sweep run` too.

pub mod deck;
mod error;
pub mod extend;
pub mod passes;

pub use error::PointError;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::engine::{Engine, LogLimits, RunStatus};
use crate::error::{hint, Result};
use crate::outcome::{FailureClass, RunFailure, RunOutcome, WarmStart};
use crate::point::deck::{Deck, Template};
use crate::scene::settings::SceneSettings;
use crate::scene::{mesh, params, Scene};
use crate::scenes::{Finished, Layout, Warm};
use crate::sweep::{ParamKind, Parameter, Sweep};
use crate::sys::atomic::write_json;
use crate::sys::process::CancelToken;

/// File names in a run directory.
pub const RESULT: &str = crate::outcome::RESULT_FILE;
pub const FAILURE: &str = "failure.json";

/// What every point of a sweep shares: the sweep, the engine, the template.
pub struct PointContext {
    pub sweep: Sweep,
    /// The scene layout the sweep file names.
    pub layout: &'static dyn Layout,
    pub engine: Engine,
    pub template: Template,
    pub timeout: Duration,
}

impl PointContext {
    pub fn new(sweep: Sweep) -> Result<PointContext> {
        // The template first: a bad one is bad input, found before the engine is run.
        let layout = crate::scenes::of(&sweep.file.scene).map_err(PointError::Layout)?;
        let path = sweep.template_path();
        let template = Template::load(path.as_deref(), layout).map_err(|e| match path {
            // The sweep file's template: named by its file and key.
            Some(_) => crate::error::Error::from(crate::sweep::SweepError::Key {
                path: sweep.path.clone(),
                key: "scene.template".into(),
                why: e.to_string(),
            }),
            None => PointError::Deck(e).into(),
        })?;
        // Under the process's interrupt flag (Ctrl-C, SIGTERM), like every run.
        let engine = Engine::locate(sweep.file.run.engine.as_deref(), &CancelToken::new())?;
        let timeout = Duration::from_secs_f64(sweep.file.run.timeout_s);
        Ok(PointContext { sweep, layout, engine, template, timeout })
    }

    /// The same engine, template and layout for another version of the sweep (a seed, a
    /// numerical level).
    pub fn with_sweep(&self, sweep: Sweep) -> PointContext {
        PointContext {
            sweep,
            layout: self.layout,
            engine: self.engine.clone(),
            template: self.template.clone(),
            timeout: self.timeout,
        }
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
        .filter(|p| crate::scenes::shown(&sweep.file.scene, p.name))
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
pub fn with_set(sweep: &Sweep, sets: &[String]) -> Result<(Sweep, Vec<f64>, Vec<String>), PointError> {
    let bad = |item: String, why: String| PointError::Set { item, why };
    let mut out = sweep.clone();
    let mut seen: Vec<(String, String)> = Vec::new();
    let mut notes = Vec::new();
    for item in sets.iter().filter(|s| !s.trim().is_empty()) {
        if item.chars().any(char::is_control) {
            return Err(bad(
                format!("{item:?}"),
                "expected name=value without control characters (newline, tab)".into(),
            ));
        }
        let (name, value) =
            item.split_once('=').ok_or_else(|| bad(item.clone(), "expected name=value".into()))?;
        let (name, value) = (name.trim(), value.trim());
        let Some(info) = params::lookup(name) else {
            let known: Vec<&str> = params::CATALOGUE.iter().map(|p| p.name).collect();
            return Err(bad(
                name.into(),
                format!(
                    "unknown parameter{}; known: {}",
                    hint(name, known.iter().copied()),
                    known.join(", ")
                ),
            ));
        };
        if let Some((_, first)) = seen.iter().find(|(n, _)| n == name) {
            return Err(bad(
                name.into(),
                format!("given twice ({first} and {value}); give each parameter once"),
            ));
        }
        let v: f64 = value
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| bad(format!("{name}={value}"), "expected a finite number".into()))?;
        if !info.accepts(v) {
            return Err(bad(format!("{name}={value}"), format!("outside {}", info.domain())));
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
pub fn prepare(ctx: &PointContext, swept_values: &[f64]) -> Result<Prepared, PointError> {
    let parameters = resolve(&ctx.sweep, swept_values);
    let scene = crate::scenes::build(&parameters, &ctx.sweep.file.scene)
        .map_err(|source| PointError::Scene { path: ctx.sweep.path.clone(), source })?;
    let mut deck = Deck::new(&ctx.template, ctx.layout, &scene, &ctx.engine.identity())?;
    deck.header = header(&parameters, &ctx.sweep.file.scene, &deck.hash);
    Ok(Prepared { hash: deck.hash.clone(), parameters, scene, deck })
}

/// Why the files a run left in `run_dir` cannot be trusted, if they cannot: LIGGGHTS does not
/// check its writes, so on a full disk its last files (the restart, a dump) are cut off and it
/// ends as if nothing happened. (A sweep's pool takes such a failure for the store's, and the
/// point stays pending.)
pub fn cut_off(run_dir: &Path) -> Option<String> {
    crate::sys::disk::low_on_space(run_dir)
        .then(|| format!("the disk holding {} is full: the run's files may be cut off", run_dir.display()))
}

/// The deck's first lines: every parameter of the point with its unit, and the run's hash.
fn header(parameters: &BTreeMap<String, f64>, settings: &SceneSettings, hash: &str) -> String {
    let values: Vec<String> = params::CATALOGUE
        .iter()
        .filter(|p| crate::scenes::shown(settings, p.name))
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

/// A finished point of the same sweep that a run may start from (its steady state mapped onto
/// the run's point: [`crate::scenes::Layout::warm_start`]).
#[derive(Debug, Clone)]
pub struct Neighbour {
    pub hash: String,
    pub dir: PathBuf,
    /// Every catalogue parameter of it, as its result.json records them.
    pub parameters: BTreeMap<String, f64>,
    /// Its distance from the point to run, in the design's unit cube.
    pub distance: f64,
}

/// How a sweep starts a run beyond its deck: choices that change how long it runs and where it
/// begins, not what it is, so its hash does not depend on them (its result records them).
#[derive(Debug, Clone, Default)]
pub struct Start {
    /// The finished point to start from (`None`: from rest).
    pub neighbour: Option<Neighbour>,
    /// The SE of MFR to run to, the sweep's choice (`None`: the scene's own target).
    pub mfr_se_target: Option<f64>,
}

/// Run a prepared point in `run_dir` from rest, to its scene's own precision.
pub fn execute(ctx: &PointContext, p: &Prepared, run_dir: &Path, cancel: &CancelToken) -> RunOutcome {
    execute_from(ctx, p, run_dir, cancel, &Start::default())
}

/// What is run for `p` under `start`: the scene, the deck (the hashed deck's files with its input
/// rendered from that scene, when it differs) and the warm start's particles and record.
pub(crate) struct Started {
    pub(crate) scene: Scene,
    deck: Deck,
    pub(crate) warm: Option<(Warm, WarmStart)>,
    mfr_se_target: Option<f64>,
}

fn started(ctx: &PointContext, p: &Prepared, start: &Start) -> Started {
    let target = start.mfr_se_target.and_then(|t| Some((t, ctx.layout.with_precision(&p.scene, t)?)));
    let (scene, mfr_se_target) = match target {
        Some((t, scene)) => (scene, Some(t)),
        None => (p.scene.clone(), None),
    };
    // A neighbour that does not map (another size distribution, nothing of it fits): from rest.
    let warm = start.neighbour.as_ref().and_then(|n| {
        let from = crate::scenes::build(&n.parameters, &ctx.sweep.file.scene).ok()?;
        let warm = ctx.layout.warm_start(&from, &n.dir, &scene, &p.deck.pile, n.distance).ok()?;
        let record = WarmStart { from: n.hash.clone(), distance: n.distance, particles: warm.particles };
        Some((warm, record))
    });
    let scene = warm.as_ref().map_or(scene, |(w, _)| w.scene.clone());
    let deck = match (&warm, mfr_se_target) {
        (None, None) => p.deck.clone(),
        _ => match ctx.template.render(&scene) {
            Ok(input) => Deck { input, ..p.deck.clone() },
            // The hashed deck rendered; this one differs in a few numbers only.
            Err(_) => {
                return Started {
                    scene: p.scene.clone(),
                    deck: p.deck.clone(),
                    warm: None,
                    mfr_se_target: None,
                }
            }
        },
    };
    Started { scene, deck, warm, mfr_se_target }
}

/// Run a prepared point in `run_dir` (created if missing; stale files from an interrupted
/// attempt are overwritten), as `start` says: from a neighbour's steady state where it maps onto
/// the point, else from rest, and to the sweep's precision where it chose one. The run's hash is
/// the same either way. Writes `result.json` or `failure.json` atomically and returns the
/// outcome; a cancelled run writes neither, so it stays pending.
pub fn execute_from(
    ctx: &PointContext,
    p: &Prepared,
    run_dir: &Path,
    cancel: &CancelToken,
    start: &Start,
) -> RunOutcome {
    let fail_measured = |class: FailureClass, reason: String, log_tail: String, wall: f64, measured| {
        let f = RunFailure { measured, ..RunFailure::of(&p.hash, class, reason, log_tail, wall) };
        crate::engine::remove_forced_restarts(run_dir);
        ctx.layout.keep(run_dir, false);
        let _ = write_json(&run_dir.join(FAILURE), &f);
        RunOutcome::Failed(f)
    };
    let fail = |class, reason, log_tail, wall| fail_measured(class, reason, log_tail, wall, None);
    if let Some(by) = ctx.layout.by_pass(&p.scene) {
        // Its passes so far are kept: it goes on from the last.
        if let Err(e) = std::fs::create_dir_all(run_dir).and_then(|_| p.deck.write(run_dir)) {
            let why = format!("cannot write the deck in {}: {e}", run_dir.display());
            return fail(FailureClass::CouldNotStart, why, String::new(), 0.0);
        }
        let (scene, warm) = match passes::warm_start(ctx, p, run_dir, || started(ctx, p, start)) {
            Ok(s) => s,
            Err(why) => return fail(FailureClass::CouldNotStart, why, String::new(), 0.0),
        };
        let by = ctx.layout.by_pass(&scene).unwrap_or(by);
        return passes::execute(ctx, p, &scene, by, run_dir, cancel, warm.as_ref());
    }
    let stale = [RESULT, FAILURE, crate::engine::LOG].map(String::from);
    for file in stale.iter().chain(&ctx.layout.run_files(&ctx.sweep.file.scene)) {
        let _ = std::fs::remove_file(run_dir.join(file));
    }
    let Started { scene, deck, warm, mfr_se_target } = started(ctx, p, start);
    let scene = &scene;
    let written =
        std::fs::create_dir_all(run_dir).and_then(|_| deck.write(run_dir)).and_then(|_| match &warm {
            Some((w, _)) => std::fs::write(run_dir.join(w.data_file), &w.data),
            None => Ok(()),
        });
    if let Err(e) = written {
        return fail(
            FailureClass::CouldNotStart,
            format!("cannot write the deck in {}: {e}", run_dir.display()),
            String::new(),
            0.0,
        );
    }
    let limits = LogLimits { ke_limit: scene.ke_limit, atoms: ctx.layout.atoms_kept(scene) };
    let run = ctx.engine.run(run_dir, Deck::INPUT, &limits, ctx.timeout, cancel);
    let wall = run.wall_time;
    match run.status {
        RunStatus::Cancelled => return RunOutcome::Cancelled,
        RunStatus::Failed { class, reason, log_tail } => return fail(class, reason, log_tail, wall),
        RunStatus::Ok => {}
    }
    if let Some(reason) = cut_off(run_dir) {
        // Its files are left as they are, the disk full: the pool takes the failure for the store's.
        return RunOutcome::Failed(RunFailure::of(
            &p.hash,
            FailureClass::Unparsable,
            reason,
            String::new(),
            wall,
        ));
    }
    let finished = Finished {
        scene,
        parameters: &p.parameters,
        hash: &p.hash,
        run_dir,
        run: &run,
        engine_version: &ctx.engine.version,
        earlier: &[],
    };
    let mut result = match ctx.layout.measure(&finished) {
        Ok(result) => result,
        Err(r) => return fail_measured(r.class, r.reason, String::new(), wall, r.measured),
    };
    result.warm_start = warm.map(|(_, record)| record);
    result.mfr_se_target = mfr_se_target;
    ctx.layout.keep(run_dir, true);
    if let Err(e) = write_json(&run_dir.join(RESULT), &result) {
        return fail(FailureClass::Unparsable, format!("cannot write {RESULT}: {e}"), String::new(), wall);
    }
    RunOutcome::Done(result)
}
