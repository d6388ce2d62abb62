//! The scene: from one design point to every number the deck needs.
//!
//! The physics lives here, typed and unit-tested; the template only lays the numbers out. All
//! lengths are metres, times seconds, moduli pascals (the catalogue's mm and MPa are converted
//! once, in [`Base::new`]).
//!
//! The building blocks the layouts share: the parameter catalogue ([`params`]), the `[scene]`
//! settings, the size distribution, the groups of numbers some layouts have (the blade and its
//! window, [`blade`]; the substrate, [`substrate`]; the dose's block, [`pile`]), the blade mesh,
//! the pile file, the passage screen, the plausibility bounds, and [`Scene`], the numbers a deck
//! is rendered from: what every layout has, and the layout's part of its own type ([`own`]).
//! Each layout derives its [`Scene`] from the common [`Base`] ([`crate::scenes`]).

pub mod bed;
pub mod blade;
pub mod cohesion;
pub mod mesh;
pub mod own;
pub mod own_settings;
pub mod params;
pub mod passage;
pub mod pile;
pub mod plausible;
pub mod pockets;
pub mod psd;
pub mod settings;
pub mod substrate;

use std::collections::BTreeMap;

use serde::Serialize;

use crate::outcome::SizeSummary;
use crate::scene::settings::SceneSettings;
use psd::SizeDistribution;

/// Simulated time between the VTK files of `sweep run --vtk`, s.
pub const VTK_EVERY_S: f64 = 0.02;
/// LIGGGHTS's least particle volume by default (`fix particletemplate/sphere`, volume_limit), m³.
pub const ENGINE_VOLUME_LIMIT: f64 = 1e-12;
/// The least region the deck inserts into, shrunk by the largest diameter, m³: LIGGGHTS 3.8
/// refuses a region under 1e-10 m³ (region.cpp, `volume_mc`: an absolute floor in SI, whatever
/// the particles' size), with a margin for its Monte-Carlo estimate of the volume.
pub const MIN_INSERT_VOLUME: f64 = 1.2e-10;
/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.81;
/// Number of equal sub-windows of the measurement window (steadiness check, dump cadence).
pub const SUB_WINDOWS: usize = 4;
/// Snapshot intervals per sub-window. Short intervals let the flux counts tell a particle that
/// passed under the tip from one thrown over the blade (whose flight takes far longer).
pub const SNAPSHOTS_PER_SUB_WINDOW: usize = 2;
/// Packing fraction assumed for a settled pile and an upper bound for a spread layer
/// (random close packing ≈ 0.64; MFR cannot exceed it).
pub const LAYER_FRACTION_MAX: f64 = 0.6;
/// Angle of repose used to size the heap the blade must still carry at the end, degrees.
pub const REPOSE_DEG: f64 = 30.0;
/// Rolling-friction model: EPSD2 (elastic-plastic spring-dashpot without the damper, Ai et al.
/// 2011 model C), which holds a static heap still; CDT's constant torque makes resting spheres
/// jitter.
pub const ROLLING_MODEL: &str = "epsd2";
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

/// A timestep beyond [`MAX_RAYLEIGH_FRACTION`] of the Rayleigh time: the fraction it is.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error(
    "timestep {fraction:.3} × the Rayleigh time is beyond the measured safe bound \
     {MAX_RAYLEIGH_FRACTION} (at 0.6 every seed lost atoms at the harshest corner of the thesis \
     space, BENCHMARKS.md \"Stability edge\"); lower scene.rayleigh_fraction, or pass --force"
)]
pub struct UnsafeTimestep {
    pub fraction: f64,
}

