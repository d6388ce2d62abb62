//! Weighted statistics of a space: lattice points as a quadrature rule, and the bootstrap of
//! weighted statistics (docs/statistics.md "The statistics of a space").
//!
//! A lattice with its endpoints is not a uniform sample of the box: every face carries full
//! weight. The statistics the sweep asks for are integrals over the box, so a lattice point is
//! weighted by the trapezoid rule, ½ for each coordinate on a face of the box
//! ([`LatticeWeights::Trapezoid`], the default). `lattice_weights = "equal"` gives every point
//! the same weight, as the thesis did. An LDS prefix is a uniform sample: equal weights.
//!
//! Not responsible for which points are in a space or which runs failed (the caller drops
//! failed runs' weights along with their values).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::analysis::stats::{Bootstrap, Interval, Moments, STATISTICS};

/// How a complete lattice's points are weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LatticeWeights {
    /// ½ per coordinate on a face of the box (the trapezoid rule; the default).
    Trapezoid,
    /// Every point alike (the thesis).
    Equal,
}

impl LatticeWeights {
    pub fn parse(s: &str) -> Option<LatticeWeights> {
        match s {
            "trapezoid" => Some(LatticeWeights::Trapezoid),
            "equal" => Some(LatticeWeights::Equal),
            _ => None,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            LatticeWeights::Trapezoid => "trapezoid",
            LatticeWeights::Equal => "equal",
        }
    }
}

/// Trapezoid weights of a space's points (`values[i][j]`: point i, parameter j) when they form
/// a complete tensor lattice (the product of the distinct values per dimension is the point
/// count, each combination once); `None` otherwise (an LDS prefix: equal weights). A point's
/// weight is ½ for each coordinate at the smallest or largest of that dimension's values.
pub fn trapezoid(values: &[Vec<f64>]) -> Option<Vec<f64>> {
    let n = values.len();
    let d = values.first()?.len();
    let mut ends = Vec::with_capacity(d);
    let mut cells = 1usize;
    for j in 0..d {
        let mut col: Vec<f64> = values.iter().map(|p| p[j]).collect();
        col.sort_by(f64::total_cmp);
        col.dedup();
        cells = cells.checked_mul(col.len())?;
        // One value (a level of 1) is no face: the dimension is not integrated.
        ends.push((col.len() > 1).then(|| (col[0], col[col.len() - 1])));
    }
    if cells != n {
        return None;
    }
    let mut keys: Vec<Vec<u64>> = values.iter().map(|p| p.iter().map(|v| v.to_bits()).collect()).collect();
    keys.sort();
    keys.dedup();
    if keys.len() != n {
        return None;
    }
    Some(
        values
            .iter()
            .map(|p| {
                p.iter()
                    .zip(&ends)
                    .map(|(v, e)| match e {
                        Some((lo, hi)) if v == lo || v == hi => 0.5,
                        _ => 1.0,
                    })
                    .product()
            })
            .collect(),
    )
}

/// The statistics of `x` with weights `w` (positive; `None` = equal). The same definitions as
/// [`crate::analysis::stats::moments`] with every sum weighted and divided by Σw; the median is the
/// weighted one (the value where the cumulative weight reaches half, the mean of the two
/// neighbours when it lands exactly on half, so equal weights give the usual median).
pub fn moments(x: &[f64], w: Option<&[f64]>) -> Moments {
    let Some(w) = w else {
        return crate::analysis::stats::moments(x);
    };
    let n = x.len();
    let total: f64 = w.iter().sum();
    if n == 0 || total <= 0.0 {
        return crate::analysis::stats::moments(&[]);
    }
    let mean = x.iter().zip(w).map(|(v, w)| v * w).sum::<f64>() / total;
    let central = |p: i32| x.iter().zip(w).map(|(v, w)| w * (v - mean).powi(p)).sum::<f64>() / total;
    let std = central(2).max(0.0).sqrt();
    let median = weighted_median(x, w, total);
    let scale = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let constant = std <= 1e-12 * scale || std == 0.0;
    let (skewness, kurtosis, moment_skewness) = if constant {
        (None, None, None)
    } else {
        (Some(3.0 * (mean - median) / std), Some(central(4) / std.powi(4)), Some(central(3) / std.powi(3)))
    };
    Moments { n, mean: Some(mean), std: Some(std), skewness, kurtosis, moment_skewness, median: Some(median) }
}

fn weighted_median(x: &[f64], w: &[f64], total: f64) -> f64 {
    let mut order: Vec<usize> = (0..x.len()).collect();
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let half = total / 2.0;
    let mut cum = 0.0;
    for (k, &i) in order.iter().enumerate() {
        cum += w[i];
        if (cum - half).abs() <= 1e-12 * total {
            return order.get(k + 1).map_or(x[i], |&j| 0.5 * (x[i] + x[j]));
        }
        if cum > half {
            return x[i];
        }
    }
    x[order[order.len() - 1]]
}

