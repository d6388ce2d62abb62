//! The sequential design of `sweep adapt`: where the next batch of runs goes, and the
//! statistics a batch is judged by. Pure functions of points and numbers.
//!
//! **The statistics.** An adaptive design is not a uniform sample, so the sample statistics of
//! its runs are not those of the space. The four statistics of MFR are computed instead from the
//! noise-aware emulator ([`Emulator`]: each run's own SE as its noise) over [`DRAWS`]
//! scrambled-Halton points, with 95 % intervals from [`PATHS`] posterior sample paths
//! ([`Emulator::space_statistics`]); [`space_stats`] turns them into the [`SpaceStats`] the
//! convergence rule reads (the half-width of each posterior interval as the statistic's noise).
//!
//! **The criterion** (stepwise uncertainty reduction, Bect et al. 2012; Chevalier et al. 2014).
//! The answer a sweep gives is the four statistics; what the rule asks is that each be known to
//! within τ of its scale. So the next batch is chosen to minimise the expected posterior
//! variance of the statistics, each over its scale squared:
//!
//! J = Σ_s Var(L_s f) / scale_s² + Var(f(u*)) / std²,
//!
//! where L_s f = Σ_r w_{s,r} f(u_r) is statistic s linearised (the delta method) about the
//! emulator's mean surface on [`REFERENCE`] quasi-random points u_r, with w_{s,r} = ∂s/∂f(u_r)
//! times Φ(m_r/σ_r), the posterior probability that MFR is above its clamp at zero. The
//! derivatives are those of the mean, of S, of Pearson's 3·(mean − median)/S (the median's by a
//! Gaussian kernel of Silverman's bandwidth) and of m4/S⁴; the scales are the rule's
//! ([`crate::analysis::convergence::scale`]), so τ cancels. The last term is the recommended
//! setting: u* the reference point where the mean surface is highest, its MFR judged on the
//! scale of MFR's spread. For a Gaussian process the variance
//! after a new run at c with noise ν does not depend on what the run gives: adding c removes
//! cov(c, L_s)² / (var(c) + ν) from Var(L_s f), in closed form, for every candidate at once. A
//! batch is built greedily, each choice conditioned on the ones before as if they had been run
//! at the emulator's mean — the "kriging believer" of Ginsbourger, Le Riche & Carraro (2010),
//! which for a variance criterion is exact, since the mean is unchanged by such a run and the
//! variance never depended on its value. Where the statistics are already known this favours
//! the regions they are most sensitive to: the edge of the zero-MFR region (the median and the
//! skewness), the tails (std and kurtosis), and for the mean an integrated variance reduction
//! over the whole space (the IMSE design of Sacks, Welch, Mitchell & Wynn 1989).
//!
//! Half of each batch ([`EXPLORE`]) is placed for coverage instead (greedy maximin distance to
//! every point so far), the rest by the criterion conditioned on it: the criterion trusts the
//! emulator's uncertainty, which a stationary process fitted to a kinked surface misjudges in
//! places (BENCHMARKS.md "Designs against a known answer" measures the share). One run of each
//! batch of two or more ([`Split`]) goes where the emulator's mean plus one SD is highest (the
//! upper confidence bound of Srinivas, Krause, Kakade & Seeger 2010): the recommended setting
//! is a run, and the criterion's one term for it of five left it short of the best on some
//! seeds.
//!
//! Candidates are a fresh block of [`CANDIDATES`] scrambled-Halton points per batch (their own
//! stream, never a point twice), [`NEAR`] points within ±0.1 of the run the emulator ranks
//! best, clipped to the cube, and where the upper bound peaks from that run (Nelder–Mead within
//! the cube, as Bayesian optimisation maximises its acquisition), so that a best setting on a
//! face, an edge or in a corner can be reached.
//! Everything is seeded and sequential: the same points and results give the same batch.
//!
//! References: Bect, Ginsbourger, Li, Picheny & Vazquez (2012), Statistics and Computing 22,
//! 773–793; Chevalier, Bect, Ginsbourger, Vazquez, Picheny & Richet (2014), Technometrics 56,
//! 455–465; Ginsbourger, Le Riche & Carraro (2010), in Computational Intelligence in Expensive
//! Optimization Problems, 131–162; Sacks, Welch, Mitchell & Wynn (1989), Statistical Science 4,
//! 409–423; Loeppky, Sacks & Welch (2009), Technometrics 51, 366–376; Srinivas, Krause, Kakade
//! & Seeger (2010), ICML, 1015–1022.

