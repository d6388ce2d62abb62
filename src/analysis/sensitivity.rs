//! First-order sensitivity indices from the sample a sweep already has (docs/statistics.md "Sensitivity indices"): which
//! parameter the MFR depends on most, with no extra runs.
//!
//! The estimator is the binned correlation ratio (Pearson's η², the given-data form of Sobol's
//! first-order index S_i = Var(E[Y | X_i]) / Var(Y)): sort the points by X_i, cut them into M
//! bins, and compare the variance of the bin means with the total variance. With M = ⌈√N⌉ (at
//! most [`MAX_BINS`]), a dimension with no more than M distinct values (a lattice) has one bin
//! per value; otherwise M bins of equal count. η² with M bins is biased upwards by about (M − 1)/N·(1 − η²),
//! so the index reported is the adjusted ε² = 1 − [SS_within/(N − M)] / [SS_total/(N − 1)],
//! clamped to [0, 1].
//!
//! `docs/study/statistics/bench_sensitivity.py` checks it against SALib's RBD-FAST and delta
//! estimators on the same data and on the Ishigami function (BENCHMARKS.md "Sensitivity
//! indices").

use serde::Serialize;

/// Most bins per parameter for continuous samples.
pub const MAX_BINS: usize = 64;

/// Below this many points per parameter the report says the ranking is not yet reliable (a
/// stated threshold: with ⌈√N⌉ bins, 50 points per parameter leaves about 7 points per bin at
/// N = 200 in 4-D; the overlap test in [`reliability`] catches the rest).
pub const RELIABLE_PER_PARAMETER: usize = 50;

/// The first-order index of one parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Index {
    pub parameter: String,
    /// Adjusted correlation ratio ε², in [0, 1]; `None` when Y has no variance or N ≤ M.
    pub first_order: Option<f64>,
    pub bins: usize,
    /// 95 % percentile bootstrap interval of the index (points resampled with replacement);
    /// `None` without [`with_intervals`] or when too few resamples defined it.
    pub lo: Option<f64>,
    pub hi: Option<f64>,
}

/// First-order indices of `y` for each column of `x` (`x[i][j]`: point i, parameter j), in
/// parameter order. Rank them with [`ranked`].
pub fn first_order(names: &[String], x: &[Vec<f64>], y: &[f64]) -> Vec<Index> {
    names
        .iter()
        .enumerate()
        .map(|(j, name)| {
            let col: Vec<f64> = x.iter().map(|p| p[j]).collect();
            let (s, bins) = correlation_ratio(&col, y);
            Index { parameter: name.clone(), first_order: s, bins, lo: None, hi: None }
        })
        .collect()
}

