//! The pour layout: the angle of repose of the sweep file's powder by the lifted-cylinder test
//! (a hollow cylinder filled with powder on a plate is raised and the powder slumps into a
//! heap; Roessler & Katterfeld 2018, Powder Technol. 330, 58–66, study this test for DEM
//! calibration).
//!
//! The run: a column of [`PARTICLES`] spheres (times `scene.supply_factor`) on a jittered
//! lattice inside a cylinder [`CYLINDER_RADIUS_D`] mean diameters in radius settles for a fixed
//! time, the cylinder rises at [`LIFT_SPEED`] × √(g·D) until its rim is two diameters above the
//! settled column's top (measured in the deck), and the heap settles until its kinetic energy is
//! below the rest criterion (`scene.rest_speed`, as the gated layout's). Its angle and packing
//! are measured from the particles at rest ([`heap`]). Plate and cylinder are of the powder's
//! material (sliding and rolling friction with the powder's coefficients), but not cohesive: at
//! 12 D across, a tube the powder sticks to lifts a cohesive column as a plug (Ti-6Al-4V
//! 15–45 µm at 0.1 mJ/m² rose with it), which no lab cylinder many diameters wider does.
//!
//! The column settles inside a smooth cylinder wall of the same radius as tall as the box (a
//! lattice of a size distribution stands several times the settled column's height, as its
//! spacing is the largest diameter); the lift is of a mesh tube only as tall as the loosest
//! settled column ([`LOOSEST_PACKING`]): a moving mesh costs each step in proportion to its
//! faces (a 1,000-particle Ti-6Al-4V pour: 0.78 ms a step of the lift with the lattice's full
//! height in faces, 0.49 ms with the short tube).
//!
//! The pour's part of its [`Scene`] is a [`Column`]: the cylinder, its lattice and its lift, and
//! the settles ([`Settle`]). There is no blade, so no gap, window or substrate (nothing is ever
//! "closed").

pub mod geometry;
pub mod heap;
pub mod result;
pub mod stand_in;

use crate::engine::dump::read_dump;
use crate::outcome::{FailureClass, PointAnswer, RunResult, RESULT_FORMAT, VX_LAYERS};
use crate::scene::blade::Settle;
use crate::scene::own::{LayoutData, OwnData};
use crate::scene::plausible::short;
use crate::scene::settings::SceneSettings;
use crate::scene::{Base, LayoutScene, Scene, GRAVITY, LAYER_FRACTION_MAX};
use crate::scenes::quantity::Quantity;
use crate::scenes::stand_in::StandInPoint;
use crate::scenes::{BadSetting, BuiltinTemplate, Finished, Layout, Rejected, SetupRows};
use heap::CALIBRATION_TARGETS;

/// The pour layout (registered in [`crate::scenes::LAYOUTS`]).
pub struct Pour;

/// The pour's part of the scene: the column in its cylinder, the lift and the settles. The deck
/// reads the cylinder and the lift under the keys the blade layouts' decks use for their pile and
/// blade (`scene.pile_x0`, `scene.blade_speed`, …), as it did when the common scene held them:
/// its template, whose hash a sweep's identity records (a sweep whose template changed is not
/// resumed), stays as it was.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Column {
    /// The column's settle, and the heap's settle until it is at rest.
    #[serde(flatten)]
    pub settle: Settle,
    /// The cylinder's inner wall spans x from `cylinder_x0` to `cylinder_x1` (its diameter).
    #[serde(rename = "pile_x0")]
    pub cylinder_x0: f64,
    #[serde(rename = "pile_x1")]
    pub cylinder_x1: f64,
    /// Height of the lifted tube, m.
    #[serde(rename = "blade_top")]
    pub tube_height: f64,
    /// Speed of its lift, m/s.
    #[serde(rename = "blade_speed")]
    pub lift_speed: f64,
    /// Steps of the longest lift (a settled column as tall as the lattice).
    #[serde(rename = "approach_steps")]
    pub lift_steps: u64,
    /// Steps of the heap's least settle before the rest criterion is checked.
    #[serde(rename = "window_length_steps")]
    pub heap_settle_steps: u64,
    /// The column's lattice: its spacing and its layers, m.
    #[serde(skip)]
    pub lattice_spacing: f64,
    #[serde(skip)]
    pub lattice_layers: usize,
}

