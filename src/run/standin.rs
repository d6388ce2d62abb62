//! A deterministic stand-in for LIGGGHTS, for demos, end-to-end tests and benchmarks of the
//! sweep logic: `[run] engine = "stand-in"` in a sweep file.
//!
//! It runs no physics. Each point's MFR and v_x profile come from a closed-form model shaped like
//! the real scene's measurements (thesis §4.1–4.5; docs/statistics.md "The stand-in engine"), plus noise drawn from the
//! point's own parameters, so the same point gives the same numbers on every machine:
//!
//! - MFR is 0 while the gap is below [`JAM_RATIO`] diameters, then rises with gap/D towards
//!   ≈ 0.25, falls with friction and with blade speed, and carries a relative noise of
//!   [`MFR_NOISE`] (the seed-to-seed spread measured on LIGGGHTS, BENCHMARKS.md "MFR noise").
//! - v_x rises with height in front of the blade most steeply at gap ≈ 2 D (the thesis's "ideal"
//!   2:1 match), flattens for larger gaps and faster blades ("inefficient"), and fluctuates from
//!   layer to layer for coarse particles and high friction ("unstable").
//!
//! - In the pour layout, a heap: its angle of repose and packing from a closed form in sliding
//!   and rolling friction and surface energy ([`PourPoint`]), with noise of known SD, so that a
//!   calibration can be checked against the parameters that made its targets.
//!
//! Not a substitute for LIGGGHTS in any result that is about powder: its numbers are made up.

use std::collections::BTreeMap;
use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use sha2::{Digest, Sha256};

use crate::error::Result;
use crate::outcome::{RunOutcome, RunResult, RESULT_FORMAT, VX_LAYERS};
use crate::point::deck::Template;
use crate::point::{resolve, PointError, RESULT};
use crate::run::pool::Executor;
use crate::scenes::StandInModel;
use crate::sweep::{Sweep, SweepError};
use crate::sys::atomic::write_json;
use crate::sys::process::CancelToken;

/// The `run.engine` value that selects the stand-in.
pub const NAME: &str = "stand-in";
/// Changes whenever the model changes, so a resume of a stand-in sweep notices.
pub const MODEL_VERSION: u32 = 2;
/// Gap/D below which nothing passes under the blade (the real scene: zero at gap = D, flow at 1.3 D).
pub const JAM_RATIO: f64 = 1.2;
/// Relative standard deviation of a point's MFR noise.
pub const MFR_NOISE: f64 = 0.042;

/// Whether a sweep asks for the stand-in.
pub fn selected(sweep: &Sweep) -> bool {
    sweep.file.run.engine.as_deref().is_some_and(|p| p == Path::new(NAME))
}

/// The stand-in executor.
pub struct StandIn {
    sweep: Sweep,
    /// What it makes up for the sweep's layout.
    model: StandInModel,
}

/// A point for the stand-in: every scene parameter and the hash.
pub struct StandInJob {
    parameters: BTreeMap<String, f64>,
    hash: String,
}

impl StandIn {
    /// The stand-in for `sweep`, refusing what LIGGGHTS's executor refuses before it runs: a
    /// template that does not load. (Each point's bounds are checked as it is prepared.)
    pub fn new(sweep: Sweep) -> Result<StandIn> {
        let layout = crate::scenes::of(&sweep.file.scene).map_err(PointError::Layout)?;
        if let Some(path) = sweep.template_path() {
            Template::load(Some(&path), layout).map_err(|e| SweepError::Key {
                path: sweep.path.clone(),
                key: "scene.template".into(),
                why: e.to_string(),
            })?;
        }
        Ok(StandIn { model: layout.stand_in(), sweep })
    }
}

impl Executor for StandIn {
    type Job = StandInJob;

    fn identity(&self) -> serde_json::Value {
        serde_json::json!({ "engine": NAME, "model_version": MODEL_VERSION })
    }

