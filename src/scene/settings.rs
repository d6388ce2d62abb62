//! The `[scene]` settings of a sweep file: layout, substrate, supply, the fidelity presets and
//! their numerical knobs, and the size-distribution spec. Scene physics that the sweep file
//! carries, so it lives with the scene; the sweep file only holds it.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::error::hint;
use crate::scene::cohesion::CohesionScaling;

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
    /// Conveyor layout: substrate travel per block of the deposit series, in diameters.
    pub block_diameters: f64,
    /// Conveyor layout: simulated time before the precision target is first checked, s (at
    /// least 10 D of travel). Unset (the default): [`WARMUP_HEAP_FALLS`] × √(H/g), H = gap +
    /// `heap_height`, the held heap's height ([`SceneSettings::warmup_for`]). The start-up
    /// transient is a time, not a travel, and that time is the heap's: run long, MFR settles
    /// within 3–6 √(H/g) at D 1–3 mm, heaps of 8–40 mm and 0.1–1.4 m/s (docs/study/recoater)
    /// and at D 24–35 µm, heaps of 0.3–1 mm and 0.02–0.2 m/s, cohesive or not
    /// (docs/study/warmup-um.md); 0.3 s at the thesis's heap, 0.04–0.07 s at a real powder's.
    /// A set value wins. The blocks after it are judged by the stop rule's MSER truncation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warmup_s: Option<f64>,
    /// Conveyor layout: the most travel after the warm-up, in diameters (the window's precision
    /// is a number of blocks): where it ends the run before the precision target is met, the
    /// point says so (`stop = "cap"`). The warm-up is never cut short by it.
    pub window_cap_diameters: f64,
    /// Conveyor layout: the window runs until the standard error of MFR is at most this
    /// fraction of MFR ...
    pub mfr_rel_se: f64,
    /// ... or at most this absolute value (MFR near zero), whichever is reached first.
    pub mfr_abs_se: f64,
    /// Conveyor layout: the least number of blocks after the warm-up before the target can stop
    /// the run.
    pub min_window_blocks: usize,
    /// Conveyor layout, in a sweep: start a point from the steady state a finished point near it
    /// left (its heap mapped to this point's size, speed and gap), so that the transient it must
    /// outlive is the difference between neighbours, not a heap starting from rest. A point with
    /// no such neighbour starts cold. The run's hash does not depend on it.
    pub warm_start: bool,
    /// Conveyor layout: the least warm-up of a warm-started point, s (at least one block); its
    /// warm-up is the cold one's times the neighbour's distance over 0.5, never less than 0.6 of
    /// the cold one nor than this.
    pub warm_warmup_s: f64,
    /// Conveyor layout, in a sweep: `"sweep"` — once the first batch has finished, every later
    /// point runs until the SE of its MFR is a tenth of the spread of MFR over that batch (what
    /// the sweep's statistics need; `mfr_rel_se`/`mfr_abs_se` until then); `"fixed"` — always
    /// `mfr_rel_se`/`mfr_abs_se` (the default when the file writes either).
    pub precision: String,
    // What the point is.
    /// The scene's layout: `"conveyor"` (default: the blade's frame, a held heap, MFR in a
    /// steady state with its SE), `"gated"` (the dose settles at rest in a closed region on a
    /// rough substrate and is released when the blade starts) or `"thesis"` (the thesis's pile
    /// on a smooth plate, settled for a fixed time).
    pub layout: String,
    /// Gated and conveyor layouts: `"rough"` (default: a layer of fixed spheres, as the previous
    /// powder layer a blade spreads onto) or `"smooth"` (a flat plate).
    pub substrate: String,
    /// Gated layout: longest settle, s; a pile still moving then fails the run (`not-settled`).
    pub settle_max_s: f64,
    /// Gated layout: blade travel past the opened gate before the window starts, in diameters.
    pub window_start_diameters: f64,
    /// Size of the heap in front of the blade, relative to the planned one (gated: gap + 10 D
    /// tall at 30° repose; thesis: the heap left at the end, gap + 6 D tall).
    pub supply_factor: f64,
    /// Layers layout: passes of the blade, each onto the layers before it.
    #[serde(skip_serializing_if = "is_default_layers")]
    pub layers: usize,
    /// Layers layout: `"loose"` (default: the layers before stay powder and are sheared again,
    /// as in a spreading test or binder jetting) or `"fused"` (each layer consolidates to a solid
    /// of its packing times its height before the next, as in laser or electron-beam fusion).
    #[serde(skip_serializing_if = "is_loose")]
    pub bed: String,
    /// Layers layout, fused bed: the first passes search for the steady depth of powder under
    /// the blade instead of building it up layer by layer — after each, the solid is set so that
    /// the next pass meets its own depth times the layer thickness over its deposit; 0: every
    /// pass is a layer on the one before, from the bare plate. Not set: a fused bed searches
    /// for [`DEFAULT_SEARCH_PASSES`] passes (at most `layers` less six), a loose bed never.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search_passes: Option<usize>,
    /// Layers layout: the fewest passes before a point may stop on its steady layer; it runs
    /// pass by pass until the steady rule holds or it reaches `layers`, the most. Not set: the
    /// search's passes and [`crate::scenes::layers::STOP_KEPT_PASSES`] laid ones after them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub least_layers: Option<usize>,
    /// Layers layout: the blade's profile, `"flat"` (default: a box, the thesis's) or `"round"`
    /// (a cylinder of `blade_radius_mm`, its lowest line the tip).
    #[serde(skip_serializing_if = "is_flat")]
    pub blade_profile: String,
    /// Layers layout: radius of a round blade, mm.
    #[serde(skip_serializing_if = "is_default_blade_radius")]
    pub blade_radius_mm: f64,
    /// Layers layout: height of the blade's tip above the machine's top surface (the level the
    /// dose is fed at and the platform drops from), mm; 0: the blade grazes it.
    #[serde(skip_serializing_if = "is_zero")]
    pub blade_clearance_mm: f64,
    /// Layers layout, a roller: segments of its circle's mesh (a numerical knob: the roller's
    /// resolution; the round blade's angle a segment by default).
    #[serde(skip_serializing_if = "is_default_roller_segments")]
    pub roller_segments: usize,
    /// Layers layout: length of the build plate along the travel, in diameters.
    #[serde(skip_serializing_if = "is_default_plate")]
    pub plate_diameters: f64,
    /// Layers layout, loose bed: the bed deeper than this many diameters under the machine's
    /// top surface, at rest and beyond the blade's reach, stops moving and its particles are not
    /// searched against each other (0: the whole bed moves).
    #[serde(skip_serializing_if = "is_zero")]
    pub freeze_depth_diameters: f64,
    /// Size distribution of the particles.
    pub size_distribution: SizeDistributionSpec,
    /// How the `surface_energy` parameter is carried to the deck's softened contact
    /// ([`crate::scene::cohesion`]): `"pull-off"` (default) or `"haervig"`.
    pub cohesion_scaling: CohesionScaling,
    /// The powder's real Young's modulus, GPa (for `cohesion_scaling = "haervig"`; 0: not given).
    pub material_youngs_gpa: f64,
    /// Half-height of each v_x layer, in diameters (0.25 = ±D/4); `thesis_band` overrides it
    /// with the thesis's fixed ±1 mm.
    pub vx_band_diameters: f64,
    pub thesis_band: bool,
    /// Seed of the initial pile: diameters and lattice jitter.
    pub seed: u64,
    /// Accept a timestep beyond [`crate::scene::MAX_RAYLEIGH_FRACTION`] and a point outside the
    /// bounds of [`crate::scene::plausible`] (`--force`; never read from a sweep file).
    #[serde(skip)]
    pub force_bounds: bool,
    /// Write particle (`custom/vtk`) and blade (`mesh/vtk`) VTK files over the spread for
    /// ParaView (`sweep run --vtk`; never read from a sweep file).
    #[serde(skip)]
    pub vtk: bool,
}