impl LayoutData for Column {
    fn steps(&self) -> u64 {
        self.lift_steps + self.heap_settle_steps
    }
}

/// The part of a pour's scene.
pub fn column(scene: &Scene) -> &Column {
    scene.own().expect("a pour's scene carries its column")
}

/// Inner radius of the cylinder, in mean diameters: 12 D across.
pub const CYLINDER_RADIUS_D: f64 = 6.0;
/// Particles in the column at `supply_factor` 1: a heap about 30 D across, a CPU minute at
/// D = 2 mm.
pub const PARTICLES: usize = 2000;
/// The fewest particles a column may hold: a heap of fewer stands under the 5 D the profile fit
/// needs (2,000 spheres of 2 mm stood 6–7 D tall).
pub const MIN_PARTICLES: usize = 500;
/// Lift speed of the cylinder, in √(g·D) (14 mm/s at D = 2 mm). The heap depends on it: a
/// faster lift lets the column run out as a collapse. At friction 0.3 and rolling friction
/// 0.175 (D = 2 mm) the heap stood 8.4, 9.7 and 13.5 mm tall after lifts at 0.6, 0.3 and 0.1
/// √(g·D), and 7.3 mm when the cylinder vanished at once (docs/scene.md "Pour").
pub const LIFT_SPEED: f64 = 0.1;
/// Half-width of the box over the foot radius of a heap of the column's powder at 10° and a
/// packing of 0.6: the walls stay out of reach of all but the longest run-out.
const BOX_MARGIN: f64 = 1.5;
/// Lattice spacing of the column over the largest diameter.
const LATTICE_CLEARANCE: f64 = 1.05;
/// Packing of the column settled in the cylinder, a lower bound: sets the tube's height. A
/// cohesive powder settles loose: Ti-6Al-4V 15–45 µm at 0.1 mJ/m² stood at 0.35–0.37 (the
/// top 1 % of its particles excluded or not); 2,000 steel spheres of 2 mm at 0.51.
pub const LOOSEST_PACKING: f64 = 0.3;
/// Simulated time between checks of the rest criterion, s.
const SETTLE_CHECK_S: f64 = 0.005;

/// The heap's particles at rest, in the run directory.
pub const HEAP_DUMP: &str = "dump.heap";

const REFUSED: &str = "a pour measures an angle of repose, not a mass flow rate, and a sweep's \
     statistics and report read MFR; run its points one at a time with `sweep run` (each prints \
     the angle with its standard error)";

