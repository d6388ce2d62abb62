//! The moving-blade layouts, `gated` and `thesis`: a pile in front of a blade that travels over
//! the plate, leaving a layer behind. The two differ only in how the dose starts ([`Dose`]).
//!
//! Geometry (docs/scene.md "Geometry"): x is the blade's travel, z is up, y is across the blade
//! and periodic (the domain depth is the blade width w). A pile is inserted in front of the
//! blade, settles on the plate z = 0, and the blade — a box whose tip is at z = gap — then
//! pushes it over the plate in +x, leaving a layer behind. Walls at both x ends keep every
//! particle in the box, so any lost atom is an instability, never an outlet.
//!
//! The run, in steps: settle → approach (the blade accelerates over a short ramp, crosses the
//! pile, and the heap develops) → measurement window ([`SUB_WINDOWS`] sub-windows of
//! [`SNAPSHOTS_PER_SUB_WINDOW`] snapshot intervals each). The run stops at the window's end:
//! the metrics count particles crossing the blade's faces between snapshots, so nothing after
//! the window is needed.

use crate::engine::dump::read_dump;
use crate::measure::frame::{Frame, COLUMNS};
use crate::measure::metrics;
use crate::measure::plausible;
use crate::outcome::{FailureClass, PointAnswer, RunResult, RESULT_FORMAT};
use crate::scene::blade::{Blade, Settle, Spreader, Window};
use crate::scene::own::{LayoutData, OwnData};
use crate::scene::own_settings::OwnSettings;
use crate::scene::pile::PileBlock;
use crate::scene::plausible::short;
use crate::scene::settings::SceneSettings;
use crate::scene::substrate::Substrate;
use crate::scene::{
    Base, LayoutScene, Scene, GRAVITY, LAYER_FRACTION_MAX, REPOSE_DEG, SNAPSHOTS_PER_SUB_WINDOW, SUB_WINDOWS,
    THESIS_BAND,
};
use crate::scenes::{BadSetting, BuiltinTemplate, Finished, Layout, Rejected, SetupRows};

pub mod settings;
pub use settings::{own, SpreadSettings};

/// Blade travel over which it accelerates from rest to full speed, in diameters. A blade that
/// starts at full speed throws the particles touching it high into the air.
const RAMP_DIAMETERS: f64 = 2.0;
/// Lattice spacing of the initial pile over the largest diameter: room for a small jitter.
const LATTICE_CLEARANCE: f64 = 1.05;
/// Length over height of the initial pile block.
const PILE_ASPECT: f64 = 1.5;
/// Gated layout: MFR assumed when sizing the dose's deposit, above every MFR measured over a
/// 24-point LDS draw of the thesis space (largest 0.126). MFR rises with the heap the blade
/// pushes, so a dose sized at the mean MFR (0.07) was tried to keep the heap the same whatever
/// the window: it removed no measured shift, and 2 of 24 points then failed as unsteady
/// against none (BENCHMARKS.md "Scene convergence", study C).
const MFR_ALLOWANCE: f64 = 0.15;
/// Gated layout: simulated time between checks of the rest criterion, s.
const SETTLE_CHECK_S: f64 = 0.005;

/// Gated layout: height of the heap pushed by the blade above the gap, in diameters (its window
/// is in diameters too: a heap in millimetres does not become steady in it at small D).
const GATED_HEAP_DIAMETERS: f64 = 10.0;

/// The built-in deck of both moving-blade layouts (it branches on `scene.layout`).
const TEMPLATE: BuiltinTemplate = BuiltinTemplate {
    name: "spreading.liggghts.tera",
    source: include_str!("../../../templates/spreading.liggghts.tera"),
};

/// The snapshots of the window, in the run directory.
pub const DUMP: &str = "dump.spread";

