//! The noise in each point, apart from the parameters' spread (docs/statistics.md "The noise in
//! each point").
//!
//! One run per point measures MFR(x) + e with e the point's own noise (standard error `mfr_se`).
//! Over the space, Var(measured) = Var(MFR(x)) + E[se²] when the noise is independent of x's
//! effect, so the parameters' share is the total variance less the mean of se², and the
//! standard deviation with the noise removed is √(Var − E[se²]) (0 when the noise explains it
//! all). Points without an `mfr_se` (results from before it was measured, screened zeros) are
//! left out of E[se²]; the split is undefined when no point has one.

use serde::Serialize;

/// The variance of MFR over a space split into the parameters' part and the per-point noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NoiseSplit {
    /// Points whose standard error entered the noise term.
    pub points_with_se: usize,
    /// Var of the measured MFR (divisor N, weighted as the statistics are).
    pub variance: f64,
    /// Mean of se² over the points that have one.
    pub noise_variance: f64,
    /// variance − noise_variance, at least 0.
    pub parameter_variance: f64,
    /// noise_variance / variance (1 when the variance is 0).
    pub noise_share: f64,
    /// √variance: the raw standard deviation.
    pub std_raw: f64,
    /// √parameter_variance: the standard deviation with the noise removed.
    pub std_without_noise: f64,
}

/// The split for values `x` with standard errors `se` (same order), weights `w` (`None` =
/// equal) as the statistics use; `None` when no point has a standard error or `x` is empty.
pub fn split(x: &[f64], se: &[Option<f64>], w: Option<&[f64]>) -> Option<NoiseSplit> {
    let ses: Vec<f64> = se.iter().flatten().copied().filter(|v| v.is_finite() && *v >= 0.0).collect();
    if ses.is_empty() || x.is_empty() {
        return None;
    }
    let m = crate::analysis::weights::moments(x, w);
    let variance = m.std?.powi(2);
    let noise_variance = ses.iter().map(|s| s * s).sum::<f64>() / ses.len() as f64;
    let parameter_variance = (variance - noise_variance).max(0.0);
    Some(NoiseSplit {
        points_with_se: ses.len(),
        variance,
        noise_variance,
        parameter_variance,
        noise_share: if variance > 0.0 { (noise_variance / variance).min(1.0) } else { 1.0 },
        std_raw: variance.sqrt(),
        std_without_noise: parameter_variance.sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_by_hand() {
        // x = 0, 2: mean 1, variance 1. se 0.6 and 0.8: mean se² = (0.36 + 0.64)/2 = 0.5, so
        // the parameters explain 0.5, noise share ½, std 1 raw and √0.5 without noise.
        let s = split(&[0.0, 2.0], &[Some(0.6), Some(0.8)], None).unwrap();
        assert!((s.variance - 1.0).abs() < 1e-15 && (s.noise_variance - 0.5).abs() < 1e-15);
        assert!((s.noise_share - 0.5).abs() < 1e-15);
        assert!((s.std_without_noise - 0.5f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn noise_larger_than_the_spread_leaves_no_parameter_share() {
        let s = split(&[1.0, 1.1], &[Some(1.0), None], None).unwrap();
        assert_eq!((s.points_with_se, s.parameter_variance, s.noise_share), (1, 0.0, 1.0));
        assert_eq!(split(&[1.0, 2.0], &[None, None], None), None);
    }

    #[test]
    fn a_noisy_sample_of_a_known_surface_recovers_its_spread() {
        // y = x on a uniform grid (Var = 1/12 in the limit) plus noise of se 0.1 from a fixed
        // sequence of ±0.1: the noise-free std comes back as √(1/12) within 1 %.
        let n = 10_000;
        let x: Vec<f64> =
            (0..n).map(|i| (i as f64 + 0.5) / n as f64 + if i % 2 == 0 { 0.1 } else { -0.1 }).collect();
        let se = vec![Some(0.1); n];
        let s = split(&x, &se, None).unwrap();
        assert!((s.std_without_noise / (1.0f64 / 12.0).sqrt() - 1.0).abs() < 0.01, "{s:?}");
        assert!(s.std_raw > s.std_without_noise);
    }
}
