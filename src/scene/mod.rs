//! The blade-spreading scene: from one design point to every number the deck needs.
//!
//! The physics lives here, typed and unit-tested; the template only lays the numbers out. All
//! lengths in this struct are metres, times seconds, moduli pascals (the catalogue's mm and MPa
//! are converted once, in [`Scene::new`]).
//!
//! Geometry (DESIGN §5): x is the blade's travel, z is up, y is across the blade and periodic
//! (the domain depth is the blade width w). A pile is inserted in front of the blade, settles on
//! the plate z = 0, and the blade — a box whose tip is at z = gap — then pushes it over the bare
//! plate in +x, leaving a layer behind. Walls at both x ends keep every particle in the box, so
//! any lost atom is an instability, never an outlet.
//!
//! The run, in steps: settle → approach (the blade crosses the pile and the heap develops) →
//! measurement window (4 sub-windows, a dump snapshot at each boundary) → tail (the last strip
//! is deposited and comes to rest; one last snapshot).

pub mod mesh;
pub mod params;
pub mod psd;

use std::collections::BTreeMap;

use serde::Serialize;

use crate::sweep::SceneSettings;
use psd::SizeDistribution;

/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.81;
/// Number of equal sub-windows of the measurement window (steadiness check, dump cadence).
pub const SUB_WINDOWS: usize = 4;
/// Volume fraction of the random insertion packing (insert/pack reaches it quickly).
const INSERT_FRACTION: f64 = 0.3;
/// Packing fraction assumed for a settled pile and an upper bound for a spread layer
/// (random close packing ≈ 0.64; MFR cannot exceed it).
const LAYER_FRACTION_MAX: f64 = 0.6;
/// Angle of repose used to size the heap the blade must still carry at the end, degrees.
const REPOSE_DEG: f64 = 30.0;
/// Thesis fidelity: the fixed timestep of the thesis runs, s (Appendix A: 1e-5 s per step).
pub const THESIS_TIMESTEP: f64 = 1e-5;
/// Thesis v_x band: ±1 mm (Appendix A, `depth = 0.001`).
pub const THESIS_BAND: f64 = 1e-3;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SceneError {
    #[error("parameter `{name}` = {value}: {why}")]
    Invalid {
        name: String,
        value: f64,
        why: String,
    },
}

/// One particle template of the deck (one per size class).
#[derive(Debug, Clone, Serialize)]
pub struct ParticleTemplate {
    pub id: String,
    pub radius: f64,
    pub fraction: f64,
    pub seed: u64,
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
    // Particles.
    pub templates: Vec<ParticleTemplate>,
    pub distribution_seed: u64,
    pub insert_seed: u64,
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
    // Pile insertion region.
    pub pile_x0: f64,
    pub pile_x1: f64,
    pub pile_z1: f64,
    // Time.
    pub rayleigh_time: f64,
    pub timestep: f64,
    pub skin: f64,
    pub settle_steps: u64,
    /// Steps from the blade's start to the window's start.
    pub approach_steps: u64,
    /// Steps between snapshots; the window is SUB_WINDOWS of them.
    pub dump_every: u64,
    /// Steps of the measurement window: SUB_WINDOWS × dump_every.
    pub window_length_steps: u64,
    pub tail_steps: u64,
    pub thermo_every: u64,
    // Measurement.
    /// Half-height of a v_x layer, m.
    pub vx_band: f64,
    /// Length of the v_x region in front of the blade (6 D, thesis Appendix A), m.
    pub vx_length: f64,
    /// Kinetic energy above which the run is unstable, J.
    pub ke_limit: f64,
}

