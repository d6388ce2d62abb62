//! Particle size distributions: monodisperse, explicit classes, a discretised Weibull, or a
//! lognormal fitted to a datasheet's D10/D50/D90.
//!
//! Everything here is a *number* distribution (fraction of particles per class), which is what
//! the pile and the feed are built from; a distribution given by volume (laser diffraction, as
//! datasheets report it) is converted class by class: the number of particles of a class is its
//! volume fraction over its particle volume, n_i ∝ v_i / d_i³. Diameters are in metres.

use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal};

use crate::analysis::simplex::minimise;
use crate::outcome::SizeSummary;
use crate::scene::settings::{Basis, SizeDistributionSpec};

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
    /// The lognormal's fit to the datasheet's D10/D50/D90: the largest relative miss of the
    /// three (`None` for the other kinds).
    pub fit_residual: Option<f64>,
}

/// Probability mass of the Weibull tails left out of the discretisation (each side).
const WEIBULL_TAIL: f64 = 0.005;

impl SizeDistribution {
    /// Build from the sweep file's spec. `diameter` is the `diameter` parameter and the Weibull
    /// shape/scale are the `weibull_shape`/`weibull_scale` parameters, all lengths in metres.
    pub fn from_spec(spec: &SizeDistributionSpec, diameter: f64, shape: f64, scale: f64) -> Self {
        let classes = match spec {
            SizeDistributionSpec::Mono => vec![SizeClass { diameter, fraction: 1.0 }],
            SizeDistributionSpec::Classes { classes, relative, basis } => to_number(
                classes
                    .iter()
                    .map(|&[d, f]| SizeClass {
                        diameter: if *relative { d * diameter } else { d * 1e-3 },
                        fraction: f,
                    })
                    .collect(),
                *basis,
            ),
            SizeDistributionSpec::Weibull { bins } => weibull_classes(shape, scale, *bins),
            SizeDistributionSpec::Lognormal { d10_um, d50_um, d90_um, cut_um, basis, bins, relative } => {
                let um = 1e-6;
                let fit = Lognormal::fit(
                    [d10_um * um, d50_um * um, d90_um * um],
                    cut_um.map(|[a, b]| [a * um, b * um]),
                );
                let scale = if *relative { diameter / (d50_um * um) } else { 1.0 };
                let classes = fit
                    .classes(*bins)
                    .into_iter()
                    .map(|c| SizeClass { diameter: c.diameter * scale, fraction: c.fraction })
                    .collect();
                return SizeDistribution::normalised(to_number(classes, *basis), Some(fit.residual));
            }
        };
        SizeDistribution::normalised(classes, None)
    }

    fn normalised(classes: Vec<SizeClass>, fit_residual: Option<f64>) -> Self {
        let total: f64 = classes.iter().map(|c| c.fraction).sum();
        SizeDistribution {
            classes: classes
                .into_iter()
                .map(|c| SizeClass { diameter: c.diameter, fraction: c.fraction / total })
                .collect(),
            fit_residual,
        }
    }

    /// The diameter below which a fraction `p` of the *volume* lies: each class spans the
    /// geometric midpoints to its neighbours (the bin edges of a lognormal's classes), and the
    /// cumulative volume is interpolated linearly in ln D across it.
    pub fn volume_quantile(&self, p: f64) -> f64 {
        let mut sorted = self.classes.clone();
        sorted.sort_by(|a, b| a.diameter.total_cmp(&b.diameter));
        let n = sorted.len();
        if n == 1 {
            return sorted[0].diameter;
        }
        let volume: Vec<f64> = sorted.iter().map(|c| c.fraction * c.diameter.powi(3)).collect();
        let total: f64 = volume.iter().sum();
        let mut edges: Vec<f64> = vec![0.0; n + 1];
        for i in 1..n {
            edges[i] = (sorted[i - 1].diameter * sorted[i].diameter).sqrt();
        }
        edges[0] = sorted[0].diameter.powi(2) / edges[1];
        edges[n] = sorted[n - 1].diameter.powi(2) / edges[n - 1];
        let mut below = 0.0;
        for i in 0..n {
            let share = volume[i] / total;
            if below + share >= p || i == n - 1 {
                let t = ((p - below) / share).clamp(0.0, 1.0);
                return (edges[i].ln() + t * (edges[i + 1].ln() - edges[i].ln())).exp();
            }
            below += share;
        }
        unreachable!("the loop returns at its last class")
    }

