//! What every point of a sweep shares, for the report's setup table and summary.json `setup`:
//! the fixed parameters, the scene's settings, the scene at the centre of the space, the engine.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::outcome::RunResult;
use crate::store::Manifest;
use crate::sweep::Sweep;

/// What every point of the sweep shares: the fixed parameters, the scene's settings, the scene
/// at the centre of the space, and the engine.
#[derive(Debug, Clone, Serialize)]
pub struct Setup {
    /// Every catalogue parameter the design does not sweep, written or default.
    pub fixed: Vec<crate::point::FixedValue>,
    /// The resolved `[scene]` settings: layout, substrate, heap size, size distribution, the
    /// fidelity preset and every numerical knob it set.
    pub scene: crate::sweep::SceneSettings,
    /// The scene built at the centre of the swept ranges (the sizes scale with the point).
    pub centre: Option<CentreScene>,
    pub engine_version: String,
    pub engine_path: String,
    /// The precision the sweep chose for its points after its first batch (if it chose one), and
    /// how many of the done runs started from a finished neighbour's steady state.
    pub precision: Option<crate::run::precision::SweepPrecision>,
    pub warm_started: usize,
    /// Done runs that ran to the scene's own target before the sweep chose its precision, and
    /// are coarser than it; and runs `sweep extend` continued.
    pub coarser: usize,
    pub extended: usize,
}

/// The scene at the centre of the space, in mm, s and counts: what one run looks like.
#[derive(Debug, Clone, Serialize)]
pub struct CentreScene {
    pub parameters: BTreeMap<String, f64>,
    pub particles: usize,
    /// What a run of it simulates, in the layout's words (a layers run: its passes and dose).
    pub runs: String,
    pub substrate_particles: usize,
    pub domain_length_mm: f64,
    pub domain_depth_mm: f64,
    pub domain_height_mm: f64,
    pub heap_length_mm: f64,
    pub heap_height_mm: f64,
    pub window_travel_mm: f64,
    pub timestep_s: f64,
    pub rayleigh_time_s: f64,
    /// The held heap and its window, of a layout that holds one (summary.json: `conveyor`).
    #[serde(rename = "conveyor")]
    pub held_heap: Option<crate::scenes::HeldHeap>,
}

impl Setup {
    pub(super) fn of(sweep: &Sweep, manifest: &Manifest, dir: &Path, done: &[&RunResult]) -> Setup {
        let mid: Vec<f64> = sweep
            .swept
            .iter()
            .map(|p| match p.kind {
                crate::sweep::ParamKind::Swept { lo, hi, .. } => 0.5 * (lo + hi),
                crate::sweep::ParamKind::Fixed(v) => v,
            })
            .collect();
        let parameters = crate::point::resolve(sweep, &mid);
        let layout = crate::scenes::of(&sweep.file.scene).ok();
        let centre = crate::scenes::build(&parameters, &sweep.file.scene).ok().map(|sc| {
            // A layout that starts from no pile (a held heap, doses pass by pass) measures no
            // window of travel from one: its pile and window are 0.
            let pile = sc.pile().filter(|p| p.pile_n.iter().product::<usize>() > 0);
            let travel = |b: &crate::scene::blade::Blade, w: &crate::scene::blade::Window| {
                let (t1, t2) = w.steps();
                b.rear_at(sc.timestep, t2) - b.rear_at(sc.timestep, t1)
            };
            let window_travel = sc.blade().zip(sc.window()).map_or(0.0, |(b, w)| travel(b, w));
            CentreScene {
                parameters: sweep.swept.iter().map(|p| (p.name.clone(), parameters[&p.name])).collect(),
                particles: sc.particles,
                runs: layout.map_or_else(String::new, |l| l.what_runs(&sc)),
                substrate_particles: sc.substrate().map_or(0, |s| s.substrate_particles),
                domain_length_mm: sc.x_hi * 1e3,
                domain_depth_mm: sc.depth * 1e3,
                domain_height_mm: (sc.z_hi - sc.z_lo) * 1e3,
                heap_length_mm: pile.map_or(0.0, |p| (p.pile_x1 - p.pile_x0) * 1e3),
                heap_height_mm: pile.map_or(0.0, |p| p.pile_z1 * 1e3),
                window_travel_mm: pile.map_or(0.0, |_| window_travel * 1e3),
                timestep_s: sc.timestep,
                rayleigh_time_s: sc.rayleigh_time,
                held_heap: layout.and_then(|l| l.held_heap(&sc)),
            }
        });
        let id = |k: &str| manifest.identity.get(k).and_then(|v| v.as_str()).unwrap_or("").to_string();
        let precision = crate::run::precision::read(dir);
        let coarser = precision.as_ref().map_or(0, |p| {
            let above = |r: &&&RunResult| {
                r.mfr_se_target.is_none() && r.answer.se.is_some_and(|se| se > p.mfr_abs_se)
            };
            done.iter().filter(above).count()
        });
        Setup {
            fixed: crate::point::fixed_values(sweep),
            scene: sweep.file.scene.clone(),
            centre,
            engine_version: id("engine_version"),
            engine_path: id("engine_path"),
            precision,
            warm_started: done.iter().filter(|r| r.warm_start.is_some()).count(),
            coarser,
            extended: done.iter().filter(|r| r.extensions > 0).count(),
        }
    }
}