/// The moving-blade layouts' part of the scene: the blade over its substrate with its window,
/// the dose's block and the settle, and what only a blade crossing its dose runs (`own`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Spread {
    #[serde(flatten)]
    pub spreader: Spreader,
    #[serde(flatten)]
    pub pile: PileBlock,
    #[serde(flatten)]
    pub settle: Settle,
    /// The deck's `scene.own.*`.
    pub own: DoseRun,
}

impl LayoutData for Spread {
    fn steps(&self) -> u64 {
        self.spreader.window.spread_steps()
    }
    fn spreader(&self) -> Option<&Spreader> {
        Some(&self.spreader)
    }
    fn pile(&self) -> Option<&PileBlock> {
        Some(&self.pile)
    }
}

/// What only a blade crossing its dose runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DoseRun {
    /// x of the gate closing the dose's region during the settle; 0: no gate.
    pub gate_x: f64,
    /// Steps after the window to the end of the domain (`run_to_end`; 0: stop at the window's
    /// end).
    pub traverse_steps: u64,
    /// Steps between dumps of every column over the whole run (0: none).
    pub full_dump_every: u64,
}

/// The part of a moving-blade scene.
pub fn spread(scene: &Scene) -> &Spread {
    scene.own().expect("a moving-blade scene carries its spread")
}

/// The `[scene]` keys both moving-blade layouts read of those some layout does not
/// ([`Layout::own_settings`]): the heap, the window and what the run dumps, the v_x profile, the
/// blade's mesh and the domain's depth.
const SPREAD_SETTINGS: &[&str] = &[
    "supply_factor",
    "window_diameters",
    "full_dump_every_s",
    "run_to_end",
    "vx_band_diameters",
    "thesis_band",
    "mesh_cells_across",
    "depth_diameters",
];

/// ... and those the gated layout reads besides: its substrate, and its dose's settle to rest
/// behind the gate (the thesis's pile settles for a fixed time on the smooth plate).
const GATED_SETTINGS: &[&str] =
    &["substrate", "settle_max_s", "settle_min_falls", "rest_speed", "window_start_diameters"];

/// A moving-blade layout: the dose it starts from (registered in [`crate::scenes::LAYOUTS`]).
pub struct MovingBlade(pub Dose);

/// The gated layout: the dose settles at rest in a region closed by a gate, on a rough (or
/// smooth) substrate, and is released when the blade starts.
pub const GATED: MovingBlade = MovingBlade(Dose::Gated);
/// The thesis's layout: its free pile on a smooth plate, settled for a fixed time.
pub const THESIS: MovingBlade = MovingBlade(Dose::Free);

impl Layout for MovingBlade {
    fn name(&self) -> &'static str {
        match self.0 {
            Dose::Gated => "gated",
            Dose::Free => "thesis",
        }
    }

    fn template(&self) -> BuiltinTemplate {
        TEMPLATE
    }

    fn check_settings(&self, settings: &SceneSettings) -> Result<(), BadSetting> {
        own(settings).check().map_err(|(key, why)| BadSetting { key, why })?;
        if settings.substrate == "powder" {
            return Err(BadSetting {
                key: "scene.substrate",
                why: "\"powder\": a bed of the powder is the conveyor layout's; expected \"rough\" or \"smooth\"".into(),
            });
        }
        Ok(())
    }

    fn derive(&self, base: Base, settings: &SceneSettings) -> Scene {
        derive(base, settings, self.0)
    }

    fn own_keys(&self, fidelity: &str, written: &toml::Table) -> Result<OwnSettings, toml::de::Error> {
        SpreadSettings::read(fidelity, written).map(OwnSettings::new)
    }

    fn own_settings(&self) -> Vec<&'static str> {
        let gate: &[&str] = if self.0 == Dose::Gated { GATED_SETTINGS } else { &[] };
        [SPREAD_SETTINGS, gate].concat()
    }

    fn atoms_kept(&self, scene: &Scene) -> Option<u64> {
        Some(scene.atoms() as u64)
    }

    fn stand_in(&self, point: &mut crate::scenes::stand_in::StandInPoint) -> Result<RunResult, Rejected> {
        Ok(crate::scenes::stand_in::flow(point))
    }

    fn measure(&self, run: &Finished) -> Result<RunResult, Rejected> {
        measure(run)
    }

    fn what_runs(&self, scene: &Scene) -> String {
        format!("{} particles, settle + {} steps", scene.particles, scene.run_steps())
    }

    fn run_files(&self, _settings: &SceneSettings) -> Vec<String> {
        vec![DUMP.into()]
    }

    fn ignores(&self, _settings: &SceneSettings, name: &str) -> Option<&'static str> {
        match name {
            "roller_speed_ratio" => Some(super::NO_ROLLER),
            "heap_height" => {
                Some("pushes the heap its pile leaves; only the conveyor layout holds one of a set height")
            }
            "layer_thickness" => Some(super::ONE_LAYER),
            _ => None,
        }
    }

    fn setup_rows(&self, s: &SceneSettings) -> SetupRows {
        SetupRows {
            head: vec![("heap size (× the planned heap)", short(s.supply_factor))],
            tail: vec![
                ("window start, blade travel (D)", short(own(s).window_start_diameters)),
                ("window length, blade travel (D)", short(own(s).window_diameters)),
                ("rest speed (× √(g·D))", short(s.rest_speed)),
            ],
        }
    }
}

