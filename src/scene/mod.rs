//! The blade-spreading scene: from one design point to every number the deck needs.
//!
//! The physics lives here, typed and unit-tested; the template only lays the numbers out. All
//! lengths in this struct are metres, times seconds, moduli pascals (the catalogue's mm and MPa
//! are converted once, in [`Scene::new`]).
//!
//! Geometry (docs/scene.md "Geometry"): x is the blade's travel, z is up, y is across the blade and periodic
//! (the domain depth is the blade width w). A pile is inserted in front of the blade, settles on
//! the plate z = 0, and the blade — a box whose tip is at z = gap — then pushes it over the bare
//! plate in +x, leaving a layer behind. Walls at both x ends keep every particle in the box, so
//! any lost atom is an instability, never an outlet.
//!
//! The run, in steps: settle → approach (the blade accelerates over a short ramp, crosses the
//! pile, and the heap develops) → measurement window ([`SUB_WINDOWS`] sub-windows of
//! [`SNAPSHOTS_PER_SUB_WINDOW`] snapshot intervals each). The run stops at the window's end: the
//! metrics count particles crossing the blade's faces between snapshots, so nothing after the
//! window is needed.

pub mod mesh;
pub mod params;
pub mod passage;
pub mod pile;
pub mod plausible;
pub mod psd;
pub mod settings;

use std::collections::BTreeMap;

use serde::Serialize;

use crate::scene::settings::SceneSettings;
use psd::SizeDistribution;

/// Simulated time between the VTK files of `sweep run --vtk`, s.
pub const VTK_EVERY_S: f64 = 0.02;
/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.81;
/// Number of equal sub-windows of the measurement window (steadiness check, dump cadence).
pub const SUB_WINDOWS: usize = 4;
/// Snapshot intervals per sub-window. Short intervals let the flux counts tell a particle that
/// passed under the tip from one thrown over the blade (whose flight takes far longer).
pub const SNAPSHOTS_PER_SUB_WINDOW: usize = 2;
/// Blade travel over which it accelerates from rest to full speed, in diameters. A blade that
/// starts at full speed throws the particles touching it high into the air.
const RAMP_DIAMETERS: f64 = 2.0;
/// Lattice spacing of the initial pile over the largest diameter: room for a small jitter.
const LATTICE_CLEARANCE: f64 = 1.05;
/// Length over height of the initial pile block.
const PILE_ASPECT: f64 = 1.5;
/// Packing fraction assumed for a settled pile and an upper bound for a spread layer
/// (random close packing ≈ 0.64; MFR cannot exceed it).
const LAYER_FRACTION_MAX: f64 = 0.6;
/// Gated layout: height of the heap pushed by the blade above the gap, in diameters.
const GATED_HEAP_DIAMETERS: f64 = 10.0;
/// Gated layout: MFR assumed when sizing the dose's deposit, above every MFR measured over a
/// 24-point LDS draw of the thesis space (largest 0.126). MFR rises with the heap the blade
/// pushes, so a dose sized at the mean MFR (0.07) was tried to keep the heap the same whatever
/// the window: it removed no measured shift, and 2 of 24 points then failed as unsteady
/// against none (BENCHMARKS.md "Scene convergence", study C).
const MFR_ALLOWANCE: f64 = 0.15;
/// Angle of repose used to size the heap the blade must still carry at the end, degrees.
const REPOSE_DEG: f64 = 30.0;
/// Rolling-friction model: EPSD2 (elastic-plastic spring-dashpot without the damper, Ai et al.
/// 2011 model C), which holds a static heap still; CDT's constant torque makes resting spheres
/// jitter.
const ROLLING_MODEL: &str = "epsd2";
/// Gated layout: simulated time between checks of the rest criterion, s.
const SETTLE_CHECK_S: f64 = 0.005;
/// Thesis fidelity: the fixed timestep of the thesis runs, s (Appendix A: 1e-5 s per step).
pub const THESIS_TIMESTEP: f64 = 1e-5;
/// Thesis v_x band: ±1 mm (Appendix A, `depth = 0.001`).
pub const THESIS_BAND: f64 = 1e-3;
/// The largest timestep, as a fraction of the Rayleigh time, that `sweep` accepts without
/// `--force`: the largest fraction that ran clean and kept MFR within its error bound at the
/// harshest corner of the thesis space (D 1 mm, gap 5 mm, v 1.6 m/s, μ 0.3), measured by
/// `sweep bench stability sweeps/thesis-lds.toml` (BENCHMARKS.md "Stability edge").
pub const MAX_RAYLEIGH_FRACTION: f64 = 0.5;
/// LIGGGHTS's least Young's modulus without `hard_particles yes`, MPa (global_properties.cpp).
pub const MIN_YOUNGS_MPA: f64 = 5.0;

