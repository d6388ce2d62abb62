//! The layers layout: the layer a machine prints on. The blade spreads layer k onto layers
//! 1…k−1, the platform dropping by `layer_thickness` between passes and the dose refilled, for
//! `scene.layers` passes; the answer is the steady layer, not the first on a bare plate.
//!
//! Geometry (docs/layers.md): x is the blade's travel, y across it (periodic), z up. The build
//! plate lies at z = 0 between `plate_x0` and `plate_x1`, in a well: before pass k the blade's
//! tip stands k · layer_thickness and `blade_clearance_mm` above the plate — the platform's drop
//! in the plate's frame (the bed never moves, so nothing has to settle after a drop) — and the
//! [`platform_gap`] above the machine's top surface, the feed platform before the well and a wall
//! after it. A dose is inserted above the feed platform, falls, and the blade pushes it over
//! the plate; what passes the plate falls into a pit beyond it and is deleted with what is left
//! on the feed platform. Meshes are re-created at each pass's height (`move` of
//! `fix mesh/surface`), so the blade returns to its start with nothing to sweep back over.
//!
//! Two beds ([`Bed`]): loose — the layers stay powder and each pass shears them again
//! (spreading tests, binder jetting); fused — after each pass the powder on the plate is replaced
//! by a solid of its volume (laser or electron-beam fusion), so the powder the blade meets
//! converges to the drop over the layer's packing.
//!
//! What each pass measures ([`measure`]): the solid volume it added to the plate (as a height),
//! Gaboriault et al. 2025's layer relative density (that over the drop), the powder's depth under
//! the tip, the layer's packing, the covered fraction and the roughness. The steady layer is the
//! passes after an MSER truncation of the point's measure, with their mean and SE.

pub mod geometry;
pub mod measure;
pub mod stand_in;

use serde::{Deserialize, Serialize};

use crate::outcome::RunResult;
use crate::scene::plausible::short;
use crate::scene::settings::{SceneSettings, DEFAULT_SEARCH_PASSES};
use crate::scene::{
    prime_seed, Base, Feed, FeedClass, Scene, GRAVITY, LAYER_FRACTION_MAX, MIN_INSERT_VOLUME,
};
use crate::scenes::moving_blade::{self, Dose};
use crate::scenes::{BadSetting, BuiltinTemplate, ByPass, Finished, Layout, Rejected, SetupRows};

/// Dose of one pass on a loose bed over what the plate's layer can hold at
/// [`LAYER_FRACTION_MAX`] (times `scene.supply_factor`): twice what a steady loose pass leaves,
/// so that the last of the plate is covered.
pub const DOSE_FACTOR: f64 = 2.0;
/// The same on a fused bed, whose steady pass must leave a whole drop of solid (a loose one
/// about 0.6 of it): at [`DOSE_FACTOR`] Ti-6Al-4V 15–45 µm at 50 µm fell behind by 7 % a pass,
/// at twice it kept pace (docs/study/layers.md); the measured machine of Gaboriault et al. 2025
/// feeds about 5.7 layers of bulk powder a pass.
pub const FUSED_DOSE_FACTOR: f64 = 4.0;

/// Whether the settings ask for a fused bed.
fn fused(s: &SceneSettings) -> bool {
    Bed::parse(&s.bed) == Some(Bed::Fused)
}