/// [`first_order`] with bootstrap intervals: `b.resamples` resamples of the points (pairs of x
/// and y, with replacement, ChaCha8 seeded by `b.seed`), each index recomputed on each; the
/// percentile interval is shifted by the bootstrap's bias (mean of the draws less the index).
pub fn with_intervals(
    names: &[String],
    x: &[Vec<f64>],
    y: &[f64],
    b: &crate::analysis::stats::Bootstrap,
) -> Vec<Index> {
    use rand::{Rng, SeedableRng};
    let mut out = first_order(names, x, y);
    let n = y.len().min(x.len());
    if n < 3 || b.resamples == 0 {
        return out;
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(b.seed);
    let mut draws: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    let (mut col, mut ys) = (vec![0.0; n], vec![0.0; n]);
    let picks: Vec<Vec<usize>> =
        (0..b.resamples).map(|_| (0..n).map(|_| rng.gen_range(0..n)).collect()).collect();
    for (j, d) in draws.iter_mut().enumerate() {
        for pick in &picks {
            for (k, &i) in pick.iter().enumerate() {
                col[k] = x[i][j];
                ys[k] = y[i];
            }
            if let (Some(v), _) = correlation_ratio(&col, &ys) {
                d.push(v);
            }
        }
    }
    let alpha = (1.0 - b.level.clamp(0.0, 1.0)) / 2.0;
    for (ix, mut d) in out.iter_mut().zip(draws) {
        if d.len() * 2 < b.resamples {
            continue;
        }
        d.sort_by(f64::total_cmp);
        // A resample repeats points, which the binned estimator reads as agreement within a
        // bin: its draws sit above the index by a bias. Shift the percentiles back by it.
        let bias = d.iter().sum::<f64>() / d.len() as f64 - ix.first_order.unwrap_or(0.0);
        let at = |p: f64| (crate::analysis::stats::percentile_sorted(&d, p) - bias).clamp(0.0, 1.0);
        ix.lo = Some(at(alpha));
        ix.hi = Some(at(1.0 - alpha));
    }
    out
}

/// Whether a ranking of `d` parameters from `n` points is reliable, and why not in words.
pub fn reliability(n: usize, ranked: &[Index]) -> (bool, String) {
    if let [only] = ranked {
        return (true, format!("{} is the only swept parameter: there is nothing to rank", only.parameter));
    }
    let d = ranked.len().max(1);
    if n < RELIABLE_PER_PARAMETER * d {
        return (
            false,
            format!(
                "ranking not yet reliable: {n} points for {d} parameters, fewer than {RELIABLE_PER_PARAMETER} per parameter"
            ),
        );
    }
    if let [a, b, ..] = ranked {
        if let (Some(alo), Some(bhi)) = (a.lo, b.hi) {
            if alo <= bhi {
                return (
                    false,
                    format!(
                        "the top two ({}, {}) are not told apart: their 95% intervals overlap",
                        a.parameter, b.parameter
                    ),
                );
            }
        }
    }
    (true, format!("{n} points for {d} parameters; the leading index's interval clears the next"))
}

/// Largest index first; undefined ones last.
pub fn ranked(mut v: Vec<Index>) -> Vec<Index> {
    v.sort_by(|a, b| b.first_order.unwrap_or(-1.0).total_cmp(&a.first_order.unwrap_or(-1.0)));
    v
}

/// ε² of `y` binned by `x`, and the number of bins.
pub fn correlation_ratio(x: &[f64], y: &[f64]) -> (Option<f64>, usize) {
    let n = x.len().min(y.len());
    if n < 3 {
        return (None, 0);
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    // Bin boundaries as index ranges into `order`.
    let mut distinct: Vec<usize> = vec![0];
    for k in 1..n {
        if x[order[k]] != x[order[k - 1]] {
            distinct.push(k);
        }
    }
    let m = ((n as f64).sqrt().ceil() as usize).clamp(2, MAX_BINS);
    let starts: Vec<usize> = if distinct.len() <= m {
        distinct
    } else {
        // Equal counts, but never splitting a run of equal x values.
        let mut s: Vec<usize> = (0..m).map(|b| b * n / m).collect();
        for b in s.iter_mut() {
            while *b > 0 && x[order[*b]] == x[order[*b - 1]] {
                *b -= 1;
            }
        }
        s.dedup();
        s
    };
    let m = starts.len();
    if n <= m || m < 2 {
        return (None, m);
    }
    let mean = y[..n].iter().sum::<f64>() / n as f64;
    let ss_total: f64 = y[..n].iter().map(|v| (v - mean).powi(2)).sum();
    if ss_total <= 0.0 {
        return (None, m);
    }
    let mut ss_within = 0.0;
    for (b, &start) in starts.iter().enumerate() {
        let end = starts.get(b + 1).copied().unwrap_or(n);
        let ys: Vec<f64> = order[start..end].iter().map(|&i| y[i]).collect();
        let bm = ys.iter().sum::<f64>() / ys.len() as f64;
        ss_within += ys.iter().map(|v| (v - bm).powi(2)).sum::<f64>();
    }
    let eps2 = 1.0 - (ss_within / (n - m) as f64) / (ss_total / (n - 1) as f64);
    (Some(eps2.clamp(0.0, 1.0)), m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Ishigami (a = 7, b = 0.1) on [−π, π]³: S1 = 0.3139, S2 = 0.4424, S3 = 0 (Saltelli 2008).
    fn ishigami(p: &[f64]) -> f64 {
        p[0].sin() + 7.0 * p[1].sin().powi(2) + 0.1 * p[2].powi(4) * p[0].sin()
    }

    #[test]
    fn ishigami_indices_from_a_random_sample() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let pi = std::f64::consts::PI;
        let x: Vec<Vec<f64>> = (0..8000).map(|_| (0..3).map(|_| rng.gen_range(-pi..pi)).collect()).collect();
        let y: Vec<f64> = x.iter().map(|p| ishigami(p)).collect();
        let names: Vec<String> = ["x1", "x2", "x3"].map(String::from).to_vec();
        let s = first_order(&names, &x, &y);
        let got: Vec<f64> = s.iter().map(|i| i.first_order.unwrap()).collect();
        assert!((got[0] - 0.3139).abs() < 0.03, "{got:?}");
        assert!((got[1] - 0.4424).abs() < 0.03, "{got:?}");
        assert!(got[2] < 0.02, "{got:?}");
        let r = ranked(s);
        assert_eq!(r[0].parameter, "x2");
    }

    #[test]
    fn intervals_bracket_the_index_and_narrow_with_n() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let pi = std::f64::consts::PI;
        let x: Vec<Vec<f64>> = (0..1600).map(|_| (0..3).map(|_| rng.gen_range(-pi..pi)).collect()).collect();
        let y: Vec<f64> = x.iter().map(|p| ishigami(p)).collect();
        let names: Vec<String> = ["x1", "x2", "x3"].map(String::from).to_vec();
        let b = crate::analysis::stats::Bootstrap { resamples: 300, ..Default::default() };
        let small = with_intervals(&names, &x[..200], &y[..200], &b);
        let large = with_intervals(&names, &x, &y, &b);
        for (s, l) in small.iter().zip(&large) {
            assert!(l.lo.unwrap() <= l.first_order.unwrap() && l.first_order.unwrap() <= l.hi.unwrap());
            assert!(l.hi.unwrap() - l.lo.unwrap() < s.hi.unwrap() - s.lo.unwrap(), "{s:?} {l:?}");
        }
        // The true S2 = 0.4424 lies inside the large sample's interval (width about 0.08).
        assert!(large[1].lo.unwrap() < 0.4424 && 0.4424 < large[1].hi.unwrap(), "{:?}", large[1]);
        let (ok, why) = reliability(100, &ranked(small));
        assert!(!ok && why.contains("fewer than 50 per parameter"), "{why}");
        let only = large[..1].to_vec();
        let (ok, _) = reliability(1600, &ranked(large));
        assert!(ok);
        // One parameter explains whatever the sweep sees: no order to doubt, at any size.
        let (ok, why) = reliability(11, &only);
        assert!(ok && why.contains("the only swept parameter"), "{why}");
    }

    #[test]
    fn a_lattice_is_binned_by_value() {
        // y = a on a 5 × 5 lattice: all variance explained by a, none by b.
        let x: Vec<Vec<f64>> = (0..25).map(|i| vec![(i / 5) as f64, (i % 5) as f64]).collect();
        let y: Vec<f64> = x.iter().map(|p| p[0]).collect();
        let s = first_order(&["a".into(), "b".into()], &x, &y);
        assert_eq!(s[0].bins, 5);
        assert!((s[0].first_order.unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(s[1].first_order, Some(0.0));
    }

    #[test]
    fn a_small_continuous_sample_gets_sqrt_n_bins() {
        // 8 points, y = x: ⌈√8⌉ = 3 bins of 2–3 points; the bins explain most of the variance.
        let x: Vec<f64> = (0..8).map(|i| i as f64 * 0.37).collect();
        let (s, bins) = correlation_ratio(&x, &x);
        assert_eq!(bins, 3);
        assert!(s.unwrap() > 0.8, "{s:?}");
    }

    #[test]
    fn constant_output_or_tiny_sample_is_undefined() {
        assert_eq!(correlation_ratio(&[1.0, 2.0, 3.0, 4.0], &[0.0; 4]).0, None);
        assert_eq!(correlation_ratio(&[1.0, 2.0], &[0.0, 1.0]).0, None);
    }
}