    fn prepare_seeded(&self, swept: &[f64], seed: Option<u64>) -> Result<StandInJob> {
        let parameters = resolve(&self.sweep, swept);
        // The scene's bounds and unit slips, as a LIGGGHTS point is refused.
        crate::scenes::build(&parameters, &self.sweep.file.scene)
            .map_err(|source| PointError::Scene { path: self.sweep.path.clone(), source })?;
        let mut h = Sha256::new();
        h.update(format!("{NAME} {MODEL_VERSION}\n"));
        for (k, v) in &parameters {
            h.update(format!("{k}={:016x}\n", v.to_bits()));
        }
        // A repeat with its own seed draws its own noise.
        if let Some(seed) = seed {
            h.update(format!("seed={seed}\n"));
        }
        let hash = h.finalize().iter().map(|b| format!("{b:02x}")).collect();
        Ok(StandInJob { parameters, hash })
    }

    fn hash<'a>(&self, job: &'a StandInJob) -> &'a str {
        &job.hash
    }

    fn execute(&self, job: &StandInJob, run_dir: &Path, _cancel: &CancelToken) -> RunOutcome {
        let p = |k: &str| job.parameters.get(k).copied().unwrap_or(f64::NAN);
        if let StandInModel::Heap { particles } = self.model {
            let pour = PourPoint {
                friction: p("friction"),
                rolling_friction: p("rolling_friction"),
                surface_energy: p("surface_energy"),
                diameter: p("diameter"),
            };
            let r = RunResult {
                hash: job.hash.clone(),
                parameters: job.parameters.clone(),
                mfr: f64::NAN,
                mfr_flux: f64::NAN,
                heap: Some(pour.model(particles, &mut Noise::new(&job.hash))),
                vx: vec![None; VX_LAYERS],
                engine_version: format!("{NAME} {MODEL_VERSION}"),
                warnings: vec![format!("{NAME}: a made-up model, not LIGGGHTS")],
                ..RunResult::default()
            };
            return write_result(job, run_dir, r);
        }
        let point = Point {
            friction: p("friction"),
            diameter: p("diameter"),
            gap: p("gap"),
            blade_speed: p("blade_speed"),
        };
        let mut noise = Noise::new(&job.hash);
        let (mfr, vx) = point.model(&mut noise);
        let r = RunResult {
            hash: job.hash.clone(),
            parameters: job.parameters.clone(),
            mfr,
            mfr_flux: mfr,
            // The model's own noise: what a seed-to-seed repeat would scatter by.
            mfr_se: Some(point.mean_mfr() * MFR_NOISE),
            mfr_windows: vec![mfr; 4],
            vx: vx.into_iter().map(Some).collect(),
            engine_version: format!("{NAME} {MODEL_VERSION}"),
            warnings: vec![format!("{NAME}: a made-up model, not LIGGGHTS")],
            warm_start: None,
            mfr_se_target: None,
            ..RunResult::default()
        };
        write_result(job, run_dir, r)
    }
}

fn write_result(job: &StandInJob, run_dir: &Path, r: RunResult) -> RunOutcome {
    match write_json(&run_dir.join(RESULT), &r) {
        Ok(()) => RunOutcome::Done(r),
        Err(e) => RunOutcome::Failed(crate::outcome::RunFailure {
            format: RESULT_FORMAT,
            hash: job.hash.clone(),
            class: crate::outcome::FailureClass::CouldNotStart,
            reason: format!("cannot write {}: {e}", run_dir.join(RESULT).display()),
            log_tail: String::new(),
            wall_time: 0.0,
            measured: None,
        }),
    }
}

/// The parameters the model reads (sweep units: mm, m/s).
#[derive(Debug, Clone, Copy)]
pub struct Point {
    pub friction: f64,
    pub diameter: f64,
    pub gap: f64,
    pub blade_speed: f64,
}