/// How the dose starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dose {
    /// Settles at rest in a region closed by a gate and is released when the blade starts; the
    /// blade pushes a heap gap + 10 D tall through the window.
    Gated,
    /// A free pile settled for a fixed time; the blade pushes the heap left at the window's
    /// end, gap + 6 D tall.
    Free,
}

/// The scene of a moving-blade point: the pile, the blade's travel, the window, the timing.
pub fn derive(base: Base, settings: &SceneSettings, dose: Dose) -> Scene {
    // The conveyor and the layers start from the thesis's scene without these keys: their preset.
    let keys = settings
        .own
        .get::<SpreadSettings>()
        .cloned()
        .unwrap_or_else(|| SpreadSettings::preset(&settings.fidelity));
    let Base { psd, d, d_min, gap, speed, timestep, .. } = base.clone();
    let density = base.material.density;
    // Geometry in units of the mean diameter, so the particle count barely changes with D.
    // The dose starts as a jittered simple-cubic block (an exact, reproducible count; no
    // random insertion to fall short). The depth is a whole number of lattice spacings so
    // the periodic images keep their spacing.
    let gated = dose == Dose::Gated;
    let spacing = LATTICE_CLEARANCE * psd.max_diameter();
    let ny = ((settings.depth_diameters * d / spacing).round() as usize).max(3);
    let depth = ny as f64 * spacing;
    let blade_thickness = d;
    let blade_x0 = d;
    let front0 = blade_x0 + blade_thickness;
    let pile_x0 = front0 + 0.5 * d;
    // The heap in front of the blade, a triangle at the angle of repose, times the supply
    // factor. Thesis layout: the heap left at the window's end, tall enough to fill the 12
    // v_x layers (z up to gap + 6 D). Gated: the heap the blade pushes through the window,
    // gap + 10 D tall, whatever the window's length (MFR depends on the heap: the study
    // measured +15 % at one point when a longer window's dose made the heap larger).
    let heap_height = gap + if gated { GATED_HEAP_DIAMETERS } else { 6.0 } * d;
    let heap_area = settings.supply_factor * heap_height.powi(2) / (2.0 * REPOSE_DEG.to_radians().tan());
    let window = keys.window_diameters * d;
    // Travel of the blade's front from its start to the window's start, for a block of
    // length `len` and height `height`. Gated: past the opened gate (the block's front) by
    // the development length. Thesis: past the settled pile's slump (about half its
    // height) and 5 D more.
    let approach_travel = |len: f64, height: f64| {
        if gated {
            0.5 * d + len + keys.window_start_diameters * d
        } else {
            0.5 * d + len + 0.5 * height + 5.0 * d
        }
    };
    // Travel = approach + window; the block's size depends on the particle count, which
    // depends on the travel: iterate to the fixed point.
    let (mut nx, mut nz) = (0usize, 0usize);
    let mut pile_len = 10.0 * d;
    for _ in 0..50 {
        let travel = approach_travel(pile_len, pile_len / PILE_ASPECT) + window;
        // Solid area (volume per depth) of the dose: the heap at a packing of 0.6, plus what
        // the blade deposits over its travel. Thesis: at the upper bound (MFR 0.6), so the
        // heap at the end is at least the planned one. Gated: at MFR_ALLOWANCE, above the
        // most the gated scene deposits, so the heap is at least its planned size.
        let deposit = if gated { MFR_ALLOWANCE } else { LAYER_FRACTION_MAX };
        let area = LAYER_FRACTION_MAX * heap_area + deposit * gap * travel;
        let needed = (area * depth / psd.mean_volume()).ceil();
        let per_layer = needed / ny as f64;
        nz = ((per_layer / PILE_ASPECT).sqrt().ceil() as usize).max(1);
        nx = ((per_layer / nz as f64).ceil() as usize).max(1);
        let new_len = nx as f64 * spacing;
        if new_len == pile_len {
            break;
        }
        pile_len = new_len;
    }
    let particles = nx * ny * nz;
    let pile_x1 = pile_x0 + pile_len;
    let pile_z1 = nz as f64 * spacing;
    let ramp_time = 2.0 * RAMP_DIAMETERS * d / speed;
    // Travel during the ramp is half of full speed × ramp time.
    let approach_time = approach_travel(pile_len, pile_z1) / speed + 0.5 * ramp_time;
    let window_time = window / speed;
    // A free fall from the top of the block, then as long again for the pile to come to
    // rest: the thesis layout's fixed settle, and the gated layout's least settle before
    // the rest criterion is checked (a lattice block is briefly still before it collapses).
    let fall_time = 2.0 * (2.0 * pile_z1 / GRAVITY).sqrt();
    let settle_time = if gated { 0.5 * keys.settle_min_falls * fall_time } else { fall_time + 0.02 };

    let intervals = (SUB_WINDOWS * SNAPSHOTS_PER_SUB_WINDOW) as f64;
    let dump_every = ((window_time / intervals) / timestep).ceil().max(1.0) as u64;
    let round_up = |t: f64| ((t / timestep).ceil() as u64).div_ceil(dump_every) * dump_every;
    let settle_steps = (settle_time / timestep).ceil() as u64;
    let settle_check_steps = (SETTLE_CHECK_S / timestep).ceil() as u64;
    // The free pile has no rest criterion: no checks, whatever `settle_max_s` says.
    let settle_max_checks = if gated {
        ((settings.settle_max_s - settle_time).max(0.0) / SETTLE_CHECK_S).ceil().max(1.0) as u64
    } else {
        0
    };
    let approach_steps = round_up(approach_time);
    let ramp_steps = ((ramp_time / timestep).ceil() as u64).max(1);
    let window_length_steps = (SUB_WINDOWS * SNAPSHOTS_PER_SUB_WINDOW) as u64 * dump_every;
    let total_travel = speed * timestep * (approach_steps + window_length_steps) as f64;
    // Room ahead for the heap at the end, plus a margin.
    let x_hi = front0 + total_travel + 3.0 * heap_height + 5.0 * d;
    // Particles climb the blade's face in a fast, shallow pile (supercritical: v/√(gH) ≫ 1);
    // a blade three pile heights tall keeps nearly all of them in front of it. Any that fly
    // over are excluded from the flux counts (they cross far above the tip).
    let blade_top = 3.0 * pile_z1 + 2.0 * d;
    // A fixed top high enough for a particle launched at √2 times the blade speed
    // (v²/g): anything above it has exploded, and LIGGGHTS stops on the lost atom at once
    // (a shrink-wrapped top would follow an exploding particle and grow without bound).
    let z_hi = blade_top + 2.0 * d + speed * speed / GRAVITY;
    // The rough substrate (gated layout): spheres of the mean diameter touching on a square
    // lattice that fits the periodic depth, their tops at z = 0, so the gap is measured
    // from the substrate's top as from the thesis's plate. The plate under it only catches
    // a sphere small enough to fall through a pocket.
    let rough = gated && settings.substrate == "rough";
    let (substrate_n, substrate_spacing) = if rough {
        let n_y = ((depth / d).floor() as usize).max(1);
        let s = depth / n_y as f64;
        ([(x_hi / s).floor() as usize, n_y], s)
    } else {
        ([0, 0], 0.0)
    };
    let z_lo = if rough { -d } else { 0.0 };
    let total_steps = approach_steps + window_length_steps;
    // The thesis's full traverse: on after the window until the blade's front is two heap
    // heights from the far wall (the heap it pushes fills the rest).
    let traverse_steps = if keys.run_to_end {
        let travel = (3.0 * heap_height + 5.0 * d) - 2.0 * heap_height;
        (travel / (speed * timestep)).ceil() as u64
    } else {
        0
    };
    let full_dump_every = if keys.full_dump_every_s > 0.0 {
        (keys.full_dump_every_s / timestep).round().max(1.0) as u64
    } else {
        0
    };

    // ParaView files every 0.02 s of the spread (the thesis's output cadence, Appendix A).

    let profile_diameter = if psd.is_mono() { d } else { psd.quantile(0.85) };
    let vx_band =
        if settings.thesis_band { THESIS_BAND } else { settings.vx_band_diameters * profile_diameter };
    // Unstable: kinetic energy of the whole pile moving at 10× the fastest speed the scene
    // can give it (the blade, or a free fall from the top of the box).
    let mass = particles as f64 * density * psd.mean_volume();
    let v_ref = speed.max((2.0 * GRAVITY * blade_top).sqrt());
    let ke_limit = 0.5 * mass * (10.0 * v_ref).powi(2);
    // At rest: rms speed below a small fraction of √(g·D), the speed a sphere gains
    // falling through one diameter.
    let rest_speed = if gated { settings.rest_speed * (GRAVITY * d).sqrt() } else { 0.0 };
    let rest_ke = if gated { 0.5 * mass * rest_speed * rest_speed } else { 0.0 };

    let laid = LayoutScene {
        particles,
        x_hi,
        depth,
        z_hi,
        z_lo,
        mesh_cell: depth / settings.mesh_cells_across as f64,
        // Frequent enough for the engine's watcher to stop an exploding run early.
        thermo_every: (total_steps / 40).clamp(1, 200),
        ke_limit,
        own: OwnData::new(Spread {
            spreader: Spreader {
                blade: Blade {
                    gap,
                    blade_speed: speed,
                    blade_thickness,
                    blade_x0,
                    blade_top,
                    blade_y_inset: 1e-3 * d_min,
                    blade_fixed: false,
                    ramp_steps,
                },
                window: Window {
                    approach_steps,
                    window_length_steps,
                    dump_every,
                    profile_diameter,
                    vx_band,
                    vx_length: 6.0 * profile_diameter,
                },
                substrate: Substrate {
                    substrate_particles: substrate_n[0] * substrate_n[1],
                    substrate_diameter: if rough { d } else { 0.0 },
                    substrate_spacing,
                    substrate_n,
                    substrate_bed: None,
                },
            },
            pile: PileBlock { pile_x0, pile_x1, pile_z1, pile_spacing: spacing, pile_n: [nx, ny, nz] },
            settle: Settle { settle_steps, rest_ke, rest_speed, settle_check_steps, settle_max_checks },
            own: DoseRun { gate_x: if gated { pile_x1 } else { 0.0 }, traverse_steps, full_dump_every },
        }),
    };
    Scene::new(&base, settings, laid)
}

