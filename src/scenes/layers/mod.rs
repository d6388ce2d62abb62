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

pub mod fixed_point;
pub mod geometry;
pub mod laid;
pub mod measure;
pub mod numerics;
mod plan;
pub mod result;
pub mod settings;
pub mod stand_in;
mod top_view;
pub mod warm;

use plan::{derive, with_plan};
pub use plan::{part, plan_of, platform_gap, Pass, Passes, Plan, Resume};

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::outcome::{AnswerKind, RunResult};
use crate::scene::own_settings::OwnSettings;
use crate::scene::plausible::short;
use crate::scene::settings::SceneSettings;
use crate::scene::{Base, Scene};
use crate::scenes::{BadSetting, BuiltinTemplate, ByPass, Finished, Layout, Rejected, SetupRows};
pub use settings::{own, LayersSettings, DEFAULT_SEARCH_PASSES};

/// The layout's name, its `[scene] layout`.
pub const NAME: &str = "layers";

/// The least depth under the top surface a loose bed may be held still from, in diameters: the
/// blade's tip stands about a layer under the top and moves the bed a few diameters below it.
const MIN_FREEZE_DEPTH_DIAMETERS: f64 = 3.0;
const MAX_FREEZE_DEPTH_DIAMETERS: f64 = 1000.0;

/// A layers point's steady layer in results.csv: relative density and packing with their SE,
/// the powder under the blade (µm), cover, roughness (in D), the first steady pass and the
/// passes run, the numerical error beside the SE (packing, µm of depth, cover), and a roller's
/// torque and turning power per metre of its width and the powder it sends over its top a pass
/// (kg per metre of its width) with its SE.
const RESULT_COLUMNS: [&str; 17] = [
    "relative_density",
    "relative_density_se",
    "steady_packing",
    "steady_packing_se",
    "depth_um",
    "depth_se_um",
    "steady_covered_fraction",
    "steady_roughness_d",
    "steady_from",
    "passes",
    "numerical_error_packing",
    "numerical_error_depth_um",
    "numerical_error_cover",
    "roller_torque_nm_per_m",
    "roller_turning_power_w_per_m",
    "ejected_kg_per_m",
    "ejected_kg_per_m_se",
];

/// Dose of one pass on a loose bed over what the plate's layer can hold at
/// [`crate::scene::LAYER_FRACTION_MAX`] (times `scene.supply_factor`): twice what a steady loose pass leaves,
/// so that the last of the plate is covered.
pub const DOSE_FACTOR: f64 = 2.0;
/// The same on a fused bed, whose steady pass must leave a whole drop of solid (a loose one
/// about 0.6 of it): at [`DOSE_FACTOR`] Ti-6Al-4V 15–45 µm at 50 µm fell behind by 7 % a pass,
/// at twice it kept pace (docs/study/layers.md); the measured machine of Gaboriault et al. 2025
/// feeds about 5.7 layers of bulk powder a pass.
pub const FUSED_DOSE_FACTOR: f64 = 4.0;

/// Whether the settings ask for a fused bed.
fn fused(s: &SceneSettings) -> bool {
    Bed::parse(&own(s).bed) == Some(Bed::Fused)
}

/// The dose of one pass over what the plate's layer holds at [`crate::scene::LAYER_FRACTION_MAX`], before
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
/// The dose is at rest for the blade once its rms speed, and the bed's, is under this share of
/// the blade's speed: what the blade then meets carries a ten-thousandth of the kinetic energy it
/// gives it. Measured at the Ti-6Al-4V machine point, a dose reaches it 10,000–20,000 steps after
/// landing, the blade starting 21,000–34,000 steps into a wait that was 44,797 fixed
/// (docs/study/layers.md "A pass is its crossing").
pub const DOSE_REST_SHARE: f64 = 0.01;
/// Checks of the rest criterion over the fixed wait's measure of a dose's fall (the fall and as
/// long again): the blade starts at most a twentieth of it after the dose is at rest.
pub const SETTLE_CHECKS: u64 = 20;
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