impl Point {
    /// The noiseless MFR.
    pub fn mean_mfr(&self) -> f64 {
        let g = self.gap / self.diameter;
        if g <= JAM_RATIO {
            return 0.0;
        }
        // Saturating rise with the gap (0.07 at 1.67 D, 0.23 at 5 D as measured), about −25 %
        // over friction 0.1 → 0.3 and −20 % over blade speed 1.2 → 1.6 m/s.
        let rise = 0.25 * (1.0 - (-(g - JAM_RATIO) / 1.5).exp());
        let friction = (1.0 - 1.2 * (self.friction - 0.2)).max(0.2);
        let speed = (1.4 / self.blade_speed).powf(0.8);
        rise * friction * speed
    }

    /// MFR and the v_x profile (m/s, layers k = 1..12 at z = gap + k·D/2).
    pub fn model(&self, noise: &mut Noise) -> (f64, Vec<f64>) {
        let mfr = (self.mean_mfr() * (1.0 + MFR_NOISE * noise.normal())).max(0.0);
        let g = self.gap / self.diameter;
        // Rise of v_x over the twelve layers, as a fraction of the blade speed: largest at the
        // 2:1 gap match, smaller for wide gaps and fast blades.
        // A jammed gap passes nothing: the whole pile rides with the blade (uniform v_x).
        let matched = if g <= JAM_RATIO { 0.0 } else { 0.25 * (-((g - 2.0) / 1.2).powi(2)).exp() };
        let rise = (matched + 0.01) * (1.4 / self.blade_speed).powi(2);
        // Layer-to-layer fluctuation: coarse particles and high friction.
        let rough = 0.12 * ((self.diameter - 2.0) / 1.0).clamp(0.0, 1.0) * (self.friction / 0.2) + 0.003;
        let vx = (0..VX_LAYERS)
            .map(|k| {
                let depth = 1.0 - k as f64 / (VX_LAYERS - 1) as f64;
                let u = 0.97 - rise * depth.powf(1.5) + rough * noise.normal();
                u * self.blade_speed
            })
            .collect();
        (mfr, vx)
    }
}

/// The pour's parameters the heap model reads (sweep units: mm, J/m²).
#[derive(Debug, Clone, Copy)]
pub struct PourPoint {
    pub friction: f64,
    pub rolling_friction: f64,
    pub surface_energy: f64,
    pub diameter: f64,
}

/// SD of the stand-in heap's angle about its mean between seeds, degrees, and of its packing.
pub const ANGLE_SCATTER: f64 = 1.0;
pub const PACKING_NOISE: f64 = 0.003;
/// The SE of the angle a stand-in heap reports (as the real pour's SE over its sectors): half
/// the scatter between seeds, as a 316L pour of 1,000 particles reported 2.0° against 3.9°
/// between seeds (docs/study/calibration.md).
pub const ANGLE_SE: f64 = 0.5;

impl PourPoint {
    /// The surface energy at which cohesion has added half its steepening: scales with the
    /// weight of a grain over its contact area, so with D² (0.05 J/m² at D = 2 mm).
    fn cohesion_half(&self) -> f64 {
        0.05 * (self.diameter / 2.0).powi(2)
    }

    fn cohesion(&self) -> f64 {
        let g = self.surface_energy.max(0.0);
        g / (g + self.cohesion_half())
    }

    /// The noiseless angle of repose, degrees: 10° for frictionless spheres, rising with the
    /// product of sliding and rolling friction (each saturating, so that one angle is met along
    /// a ridge of pairs) and with cohesion. The shape of the pour's measurements (steeper with
    /// either friction, by less at larger values: docs/study/pour), not their numbers.
    pub fn mean_angle(&self) -> f64 {
        let rolling = (self.rolling_friction / 0.15).tanh();
        let sliding = (self.friction / 0.2).tanh();
        10.0 + 30.0 * rolling * sliding + 10.0 * self.cohesion()
    }

    /// The noiseless packing of the heap: looser with friction, more with sliding than rolling,
    /// and with cohesion.
    pub fn mean_packing(&self) -> f64 {
        0.64 - 0.1 * self.friction - 0.05 * self.rolling_friction - 0.05 * self.cohesion()
    }

