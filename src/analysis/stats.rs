//! The statistics of a set of numbers (thesis Eq. 18–21; docs/statistics.md "The statistics of a space") and their bootstrap
//! intervals.
//!
//! Pure functions of `&[f64]`: no files, no sweeps. A statistic that a set cannot define (the
//! skewness of one value, the kurtosis of a set with S = 0) is `None`, which the report writes
//! as an empty CSV cell or JSON `null`: never NaN or inf in a file.
//!
//! Not responsible for deciding convergence ([`crate::analysis::convergence`]) or for which values go in
//! (the report filters failed runs out before calling here).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// The standard deviation below which a set counts as constant (S = 0), relative to the largest
/// magnitude in it: the shape statistics divide by S, and rounding alone leaves S ≈ 1e-17·|x|.
const CONSTANT_REL: f64 = 1e-12;

/// The four statistics of the thesis plus the moment skewness.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
pub struct Moments {
    pub n: usize,
    /// Eq. 18: Σx/N. `None` for an empty set.
    pub mean: Option<f64>,
    /// Eq. 19: √(Σ(x − x̄)²/N), divisor N. `None` for an empty set.
    pub std: Option<f64>,
    /// Eq. 20, Pearson's second skewness coefficient 3·(x̄ − median)/S. `None` when S = 0.
    pub skewness: Option<f64>,
    /// Eq. 21, m4/S⁴ with m4 = Σ(x − x̄)⁴/N (3 for a normal distribution: not the excess).
    /// `None` when S = 0.
    pub kurtosis: Option<f64>,
    /// The moment skewness m3/S³ (Fisher–Pearson, biased). `None` when S = 0.
    pub moment_skewness: Option<f64>,
    /// The median, which Eq. 20 needs. `None` for an empty set.
    pub median: Option<f64>,
}

/// The four statistics the convergence rule compares, in report order.
pub const STATISTICS: [Statistic; 4] =
    [Statistic::Mean, Statistic::Std, Statistic::Skewness, Statistic::Kurtosis];

/// One of the statistics judged for convergence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Statistic {
    Mean,
    Std,
    Skewness,
    Kurtosis,
}

impl Statistic {
    pub fn name(self) -> &'static str {
        match self {
            Statistic::Mean => "mean",
            Statistic::Std => "std",
            Statistic::Skewness => "skewness",
            Statistic::Kurtosis => "kurtosis",
        }
    }

    /// Replace this statistic of `m` by `v`.
    pub fn set(self, m: &mut Moments, v: f64) {
        let slot = match self {
            Statistic::Mean => &mut m.mean,
            Statistic::Std => &mut m.std,
            Statistic::Skewness => &mut m.skewness,
            Statistic::Kurtosis => &mut m.kurtosis,
        };
        *slot = Some(v);
    }

    /// This statistic of `m`.
    pub fn of(self, m: &Moments) -> Option<f64> {
        match self {
            Statistic::Mean => m.mean,
            Statistic::Std => m.std,
            Statistic::Skewness => m.skewness,
            Statistic::Kurtosis => m.kurtosis,
        }
    }
}

/// The statistics of `x` (finite values; callers drop NaN and failed runs first).
///
/// The mean is Σx/N; the central moments m2, m3 and m4 one pass of sums about it; the median
/// the middle order statistic (the mean of the two middle ones for even N, as statrs has it).
pub fn moments(x: &[f64]) -> Moments {
    moments_reordering(&mut x.to_vec())
}