impl Layout for Layers {
    fn name(&self) -> &'static str {
        NAME
    }

    fn template(&self) -> BuiltinTemplate {
        TEMPLATE
    }

    fn check_settings(&self, s: &SceneSettings) -> Result<(), BadSetting> {
        settings::check(s)
    }

    fn derive(&self, base: Base, settings: &SceneSettings) -> Scene {
        derive(base, settings)
    }

    fn own_keys(&self, _fidelity: &str, written: &toml::Table) -> Result<OwnSettings, toml::de::Error> {
        LayersSettings::read(written).map(OwnSettings::new)
    }

    fn own_settings(&self) -> Vec<&'static str> {
        // It spreads onto its own bed of the powder and measures the layers it leaves, not the
        // speed in front of the blade.
        vec![
            "supply_factor",
            "layers",
            "bed",
            "search_passes",
            "least_layers",
            "blade_profile",
            "blade_radius_mm",
            "roller_segments",
            "blade_clearance_mm",
            "plate_diameters",
            "freeze_depth_diameters",
            "warm_start",
            "laid_dose",
            "mesh_cells_across",
            "depth_diameters",
        ]
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

    fn check_result(&self, r: &RunResult) -> Result<(), crate::measure::plausible::Implausible> {
        // The answer and its windows are the passes' packing or relative density (deposit over
        // the drop): at most the packing bound times the powder under the blade over the drop.
        // No flux past the blade and no steadiness p-value: the passes are the test.
        let depth = result::series(r).map_or(1.0, |l| {
            l.passes.iter().map(|p| p.effective_thickness_m / l.layer_thickness_m).fold(1.0, f64::max)
        });
        crate::measure::plausible::check_result(
            r,
            crate::measure::plausible::Measures { flow: true, flux: result::series(r).is_none(), depth },
        )
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

    fn ignores(&self, settings: &SceneSettings, name: &str) -> Option<&'static str> {
        match name {
            "roller_speed_ratio" if own(settings).blade_profile != "roller" => Some(
                "turns no roller with this blade: only blade_profile = \"roller\" reads roller_speed_ratio",
            ),
            "gap" => Some("sets its blade layer_thickness (and scene.blade_clearance_mm) above the bed"),
            "heap_height" => Some("doses each pass by scene.supply_factor; only the conveyor layout holds a heap of a set height"),
            _ => None,
        }
    }

    fn setup_rows(&self, s: &SceneSettings) -> SetupRows {
        SetupRows {
            head: vec![
                ("passes", own(s).layers.to_string()),
                (
                    "bed",
                    if search_passes(s) > 0 {
                        match search_passes(s) {
                            1 => format!("{}, the first pass a search for its steady depth", own(s).bed),
                            n => {
                                format!("{}, the first {n} passes a search for its steady depth", own(s).bed)
                            }
                        }
                    } else {
                        own(s).bed.clone()
                    },
                ),
                (
                    "blade profile",
                    match own(s).blade_profile.as_str() {
                        "round" => format!("round, radius {} mm", short(own(s).blade_radius_mm)),
                        "roller" => format!(
                            "roller, radius {} mm (roller_speed_ratio turns it)",
                            short(own(s).blade_radius_mm)
                        ),
                        _ => "flat".into(),
                    },
                ),
                ("blade clearance over the plate's drops (mm)", short(own(s).blade_clearance_mm)),
                ("build plate length (D)", short(own(s).plate_diameters)),
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
        .into_iter()
        .chain(plan.roller.then(|| ("over.stl", geometry::over_stl(scene, &plan))))
        .collect()
    }

    fn run_files(&self, s: &SceneSettings) -> Vec<String> {
        // One dump per pass; the log is the run's own.
        (1..=own(s).layers.max(1)).map(measure::layer_dump).collect()
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

    fn warm_start(
        &self,
        _from: &Scene,
        from_dir: &std::path::Path,
        to: &Scene,
        _to_pile: &str,
        _distance: f64,
    ) -> Result<crate::scenes::Warm, crate::scenes::ColdStart> {
        warm::start(from_dir, to)
    }

    fn warm_again(&self, to: &Scene, data: &str) -> Result<Scene, String> {
        warm::again(to, data)
    }

    fn warm_start_files(&self) -> Option<crate::scenes::WarmFiles> {
        Some(crate::scenes::WarmFiles { state: crate::outcome::RESULT_FILE, data: warm::WARM_DATA })
    }

    fn with_most_passes(&self, scene: &Scene, most: usize) -> Result<Scene, String> {
        let mut plan = plan_of(scene);
        let room = plan.passes.len();
        if most > room {
            return Err(format!(
                "its machine is built for {room} passes (twice the sweep's scene.layers): run the point \
                 again with a larger scene.layers"
            ));
        }
        plan.most_passes = most;
        plan.last_pass = most;
        Ok(with_plan(scene, plan))
    }

    fn measured_through(&self, scene: &Scene, k: usize) -> Scene {
        let mut plan = plan_of(scene);
        plan.last_pass = k;
        with_plan(scene, plan)
    }

    fn ready_pass(&self, scene: &Scene, k: usize, run_dir: &Path) -> Result<(), String> {
        if plan_of(scene).laid_dose && k > laid::TEMPLATE_PASS {
            laid::ready(run_dir)?;
        }
        Ok(())
    }

    fn pass_files(&self, from: usize, to: usize) -> Vec<String> {
        let dose = (from <= laid::TEMPLATE_PASS).then_some([laid::DOSE_DUMP, laid::LAID_DOSE]);
        (from..=to).map(measure::layer_dump).chain(dose.into_iter().flatten().map(String::from)).collect()
    }

    fn pile(&self, _scene: &Scene) -> String {
        // The deck creates its box; every particle is inserted by a dose.
        String::new()
    }

    fn answer(&self, settings: &SceneSettings) -> AnswerKind {
        // A fused bed's relative density is the whole drop by construction.
        if fused(settings) {
            AnswerKind::SteadyPacking
        } else {
            AnswerKind::RelativeDensity
        }
    }

    fn answer_detail(&self, r: &RunResult) -> Option<String> {
        let l = result::series(r)?;
        Some(format!(
            // To 0.1 µm: a steady depth's SE is often under a micrometre, and "± 0" says nothing.
            "{:.1} ± {:.1} µm of powder under the blade ({:.1} × the layer thickness), steady from pass {} of {}{}",
            l.effective_thickness_m * 1e6,
            l.effective_thickness_se_m * 1e6,
            l.effective_thickness_m / l.layer_thickness_m,
            l.steady_from,
            l.passes.len(),
            l.numerical_error.as_ref().map_or(String::new(), |e| format!(
                "; numerical error {}",
                numerics::summary(e, l.effective_thickness_m)
            ))
        ))
    }

    fn calibration_targets(&self) -> &'static [crate::scenes::quantity::Quantity] {
        CALIBRATION_TARGETS
    }

    fn result_columns(&self) -> &'static [&'static str] {
        &RESULT_COLUMNS
    }

    fn result_values(&self, r: &RunResult) -> Vec<String> {
        let Some(l) = result::series(r) else { return vec![String::new(); RESULT_COLUMNS.len()] };
        let um = |m: f64| m * 1e6;
        let e = l.numerical_error.as_ref();
        let values = [
            Some(l.relative_density),
            Some(l.relative_density_se),
            Some(l.packing),
            Some(l.packing_se),
            Some(um(l.effective_thickness_m)),
            Some(um(l.effective_thickness_se_m)),
            Some(l.covered_fraction),
            Some(l.roughness_d),
            Some(l.steady_from as f64),
            Some(l.passes.len() as f64),
            e.map(|e| e.packing),
            e.map(|e| um(e.depth_fraction * l.effective_thickness_m)),
            e.map(|e| e.covered_fraction),
            l.roller.map(|r| r.mean.torque_nm_per_m),
            l.roller.map(|r| r.mean.turning_power_w_per_m),
            l.roller.and_then(|r| r.mean.ejected_kg_per_m),
            l.roller.and_then(|r| r.se.ejected_kg_per_m),
        ];
        values.iter().map(|v| v.filter(|v| v.is_finite()).map_or(String::new(), |v| v.to_string())).collect()
    }

    fn pass_series(&self, r: &RunResult) -> Option<crate::scenes::figures::PassSeries> {
        let l = result::series(r)?;
        Some(top_view::pass_series(l, l.bed == "fused"))
    }

    fn top_view(
        &self,
        scene: &Scene,
        run_dir: &Path,
        r: &RunResult,
    ) -> Option<Result<crate::scenes::figures::TopView, String>> {
        Some(top_view::top_view(scene, run_dir, result::series(r)?.passes.len()))
    }

    fn result_lines(&self, r: &RunResult) -> Option<Vec<String>> {
        let l = result::series(r)?;
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
        lines.extend(l.roller.iter().flat_map(measure::roller_lines));
        if let Some(e) = &l.numerical_error {
            lines.push(format!(
                "numerical error  {} (beside the SE, not in it)",
                numerics::summary(e, l.effective_thickness_m)
            ));
            for t in &e.terms {
                lines.push(format!(
                    "                 {}: packing {:.3}, depth {:.1} %, cover {:.2}",
                    t.choice,
                    t.packing,
                    100.0 * t.depth_fraction,
                    t.covered_fraction
                ));
            }
            if !e.unmeasured.is_empty() {
                lines.push(format!("                 not measured: {}", e.unmeasured.join(", ")));
            }
        }
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

/// What a calibration can fit a layers sweep to: its steady layer's relative density and
/// packing, with their SE over the steady passes, on either bed.
pub const CALIBRATION_TARGETS: &[crate::scenes::quantity::Quantity] = &[
    crate::scenes::quantity::Quantity {
        name: "relative_density",
        unit: "-",
        read: |r| result::series(r).map(|l| (l.relative_density, Some(l.relative_density_se))),
        repeats: 1,
        // Deposit over the drop: about 1 on a fused bed, which keeps the whole drop; a pass may
        // leave more than the drop, never twice it at the packing of spheres.
        possible: (0.0, 2.0),
        lo_possible: true,
    },
    crate::scenes::quantity::Quantity {
        name: "steady_packing",
        unit: "-",
        read: |r| result::series(r).map(|l| (l.packing, Some(l.packing_se))),
        repeats: 1,
        possible: (0.0, crate::measure::plausible::PACKING_MAX),
        lo_possible: true,
    },
];

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
    own(s)
        .search_passes
        .unwrap_or_else(|| DEFAULT_SEARCH_PASSES.min(own(s).layers.saturating_sub(MIN_LAID_PASSES)))
}

/// Largest round blade, mm.
pub const MAX_BLADE_RADIUS_MM: f64 = 100.0;
/// Highest blade tip over the machine's top surface, mm.
pub const MAX_CLEARANCE_MM: f64 = 10.0;
/// Longest build plate, in diameters (10,000 D is 300 mm of a 30 µm powder).
pub const MAX_PLATE_DIAMETERS: f64 = 10_000.0;

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
    own(s).least_layers.unwrap_or(search_passes(s) + STOP_KEPT_PASSES).min(own(s).layers.max(1))
}

#[cfg(test)]
mod tests;