impl Layout for Pour {
    fn name(&self) -> &'static str {
        "pour"
    }

    fn template(&self) -> BuiltinTemplate {
        BuiltinTemplate {
            name: "pour.liggghts.tera",
            source: include_str!("../../../templates/pour.liggghts.tera"),
        }
    }

    fn check_settings(&self, s: &SceneSettings) -> Result<(), BadSetting> {
        for (key, v) in [("scene.rest_speed", s.rest_speed), ("scene.settle_max_s", s.settle_max_s)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(BadSetting { key, why: format!("{v}: expected a positive number") });
            }
        }
        let n = column_particles(s.supply_factor);
        if n < MIN_PARTICLES {
            return Err(BadSetting {
                key: "scene.supply_factor",
                why: format!(
                    "{}: a column of {n} particles; expected at least {:.2} ({MIN_PARTICLES} particles, \
                     the smallest heap whose angle can be fitted)",
                    s.supply_factor,
                    MIN_PARTICLES as f64 / PARTICLES as f64
                ),
            });
        }
        Ok(())
    }

    fn derive(&self, base: Base, settings: &SceneSettings) -> Scene {
        derive(base, settings)
    }

    fn own_settings(&self) -> Vec<&'static str> {
        // Its heap stands on the smooth plate in a box of its own: no substrate, blade mesh or
        // domain depth of a spread.
        vec!["supply_factor", "rest_speed", "settle_max_s"]
    }

    fn atoms_kept(&self, scene: &Scene) -> Option<u64> {
        // A closed box: nothing leaves.
        Some(scene.particles as u64)
    }

    fn measure(&self, run: &Finished) -> Result<RunResult, Rejected> {
        measure(run)
    }

    fn what_runs(&self, s: &Scene) -> String {
        format!(
            "{} particles poured from a {:.1} mm cylinder lifted at {:.3} m/s, settled until at rest",
            s.particles,
            2e3 * geometry::cylinder_radius(s),
            column(s).lift_speed
        )
    }

    fn ignores(&self, _settings: &SceneSettings, name: &str) -> Option<&'static str> {
        match name {
            "gap" | "heap_height" | "layer_thickness" | "roller_speed_ratio" => {
                Some("pours a heap on the plate: it has no blade")
            }
            "blade_speed" => Some("lifts its cylinder at a fixed speed in √(g·D)"),
            _ => None,
        }
    }

    fn setup_rows(&self, s: &SceneSettings) -> SetupRows {
        SetupRows {
            head: vec![
                ("particles in the column", column_particles(s.supply_factor).to_string()),
                ("cylinder diameter (D)", short(2.0 * CYLINDER_RADIUS_D)),
            ],
            tail: vec![("rest speed (× √(g·D))", short(s.rest_speed))],
        }
    }

    fn run_files(&self, _settings: &SceneSettings) -> Vec<String> {
        vec![HEAP_DUMP.into()]
    }

    fn result_columns(&self) -> &'static [&'static str] {
        &["angle_of_repose_deg", "angle_of_repose_se_deg", "bulk_packing", "heap_height_mm"]
    }

    fn result_values(&self, r: &RunResult) -> Vec<String> {
        match result::heap(r) {
            Some(h) => [h.angle_deg, h.angle_se_deg, h.packing, h.height_mm].map(|v| v.to_string()).to_vec(),
            None => vec![String::new(); 4],
        }
    }

    fn calibration_targets(&self) -> &'static [Quantity] {
        CALIBRATION_TARGETS
    }

    fn stand_in(&self, point: &mut StandInPoint) -> Result<RunResult, Rejected> {
        Ok(stand_in::heap(point))
    }

    fn mesh(&self, scene: &Scene) -> String {
        geometry::tube_stl(scene)
    }

    fn pile(&self, scene: &Scene) -> String {
        geometry::column_data(scene)
    }

    fn check_result(&self, r: &RunResult) -> Result<(), crate::measure::plausible::Implausible> {
        // Nothing flows in a heap: its flow's numbers are NaN (not measured).
        let flow = !(result::heap(r).is_some() && r.answer.value.is_nan());
        crate::measure::plausible::check_result(
            r,
            crate::measure::plausible::Measures { flow, flux: flow, depth: 1.0 },
        )
    }

    fn refuses_sweeps(&self) -> Option<&'static str> {
        Some(REFUSED)
    }

    fn result_lines(&self, r: &RunResult) -> Option<Vec<String>> {
        let h = result::heap(r)?;
        let sectors: Vec<String> = h.sector_angles_deg.iter().map(|a| format!("{a:.1}")).collect();
        Some(vec![
            format!(
                "angle of repose  {:.2} ± {:.2}° (SE over {} sectors: {})",
                h.angle_deg,
                h.angle_se_deg,
                sectors.len(),
                sectors.join(" ")
            ),
            format!(
                "heap             {:.1} mm tall, foot radius {:.1} mm, packing {:.3}; {} run out",
                h.height_mm, h.base_radius_mm, h.packing, h.particles_run_out
            ),
        ])
    }
}