/// The dose of one pass over what the plate's layer holds at [`LAYER_FRACTION_MAX`], before
/// `scene.supply_factor`.
fn dose_factor(s: &SceneSettings) -> f64 {
    if fused(s) {
        FUSED_DOSE_FACTOR
    } else {
        DOSE_FACTOR
    }
}
/// Volume fraction the dose is inserted at (random placement without overlaps, before it falls);
/// a dose too small for LIGGGHTS's least insertion region is inserted sparser.
pub const DOSE_FRACTION: f64 = 0.3;
/// Fastest a sparse dose is thrown down, m/s: a few times a dense dose's landing speed, well
/// under a speed at which a fine powder's contacts need a shorter timestep.
pub const MAX_DOSE_SPEED: f64 = 0.5;
/// Length of the feed platform the dose lies on, over the plate's length.
const FEED_OVER_PLATE: f64 = 0.5;
/// Length of the pit beyond the plate, in diameters: it holds one pass's excess dose.
const PIT_DIAMETERS: f64 = 20.0;
/// Blade travel over which it accelerates from rest to full speed, in diameters.
const RAMP_DIAMETERS: f64 = 2.0;
/// Chance that a point whose passes have no trend at all is called unsteady: the slope test's
/// two-sided level, shared between the series a bed checks (one loose, two fused).
pub const TREND_FALSE_ALARM: f64 = 0.05;
/// Lag-1 autocorrelation of a fused bed's depth under the blade from pass to pass, which its
/// steady layer's SE and slope test allow for: the mean over twelve steady Ti-6Al-4V records at
/// 30–80 µm (docs/study/layers.md "How correlated the passes are"), 0.5–0.9 within its SE.
pub const FUSED_DEPTH_LAG1: f64 = 0.65;
/// Lag-1 autocorrelation of a fused bed's packing and relative density, likewise (0–0.3).
pub const FUSED_PACKING_LAG1: f64 = 0.15;
/// Fewest passes in the steady layer for a mean and an SE.
pub const MIN_STEADY_PASSES: usize = 3;
/// Most passes a point may ask for (each is a whole spread; 30 is hours at 20–40 µm).
pub const MAX_LAYERS: usize = 100;
/// Deepest powder under the blade a fused bed's search may ask for, in layer thicknesses (a
/// layer packed at 0.05).
pub const SEARCH_MAX_DEPTH_LAYERS: f64 = 20.0;
/// Most a search pass may multiply the depth by (a pass that deposited almost nothing).
pub const SEARCH_MAX_GROWTH: f64 = 3.0;
/// Share of a round blade's half circle that is meshed, centred on its lowest line (Gaboriault
/// et al.'s case generator meshes 0.75 of it; above it the blade's faces are vertical).
pub const ROUND_ARC_SHARE: f64 = 0.75;

/// The built-in deck.
const TEMPLATE: BuiltinTemplate = BuiltinTemplate {
    name: "layers.liggghts.tera",
    source: include_str!("../../../templates/layers.liggghts.tera"),
};

/// The layers layout (registered in [`crate::scenes::LAYOUTS`]).
pub struct Layers;

/// What happens to a layer once the next is spread onto it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Bed {
    /// It stays powder and is sheared again.
    Loose,
    /// It consolidates to a solid of its volume.
    Fused,
}

impl Bed {
    pub fn parse(name: &str) -> Option<Bed> {
        match name {
            "loose" => Some(Bed::Loose),
            "fused" => Some(Bed::Fused),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Bed::Loose => "loose",
            Bed::Fused => "fused",
        }
    }
}

/// One pass of the blade, as the deck runs it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pass {
    /// From 1.
    pub k: usize,
    /// Height of the machine's top surface — the feed platform and the wall — over the plate, m.
    pub top: f64,
    /// Height of the blade's tip over the plate, m.
    pub tip: f64,
    /// Step at which the blade starts (its ramp counts from it).
    pub start: u64,
    /// Prime seed of this pass's dose.
    pub seed: u64,
}