/// The default warm-up in gravity times of the held heap, √(H/g) with H = gap + `heap_height`
/// (docs/study/warmup-um.md): long runs at D 1–3 mm and 24–35 µm settle within it.
pub const WARMUP_HEAP_FALLS: f64 = 6.5;

/// The fidelity presets, fastest first.
pub const FIDELITIES: [&str; 3] = ["fast", "reference", "thesis"];

/// The numerical knobs a preset sets (field names of [`SceneSettings`]); everything else in
/// `[scene]` says what the point is and is the same in every preset.
pub const KNOBS: [&str; 21] = [
    "rayleigh_fraction",
    "timestep_s",
    "stiffness_factor",
    "mesh_cells_across",
    "roller_segments",
    "depth_diameters",
    "window_diameters",
    "rest_speed",
    "settle_min_falls",
    "skin_diameters",
    "full_dump_every_s",
    "run_to_end",
    "block_diameters",
    "warmup_s",
    "window_cap_diameters",
    "mfr_rel_se",
    "mfr_abs_se",
    "min_window_blocks",
    "warm_start",
    "warm_warmup_s",
    "precision",
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
                warm_start: false,
                precision: "fixed".into(),
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
                warm_start: false,
                precision: "fixed".into(),
                ..fast
            }),
            _ => None,
        }
    }

    /// These settings with every knob the file did not write (`written`: keys of `[scene]`)
    /// taken from the preset named by `fidelity`.
    pub fn resolve_preset(&self, written: &[String]) -> std::result::Result<SceneSettings, KnobError> {
        let preset = SceneSettings::preset(&self.fidelity)
            .ok_or_else(|| KnobError::UnknownFidelity { fidelity: self.fidelity.clone() })?;
        let mut table = toml::Table::try_from(&preset)?;
        let mine = toml::Table::try_from(self)?;
        for key in written {
            if let Some(v) = mine.get(key) {
                table.insert(key.clone(), v.clone());
            }
        }
        let mut resolved: SceneSettings = table.try_into()?;
        resolved.force_bounds = self.force_bounds;
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
        s.layers = self.layers;
        s.bed = self.bed.clone();
        s.search_passes = self.search_passes;
        s.least_layers = self.least_layers;
        s.blade_profile = self.blade_profile.clone();
        s.blade_radius_mm = self.blade_radius_mm;
        s.blade_clearance_mm = self.blade_clearance_mm;
        s.plate_diameters = self.plate_diameters;
        s.freeze_depth_diameters = self.freeze_depth_diameters;
        s.size_distribution = self.size_distribution.clone();
        s.cohesion_scaling = self.cohesion_scaling;
        s.material_youngs_gpa = self.material_youngs_gpa;
        s.vx_band_diameters = self.vx_band_diameters;
        s.thesis_band = self.thesis_band;
        s.seed = self.seed;
        s.force_bounds = self.force_bounds;
        s
    }

    /// These settings with `key = value` (TOML syntax) set, for a knob only.
    pub fn with_knob(&self, key: &str, value: &str) -> std::result::Result<SceneSettings, KnobError> {
        let (key, value) = (key.to_string(), value.to_string());
        if !KNOBS.contains(&key.as_str()) {
            return Err(KnobError::NotAKnob { key });
        }
        let Ok(parsed) = toml::from_str::<toml::Table>(&format!("{key} = {value}")) else {
            return Err(KnobError::NotToml { key, value });
        };
        let mut table = toml::Table::try_from(self)?;
        table.extend(parsed);
        let mut s: SceneSettings = table.try_into().map_err(|e: toml::de::Error| {
            let why = e.message().trim().to_string();
            KnobError::Value { key, value, why }
        })?;
        s.force_bounds = self.force_bounds;
        Ok(s)
    }
}