    /// A heap of `particles` spheres: the angle and packing with their noise ([`ANGLE_SCATTER`],
    /// [`PACKING_NOISE`]), reporting [`ANGLE_SE`] as its angle's SE.
    pub fn model(&self, particles: usize, noise: &mut Noise) -> crate::outcome::heap::Heap {
        let angle = self.mean_angle() + ANGLE_SCATTER * noise.normal();
        let packing = self.mean_packing() + PACKING_NOISE * noise.normal();
        // The cone of the particles at this angle and packing: V = π r² h / 3, h = r tan θ.
        let solid = particles as f64 * std::f64::consts::PI * self.diameter.powi(3) / 6.0;
        let tan = angle.to_radians().tan();
        let radius = (3.0 * solid / packing / (std::f64::consts::PI * tan)).cbrt();
        crate::outcome::heap::Heap {
            angle_deg: angle,
            angle_se_deg: ANGLE_SE,
            sector_angles_deg: Vec::new(),
            height_mm: radius * tan,
            base_radius_mm: radius,
            packing,
            particles_in_heap: particles,
            particles_run_out: 0,
        }
    }
}

/// Normal deviates from a point's hash: deterministic per point (ChaCha8 seeded with the
/// hash's SHA-256).
pub struct Noise {
    rng: ChaCha8Rng,
}

impl Noise {
    pub fn new(hash: &str) -> Noise {
        Noise { rng: ChaCha8Rng::from_seed(Sha256::digest(hash.as_bytes()).into()) }
    }

    /// A standard normal deviate.
    pub fn normal(&mut self) -> f64 {
        self.rng.sample(StandardNormal)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(friction: f64, diameter: f64, gap: f64, blade_speed: f64) -> Point {
        Point { friction, diameter, gap, blade_speed }
    }

    #[test]
    fn mfr_is_zero_below_the_jam_ratio_and_rises_with_the_gap() {
        assert_eq!(pt(0.2, 3.0, 3.5, 1.4).mean_mfr(), 0.0, "gap 1.17 D");
        let m: Vec<f64> = [1.5, 2.0, 3.0, 5.0].iter().map(|g| pt(0.2, 1.0, *g, 1.4).mean_mfr()).collect();
        assert!(m.windows(2).all(|w| w[1] > w[0]), "{m:?}");
        // The real scene's corners (thesis layout, measured when the stand-in was made): 0.093 at D 3, gap 5; 0.219 at D 1, gap 5 (μ 0.3, v 1.6).
        let corner = pt(0.3, 3.0, 5.0, 1.6).mean_mfr();
        assert!((0.04..0.12).contains(&corner), "{corner}");
        let corner = pt(0.3, 1.0, 5.0, 1.6).mean_mfr();
        assert!((0.15..0.26).contains(&corner), "{corner}");
    }

    #[test]
    fn mfr_falls_with_friction_and_blade_speed() {
        assert!(pt(0.3, 1.0, 3.0, 1.4).mean_mfr() < pt(0.1, 1.0, 3.0, 1.4).mean_mfr());
        assert!(pt(0.2, 1.0, 3.0, 1.6).mean_mfr() < pt(0.2, 1.0, 3.0, 1.2).mean_mfr());
    }

    #[test]
    fn noise_is_deterministic_per_point_and_of_the_measured_size() {
        let p = pt(0.2, 1.0, 3.0, 1.4);
        let a = p.model(&mut Noise::new("abc"));
        assert_eq!(a, p.model(&mut Noise::new("abc")));
        let rel: Vec<f64> =
            (0..2000).map(|i| p.model(&mut Noise::new(&format!("h{i}"))).0 / p.mean_mfr() - 1.0).collect();
        let m = crate::analysis::stats::moments(&rel);
        assert!(m.mean.unwrap().abs() < 0.005, "{m:?}");
        assert!((m.std.unwrap() - MFR_NOISE).abs() < 0.004, "{m:?}");
    }
}