use serde::Serialize;

use crate::analysis::convergence::{scale, SpaceStats};
use crate::analysis::emulator::{EmulatedStatistics, Emulator};
use crate::analysis::simplex::minimise;
use crate::analysis::stats::{moments, STATISTICS};
use crate::design::halton::{halton_range, Scrambling};

/// Mean-surface points for the statistics, and posterior paths for their intervals.
pub const DRAWS: usize = 4096;
pub const PATHS: usize = 200;
/// Points the criterion integrates over.
pub const REFERENCE: usize = 1024;
/// Fresh candidates per batch.
pub const CANDIDATES: usize = 1024;
/// The share of each batch placed for coverage (maximin) rather than by the criterion.
pub const EXPLORE: f64 = 0.5;

/// The runs of a batch of `size` placed for coverage.
pub fn explore_count(size: usize, share: f64) -> usize {
    ((size as f64 * share).floor() as usize).min(size)
}

/// How a batch is shared: the first `explore` runs for coverage, the next `exploit` where the
/// emulator's upper bound (mean + one SD) is highest, the rest by the criterion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Split {
    pub explore: usize,
    pub exploit: usize,
}

impl Split {
    /// A batch of `size` with `share` of it for coverage, and one run (in a batch of at least
    /// two) towards the best setting: the criterion's own term for the best setting is one of
    /// five, and on its own it left the recommended run short of the best on some seeds
    /// (BENCHMARKS.md "Designs against a known answer").
    pub fn of(size: usize, share: f64) -> Split {
        let explore = explore_count(size, share);
        Split { explore, exploit: usize::from(size >= 2 && explore < size) }
    }

    /// Every run by the criterion (for tests).
    pub const CRITERION: Split = Split { explore: 0, exploit: 0 };
}

/// Candidates near the best run, per batch, and how far from it they reach in the unit cube.
pub const NEAR: usize = 128;
const NEAR_REACH: f64 = 0.1;
const NEAR_STREAM: u64 = 3;

/// The candidates of batch `batch`: its block of the candidate stream ([`candidates`]), then
/// [`NEAR`] points within ±0.1 of the run the emulator ranks best among `existing`, clipped to
/// the cube (so a best setting on a face or in a corner is reached), then the upper bound's
/// peak from that run ([`upper_bound_peak`]).
pub fn batch_candidates(
    dim: usize,
    batch: usize,
    seed: u64,
    em: Option<&Emulator>,
    existing: &[Vec<f64>],
) -> Vec<Vec<f64>> {
    let mut cands = candidates(dim, batch, seed);
    let Some(best) = em.and_then(|em| em.rank(existing, 1).first().map(|r| existing[r.0].clone())) else {
        return cands;
    };
    let start = (batch * NEAR) as u64;
    for h in halton_range(dim, start, NEAR, Scrambling::Random, seed.wrapping_add(NEAR_STREAM)) {
        cands.push(
            best.iter().zip(&h).map(|(b, u)| (b + NEAR_REACH * (2.0 * u - 1.0)).clamp(0.0, 1.0)).collect(),
        );
    }
    if let Some(em) = em {
        cands.push(upper_bound_peak(em, &best));
    }
    cands
}

