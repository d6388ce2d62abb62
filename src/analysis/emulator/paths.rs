//! The space's statistics from the emulator with their posterior intervals: the mean surface on
//! many points, and posterior sample paths on a sub-design for each statistic's shift.

use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Serialize;

use crate::analysis::stats::{percentile_sorted, Interval, Moments, STATISTICS};

use super::{dist, factor, matern52, Emulator};

/// Points of the sub-design the posterior sample paths are drawn on. Each path's statistic on
/// these points carries a sampling error of its own that widens the intervals: on the replayed
/// LIGGGHTS sweep at 240 adaptive runs the skewness's 95 % half-width was 2.1–2.5 times the
/// rule's tolerance on 256 points, 1.6–1.8 on 1,024 and 1.3–1.7 on 2,048 (at a quarter of the
/// runs' noise: 1.8–2.1, 0.9–1.1, 0.8–1.0), so that on 256 no noise level let the rule hold
/// (BENCHMARKS.md "The answer's cost"). Its cost: a square matrix this size factored (about
/// 0.2 s in blocks, `cholesky`), and the runs' factor solved against this many points.
pub const PATH_POINTS: usize = 2048;

/// The space's statistics from the emulator, with 95 % intervals from its posterior.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EmulatedStatistics {
    /// Points of the design the mean surface was evaluated on (scrambled Halton).
    pub draws: usize,
    /// Posterior sample paths behind the intervals.
    pub paths: usize,
    /// Mean, std, skewness and kurtosis: posterior medians ([`Emulator::space_statistics`]);
    /// `n`, `median` and `moment_skewness`: the mean surface's.
    pub statistics: Moments,
    /// Intervals of mean, std, skewness, kurtosis.
    pub intervals: [Interval; 4],
}