/// The layers layout's own numbers (`scene.own`). Lengths in m.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub fused: bool,
    pub layer_thickness: f64,
    /// Fused bed: the first passes that search for the steady depth (not layers on the one
    /// before), and the deepest powder under the tip they may ask for.
    #[serde(default)]
    pub search_passes: usize,
    #[serde(default)]
    pub search_max_depth: f64,
    /// Least deposit a search pass counts (a pass that left almost nothing multiplies the depth
    /// by at most [`SEARCH_MAX_GROWTH`]).
    #[serde(default)]
    pub search_least_deposit: f64,
    /// The blade's tip over the plate's k drops (the first layer is a drop and this deep).
    pub clearance: f64,
    /// The blade's tip over the feed platform and the wall: the clearance, but a round blade's
    /// at least the largest diameter ([`platform_gap`]).
    #[serde(default)]
    pub platform_gap: f64,
    pub plate_x0: f64,
    pub plate_x1: f64,
    /// Plate area (length × depth), m².
    pub plate_area: f64,
    /// The feed platform's back end (its top runs from here to `plate_x0`).
    pub feed_x0: f64,
    /// How far the feed platform's and the wall's faces reach below their top: past the plate
    /// at the last pass.
    pub block_depth: f64,
    /// The round blade's radius (0: flat).
    pub blade_radius: f64,
    /// x of the blade's lowest line at the start (flat: its rear face), and its travel in a pass.
    pub tip_x0: f64,
    pub travel: f64,
    /// The dose's insertion region above the top surface.
    pub dose_x0: f64,
    pub dose_x1: f64,
    pub dose_lift: f64,
    pub dose_height: f64,
    /// The first dose's region height: it fills the clearance too.
    pub first_dose_height: f64,
    pub dose_fraction: f64,
    /// Downward speed the dose is inserted at, m/s (0 unless it is sparse).
    pub dose_speed: f64,
    pub dose_particles: usize,
    /// Steps of the first dose's fall before the first pass.
    pub fall_steps: u64,
    /// Steps of a pass until the blade has cleared the feed platform (the next dose goes in).
    pub clear_steps: u64,
    /// Steps of the blade's whole pass, the rest after it, and the wait for the rest of the
    /// next dose's fall before the next pass.
    pub pass_steps: u64,
    pub rest_steps: u64,
    pub wait_steps: u64,
    /// Every pass the machine is built for: its box and its faces reach the last of them, so
    /// that `sweep extend` can add passes up to it ([`EXTEND_ROOM`] times the most).
    pub passes: Vec<Pass>,
    /// The most passes a point runs (`scene.layers`); 0 in a plan read from an older result: all.
    #[serde(default)]
    pub most_passes: usize,
    /// The passes this deck runs, from 1: every pass in the deck `sweep render` writes, one in
    /// a point's run by the pass.
    #[serde(default = "first")]
    pub first_pass: usize,
    #[serde(default)]
    pub last_pass: usize,
    /// A deck of a point's run by the pass: each pass readies the next one's dose and lift,
    /// whether or not the point runs it.
    #[serde(default)]
    pub by_pass: bool,
    /// The state the deck's first pass goes on from, if it is not the first.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resume: Option<Resume>,
    /// The fewest passes before the point may stop on its steady layer (the most: `passes`).
    #[serde(default)]
    pub least_passes: usize,
    pub feed: Vec<FeedClass>,
    pub volume_limit: f64,
    pub distribution_seed: u64,
}

fn first() -> usize {
    1
}

/// Where a pass goes on from: the restart the last pass wrote, and on a fused bed the solid's
/// top it left (m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Resume {
    pub restart: String,
    pub solid: f64,
}

impl Plan {
    /// Steps of the whole run: the first dose's fall, then each pass with its rest and wait.
    pub fn total_steps(&self) -> u64 {
        let n = self.most() as u64;
        self.fall_steps + n * (self.pass_steps + self.rest_steps) + n.saturating_sub(1) * self.wait_steps
    }

    /// The most passes a point runs.
    pub fn most(&self) -> usize {
        if self.most_passes == 0 {
            self.passes.len()
        } else {
            self.most_passes
        }
    }

    /// The last pass this deck runs (a plan read from an older result runs every pass).
    pub fn reached(&self) -> usize {
        if self.last_pass == 0 {
            self.most()
        } else {
            self.last_pass
        }
    }

    /// The platform's drop before pass `k` (from 1): the first includes the clearance.
    pub fn drop_before(&self, k: usize) -> f64 {
        if k == 1 {
            self.layer_thickness + self.clearance
        } else {
            self.layer_thickness
        }
    }
}