/// Where the emulator's upper bound (mean + one SD) peaks near `from`: Nelder–Mead within the
/// cube. A best setting on an edge or in a corner needs several coordinates at their bounds at
/// once, which random candidates near the best run seldom are (on the replayed LIGGGHTS surface
/// the best lies on an edge, and the runs of two seeds in six stopped one SE short of it).
fn upper_bound_peak(em: &Emulator, from: &[f64]) -> Vec<f64> {
    let negative_bound = |u: &[f64]| {
        let (m, s) = em.predict(u);
        -(m + s)
    };
    let into_cube = |p: &mut [f64]| p.iter_mut().for_each(|v| *v = v.clamp(0.0, 1.0));
    minimise(&negative_bound, from, NEAR_REACH, 100 * from.len(), &into_cube)
}
/// The quantities the criterion targets: the four statistics and the best setting's MFR.
const TARGETS: usize = 5;

/// Streams of the seeded Halton sequences, so that the first batch, the candidates, the
/// reference points and the statistics' points are different point sets.
const CANDIDATE_STREAM: u64 = 1;
const REFERENCE_STREAM: u64 = 2;

/// One run the criterion chose, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Choice {
    /// Unit coordinates.
    pub point: Vec<f64>,
    /// The emulator's MFR there and its SE, before the batch.
    pub mfr: f64,
    pub se: f64,
    /// The share of the criterion J (before the batch) this run is expected to remove.
    pub gain: f64,
    /// Its SE target as a multiple of the sweep's (one of [`SE_SCALES`]; 1 for runs placed for
    /// coverage or towards the best setting).
    pub se_scale: f64,
}

/// The emulator's statistics of a space and their intervals as the rule reads them; `None`
/// for both when no emulator could be fitted (too few points, no spread): a space the rule
/// never passes.
pub fn space_stats(n: usize, em: Option<&Emulator>, seed: u64) -> (SpaceStats, Option<EmulatedStatistics>) {
    let Some(em) = em else {
        let empty = moments(&[]);
        return (SpaceStats { n, moments: empty, noise: [None; 4] }, None);
    };
    let e = em.space_statistics(DRAWS, PATHS, seed);
    let noise = e.intervals.map(|i| i.lo.zip(i.hi).map(|(lo, hi)| (hi - lo) / 2.0));
    (SpaceStats { n, moments: e.statistics, noise }, Some(e))
}

/// The noise variance of a new run: the mean se² of the runs that record one, plus the
/// emulator's nugget.
pub fn new_run_noise(em: &Emulator, se: &[Option<f64>]) -> f64 {
    RunNoise::of(em, se, &[]).at(1.0)
}

/// The SE targets a run may be given when the criterion chooses each run's precision, as
/// multiples of the sweep's: its own, half and a quarter of it. Measured on the benchmark only
/// (`sweep bench designs --precision-per-run`): on the replayed thesis sweep it bought less than
/// every run at half the SE (BENCHMARKS.md "The answer's cost"), so `sweep adapt` runs every
/// point at the sweep's target.
pub const SE_SCALES: [f64; 3] = [1.0, 0.5, 0.25];

/// A new run's noise and cost at an SE target `scale` times the sweep's, and the scales it may
/// be given.
///
/// Its noise variance is `scale²` times the runs' own (the mean se² of the runs that record
/// one, each divided by the square of the scale it ran at) plus the emulator's nugget, which is
/// not the runs' and no longer window lowers. Its cost, in runs at the sweep's target, is
/// `w + (1 − w) / scale²`: the warm-up, a share `w` of a run at the sweep's target, is paid
/// whatever the target, and the window grows as 1/SE².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunNoise {
    pub measured: f64,
    pub nugget: f64,
    pub warmup_share: f64,
    /// The SE targets, as multiples of the sweep's, the criterion chooses each run's from
    /// (`[1.0]`: every run at the sweep's; [`SE_SCALES`]).
    pub scales: &'static [f64],
}