/// The settle's end from the log, and the window's snapshots from `dump`, each checked for
/// what the engine cannot have written. Shared by every blade layout.
pub fn read_frames(run: &Finished, blade: &Blade, dump: &str) -> Result<(u64, Vec<Frame>), Rejected> {
    let settle_steps =
        crate::engine::settled_at(&run.run.log).map_err(|(class, reason)| Rejected::new(class, reason))?;
    let frames: Vec<Frame> = read_dump(run.run_dir.join(dump), &COLUMNS)
        .and_then(|snaps| snaps.iter().map(Frame::from_snapshot).collect())
        .map_err(|e| Rejected::new(FailureClass::Unparsable, e.to_string()))?;
    // What the engine wrote must be possible before the metrics read it.
    let speeds = plausible::SphereSpeeds::of(run.scene, blade.blade_speed);
    if let Some(e) = frames.iter().find_map(|f| plausible::check_frame(f, &speeds).err()) {
        return Err(Rejected::new(FailureClass::Implausible, format!("{dump}: {e}")));
    }
    Ok((settle_steps, frames))
}

/// A moving-blade run's result: MFR from the flux counts over the window, steady when the
/// window's halves agree within counting noise.
pub fn measure(run: &Finished) -> Result<RunResult, Rejected> {
    let scene = run.scene;
    let Spreader { blade, window, .. } = &spread(scene).spreader;
    let (settle_steps, frames) = read_frames(run, blade, DUMP)?;
    let m = metrics::compute(scene, blade, window, &frames)
        .map_err(|e| Rejected::new(FailureClass::Unparsable, e.to_string()))?;
    let steps = settle_steps + window.spread_steps();
    let result = RunResult {
        format: RESULT_FORMAT,
        hash: run.hash.to_string(),
        parameters: run.parameters.clone(),
        answer: PointAnswer::mfr(m.mfr),
        mfr_flux: m.mfr_flux,
        answer_particles: m.mfr_particles,
        steady_state: None,
        vx_se: Vec::new(),
        answer_windows: m.mfr_windows,
        steady: m.steady,
        steady_p: m.steady_p,
        vx: m.vx,
        particles: m.particles,
        layer: m.layer,
        layer_thickness: Some(scene.layer_thickness(blade)),
        layer_packing: Some(scene.layer_packing(blade, m.mfr)),
        layer_packing_se: None,
        own: crate::outcome::OwnResult::none(),
        settle_steps,
        ..run.record(steps)
    };
    if !result.steady {
        let reason = format!(
            "MFR not steady over the window: halves differ beyond counting noise (p = {:.2e} < {}), sub-window MFR {:?}",
            result.steady_p,
            metrics::STEADY_ALPHA,
            result.answer_windows.iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>()
        );
        return Err(Rejected::measured(FailureClass::Unsteady, reason, result));
    }
    check_result(scene, blade, result)
}