/// Why settings cannot take a preset's knobs or a knob's value.
#[derive(Debug, thiserror::Error)]
pub enum KnobError {
    /// A `fidelity` that names no preset.
    #[error("\"{fidelity}\": expected one of {}", quoted(&FIDELITIES))]
    UnknownFidelity { fidelity: String },
    /// The settings would not go through TOML (a broken invariant).
    #[error(transparent)]
    Write(#[from] toml::ser::Error),
    #[error(transparent)]
    Read(#[from] toml::de::Error),
    /// Not one of [`KNOBS`].
    #[error("`{key}` is not a numerical knob{}; knobs: {}", hint(.key, KNOBS), KNOBS.join(", "))]
    NotAKnob { key: String },
    #[error("{key} = {value}: not a TOML value")]
    NotToml { key: String, value: String },
    /// A value the knob cannot take; `why` is TOML's message.
    #[error("{key} = {value}: {why}")]
    Value { key: String, value: String, why: String },
}

pub(crate) fn quoted(names: &[&str]) -> String {
    names.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(", ")
}

impl SceneSettings {
    /// The conveyor's warm-up, s, for a held heap `heap_height` tall (m, gap included): the
    /// set `warmup_s`, or [`WARMUP_HEAP_FALLS`] × √(H/g).
    pub fn warmup_for(&self, heap_height: f64) -> f64 {
        self.warmup_s.unwrap_or_else(|| WARMUP_HEAP_FALLS * (heap_height / crate::scene::GRAVITY).sqrt())
    }
}

impl SceneSettings {
    /// The defaults on the gated layout (the unit tests of that scene).
    #[cfg(test)]
    pub(crate) fn gated() -> SceneSettings {
        SceneSettings { layout: "gated".into(), ..SceneSettings::default() }
    }
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
            block_diameters: 5.0,
            warmup_s: None,
            window_cap_diameters: 600.0,
            mfr_rel_se: 0.05,
            mfr_abs_se: 0.005,
            min_window_blocks: 8,
            // Opt-in: at machine speeds a warm start left points 3–5 SE above long runs that
            // a start from rest got right (BENCHMARKS.md "Warm start at machine speeds").
            warm_start: false,
            warm_warmup_s: 0.03,
            precision: "sweep".into(),
            layout: "conveyor".into(),
            substrate: "rough".into(),
            settle_max_s: 1.0,
            window_start_diameters: 30.0,
            supply_factor: 1.0,
            layers: DEFAULT_LAYERS,
            bed: "loose".into(),
            search_passes: None,
            least_layers: None,
            blade_profile: "flat".into(),
            blade_radius_mm: DEFAULT_BLADE_RADIUS_MM,
            roller_segments: DEFAULT_ROLLER_SEGMENTS,
            blade_clearance_mm: 0.0,
            plate_diameters: DEFAULT_PLATE_DIAMETERS,
            freeze_depth_diameters: 0.0,
            size_distribution: SizeDistributionSpec::default(),
            cohesion_scaling: CohesionScaling::PullOff,
            material_youngs_gpa: 0.0,
            vx_band_diameters: 0.25,
            thesis_band: false,
            seed: 12345,
            force_bounds: false,
            vtk: false,
        }
    }
}

