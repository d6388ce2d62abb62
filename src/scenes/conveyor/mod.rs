//! The conveyor layout: the blade's frame. The blade stands still with its rear face at
//! `blade_x0`, the rough substrate moves under it at −v (x periodic), a heap is held in front of
//! it (topped up to its count every fifth of a block), and the deposit is deleted downstream.
//! MFR is measured in a steady state with its standard error ([`crate::measure::steady`]).

pub mod extend;
pub mod settings;
pub mod warm;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::measure::frame::{Frame, COLUMNS};
use crate::measure::{layer, steady};
use crate::outcome::layer::Layer;
use crate::outcome::steady::SteadyState;
use crate::outcome::{FailureClass, PointAnswer, RunResult, RESULT_FORMAT};
use crate::scene::bed::Bed;
use crate::scene::blade::Spreader;
use crate::scene::own::LayoutData;
use crate::scene::own_settings::OwnSettings;
use crate::scene::plausible::short;
use crate::scene::settings::SceneSettings;
use crate::scene::substrate::Substrate;
use crate::scene::{
    prime_seed, Base, Feed, FeedClass, Scene, GRAVITY, LAYER_FRACTION_MAX, MIN_INSERT_VOLUME, REPOSE_DEG,
};
use crate::scenes::moving_blade::{self, Dose};
use crate::scenes::{
    BadSetting, BuiltinTemplate, Finished, HeldHeap, Layout, Rejected, SetupRows, WarmFiles,
};
pub use settings::{own, ConveyorSettings};

/// The conveyor layout (registered in [`crate::scenes::LAYOUTS`]).
pub struct Conveyor;

/// The layout's name, its `[scene] layout`.
pub const NAME: &str = "conveyor";

/// Depth of a powder bed's solid, in diameters (at a packing of 0.55: about 2.6 D deep).
const BED_THICKNESS: f64 = 2.0;

/// The conveyor's one snapshot of the deposit behind the blade at the end.
pub const STRIP_DUMP: &str = "dump.strip";

/// The conveyor's own numbers (`scene.own`): a heap of `heap_particles` topped up in the box
/// ahead of the blade, the deposit deleted downstream, and the block series. All lengths in m.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Held {
    /// Height of the held heap (gap + the `heap_height` parameter), and the particles it holds at a
    /// packing of 0.6 in its 30° repose triangle.
    pub heap_height: f64,
    pub heap_particles: usize,
    /// The box the heap is counted and topped up in: from the blade's front face to a wall at
    /// `heap_x1`, from the substrate to `heap_z1`.
    pub heap_x1: f64,
    pub heap_z1: f64,
    /// Deposit strip behind the blade: from `delete_x1` to the blade's rear face; everything
    /// behind `delete_x1` is deleted after each block.
    pub delete_x1: f64,
    pub block_steps: u64,
    pub insert_every: u64,
    pub warmup_blocks: u64,
    pub min_window_blocks: u64,
    pub max_blocks: u64,
    /// Mass of a full flow through the gap over one block: ρ · w · h · v · Δt_block, kg.
    pub ideal_block_mass: f64,
    pub mfr_rel_se: f64,
    pub mfr_abs_se: f64,
    /// The substrate is a bed of the powder: its spheres reach above the deposit regions' floor,
    /// so the deck deletes only powder from the delete region.
    pub powder_bed: bool,
    /// Bottom of the deposit strip and the delete region, m.
    pub regions_z0: f64,
    /// Particle templates of the feed: diameter, mass fraction, prime seed.
    pub feed: Vec<FeedClass>,
    /// The least particle volume the feed's templates accept, m³ (0: the engine's default,
    /// 1e-12 m³, which refuses every sphere below 124 µm).
    pub volume_limit: f64,
    /// Prime seeds of the feed's distribution and insertion.
    pub distribution_seed: u64,
    pub insert_seed: u64,
    /// Write the powder ahead of the blade's rear face at the end (`dump.state`), for warm starts.
    pub keep_state: bool,
    /// Start from `warm.data` (a neighbour's state mapped to this point), after a warm-up of
    /// `warm_warmup_blocks` in place of `warmup_blocks`.
    pub warm_start: bool,
    pub warm_warmup_blocks: u64,
    /// Continue a finished run from the restart its last part wrote, instead of from rest
    /// (`sweep extend`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extend: Option<extend::Continuation>,
}

