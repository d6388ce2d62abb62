//! Sweep files: the TOML a user writes, parsed and validated into a [`Sweep`].
//!
//! Responsible for syntax, unknown keys (with "did you mean"), and values that make no sense
//! (lo ≥ hi, non-finite, zero levels, N = 0). Every error is one line naming the file and the
//! key. Not responsible for the physics meaning of parameters: that is the scene's catalogue
//! ([`crate::scene::params`]), which this module consults for names and units.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{hint, Error, Result};
use crate::scene::params::{self, ParamInfo};

/// Version of the resolved sweep format written to `DIR/sweep.toml`.
pub const SWEEP_FORMAT: u32 = 1;

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Name of the sweep; the default output directory is `runs/<name>`.
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Every parameter of the scene that the sweep sets: a range (swept) or a value (fixed).
    /// Parameters not named take the scene's defaults.
    pub parameters: toml::Table,
    #[serde(default)]
    pub design: DesignSettings,
    #[serde(default)]
    pub convergence: ConvergenceSettings,
    #[serde(default)]
    pub scene: SceneSettings,
    #[serde(default)]
    pub run: RunSettings,
}

/// One entry of `[parameters]` as written: either `{ lo, hi, [unit], [scale] }` or `{ value,
/// [unit] }` or a bare number.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
struct ParamEntry {
    lo: Option<f64>,
    hi: Option<f64>,
    value: Option<f64>,
    unit: Option<String>,
    #[serde(default)]
    scale: Scale,
}

#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Scale {
    #[default]
    Linear,
    /// Uniform in log(x); only for positive ranges.
    Log,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct DesignSettings {
    /// Lattice levels: n values per dimension, run in order (`sweep lattice`).
    pub lattice_levels: Vec<usize>,
    pub lds: LdsSettings,
}