    /// What result.json says of the sizes: number mean, D10/D50/D90 by volume, span, classes.
    pub fn summary(&self) -> SizeSummary {
        let [d10, d50, d90] = [0.1, 0.5, 0.9].map(|p| self.volume_quantile(p));
        SizeSummary {
            mean_diameter: self.mean_diameter(),
            d10,
            d50,
            d90,
            span: (d90 - d10) / d50,
            classes: self.classes.len(),
            fit_residual: self.fit_residual,
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

/// Fractions by number from fractions on `basis`: n_i ∝ v_i / d_i³ for a volume basis.
fn to_number(classes: Vec<SizeClass>, basis: Basis) -> Vec<SizeClass> {
    match basis {
        Basis::Number => classes,
        Basis::Volume => classes
            .into_iter()
            .map(|c| SizeClass { diameter: c.diameter, fraction: c.fraction / c.diameter.powi(3) })
            .collect(),
    }
}

/// The standard normal quantiles of the 10th and 90th percentile: ∓1.2816.
const Z90: f64 = 1.281_551_565_545;

/// A lognormal in diameter truncated to [lo, hi]: ln D ~ N(mu, sigma²) on the basis it was
/// fitted on (volume or number), renormalised over the cut.
#[derive(Debug, Clone, Copy)]
pub struct Lognormal {
    pub mu: f64,
    pub sigma: f64,
    pub lo: f64,
    pub hi: f64,
    /// The largest relative miss of the fitted D10/D50/D90 against the given ones.
    pub residual: f64,
}

impl Lognormal {
    /// Fit (mu, sigma) so that the truncated distribution's 10th, 50th and 90th percentiles
    /// match `q` = [D10, D50, D90] in the least-squares sense in ln D. Without a cut the fit is
    /// exact in closed form for a symmetric datasheet and is truncated at its 0.05 % tails.
    pub fn fit(q: [f64; 3], cut: Option<[f64; 2]>) -> Lognormal {
        let ln_q = q.map(f64::ln);
        let start = [ln_q[1], (ln_q[2] - ln_q[0]) / (2.0 * Z90)];
        let (lo, hi) = match cut {
            Some([lo, hi]) => (lo, hi),
            None => {
                let tail = 3.29; // the 0.05 % quantile of N(0, 1)
                ((start[0] - tail * start[1]).exp(), (start[0] + tail * start[1]).exp())
            }
        };
        let at = |p: &[f64]| Lognormal { mu: p[0], sigma: p[1], lo, hi, residual: 0.0 };
        let misfit = |p: &[f64]| {
            let l = at(p);
            [0.1, 0.5, 0.9].iter().zip(&ln_q).map(|(&pr, lq)| (l.quantile(pr).ln() - lq).powi(2)).sum()
        };
        let best = minimise(&misfit, &start, 0.1 * start[1], 2000, &|p| p[1] = p[1].max(1e-3));
        let mut fit = at(&best);
        fit.residual = [0.1, 0.5, 0.9]
            .iter()
            .zip(&q)
            .map(|(&pr, d)| (fit.quantile(pr) / d - 1.0).abs())
            .fold(0.0, f64::max);
        fit
    }

    fn normal() -> Normal {
        Normal::new(0.0, 1.0).expect("the standard normal")
    }

    /// The truncated CDF at diameter `d`.
    pub fn cdf(&self, d: f64) -> f64 {
        let n = Self::normal();
        let phi = |x: f64| n.cdf((x.ln() - self.mu) / self.sigma);
        ((phi(d) - phi(self.lo)) / (phi(self.hi) - phi(self.lo))).clamp(0.0, 1.0)
    }

    /// The truncated distribution's quantile.
    pub fn quantile(&self, p: f64) -> f64 {
        let n = Self::normal();
        let a = n.cdf((self.lo.ln() - self.mu) / self.sigma);
        let b = n.cdf((self.hi.ln() - self.mu) / self.sigma);
        (self.mu + self.sigma * n.inverse_cdf(a + p * (b - a))).exp()
    }

    /// `bins` classes of equal width in ln D over the cut, each at its bin's geometric centre
    /// with the probability of its bin (on the fitted basis).
    pub fn classes(&self, bins: usize) -> Vec<SizeClass> {
        let width = (self.hi / self.lo).ln() / bins as f64;
        (0..bins)
            .map(|i| {
                let a = self.lo * (i as f64 * width).exp();
                let b = a * width.exp();
                SizeClass { diameter: (a * b).sqrt(), fraction: self.cdf(b) - self.cdf(a) }
            })
            .collect()
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
            basis: Basis::Number,
        };
        let d = SizeDistribution::from_spec(&spec, 2e-3, 0.0, 0.0);
        assert!((d.classes[0].diameter - 1.4e-3).abs() < 1e-15);
        assert!((d.classes.iter().map(|c| c.fraction).sum::<f64>() - 1.0).abs() < 1e-12);
        // Cumulative 4.44 + 22.76 + 40.78 = 67.98 % < 85 % ≤ 94.89 %: D85 is the fourth class,
        // as the thesis notes ("happens to be the fourth featured diameter").
        assert!((d.quantile(0.85) - 2.3e-3).abs() < 1e-15);
    }

    fn lognormal(q: [f64; 3], cut: Option<[f64; 2]>, bins: usize) -> SizeDistribution {
        let spec = SizeDistributionSpec::Lognormal {
            d10_um: q[0],
            d50_um: q[1],
            d90_um: q[2],
            cut_um: cut,
            basis: Basis::Volume,
            bins,
            relative: false,
        };
        SizeDistribution::from_spec(&spec, 0.0, 0.0, 0.0)
    }

    #[test]
    fn a_lognormal_fitted_to_a_datasheet_gives_back_its_d10_d50_d90() {
        // Values of the kind laser diffraction gives for gas-atomised powders sieved to
        // 15–45 µm (Ti-6Al-4V), 15–53 µm (316L) and 20–63 µm (AlSi10Mg, no cut given).
        for (q, cut) in [
            ([20.0, 31.0, 42.0], Some([15.0, 45.0])),
            ([19.0, 31.0, 48.0], Some([15.0, 53.0])),
            ([27.0, 41.0, 60.0], None),
        ] {
            let d = lognormal(q, cut, 10);
            for (p, want) in [0.1, 0.5, 0.9].into_iter().zip(q) {
                let got = d.volume_quantile(p) * 1e6;
                assert!(
                    (got / want - 1.0).abs() < 0.02,
                    "{q:?} cut {cut:?}: D{} {got:.2} µm, datasheet {want}",
                    p * 100.0
                );
            }
            assert!(d.fit_residual.unwrap() < 0.02, "{q:?}: residual {:?}", d.fit_residual);
            // Nothing outside the sieve cut.
            if let Some([lo, hi]) = cut {
                assert!(d.min_diameter() * 1e6 > lo && d.max_diameter() * 1e6 < hi);
            }
        }
    }

    #[test]
    fn a_volume_lognormal_has_the_hatch_choate_number_mean() {
        // By volume ln D ~ N(μ, σ²) makes it N(μ − 3σ², σ²) by number, whose mean diameter is
        // exp(μ − 2.5 σ²) (Hatch & Choate 1929); D90 = D50²/D10 makes the datasheet exactly lognormal.
        let (d10, d50, d90) = (20.0, 32.0, 51.2);
        // A cut far in the tails: nothing of the number distribution is lost.
        let d = lognormal([d10, d50, d90], Some([1.0, 1000.0]), 400);
        let sigma = (d90 / d10).ln() / (2.0 * Z90);
        let mu = (d10 * d90).sqrt().ln();
        let exact = (mu - 2.5 * sigma * sigma).exp() * 1e-6;
        assert!((d.mean_diameter() / exact - 1.0).abs() < 0.01, "{} against {exact}", d.mean_diameter());
        assert!(d.fit_residual.unwrap() < 1e-6);
    }

    #[test]
    fn a_table_by_volume_counts_many_more_small_particles() {
        // Equal volumes of 20 and 40 µm spheres: 2³ = 8 small ones for every large one.
        let spec = SizeDistributionSpec::Classes {
            classes: vec![[0.02, 0.5], [0.04, 0.5]],
            relative: false,
            basis: Basis::Volume,
        };
        let d = SizeDistribution::from_spec(&spec, 0.0, 0.0, 0.0);
        assert!((d.classes[0].fraction / d.classes[1].fraction - 8.0).abs() < 1e-9);
        assert!((d.volume_quantile(0.5) - (0.02f64 * 0.04).sqrt() * 1e-3).abs() < 1e-12);
    }

    #[test]
    fn a_relative_lognormal_puts_its_d50_at_the_diameter_parameter() {
        let spec = SizeDistributionSpec::Lognormal {
            d10_um: 20.0,
            d50_um: 32.0,
            d90_um: 44.0,
            cut_um: Some([15.0, 45.0]),
            basis: Basis::Volume,
            bins: 10,
            relative: true,
        };
        let d = SizeDistribution::from_spec(&spec, 64e-6, 0.0, 0.0);
        assert!((d.volume_quantile(0.5) / 64e-6 - 1.0).abs() < 0.02);
        assert!((d.min_diameter() / 30e-6) > 1.0);
    }
}