impl Scene {
    /// Build the scene from every catalogue parameter (in catalogue units) and the settings.
    pub fn new(
        values: &BTreeMap<String, f64>,
        settings: &SceneSettings,
    ) -> Result<Scene, SceneError> {
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
        let youngs = get("youngs_modulus") * 1e6;
        let poisson = get("poisson");

        let rayleigh_time = rayleigh_time(d_min / 2.0, density, youngs, poisson);
        let timestep = if settings.fidelity == "thesis" {
            THESIS_TIMESTEP
        } else {
            settings.rayleigh_fraction * rayleigh_time
        };
        if timestep > 0.5 * rayleigh_time {
            return Err(SceneError::Invalid {
                name: "timestep".into(),
                value: timestep,
                why: format!("above half the Rayleigh time {rayleigh_time:.3e} s: unstable"),
            });
        }

        // Geometry in units of the mean diameter, so the particle count barely changes with D.
        let depth = settings.depth_diameters * d;
        let blade_thickness = d;
        let blade_x0 = d;
        let front0 = blade_x0 + blade_thickness;
        let pile_x0 = front0 + 0.5 * d;
        // The heap the blade must still carry at the end: tall enough to fill the 12 v_x layers
        // (z up to gap + 6 D), a triangle at the angle of repose.
        let heap_height = gap + 6.0 * d;
        let heap_area = heap_height.powi(2) / (2.0 * REPOSE_DEG.to_radians().tan());
        let develop = 5.0 * d;
        let window = 20.0 * d;
        let tail = 3.0 * d;
        // Travel = pile length (+ its slump) + develop + window + tail; the pile length depends on
        // the particle count, which depends on the travel: iterate to the fixed point.
        let mut pile_len = 10.0 * d;
        let mut particles = 0usize;
        for _ in 0..50 {
            let travel = 1.5 * pile_len + develop + window + tail;
            let area = LAYER_FRACTION_MAX * (gap * travel + heap_area);
            particles = (area * depth / psd.mean_volume()).ceil() as usize;
            // Square insertion block at the insertion packing fraction.
            let new_len = (particles as f64 * psd.mean_volume() / (INSERT_FRACTION * depth)).sqrt();
            if (new_len - pile_len).abs() < 1e-9 {
                break;
            }
            pile_len = new_len;
        }
        let pile_x1 = pile_x0 + pile_len;
        let pile_z1 = pile_len;
        // The settled pile slumps forward by about half its height; start measuring `develop`
        // after that, with a heap fully formed in front of the blade.
        let window_start_front = pile_x1 + 0.5 * pile_len + develop;
        let approach_time = (window_start_front - front0) / speed;
        let window_time = window / speed;
        let tail_time = tail / speed;
        // Settling: a free fall from the top of the insertion block, then as long again for
        // the pile to come to rest.
        let settle_time = 2.0 * (2.0 * pile_z1 / GRAVITY).sqrt() + 0.02;

        let dump_every = ((window_time / SUB_WINDOWS as f64) / timestep)
            .ceil()
            .max(1.0) as u64;
        let round_up = |t: f64| ((t / timestep).ceil() as u64).div_ceil(dump_every) * dump_every;
        let settle_steps = round_up(settle_time);
        let approach_steps = round_up(approach_time);
        let tail_steps = round_up(tail_time);
        let total_travel = speed
            * timestep
            * (approach_steps + SUB_WINDOWS as u64 * dump_every + tail_steps) as f64;
        // Room ahead for the heap at the end, plus a margin.
        let x_hi = front0 + total_travel + 3.0 * heap_height + 5.0 * d;
        let blade_top = pile_z1 + 2.0 * d;
        let z_hi = blade_top + 2.0 * d;
        let total_steps =
            settle_steps + approach_steps + SUB_WINDOWS as u64 * dump_every + tail_steps;

        let profile_diameter = if psd.is_mono() { d } else { psd.quantile(0.85) };
        let vx_band = if settings.thesis_band {
            THESIS_BAND
        } else {
            settings.vx_band_diameters * profile_diameter
        };
        // Unstable: kinetic energy of the whole pile moving at 10× the fastest speed the scene
        // can give it (the blade, or a free fall from the top of the box).
        let mass = particles as f64 * density * psd.mean_volume();
        let v_ref = speed.max((2.0 * GRAVITY * z_hi).sqrt());
        let ke_limit = 0.5 * mass * (10.0 * v_ref).powi(2);

        let seeds = Seeds::new(settings.seed);
        let templates = psd
            .classes
            .iter()
            .enumerate()
            .map(|(i, c)| ParticleTemplate {
                id: format!("pts{}", i + 1),
                radius: c.diameter / 2.0,
                fraction: c.fraction,
                seed: seeds.get(3 + i),
            })
            .collect();

        Ok(Scene {
            density,
            youngs_modulus: youngs,
            poisson,
            restitution: get("restitution"),
            friction: get("friction"),
            rolling_friction: get("rolling_friction"),
            templates,
            distribution_seed: seeds.get(1),
            insert_seed: seeds.get(2),
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
            pile_x0,
            pile_x1,
            pile_z1,
            rayleigh_time,
            timestep,
            // Half a smallest radius: particles move far less than that between list builds.
            skin: 0.25 * d_min,
            settle_steps,
            approach_steps,
            dump_every,
            window_length_steps: SUB_WINDOWS as u64 * dump_every,
            tail_steps,
            thermo_every: (total_steps / 40).max(1),
            vx_band,
            vx_length: 6.0 * profile_diameter,
            ke_limit,
        })
    }