impl Layout for Layers {
    fn name(&self) -> &'static str {
        "layers"
    }

    fn template(&self) -> BuiltinTemplate {
        TEMPLATE
    }

    fn check_settings(&self, s: &SceneSettings) -> Result<(), BadSetting> {
        if !(1..=MAX_LAYERS).contains(&s.layers) {
            return Err(BadSetting {
                key: "scene.layers",
                why: format!("{}: expected a whole number of passes from 1 to {MAX_LAYERS}", s.layers),
            });
        }
        if Bed::parse(&s.bed).is_none() {
            return Err(BadSetting {
                key: "scene.bed",
                why: format!("\"{}\": expected \"loose\" or \"fused\"", s.bed),
            });
        }
        let asked = s.search_passes.unwrap_or(0);
        if asked > 0 && !fused(s) {
            return Err(BadSetting {
                key: "scene.search_passes",
                why: format!(
                    "{asked}: a search for the steady depth needs bed = \"fused\" (a loose bed's depth is the powder it keeps); expected 0"
                ),
            });
        }
        if asked > 0 && asked + MIN_STEADY_PASSES > s.layers {
            return Err(BadSetting {
                key: "scene.search_passes",
                why: format!(
                    "{asked}: expected at most scene.layers − {MIN_STEADY_PASSES} = {} (the steady layer needs {MIN_STEADY_PASSES} passes after the search)",
                    s.layers.saturating_sub(MIN_STEADY_PASSES)
                ),
            });
        }
        if let Some(least) = s.least_layers {
            if !(1..=s.layers).contains(&least) {
                return Err(BadSetting {
                    key: "scene.least_layers",
                    why: format!(
                        "{least}: expected a whole number of passes from 1 to scene.layers = {} (the most a point runs)",
                        s.layers
                    ),
                });
            }
        }
        if !matches!(s.blade_profile.as_str(), "flat" | "round") {
            return Err(BadSetting {
                key: "scene.blade_profile",
                why: format!("\"{}\": expected \"flat\" or \"round\"", s.blade_profile),
            });
        }
        for (key, v, least) in [
            ("scene.blade_radius_mm", s.blade_radius_mm, f64::MIN_POSITIVE),
            ("scene.blade_clearance_mm", s.blade_clearance_mm, 0.0),
            ("scene.plate_diameters", s.plate_diameters, 10.0),
            ("scene.supply_factor", s.supply_factor, 0.5),
        ] {
            if !(v.is_finite() && v >= least) {
                return Err(BadSetting {
                    key,
                    why: format!("{v}: expected a finite number of at least {least}"),
                });
            }
        }
        if s.substrate == "powder" {
            return Err(BadSetting {
                key: "scene.substrate",
                why: "\"powder\": the layers layout spreads its own bed of the powder (scene.bed); expected \"smooth\" or \"rough\", which it ignores".into(),
            });
        }
        Ok(())
    }

    fn derive(&self, base: Base, settings: &SceneSettings) -> Scene {
        derive(base, settings)
    }

    fn atoms_kept(&self, _scene: &Scene) -> Option<u64> {
        // Doses are inserted and what lies off the plate deleted, pass by pass.
        None
    }

    fn measure(&self, run: &Finished) -> Result<RunResult, Rejected> {
        measure::measure(run)
    }

    fn stand_in(&self, point: &mut crate::scenes::stand_in::StandInPoint) -> Result<RunResult, Rejected> {
        stand_in::passes(point)
    }

    fn what_runs(&self, s: &Scene) -> String {
        let plan = plan_of(s);
        format!(
            "{} passes of {} particles' dose onto a {} bed, {} steps",
            plan.most(),
            plan.dose_particles,
            if plan.fused { "fused" } else { "loose" },
            plan.total_steps()
        )
    }

    fn ignores(&self, name: &str) -> Option<&'static str> {
        match name {
            "gap" => Some("sets its blade layer_thickness (and scene.blade_clearance_mm) above the bed"),
            "heap_height" => Some("doses each pass by scene.supply_factor; only the conveyor layout holds a heap of a set height"),
            "scene.substrate" => Some("spreads onto its own bed of the powder (scene.bed)"),
            "scene.vx_band_diameters" => Some("measures the layers it leaves, not the speed in front of the blade"),
            _ => None,
        }
    }

    fn setup_rows(&self, s: &SceneSettings) -> SetupRows {
        SetupRows {
            head: vec![
                ("passes", s.layers.to_string()),
                (
                    "bed",
                    if search_passes(s) > 0 {
                        match search_passes(s) {
                            1 => format!("{}, the first pass a search for its steady depth", s.bed),
                            n => format!("{}, the first {n} passes a search for its steady depth", s.bed),
                        }
                    } else {
                        s.bed.clone()
                    },
                ),
                (
                    "blade profile",
                    if s.blade_profile == "round" {
                        format!("round, radius {} mm", short(s.blade_radius_mm))
                    } else {
                        "flat".into()
                    },
                ),
                ("blade clearance over the plate's drops (mm)", short(s.blade_clearance_mm)),
                ("build plate length (D)", short(s.plate_diameters)),
                ("dose (× the plate's layer)", short(dose_factor(s) * s.supply_factor)),
            ],
            tail: Vec::new(),
        }
    }

    fn mesh(&self, scene: &Scene) -> String {
        geometry::blade_stl(scene, &plan_of(scene))
    }

    fn extra_meshes(&self, scene: &Scene) -> Vec<(&'static str, String)> {
        let plan = plan_of(scene);
        vec![
            ("feed.stl", geometry::feed_stl(scene, &plan)),
            ("wall.stl", geometry::wall_stl(scene, &plan)),
            ("plate.stl", geometry::plate_stl(scene, &plan)),
            ("pit.stl", geometry::pit_stl(scene, &plan)),
        ]
    }

    fn run_files(&self, s: &SceneSettings) -> Vec<String> {
        // One dump per pass; the log is the run's own.
        (1..=s.layers.max(1)).map(measure::layer_dump).collect()
    }

    fn by_pass(&self, scene: &Scene) -> Option<ByPass> {
        let plan = plan_of(scene);
        Some(ByPass { least: plan.least_passes.max(1), most: plan.most() })
    }

    fn pass_scene(&self, scene: &Scene, k: usize, before: Option<(&str, &str)>) -> Result<Scene, String> {
        let mut plan = plan_of(scene);
        plan.resume = match before {
            None if k == 1 => None,
            None => return Err(format!("pass {k} goes on from pass {}'s restart, and there is none", k - 1)),
            Some((restart, log)) => {
                let solid = if plan.fused {
                    let solids = measure::parse_solids(log);
                    solids.iter().find(|(j, _)| *j == k - 1).map(|s| s.1).ok_or_else(|| {
                        format!("pass {}'s log does not say where its solid's top is", k - 1)
                    })?
                } else {
                    0.0
                };
                Some(Resume { restart: restart.to_string(), solid })
            }
        };
        plan.first_pass = k;
        plan.last_pass = k;
        plan.by_pass = true;
        Ok(with_plan(scene, plan))
    }

    fn measured_through(&self, scene: &Scene, k: usize) -> Scene {
        let mut plan = plan_of(scene);
        plan.last_pass = k;
        with_plan(scene, plan)
    }

    fn pass_files(&self, from: usize, to: usize) -> Vec<String> {
        (from..=to).map(measure::layer_dump).collect()
    }

    fn pile(&self, _scene: &Scene) -> String {
        // The deck creates its box; every particle is inserted by a dose.
        String::new()
    }

    fn answer_name(&self, settings: &SceneSettings) -> &'static str {
        if fused(settings) {
            "steady-layer packing"
        } else {
            "steady-layer relative density"
        }
    }

    fn answer_detail(&self, r: &RunResult) -> Option<String> {
        let l = r.layers.as_ref()?;
        Some(format!(
            // To 0.1 µm: a steady depth's SE is often under a micrometre, and "± 0" says nothing.
            "{:.1} ± {:.1} µm of powder under the blade ({:.1} × the layer thickness), steady from pass {} of {}",
            l.effective_thickness_m * 1e6,
            l.effective_thickness_se_m * 1e6,
            l.effective_thickness_m / l.layer_thickness_m,
            l.steady_from,
            l.passes.len()
        ))
    }

    fn result_lines(&self, r: &RunResult) -> Option<Vec<String>> {
        let l = r.layers.as_ref()?;
        let mut lines = vec![format!(
            "steady layer     from pass {} of {}{}: packing {:.3} ± {:.3}, relative density {:.3} ± {:.3}",
            l.steady_from,
            l.passes.len(),
            if l.steady { "" } else { " (NOT steady)" },
            l.packing,
            l.packing_se,
            l.relative_density,
            l.relative_density_se
        )];
        lines.push(format!(
            "                 {:.1} ± {:.1} µm of powder under the tip (layer {:.0} µm), {:.2} covered, roughness {:.2} D",
            l.effective_thickness_m * 1e6,
            l.effective_thickness_se_m * 1e6,
            l.layer_thickness_m * 1e6,
            l.covered_fraction,
            l.roughness_d
        ));
        lines.push("pass  deposit µm  rel. density  depth µm  packing  covered  rough D".into());
        for p in &l.passes {
            lines.push(format!(
                "{:>4}  {:>10.1}  {:>12.3}  {:>8.1}  {:>7.3}  {:>7.2}  {:>7.2}",
                p.k,
                p.deposit_m * 1e6,
                p.relative_density,
                p.effective_thickness_m * 1e6,
                p.packing,
                p.covered_fraction,
                p.roughness_d
            ));
        }
        Some(lines)
    }
}