/// Layers layout: passes by default; enough for the steady layer of every case measured
/// (docs/study/layers.md).
pub const DEFAULT_LAYERS: usize = 10;
/// Layers layout, fused bed: search passes by default (docs/study/layers.md: Ti-6Al-4V's depth
/// came within 3 % of its steady value in six).
pub const DEFAULT_SEARCH_PASSES: usize = 6;
/// Layers layout: a round blade's radius by default, mm (Gaboriault et al. 2025's blade).
pub const DEFAULT_BLADE_RADIUS_MM: f64 = 2.5;
/// Segments of a roller's whole circle: the round blade's angle a segment (its 48 over 0.75 of a
/// half circle); docs/study/roller.md "The roller's numerics" halves and doubles it.
pub const DEFAULT_ROLLER_SEGMENTS: usize = 128;
/// Layers layout: the build plate's length by default, in diameters.
pub const DEFAULT_PLATE_DIAMETERS: f64 = 40.0;

fn is_default_layers(n: &usize) -> bool {
    *n == DEFAULT_LAYERS
}
fn is_loose(b: &str) -> bool {
    b == "loose"
}
fn is_flat(p: &str) -> bool {
    p == "flat"
}
fn is_default_blade_radius(r: &f64) -> bool {
    *r == DEFAULT_BLADE_RADIUS_MM
}
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}
fn is_default_roller_segments(n: &usize) -> bool {
    *n == DEFAULT_ROLLER_SEGMENTS
}
fn is_default_plate(v: &f64) -> bool {
    *v == DEFAULT_PLATE_DIAMETERS
}