/// Particles in the column: [`PARTICLES`] × `supply_factor`, rounded. A smaller column is a
/// cheaper pour (the lift, the longest part, is as long as the column is tall, so the cost goes
/// as the count squared) and a smaller heap, whose angle scatters more.
pub fn column_particles(supply_factor: f64) -> usize {
    (PARTICLES as f64 * supply_factor).round().max(0.0) as usize
}

/// The pour's scene from the point's common part.
fn derive(base: Base, settings: &SceneSettings) -> Scene {
    let Base { psd, d, timestep, .. } = base.clone();
    let density = base.material.density;
    let particles = column_particles(settings.supply_factor);
    let spacing = LATTICE_CLEARANCE * psd.max_diameter();
    let radius = CYLINDER_RADIUS_D * d;
    let per_layer = geometry::layer_sites(radius, spacing).len().max(1);
    let layers = particles.div_ceil(per_layer);
    let column = layers as f64 * spacing;
    // The tube stands two diameters above the loosest settled column (never above the lattice),
    // and rises until its rim is two diameters above the settled column's top, which the deck
    // measures; at most the lattice's height.
    let solid = particles as f64 * psd.mean_volume();
    let tube_height =
        (solid / (LOOSEST_PACKING * std::f64::consts::PI * radius * radius) + 2.0 * d).min(column + d);
    let longest_lift = column + 2.0 * d;
    let speed = LIFT_SPEED * (GRAVITY * d).sqrt();
    let foot_10deg =
        (3.0 * solid / (LAYER_FRACTION_MAX * std::f64::consts::PI * 10f64.to_radians().tan())).cbrt();
    let width = 2.0 * (BOX_MARGIN * foot_10deg).max(radius + 2.0 * d);
    let z_hi = column.max(tube_height + longest_lift) + 2.0 * d;
    let steps = |t: f64| ((t / timestep).ceil() as u64).max(1);
    // The column falls a little as its lattice collapses: a free fall of its height and as long
    // again.
    let fall_time = 2.0 * (2.0 * column / GRAVITY).sqrt();
    let mass = particles as f64 * density * psd.mean_volume();
    let rest_speed = settings.rest_speed * (GRAVITY * d).sqrt();
    let check = steps(SETTLE_CHECK_S);
    let settle_least = fall_time;
    let max_checks =
        ((settings.settle_max_s - settle_least).max(0.0) / SETTLE_CHECK_S).ceil().max(1.0) as u64;
    let v_ref = (2.0 * GRAVITY * z_hi).sqrt();
    let laid = LayoutScene {
        particles,
        x_hi: width,
        depth: width,
        z_hi,
        z_lo: 0.0,
        mesh_cell: d,
        thermo_every: check.min(200),
        ke_limit: 0.5 * mass * (10.0 * v_ref).powi(2),
        own: OwnData::new(Column {
            settle: Settle {
                settle_steps: steps(fall_time),
                rest_ke: 0.5 * mass * rest_speed * rest_speed,
                rest_speed,
                settle_check_steps: check,
                settle_max_checks: max_checks,
            },
            cylinder_x0: 0.5 * width - radius,
            cylinder_x1: 0.5 * width + radius,
            tube_height,
            lift_speed: speed,
            lift_steps: steps(longest_lift / speed),
            heap_settle_steps: steps(settle_least),
            lattice_spacing: spacing,
            lattice_layers: layers,
        }),
    };
    Scene::new(&base, settings, laid)
}