/// Laid passes a default search leaves after it: the steady layer's [`MIN_STEADY_PASSES`] and as
/// many again for MSER to cut a transient from (with only three left, a point of eight passes
/// failed as unsteady whenever MSER cut one).
const MIN_LAID_PASSES: usize = 2 * MIN_STEADY_PASSES;

/// The passes that search for a fused bed's steady depth: as set, or by default
/// [`DEFAULT_SEARCH_PASSES`] less what [`MIN_LAID_PASSES`] needs after them; none on a loose bed.
pub fn search_passes(s: &SceneSettings) -> usize {
    if !fused(s) {
        return 0;
    }
    s.search_passes.unwrap_or_else(|| DEFAULT_SEARCH_PASSES.min(s.layers.saturating_sub(MIN_LAID_PASSES)))
}

/// How many times its most passes (`scene.layers`) a point's box and faces are built for:
/// `sweep extend` adds passes up to that many (a restart keeps the box it was written with).
pub const EXTEND_ROOM: usize = 2;

/// Laid passes a point's steady layer keeps, at the least, before it stops on it short of its
/// most passes (a fused bed's also keeping the whole drop: [`measure::keeps_the_drop`]): with
/// three, the slope test (|t| within 12.7 at 5 %) let a transient pass for steady. Replayed on
/// the 35 recorded runs, stopping so saves 15 % of their passes, the answer where it stops
/// within 0.83 combined SE of all its passes' (RMS; one of 28 beyond 2); at five 7 %, at three
/// 26 % with three beyond 2 (docs/study/layers/stop_rule.py). At its most passes a point is
/// judged on [`MIN_STEADY_PASSES`] as before.
pub const STOP_KEPT_PASSES: usize = 4;