/// The conveyor's part of the scene: the blade held still, its window, the substrate moving
/// under it, and the held heap (`own`).
#[derive(Debug, Clone, Serialize)]
pub struct HeldRun {
    #[serde(flatten)]
    pub spreader: Spreader,
    /// The deck's `scene.own.*`.
    #[serde(rename = "own")]
    pub held: Held,
}

impl LayoutData for HeldRun {
    fn steps(&self) -> u64 {
        self.spreader.window.spread_steps()
    }
    fn spreader(&self) -> Option<&Spreader> {
        Some(&self.spreader)
    }
}

/// The part of a conveyor scene.
pub fn part(scene: &Scene) -> &HeldRun {
    scene.own().expect("a conveyor scene carries its held run")
}

/// The held heap's numbers of a conveyor scene.
pub fn held(scene: &Scene) -> &Held {
    &part(scene).held
}

/// `scene` with its part changed by `change`.
pub fn with_part(mut scene: Scene, change: impl FnOnce(&mut HeldRun)) -> Scene {
    change(scene.own_mut().expect("a conveyor scene carries its held run"));
    scene
}

/// `scene` with its held heap's numbers changed by `change`.
pub fn with_held(scene: Scene, change: impl FnOnce(&mut Held)) -> Scene {
    with_part(scene, |p| change(&mut p.held))
}