/// The particle size distribution, as written in the sweep file.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "kebab-case")]
pub enum SizeDistributionSpec {
    /// Every particle has the `diameter` parameter.
    #[default]
    Mono,
    /// Discrete classes: `classes = [[d, fraction], ...]`; `d` in mm, or in multiples of the
    /// `diameter` parameter when `relative = true` (thesis Tables 3.2–3.3); fractions by number,
    /// or by volume (`basis = "volume"`, as laser diffraction reports a measured table).
    Classes {
        classes: Vec<[f64; 2]>,
        #[serde(default)]
        relative: bool,
        #[serde(default, skip_serializing_if = "Basis::is_number")]
        basis: Basis,
    },
    /// Two-parameter Weibull in diameter, from the `weibull_shape` and `weibull_scale`
    /// parameters, discretised into `bins` classes of equal probability width.
    Weibull {
        #[serde(default = "default_bins")]
        bins: usize,
    },
    /// A lognormal fitted to a datasheet's D10, D50 and D90 (µm; by volume unless
    /// `basis = "number"`), truncated to `cut_um = [lo, hi]` (the sieve cut), discretised into
    /// `bins` classes of equal width in ln D. `relative = true` scales every size by
    /// `diameter` / D50, so the `diameter` parameter sweeps the powder's size at its shape.
    Lognormal {
        d10_um: f64,
        d50_um: f64,
        d90_um: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        cut_um: Option<[f64; 2]>,
        #[serde(default = "volume_basis")]
        basis: Basis,
        #[serde(default = "default_lognormal_bins")]
        bins: usize,
        #[serde(default)]
        relative: bool,
    },
}

impl SizeDistributionSpec {
    /// The sizes in a few words, for the report's setup.
    pub fn describe(&self) -> String {
        let basis = |b: &Basis| if *b == Basis::Volume { "by volume" } else { "by number" };
        match self {
            SizeDistributionSpec::Mono => "one size (diameter)".into(),
            SizeDistributionSpec::Classes { classes, relative, basis: b } => {
                let (lo, hi) = classes
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| (lo.min(c[0]), hi.max(c[0])));
                let unit = if *relative { "× diameter" } else { "mm" };
                format!("{} classes, {lo}–{hi} {unit}, fractions {}", classes.len(), basis(b))
            }
            SizeDistributionSpec::Weibull { bins } => {
                format!("Weibull (weibull_shape, weibull_scale), {bins} classes")
            }
            SizeDistributionSpec::Lognormal { d10_um, d50_um, d90_um, cut_um, basis: b, bins, relative } => {
                let mut out =
                    format!("lognormal fitted to D10/D50/D90 = {d10_um}/{d50_um}/{d90_um} µm {}", basis(b));
                if let Some([lo, hi]) = cut_um {
                    out += &format!(", sieved to {lo}–{hi} µm");
                }
                out += &format!(", {bins} classes");
                if *relative {
                    out += ", scaled by diameter / D50";
                }
                out
            }
        }
    }

    /// Why the size parameter `name` (`diameter`, `weibull_shape`, `weibull_scale`) plays no part
    /// in these sizes, if it plays none.
    pub fn ignores(&self, name: &str) -> Option<&'static str> {
        use SizeDistributionSpec::*;
        match (name, self) {
            ("diameter", Classes { relative: false, .. } | Lognormal { relative: false, .. }) => Some(
                "the size distribution's sizes are absolute; set `relative = true` in [scene.size_distribution] to scale them by `diameter`, or fix `diameter`",
            ),
            ("diameter", Weibull { .. }) => Some(
                "a Weibull size distribution takes its sizes from weibull_scale and weibull_shape; sweep those instead",
            ),
            ("weibull_shape" | "weibull_scale", Mono | Classes { .. } | Lognormal { .. }) => {
                Some("only a Weibull size distribution reads it (kind = \"weibull\" in [scene.size_distribution])")
            }
            _ => None,
        }
    }
}

/// What the fractions of a size distribution count.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Basis {
    /// Fractions of the particles (what the engine inserts by).
    #[default]
    Number,
    /// Fractions of the volume (laser diffraction, every powder datasheet).
    Volume,
}

impl Basis {
    fn is_number(&self) -> bool {
        *self == Basis::Number
    }
}

fn volume_basis() -> Basis {
    Basis::Volume
}

fn default_bins() -> usize {
    5
}

fn default_lognormal_bins() -> usize {
    10
}
