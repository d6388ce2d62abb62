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
    /// `"scaled"` (default: every statistic moved and known within the tolerance on its own
    /// scale, held for `hold` spaces), `"any"` (the thesis's rule: any one statistic within
    /// tolerance relatively; floor and hold do not apply) or `"all"` (every statistic within
    /// tolerance relatively or by the floor). See [`crate::convergence`].
    pub rule: String,
    /// Relative change of a statistic between consecutive spaces that counts as converged.
    pub tolerance: f64,
    /// Absolute change below which a statistic counts as converged whatever its relative change
    /// (rule "all" only).
    pub floor: f64,
    /// Consecutive spaces the rule must hold for.
    pub hold: usize,
    /// No space with fewer points counts as converged. `sweep lds --max M` on a converged
    /// directory sets it to the old extent, so that the extension is judged on its own.
    pub min_points: usize,
    /// `"trapezoid"` (default: a complete lattice's points weighted by the trapezoid rule) or
    /// `"equal"` (the thesis). See [`crate::weights`].
    pub lattice_weights: String,
}

impl Default for ConvergenceSettings {
    fn default() -> Self {
        ConvergenceSettings {
            rule: "scaled".into(),
            tolerance: 0.05,
            floor: 0.01,
            hold: 2,
            min_points: 0,
            lattice_weights: "trapezoid".into(),
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SceneSettings {
    /// A path to a Tera template overriding the built-in `spreading.liggghts.tera`
    /// (relative to the sweep file).
    pub template: Option<PathBuf>,
    /// Fidelity preset (see [`FIDELITIES`] and [`SceneSettings::preset`]): it sets every
    /// numerical knob ([`KNOBS`]) the file does not set itself.
    pub fidelity: String,
    // The numerical knobs: how finely a point is computed, not what it is.
    /// Timestep as a fraction of the Rayleigh time.
    pub rayleigh_fraction: f64,
    /// A fixed timestep, s, in place of `rayleigh_fraction` (0: use the fraction).
    pub timestep_s: f64,
    /// Young's modulus in the deck over the point's `youngs_modulus` (a softer contact allows a
    /// longer step; never below LIGGGHTS's floor of 5 MPa).
    pub stiffness_factor: f64,
    /// Blade mesh resolution: cells across the domain depth (the other faces use the same cell).
    pub mesh_cells_across: usize,
    /// Domain depth across the blade (periodic y), in particle diameters.
    pub depth_diameters: f64,
    /// Length of the MFR measurement window (blade travel), in diameters.
    pub window_diameters: f64,
    /// Gated layout: the pile is at rest when its rms speed is below this fraction of √(g·D).
    pub rest_speed: f64,
    /// Gated layout: the least settle before the rest criterion is first checked, in free-fall
    /// times of the dose block (a lattice block is still for an instant before it collapses).
    pub settle_min_falls: f64,
    /// Neighbour-list skin, in smallest diameters.
    pub skin_diameters: f64,
    /// Interval of a dump of every per-particle column over the whole run, s (0: none; only the
    /// window's snapshots of the columns the metrics read are written).
    pub full_dump_every_s: f64,
    /// Keep the blade going after the window to the end of the domain (the thesis's full
    /// traverse) instead of stopping once the window is measured.
    pub run_to_end: bool,
    // What the point is.
    /// The scene's layout: `"gated"` (default: the dose settles at rest in a closed region on a
    /// rough substrate and is released when the blade starts) or `"thesis"` (the thesis's pile
    /// on a smooth plate, settled for a fixed time).
    pub layout: String,
    /// Gated layout: `"rough"` (default: a layer of fixed spheres, as the previous powder layer
    /// a blade spreads onto) or `"smooth"` (a flat plate).
    pub substrate: String,
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

/// The fidelity presets, fastest first.
pub const FIDELITIES: [&str; 3] = ["fast", "reference", "thesis"];

/// The numerical knobs a preset sets (field names of [`SceneSettings`]); everything else in
/// `[scene]` says what the point is and is the same in every preset.
pub const KNOBS: [&str; 11] = [
    "rayleigh_fraction",
    "timestep_s",
    "stiffness_factor",
    "mesh_cells_across",
    "depth_diameters",
    "window_diameters",
    "rest_speed",
    "settle_min_falls",
    "skin_diameters",
    "full_dump_every_s",
    "run_to_end",
];

impl SceneSettings {
    /// The settings of a fidelity preset (docs/scene.md "Fidelity"; BENCHMARKS.md "Fidelity").
    ///
    /// - `fast` (default): the measured fastest settings whose MFR stays within the stated error
    ///   of `reference`.
    /// - `reference`: what errors are measured against: a fine step, a domain twice as deep,
    ///   a window twice as long, a stricter rest criterion, a fine blade mesh.
    /// - `thesis`: the thesis's way (the baseline every speed-up is quoted against): its fixed
    ///   1e-5 s step, every column dumped every 2,000 steps (0.02 s, Appendix A), the blade
    ///   driven to the end of the domain; every run settles its own pile.
    pub fn preset(fidelity: &str) -> Option<SceneSettings> {
        let fast = SceneSettings::default();
        match fidelity {
            "fast" => Some(fast),
            "reference" => Some(SceneSettings {
                fidelity: fidelity.into(),
                rayleigh_fraction: 0.1,
                stiffness_factor: 1.0,
                mesh_cells_across: 12,
                depth_diameters: 12.0,
                window_diameters: 80.0,
                rest_speed: 0.005,
                settle_min_falls: 2.0,
                skin_diameters: 0.25,
                ..fast
            }),
            "thesis" => Some(SceneSettings {
                fidelity: fidelity.into(),
                timestep_s: crate::scene::THESIS_TIMESTEP,
                stiffness_factor: 1.0,
                mesh_cells_across: 6,
                settle_min_falls: 2.0,
                skin_diameters: 0.25,
                full_dump_every_s: 0.02,
                run_to_end: true,
                ..fast
            }),
            _ => None,
        }
    }

    /// These settings with every knob the file did not write (`written`: keys of `[scene]`)
    /// taken from the preset named by `fidelity`.
    pub fn resolve_preset(&self, written: &[String]) -> std::result::Result<SceneSettings, String> {
        let preset = SceneSettings::preset(&self.fidelity)
            .ok_or_else(|| format!("\"{}\": expected one of {}", self.fidelity, quoted(&FIDELITIES)))?;
        let mut table = toml::Table::try_from(&preset).map_err(|e| e.to_string())?;
        let mine = toml::Table::try_from(self).map_err(|e| e.to_string())?;
        for key in written {
            if let Some(v) = mine.get(key) {
                table.insert(key.clone(), v.clone());
            }
        }
        let mut resolved: SceneSettings = table.try_into().map_err(|e: toml::de::Error| e.to_string())?;
        resolved.force_timestep = self.force_timestep;
        Ok(resolved)
    }
}

impl SceneSettings {
    /// These settings with every knob ([`KNOBS`]) and the fidelity's name taken from `preset`:
    /// the same point computed another way.
    pub fn with_knobs_of(&self, preset: &SceneSettings) -> SceneSettings {
        let mut s = preset.clone();
        s.template = self.template.clone();
        s.layout = self.layout.clone();
        s.substrate = self.substrate.clone();
        s.settle_max_s = self.settle_max_s;
        s.window_start_diameters = self.window_start_diameters;
        s.supply_factor = self.supply_factor;
        s.size_distribution = self.size_distribution.clone();
        s.vx_band_diameters = self.vx_band_diameters;
        s.thesis_band = self.thesis_band;
        s.seed = self.seed;
        s.force_timestep = self.force_timestep;
        s
    }

    /// These settings with `key = value` (TOML syntax) set, for a knob only.
    pub fn with_knob(&self, key: &str, value: &str) -> std::result::Result<SceneSettings, String> {
        if !KNOBS.contains(&key) {
            return Err(format!(
                "`{key}` is not a numerical knob{}; knobs: {}",
                hint(key, KNOBS),
                KNOBS.join(", ")
            ));
        }
        let parsed: toml::Table = toml::from_str(&format!("{key} = {value}"))
            .map_err(|_| format!("{key} = {value}: not a TOML value"))?;
        let mut table = toml::Table::try_from(self).map_err(|e| e.to_string())?;
        table.extend(parsed);
        let mut s: SceneSettings = table
            .try_into()
            .map_err(|e: toml::de::Error| format!("{key} = {value}: {}", e.message().trim()))?;
        s.force_timestep = self.force_timestep;
        Ok(s)
    }
}

fn quoted(names: &[&str]) -> String {
    names.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(", ")
}

impl Default for SceneSettings {
    fn default() -> Self {
        SceneSettings {
            template: None,
            fidelity: "fast".into(),
            // The fast preset (BENCHMARKS.md "Fidelity"): the largest step with a 1.5× margin
            // below the measured safe bound 0.5, a blade mesh of one cell across the depth
            // (the moving mesh's neighbour rebuilds dominate a step) and a skin of half a
            // diameter (fewer rebuilds): 2.4× less CPU than the previous 0.2 / 6 cells / 0.25
            // at worst |ΔMFR| 0.017 and mean 0.009 against the reference over 8 points × 2 seeds.
            // The stiffness reduction is not in it: 0.25 was 1.5× cheaper again but moved MFR
            // by up to 0.042.
            rayleigh_fraction: 0.33,
            timestep_s: 0.0,
            stiffness_factor: 1.0,
            mesh_cells_across: 1,
            depth_diameters: 6.0,
            // 40 D: measured 2.8× less seed-to-seed spread than 20 D for 1.6× the CPU
            // (BENCHMARKS.md "MFR noise").
            window_diameters: 40.0,
            rest_speed: 0.01,
            settle_min_falls: 2.0,
            skin_diameters: 0.5,
            full_dump_every_s: 0.0,
            run_to_end: false,
            layout: "gated".into(),
            substrate: "rough".into(),
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
        let mut file: SweepFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        // The preset fills the knobs the file leaves out (the file parsed, so this parses too).
        let raw: toml::Table = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        let written: Vec<String> = raw
            .get("scene")
            .and_then(|v| v.as_table())
            .map(|t| t.keys().cloned().collect())
            .unwrap_or_default();
        file.scene = file
            .scene
            .resolve_preset(&written)
            .map_err(|e| Error::input(format!("{}: scene.fidelity: {e}", path.display())))?;
        let (swept, fixed) = validate(&file, path)?;
        Ok(Sweep { path: path.to_path_buf(), file, swept, fixed })
    }

    /// This sweep with other scene settings, validated as if they had been written in the file.
    pub fn with_scene(&self, scene: SceneSettings) -> Result<Sweep> {
        let mut file = self.file.clone();
        file.scene = scene;
        let (swept, fixed) = validate(&file, &self.path)?;
        Ok(Sweep { path: self.path.clone(), file, swept, fixed })
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
    if crate::convergence::Rule::parse(&c.rule).is_none() {
        return Err(bad(
            "convergence.rule",
            format!("\"{}\": expected \"scaled\", \"any\" or \"all\"", c.rule),
        ));
    }
    if crate::weights::LatticeWeights::parse(&c.lattice_weights).is_none() {
        return Err(bad(
            "convergence.lattice_weights",
            format!("\"{}\": expected \"trapezoid\" or \"equal\"", c.lattice_weights),
        ));
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
    if !FIDELITIES.contains(&s.fidelity.as_str()) {
        return Err(bad(
            "scene.fidelity",
            format!("\"{}\": expected one of {}", s.fidelity, quoted(&FIDELITIES)),
        ));
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
        ("scene.stiffness_factor", s.stiffness_factor),
        ("scene.settle_min_falls", s.settle_min_falls),
        ("scene.skin_diameters", s.skin_diameters),
    ] {
        if !v.is_finite() || v <= 0.0 {
            return Err(bad(k, format!("{v}: expected a finite number > 0")));
        }
    }
    for (k, v) in [("scene.timestep_s", s.timestep_s), ("scene.full_dump_every_s", s.full_dump_every_s)] {
        if !v.is_finite() || v < 0.0 {
            return Err(bad(k, format!("{v}: expected a finite number ≥ 0 (0: off)")));
        }
    }
    if s.stiffness_factor > 1.0 {
        return Err(bad(
            "scene.stiffness_factor",
            format!("{}: expected at most 1 (a reduction)", s.stiffness_factor),
        ));
    }
    if s.mesh_cells_across == 0 {
        return Err(bad("scene.mesh_cells_across", "expected at least 1".into()));
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

#[cfg(test)]
mod preset_tests {
    use super::*;

    fn scene_of(scene: &str) -> Result<SceneSettings> {
        let text = format!("name = \"t\"\n[parameters]\ngap = {{ lo = 1.0, hi = 2.0 }}\n[scene]\n{scene}\n");
        Sweep::parse(&text, Path::new("t.toml")).map(|s| s.file.scene)
    }

    #[test]
    fn a_preset_sets_the_knobs_the_file_leaves_out_and_the_file_wins_where_it_speaks() {
        let r = scene_of("fidelity = \"reference\"").unwrap();
        assert_eq!(r, SceneSettings::preset("reference").unwrap());
        // The reference is finer in every knob it changes.
        let fast = SceneSettings::default();
        assert!(r.rayleigh_fraction < fast.rayleigh_fraction);
        assert!(r.depth_diameters > fast.depth_diameters && r.window_diameters > fast.window_diameters);
        assert!(r.rest_speed < fast.rest_speed && r.stiffness_factor >= fast.stiffness_factor);
        let mine = scene_of("fidelity = \"reference\"\ndepth_diameters = 5\nseed = 7").unwrap();
        assert_eq!((mine.depth_diameters, mine.seed, mine.window_diameters), (5.0, 7, r.window_diameters));
        let thesis = scene_of("fidelity = \"thesis\"").unwrap();
        assert_eq!(thesis.timestep_s, crate::scene::THESIS_TIMESTEP);
        assert!(thesis.run_to_end && thesis.full_dump_every_s > 0.0);
        assert_eq!(scene_of("").unwrap(), SceneSettings::default());
    }

    #[test]
    fn the_resolved_settings_read_back_to_themselves() {
        // DIR/sweep.toml holds every key: a resume must see the same knobs.
        let text = "name = \"t\"\n[parameters]\ngap = { lo = 1.0, hi = 2.0 }\n[scene]\nfidelity = \"thesis\"\nwindow_diameters = 30\n";
        let first = Sweep::parse(text, Path::new("t.toml")).unwrap();
        let body = toml::to_string(&first.file).unwrap();
        let again = Sweep::parse(&body, Path::new("sweep.toml")).unwrap();
        assert_eq!(again.file.scene, first.file.scene);
        assert_eq!(again.file.scene.window_diameters, 30.0);
    }

    #[test]
    fn a_bad_fidelity_or_knob_is_one_line_naming_the_key() {
        for (scene, key) in [
            ("fidelity = \"fastest\"", "scene.fidelity"),
            ("stiffness_factor = 2", "scene.stiffness_factor"),
            ("mesh_cells_across = 0", "scene.mesh_cells_across"),
            ("timestep_s = -1", "scene.timestep_s"),
        ] {
            let e = scene_of(scene).unwrap_err().to_string();
            assert!(e.contains(key) && !e.contains('\n'), "{scene}: {e}");
        }
    }

    #[test]
    fn knobs_of_a_preset_replace_only_the_knobs() {
        let mine =
            SceneSettings { supply_factor: 1.5, seed: 3, depth_diameters: 4.0, ..SceneSettings::default() };
        let r = mine.with_knobs_of(&SceneSettings::preset("reference").unwrap());
        assert_eq!((r.supply_factor, r.seed, r.fidelity.as_str()), (1.5, 3, "reference"));
        assert_eq!(r.depth_diameters, 12.0);
        let k = mine.with_knob("rayleigh_fraction", "0.3").unwrap();
        assert_eq!((k.rayleigh_fraction, k.supply_factor), (0.3, 1.5));
        assert!(mine.with_knob("supply_factor", "2").unwrap_err().contains("not a numerical knob"));
        assert!(mine.with_knob("run_to_end", "maybe").is_err());
    }
}