impl Layout for Conveyor {
    fn name(&self) -> &'static str {
        NAME
    }

    fn template(&self) -> BuiltinTemplate {
        BuiltinTemplate {
            name: "conveyor.liggghts.tera",
            source: include_str!("../../../templates/conveyor.liggghts.tera"),
        }
    }

    fn check_settings(&self, s: &SceneSettings) -> Result<(), BadSetting> {
        let bad = |key, why| Err(BadSetting { key, why });
        for (k, v) in [
            ("scene.block_diameters", own(s).block_diameters),
            ("scene.window_cap_diameters", own(s).window_cap_diameters),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(k, format!("{v}: expected a positive number"));
            }
        }
        for (k, v) in [
            ("scene.warmup_s", own(s).warmup_s.unwrap_or(0.0)),
            ("scene.mfr_rel_se", own(s).mfr_rel_se),
            ("scene.mfr_abs_se", own(s).mfr_abs_se),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(k, format!("{v}: expected a number ≥ 0"));
            }
        }
        if !["sweep", "fixed"].contains(&own(s).precision.as_str()) {
            return bad(
                "scene.precision",
                format!("\"{}\": expected \"sweep\" or \"fixed\"", own(s).precision),
            );
        }
        // MSER may drop up to half the window, and the trend over what is left needs 3 blocks.
        if own(s).min_window_blocks < 5 {
            return bad(
                "scene.min_window_blocks",
                format!(
                    "{}: expected at least 5 (MSER may drop half of the blocks; the trend needs 3 left)",
                    own(s).min_window_blocks
                ),
            );
        }
        if (own(s).min_window_blocks as f64 + 1.0) * own(s).block_diameters > own(s).window_cap_diameters {
            return bad(
                "scene.window_cap_diameters",
                format!(
                    "{}: expected more than min_window_blocks × block_diameters = {}",
                    own(s).window_cap_diameters,
                    own(s).min_window_blocks as f64 * own(s).block_diameters
                ),
            );
        }
        Ok(())
    }

    fn derive(&self, base: Base, settings: &SceneSettings) -> Scene {
        derive(base, settings)
    }

    fn own_keys(&self, fidelity: &str, written: &toml::Table) -> Result<OwnSettings, toml::de::Error> {
        ConveyorSettings::read(fidelity, written).map(OwnSettings::new)
    }

    fn own_settings(&self) -> Vec<&'static str> {
        vec![
            // Its substrate, the v_x profile in front of its blade, the blade's mesh and depth.
            "substrate",
            "vx_band_diameters",
            "thesis_band",
            "mesh_cells_across",
            "depth_diameters",
            // A held heap of `heap_height` (not a supply), its deposit series measured block by
            // block to a precision, ...
            "block_diameters",
            "min_window_blocks",
            "warmup_s",
            "window_cap_diameters",
            "mfr_rel_se",
            "mfr_abs_se",
            "precision",
            // ... and a warm start from a neighbour's steady heap.
            "warm_start",
            "warm_warmup_s",
        ]
    }

    fn atoms_kept(&self, _scene: &Scene) -> Option<u64> {
        // The feed inserts and the delete region removes atoms by design.
        None
    }

    fn stand_in(&self, point: &mut crate::scenes::stand_in::StandInPoint) -> Result<RunResult, Rejected> {
        Ok(crate::scenes::stand_in::flow(point))
    }

    fn measure(&self, run: &Finished) -> Result<RunResult, Rejected> {
        measure(run)
    }

    fn what_runs(&self, sc: &Scene) -> String {
        format!("a heap held at {} particles, at most {} steps", held(sc).heap_particles, sc.run_steps())
    }

    fn ignores(&self, _settings: &SceneSettings, name: &str) -> Option<&'static str> {
        match name {
            "layer_thickness" => Some(super::ONE_LAYER),
            "roller_speed_ratio" => Some(super::NO_ROLLER),
            _ => None,
        }
    }

    fn setup_rows(&self, sc: &SceneSettings) -> SetupRows {
        SetupRows {
            head: vec![
                ("block of the deposit series, travel (D)", short(own(sc).block_diameters)),
                (
                    "warm-up (s)",
                    match own(sc).warmup_s {
                        Some(w) => short(w),
                        None => format!(
                            "{} √(H/g), H = gap + heap_height (the held heap's fall time)",
                            short(settings::WARMUP_HEAP_FALLS)
                        ),
                    },
                ),
                (
                    "precision target: SE of MFR at most",
                    match own(sc).precision.as_str() {
                        "sweep" => format!(
                            "{} × MFR or {} over the first batch, then σ·√(τ/3) (the sweep's precision; half of it in sweep adapt)",
                            short(own(sc).mfr_rel_se),
                            short(own(sc).mfr_abs_se)
                        ),
                        _ => format!("{} × MFR or {}", short(own(sc).mfr_rel_se), short(own(sc).mfr_abs_se)),
                    },
                ),
                (
                    "warm start",
                    if own(sc).warm_start {
                        format!(
                            "from the nearest finished point; warm-up the cold one's × distance/0.5, at least {} of it and {} s",
                            short(warm::LEAST_WARMUP_SHARE),
                            short(own(sc).warm_warmup_s)
                        )
                    } else {
                        "no: every point from rest".into()
                    },
                ),
                ("least window (blocks)", own(sc).min_window_blocks.to_string()),
                ("window cap, travel after the warm-up (D)", short(own(sc).window_cap_diameters)),
            ],
            tail: Vec::new(),
        }
    }

    fn warm_start(
        &self,
        from: &Scene,
        from_dir: &Path,
        to: &Scene,
        to_pile: &str,
        distance: f64,
    ) -> Result<warm::Warm, super::ColdStart> {
        warm::map(from, &from_dir.join(warm::STATE_DUMP), to, to_pile, distance)
    }

    fn run_files(&self, _settings: &SceneSettings) -> Vec<String> {
        [
            moving_blade::DUMP,
            STRIP_DUMP,
            warm::STATE_DUMP,
            warm::WARM_DATA,
            extend::RESTART,
            extend::KEPT_RESTART,
            extend::PRIOR_RESTART,
        ]
        .map(String::from)
        .to_vec()
    }

    fn warm_start_files(&self) -> Option<WarmFiles> {
        Some(WarmFiles { state: warm::STATE_DUMP, data: warm::WARM_DATA })
    }

    fn continuation(
        &self,
        scene: &Scene,
        warm_distance: Option<f64>,
        parts: &[PathBuf],
        part_dir: &Path,
    ) -> Result<Scene, String> {
        // The warm-up and the cap of the run's first part: a warm start's were its own.
        let scene = match warm_distance {
            Some(d) => warm::warm_started(scene, d),
            None => scene.clone(),
        };
        extend::continuation(&scene, parts, part_dir).map_err(|e| e.to_string())
    }

    fn keep(&self, run_dir: &Path, done: bool) {
        // A restart that cannot be kept leaves a point that cannot be extended, nothing worse.
        let _ = extend::keep_restart(run_dir, done);
    }

    fn with_precision(&self, scene: &Scene, mfr_abs_se: f64) -> Option<Scene> {
        Some(with_held(scene.clone(), |c| {
            c.mfr_rel_se = 0.0;
            c.mfr_abs_se = mfr_abs_se;
        }))
    }

    fn held_heap(&self, sc: &Scene) -> Option<HeldHeap> {
        let HeldRun { spreader: Spreader { blade, .. }, held: c } = part(sc);
        let block_mm = blade.blade_speed * sc.timestep * c.block_steps as f64 * 1e3;
        Some(HeldHeap {
            heap_particles: c.heap_particles,
            heap_height_mm: c.heap_height * 1e3,
            block_travel_mm: block_mm,
            warmup_blocks: c.warmup_blocks,
            min_window_blocks: c.min_window_blocks,
            cap_travel_mm: block_mm * c.max_blocks as f64,
        })
    }
}