/// [`moments`] of `x`, which the median's selection reorders: the bootstrap's resample, drawn
/// afresh each time, needs no copy.
fn moments_reordering(x: &mut [f64]) -> Moments {
    let n = x.len();
    if n == 0 {
        return Moments {
            n,
            mean: None,
            std: None,
            skewness: None,
            kurtosis: None,
            moment_skewness: None,
            median: None,
        };
    }
    let nf = n as f64;
    let mean = x.iter().sum::<f64>() / nf;
    let (mut s2, mut s3, mut s4, mut scale) = (0.0, 0.0, 0.0, 0.0f64);
    for &v in x.iter() {
        let d = v - mean;
        let d2 = d * d;
        s2 += d2;
        s3 += d2 * d;
        s4 += d2 * d2;
        scale = scale.max(v.abs());
    }
    let std = if n == 1 { 0.0 } else { (s2 / nf).sqrt() };
    let median = median_reordering(x);
    let constant = std <= CONSTANT_REL * scale || std == 0.0;
    let (skewness, kurtosis, moment_skewness) = if constant {
        (None, None, None)
    } else {
        let (m3, m4) = (s3 / nf, s4 / nf);
        (Some(3.0 * (mean - median) / std), Some(m4 / std.powi(4)), Some(m3 / std.powi(3)))
    };
    Moments { n, mean: Some(mean), std: Some(std), skewness, kurtosis, moment_skewness, median: Some(median) }
}

/// The median of non-empty `x`, selected in place: for even N the mean of the two middle order
/// statistics, the lower being the largest value left below the upper by the selection.
fn median_reordering(x: &mut [f64]) -> f64 {
    let (n, k) = (x.len(), x.len() / 2);
    let (below, upper, _) = x.select_nth_unstable_by(k, f64::total_cmp);
    let upper = *upper;
    if n % 2 != 0 {
        upper
    } else {
        let lower = below.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lower + upper) / 2.0
    }
}

/// A confidence interval; `None` bounds when too few resamples defined the statistic.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
pub struct Interval {
    pub lo: Option<f64>,
    pub hi: Option<f64>,
}

impl Interval {
    pub const UNDEFINED: Interval = Interval { lo: None, hi: None };
}

/// Settings of the bootstrap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bootstrap {
    pub resamples: usize,
    /// Two-sided confidence level, e.g. 0.95.
    pub level: f64,
    pub seed: u64,
}

impl Default for Bootstrap {
    /// 1,000 resamples: the 2.5 % and 97.5 % percentiles then rest on 25 resamples each, which
    /// moves a bound by about a tenth of the interval's width from seed to seed.
    fn default() -> Self {
        Bootstrap { resamples: 1000, level: 0.95, seed: 14 }
    }
}

/// Percentile bootstrap intervals of the four [`STATISTICS`] of `x`, in that order.
///
/// Each resample draws N values with replacement (ChaCha8 seeded with `b.seed`, so the same set
/// and seed give the same intervals on every machine). A resample where a statistic is undefined
/// (all drawn values equal) is left out of that statistic's percentiles; when more than half are
/// left out, or N < 2, the interval is undefined.
pub fn bootstrap(x: &[f64], b: &Bootstrap) -> [Interval; 4] {
    let n = x.len();
    if n < 2 || b.resamples == 0 {
        return [Interval::UNDEFINED; 4];
    }
    let mut rng = ChaCha8Rng::seed_from_u64(b.seed);
    let mut draws: [Vec<f64>; 4] = Default::default();
    let mut sample = vec![0.0; n];
    for _ in 0..b.resamples {
        for s in sample.iter_mut() {
            *s = x[rng.gen_range(0..n)];
        }
        let m = moments_reordering(&mut sample);
        for (d, stat) in draws.iter_mut().zip(STATISTICS) {
            if let Some(v) = stat.of(&m) {
                d.push(v);
            }
        }
    }
    percentile_intervals(draws, b)
}

/// The percentile intervals of each statistic's resampled values; undefined where more than half
/// of the resamples left the statistic undefined.
pub fn percentile_intervals(draws: [Vec<f64>; 4], b: &Bootstrap) -> [Interval; 4] {
    let alpha = (1.0 - b.level.clamp(0.0, 1.0)) / 2.0;
    draws.map(|mut d| {
        if d.len() * 2 < b.resamples {
            return Interval::UNDEFINED;
        }
        d.sort_by(f64::total_cmp);
        Interval { lo: Some(percentile_sorted(&d, alpha)), hi: Some(percentile_sorted(&d, 1.0 - alpha)) }
    })
}