/// Refuse a timestep beyond [`MAX_RAYLEIGH_FRACTION`] of the Rayleigh time, saying why.
pub fn check_rayleigh_fraction(fraction: f64) -> Result<(), UnsafeTimestep> {
    if fraction > MAX_RAYLEIGH_FRACTION * (1.0 + 1e-9) {
        return Err(UnsafeTimestep { fraction });
    }
    Ok(())
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SceneError {
    #[error("parameter `{name}` = {value}: {why}")]
    Invalid { name: String, value: f64, why: String },
    /// Far outside what the scene is built for ([`plausible`]); the message names the slip.
    #[error(transparent)]
    Implausible(#[from] plausible::OutOfBounds),
}

/// The powder's material and contact law as the deck sets them (SI), the same for every layout.
#[derive(Debug, Clone, Serialize)]
pub struct PowderMaterial {
    pub density: f64,
    /// Young's modulus as the deck sets it (the stiffness factor applied, at least LIGGGHTS's
    /// floor), Pa.
    pub youngs_modulus: f64,
    pub poisson: f64,
    pub restitution: f64,
    pub friction: f64,
    pub rolling_friction: f64,
    /// LIGGGHTS rolling-friction model (used when `rolling_friction` > 0).
    pub rolling_model: &'static str,
    /// SJKR cohesion energy density, J/m³ ([`cohesion`]); 0: no cohesion.
    pub cohesion_energy_density: f64,
}

/// Every number the deck and the metrics need for one point: what every layout has, and the
/// layout's own part ([`own`]: its type, of the groups it shares with other layouts and the
/// numbers only it has).
#[derive(Debug, Clone, Serialize)]
pub struct Scene {
    /// The powder's material and contact law; its fields are the deck's names (`density`, …).
    #[serde(flatten)]
    pub material: PowderMaterial,
    /// The layout's name (see [`crate::scenes`]).
    pub layout: String,
    // Particles.
    pub size_classes: Vec<psd::SizeClass>,
    /// The distribution in a few numbers (mean, D10/D50/D90 by volume, span, classes).
    pub sizes: SizeSummary,
    /// Seed of the pile's diameters and jitter.
    pub seed: u64,
    /// The powder's particles: placed at the start, or the most the run inserts.
    pub particles: usize,
    /// Number-mean diameter: the unit of the scene's geometry, m.
    pub diameter: f64,
    // Domain.
    pub x_hi: f64,
    pub depth: f64,
    pub z_hi: f64,
    /// Bottom of the box and height of the plate: 0 on a smooth plate, minus one substrate
    /// diameter under a rough substrate.
    pub z_lo: f64,
    // Time.
    pub rayleigh_time: f64,
    pub timestep: f64,
    pub skin: f64,
    /// Steps between the VTK files of the run (0: none).
    pub vtk_every: u64,
    /// Largest cell of the wall meshes, m.
    pub mesh_cell: f64,
    pub thermo_every: u64,
    /// Kinetic energy above which the run is unstable, J.
    pub ke_limit: f64,
    /// The layout's part, of its own type: its fields beside the ones above in the deck's
    /// context (see [`own`]); the layout reads it back with [`Scene::own`], the levels below
    /// the layouts ask it for the groups they read ([`Scene::blade`], …).
    #[serde(flatten)]
    pub own: own::OwnData,
}

#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct FeedClass {
    pub diameter: f64,
    pub mass_fraction: f64,
    pub seed: u64,
}

/// The particle templates of a layout that inserts its powder as it runs (the conveyor's
/// top-up, the layers' doses), and the least particle volume they accept.
#[derive(Debug, Clone, PartialEq)]
pub struct Feed {
    /// One template per size class: its diameter, its share of the mass (its number fraction
    /// times d³, normalised) and the `i + 2`-th prime seed after the scene's seed.
    pub classes: Vec<FeedClass>,
    /// The least particle volume the templates accept, m³: below ten times the engine's default
    /// ([`ENGINE_VOLUME_LIMIT`], which refuses every sphere below 124 µm), a thousandth of the
    /// smallest sphere's; above it 0, and the deck keeps the engine's default.
    pub volume_limit: f64,
}

impl Feed {
    /// The feed of `psd` for a scene seeded with `seed`.
    pub fn of(psd: &SizeDistribution, seed: u64) -> Feed {
        let total: f64 = psd.classes.iter().map(|c| c.fraction * c.diameter.powi(3)).sum();
        let classes = psd
            .classes
            .iter()
            .enumerate()
            .map(|(i, c)| FeedClass {
                diameter: c.diameter,
                mass_fraction: c.fraction * c.diameter.powi(3) / total,
                seed: prime_seed(seed, i + 2),
            })
            .collect();
        let smallest = std::f64::consts::PI / 6.0 * psd.min_diameter().powi(3);
        let volume_limit = if smallest < 10.0 * ENGINE_VOLUME_LIMIT { 1e-3 * smallest } else { 0.0 };
        Feed { classes, volume_limit }
    }
}

/// The prime seed of stream `n` of a scene seeded with `seed` (LIGGGHTS wants primes above
/// 10,000): the first prime at or after a point drawn by SHA-256 from both, below 2³¹. Distinct
/// seeds give distinct streams (two pairs share a prime only if their draws fall in one gap
/// between primes, about one in 10⁸); neighbouring seeds must not, as repeats run with seed,
/// seed + 1, ….
pub fn prime_seed(seed: u64, n: usize) -> u64 {
    use sha2::{Digest, Sha256};
    const LEAST: u64 = 10_007;
    // Room below 2³¹ for the longest gap between primes there (under 300).
    const SPAN: u64 = (1 << 31) - LEAST - 1_000;
    let digest = Sha256::digest(format!("demsweep prime seed {seed} stream {n}").as_bytes());
    let draw = u64::from_le_bytes(digest[..8].try_into().expect("8 bytes"));
    (LEAST + draw % SPAN..).find(|&k| is_prime_u32(k)).expect("a prime below 2^31")
}

/// Deterministic Miller–Rabin for k < 2³² (bases 2, 7 and 61 suffice there).
fn is_prime_u32(k: u64) -> bool {
    if k < 2 {
        return false;
    }
    for p in [2, 3, 5, 7, 11, 13, 61] {
        if k.is_multiple_of(p) {
            return k == p;
        }
    }
    let (mut d, mut r) = (k - 1, 0);
    while d.is_multiple_of(2) {
        d /= 2;
        r += 1;
    }
    let mul = |a: u64, b: u64| a * b % k; // k < 2³², so a·b < 2⁶⁴
    let pow = |mut b: u64, mut e: u64| {
        let mut acc = 1;
        while e > 0 {
            if e & 1 == 1 {
                acc = mul(acc, b);
            }
            b = mul(b, b);
            e >>= 1;
        }
        acc
    };
    [2u64, 7, 61].iter().all(|&a| {
        let mut x = pow(a % k, d);
        if x == 1 || x == k - 1 {
            return true;
        }
        (1..r).any(|_| {
            x = mul(x, x);
            x == k - 1
        })
    })
}

/// What every layout derives its scene from: the point's material, sizes and timestep, in SI.
#[derive(Debug, Clone)]
pub struct Base {
    pub psd: SizeDistribution,
    /// Number-mean and smallest diameter, m.
    pub d: f64,
    pub d_min: f64,
    pub gap: f64,
    /// Height of the heap in front of the blade above its tip, m.
    pub heap_height: f64,
    /// How far the platform drops between passes (layers layout), m.
    pub layer_thickness: f64,
    pub speed: f64,
    /// A roller's surface speed about its axis over its travel speed (counter-rotation
    /// positive); read only by the layers layout's roller.
    pub roller_speed_ratio: f64,
    pub material: PowderMaterial,
    pub rayleigh_time: f64,
    pub timestep: f64,
}

impl Base {
    /// The common part of every point: every catalogue parameter in its domain, the size
    /// distribution, the material and the timestep (refused beyond the measured stability bound
    /// unless forced).
    pub fn new(values: &BTreeMap<String, f64>, settings: &SceneSettings) -> Result<Base, SceneError> {
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

        let surface_energy = cohesion::scaled_surface_energy(
            get("surface_energy"),
            settings.cohesion_scaling,
            youngs,
            settings.material_youngs_gpa * 1e9,
        );
        let cohesion_energy_density = cohesion::sjkr_energy_density(surface_energy, d, youngs, poisson);

        let rayleigh_time = rayleigh_time(d_min / 2.0, density, youngs, poisson);
        let timestep = if settings.timestep_s > 0.0 {
            settings.timestep_s
        } else {
            settings.rayleigh_fraction * rayleigh_time
        };
        if !settings.force_bounds {
            if let Err(why) = check_rayleigh_fraction(timestep / rayleigh_time) {
                return Err(SceneError::Invalid {
                    name: "timestep".into(),
                    value: timestep,
                    why: why.to_string(),
                });
            }
        }

        Ok(Base {
            psd,
            d,
            d_min,
            gap,
            heap_height: get("heap_height") * mm,
            layer_thickness: get("layer_thickness") * mm,
            speed,
            roller_speed_ratio: get("roller_speed_ratio"),
            material: PowderMaterial {
                density,
                youngs_modulus: youngs,
                poisson,
                restitution: get("restitution"),
                friction: get("friction"),
                rolling_friction: get("rolling_friction"),
                rolling_model: ROLLING_MODEL,
                cohesion_energy_density,
            },
            rayleigh_time,
            timestep,
        })
    }
}

/// What a layout decides of its scene: the powder's count, the box, the meshes' cell, the
/// cadence of the log and the unstable bound, and its own part. The rest of a scene is the
/// point's and the settings' alike for every layout ([`Scene::new`]).
pub struct LayoutScene {
    pub particles: usize,
    pub x_hi: f64,
    pub depth: f64,
    pub z_hi: f64,
    pub z_lo: f64,
    pub mesh_cell: f64,
    pub thermo_every: u64,
    pub ke_limit: f64,
    pub own: own::OwnData,
}

impl Scene {
    /// The scene of the point `base` under `settings`, laid out as the layout says (`laid`):
    /// the material, the sizes, the seed, the time, the neighbour skin (a share of the smallest
    /// diameter) and the VTK interval ([`VTK_EVERY_S`], when asked for) are the same for every
    /// layout.
    pub fn new(base: &Base, settings: &SceneSettings, laid: LayoutScene) -> Scene {
        let LayoutScene { particles, x_hi, depth, z_hi, z_lo, mesh_cell, thermo_every, ke_limit, own } = laid;
        let timestep = base.timestep;
        Scene {
            material: base.material.clone(),
            layout: settings.layout.clone(),
            size_classes: base.psd.classes.clone(),
            sizes: base.psd.summary(),
            seed: settings.seed,
            particles,
            diameter: base.d,
            x_hi,
            depth,
            z_hi,
            z_lo,
            rayleigh_time: base.rayleigh_time,
            timestep,
            // A quarter of the smallest diameter (default): particles move far less than that
            // between list builds (`neigh_modify delay 0` rebuilds as soon as one has).
            skin: settings.skin_diameters * base.d_min,
            vtk_every: if settings.vtk { (VTK_EVERY_S / timestep).round().max(1.0) as u64 } else { 0 },
            mesh_cell,
            thermo_every,
            ke_limit,
            own,
        }
    }

    /// The layout's part, if it is of the type `T` the layout keeps there.
    pub fn own<T: std::any::Any>(&self) -> Option<&T> {
        self.own.get()
    }

    /// The same, to change.
    pub fn own_mut<T: std::any::Any>(&mut self) -> Option<&mut T> {
        self.own.get_mut()
    }

    /// Keep `data` as the layout's part.
    pub fn set_own<T: own::LayoutData>(&mut self, data: T) {
        self.own = own::OwnData::new(data);
    }

    /// The blade, of a layout that moves one.
    pub fn blade(&self) -> Option<&blade::Blade> {
        self.own.data().blade()
    }

    /// The window its flow is measured over, of a layout that measures one.
    pub fn window(&self) -> Option<&blade::Window> {
        self.own.data().window()
    }

    /// The substrate, of a layout that spreads onto one.
    pub fn substrate(&self) -> Option<&substrate::Substrate> {
        self.own.data().substrate()
    }

    /// The block the dose starts as, of a layout whose dose starts as one.
    pub fn pile(&self) -> Option<&pile::PileBlock> {
        self.own.data().pile()
    }

    /// The steps a run takes after its settle, at most ([`own::LayoutData::steps`]).
    pub fn run_steps(&self) -> u64 {
        self.own.data().steps()
    }

    /// The spread layer's thickness under `blade`: the gap plus the pockets' open depth, m.
    pub fn layer_thickness(&self, blade: &blade::Blade) -> f64 {
        blade.gap + self.open_depth()
    }

    /// Open depth of the substrate's pockets below its tops that the powder's smallest sphere
    /// reaches, m ([`pockets`]); 0 on a smooth plate. Computed when a run is measured, not
    /// when a point is planned.
    pub fn open_depth(&self) -> f64 {
        self.substrate().map_or(0.0, |s| s.open_depth(self.min_diameter()))
    }

    /// The deposit's packing over the layer's thickness under `blade`, for an MFR (mass over
    /// ρ·w·gap·v).
    pub fn layer_packing(&self, blade: &blade::Blade, mfr: f64) -> f64 {
        mfr * blade.gap / self.layer_thickness(blade)
    }

    /// The sizes for result.json: `None` for one size.
    pub fn sizes_of_a_distribution(&self) -> Option<SizeSummary> {
        (self.size_classes.len() > 1).then(|| self.sizes.clone())
    }

    /// Atoms in the box: the powder and the substrate.
    pub fn atoms(&self) -> usize {
        self.particles + self.substrate().map_or(0, |s| s.substrate_particles)
    }

    /// Centre height of v_x layer k = 1..12 (thesis Appendix A); `None` in a scene with no
    /// blade's window to measure v_x in front of.
    pub fn layer_height(&self, k: usize) -> Option<f64> {
        let (blade, window) = self.blade().zip(self.window())?;
        Some(window.layer_height(blade.gap, k))
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
    use super::psd::{SizeClass, SizeDistribution};
    use super::*;

    #[test]
    fn neighbouring_seeds_and_streams_get_distinct_prime_seeds() {
        // The old rule (the n-th prime after 10,007 + seed) gave seeds 12345–12354 one prime.
        let mut seen = std::collections::HashSet::new();
        for seed in (12_345..12_445).chain(0..100) {
            for n in 0..8 {
                let p = prime_seed(seed, n);
                assert!((10_007..1 << 31).contains(&p), "{p}");
                assert!(seen.insert(p), "seed {seed} stream {n}: {p} again");
            }
        }
        assert_eq!(prime_seed(7, 3), prime_seed(7, 3));
    }

    #[test]
    fn the_primality_test_agrees_with_trial_division() {
        let trial = |k: u64| k > 1 && (2..).take_while(|d| d * d <= k).all(|d| !k.is_multiple_of(d));
        for k in (0..20_000).chain(2_147_383_000..2_147_483_648) {
            assert_eq!(is_prime_u32(k), trial(k), "{k}");
        }
        // Strong pseudoprimes to single bases (2047 to base 2; 3215031751 is past 2³²'s bases).
        assert!(!is_prime_u32(2047) && !is_prime_u32(1_373_653) && !is_prime_u32(25_326_001));
    }

    fn psd(classes: &[(f64, f64)]) -> SizeDistribution {
        SizeDistribution {
            classes: classes.iter().map(|&(diameter, fraction)| SizeClass { diameter, fraction }).collect(),
            fit_residual: None,
        }
    }

    #[test]
    fn a_feed_weighs_its_classes_by_mass_and_lowers_the_least_volume_only_for_fine_powder() {
        // Half the particles 20 µm, half 40 µm: the coarse class holds 8/9 of the mass.
        let fine = Feed::of(&psd(&[(20e-6, 0.5), (40e-6, 0.5)]), 7);
        let shares: Vec<f64> = fine.classes.iter().map(|c| c.mass_fraction).collect();
        assert!((shares[0] - 1.0 / 9.0).abs() < 1e-12 && (shares[1] - 8.0 / 9.0).abs() < 1e-12, "{shares:?}");
        assert_eq!(
            fine.classes.iter().map(|c| c.seed).collect::<Vec<_>>(),
            [prime_seed(7, 2), prime_seed(7, 3)]
        );
        // A 20 µm sphere is far below the engine's least volume: a thousandth of it is the limit.
        let smallest = std::f64::consts::PI / 6.0 * 20e-6_f64.powi(3);
        assert_eq!(fine.volume_limit, 1e-3 * smallest);
        // 2 mm spheres keep the engine's default.
        assert_eq!(Feed::of(&psd(&[(2e-3, 1.0)]), 7).volume_limit, 0.0);
    }
}