impl RunNoise {
    /// From the emulator, the runs' SEs and the scale of the SE target each ran at (absent:
    /// the sweep's own, 1); every new run at the sweep's target, so no cost to weigh.
    pub fn of(em: &Emulator, se: &[Option<f64>], scales: &[f64]) -> RunNoise {
        let s: Vec<f64> = se
            .iter()
            .enumerate()
            .filter_map(|(i, s)| Some((s.as_ref()? / scales.get(i).copied().unwrap_or(1.0)).powi(2)))
            .collect();
        let measured = if s.is_empty() { 0.0 } else { s.iter().sum::<f64>() / s.len() as f64 };
        RunNoise { measured, nugget: em.nugget_variance(), warmup_share: 1.0, scales: &[1.0] }
    }

    /// The noise variance of a new run at `scale` times the sweep's SE target.
    pub fn at(&self, scale: f64) -> f64 {
        scale * scale * self.measured + self.nugget
    }

    /// Its cost in runs at the sweep's target.
    pub fn cost(&self, scale: f64) -> f64 {
        self.warmup_share + (1.0 - self.warmup_share) / (scale * scale)
    }
}

/// The candidates of batch `batch` (0 is the first adaptive batch): their own block of the
/// candidate stream.
pub fn candidates(dim: usize, batch: usize, seed: u64) -> Vec<Vec<f64>> {
    let start = (batch * CANDIDATES) as u64;
    halton_range(dim, start, CANDIDATES, Scrambling::Random, seed.wrapping_add(CANDIDATE_STREAM))
}

/// The points the criterion integrates over.
pub fn reference(dim: usize, seed: u64) -> Vec<Vec<f64>> {
    halton_range(dim, 0, REFERENCE, Scrambling::Random, seed.wrapping_add(REFERENCE_STREAM))
}

fn std_normal_cdf(x: f64) -> f64 {
    0.5 * statrs::function::erf::erfc(-x / std::f64::consts::SQRT_2)
}

