//! Particle size distributions: monodisperse, explicit classes, or a discretised Weibull.
//!
//! Everything here is a *number* distribution (fraction of particles per class), which is what
//! LIGGGHTS's `particledistribution/discrete/numberbased` takes. Diameters are in metres.

use serde::Serialize;

use crate::scene::settings::SizeDistributionSpec;

/// One size class: diameter (m) and number fraction (the fractions of a distribution sum to 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SizeClass {
    pub diameter: f64,
    pub fraction: f64,
}

/// A discrete number distribution of diameters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SizeDistribution {
    pub classes: Vec<SizeClass>,
}

/// Probability mass of the Weibull tails left out of the discretisation (each side).
const WEIBULL_TAIL: f64 = 0.005;

impl SizeDistribution {
    /// Build from the sweep file's spec. `diameter` is the `diameter` parameter and the Weibull
    /// shape/scale are the `weibull_shape`/`weibull_scale` parameters, all lengths in metres.
    pub fn from_spec(spec: &SizeDistributionSpec, diameter: f64, shape: f64, scale: f64) -> Self {
        let classes = match spec {
            SizeDistributionSpec::Mono => vec![SizeClass { diameter, fraction: 1.0 }],
            SizeDistributionSpec::Classes { classes, relative } => classes
                .iter()
                .map(|&[d, f]| SizeClass {
                    diameter: if *relative { d * diameter } else { d * 1e-3 },
                    fraction: f,
                })
                .collect(),
            SizeDistributionSpec::Weibull { bins } => weibull_classes(shape, scale, *bins),
        };
        let total: f64 = classes.iter().map(|c| c.fraction).sum();
        SizeDistribution {
            classes: classes
                .into_iter()
                .map(|c| SizeClass { diameter: c.diameter, fraction: c.fraction / total })
                .collect(),
        }
    }

    pub fn is_mono(&self) -> bool {
        self.classes.len() == 1
    }

    pub fn min_diameter(&self) -> f64 {
        self.classes.iter().map(|c| c.diameter).fold(f64::INFINITY, f64::min)
    }

    pub fn max_diameter(&self) -> f64 {
        self.classes.iter().map(|c| c.diameter).fold(0.0, f64::max)
    }

    /// Number-weighted mean diameter, m.
    pub fn mean_diameter(&self) -> f64 {
        self.classes.iter().map(|c| c.fraction * c.diameter).sum()
    }

    /// Mean particle volume, m³.
    pub fn mean_volume(&self) -> f64 {
        self.classes.iter().map(|c| c.fraction * std::f64::consts::PI / 6.0 * c.diameter.powi(3)).sum()
    }

    /// The diameter below which a fraction `p` of the particles lies (by number), taking the
    /// smallest class diameter whose cumulative fraction reaches `p`. Thesis §3.2 uses D85 as the
    /// characteristic diameter of the v_x layers for a size distribution.
    pub fn quantile(&self, p: f64) -> f64 {
        let mut sorted = self.classes.clone();
        sorted.sort_by(|a, b| a.diameter.total_cmp(&b.diameter));
        let mut cumulative = 0.0;
        for c in &sorted {
            cumulative += c.fraction;
            if cumulative >= p - 1e-12 {
                return c.diameter;
            }
        }
        sorted.last().map(|c| c.diameter).unwrap_or(0.0)
    }
}

/// Weibull CDF F(d) = 1 − exp(−(d/λ)^k).
fn weibull_cdf(d: f64, shape: f64, scale: f64) -> f64 {
    1.0 - (-(d / scale).powf(shape)).exp()
}

/// Weibull quantile d(p) = λ (−ln(1 − p))^(1/k).
fn weibull_quantile(p: f64, shape: f64, scale: f64) -> f64 {
    scale * (-(1.0 - p).ln()).powf(1.0 / shape)
}

/// Discretise a Weibull(k, λ) diameter distribution into `bins` classes of equal width in
/// diameter between its 0.5 % and 99.5 % quantiles, each at its bin centre with the probability
/// of its bin (renormalised) — the construction of thesis Tables 3.2–3.3 (five equal-width
/// classes around the nominal diameter).
pub fn weibull_classes(shape: f64, scale: f64, bins: usize) -> Vec<SizeClass> {
    let lo = weibull_quantile(WEIBULL_TAIL, shape, scale);
    let hi = weibull_quantile(1.0 - WEIBULL_TAIL, shape, scale);
    let width = (hi - lo) / bins as f64;
    (0..bins)
        .map(|i| {
            let a = lo + i as f64 * width;
            let b = a + width;
            SizeClass {
                diameter: 0.5 * (a + b),
                fraction: weibull_cdf(b, shape, scale) - weibull_cdf(a, shape, scale),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weibull_bins_carry_the_probability_between_the_tails() {
        let classes = weibull_classes(4.0, 2e-3, 5);
        let total: f64 = classes.iter().map(|c| c.fraction).sum();
        // Everything but the two 0.5 % tails.
        assert!((total - (1.0 - 2.0 * WEIBULL_TAIL)).abs() < 1e-12);
        // Weibull(k = 4) is nearly symmetric with its mode at λ((k−1)/k)^(1/k) ≈ 0.93 λ: the
        // middle bin holds the most particles.
        let max = classes.iter().map(|c| c.fraction).fold(0.0, f64::max);
        assert_eq!(classes[2].fraction, max);
    }

    #[test]
    fn weibull_mean_matches_closed_form() {
        // Mean of Weibull(k, λ) = λ Γ(1 + 1/k); for k = 2: λ √π / 2.
        let d = SizeDistribution::from_spec(&SizeDistributionSpec::Weibull { bins: 400 }, 0.0, 2.0, 1e-3);
        let exact = 1e-3 * std::f64::consts::PI.sqrt() / 2.0;
        assert!((d.mean_diameter() - exact).abs() / exact < 5e-3, "{}", d.mean_diameter());
    }

    #[test]
    fn relative_classes_scale_with_the_diameter_and_normalise() {
        // Thesis Table 3.2, strategy 1, nominal 2 mm.
        let spec = SizeDistributionSpec::Classes {
            classes: vec![[0.7, 4.44], [0.85, 22.76], [1.0, 40.78], [1.15, 26.91], [1.3, 5.11]],
            relative: true,
        };
        let d = SizeDistribution::from_spec(&spec, 2e-3, 0.0, 0.0);
        assert!((d.classes[0].diameter - 1.4e-3).abs() < 1e-15);
        assert!((d.classes.iter().map(|c| c.fraction).sum::<f64>() - 1.0).abs() < 1e-12);
        // Cumulative 4.44 + 22.76 + 40.78 = 67.98 % < 85 % ≤ 94.89 %: D85 is the fourth class,
        // as the thesis notes ("happens to be the fourth featured diameter").
        assert!((d.quantile(0.85) - 2.3e-3).abs() < 1e-15);
    }
}