/// The fewest passes before a point may stop on its steady layer: as set, or the search's and
/// [`STOP_KEPT_PASSES`] after it (never above the most, `layers`).
pub fn least_passes(s: &SceneSettings) -> usize {
    s.least_layers.unwrap_or(search_passes(s) + STOP_KEPT_PASSES).min(s.layers.max(1))
}

/// The blade's tip over the feed platform and the wall. A round blade's arc closes on a flat
/// face in a wedge: with less than the largest diameter under its tip it grinds the powder on the
/// feed platform into the face, and a soft powder is pressed through it (measured at
/// Ti-6Al-4V 15–45 µm with no clearance: 29 particles inside the platform after the first pass,
/// 65 after the second, thrown out at up to 10 m/s, and the neighbour lists rebuilt every 10
/// steps for 1.7 × the crossing's CPU; docs/study/layers.md "The platform gap"). So it rides at
/// least that high over both; a flat blade meets the powder with its vertical face and keeps the
/// clearance.
pub fn platform_gap(blade_radius: f64, clearance: f64, d_max: f64) -> f64 {
    if blade_radius > 0.0 {
        clearance.max(d_max)
    } else {
        clearance
    }
}

/// `scene` carrying `plan`.
fn with_plan(scene: &Scene, plan: Plan) -> Scene {
    let mut s = scene.clone();
    s.own = serde_json::to_value(plan).expect("a plan serialises");
    s
}

/// The plan a scene of this layout carries.
pub fn plan_of(scene: &Scene) -> Plan {
    scene.own::<Plan>().cloned().expect("a layers scene carries its plan")
}