/// The bounds every blade layout's result must meet: not squeezed through the gap of `blade` it
/// cannot pass (its numbers kept), and no impossible number.
pub fn check_result(scene: &Scene, blade: &Blade, result: RunResult) -> Result<RunResult, Rejected> {
    if let Err(e) = plausible::check_squeezed(scene, blade.gap, result.answer.value) {
        return Err(Rejected::measured(FailureClass::Implausible, e.to_string(), result));
    }
    if let Err(e) = plausible::check_result(&result, plausible::Measures::FLOW) {
        return Err(Rejected::new(FailureClass::Implausible, e.to_string()));
    }
    Ok(result)
}

#[cfg(test)]
mod scene_tests;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{rayleigh_time, MIN_YOUNGS_MPA, THESIS_TIMESTEP};
    use std::collections::BTreeMap;

    fn scene(pairs: &[(&str, f64)]) -> Scene {
        let values = pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        crate::scenes::build(&values, &SceneSettings::gated()).unwrap()
    }

    #[test]
    fn rayleigh_time_matches_hand_calculation() {
        // r = 0.5 mm, ρ = 7980, E = 21 MPa, ν = 0.3: G = 8.0769 MPa,
        // √(ρ/G) = 0.031433 s/m, π·0.5e-3·0.031433 / 0.92553 = 5.3349e-5 s.
        let t = rayleigh_time(0.5e-3, 7980.0, 21e6, 0.3);
        assert!((t - 5.3349e-5).abs() / 5.3349e-5 < 1e-4, "{t}");
    }

    #[test]
    fn timestep_is_the_rayleigh_fraction_or_the_thesis_step() {
        let s = scene(&[("diameter", 1.0)]);
        let fraction = SceneSettings::gated().rayleigh_fraction;
        assert!((s.timestep - fraction * s.rayleigh_time).abs() < 1e-18);
        let settings = crate::scenes::settings::preset(&super::THESIS, "thesis").unwrap();
        let t = crate::scenes::build(&BTreeMap::new(), &settings).unwrap();
        assert_eq!(t.timestep, THESIS_TIMESTEP);
    }

    #[test]
    fn the_stiffness_reduction_lengthens_the_rayleigh_time_and_stops_at_the_floor() {
        // T_R ∝ 1/√E: a quarter of the modulus doubles it.
        let values: BTreeMap<String, f64> = [("youngs_modulus".to_string(), 21.0)].into_iter().collect();
        let full =
            crate::scenes::build(&values, &SceneSettings { stiffness_factor: 1.0, ..SceneSettings::gated() })
                .unwrap();
        let soft = crate::scenes::build(
            &values,
            &SceneSettings { stiffness_factor: 0.25, ..SceneSettings::gated() },
        )
        .unwrap();
        assert!((soft.material.youngs_modulus - 5.25e6).abs() < 1e-6);
        assert!((soft.rayleigh_time / full.rayleigh_time - 2.0).abs() < 1e-12);
        let floor =
            crate::scenes::build(&values, &SceneSettings { stiffness_factor: 0.1, ..SceneSettings::gated() })
                .unwrap();
        assert_eq!(floor.material.youngs_modulus, MIN_YOUNGS_MPA * 1e6);
    }

    #[test]
    fn the_window_is_after_the_pile_and_inside_the_box() {
        for (d, gap) in [(1.0, 1.0), (1.0, 5.0), (3.0, 1.0), (3.0, 5.0)] {
            let s = scene(&[("diameter", d), ("gap", gap), ("blade_speed", 1.6)]);
            let Spread { spreader: Spreader { blade, window, .. }, pile, .. } = spread(&s);
            let rear = |step| blade.rear_at(s.timestep, step);
            let front = |step| blade.front_at(s.timestep, step);
            let (t1, t2) = window.steps();
            // Window starts after the blade front has passed the insertion block's far end.
            assert!(front(t1) > pile.pile_x1, "d={d} gap={gap}");
            // Window length is window_diameters·D (rounded up to whole snapshot intervals), at
            // full speed.
            let len = rear(t2) - rear(t1);
            let w = own(&SceneSettings::gated()).window_diameters * s.diameter;
            assert!(len >= w && len < w + s.diameter, "{len}");
            // The blade is at full speed when the window opens.
            assert!(t1 >= blade.start_step() + blade.ramp_steps);
            // The blade never leaves the box.
            assert!(front(window.spread_steps()) < s.x_hi);
            assert!(blade.blade_top < s.z_hi);
            // All step counts line up with the dump cadence.
            assert_eq!(t1 % window.dump_every, 0);
            assert_eq!(window.spread_steps() % window.dump_every, 0);
        }
    }

    #[test]
    fn particle_count_depends_on_the_geometry_in_diameters_only() {
        // The gated scene is in diameters, its heap too: the count depends on gap/D, not on D.
        let a = scene(&[("diameter", 1.0), ("gap", 2.0)]).particles;
        let b = scene(&[("diameter", 3.0), ("gap", 6.0)]).particles;
        assert_eq!(a, b);
    }

    #[test]
    fn layers_are_centred_at_gap_plus_half_diameters() {
        let s = scene(&[("diameter", 2.0), ("gap", 3.0)]);
        assert!((s.layer_height(1).unwrap() - 4e-3).abs() < 1e-15);
        assert!((s.layer_height(12).unwrap() - 15e-3).abs() < 1e-15);
        assert!((spread(&s).spreader.window.vx_band - 0.5e-3).abs() < 1e-15);
    }

    #[test]
    fn the_rest_criterion_is_an_rms_speed_of_one_percent_of_sqrt_g_d() {
        // D = 2 mm: v_rest = 0.01 √(9.81 · 0.002) = 1.4007e-3 m/s; KE_rest = ½ M v², with M the
        // dose's mass, n · ρ · π D³ / 6.
        let s = scene(&[("diameter", 2.0)]);
        let v = 0.01 * (9.81f64 * 0.002).sqrt();
        let settle = &spread(&s).settle;
        assert!((settle.rest_speed - v).abs() < 1e-12);
        let mass = s.particles as f64 * 7980.0 * std::f64::consts::PI * 0.002f64.powi(3) / 6.0;
        assert!((settle.rest_ke / (0.5 * mass * v * v) - 1.0).abs() < 1e-9);
        // The thesis layout has no rest criterion, gate or substrate.
        let values = [("diameter".to_string(), 2.0)].into_iter().collect();
        let thesis = SceneSettings { layout: "thesis".into(), ..SceneSettings::gated() };
        let t = crate::scenes::build(&values, &thesis).unwrap();
        let t_spread = spread(&t);
        assert_eq!(
            (
                t_spread.settle.rest_ke,
                t_spread.settle.rest_speed,
                t_spread.settle.settle_max_checks,
                t_spread.own.gate_x,
                t_spread.spreader.substrate.substrate_particles,
                t.z_lo
            ),
            (0.0, 0.0, 0, 0.0, 0, 0.0)
        );
        let s_spread = spread(&s);
        assert!(
            s_spread.own.gate_x > 0.0
                && s_spread.spreader.substrate.substrate_particles > 0
                && s.z_lo == -s.diameter
        );
    }

    #[test]
    fn out_of_domain_values_name_the_parameter() {
        let values = [("restitution".to_string(), 0.0)].into_iter().collect();
        let err = crate::scenes::build(&values, &SceneSettings::gated()).unwrap_err();
        assert!(err.to_string().contains("restitution"), "{err}");
    }
}