impl Default for DesignSettings {
    fn default() -> Self {
        DesignSettings { lattice_levels: vec![5, 6, 7, 9, 10], lds: LdsSettings::default() }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct LdsSettings {
    /// Points per batch; each prefix of the sequence at a multiple of `step` is one space.
    pub step: usize,
    /// Most points to run.
    pub max: usize,
    pub scrambling: Scrambling,
    /// Seed for `scrambling = "random"`. The default, 14, was chosen by measurement
    /// (`scripts/bench_discrepancy.py`, BENCHMARKS.md "Design discrepancy"): of seeds 0–39 it
    /// has the smallest worst-case ratio of its centred discrepancy to the average of
    /// scipy's scrambled Halton in 4-D and 6-D (N = 400, 800, 2400) and 8-D (N = 100), and is
    /// below that average in every case.
    pub seed: u64,
}

impl Default for LdsSettings {
    fn default() -> Self {
        LdsSettings { step: 400, max: 2400, scrambling: Scrambling::default(), seed: DEFAULT_SEED }
    }
}

/// The default `design.lds.seed` (see [`LdsSettings::seed`]).
pub const DEFAULT_SEED: u64 = 14;

/// How the Halton digits are permuted (see [`crate::design::halton`]).
///
/// The default is `Random`, chosen by measured discrepancy (BENCHMARKS.md "Design
/// discrepancy"): its seed-average centred discrepancy equals scipy's scrambled Halton's, while
/// Braaten–Weller's is 1.3× higher in 4-D at N = 400 and plain Halton's 1.55×.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Scrambling {
    /// Plain Halton (radical inverse, no permutation).
    None,
    /// Braaten & Weller (1979) fixed permutations, one per base.
    BraatenWeller,
    /// Seeded random permutations per base and digit position (Owen 2017).
    #[default]
    Random,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ConvergenceSettings {
    /// `"all"` (default: every statistic within tolerance, with the floor, held for `hold`
    /// spaces) or `"any"` (the thesis's rule: any one statistic within tolerance; floor and hold
    /// do not apply). See [`crate::convergence`].
    pub rule: String,
    /// Relative change of a statistic between consecutive spaces that counts as converged.
    pub tolerance: f64,
    /// Absolute change below which a statistic counts as converged whatever its relative change.
    pub floor: f64,
    /// Consecutive spaces the rule must hold for.
    pub hold: usize,
    /// No space with fewer points counts as converged. `sweep lds --max M` on a converged
    /// directory sets it to the old extent, so that the extension is judged on its own.
    pub min_points: usize,
}

impl Default for ConvergenceSettings {
    fn default() -> Self {
        ConvergenceSettings { rule: "all".into(), tolerance: 0.05, floor: 0.01, hold: 2, min_points: 0 }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SceneSettings {
    /// A path to a Tera template overriding the built-in `spreading.liggghts.tera`
    /// (relative to the sweep file).
    pub template: Option<PathBuf>,
    /// Fidelity preset: `"fast"` (default) or `"thesis"` (the thesis's 1e-5 s step, full run).
    pub fidelity: String,
    /// Timestep as a fraction of the Rayleigh time.
    pub rayleigh_fraction: f64,
    /// Domain depth across the blade (periodic y), in particle diameters.
    pub depth_diameters: f64,
    /// Length of the MFR measurement window (blade travel), in diameters.
    pub window_diameters: f64,
    /// The scene's layout: `"gated"` (default: the dose settles at rest in a closed region on a
    /// rough substrate and is released when the blade starts) or `"thesis"` (the thesis's pile
    /// on a smooth plate, settled for a fixed time).
    pub layout: String,
    /// Gated layout: `"rough"` (default: a layer of fixed spheres, as the previous powder layer
    /// a blade spreads onto) or `"smooth"` (a flat plate).
    pub substrate: String,
    /// Gated layout: the pile is at rest when its rms speed is below this fraction of √(g·D).
    pub rest_speed: f64,
    /// Gated layout: longest settle, s; a pile still moving then fails the run (`not-settled`).
    pub settle_max_s: f64,
    /// Gated layout: blade travel past the opened gate before the window starts, in diameters.
    pub window_start_diameters: f64,
    /// Size of the heap in front of the blade, relative to the planned one (gated: gap + 10 D
    /// tall at 30° repose; thesis: the heap left at the end, gap + 6 D tall).
    pub supply_factor: f64,
    /// Size distribution of the particles.
    pub size_distribution: SizeDistributionSpec,
    /// Half-height of each v_x layer, in diameters (0.25 = ±D/4); `thesis_band` overrides it
    /// with the thesis's fixed ±1 mm.
    pub vx_band_diameters: f64,
    pub thesis_band: bool,
    /// Seed of the initial pile: diameters and lattice jitter.
    pub seed: u64,
    /// Accept a timestep beyond [`crate::scene::MAX_RAYLEIGH_FRACTION`] (`--force`; never read
    /// from a sweep file).
    #[serde(skip)]
    pub force_timestep: bool,
}

impl Default for SceneSettings {
    fn default() -> Self {
        SceneSettings {
            template: None,
            fidelity: "fast".into(),
            rayleigh_fraction: 0.2,
            depth_diameters: 6.0,
            // 40 D: measured 2.8× less seed-to-seed spread than 20 D for 1.6× the CPU
            // (BENCHMARKS.md "MFR noise").
            window_diameters: 40.0,
            layout: "gated".into(),
            substrate: "rough".into(),
            rest_speed: 0.01,
            settle_max_s: 1.0,
            window_start_diameters: 30.0,
            supply_factor: 1.0,
            size_distribution: SizeDistributionSpec::default(),
            vx_band_diameters: 0.25,
            thesis_band: false,
            seed: 12345,
            force_timestep: false,
        }
    }
}

/// The particle size distribution, as written in the sweep file.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "kebab-case")]
pub enum SizeDistributionSpec {
    /// Every particle has the `diameter` parameter.
    #[default]
    Mono,
    /// Discrete classes: `classes = [[d, fraction], ...]`; `d` in mm, or in multiples of the
    /// `diameter` parameter when `relative = true` (thesis Tables 3.2–3.3).
    Classes {
        classes: Vec<[f64; 2]>,
        #[serde(default)]
        relative: bool,
    },
    /// Two-parameter Weibull in diameter, from the `weibull_shape` and `weibull_scale`
    /// parameters, discretised into `bins` classes of equal probability width.
    Weibull {
        #[serde(default = "default_bins")]
        bins: usize,
    },
}

fn default_bins() -> usize {
    5
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RunSettings {
    /// LIGGGHTS executable (default: `liggghts` on PATH).
    pub engine: Option<PathBuf>,
    /// Wall-clock limit of one run, seconds.
    pub timeout_s: f64,
    /// Retries of transient failures (could not start, killed by a signal, timed out).
    pub retries: u32,
    /// Skip the points where nothing can pass under the blade ([`crate::scene::screen`]),
    /// counting them as MFR = 0, once a seeded sample of them has run and given MFR = 0
    /// ([`crate::screen`]).
    pub screen: bool,
    /// Fraction of the closed points run anyway to verify the screen (seeded by
    /// `design.lds.seed`).
    pub screen_sample: f64,
    /// ... and at least this many (every closed point when fewer).
    pub screen_sample_min: usize,
}

impl Default for RunSettings {
    fn default() -> Self {
        RunSettings {
            engine: None,
            timeout_s: 600.0,
            retries: 1,
            screen: true,
            // A tenth: on a 2,400-point sweep of the thesis space about 12 of ~120 closed points.
            screen_sample: 0.1,
            screen_sample_min: 3,
        }
    }
}

/// One parameter after validation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Parameter {
    pub name: String,
    pub unit: &'static str,
    pub kind: ParamKind,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum ParamKind {
    Swept { lo: f64, hi: f64, scale: Scale },
    Fixed(f64),
}

/// A validated sweep: the file as written plus its parameters resolved against the catalogue.
#[derive(Debug, Clone)]
pub struct Sweep {
    pub path: PathBuf,
    pub file: SweepFile,
    /// Swept parameters in file order: the design's dimensions.
    pub swept: Vec<Parameter>,
    /// Fixed parameters as written.
    pub fixed: Vec<Parameter>,
}

impl Sweep {
    pub fn load(path: &Path) -> Result<Sweep> {
        if path.is_dir() {
            return Err(Error::input(format!(
                "cannot read sweep file {}: it is a directory",
                path.display()
            )));
        }
        let text = std::fs::read_to_string(path).map_err(|e| {
            Error::input(format!("cannot read sweep file {}: {}", path.display(), io_reason(&e)))
        })?;
        Sweep::parse(&text, path)
    }

    /// Parse and validate; `path` is only used in messages and to resolve relative paths.
    pub fn parse(text: &str, path: &Path) -> Result<Sweep> {
        let file: SweepFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        let (swept, fixed) = validate(&file, path)?;
        Ok(Sweep { path: path.to_path_buf(), file, swept, fixed })
    }

    pub fn names(&self) -> Vec<&str> {
        self.swept.iter().map(|p| p.name.as_str()).collect()
    }

    /// The design's dimension.
    pub fn dim(&self) -> usize {
        self.swept.len()
    }

    /// Resolve the template override path against the sweep file's directory.
    pub fn template_path(&self) -> Option<PathBuf> {
        self.file.scene.template.as_ref().map(|t| {
            if t.is_absolute() {
                t.clone()
            } else {
                self.path.parent().unwrap_or(Path::new(".")).join(t)
            }
        })
    }
}

fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => e.to_string(),
    }
}

/// Turn a (multi-line) toml error into one line:
/// `file:line: key.path: message (did you mean ..?)`.
fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> Error {
    let start = e.span().map(|s| s.start.min(text.len()));
    let line = start.map(|s| text[..s].matches('\n').count() + 1);
    let msg = e
        .message()
        .trim()
        .replace('\n', " ")
        .replace("expected usize", "expected a whole number ≥ 0")
        .replace("expected u64", "expected a whole number ≥ 0")
        .replace("expected u32", "expected a whole number ≥ 0");
    let mut extra = String::new();
    // serde's message: "unknown field `frction`, expected one of `a`, `b`".
    if let Some(rest) = msg.strip_prefix("unknown field `") {
        if let Some((word, tail)) = rest.split_once('`') {
            let candidates: Vec<&str> = tail.split('`').skip(1).step_by(2).collect();
            extra = hint(word, candidates);
        }
    }
    let at = line.map(|l| format!(":{l}")).unwrap_or_default();
    let key = start.and_then(|s| key_at(text, s)).map(|k| format!(" {k}:")).unwrap_or_default();
    Error::input(format!("{}{at}:{key} {msg}{extra}", path.display()))
}

/// The dotted key whose `key = value` line holds byte `offset` of `text`, prefixed with the
/// enclosing `[table]` header, e.g. `design.lds.max`; `None` on a header or a blank line.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line = text[line_start..].lines().next().unwrap_or("").trim();
    let (key, _) = line.split_once('=')?;
    let key = key.trim().replace([' ', '"', '\''], "");
    if key.is_empty() || key.starts_with('[') || key.starts_with('#') {
        return None;
    }
    let header = text[..line_start].lines().rev().find_map(|l| {
        let l = l.trim();
        l.starts_with('[')
            .then(|| l.trim_start_matches('[').split(']').next().unwrap_or("").replace([' ', '"', '\''], ""))
    });
    Some(match header {
        Some(h) if !h.is_empty() => format!("{h}.{key}"),
        _ => key,
    })
}

fn validate(file: &SweepFile, path: &Path) -> Result<(Vec<Parameter>, Vec<Parameter>)> {
    let p = path.display();
    let bad = |key: &str, what: String| Error::input(format!("{p}: {key}: {what}"));
    if file.name.trim().is_empty() || file.name.contains(['/', '\\']) || file.name.starts_with('.') {
        return Err(bad("name", "expected a non-empty name without slashes".into()));
    }
    let mut swept = Vec::new();
    let mut fixed = Vec::new();
    for (name, value) in &file.parameters {
        let key = format!("parameters.{name}");
        let info: &ParamInfo = params::lookup(name).ok_or_else(|| {
            bad(
                &key,
                format!(
                    "unknown parameter{}; known: {}",
                    hint(name, params::CATALOGUE.iter().map(|i| i.name)),
                    params::CATALOGUE.iter().map(|i| i.name).collect::<Vec<_>>().join(", ")
                ),
            )
        })?;
        let entry: ParamEntry = match value {
            toml::Value::Float(_) | toml::Value::Integer(_) => ParamEntry {
                lo: None,
                hi: None,
                value: Some(as_f64(value).unwrap()),
                unit: None,
                scale: Scale::Linear,
            },
            toml::Value::Table(_) => value.clone().try_into().map_err(|e: toml::de::Error| {
                let msg = e.message().trim().replace('\n', " ");
                let mut extra = String::new();
                if let Some(rest) = msg.strip_prefix("unknown field `") {
                    if let Some((word, _)) = rest.split_once('`') {
                        extra = hint(word, ["lo", "hi", "value", "unit", "scale"]);
                    }
                }
                bad(&key, format!("{msg}{extra}"))
            })?,
            _ => {
                return Err(bad(
                    &key,
                    "expected a number or a table { lo = .., hi = .. } / { value = .. }".into(),
                ))
            }
        };
        if let Some(unit) = &entry.unit {
            if unit != info.unit {
                return Err(bad(
                    &format!("{key}.unit"),
                    format!("is \"{unit}\" but {name} is given in \"{}\"", info.unit),
                ));
            }
        }
        let check = |k: &str, v: f64| -> Result<f64> {
            if !v.is_finite() {
                return Err(bad(&format!("{key}.{k}"), format!("{v} is not a finite number")));
            }
            if !info.accepts(v) {
                return Err(bad(&format!("{key}.{k}"), format!("{v} is outside {}", info.domain())));
            }
            Ok(v)
        };
        let kind = match (entry.lo, entry.hi, entry.value) {
            (Some(lo), Some(hi), None) => {
                let (lo, hi) = (check("lo", lo)?, check("hi", hi)?);
                if lo >= hi {
                    return Err(bad(&key, format!("lo = {lo} must be below hi = {hi}")));
                }
                if entry.scale == Scale::Log && lo <= 0.0 {
                    return Err(bad(&format!("{key}.scale"), "log scale needs lo > 0".into()));
                }
                ParamKind::Swept { lo, hi, scale: entry.scale }
            }
            (None, None, Some(v)) => ParamKind::Fixed(check("value", v)?),
            _ => {
                return Err(bad(&key, "expected either both `lo` and `hi` (swept) or `value` (fixed)".into()))
            }
        };
        let param = Parameter { name: name.clone(), unit: info.unit, kind };
        match param.kind {
            ParamKind::Swept { .. } => swept.push(param),
            ParamKind::Fixed(_) => fixed.push(param),
        }
    }
    if swept.is_empty() {
        return Err(bad("parameters", "expected at least one swept parameter { lo, hi }".into()));
    }
    let d = &file.design;
    if d.lattice_levels.is_empty() {
        return Err(bad(
            "design.lattice_levels",
            "expected at least one level, e.g. [5, 6, 7, 9, 10]".into(),
        ));
    }
    // Only the level count here: whether n^d points are too many matters only when a lattice
    // is built (`design::lattice_size`), and an LDS sweep never builds one.
    if let Some(i) = d.lattice_levels.iter().position(|&n| n < 2) {
        return Err(bad(
            &format!("design.lattice_levels[{i}]"),
            format!("{}: expected at least 2 values per dimension", d.lattice_levels[i]),
        ));
    }
    for (key, n) in [("design.lds.step", d.lds.step), ("design.lds.max", d.lds.max)] {
        crate::design::lds_size(n).map_err(|e| bad(key, format!("{n}: {e}")))?;
    }
    let c = &file.convergence;
    if c.rule != "all" && c.rule != "any" {
        return Err(bad("convergence.rule", format!("\"{}\": expected \"all\" or \"any\"", c.rule)));
    }
    for (k, v) in [("convergence.tolerance", c.tolerance), ("convergence.floor", c.floor)] {
        if !v.is_finite() || v < 0.0 {
            return Err(bad(k, format!("{v}: expected a finite number ≥ 0")));
        }
    }
    if c.hold == 0 {
        return Err(bad("convergence.hold", "expected at least 1".into()));
    }
    let s = &file.scene;
    if s.fidelity != "fast" && s.fidelity != "thesis" {
        return Err(bad("scene.fidelity", format!("\"{}\": expected \"fast\" or \"thesis\"", s.fidelity)));
    }
    if s.layout != "gated" && s.layout != "thesis" {
        return Err(bad("scene.layout", format!("\"{}\": expected \"gated\" or \"thesis\"", s.layout)));
    }
    if s.substrate != "rough" && s.substrate != "smooth" {
        return Err(bad("scene.substrate", format!("\"{}\": expected \"rough\" or \"smooth\"", s.substrate)));
    }
    for (k, v) in [
        ("scene.rest_speed", s.rest_speed),
        ("scene.settle_max_s", s.settle_max_s),
        ("scene.window_start_diameters", s.window_start_diameters),
        ("scene.supply_factor", s.supply_factor),
        ("scene.rayleigh_fraction", s.rayleigh_fraction),
        ("scene.depth_diameters", s.depth_diameters),
        ("scene.window_diameters", s.window_diameters),
        ("scene.vx_band_diameters", s.vx_band_diameters),
    ] {
        if !v.is_finite() || v <= 0.0 {
            return Err(bad(k, format!("{v}: expected a finite number > 0")));
        }
    }
    if s.rayleigh_fraction > 1.0 {
        return Err(bad("scene.rayleigh_fraction", format!("{}: expected at most 1", s.rayleigh_fraction)));
    }
    match &s.size_distribution {
        SizeDistributionSpec::Mono => {}
        SizeDistributionSpec::Classes { classes, .. } => {
            if classes.is_empty() {
                return Err(bad("scene.size_distribution.classes", "expected at least one class".into()));
            }
            for (i, [dia, frac]) in classes.iter().enumerate() {
                if !(dia.is_finite() && *dia > 0.0 && frac.is_finite() && *frac > 0.0) {
                    return Err(bad(
                        &format!("scene.size_distribution.classes[{i}]"),
                        format!("[{dia}, {frac}]: expected a positive diameter and fraction"),
                    ));
                }
            }
        }
        SizeDistributionSpec::Weibull { bins } => {
            if *bins == 0 {
                return Err(bad("scene.size_distribution.bins", "expected at least 1".into()));
            }
        }
    }
    if !(file.run.timeout_s.is_finite() && file.run.timeout_s > 0.0) {
        return Err(bad("run.timeout_s", format!("{}: expected seconds > 0", file.run.timeout_s)));
    }
    let r = &file.run;
    if !(r.screen_sample.is_finite() && (0.0..=1.0).contains(&r.screen_sample)) {
        return Err(bad("run.screen_sample", format!("{}: expected a fraction in [0, 1]", r.screen_sample)));
    }
    if r.screen_sample_min == 0 {
        return Err(bad(
            "run.screen_sample_min",
            "0: expected at least 1 (a screen is trusted only once verified; `screen = false` runs every point)"
                .into(),
        ));
    }
    Ok((swept, fixed))
}

fn as_f64(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}