/// ∂s/∂f(u_r) of mean, std, Pearson skewness and kurtosis at the values `f`; `None` when S = 0.
fn gradients(f: &[f64]) -> Option<[Vec<f64>; 4]> {
    let mo = moments(f);
    let (m, s, med, p, k) = (mo.mean?, mo.std?, mo.median?, mo.skewness?, mo.kurtosis?);
    let n = f.len() as f64;
    let m3 = f.iter().map(|v| (v - m).powi(3)).sum::<f64>() / n;
    let h = 1.06 * s * n.powf(-0.2);
    let kern: Vec<f64> = f.iter().map(|v| (-0.5 * ((v - med) / h).powi(2)).exp()).collect();
    let ksum: f64 = kern.iter().sum::<f64>().max(f64::MIN_POSITIVE);
    let d_mean = vec![1.0 / n; f.len()];
    let d_std: Vec<f64> = f.iter().map(|v| (v - m) / (n * s)).collect();
    let d_skew: Vec<f64> =
        (0..f.len()).map(|r| 3.0 * (1.0 / n - kern[r] / ksum) / s - p * d_std[r] / s).collect();
    let d_kurt: Vec<f64> = (0..f.len())
        .map(|r| 4.0 * ((f[r] - m).powi(3) - m3) / (n * s.powi(4)) - 4.0 * k * d_std[r] / s)
        .collect();
    Some([d_mean, d_std, d_skew, d_kurt])
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The next `size` runs among `cands` by the criterion (module docs), with `noise` a new run's
/// noise and cost; and J before the batch. `None` when the statistics are undefined (the
/// emulator's surface has no spread).
///
/// The first `split.explore` runs of the batch are placed for coverage instead, each the
/// candidate farthest from the points so far (`existing` and the batch's: greedy maximin); the
/// next `split.exploit` where the emulator's mean plus its SD (conditioned on the runs chosen
/// before, whose values it believes) is highest; both at the sweep's SE target. The rest go by
/// the criterion, conditioned on them: each the candidate and SE target among `noise.scales`
/// (scales of the sweep's target) that remove the most of J per unit of cost. A quieter run costs more
/// and removes more, most where the emulator already knows the surface well and a run's own
/// noise is what is left; where it knows little, a run at the sweep's target removes nearly as
/// much for less (`noise.scales = [1.0]`: every run at the sweep's target).
pub fn next_batch(
    em: &Emulator,
    noise: &RunNoise,
    cands: &[Vec<f64>],
    refs: &[Vec<f64>],
    existing: &[Vec<f64>],
    size: usize,
    split: Split,
) -> Option<(Vec<Choice>, f64)> {
    let pred: Vec<(f64, f64)> = refs.iter().map(|u| em.predict(u)).collect();
    let f: Vec<f64> = pred.iter().map(|p| p.0.max(0.0)).collect();
    let mo = moments(&f);
    let grads = gradients(&f)?;
    // Weights of the linearised statistics, each over its scale (τ cancels in the argmax).
    let mut w: Vec<Vec<f64>> = STATISTICS
        .iter()
        .zip(&grads)
        .map(|(s, g)| {
            let sc = scale(*s, &mo).filter(|v| *v > 0.0).unwrap_or(1.0);
            g.iter()
                .zip(&pred)
                .map(|(g, (m, sd))| {
                    let above = if *sd > 0.0 { std_normal_cdf(m / sd) } else { f64::from(*m > 0.0) };
                    g * above / sc
                })
                .collect()
        })
        .collect();
    // The recommended setting's MFR, over the std (the mean's scale where MFR is spread).
    let (top, _) = f.iter().enumerate().fold((0, f64::MIN), |a, (i, v)| if *v > a.1 { (i, *v) } else { a });
    let mut at_best = vec![0.0; refs.len()];
    at_best[top] = 1.0 / mo.std.filter(|s| *s > 0.0).unwrap_or(1.0);
    w.push(at_best);
    let vr: Vec<Vec<f64>> = refs.iter().map(|u| em.whitened(u)).collect();
    let n = vr.first().map_or(0, |v| v.len());
    // a_s = Σ_r w_sr L⁻¹k_r, and Var(L_s) = Σ_rr' w w k(r, r') − a_s·a_s.
    let a: Vec<Vec<f64>> = w
        .iter()
        .map(|ws| {
            let mut acc = vec![0.0; n];
            for (wr, v) in ws.iter().zip(&vr) {
                for (x, y) in acc.iter_mut().zip(v) {
                    *x += wr * y;
                }
            }
            acc
        })
        .collect();
    let mut var_l = [0.0f64; TARGETS];
    for i in 0..refs.len() {
        for j in 0..=i {
            let k = em.prior_cov(&refs[i], &refs[j]);
            let twice = if i == j { 1.0 } else { 2.0 };
            for s in 0..TARGETS {
                var_l[s] += twice * w[s][i] * w[s][j] * k;
            }
        }
    }
    for s in 0..TARGETS {
        var_l[s] = (var_l[s] - dot(&a[s], &a[s])).max(0.0);
    }
    let before: f64 = var_l.iter().sum();
    // Per candidate: its whitened vector, posterior variance and covariance with each L_s.
    let vc: Vec<Vec<f64>> = cands.iter().map(|u| em.whitened(u)).collect();
    let mut var_c: Vec<f64> =
        cands.iter().zip(&vc).map(|(u, v)| (em.prior_cov(u, u) - dot(v, v)).max(0.0)).collect();
    let mean_c: Vec<f64> = cands.iter().map(|u| em.mean(u)).collect();
    let mut cov_cl: Vec<[f64; TARGETS]> = cands
        .iter()
        .zip(&vc)
        .map(|(u, v)| {
            let mut out = [0.0; TARGETS];
            for (r, ur) in refs.iter().enumerate() {
                let k = em.prior_cov(u, ur);
                for s in 0..TARGETS {
                    out[s] += w[s][r] * k;
                }
            }
            for s in 0..TARGETS {
                out[s] -= dot(v, &a[s]);
            }
            out
        })
        .collect();
    let mut updates: Vec<Vec<f64>> = Vec::new();
    let mut taken = vec![false; cands.len()];
    let mut chosen = Vec::new();
    let d2 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
    let mut nearest: Vec<f64> =
        cands.iter().map(|c| existing.iter().map(|e| d2(c, e)).fold(f64::INFINITY, f64::min)).collect();
    for step in 0..size.min(cands.len()) {
        let by_criterion = step >= split.explore + split.exploit;
        let gain = |c: usize, scale: f64| {
            cov_cl[c].iter().map(|x| x * x).sum::<f64>() / (var_c[c] + noise.at(scale)).max(1e-300)
        };
        // The best scale for a candidate, and its score: the gain per cost by the criterion,
        // else the coverage or upper-bound score at the sweep's target.
        // The SE target that removes the most of J per unit of cost at candidate c, and that.
        let best_scale = |c: usize| -> (f64, f64) {
            noise.scales.iter().fold((1.0, f64::MIN), |b, &sc| {
                let v = gain(c, sc) / noise.cost(sc);
                if v > b.1 {
                    (sc, v)
                } else {
                    b
                }
            })
        };
        let score = |c: usize| {
            if step < split.explore {
                nearest[c]
            } else if !by_criterion {
                mean_c[c] + var_c[c].sqrt()
            } else {
                best_scale(c).1
            }
        };
        let Some(best) = (0..cands.len())
            .filter(|&c| !taken[c])
            .fold(None, |b: Option<(usize, f64)>, c| match b {
                Some((_, g)) if g >= score(c) => b,
                _ => Some((c, score(c))),
            })
            .map(|(c, _)| c)
        else {
            break;
        };
        let scale = if by_criterion { best_scale(best).0 } else { 1.0 };
        for (c, n) in nearest.iter_mut().enumerate() {
            *n = n.min(d2(&cands[c], &cands[best]));
        }
        let g = gain(best, scale);
        let (m, sd) = em.predict(&cands[best]);
        chosen.push(Choice {
            point: cands[best].clone(),
            mfr: m,
            se: sd,
            gain: if before > 0.0 { g / before } else { 0.0 },
            se_scale: scale,
        });
        taken[best] = true;
        // Condition on the chosen run: a rank-one update of every candidate's variance and
        // covariances.
        let denom = (var_c[best] + noise.at(scale)).max(1e-300).sqrt();
        let u: Vec<f64> = (0..cands.len())
            .map(|c| {
                let prior = em.prior_cov(&cands[c], &cands[best]) - dot(&vc[c], &vc[best]);
                let earlier: f64 = updates.iter().map(|up| up[c] * up[best]).sum();
                (prior - earlier) / denom
            })
            .collect();
        let lb: [f64; TARGETS] = cov_cl[best].map(|x| x / denom);
        for c in 0..cands.len() {
            var_c[c] = (var_c[c] - u[c] * u[c]).max(0.0);
            for s in 0..TARGETS {
                cov_cl[c][s] -= u[c] * lb[s];
            }
        }
        updates.push(u);
    }
    Some((chosen, before))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs whose noise variance is 1e-4 and whose warm-up is free.
    const NOISE: RunNoise = RunNoise { measured: 1e-4, nugget: 0.0, warmup_share: 0.0, scales: &[1.0] };

    /// A kinked surface like MFR's: zero over part of the square, rising beyond.
    fn kinked(u: &[f64]) -> f64 {
        (u[0] + 0.5 * u[1] - 0.5).max(0.0)
    }

    fn fitted(n: usize) -> (Vec<Vec<f64>>, Emulator) {
        let x = crate::design::halton::halton(2, n, Scrambling::Random, 3);
        let y: Vec<f64> = x.iter().map(|u| kinked(u)).collect();
        let e = Emulator::fit(&x, &y, &vec![Some(0.01); n]).unwrap();
        (x, e)
    }

    #[test]
    fn gradients_match_finite_differences() {
        let f: Vec<f64> = (0..50).map(|i| ((i * 37 % 50) as f64 / 50.0).powi(2)).collect();
        let g = gradients(&f).unwrap();
        let h = 1e-6;
        for r in [3, 17, 40] {
            let mut up = f.clone();
            up[r] += h;
            let (a, b) = (moments(&f), moments(&up));
            let fd_mean = (b.mean.unwrap() - a.mean.unwrap()) / h;
            let fd_std = (b.std.unwrap() - a.std.unwrap()) / h;
            let fd_kurt = (b.kurtosis.unwrap() - a.kurtosis.unwrap()) / h;
            assert!((fd_mean - g[0][r]).abs() < 1e-6, "{fd_mean} {}", g[0][r]);
            assert!((fd_std - g[1][r]).abs() < 1e-5, "{fd_std} {}", g[1][r]);
            assert!((fd_kurt - g[3][r]).abs() < 1e-3 * fd_kurt.abs().max(1.0), "{fd_kurt} {}", g[3][r]);
        }
    }

    #[test]
    fn a_batch_is_reproducible_distinct_and_starts_where_the_spread_is_decided() {
        let (_, e) = fitted(20);
        let c = candidates(2, 0, 14);
        let r = reference(2, 14);
        let (a, before) = next_batch(&e, &NOISE, &c, &r, &[], 6, Split::CRITERION).unwrap();
        let (b, _) = next_batch(&e, &NOISE, &c, &r, &[], 6, Split::CRITERION).unwrap();
        assert_eq!(a, b);
        assert!(before > 0.0);
        assert_eq!(a.len(), 6);
        for i in 0..a.len() {
            for j in 0..i {
                assert_ne!(a[i].point, a[j].point);
            }
        }
        // Each removes a part of the criterion, and together less than all of it (the runs
        // are noisy).
        assert!(a.iter().all(|c| c.gain > 0.0), "{a:?}");
        assert!(a.iter().map(|c| c.gain).sum::<f64>() < 1.0);
        // The first goes where the kinked surface is highest, which sets its spread.
        assert!(a[0].point[0] + 0.5 * a[0].point[1] > 1.0, "{a:?}");
    }

    #[test]
    fn one_run_goes_where_the_upper_bound_is_highest_among_candidates_and_its_peak_near_the_best_run() {
        assert_eq!(Split::of(20, 0.5), Split { explore: 10, exploit: 1 });
        assert_eq!(Split::of(2, 0.5), Split { explore: 1, exploit: 1 });
        assert_eq!(Split::of(1, 0.5), Split { explore: 0, exploit: 0 });
        let (x, e) = fitted(20);
        let c = batch_candidates(2, 0, 14, Some(&e), &x);
        assert_eq!(c.len(), CANDIDATES + NEAR + 1);
        assert_eq!(batch_candidates(2, 0, 14, None, &x).len(), CANDIDATES);
        let best = &x[e.rank(&x, 1)[0].0];
        for u in &c[CANDIDATES..CANDIDATES + NEAR] {
            for (a, b) in u.iter().zip(best) {
                assert!((a - b).abs() <= NEAR_REACH + 1e-12 && (0.0..=1.0).contains(a), "{u:?} {best:?}");
            }
        }
        let r = reference(2, 14);
        let (batch, _) = next_batch(&e, &NOISE, &c, &r, &x, 3, Split { explore: 0, exploit: 1 }).unwrap();
        let ucb = |u: &[f64]| {
            let (m, sd) = e.predict(u);
            m + sd
        };
        // The last candidate is the upper bound's peak from the best run: in the corner (1, 1)
        // where the kinked surface is highest, beyond the reach of the random ones.
        let peak = &c[CANDIDATES + NEAR];
        assert!(ucb(peak) >= ucb(best), "{peak:?} {best:?}");
        assert!(peak.iter().all(|v| *v > 0.999 && *v <= 1.0), "{peak:?} from {best:?}");
        assert!(
            best.iter().any(|v| *v < 1.0 - NEAR_REACH),
            "the best run {best:?} is in reach of the corner already"
        );
        let top = c.iter().map(|u| ucb(u)).fold(f64::MIN, f64::max);
        assert!((ucb(&batch[0].point) - top).abs() < 1e-9 * top.abs().max(1.0), "{batch:?}");
        // The kinked surface is highest in the corner u = (1, 1).
        assert!(batch[0].point[0] + 0.5 * batch[0].point[1] > 1.2, "{batch:?}");
    }

    #[test]
    fn a_run_s_noise_and_cost_follow_its_se_target() {
        let (_, e) = fitted(20);
        // Two runs, one at the sweep's target and one at half of it: each brought back to the
        // sweep's target, both 0.02.
        let n = RunNoise {
            warmup_share: 0.73,
            ..RunNoise::of(&e, &[Some(0.02), Some(0.01), None], &[1.0, 0.5, 1.0])
        };
        assert!((n.measured - 4e-4).abs() < 1e-15, "{n:?}");
        assert!((n.at(0.5) - (1e-4 + e.nugget_variance())).abs() < 1e-15);
        // The warm-up is paid at any target, the window grows as 1/SE².
        assert!((n.cost(1.0) - 1.0).abs() < 1e-15);
        assert!((n.cost(0.25) - (0.73 + 0.27 * 16.0)).abs() < 1e-12);
    }

    #[test]
    fn a_quieter_run_is_chosen_only_where_a_run_s_own_noise_is_most_of_what_is_not_known() {
        let (x, e) = fitted(16);
        let scales_of = |measured: f64, scales: &'static [f64]| {
            let noise = RunNoise { measured, nugget: 0.0, warmup_share: 0.73, scales };
            let (c, r) = (candidates(2, 0, 14), reference(2, 14));
            let (b, _) = next_batch(&e, &noise, &c, &r, &x, 4, Split::CRITERION).unwrap();
            b.iter().map(|c| c.se_scale).collect::<Vec<f64>>()
        };
        // Runs far quieter than the emulator is unsure: a quieter run removes hardly more, for
        // five times the cost.
        assert_eq!(scales_of(1e-8, &SE_SCALES), vec![1.0; 4]);
        // Runs far noisier: their noise is what is left, and only a quieter run lowers it.
        assert_eq!(scales_of(1.0, &SE_SCALES), vec![0.25; 4]);
        // With one scale to choose from, every run is at it.
        assert_eq!(scales_of(1.0, &[1.0]), vec![1.0; 4]);
    }

    #[test]
    fn the_criterion_shrinks_when_the_chosen_runs_are_added() {
        // Run the chosen batch for real and refit: J falls by more than it would for as many
        // candidates taken in stream order (a space-filling batch of the same size).
        let (x, e) = fitted(16);
        let c = candidates(2, 0, 14);
        let r = reference(2, 14);
        let (batch, before) = next_batch(&e, &NOISE, &c, &r, &x, 8, Split::CRITERION).unwrap();
        let after = |extra: Vec<Vec<f64>>| {
            let mut xs = x.clone();
            xs.extend(extra);
            let y: Vec<f64> = xs.iter().map(|u| kinked(u)).collect();
            let e2 = Emulator::fit(&xs, &y, &vec![Some(0.01); xs.len()]).unwrap();
            next_batch(&e2, &NOISE, &c, &r, &xs, 1, Split::CRITERION).unwrap().1
        };
        let chosen = after(batch.iter().map(|c| c.point.clone()).collect());
        let plain = after(c[..8].to_vec());
        assert!(chosen < before, "{chosen} vs {before}");
        assert!(chosen < plain, "chosen {chosen} vs in stream order {plain}");
    }
}