/// The heap at rest from `dump.heap`: its angle, SE and packing. Nothing flows in a pour, so
/// every MFR field is NaN (absent from `result.json`).
fn measure(run: &Finished) -> Result<RunResult, Rejected> {
    let scene = run.scene;
    let steps =
        crate::engine::settled_at(&run.run.log).map_err(|(class, reason)| Rejected::new(class, reason))?;
    let snaps = read_dump(run.run_dir.join(HEAP_DUMP), &["x", "y", "z", "radius"])
        .map_err(|e| Rejected::new(FailureClass::Unparsable, e.to_string()))?;
    let Some(last) = snaps.last() else {
        return Err(Rejected::new(FailureClass::Unparsable, format!("{HEAP_DUMP}: no snapshot")));
    };
    let col = |name| last.column(name).expect("required column");
    let (x, y, z, r) = (col("x"), col("y"), col("z"), col("radius"));
    let grains: Vec<heap::Grain> = (0..last.len())
        .map(|i| heap::Grain { x: last.get(i, x), y: last.get(i, y), z: last.get(i, z), r: last.get(i, r) })
        .collect();
    if grains.len() != scene.particles {
        return Err(Rejected::new(
            FailureClass::Unparsable,
            format!("{HEAP_DUMP}: {} particles, expected {}", grains.len(), scene.particles),
        ));
    }
    let heap = heap::measure(&grains, geometry::axis(scene), scene.diameter)
        .map_err(|e| Rejected::new(FailureClass::Implausible, format!("no heap to measure: {e}")))?;
    if !(heap.packing > 0.0 && heap.packing < 0.75) {
        return Err(Rejected::new(
            FailureClass::Implausible,
            format!(
                "heap packing {:.3}: outside (0, 0.75), beyond the densest packing of spheres",
                heap.packing
            ),
        ));
    }
    Ok(RunResult {
        format: RESULT_FORMAT,
        hash: run.hash.to_string(),
        parameters: run.parameters.clone(),
        answer: PointAnswer::none(),
        mfr_flux: f64::NAN,
        answer_particles: 0,
        steady_state: None,
        answer_windows: Vec::new(),
        // The heap came to rest (a heap still moving fails as not-settled).
        steady: true,
        steady_p: f64::NAN,
        // No blade, so no layer in front of one: every v_x layer empty (a sweep directory reads
        // a done result as one v_x per layer).
        vx: vec![None; VX_LAYERS],
        vx_se: Vec::new(),
        particles: scene.particles,
        layer: None,
        own: crate::outcome::OwnResult::new(heap),
        settle_steps: steps,
        ..run.record(steps)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pour(supply_factor: f64) -> Scene {
        let values =
            [("diameter".to_string(), 2.0), ("rolling_friction".to_string(), 0.2)].into_iter().collect();
        let settings = SceneSettings { supply_factor, ..crate::scenes::settings::defaults(&Pour) };
        crate::scenes::build(&values, &settings).unwrap()
    }

    /// Ti-6Al-4V 15–45 µm (sweeps/ti64-machine.toml's sizes) in the pour.
    fn ti64(supply_factor: f64) -> Scene {
        ti64_with(supply_factor, 0.0)
    }

    fn ti64_with(supply_factor: f64, surface_energy: f64) -> Scene {
        let settings: SceneSettings = toml::from_str(
            "layout = \"pour\"\n[size_distribution]\nkind = \"lognormal\"\nd10_um = 20.0\nd50_um = 31.0\n\
             d90_um = 42.0\ncut_um = [15.0, 45.0]\nbins = 8\n",
        )
        .unwrap();
        let values = [("density".to_string(), 4430.0), ("surface_energy".to_string(), surface_energy)]
            .into_iter()
            .collect();
        crate::scenes::build(&values, &SceneSettings { supply_factor, ..settings }).unwrap()
    }

    #[test]
    fn the_supply_factor_sizes_the_column_and_its_lift() {
        let (full, half) = (pour(1.0), pour(0.5));
        assert_eq!((full.particles, half.particles), (2000, 1000));
        // Every particle is on the lattice, in fewer layers.
        assert!(geometry::column_data(&half).contains("\n1000 atoms\n"));
        assert!(column(&half).lattice_layers < column(&full).lattice_layers);
        // A size distribution's lattice stands far above its settled column: there the tube is
        // 2 D above the loosest settled column, so half the solid is half its height (less its
        // 2 D), and half the faces the moving mesh costs. Equal spheres pack on the lattice
        // nearly as they settle, and the tube is the lattice's height.
        let (ti, ti_half) = (ti64(1.0), ti64(0.5));
        let tube = |s: &Scene| column(s).tube_height - 2.0 * s.diameter;
        assert!((tube(&ti_half) / tube(&ti) - 0.5).abs() < 1e-9, "{} {}", tube(&ti_half), tube(&ti));
        let loosest = |s: &Scene| {
            let solid: f64 = s.size_classes.iter().map(|c| c.fraction * c.diameter.powi(3)).sum::<f64>()
                * std::f64::consts::PI
                / 6.0
                * s.particles as f64;
            solid / (LOOSEST_PACKING * std::f64::consts::PI * geometry::cylinder_radius(s).powi(2))
        };
        assert!((tube(&ti) / loosest(&ti) - 1.0).abs() < 1e-9, "{} {}", tube(&ti), loosest(&ti));
        let lattice = |s: &Scene| column(s).lattice_layers as f64 * column(s).lattice_spacing;
        assert!(column(&ti).tube_height < lattice(&ti) / 3.0);
        for s in [&full, &half] {
            assert!((column(s).tube_height - (lattice(s) + s.diameter)).abs() < 1e-12);
        }
        // The longest lift clears a settled column as tall as the lattice, inside the box.
        for s in [&full, &half, &ti, &ti_half] {
            let c = column(s);
            let longest = c.lift_steps as f64 * s.timestep * c.lift_speed;
            assert!(longest >= lattice(s) + 2.0 * s.diameter);
            assert!(c.tube_height + longest < s.z_hi);
        }
        // The rest criterion is the same rms speed over the smaller mass.
        assert!((column(&half).settle.rest_ke / column(&full).settle.rest_ke - 0.5).abs() < 1e-12);
    }

    #[test]
    fn the_tube_faces_stand_at_the_cylinders_radius_and_the_deck_sizes_the_lift() {
        let s = pour(1.0);
        let stl = geometry::tube_stl(&s);
        let [cx, cy] = geometry::axis(&s);
        let r = geometry::cylinder_radius(&s);
        let v: Vec<[f64; 2]> = stl
            .lines()
            .filter_map(|l| l.trim().strip_prefix("vertex "))
            .map(|l| {
                let c: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
                [c[0] - cx, c[1] - cy]
            })
            .collect();
        // Every face's mid-line lies at the radius of the wall the column settled against.
        let step = 2.0 * std::f64::consts::PI / 48.0;
        let corner = r / (step / 2.0).cos();
        assert!(v.iter().all(|p| (p[0].hypot(p[1]) - corner).abs() < 1e-9 * r));
        assert!((corner * (step / 2.0).cos() - r).abs() < 1e-15);
        let mut context = tera::Context::new();
        context.insert("scene", &s);
        let deck = tera::Tera::one_off(Pour.template().source, &context, false).unwrap();
        assert!(deck.contains(&format!("zcylinder {} ", r)), "{deck}");
        assert!(deck.contains("run ${liftsteps}") && deck.contains("compute ztop powder reduce max v_top"));
        // A cohesive powder: cohesive between particles, not against plate, walls or tube.
        let c = ti64_with(1.0, 1e-4);
        assert!(c.material.cohesion_energy_density > 0.0);
        let mut context = tera::Context::new();
        context.insert("scene", &c);
        let deck = tera::Tera::one_off(Pour.template().source, &context, false).unwrap();
        let k = c.material.cohesion_energy_density;
        assert!(
            deck.contains(&format!("cohesionEnergyDensity peratomtypepair 2 {k} 0.0 0.0 0.0\n")),
            "{deck}"
        );
    }

    #[test]
    fn a_column_too_small_for_a_heap_is_refused_naming_the_key() {
        let small = SceneSettings { supply_factor: 0.2, ..crate::scenes::settings::defaults(&Pour) };
        let e = Pour.check_settings(&small).unwrap_err();
        assert_eq!(e.key, "scene.supply_factor");
        assert!(e.why.contains("400 particles") && e.why.contains("at least 0.25"), "{}", e.why);
        let ok = SceneSettings { supply_factor: 0.25, ..small };
        assert!(Pour.check_settings(&ok).is_ok());
    }
}
