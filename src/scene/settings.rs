//! The `[scene]` settings of a sweep file: layout, substrate, supply, the fidelity presets and
//! their numerical knobs, and the size-distribution spec. Scene physics that the sweep file
//! carries, so it lives with the scene; the sweep file only holds it.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::error::hint;
use crate::scene::cohesion::CohesionScaling;
use crate::scene::own_settings::OwnSettings;

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default = "SceneSettings::fast")]
pub struct SceneSettings {
    /// A path to a Tera template overriding the built-in `spreading.liggghts.tera`
    /// (relative to the sweep file).
    pub template: Option<PathBuf>,
    /// Fidelity preset (see [`FIDELITIES`] and [`SceneSettings::common_preset`]): it sets every
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
    /// Gated layout: the pile is at rest when its rms speed is below this fraction of √(g·D).
    pub rest_speed: f64,
    /// Neighbour-list skin, in smallest diameters.
    pub skin_diameters: f64,
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
    /// Size of the heap in front of the blade, relative to the planned one (gated: gap + 10 D
    /// tall at 30° repose; thesis: the heap left at the end, gap + 6 D tall).
    pub supply_factor: f64,
    /// The layout's own keys, of its type ([`crate::scene::own_settings`]): written into
    /// `[scene]` beside these, read by `crate::scenes::settings::parse`, which gives them to the
    /// layout (deserialising these settings alone leaves them the defaults of none).
    #[serde(flatten, skip_deserializing)]
    pub own: OwnSettings,
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

/// The fidelity presets, fastest first.
pub const FIDELITIES: [&str; 3] = ["fast", "reference", "thesis"];

/// The numerical knobs a preset sets of the keys every layout's settings hold (field names of
/// [`SceneSettings`]; a layout's own keys name theirs, `LayoutSettings::knobs`); everything else
/// in `[scene]` says what the point is and is the same in every preset.
pub const KNOBS: [&str; 7] = [
    "rayleigh_fraction",
    "timestep_s",
    "stiffness_factor",
    "mesh_cells_across",
    "depth_diameters",
    "rest_speed",
    "skin_diameters",
];

impl SceneSettings {
    /// The keys every layout's settings hold at a fidelity preset (docs/scene.md "Fidelity";
    /// BENCHMARKS.md "Fidelity"), without any layout's own keys: not the settings of a point
    /// (`crate::scenes::settings::preset` gives a layout's whole preset).
    ///
    /// - `fast` (default): the measured fastest settings whose MFR stays within the stated error
    ///   of `reference`.
    /// - `reference`: what errors are measured against: a fine step, a domain twice as deep,
    ///   a window twice as long, a stricter rest criterion, a fine blade mesh.
    /// - `thesis`: the thesis's way (the baseline every speed-up is quoted against): its fixed
    ///   1e-5 s step, every column dumped every 2,000 steps (0.02 s, Appendix A), the blade
    ///   driven to the end of the domain; every run settles its own pile.
    pub fn common_preset(fidelity: &str) -> Option<SceneSettings> {
        let fast = SceneSettings::fast();
        match fidelity {
            "fast" => Some(fast),
            "reference" => Some(SceneSettings {
                fidelity: fidelity.into(),
                rayleigh_fraction: 0.1,
                stiffness_factor: 1.0,
                mesh_cells_across: 12,
                depth_diameters: 12.0,
                rest_speed: 0.005,
                skin_diameters: 0.25,
                ..fast
            }),
            "thesis" => Some(SceneSettings {
                fidelity: fidelity.into(),
                timestep_s: crate::scene::THESIS_TIMESTEP,
                stiffness_factor: 1.0,
                mesh_cells_across: 6,
                skin_diameters: 0.25,
                ..fast
            }),
            _ => None,
        }
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
    /// Not one of the knobs of the settings' layout (`knobs`: [`KNOBS`] and its own).
    #[error("`{key}` is not a numerical knob{}; knobs: {}", hint(.key, knobs.iter().copied()), knobs.join(", "))]
    NotAKnob { key: String, knobs: Vec<&'static str> },
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
    /// The fast preset of the keys every layout's settings hold, on the conveyor without its
    /// own keys (`crate::scenes::settings::parse` gives a layout its own).
    fn fast() -> SceneSettings {
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
            rest_speed: 0.01,
            skin_diameters: 0.5,
            layout: "conveyor".into(),
            substrate: "rough".into(),
            settle_max_s: 1.0,
            supply_factor: 1.0,
            own: OwnSettings::none(),
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