/// The held heap's scene (see [`crate::scene::Conveyor`]): the free pile's scene with the
/// blade held still, the substrate moving and the heap topped up.
fn derive(base: Base, settings: &SceneSettings) -> Scene {
    let psd = base.psd.clone();
    let heap_above = base.heap_height;
    // A smooth substrate: no spheres; the plate moves, sheared at −v (the deck's `shear x`).
    let rough = settings.substrate == "rough";
    let powder_bed = settings.substrate == "powder";
    let mut s = moving_blade::derive(base, settings, Dose::Free);
    let Spreader { blade: mut b, mut window, .. } = moving_blade::spread(&s).spreader.clone();
    let d = s.diameter;
    let (gap, v, dt) = (b.gap, b.blade_speed, s.timestep);
    let heap_height = gap + heap_above;
    let heap_base = heap_height / REPOSE_DEG.to_radians().tan();
    // LIGGGHTS refuses to insert into a region under 1e-10 m³ (region.cpp, volume_mc, an
    // absolute floor in SI) once it is shrunk by the largest radius on every side: a heap of
    // fine powder gets the depth its box needs.
    let d_max = psd.max_diameter();
    let heap_box = (heap_base + 3.0 * d - d_max) * (1.6 * heap_height - d_max);
    if heap_box * (s.depth - d_max) < MIN_INSERT_VOLUME {
        s.depth = d_max + MIN_INSERT_VOLUME / heap_box;
        s.mesh_cell = s.depth / settings.mesh_cells_across as f64;
    }
    let heap_particles =
        (LAYER_FRACTION_MAX * 0.5 * heap_height * heap_base * s.depth / psd.mean_volume()).ceil() as usize;
    // Behind the blade: 10 D of deposit strip, then the delete region (6 D).
    let blade_x0 = 16.0 * d;
    let front0 = blade_x0 + b.blade_thickness;
    let heap_x1 = front0 + heap_base + 3.0 * d;
    // The substrate's lattice fills the periodic length exactly.
    let n_y = ((s.depth / d).floor() as usize).max(1);
    let spacing = s.depth / n_y as f64;
    let n_x = ((heap_x1 + 2.0 * d) / spacing).ceil() as usize;
    let x_hi = if powder_bed { heap_x1 + 2.0 * d } else { n_x as f64 * spacing };
    let block_steps = ((own(settings).block_diameters * d / (v * dt)).ceil() as u64).max(1);
    let blocks = |travel: f64| (travel / own(settings).block_diameters).ceil() as u64;
    let warmup_blocks = blocks((own(settings).warmup_for(heap_height) * v).max(10.0 * d) / d);
    let max_blocks = warmup_blocks + blocks(own(settings).window_cap_diameters);
    let blade_top = 2.0 * heap_height + 2.0 * d;
    let mean_volume = psd.mean_volume();
    let mass = heap_particles as f64 * s.material.density * mean_volume;
    let Feed { classes: feed, volume_limit } = Feed::of(&psd, s.seed);
    b.blade_fixed = true;
    s.particles = 0;
    b.blade_x0 = blade_x0;
    b.blade_top = blade_top;
    s.x_hi = x_hi;
    s.z_hi = blade_top + 2.0 * d + v * v / GRAVITY;
    let substrate_bed = powder_bed
        .then(|| Bed::deposit(&psd.classes, x_hi, s.depth, BED_THICKNESS * d, prime_seed(s.seed, 3)));
    s.z_lo = match &substrate_bed {
        Some(bed) => bed.floor,
        None if rough => -d,
        None => 0.0,
    };
    let substrate_n = if rough { [n_x, n_y] } else { [0, 0] };
    let substrate = Substrate {
        substrate_particles: substrate_bed
            .as_ref()
            .map_or(substrate_n[0] * substrate_n[1], |bed| bed.spheres.len()),
        substrate_diameter: if rough || powder_bed { d } else { 0.0 },
        substrate_spacing: if rough { spacing } else { 0.0 },
        substrate_n,
        substrate_bed,
    };
    let held = Held {
        heap_height,
        heap_particles,
        heap_x1,
        heap_z1: 1.6 * heap_height,
        delete_x1: blade_x0 - 10.0 * d,
        block_steps,
        insert_every: (block_steps / 5).max(1),
        warmup_blocks,
        min_window_blocks: own(settings).min_window_blocks as u64,
        max_blocks,
        ideal_block_mass: s.material.density * s.depth * gap * v * dt * block_steps as f64,
        mfr_rel_se: own(settings).mfr_rel_se,
        mfr_abs_se: own(settings).mfr_abs_se,
        powder_bed,
        // Above the lattice's centres (a delete region takes every atom in it); a bed's deposit
        // sits in pockets down to its floor, and the deck deletes only the powder there.
        regions_z0: if powder_bed { s.z_lo } else { -0.2 * d },
        feed,
        volume_limit,
        distribution_seed: prime_seed(s.seed, 0),
        insert_seed: prime_seed(s.seed, 1),
        keep_state: own(settings).warm_start,
        warm_start: false,
        warm_warmup_blocks: blocks((own(settings).warm_warmup_s * v / d).max(own(settings).block_diameters)),
        extend: None,
    };
    b.ramp_steps = 1;
    window.approach_steps = 0;
    window.dump_every = block_steps;
    window.window_length_steps = max_blocks * block_steps;
    s.set_own(HeldRun { spreader: Spreader { blade: b, window, substrate }, held });
    s.thermo_every = block_steps.min(1000);
    let v_ref = v.max((2.0 * GRAVITY * blade_top).sqrt());
    s.ke_limit = 0.5 * mass * (10.0 * v_ref).powi(2);
    s
}

