//! Quality of the spread layer itself, from the deposit behind the blade at the window's end
//! (docs/layer.md gives the definitions for users):
//!
//! The deposit is every powder particle whose centre is below the tip (z < gap) on the strip
//! the blade's rear face swept during the window, [x_r(t1), x_r(t2) − [`SETTLE_MARGIN`]·D]: the
//! last few diameters right behind the blade are still being laid down and are left out.
//!
//! - **uniformity** (`layer_cv`): the coefficient of variation of the deposited mass in bins of
//!   [`BIN_DIAMETERS`]·D along the travel (full depth each). Its counting noise
//!   (`layer_cv_noise`) is what a layer of independently placed particles of the same masses
//!   would show: √(mean over bins of Σm²) / mean bin mass. A layer is even along the travel
//!   when `layer_cv` is near its noise; gaps and clumps push it above.
//! - **covered fraction** (`covered_fraction`): the share of the strip's area (x along the
//!   travel, y across, periodic) under at least one deposited particle's projected disc,
//!   sampled on a grid of D/[`GRID_PER_D`]. Its complement is the empty-patch area fraction,
//!   the uncovered substrate that Nan et al. (2018) count as empty patches.
//! - **roughness** (`roughness_d`): the RMS of the layer's top-surface height about its mean,
//!   in D, on the same grid; the height of a cell is the top of the highest sphere over it
//!   (z + √(r² − d²)), or the substrate's top (z = 0) where nothing covers it.
//!
//! Reads only id-free columns x, y, z and mass (radius from mass and the solid density).

use crate::measure::frame::Frame;
use crate::outcome::layer::Layer;
use crate::scene::Scene;

/// Bin length along the travel for the uniformity, in D.
pub const BIN_DIAMETERS: f64 = 3.0;
/// Grid cells per D for coverage and roughness.
pub const GRID_PER_D: f64 = 4.0;
/// Length right behind the blade left out of the deposit, in D (still being laid down).
pub const SETTLE_MARGIN: f64 = 2.0;

/// The layer at `frame` (the window's last snapshot) over the strip from `x0` to `x1`, under a
/// blade at `gap`.
pub fn measure(scene: &Scene, gap: f64, frame: &Frame, x0: f64, x1: f64) -> Option<Layer> {
    let d = scene.diameter;
    let x1 = x1 - SETTLE_MARGIN * d;
    let y = frame.y.as_ref()?;
    if x1 - x0 < 2.0 * BIN_DIAMETERS * d {
        return None;
    }
    let radius = |m: f64| (3.0 * m / (4.0 * std::f64::consts::PI * scene.material.density)).cbrt();
    let deposit: Vec<usize> =
        (0..frame.len()).filter(|&i| frame.x[i] >= x0 && frame.x[i] < x1 && frame.z[i] < gap).collect();

    // Uniformity along the travel.
    // Whole bins over the strip (the small epsilon keeps an exact multiple from rounding down).
    let nb = ((x1 - x0) / (BIN_DIAMETERS * d) + 1e-9).floor() as usize;
    let bin = (x1 - x0) / nb as f64;
    let (mut mass, mut mass_sq) = (vec![0.0; nb], vec![0.0; nb]);
    for &i in &deposit {
        let b = (((frame.x[i] - x0) / bin) as usize).min(nb - 1);
        mass[b] += frame.mass[i];
        mass_sq[b] += frame.mass[i] * frame.mass[i];
    }
    let mean = mass.iter().sum::<f64>() / nb as f64;
    let (cv, noise) = if mean > 0.0 {
        let var = mass.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / nb as f64;
        (var.sqrt() / mean, (mass_sq.iter().sum::<f64>() / nb as f64).sqrt() / mean)
    } else {
        (0.0, 0.0)
    };

    // Coverage and the top surface on a grid over the strip (y periodic over the depth).
    let h = d / GRID_PER_D;
    let (nx, ny) = (((x1 - x0) / h).round() as usize, (scene.depth / h).round().max(1.0) as usize);
    let (hx, hy) = ((x1 - x0) / nx as f64, scene.depth / ny as f64);
    let mut top: Vec<Option<f64>> = vec![None; nx * ny];
    for &i in &deposit {
        let r = radius(frame.mass[i]);
        let (xi, yi, zi) = (frame.x[i], y[i].rem_euclid(scene.depth), frame.z[i]);
        let (cx0, cx1) = (((xi - r - x0) / hx).floor() as i64, ((xi + r - x0) / hx).ceil() as i64);
        let (cy0, cy1) = (((yi - r) / hy).floor() as i64, ((yi + r) / hy).ceil() as i64);
        for cx in cx0.max(0)..cx1.min(nx as i64) {
            let gx = x0 + (cx as f64 + 0.5) * hx;
            for cy in cy0..cy1 {
                let gy = (cy as f64 + 0.5) * hy;
                let d2 = (gx - xi).powi(2) + (gy - yi).powi(2);
                if d2 < r * r {
                    let cell = &mut top[cx as usize * ny + cy.rem_euclid(ny as i64) as usize];
                    let z = zi + (r * r - d2).sqrt();
                    *cell = Some(cell.map_or(z, |t: f64| t.max(z)));
                }
            }
        }
    }
    let covered = top.iter().filter(|t| t.is_some()).count() as f64 / top.len() as f64;
    let heights: Vec<f64> = top.iter().map(|t| t.unwrap_or(0.0).max(0.0)).collect();
    let hmean = heights.iter().sum::<f64>() / heights.len() as f64;
    let rms = (heights.iter().map(|z| (z - hmean).powi(2)).sum::<f64>() / heights.len() as f64).sqrt();
    Some(Layer {
        layer_cv: cv,
        layer_cv_noise: noise,
        covered_fraction: covered,
        roughness_d: rms / d,
        height_d: hmean / d,
        particles: deposit.len(),
    })
}