impl Emulator {
    /// The space's MFR statistics from the emulator, each the posterior median of the statistic
    /// with its 95 % posterior interval. The mean surface, clamped at 0 (MFR cannot be
    /// negative), is evaluated on `draws` scrambled-Halton points of the unit cube; `paths`
    /// posterior sample paths on the first [`PATH_POINTS`] of them give each statistic's shift
    /// from the mean surface's on the same points; the estimate is the mean surface's statistic
    /// plus the median shift, the interval plus the 2.5 and 97.5 % shifts.
    ///
    /// Why the median shift: a statistic of the mean surface is not the mean of that statistic
    /// over the functions the emulator deems possible. The mean surface is smoother than any of
    /// them, so its spread is smaller and its skewness another (a sample path's std is larger,
    /// nearly always); the plain plug-in value can lie outside the posterior's own interval.
    pub fn space_statistics(&self, draws: usize, paths: usize, seed: u64) -> EmulatedStatistics {
        let d = self.x[0].len();
        let pts = crate::design::halton::halton(d, draws, crate::design::halton::Scrambling::Random, seed);
        let surface: Vec<f64> = pts.iter().map(|u| self.mean(u).max(0.0)).collect();
        let statistics = crate::analysis::stats::moments(&surface);
        let m = pts.len().min(PATH_POINTS);
        let sub = &pts[..m];
        let n = self.n();
        // Posterior covariance on the sub-design: K** − VᵀV, V = L⁻¹K*.
        let mut v =
            DMatrix::from_fn(n, m, |i, j| self.sigma2 * matern52(dist(&self.x[i], &sub[j], &self.theta)));
        super::cholesky::solve_lower(self.chol.l_dirty(), &mut v);
        // As a product of the transpose (a blocked matrix product), not `tr_mul`'s dot per entry.
        let vtv = v.transpose() * &v;
        let mut cov = DMatrix::from_fn(m, m, |i, j| {
            self.sigma2 * matern52(dist(&sub[i], &sub[j], &self.theta)) - vtv[(i, j)]
        });
        for i in 0..m {
            cov[(i, i)] += 1e-10 * self.sigma2;
        }
        let mut jitter = 1e-8 * self.sigma2;
        let mut chol = factor(cov.clone());
        while chol.is_none() && jitter < self.sigma2 {
            for i in 0..m {
                cov[(i, i)] += jitter;
            }
            jitter *= 10.0;
            chol = factor(cov.clone());
        }
        let mean_sub: Vec<f64> = sub.iter().map(|u| self.mean(u)).collect();
        let base = crate::analysis::stats::moments(&mean_sub.iter().map(|v| v.max(0.0)).collect::<Vec<_>>());
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
        let mut shifts: [Vec<f64>; 4] = Default::default();
        if let Some(chol) = chol {
            // Every path's deviates at once: one matrix product.
            let e = DMatrix::from_iterator(m, paths, (&mut rng).sample_iter(StandardNormal).take(m * paths));
            let deviations = chol.unpack() * e;
            for c in deviations.column_iter() {
                let path: Vec<f64> = mean_sub
                    .iter()
                    .zip(c.iter())
                    .map(|(mean, c)| (mean + self.y_scale * c).max(0.0))
                    .collect();
                let pm = crate::analysis::stats::moments(&path);
                for (sh, s) in shifts.iter_mut().zip(STATISTICS) {
                    if let (Some(a), Some(b)) = (s.of(&pm), s.of(&base)) {
                        sh.push(a - b);
                    }
                }
            }
        }
        let mut statistics = statistics;
        let mut intervals = [Interval::UNDEFINED; 4];
        for (k, s) in STATISTICS.iter().enumerate() {
            let (Some(est), true) = (s.of(&statistics), shifts[k].len() * 2 >= paths.max(1)) else {
                continue;
            };
            let mut d = shifts[k].clone();
            d.sort_by(f64::total_cmp);
            intervals[k] = Interval {
                lo: Some(est + percentile_sorted(&d, 0.025)),
                hi: Some(est + percentile_sorted(&d, 0.975)),
            };
            s.set(&mut statistics, est + percentile_sorted(&d, 0.5));
        }
        EmulatedStatistics { draws: pts.len(), paths, statistics, intervals }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_statistic_of_the_emulator_lies_in_its_own_interval() {
        // The demo sweep's 8 points on LIGGGHTS (sweeps/quick.toml: gap and blade speed in unit
        // coordinates, MFR, its SE). The mean surface's Pearson skewness, 1.19, lay outside the
        // paths' interval [-0.28, 0.99]: every path is rougher than the mean surface.
        let runs = [
            (0.31923482249892476, 0.16267685641463192, 0.1115797051520569, 0.005116580288270625),
            (0.8192348224989248, 0.829343523081299, 0.08453892701638249, 0.00498966590361551),
            (0.06923482249892476, 0.4960101897479652, 0.06623452369797514, 0.004749229670148622),
            (0.5692348224989248, 0.2737879675257432, 0.1094633186292546, 0.005405857262166251),
            (0.44423482249892476, 0.9404546341924097, 0.08271334327518778, 0.003222597789942424),
            (0.9442348224989248, 0.6071213008590765, 0.08911701089440595, 0.0046887457485056),
            (0.19423482249892476, 0.05156574530352065, 0.09382351145288374, 0.004767585027339706),
            (0.6942348224989248, 0.7182324119701877, 0.08386850550877369, 0.004911592526399557),
        ];
        let x: Vec<Vec<f64>> = runs.iter().map(|r| vec![r.0, r.1]).collect();
        let y: Vec<f64> = runs.iter().map(|r| r.2).collect();
        let se: Vec<Option<f64>> = runs.iter().map(|r| Some(r.3)).collect();
        let e = Emulator::fit(&x, &y, &se).unwrap();
        let s = e.space_statistics(4096, 200, 14);
        for (k, st) in STATISTICS.iter().enumerate() {
            let (v, iv) = (st.of(&s.statistics).unwrap(), s.intervals[k]);
            assert!(iv.lo.unwrap() <= v && v <= iv.hi.unwrap(), "{}: {v} {iv:?}", st.name());
        }
        // The case this guards: the plain skewness of the mean surface misses the interval.
        let pts = crate::design::halton::halton(2, 4096, crate::design::halton::Scrambling::Random, 14);
        let plain =
            crate::analysis::stats::moments(&pts.iter().map(|u| e.predict(u).0.max(0.0)).collect::<Vec<_>>());
        let (p, iv) = (plain.skewness.unwrap(), s.intervals[2]);
        assert!(p > iv.hi.unwrap(), "plain skewness {p} inside {iv:?}: the test shows nothing");
    }
}