#[cfg(test)]
mod ramp_tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn blade_position_is_continuous_through_the_ramp_and_linear_after() {
        let s = crate::scenes::build(&BTreeMap::new(), &SceneSettings::gated()).unwrap();
        let blade = &spread(&s).spreader.blade;
        let at = |step| blade.rear_at(s.timestep, step);
        let s0 = blade.start_step();
        let r = blade.ramp_steps;
        assert_eq!(at(s0), blade.blade_x0);
        // During the ramp the travel is v·dt·k²/(2r): a quarter of full-speed travel at k = r/2.
        let half = at(s0 + r / 2) - blade.blade_x0;
        let k = (r / 2) as f64;
        assert!((half - blade.blade_speed * s.timestep * k * k / (2.0 * r as f64)).abs() < 1e-15);
        // After it, exactly v·dt per step.
        let a = at(s0 + r + 10);
        let b = at(s0 + r + 11);
        assert!((b - a - blade.blade_speed * s.timestep).abs() < 1e-15);
        // The ramp's travel is RAMP_DIAMETERS·D to within a step.
        let ramp_travel = at(s0 + r) - blade.blade_x0;
        assert!((ramp_travel - RAMP_DIAMETERS * s.diameter).abs() < blade.blade_speed * s.timestep);
    }
}