/// Refuse a timestep beyond [`MAX_RAYLEIGH_FRACTION`] of the Rayleigh time, saying why.
pub fn check_rayleigh_fraction(fraction: f64) -> Result<(), String> {
    if fraction > MAX_RAYLEIGH_FRACTION * (1.0 + 1e-9) {
        return Err(format!(
            "timestep {fraction:.3} × the Rayleigh time is beyond the measured safe bound \
             {MAX_RAYLEIGH_FRACTION} (at 0.6 every seed lost atoms at the harshest corner of the thesis \
             space, BENCHMARKS.md \"Stability edge\"); lower scene.rayleigh_fraction, or pass --force"
        ));
    }
    Ok(())
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SceneError {
    #[error("parameter `{name}` = {value}: {why}")]
    Invalid { name: String, value: f64, why: String },
    /// Far outside what the scene is built for ([`plausible`]); the message names the slip.
    #[error("{0}")]
    Implausible(String),
}

/// Every number the deck and the metrics need for one point.
#[derive(Debug, Clone, Serialize)]
pub struct Scene {
    // Material (SI).
    pub density: f64,
    pub youngs_modulus: f64,
    pub poisson: f64,
    pub restitution: f64,
    pub friction: f64,
    pub rolling_friction: f64,
    /// LIGGGHTS rolling-friction model (used when `rolling_friction` > 0).
    pub rolling_model: &'static str,
    /// `"conveyor"`, `"gated"` or `"thesis"` (see [`crate::scene::settings::SceneSettings::layout`]).
    pub layout: String,
    // Particles.
    pub size_classes: Vec<psd::SizeClass>,
    /// Seed of the pile's diameters and jitter.
    pub seed: u64,
    pub particles: usize,
    /// Number-mean diameter: the unit of the scene's geometry, m.
    pub diameter: f64,
    /// Diameter that sets the v_x layers: D for one size, D85 for a distribution (thesis §3.2).
    pub profile_diameter: f64,
    // Blade.
    pub gap: f64,
    pub blade_speed: f64,
    pub blade_thickness: f64,
    /// x of the blade's rear face at the start; the front face is at + thickness.
    pub blade_x0: f64,
    pub blade_top: f64,
    /// Inset of the blade mesh from the periodic y faces (it must lie inside the box).
    pub blade_y_inset: f64,
    // Domain.
    pub x_hi: f64,
    pub depth: f64,
    pub z_hi: f64,
    /// Bottom of the box and height of the plate: 0 on a smooth plate, minus one substrate
    /// diameter under a rough substrate.
    pub z_lo: f64,
    // The rough substrate: fixed spheres on a square lattice, tops at z = 0 (none: 0 spheres).
    pub substrate_particles: usize,
    pub substrate_diameter: f64,
    pub substrate_spacing: f64,
    pub substrate_n: [usize; 2],
    /// x of the gate closing the dose's region during the settle; 0: no gate.
    pub gate_x: f64,
    // The initial pile: a jittered simple-cubic block nx × ny × nz with this spacing, from x0.
    pub pile_x0: f64,
    pub pile_x1: f64,
    pub pile_z1: f64,
    pub pile_spacing: f64,
    pub pile_n: [usize; 3],
    // Time.
    pub rayleigh_time: f64,
    pub timestep: f64,
    pub skin: f64,
    /// Thesis layout: steps of the fixed-time settle. Gated: the settle runs at least this long
    /// before the rest criterion is checked.
    pub settle_steps: u64,
    /// Gated layout: translational kinetic energy of the powder below which it is at rest, J
    /// (0: fixed-time settle).
    pub rest_ke: f64,
    /// The rms speed that `rest_ke` stands for, m/s.
    pub rest_speed: f64,
    /// Gated layout: steps between rest checks, and the most checks before the run fails.
    pub settle_check_steps: u64,
    pub settle_max_checks: u64,
    /// Steps from the blade's start (step 0 of the spread) to the window's start.
    pub approach_steps: u64,
    /// Steps over which the blade accelerates linearly from rest to full speed.
    pub ramp_steps: u64,
    /// Steps between snapshots; the window is SUB_WINDOWS × SNAPSHOTS_PER_SUB_WINDOW of them.
    pub dump_every: u64,
    /// Steps of the measurement window.
    pub window_length_steps: u64,
    /// Steps after the window to the end of the domain (`run_to_end`; 0: stop at the window's
    /// end).
    pub traverse_steps: u64,
    /// Steps between dumps of every column over the whole run (0: none).
    pub full_dump_every: u64,
    /// Steps between the VTK files of the particles and the blade over the spread (0: none).
    pub vtk_every: u64,
    /// Largest cell of the blade mesh, m.
    pub mesh_cell: f64,
    pub thermo_every: u64,
    // Measurement.
    /// Half-height of a v_x layer, m.
    pub vx_band: f64,
    /// Length of the v_x region in front of the blade (6 D, thesis Appendix A), m.
    pub vx_length: f64,
    /// Kinetic energy above which the run is unstable, J.
    pub ke_limit: f64,
    /// Conveyor layout (zero elsewhere): the held heap and the block series.
    pub conveyor: Conveyor,
}

/// The blade's frame (conveyor layout): the blade stands still with its rear face at
/// `blade_x0`, the rough substrate moves under it at −v (x periodic), a heap of
/// `heap_particles` is topped up in the box ahead of the blade, and the deposit is deleted
/// downstream. All lengths in m.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Conveyor {
    /// Height of the held heap (gap + heap_diameters·D), and the particles it holds at a
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
    /// Particle templates of the feed: diameter, mass fraction, prime seed.
    pub feed: Vec<FeedClass>,
    /// Prime seeds of the feed's distribution and insertion.
    pub distribution_seed: u64,
    pub insert_seed: u64,
}