/// Percentile bootstrap intervals of the four [`STATISTICS`] of `x` with weights `w`: each
/// resample draws N points with replacement, each keeping its weight, and computes the weighted
/// statistics. Equal weights give exactly [`crate::analysis::stats::bootstrap`]'s intervals.
pub fn bootstrap(x: &[f64], w: Option<&[f64]>, b: &Bootstrap) -> [Interval; 4] {
    let Some(w) = w else {
        return crate::analysis::stats::bootstrap(x, b);
    };
    let n = x.len();
    if n < 2 || b.resamples == 0 {
        return [Interval::UNDEFINED; 4];
    }
    let mut rng = ChaCha8Rng::seed_from_u64(b.seed);
    let mut draws: [Vec<f64>; 4] = Default::default();
    let (mut xs, mut ws) = (vec![0.0; n], vec![0.0; n]);
    for _ in 0..b.resamples {
        for k in 0..n {
            let i = rng.gen_range(0..n);
            xs[k] = x[i];
            ws[k] = w[i];
        }
        let m = moments(&xs, Some(&ws));
        for (d, stat) in draws.iter_mut().zip(STATISTICS) {
            if let Some(v) = stat.of(&m) {
                d.push(v);
            }
        }
    }
    crate::analysis::stats::percentile_intervals(draws, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(levels: &[usize]) -> Vec<Vec<f64>> {
        let mut pts = vec![vec![]];
        for &l in levels {
            pts = pts
                .into_iter()
                .flat_map(|p| {
                    (0..l).map(move |k| {
                        let mut q = p.clone();
                        q.push(if l == 1 { 0.5 } else { k as f64 / (l - 1) as f64 });
                        q
                    })
                })
                .collect();
        }
        pts
    }

    #[test]
    fn trapezoid_weights_of_a_3_by_3_lattice() {
        // Corners ¼, edge midpoints ½, the centre 1: Σw = 4 = (3 − 1)², the box's area in cells.
        let w = trapezoid(&grid(&[3, 3])).unwrap();
        assert_eq!(w, vec![0.25, 0.5, 0.25, 0.5, 1.0, 0.5, 0.25, 0.5, 0.25]);
    }

    #[test]
    fn a_non_lattice_or_an_incomplete_one_gets_no_weights() {
        let mut g = grid(&[3, 3]);
        g.pop();
        assert_eq!(trapezoid(&g), None);
        let lds: Vec<Vec<f64>> = (0..9).map(|i| vec![i as f64 * 0.1, (i * 7 % 9) as f64]).collect();
        assert_eq!(trapezoid(&lds), None);
        // A duplicated point with a missing one has the right count but is no lattice.
        let mut dup = grid(&[2, 2]);
        dup[3] = dup[0].clone();
        assert_eq!(trapezoid(&dup), None);
    }

    #[test]
    fn trapezoid_integrates_a_linear_function_exactly_where_equal_weights_do_too_but_not_x_squared() {
        // ∫₀¹ x² dx = 1/3. On 5 points: equal weights give (0 + 1/16 + 1/4 + 9/16 + 1)/5 = 0.375;
        // the trapezoid (½·0 + 1/16 + 1/4 + 9/16 + ½·1)/4 = 0.34375.
        let g = grid(&[5]);
        let y: Vec<f64> = g.iter().map(|p| p[0] * p[0]).collect();
        let w = trapezoid(&g).unwrap();
        assert!((moments(&y, Some(&w)).mean.unwrap() - 0.34375).abs() < 1e-15);
        assert!((moments(&y, None).mean.unwrap() - 0.375).abs() < 1e-15);
    }

    #[test]
    fn equal_weights_reproduce_the_unweighted_statistics_and_bootstrap() {
        let x: Vec<f64> = (0..40).map(|i| ((i * 13) % 17) as f64 * 0.1 + (i as f64 * 0.3).sin()).collect();
        let ones = vec![2.0; x.len()];
        let (a, b) = (moments(&x, Some(&ones)), crate::analysis::stats::moments(&x));
        for s in STATISTICS {
            assert!((s.of(&a).unwrap() - s.of(&b).unwrap()).abs() < 1e-12, "{}", s.name());
        }
        assert_eq!(a.median, b.median);
        let boot = Bootstrap { resamples: 200, ..Bootstrap::default() };
        let (ia, ib) = (bootstrap(&x, Some(&ones), &boot), crate::analysis::stats::bootstrap(&x, &boot));
        for (p, q) in ia.iter().zip(ib) {
            assert!(
                (p.lo.unwrap() - q.lo.unwrap()).abs() < 1e-12
                    && (p.hi.unwrap() - q.hi.unwrap()).abs() < 1e-12
            );
        }
    }

    #[test]
    fn weighted_median_by_hand() {
        // Values 1, 2, 3 with weights 1, 1, 3: half the weight (2.5) is reached at 3.
        assert_eq!(moments(&[1.0, 2.0, 3.0], Some(&[1.0, 1.0, 3.0])).median, Some(3.0));
        // Weights 1, 1, 2: the cumulative weight hits 2 = half exactly at 2 → (2 + 3)/2.
        assert_eq!(moments(&[1.0, 2.0, 3.0], Some(&[1.0, 1.0, 2.0])).median, Some(2.5));
    }
}