/// The `p` quantile of sorted, non-empty `d`, linear between order statistics (numpy's default).
pub fn percentile_sorted(d: &[f64], p: f64) -> f64 {
    let pos = p.clamp(0.0, 1.0) * (d.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    if i + 1 < d.len() {
        d[i] + f * (d[i + 1] - d[i])
    } else {
        d[i]
    }
}

/// A set of numbers read from text, with what was skipped.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Column {
    pub values: Vec<f64>,
    /// Empty cells.
    pub empty: usize,
    /// Cells that are not finite numbers.
    pub non_numeric: usize,
}

/// Parse cells into finite numbers, counting the empty and the unreadable ones.
pub fn parse_cells<'a>(cells: impl IntoIterator<Item = &'a str>) -> Column {
    let mut c = Column::default();
    for cell in cells {
        let t = cell.trim();
        if t.is_empty() {
            c.empty += 1;
        } else {
            match t.parse::<f64>() {
                Ok(v) if v.is_finite() => c.values.push(v),
                _ => c.non_numeric += 1,
            }
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use statrs::statistics::{Data, OrderStatistics, Statistics};

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    #[test]
    fn hand_worked_set() {
        // x = 1, 2, 3, 4, 10. Worked by hand:
        // mean = 20/5 = 4; deviations −3, −2, −1, 0, 6
        // Σd² = 9+4+1+0+36 = 50, S² = 10, S = √10
        // median = 3, Pearson 2 = 3·(4 − 3)/√10 = 0.948683
        // Σd³ = −27−8−1+0+216 = 180, m3 = 36, m3/S³ = 36/31.6228 = 1.138420
        // Σd⁴ = 81+16+1+0+1296 = 1394, m4 = 278.8, m4/S⁴ = 278.8/100 = 2.788
        let m = moments(&[1.0, 2.0, 3.0, 4.0, 10.0]);
        assert_eq!(m.n, 5);
        assert!(close(m.mean.unwrap(), 4.0, 1e-15));
        assert!(close(m.std.unwrap(), 10f64.sqrt(), 1e-15));
        assert_eq!(m.median, Some(3.0));
        assert!(close(m.skewness.unwrap(), 0.948_683_298_050_513_8, 1e-14));
        assert!(close(m.moment_skewness.unwrap(), 1.138_419_957_660_617, 1e-14));
        assert!(close(m.kurtosis.unwrap(), 2.788, 1e-14));
    }

    #[test]
    fn symmetric_two_point_set() {
        // 0, 0, 1, 1: mean 0.5 = median, S = 0.5, every |d| = 0.5 so m4/S⁴ = 1 (the least
        // kurtosis any set can have), and both skewnesses are 0.
        let m = moments(&[0.0, 0.0, 1.0, 1.0]);
        assert_eq!(m.skewness, Some(0.0));
        assert_eq!(m.moment_skewness, Some(0.0));
        assert!(close(m.kurtosis.unwrap(), 1.0, 1e-15));
        assert!(close(m.std.unwrap(), 0.5, 1e-15));
    }

    #[test]
    fn mean_std_median_agree_with_statrs_and_a_plain_two_pass() {
        let x: Vec<f64> = (0..101).map(|i| ((i * 37) % 101) as f64 / 7.0 + (i as f64).sin()).collect();
        let m = moments(&x);
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        let mut s = x.clone();
        s.sort_by(f64::total_cmp);
        assert!(close(m.mean.unwrap(), mean, 1e-13));
        assert!(close(m.std.unwrap(), var.sqrt(), 1e-13));
        assert_eq!(m.median, Some(s[50]));
        // statrs' sample variance has divisor N − 1.
        assert!(close(m.std.unwrap().powi(2) * n / (n - 1.0), x.iter().variance(), 1e-12));
        assert_eq!(m.median, Some(Data::new(x.clone()).median()));
    }

    #[test]
    fn the_median_selected_in_place_is_statrs_s_for_odd_and_even_sets_with_ties() {
        for n in [1, 2, 3, 4, 7, 10, 101, 1000] {
            let x: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64 * 0.25 - (i % 3) as f64).collect();
            assert_eq!(moments(&x).median, Some(Data::new(x.clone()).median()), "n = {n}");
        }
    }

    #[test]
    fn kurtosis_of_a_large_normal_sample_is_three_not_zero() {
        let x: Vec<f64> = normal_sample(20_000, 3);
        let m = moments(&x);
        assert!((m.kurtosis.unwrap() - 3.0).abs() < 0.1, "{:?}", m.kurtosis);
        assert!(m.skewness.unwrap().abs() < 0.05);
    }

    /// `n` standard normal deviates, seeded.
    fn normal_sample(n: usize, seed: u64) -> Vec<f64> {
        ChaCha8Rng::seed_from_u64(seed).sample_iter(rand_distr::StandardNormal).take(n).collect()
    }

    #[test]
    fn degenerate_sets_are_undefined_not_nan() {
        let empty = moments(&[]);
        assert_eq!((empty.n, empty.mean, empty.std, empty.kurtosis), (0, None, None, None));
        let one = moments(&[0.3]);
        assert_eq!((one.mean, one.std, one.skewness, one.kurtosis), (Some(0.3), Some(0.0), None, None));
        // Every MFR = 0: the thesis's "unrealistic" corner of the space.
        let zeros = moments(&[0.0; 7]);
        assert_eq!(
            (zeros.mean, zeros.std, zeros.skewness, zeros.kurtosis),
            (Some(0.0), Some(0.0), None, None)
        );
        // Equal values whose computed S is rounding noise, not spread.
        let equal = moments(&[0.1; 3]);
        assert_eq!((equal.skewness, equal.kurtosis, equal.moment_skewness), (None, None, None));
        for m in [empty, one, zeros, equal] {
            let json = serde_json::to_string(&m).unwrap();
            assert!(!json.contains("NaN") && !json.contains("inf"), "{json}");
        }
    }

    #[test]
    fn bootstrap_is_seeded_and_brackets_the_statistic() {
        let x: Vec<f64> = normal_sample(400, 5).iter().map(|v| 0.3 + 0.1 * v).collect();
        let b = Bootstrap::default();
        let a = bootstrap(&x, &b);
        assert_eq!(a, bootstrap(&x, &b), "same seed, same intervals");
        let m = moments(&x);
        for (iv, stat) in a.iter().zip(STATISTICS) {
            let (lo, hi, v) = (iv.lo.unwrap(), iv.hi.unwrap(), stat.of(&m).unwrap());
            assert!(lo < v && v < hi, "{} {lo} {v} {hi}", stat.name());
        }
        // The mean's interval is about ±1.96·S/√N = ±0.0098 wide here.
        let w = a[0].hi.unwrap() - a[0].lo.unwrap();
        assert!((w - 2.0 * 1.96 * 0.1 / 20.0).abs() < 0.004, "{w}");
        let other = bootstrap(&x, &Bootstrap { seed: 99, ..b });
        assert_ne!(a, other);
    }

    #[test]
    fn bootstrap_of_degenerate_sets_is_undefined() {
        let b = Bootstrap::default();
        assert_eq!(bootstrap(&[], &b), [Interval::UNDEFINED; 4]);
        assert_eq!(bootstrap(&[1.0], &b), [Interval::UNDEFINED; 4]);
        let zeros = bootstrap(&[0.0; 10], &b);
        assert_eq!(zeros[0], Interval { lo: Some(0.0), hi: Some(0.0) });
        assert_eq!(zeros[2], Interval::UNDEFINED);
    }

    #[test]
    fn percentiles_interpolate_like_numpy() {
        let d = [1.0, 2.0, 3.0, 4.0];
        // numpy.percentile([1,2,3,4], 25) = 1.75, 50 → 2.5, 100 → 4
        assert_eq!(percentile_sorted(&d, 0.25), 1.75);
        assert_eq!(percentile_sorted(&d, 0.5), 2.5);
        assert_eq!(percentile_sorted(&d, 1.0), 4.0);
    }

    #[test]
    fn cells_skip_empty_and_non_numbers() {
        let c = parse_cells(["0.5", "", " 1e-1 ", "abc", "NaN", "inf", "2"]);
        assert_eq!(c.values, vec![0.5, 0.1, 2.0]);
        assert_eq!((c.empty, c.non_numeric), (1, 3));
    }
}