/// The spread layer: coverage and roughness from the strip behind the blade at the end
/// (`dump.strip`), uniformity from the mass each block of the steady window deposited.
fn conveyor_layer(scene: &Scene, frame: &Frame, st: &SteadyState) -> Option<Layer> {
    let HeldRun { spreader: Spreader { blade, .. }, held: c } = part(scene);
    let mut l = layer::measure(scene, blade.gap, frame, c.delete_x1, blade.blade_x0)?;
    let particle_mass = |d: f64| scene.material.density * std::f64::consts::PI / 6.0 * d.powi(3);
    let weighted: f64 = c.feed.iter().map(|f| f.mass_fraction * particle_mass(f.diameter)).sum::<f64>()
        / c.feed.iter().map(|f| f.mass_fraction).sum::<f64>();
    let block_mass: Vec<f64> =
        st.block_mfr[st.transient_blocks..].iter().map(|y| y * c.ideal_block_mass).collect();
    (l.layer_cv, l.layer_cv_noise) = layer::along_travel(&block_mass, weighted);
    Some(l)
}

/// The block series from the log, the steady window, MFR with its SE; a run that did not
/// become steady fails as `unsteady` with its numbers kept.
/// An extended run (`run.earlier` not empty) is measured over every part's blocks and snapshots.
fn measure(run: &Finished) -> Result<RunResult, Rejected> {
    let unparsable = |e: String| Rejected::new(FailureClass::Unparsable, e);
    let scene = run.scene;
    let HeldRun { spreader: Spreader { blade, window, .. }, held: c } = part(scene);
    let (_, these) = moving_blade::read_frames(run, blade, moving_blade::DUMP)?;
    let (mut blocks, _) = extend::earlier_blocks(run.earlier).map_err(|e| unparsable(e.to_string()))?;
    let mut frames = Vec::new();
    for dir in run.earlier {
        let path = dir.join(moving_blade::DUMP);
        let snaps = crate::engine::dump::read_dump(&path, &COLUMNS)
            .map_err(|e| unparsable(format!("{}: {e}", path.display())))?;
        for s in &snaps {
            frames.push(Frame::from_snapshot(s).map_err(|e| unparsable(format!("{}: {e}", path.display())))?);
        }
    }
    // A continuation's first snapshot is the earlier part's last, taken again.
    let joined = frames.last().map(|f| f.step);
    frames.extend(these.into_iter().filter(|f| joined.is_none_or(|j| f.step > j)));
    let (more, stop) = steady::parse_blocks(&run.run.log).map_err(|e| unparsable(e.to_string()))?;
    blocks.extend(more);
    let (blocks, stop) = steady::series(blocks, stop).map_err(|e| unparsable(e.to_string()))?;
    let blocks_of = steady::HeldBlocks {
        ideal_block_mass: c.ideal_block_mass,
        warmup_blocks: c.warmup_blocks,
        block_steps: c.block_steps,
        heap_particles: c.heap_particles,
    };
    let st = steady::compute(scene, (blade, window), &blocks_of, &blocks, &stop, &frames);
    // The steady window in quarters (the moving-blade scenes' sub-windows, for the same readers).
    let w = &st.state.block_mfr[st.state.transient_blocks..];
    let quarter = w.len().div_ceil(4).max(1);
    let answer_windows = w.chunks(quarter).map(|c| c.iter().sum::<f64>() / c.len() as f64).collect();
    let steps = blocks.last().map(|b| b.step).unwrap_or(0);
    let strip = crate::engine::dump::read_dump(run.run_dir.join(STRIP_DUMP), &COLUMNS)
        .ok()
        .and_then(|snaps| snaps.last().and_then(|s| Frame::from_snapshot(s).ok()));
    let layer = strip.as_ref().and_then(|f| conveyor_layer(scene, f, &st.state));
    let result = RunResult {
        format: RESULT_FORMAT,
        hash: run.hash.to_string(),
        parameters: run.parameters.clone(),
        answer: PointAnswer { se: Some(st.mfr_se), ..PointAnswer::mfr(st.mfr) },
        mfr_flux: st.mfr_deleted,
        answer_particles: st.particles,
        steady_state: Some(Box::new(st.state)),
        vx_se: st.vx_se,
        answer_windows,
        steady: st.unsteady.is_none(),
        steady_p: 1.0,
        vx: st.vx,
        particles: c.heap_particles,
        layer,
        layer_thickness: Some(scene.layer_thickness(blade)),
        layer_packing: Some(scene.layer_packing(blade, st.mfr)),
        layer_packing_se: Some(scene.layer_packing(blade, st.mfr_se)),
        own: crate::outcome::OwnResult::none(),
        settle_steps: 0,
        ..run.record(steps)
    };
    if let Some(why) = st.unsteady {
        return Err(Rejected::measured(FailureClass::Unsteady, format!("MFR not steady: {why}"), result));
    }
    moving_blade::check_result(scene, blade, result)
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::settings::{own, ConveyorSettings, WARMUP_HEAP_FALLS};
    use crate::scene::settings::SceneSettings;

    fn scene(values: &[(&str, f64)], settings: &SceneSettings) -> crate::scene::Scene {
        let values: BTreeMap<String, f64> = values.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        crate::scenes::build(&values, settings).unwrap()
    }

    /// The planned warm-up, s, and one block's time.
    fn warmup(scene: &crate::scene::Scene) -> (f64, f64) {
        let c = super::held(scene);
        let block_s = c.block_steps as f64 * scene.timestep;
        (c.warmup_blocks as f64 * block_s, block_s)
    }

    #[test]
    fn the_warm_up_is_whole_however_fine_the_powder_and_the_cap_counts_after_it() {
        // D 0.5 mm at 1.4 m/s under a 20 mm heap: the warm-up is the heap's 6.5 √(H/g) ≈ 0.3 s,
        // 420 mm of travel, 840 D, past a cap of 600 D counted from the start; the warm-up is
        // kept whole and the window gets its 600 D after it.
        let settings = SceneSettings::default();
        let sc = scene(&[("diameter", 0.5), ("gap", 1.25), ("blade_speed", 1.4)], &settings);
        let (warmup_s, block_s) = warmup(&sc);
        let rule = WARMUP_HEAP_FALLS * (0.02125f64 / crate::scene::GRAVITY).sqrt();
        assert!((rule..rule + block_s).contains(&warmup_s), "warm-up {warmup_s} s against {rule} s");
        let c = super::held(&sc);
        let after = (c.max_blocks - c.warmup_blocks) as f64 * own(&settings).block_diameters;
        assert!(
            (600.0..600.0 + own(&settings).block_diameters).contains(&after),
            "{after} D after the warm-up"
        );
    }

    #[test]
    fn the_default_warm_up_keeps_the_thesis_scale_and_shrinks_with_the_heap() {
        let settings = SceneSettings::default();
        // The thesis's space (D 1–3 mm, gap 1–5 mm, 20 mm heap, 1.2–1.6 m/s): never under the
        // 0.3 s its long runs need (docs/study/recoater).
        for (d, gap, v) in [(2.0, 3.0, 1.4), (1.0, 1.0, 1.6), (3.0, 5.0, 1.2), (2.0, 1.0, 1.2)] {
            let (w, _) = warmup(&scene(&[("diameter", d), ("gap", gap), ("blade_speed", v)], &settings));
            assert!((0.3..0.34).contains(&w), "D {d} mm, gap {gap} mm, {v} m/s: warm-up {w} s");
        }
        // A real powder's point: 35 µm, a 100 µm gap, a 1 mm heap, 0.08 m/s. Its warm-up is the
        // heap's, √(1.1 mm / g) × 6.5 ≈ 0.069 s, not the 0.3 s (650,000 steps) of a 20 mm heap.
        let um = [("diameter", 0.035), ("gap", 0.1), ("heap_height", 1.0), ("blade_speed", 0.08)];
        let sc = scene(&um, &settings);
        let (w, block_s) = warmup(&sc);
        assert!((0.068..0.069 + block_s).contains(&w), "35 µm: warm-up {w} s");
        assert!(w < 0.25 * 0.3, "35 µm: warm-up {w} s");
        // A taller heap takes longer, as √H: four times the heap, about twice the warm-up.
        let (w4, block4) = warmup(&scene(&[um[0], um[1], ("heap_height", 4.3), um[3]], &settings));
        assert!(((2.0 * w - 2.0 * block_s)..(2.0 * w + block4)).contains(&w4), "{w} s → {w4} s");
        // A set warmup_s wins over the rule.
        let set = ConveyorSettings { warmup_s: Some(0.005), ..ConveyorSettings::default() }.settings();
        let (w, block_s) = warmup(&scene(&um, &set));
        assert!((0.005..0.005 + block_s).contains(&w), "set 0.005 s: warm-up {w} s");
    }

    #[test]
    fn a_flow_that_stops_is_a_jam_not_a_steady_zero() {
        use crate::measure::steady::{compute, Block, HeldBlocks};
        let values: BTreeMap<String, f64> =
            [("diameter", 2.0), ("gap", 1.7)].iter().map(|(k, v)| (k.to_string(), *v)).collect();
        let settings = SceneSettings { layout: "conveyor".into(), ..SceneSettings::default() };
        let scene = crate::scenes::build(&values, &settings).unwrap();
        let cv = super::held(&scene);
        let c = HeldBlocks {
            ideal_block_mass: cv.ideal_block_mass,
            warmup_blocks: cv.warmup_blocks,
            block_steps: cv.block_steps,
            heap_particles: cv.heap_particles,
        };
        let m = c.ideal_block_mass;
        let warm = c.warmup_blocks as usize;
        // Blocks of deposit (gone mass only, the strip empty): flowing at 0.08 for the warm-up
        // and 12 blocks after it, then nothing for 14 blocks.
        let mfr: Vec<f64> = (0..warm + 26).map(|k| if k < warm + 12 { 0.08 } else { 0.0 }).collect();
        let blocks: Vec<Block> = mfr
            .iter()
            .enumerate()
            .map(|(k, y)| Block {
                step: 100 * (k as u64 + 1),
                gone: y * m,
                strip: 0.0,
                heap: c.heap_particles as u64,
                heap_mass: 0.0,
            })
            .collect();
        let p = super::part(&scene);
        let st = compute(&scene, (&p.spreader.blade, &p.spreader.window), &c, &blocks, "target", &[]);
        assert_eq!(st.mfr, 0.0);
        assert!(st.unsteady.as_deref().is_some_and(|w| w.contains("the flow stopped")), "{:?}", st.unsteady);
        // A point where nothing ever passes is a steady zero.
        let none: Vec<Block> = blocks.iter().map(|b| Block { gone: 0.0, ..*b }).collect();
        let st = compute(&scene, (&p.spreader.blade, &p.spreader.window), &c, &none, "target", &[]);
        assert_eq!((st.mfr, st.unsteady), (0.0, None));
    }
}