#[derive(Debug, Clone, Serialize)]
pub struct FeedClass {
    pub diameter: f64,
    pub mass_fraction: f64,
    pub seed: u64,
}

/// The `n`-th prime above 10,000 after `start` (LIGGGHTS wants prime seeds above 10,000).
fn prime_seed(start: u64, n: usize) -> u64 {
    let is_prime = |k: u64| k > 1 && (2..).take_while(|d| d * d <= k).all(|d| !k.is_multiple_of(d));
    (10_007 + start % 1_000_000..).filter(|&k| is_prime(k)).nth(n).expect("primes are infinite")
}

impl Scene {
    /// Build the scene from every catalogue parameter (in catalogue units) and the settings.
    pub fn new(values: &BTreeMap<String, f64>, settings: &SceneSettings) -> Result<Scene, SceneError> {
        let get = |name: &str| -> f64 {
            values
                .get(name)
                .copied()
                .unwrap_or_else(|| params::lookup(name).map(|p| p.default).unwrap_or(f64::NAN))
        };
        for info in params::CATALOGUE {
            let v = get(info.name);
            if !v.is_finite() || !info.accepts(v) {
                return Err(SceneError::Invalid {
                    name: info.name.into(),
                    value: v,
                    why: format!("outside {}", info.domain()),
                });
            }
        }
        let mm = 1e-3;
        let psd = SizeDistribution::from_spec(
            &settings.size_distribution,
            get("diameter") * mm,
            get("weibull_shape"),
            get("weibull_scale") * mm,
        );
        let d = psd.mean_diameter();
        let d_min = psd.min_diameter();
        let gap = get("gap") * mm;
        let speed = get("blade_speed");
        let density = get("density");
        // The stiffness reduction stops at LIGGGHTS's floor (it refuses a softer modulus).
        let youngs = (get("youngs_modulus") * settings.stiffness_factor).max(MIN_YOUNGS_MPA) * 1e6;
        let poisson = get("poisson");

        let rayleigh_time = rayleigh_time(d_min / 2.0, density, youngs, poisson);
        let timestep = if settings.timestep_s > 0.0 {
            settings.timestep_s
        } else {
            settings.rayleigh_fraction * rayleigh_time
        };
        if !settings.force_bounds {
            if let Err(why) = check_rayleigh_fraction(timestep / rayleigh_time) {
                return Err(SceneError::Invalid { name: "timestep".into(), value: timestep, why });
            }
        }

        // Geometry in units of the mean diameter, so the particle count barely changes with D.
        // The dose starts as a jittered simple-cubic block (an exact, reproducible count; no
        // random insertion to fall short). The depth is a whole number of lattice spacings so
        // the periodic images keep their spacing.
        let gated = settings.layout == "gated";
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
        let window = settings.window_diameters * d;
        // Travel of the blade's front from its start to the window's start, for a block of
        // length `len` and height `height`. Gated: past the opened gate (the block's front) by
        // the development length. Thesis: past the settled pile's slump (about half its
        // height) and 5 D more.
        let approach_travel = |len: f64, height: f64| {
            if gated {
                0.5 * d + len + settings.window_start_diameters * d
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
        let settle_time = if gated { 0.5 * settings.settle_min_falls * fall_time } else { fall_time + 0.02 };

        let intervals = (SUB_WINDOWS * SNAPSHOTS_PER_SUB_WINDOW) as f64;
        let dump_every = ((window_time / intervals) / timestep).ceil().max(1.0) as u64;
        let round_up = |t: f64| ((t / timestep).ceil() as u64).div_ceil(dump_every) * dump_every;
        let settle_steps = (settle_time / timestep).ceil() as u64;
        let settle_check_steps = (SETTLE_CHECK_S / timestep).ceil() as u64;
        let settle_max_checks =
            ((settings.settle_max_s - settle_time).max(0.0) / SETTLE_CHECK_S).ceil().max(1.0) as u64;
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
        let traverse_steps = if settings.run_to_end {
            let travel = (3.0 * heap_height + 5.0 * d) - 2.0 * heap_height;
            (travel / (speed * timestep)).ceil() as u64
        } else {
            0
        };
        let full_dump_every = if settings.full_dump_every_s > 0.0 {
            (settings.full_dump_every_s / timestep).round().max(1.0) as u64
        } else {
            0
        };

        // ParaView files every 0.02 s of the spread (the thesis's output cadence, Appendix A).
        let vtk_every = if settings.vtk { (VTK_EVERY_S / timestep).round().max(1.0) as u64 } else { 0 };

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
        let rest_speed = settings.rest_speed * (GRAVITY * d).sqrt();
        let rest_ke = if gated { 0.5 * mass * rest_speed * rest_speed } else { 0.0 };

        let scene = Scene {
            density,
            youngs_modulus: youngs,
            poisson,
            restitution: get("restitution"),
            friction: get("friction"),
            rolling_friction: get("rolling_friction"),
            rolling_model: ROLLING_MODEL,
            layout: settings.layout.clone(),
            size_classes: psd.classes.clone(),
            seed: settings.seed,
            particles,
            diameter: d,
            profile_diameter,
            gap,
            blade_speed: speed,
            blade_thickness,
            blade_x0,
            blade_top,
            blade_y_inset: 1e-3 * d_min,
            x_hi,
            depth,
            z_hi,
            z_lo,
            substrate_particles: substrate_n[0] * substrate_n[1],
            substrate_diameter: if rough { d } else { 0.0 },
            substrate_spacing,
            substrate_n,
            gate_x: if gated { pile_x1 } else { 0.0 },
            pile_x0,
            pile_x1,
            pile_z1,
            pile_spacing: spacing,
            pile_n: [nx, ny, nz],
            rayleigh_time,
            timestep,
            // A quarter of the smallest diameter (default): particles move far less than that
            // between list builds (`neigh_modify delay 0` rebuilds as soon as one has).
            skin: settings.skin_diameters * d_min,
            settle_steps,
            rest_ke,
            rest_speed,
            settle_check_steps,
            settle_max_checks,
            approach_steps,
            ramp_steps,
            dump_every,
            window_length_steps,
            traverse_steps,
            full_dump_every,
            vtk_every,
            mesh_cell: depth / settings.mesh_cells_across as f64,
            // Frequent enough for the engine's watcher to stop an exploding run early.
            thermo_every: (total_steps / 40).clamp(1, 200),
            vx_band,
            vx_length: 6.0 * profile_diameter,
            ke_limit,
            conveyor: Conveyor::default(),
        };
        let scene =
            if settings.layout == "conveyor" { Scene::conveyor(scene, &psd, settings) } else { scene };
        if !settings.force_bounds {
            plausible::check(&scene, values, settings).map_err(SceneError::Implausible)?;
        }
        Ok(scene)
    }

    /// The conveyor layout's scene (see [`Conveyor`]), from what [`Scene::new`] derived.
    fn conveyor(mut s: Scene, psd: &SizeDistribution, settings: &SceneSettings) -> Scene {
        let d = s.diameter;
        let (gap, v, dt) = (s.gap, s.blade_speed, s.timestep);
        let heap_height = gap + settings.heap_diameters * d;
        let heap_base = heap_height / REPOSE_DEG.to_radians().tan();
        let heap_particles = (LAYER_FRACTION_MAX * 0.5 * heap_height * heap_base * s.depth
            / psd.mean_volume())
        .ceil() as usize;
        // Behind the blade: 10 D of deposit strip, then the delete region (6 D).
        let blade_x0 = 16.0 * d;
        let front0 = blade_x0 + s.blade_thickness;
        let heap_x1 = front0 + heap_base + 3.0 * d;
        // The substrate's lattice fills the periodic length exactly.
        let n_y = ((s.depth / d).floor() as usize).max(1);
        let spacing = s.depth / n_y as f64;
        let n_x = ((heap_x1 + 2.0 * d) / spacing).ceil() as usize;
        let x_hi = n_x as f64 * spacing;
        let block_steps = ((settings.block_diameters * d / (v * dt)).ceil() as u64).max(1);
        let blocks = |travel: f64| (travel / settings.block_diameters).ceil() as u64;
        let max_blocks = blocks(settings.window_cap_diameters);
        let blade_top = 2.0 * heap_height + 2.0 * d;
        let mean_volume = psd.mean_volume();
        let mass = heap_particles as f64 * s.density * mean_volume;
        let feed_total: f64 = psd.classes.iter().map(|c| c.fraction * c.diameter.powi(3)).sum();
        let feed = psd
            .classes
            .iter()
            .enumerate()
            .map(|(i, c)| FeedClass {
                diameter: c.diameter,
                mass_fraction: c.fraction * c.diameter.powi(3) / feed_total,
                seed: prime_seed(s.seed, i + 2),
            })
            .collect();
        s.conveyor = Conveyor {
            heap_height,
            heap_particles,
            heap_x1,
            heap_z1: 1.6 * heap_height,
            delete_x1: blade_x0 - 10.0 * d,
            block_steps,
            insert_every: (block_steps / 5).max(1),
            // Never more than the cap leaves room for: the cap wins, and the point says so.
            warmup_blocks: blocks((settings.warmup_s * v).max(10.0 * d) / d)
                .min(max_blocks.saturating_sub(settings.min_window_blocks as u64)),
            min_window_blocks: settings.min_window_blocks as u64,
            max_blocks,
            ideal_block_mass: s.density * s.depth * gap * v * dt * block_steps as f64,
            mfr_rel_se: settings.mfr_rel_se,
            mfr_abs_se: settings.mfr_abs_se,
            feed,
            distribution_seed: prime_seed(s.seed, 0),
            insert_seed: prime_seed(s.seed, 1),
        };
        s.particles = 0;
        s.pile_n = [0, 0, 0];
        s.blade_x0 = blade_x0;
        s.blade_top = blade_top;
        s.x_hi = x_hi;
        s.z_hi = blade_top + 2.0 * d + v * v / GRAVITY;
        s.z_lo = -d;
        s.substrate_n = [n_x, n_y];
        s.substrate_spacing = spacing;
        s.substrate_diameter = d;
        s.substrate_particles = n_x * n_y;
        s.gate_x = 0.0;
        s.rest_ke = 0.0;
        s.settle_steps = 0;
        s.approach_steps = 0;
        s.ramp_steps = 1;
        s.dump_every = block_steps;
        s.window_length_steps = max_blocks * block_steps;
        s.traverse_steps = 0;
        s.thermo_every = block_steps.min(1000);
        let v_ref = v.max((2.0 * GRAVITY * blade_top).sqrt());
        s.ke_limit = 0.5 * mass * (10.0 * v_ref).powi(2);
        s
    }

    /// The conveyor layout: the blade stands still and the substrate moves.
    pub fn is_conveyor(&self) -> bool {
        self.layout == "conveyor"
    }

    /// Timestep at which the blade starts moving: the spread's steps count from it (the deck
    /// resets the step counter once the pile has settled).
    pub fn blade_start_step(&self) -> u64 {
        0
    }

    /// Timestep of the window's start (t1) and end (t2).
    pub fn window_steps(&self) -> (u64, u64) {
        let t1 = self.approach_steps;
        (t1, t1 + self.window_length_steps)
    }

    /// Steps of the spread, from the blade's start to the window's end.
    pub fn spread_steps(&self) -> u64 {
        self.window_steps().1
    }

    /// Atoms in the box: the powder and the substrate.
    pub fn atoms(&self) -> usize {
        self.particles + self.substrate_particles
    }

    /// x of the blade's rear face at timestep `step`: at rest until the blade starts, then a
    /// linear velocity ramp over `ramp_steps` (travel v·t²/(2 t_r)), then full speed.
    pub fn blade_rear_at(&self, step: u64) -> f64 {
        if self.is_conveyor() {
            return self.blade_x0;
        }
        let k = step.saturating_sub(self.blade_start_step()) as f64;
        let r = self.ramp_steps as f64;
        let travel_steps = if k <= r { k * k / (2.0 * r) } else { k - 0.5 * r };
        self.blade_x0 + self.blade_speed * self.timestep * travel_steps
    }

    /// x of the blade's front face at timestep `step`.
    pub fn blade_front_at(&self, step: u64) -> f64 {
        self.blade_rear_at(step) + self.blade_thickness
    }

    /// Centre height of v_x layer k = 1..12: z = gap + k·D/2 (thesis Appendix A).
    pub fn layer_height(&self, k: usize) -> f64 {
        self.gap + k as f64 * self.profile_diameter / 2.0
    }
}

/// Rayleigh time of a sphere of radius `r` (LIGGGHTS fix_check_timestep_gran.cpp):
/// T_R = π r √(ρ/G) / (0.1631 ν + 0.8766), with G = E / (2(1 + ν)).
pub fn rayleigh_time(r: f64, density: f64, youngs: f64, poisson: f64) -> f64 {
    let shear = youngs / (2.0 * (1.0 + poisson));
    std::f64::consts::PI * r * (density / shear).sqrt() / (0.1631 * poisson + 0.8766)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(pairs: &[(&str, f64)]) -> Scene {
        let values = pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        Scene::new(&values, &SceneSettings::gated()).unwrap()
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
        let settings = SceneSettings::preset("thesis").unwrap();
        let t = Scene::new(&BTreeMap::new(), &settings).unwrap();
        assert_eq!(t.timestep, THESIS_TIMESTEP);
    }

    #[test]
    fn the_stiffness_reduction_lengthens_the_rayleigh_time_and_stops_at_the_floor() {
        // T_R ∝ 1/√E: a quarter of the modulus doubles it.
        let values: BTreeMap<String, f64> = [("youngs_modulus".to_string(), 21.0)].into_iter().collect();
        let full =
            Scene::new(&values, &SceneSettings { stiffness_factor: 1.0, ..SceneSettings::gated() }).unwrap();
        let soft =
            Scene::new(&values, &SceneSettings { stiffness_factor: 0.25, ..SceneSettings::gated() }).unwrap();
        assert!((soft.youngs_modulus - 5.25e6).abs() < 1e-6);
        assert!((soft.rayleigh_time / full.rayleigh_time - 2.0).abs() < 1e-12);
        let floor =
            Scene::new(&values, &SceneSettings { stiffness_factor: 0.1, ..SceneSettings::gated() }).unwrap();
        assert_eq!(floor.youngs_modulus, MIN_YOUNGS_MPA * 1e6);
    }

    #[test]
    fn the_window_is_after_the_pile_and_inside_the_box() {
        for (d, gap) in [(1.0, 1.0), (1.0, 5.0), (3.0, 1.0), (3.0, 5.0)] {
            let s = scene(&[("diameter", d), ("gap", gap), ("blade_speed", 1.6)]);
            let (t1, t2) = s.window_steps();
            // Window starts after the blade front has passed the insertion block's far end.
            assert!(s.blade_front_at(t1) > s.pile_x1, "d={d} gap={gap}");
            // Window length is window_diameters·D (rounded up to whole snapshot intervals), at
            // full speed.
            let len = s.blade_rear_at(t2) - s.blade_rear_at(t1);
            let w = SceneSettings::gated().window_diameters * s.diameter;
            assert!(len >= w && len < w + s.diameter, "{len}");
            // The blade is at full speed when the window opens.
            assert!(t1 >= s.blade_start_step() + s.ramp_steps);
            // The blade never leaves the box.
            assert!(s.blade_front_at(s.spread_steps()) < s.x_hi);
            assert!(s.blade_top < s.z_hi);
            // All step counts line up with the dump cadence.
            assert_eq!(t1 % s.dump_every, 0);
            assert_eq!(s.spread_steps() % s.dump_every, 0);
        }
    }

    #[test]
    fn particle_count_scales_weakly_with_diameter() {
        // Geometry is in diameters, so the count depends on gap/D, not on D itself.
        let a = scene(&[("diameter", 1.0), ("gap", 2.0)]).particles;
        let b = scene(&[("diameter", 3.0), ("gap", 6.0)]).particles;
        assert_eq!(a, b);
    }

    #[test]
    fn layers_are_centred_at_gap_plus_half_diameters() {
        let s = scene(&[("diameter", 2.0), ("gap", 3.0)]);
        assert!((s.layer_height(1) - 4e-3).abs() < 1e-15);
        assert!((s.layer_height(12) - 15e-3).abs() < 1e-15);
        assert!((s.vx_band - 0.5e-3).abs() < 1e-15);
    }

    #[test]
    fn the_rest_criterion_is_an_rms_speed_of_one_percent_of_sqrt_g_d() {
        // D = 2 mm: v_rest = 0.01 √(9.81 · 0.002) = 1.4007e-3 m/s; KE_rest = ½ M v², with M the
        // dose's mass, n · ρ · π D³ / 6.
        let s = scene(&[("diameter", 2.0)]);
        let v = 0.01 * (9.81f64 * 0.002).sqrt();
        assert!((s.rest_speed - v).abs() < 1e-12);
        let mass = s.particles as f64 * 7980.0 * std::f64::consts::PI * 0.002f64.powi(3) / 6.0;
        assert!((s.rest_ke / (0.5 * mass * v * v) - 1.0).abs() < 1e-9);
        // The thesis layout has no rest criterion, gate or substrate.
        let values = [("diameter".to_string(), 2.0)].into_iter().collect();
        let thesis = SceneSettings { layout: "thesis".into(), ..SceneSettings::gated() };
        let t = Scene::new(&values, &thesis).unwrap();
        assert_eq!((t.rest_ke, t.gate_x, t.substrate_particles, t.z_lo), (0.0, 0.0, 0, 0.0));
        assert!(s.gate_x > 0.0 && s.substrate_particles > 0 && s.z_lo == -s.diameter);
    }

    #[test]
    fn out_of_domain_values_name_the_parameter() {
        let values = [("restitution".to_string(), 0.0)].into_iter().collect();
        let err = Scene::new(&values, &SceneSettings::gated()).unwrap_err();
        assert!(err.to_string().contains("restitution"), "{err}");
    }
}

#[cfg(test)]
mod ramp_tests {
    use super::*;

    #[test]
    fn blade_position_is_continuous_through_the_ramp_and_linear_after() {
        let s = Scene::new(&BTreeMap::new(), &SceneSettings::gated()).unwrap();
        let s0 = s.blade_start_step();
        let r = s.ramp_steps;
        assert_eq!(s.blade_rear_at(s0), s.blade_x0);
        // During the ramp the travel is v·dt·k²/(2r): a quarter of full-speed travel at k = r/2.
        let half = s.blade_rear_at(s0 + r / 2) - s.blade_x0;
        let k = (r / 2) as f64;
        assert!((half - s.blade_speed * s.timestep * k * k / (2.0 * r as f64)).abs() < 1e-15);
        // After it, exactly v·dt per step.
        let a = s.blade_rear_at(s0 + r + 10);
        let b = s.blade_rear_at(s0 + r + 11);
        assert!((b - a - s.blade_speed * s.timestep).abs() < 1e-15);
        // The ramp's travel is RAMP_DIAMETERS·D to within a step.
        let ramp_travel = s.blade_rear_at(s0 + r) - s.blade_x0;
        assert!((ramp_travel - RAMP_DIAMETERS * s.diameter).abs() < s.blade_speed * s.timestep);
    }
}
