//! The answers of one run: MFR, its cross-check, its steadiness, and the v_x profile.
//!
//! Definitions (docs/scene.md "Metrics", thesis Eq. 15–17 and Appendix A), with t1, t2 the window's ends and
//! x_r(t), x_f(t) the blade's rear and front faces:
//! - MFR = Σ m_i / (ρ · w · h · v · Δt): the mass that passed under the blade during the window
//!   (thesis Eq. 17, "mass of flow under blade"), over the mass of a full flow through the gap
//!   (Eq. 16). v·Δt is the length of the strip the tip swept, so MFR is the packing fraction of
//!   the layer deposited on that strip times its height over h (≤ ~0.64, random close packing).
//!   The mass is counted by particle id between consecutive snapshots: a particle that was at or
//!   ahead of the rear face and is behind it and below the tip (z < h) at the next snapshot was
//!   deposited (one going back the other way is subtracted). Counting crossings, rather than
//!   the particles lying on the strip at the end, matters: without rolling friction the
//!   deposited spheres keep rolling, and a particle thrown over the blade lands on the strip
//!   long after it flew (its flight takes far longer than a snapshot interval).
//! - Flux MFR: the same count across the blade's *front* face. Both planes carry the same mass
//!   in a steady flow; they differ by the change of what sits under the blade.
//! - Steadiness: a test of the window's halves. Under a steady flow the masses deposited over the
//!   two halves (equal travel) differ only by counting noise: for crossings of masses m_i, the
//!   difference has variance Σ m_i² (compound Poisson; for one size, n·m²). The flow is
//!   unsteady when the two-sided p-value of z = (M₁ − M₂)/√Σm_i² is below [`STEADY_ALPHA`]: a
//!   1 % false-alarm rate on a steady Poisson flow.
//! - v_x: in front of the blade, x_f ≤ x ≤ x_f + 6D, layer k = 1..12 centred at
//!   z_k = h + k·D/2 with half-height b; the mean v_x of the particles in the band, pooled over
//!   the window's snapshots. An empty layer is `None`.

use std::collections::HashMap;

use crate::measure::frame::Frame;
use crate::outcome::VX_LAYERS;
use crate::scene::blade::{Blade, Window};
use crate::scene::Scene;