/// The scene of a layers point: the moving blade's common numbers, then the well, the dose and
/// the passes.
fn derive(base: Base, settings: &SceneSettings) -> Scene {
    let t = base.layer_thickness;
    let clearance = settings.blade_clearance_mm * 1e-3;
    let mut s = moving_blade::derive(base.clone(), settings, Dose::Free);
    let Base { psd, d, speed: v, timestep: dt, .. } = base;
    let fused = fused(settings);
    let layers = settings.layers.max(1);
    let plate_len = settings.plate_diameters.max(10.0) * d;
    let feed_len = FEED_OVER_PLATE * plate_len;
    let radius = if settings.blade_profile == "round" { settings.blade_radius_mm * 1e-3 } else { 0.0 };
    // The blade's x extent about its lowest line: behind and ahead of it.
    let (behind, ahead) = if radius > 0.0 {
        let half = radius * (0.5 * ROUND_ARC_SHARE * std::f64::consts::PI).sin();
        (half, half)
    } else {
        (0.0, d)
    };
    let d_max = psd.max_diameter();
    let platform_gap = platform_gap(radius, clearance, d_max);
    let tip_x0 = 0.5 * d + behind + d;
    let front0 = tip_x0 + ahead;
    let dose_x0 = front0 + 0.5 * d;
    let plate_x0 = dose_x0 + feed_len + d;
    let plate_x1 = plate_x0 + plate_len;
    // The tip runs past the plate's end by two diameters: everything ahead of it is in the pit.
    let travel = plate_x1 + 2.0 * d - tip_x0;
    let x_hi = plate_x1 + 2.0 * d + ahead + PIT_DIAMETERS * d;

    let dose_x1 = plate_x0 - d;
    // Every dose is dose_factor layers of the drop; the first fills the drop and the clearance.
    // LIGGGHTS refuses to insert into a region under its floor once shrunk by the largest
    // diameter (MIN_INSERT_VOLUME): a fine powder in thin layers gets its dose inserted sparser
    // in a taller region at the same depth, not a wider box (which would multiply the particles
    // of every layer).
    let w = s.depth;
    let dose_for = |drop: f64| {
        dose_factor(settings) * settings.supply_factor * plate_len * drop * LAYER_FRACTION_MAX * w
    };
    let dose_len = dose_x1 - dose_x0;
    let (dose_solid, first_solid) = (dose_for(t), dose_for(t + clearance));
    let shrunk_area = (dose_len - d_max) * (w - d_max);
    let dose_fraction = DOSE_FRACTION.min(dose_solid / (dose_len * w) * shrunk_area / MIN_INSERT_VOLUME);
    let dose_particles = (dose_solid / psd.mean_volume()).ceil() as usize;
    let region_height = |solid: f64, fraction: f64| solid / (fraction * dose_len * w) + d_max;
    let (dose_height, first_dose_height) =
        (region_height(dose_solid, dose_fraction), region_height(first_solid, dose_fraction));
    let dose_lift = 0.5 * d;
    // The box and the machine's faces reach the last pass `sweep extend` may add.
    let room = EXTEND_ROOM * layers;
    let last_top = room as f64 * t;
    // A search may set the solid below the plate (the depth it asks for deeper than the layers so
    // far): the feed platform's and the wall's faces reach that far down too.
    let search_passes = search_passes(settings);
    let search_max_depth = if search_passes > 0 { SEARCH_MAX_DEPTH_LAYERS * t } else { 0.0 };
    let block_depth = last_top + clearance + 2.0 * d + search_max_depth;
    // The pit holds a pass's excess dose below the plate.
    let pit_depth = 10.0 * d + first_solid / (LAYER_FRACTION_MAX * PIT_DIAMETERS * d * w);
    // The blade stands above the first dose as it would lie at DOSE_FRACTION (a sparse dose
    // falls in front of it and settles lower).
    let blade_height = (dose_lift + region_height(first_solid, DOSE_FRACTION) + 2.0 * d)
        .max(radius * (1.0 - (0.5 * ROUND_ARC_SHARE * std::f64::consts::PI).cos()) + 2.0 * d);
    let z_top = last_top + clearance + blade_height.max(dose_lift + first_dose_height) + 2.0 * d;

    let steps = |time: f64| ((time / dt).ceil() as u64).max(1);
    // The dose falls from the top of its region, and as long again to come down in a heap. The
    // first dose falls before the first pass; every later one is inserted as soon as the blade
    // has cleared the feed platform, and falls while the blade crosses the plate (what is left
    // of its fall is waited for before the next pass).
    // A sparse dose is thrown down so that it lands in about the time the dense one falls (at
    // most at MAX_DOSE_SPEED): its tall region would otherwise take longer to fall than a pass.
    let dense_height = dose_lift + region_height(dose_solid, DOSE_FRACTION);
    let dense_fall = (2.0 * dense_height / GRAVITY).sqrt();
    let dose_speed = ((dose_lift + dose_height - dense_height).max(0.0) / dense_fall).min(MAX_DOSE_SPEED);
    let fall = |height: f64| {
        let h = dose_lift + height;
        steps(2.0 * ((dose_speed * dose_speed + 2.0 * GRAVITY * h).sqrt() - dose_speed) / GRAVITY)
    };
    let (fall_steps, later_fall_steps) = (fall(first_dose_height), fall(dose_height));
    let ramp_time = 2.0 * RAMP_DIAMETERS * d / v;
    let ramp_steps = steps(ramp_time);
    let pass_steps = steps(travel / v + 0.5 * ramp_time);
    let clear_travel = (plate_x0 - (tip_x0 - behind)).min(travel);
    let clear_steps = steps(clear_travel / v + 0.5 * ramp_time).min(pass_steps);
    let rest_steps = steps((2.0 * 10.0 * d / GRAVITY).sqrt());
    let wait_steps = later_fall_steps.saturating_sub(pass_steps - clear_steps + rest_steps);
    let cycle = pass_steps + rest_steps + wait_steps;
    let passes = (1..=room)
        .map(|k| {
            let tip = k as f64 * t + clearance;
            Pass {
                k,
                top: tip - platform_gap,
                tip,
                start: fall_steps + (k as u64 - 1) * cycle,
                seed: prime_seed(settings.seed, 100 + k),
            }
        })
        .collect();
    let Feed { classes: feed, volume_limit } = Feed::of(&psd, settings.seed);
    let plan = Plan {
        fused,
        layer_thickness: t,
        search_passes,
        search_max_depth,
        search_least_deposit: t / SEARCH_MAX_GROWTH,
        clearance,
        platform_gap,
        plate_x0,
        plate_x1,
        plate_area: plate_len * w,
        feed_x0: 0.5 * d,
        block_depth,
        blade_radius: radius,
        tip_x0,
        travel,
        dose_x0,
        dose_x1,
        dose_lift,
        dose_height,
        first_dose_height,
        dose_fraction,
        dose_speed,
        dose_particles,
        fall_steps,
        clear_steps,
        pass_steps,
        rest_steps,
        wait_steps,
        first_pass: 1,
        most_passes: layers,
        last_pass: layers,
        by_pass: false,
        resume: None,
        least_passes: least_passes(settings),
        passes,
        feed,
        volume_limit,
        distribution_seed: prime_seed(settings.seed, 0),
    };

    let mass = (first_solid / psd.mean_volume() + dose_particles as f64 * layers as f64)
        * s.material.density
        * psd.mean_volume();
    let v_ref = v.max((2.0 * GRAVITY * z_top).sqrt());
    s.gap = t + clearance;
    s.particles = dose_particles * layers;
    s.pile_n = [0, 0, 0];
    s.rest_ke = 0.0;
    s.blade_x0 = tip_x0;
    s.blade_thickness = if radius > 0.0 { 0.0 } else { d };
    s.blade_top = blade_height;
    s.x_hi = x_hi;
    // The feed platform's and the wall's faces reach block_depth under their top, which stands
    // lower than the plate's drops where the platform gap exceeds the clearance.
    s.z_lo = -(block_depth.max(pit_depth) + d + (platform_gap - clearance));
    s.z_hi = z_top + v * v / GRAVITY;
    s.settle_steps = 0;
    s.approach_steps = 0;
    s.ramp_steps = ramp_steps;
    s.window_length_steps = fall_steps + cycle * layers as u64 - wait_steps;
    s.dump_every = 0;
    s.thermo_every = (cycle / 20).clamp(1, 1000);
    s.ke_limit = 0.5 * mass * (10.0 * v_ref).powi(2);
    s.set_own(plan);
    s
}

#[cfg(test)]
mod tests;