/// The conveyor's uniformity along the travel: the coefficient of variation of the mass each
/// block deposits over the steady window (`block_mass`, bins of one block's travel), and its
/// counting noise √(m_w / M̄), where m_w is the feed's mass-weighted mean particle mass (a
/// block's Σm² is about its mass times m_w when it deposits the feed's size mix).
pub fn along_travel(block_mass: &[f64], weighted_particle_mass: f64) -> (f64, f64) {
    let n = block_mass.len() as f64;
    let mean = block_mass.iter().sum::<f64>() / n;
    if block_mass.len() < 2 || mean <= 0.0 {
        return (0.0, 0.0);
    }
    let var = block_mass.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / n;
    (var.sqrt() / mean, (weighted_particle_mass / mean).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn independent_blocks_of_a_size_mix_scatter_by_the_compound_poisson_noise() {
        use rand::{Rng, SeedableRng};
        // Blocks of Poisson(40) particles, a third of them twice the mass of the rest: the CV of
        // the block mass is √(E[m²] / (λ E[m]²)), which is what the noise gives from m_w.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (lambda, masses) = (40.0_f64, [1.0, 1.0, 2.0]);
        let blocks: Vec<f64> = (0..4000)
            .map(|_| {
                // Poisson by counting unit-rate exponential gaps within λ.
                let (mut t, mut m) = (0.0, 0.0);
                loop {
                    t -= (1.0 - rng.gen::<f64>()).ln();
                    if t > lambda {
                        break m;
                    }
                    m += masses[rng.gen_range(0..3)];
                }
            })
            .collect();
        let weighted = (1.0 + 1.0 + 4.0) / (1.0 + 1.0 + 2.0); // Σ m² / Σ m over the mix
        let (cv, noise) = along_travel(&blocks, weighted);
        let exact = (2.0_f64 / (lambda * (4.0_f64 / 3.0).powi(2))).sqrt();
        assert!((noise - exact).abs() < 0.02 * exact, "noise {noise} vs {exact}");
        assert!((cv - exact).abs() < 0.05 * exact, "cv {cv} vs {exact}");
        // An empty or single block has no spread.
        assert_eq!(along_travel(&[0.0, 0.0], 1.0), (0.0, 0.0));
        assert_eq!(along_travel(&[3.0], 1.0), (0.0, 0.0));
    }
}