/// False-alarm rate of the steadiness test: the p-value below which the flow is unsteady.
pub const STEADY_ALPHA: f64 = 0.01;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MetricsError {
    #[error("the dump has no snapshot at step {0} (window start, end, or final)")]
    MissingSnapshot(u64),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Metrics {
    pub mfr: f64,
    pub mfr_flux: f64,
    pub mfr_windows: Vec<f64>,
    /// Particles that crossed the rear face (gross count, both directions).
    pub mfr_particles: usize,
    pub steady: bool,
    /// Two-sided p-value of the steadiness test.
    pub steady_p: f64,
    pub vx: Vec<Option<f64>>,
    pub particles: usize,
    /// The spread layer's quality at the window's end ([`crate::measure::layer`]); `None` when
    /// the dump has no `y` or the strip is too short.
    pub layer: Option<crate::outcome::layer::Layer>,
}

/// Compute the metrics of a run from its snapshots (any order; steps as the scene planned).
pub fn compute(
    scene: &Scene,
    blade: &Blade,
    window: &Window,
    frames: &[Frame],
) -> Result<Metrics, MetricsError> {
    let (t1, t2) = window.steps();
    let dump_every = window.dump_every;
    let steps: Vec<u64> = (t1..=t2).step_by(dump_every as usize).collect();
    let at = |step: u64| blade.rear_at(scene.timestep, step);
    let frames_of_window: Vec<&Frame> = steps
        .iter()
        .map(|&step| frames.iter().find(|f| f.step == step).ok_or(MetricsError::MissingSnapshot(step)))
        .collect::<Result<_, _>>()?;

    // Crossings of the rear (deposit) and front (cross-check) faces per snapshot interval.
    let rear: Vec<Crossing> =
        frames_of_window.windows(2).map(|p| crossing(scene, blade, p[0], p[1], Face::Rear)).collect();
    let front: Vec<Crossing> =
        frames_of_window.windows(2).map(|p| crossing(scene, blade, p[0], p[1], Face::Front)).collect();
    // Ideal mass per metre of strip: ρ · w · h (thesis Eq. 16 with v·Δt the strip length).
    let ideal_per_length = scene.material.density * scene.depth * blade.gap;
    let mfr_of = |c: &[Crossing], a: u64, b: u64| -> f64 {
        c.iter().map(|x| x.mass).sum::<f64>() / (ideal_per_length * (at(b) - at(a)))
    };
    let per = crate::scene::SNAPSHOTS_PER_SUB_WINDOW;
    let sub: Vec<f64> = rear
        .chunks(per)
        .zip(steps.chunks(per))
        .map(|(c, s)| mfr_of(c, s[0], s[0] + per as u64 * dump_every))
        .collect();
    let half = rear.len() / 2;
    let steady_p = halves_p_value(&rear[..half], &rear[half..]);

    Ok(Metrics {
        mfr: mfr_of(&rear, t1, t2),
        mfr_flux: mfr_of(&front, t1, t2),
        steady: steady_p >= STEADY_ALPHA,
        steady_p,
        mfr_windows: sub,
        mfr_particles: rear.iter().map(|c| c.count).sum(),
        vx: vx_profile(scene, blade, window, frames_of_window.iter().copied()),
        particles: frames_of_window.last().map(|f| f.len()).unwrap_or(0),
        layer: frames_of_window
            .last()
            .and_then(|f| crate::measure::layer::measure(scene, blade.gap, f, at(t1), at(t2))),
    })
}

#[derive(Clone, Copy)]
enum Face {
    Rear,
    Front,
}

/// Net mass (and gross count) that crossed a blade face from ahead to behind, below the tip.
struct Crossing {
    mass: f64,
    /// Σ m² over the crossings, both directions: the counting variance of `mass`.
    mass_sq: f64,
    count: usize,
}

fn crossing(scene: &Scene, blade: &Blade, a: &Frame, b: &Frame, face: Face) -> Crossing {
    let plane = |step: u64| match face {
        Face::Rear => blade.rear_at(scene.timestep, step),
        Face::Front => blade.front_at(scene.timestep, step),
    };
    let (pa, pb) = (plane(a.step), plane(b.step));
    let before: HashMap<u64, usize> = a.id.iter().enumerate().map(|(i, &id)| (id, i)).collect();
    let mut out = Crossing { mass: 0.0, mass_sq: 0.0, count: 0 };
    for j in 0..b.len() {
        let Some(&i) = before.get(&b.id[j]) else {
            continue;
        };
        let was_ahead = a.x[i] >= pa;
        let is_ahead = b.x[j] >= pb;
        if was_ahead && !is_ahead && b.z[j] < blade.gap {
            out.mass += b.mass[j];
            out.mass_sq += b.mass[j] * b.mass[j];
            out.count += 1;
        } else if !was_ahead && is_ahead && a.z[i] < blade.gap {
            out.mass -= b.mass[j];
            out.mass_sq += b.mass[j] * b.mass[j];
            out.count += 1;
        }
    }
    out
}

/// Two-sided p-value that two spans of equal travel deposited the same mass, given counting
/// noise: z = (M₁ − M₂)/√(Σ m²). No crossing at all is a steady (empty) flow: p = 1.
fn halves_p_value(first: &[Crossing], second: &[Crossing]) -> f64 {
    let mass = |c: &[Crossing]| c.iter().map(|x| x.mass).sum::<f64>();
    let var: f64 = first.iter().chain(second).map(|x| x.mass_sq).sum();
    if var <= 0.0 {
        return 1.0;
    }
    let z = (mass(first) - mass(second)).abs() / var.sqrt();
    2.0 * (1.0 - standard_normal_cdf(z))
}

fn standard_normal_cdf(z: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::new(0.0, 1.0).expect("unit normal").cdf(z)
}

/// Mean v_x per layer, pooled over `frames`.
pub(crate) fn vx_profile<'a>(
    scene: &Scene,
    blade: &Blade,
    window: &Window,
    frames: impl Iterator<Item = &'a Frame>,
) -> Vec<Option<f64>> {
    let mut sum = [0.0; VX_LAYERS];
    let mut count = [0usize; VX_LAYERS];
    for f in frames {
        let x0 = blade.front_at(scene.timestep, f.step);
        let x1 = x0 + window.vx_length;
        for i in 0..f.len() {
            if f.x[i] < x0 || f.x[i] > x1 {
                continue;
            }
            for k in 0..VX_LAYERS {
                if (f.z[i] - window.layer_height(blade.gap, k + 1)).abs() <= window.vx_band {
                    sum[k] += f.vx[i];
                    count[k] += 1;
                }
            }
        }
    }
    (0..VX_LAYERS).map(|k| (count[k] > 0).then(|| sum[k] / count[k] as f64)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crossings(masses: &[(f64, usize)]) -> Vec<Crossing> {
        masses
            .iter()
            .map(|&(m, n)| Crossing { mass: m * n as f64, mass_sq: m * m * n as f64, count: n })
            .collect()
    }

    #[test]
    fn steadiness_flags_a_trend_beyond_noise() {
        // Equal halves: p = 1.
        assert_eq!(halves_p_value(&crossings(&[(1.0, 50); 2]), &crossings(&[(1.0, 50); 2])), 1.0);
        // The decay seen on the first scene, 0.212, 0.208 | 0.120, 0.116 over ~100 particles:
        // 64 against 36 counted, z = 28/√100 = 2.8, p = 0.0051 < 1 %.
        let p = halves_p_value(&crossings(&[(1.0, 32), (1.0, 32)]), &crossings(&[(1.0, 18), (1.0, 18)]));
        assert!((p - 0.00511).abs() < 1e-4, "{p}");
        // The same trend on 10 particles is within counting noise: 6.4 against 3.6 ≈ 6 vs 4.
        assert!(halves_p_value(&crossings(&[(1.0, 6)]), &crossings(&[(1.0, 4)])) > 0.5);
        // No flow at all is a steady state.
        assert_eq!(halves_p_value(&crossings(&[(1.0, 0)]), &crossings(&[(1.0, 0)])), 1.0);
        // z = 1.96 is p = 0.05: a difference of 3.8416 over a variance of 3.8416.
        let c = |m: f64| vec![Crossing { mass: m, mass_sq: 3.8416 / 2.0, count: 1 }];
        assert!((halves_p_value(&c(3.8416), &c(0.0)) - 0.05).abs() < 1e-3);
    }
}
