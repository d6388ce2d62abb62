//! The pour's stand-in model (`[run] engine = "stand-in"`): a heap whose angle of repose and
//! packing come from a closed form in sliding and rolling friction and surface energy
//! ([`PourPoint`]), with noise of known SD, so that a calibration can be checked against the
//! parameters that made its targets. Nothing flows: its MFR and v_x are not measured.

use super::heap::SECTORS;
use super::result::Heap;
use crate::outcome::{PointAnswer, RunResult, VX_LAYERS};
use crate::scenes::stand_in::{Noise, StandInPoint};

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
    pub fn model(&self, particles: usize, noise: &mut Noise) -> Heap {
        let angle = self.mean_angle() + ANGLE_SCATTER * noise.normal();
        let packing = self.mean_packing() + PACKING_NOISE * noise.normal();
        // The cone of the particles at this angle and packing: V = π r² h / 3, h = r tan θ.
        let solid = particles as f64 * std::f64::consts::PI * self.diameter.powi(3) / 6.0;
        let tan = angle.to_radians().tan();
        let radius = (3.0 * solid / packing / (std::f64::consts::PI * tan)).cbrt();
        // The sectors about the angle, scattered so that their mean is it and its SE over them
        // is ANGLE_SE (drawn after the angle and packing, which keep their draws).
        let n = SECTORS as f64;
        let z: Vec<f64> = (0..SECTORS).map(|_| noise.normal()).collect();
        let mean = z.iter().sum::<f64>() / n;
        let sd = (z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let sector_angles_deg = z.iter().map(|v| angle + ANGLE_SE * n.sqrt() * (v - mean) / sd).collect();
        Heap {
            angle_deg: angle,
            angle_se_deg: ANGLE_SE,
            sector_angles_deg,
            height_mm: radius * tan,
            base_radius_mm: radius,
            packing,
            particles_in_heap: particles,
            particles_run_out: 0,
        }
    }
}

/// The pour's made-up result: the heap of the point's column, no flow.
pub fn heap(point: &mut StandInPoint) -> RunResult {
    let pour = PourPoint {
        friction: point.get("friction"),
        rolling_friction: point.get("rolling_friction"),
        surface_energy: point.get("surface_energy"),
        diameter: point.diameter_mm(),
    };
    RunResult {
        answer: PointAnswer::none(),
        mfr_flux: f64::NAN,
        own: crate::outcome::OwnResult::new(pour.model(point.scene.particles, &mut point.noise)),
        particles: point.scene.particles,
        vx: vec![None; VX_LAYERS],
        ..RunResult::default()
    }
}