    /// Timestep at which the blade starts moving.
    pub fn blade_start_step(&self) -> u64 {
        self.settle_steps
    }

    /// Timestep of the window's start (t1) and end (t2).
    pub fn window_steps(&self) -> (u64, u64) {
        let t1 = self.settle_steps + self.approach_steps;
        (t1, t1 + self.window_length_steps)
    }

    pub fn total_steps(&self) -> u64 {
        self.window_steps().1 + self.tail_steps
    }

    /// x of the blade's rear face at timestep `step`.
    pub fn blade_rear_at(&self, step: u64) -> f64 {
        let moving = step.saturating_sub(self.blade_start_step()) as f64 * self.timestep;
        self.blade_x0 + self.blade_speed * moving
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

/// LIGGGHTS random seeds must be primes above 10,000; derive distinct ones from the scene seed.
struct Seeds(u64);

impl Seeds {
    fn new(seed: u64) -> Self {
        Seeds(seed)
    }

    /// The `k`-th seed: the first prime at or above 10,007 + (seed·131 + k·7,919) mod 10^7.
    fn get(&self, k: usize) -> u64 {
        let mut n = 10_007 + (self.0.wrapping_mul(131).wrapping_add(k as u64 * 7_919)) % 10_000_000;
        while !is_prime(n) {
            n += 1;
        }
        n
    }
}

fn is_prime(n: u64) -> bool {
    n >= 2 && (2..).take_while(|d| d * d <= n).all(|d| n % d != 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(pairs: &[(&str, f64)]) -> Scene {
        let values = pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        Scene::new(&values, &SceneSettings::default()).unwrap()
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
        assert!((s.timestep - 0.2 * s.rayleigh_time).abs() < 1e-18);
        let mut settings = SceneSettings::default();
        settings.fidelity = "thesis".into();
        let t = Scene::new(&BTreeMap::new(), &settings).unwrap();
        assert_eq!(t.timestep, THESIS_TIMESTEP);
    }

    #[test]
    fn the_window_is_after_the_pile_and_inside_the_box() {
        for (d, gap) in [(1.0, 1.0), (1.0, 5.0), (3.0, 1.0), (3.0, 5.0)] {
            let s = scene(&[("diameter", d), ("gap", gap), ("blade_speed", 1.6)]);
            let (t1, t2) = s.window_steps();
            // Window starts after the blade front has passed the insertion block's far end.
            assert!(s.blade_front_at(t1) > s.pile_x1, "d={d} gap={gap}");
            // Window length is 20 D within one step of rounding.
            let len = s.blade_rear_at(t2) - s.blade_rear_at(t1);
            assert!((len - 20.0 * s.diameter).abs() < 0.1 * s.diameter, "{len}");
            // The blade never leaves the box.
            assert!(s.blade_front_at(s.total_steps()) < s.x_hi);
            assert!(s.blade_top < s.z_hi);
            // All step counts line up with the dump cadence.
            assert_eq!(t1 % s.dump_every, 0);
            assert_eq!(s.total_steps() % s.dump_every, 0);
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
    fn seeds_are_distinct_primes_above_10000() {
        let s = Seeds::new(12345);
        let v: Vec<u64> = (0..8).map(|k| s.get(k)).collect();
        for &p in &v {
            assert!(p > 10_000 && is_prime(p));
        }
        let mut u = v.clone();
        u.dedup();
        assert_eq!(u.len(), v.len());
    }

    #[test]
    fn out_of_domain_values_name_the_parameter() {
        let values = [("restitution".to_string(), 0.0)].into_iter().collect();
        let err = Scene::new(&values, &SceneSettings::default()).unwrap_err();
        assert!(err.to_string().contains("restitution"), "{err}");
    }
}
