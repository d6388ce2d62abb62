//! Calibration of a model's free parameters against measured targets (`sweep calibrate`): the
//! posterior over the parameters, how well the targets identify each, where the next runs go,
//! and when the posterior has stopped shrinking. Pure functions of emulators and numbers.
//!
//! **The posterior** (Bayesian calibration with a Gaussian-process emulator, Kennedy & O'Hagan
//! 2001; the emulator's own variance in the likelihood as in Higdon et al. 2004). Each target k
//! (a measured value y_k ± σ_k, e.g. an angle of repose of 34.0 ± 1.0°) has its own emulator of
//! the simulated quantity over the unit cube of the free parameters, fitted with each run's own
//! SE as its noise ([`Emulator`]). At a setting u the emulator says m_k(u) ± s_k(u); with a
//! uniform prior over the sweep file's ranges the posterior density is
//!
//! π(u) ∝ Π_k N(y_k; m_k(u), σ_k² + s_k(u)²),
//!
//! so a setting the emulator is unsure of is neither trusted nor ruled out. π is evaluated on
//! [`SAMPLES`] scrambled-Halton points of the cube, then on as many again inside the box that
//! holds every point whose density is within 10⁻⁶ of the highest (a zoom, so that a narrow
//! posterior gets thousands of points, not a dozen); the weighted points of the zoom are the
//! posterior sample. Credible intervals are its weighted 2.5 and 97.5 % quantiles.
//!
//! **Identification.** A parameter is identified when its posterior SD is a small share of its
//! prior SD (1/√12 of the range): under [`IDENTIFIED`] identified, under [`PARTLY`] partly, else
//! the targets hardly constrain it. Two parameters whose posterior correlation is beyond
//! [`RIDGE`] lie on a ridge: pairs along it reproduce the targets equally well, and only their
//! combination is known (a friction/rolling-friction trade-off against one angle of repose).
//!
//! **The next runs** (Bayesian active learning for posterior estimation, Kandasamy, Schneider &
//! Póczos 2015). The posterior is uncertain where the emulator is: the density at u is itself a
//! random variable under the emulator's posterior, and the run that most reduces the
//! uncertainty of π is, to first order, the one where its variance is largest. For Gaussian
//! likelihoods and independent emulators the variance is in closed form: with L_k = N(y_k; f_k,
//! σ_k²), f_k ~ N(m_k, s_k²),
//!
//! E[L_k] = N(y_k; m_k, s_k² + σ_k²),  E[L_k²] = N(y_k; m_k, s_k² + σ_k²/2) / (2σ_k√π),
//!
//! and Var π = Π E[L_k²] − Π E[L_k]². It is large where the mean is near the targets and the
//! emulator unsure — not where the targets are already known to be missed, nor where the
//! posterior is already pinned down. A batch is built greedily: after each choice every
//! emulator's variance is updated as if the run had been made (the kriging believer of
//! Ginsbourger, Le Riche & Carraro 2010; exact for the variance, which does not depend on the
//! run's value), so the runs of one batch spread along the region that matters. A quarter of
//! each batch ([`EXPLORE`]) goes to coverage (the candidate farthest from every run): the
//! criterion trusts the emulator, which early on may be confidently wrong far from any run.
//! Candidates: a fresh block of [`CANDIDATES`] scrambled-Halton points of the cube per batch and
//! [`ZOOM_CANDIDATES`] inside the posterior's box.
//!
//! **The stopping rule.** After each batch the credible intervals are compared with the last
//! batch's: the rule holds when no bound moved by more than the tolerance times the interval's
//! earlier width ([`interval_change`]); the calibration has converged when it held for `hold`
//! batches in a row: the credible region has stopped shrinking (and moving).
//!
//! References: Kennedy & O'Hagan (2001), J. R. Statist. Soc. B 63, 425–464; Higdon, Kennedy,
//! Cavendish, Cafeo & Ryne (2004), SIAM J. Sci. Comput. 26, 448–466; Kandasamy, Schneider &
//! Póczos (2015), IJCAI, 3605–3611; Ginsbourger, Le Riche & Carraro (2010), in Computational
//! Intelligence in Expensive Optimization Problems, 131–162.

use serde::{Deserialize, Serialize};

use crate::analysis::emulator::Emulator;
use crate::design::halton::{halton_range, Scrambling};

/// Points of the cube, and again of the zoom box, the posterior is evaluated on.
pub const SAMPLES: usize = 4096;
/// Fresh candidates of the cube per batch, and candidates inside the posterior's box.
pub const CANDIDATES: usize = 1024;
pub const ZOOM_CANDIDATES: usize = 512;
/// Share of a batch placed for coverage.
pub const EXPLORE: f64 = 0.25;
/// Posterior SD over prior SD below which a parameter is identified, or partly identified.
pub const IDENTIFIED: f64 = 0.25;
pub const PARTLY: f64 = 0.6;
/// Posterior correlation beyond which two parameters lie on a ridge.
pub const RIDGE: f64 = 0.7;
/// Density, relative to the highest, above which a point of the cube is inside the zoom box.
const ZOOM_LEVEL: f64 = 1e-6;

const ZOOM_STREAM: u64 = 21;
const CANDIDATE_STREAM: u64 = 22;
const ZOOM_CANDIDATE_STREAM: u64 = 23;

/// What a `--target` should look like, said after each way it can be wrong.
const TARGET_FORM: &str = "expected NAME=VALUE±SD (or +-), e.g. angle_of_repose=34.0±1.0";

/// Why a `--target` is not one ([`Target::parse`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TargetError {
    #[error("{TARGET_FORM}")]
    NoEquals,
    #[error("no ± SD: {TARGET_FORM}")]
    NoSd,
    /// The value or the SD (`what`) is not a finite number.
    #[error("{what} {text:?} is not a number: {TARGET_FORM}")]
    NotANumber { what: &'static str, text: String },
    #[error("no name: {TARGET_FORM}")]
    NoName,
    #[error("SD {sd}: expected a positive uncertainty (the measurement's SD)")]
    Sd { sd: f64 },
}

/// A measured value to reproduce: `name = value ± sd`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Target {
    pub name: String,
    pub value: f64,
    pub sd: f64,
}

impl Target {
    /// `name=value±sd` (or `+-`), e.g. `angle_of_repose=34.0±1.0`; the error says what was
    /// expected.
    pub fn parse(s: &str) -> Result<Target, TargetError> {
        let (name, rest) = s.split_once('=').ok_or(TargetError::NoEquals)?;
        let (value, sd) = rest.split_once('±').or_else(|| rest.split_once("+-")).ok_or(TargetError::NoSd)?;
        let num = |t: &str, what: &'static str| {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| TargetError::NotANumber { what, text: t.to_string() })
        };
        let (name, value, sd) = (name.trim(), num(value, "value")?, num(sd, "SD")?);
        if name.is_empty() {
            return Err(TargetError::NoName);
        }
        if sd <= 0.0 {
            return Err(TargetError::Sd { sd });
        }
        Ok(Target { name: name.to_string(), value, sd })
    }
}

/// The noise of one simulated quantity: how much one run scatters about its setting's mean.
///
/// A pour's own SE (over its heap's sectors) sees one avalanche history; the scatter between
/// seeds (another initial packing of the same powder) is the test's noise, and was twice that
/// SE on LIGGGHTS (docs/study/calibration.md). With settings run more than once it is measured
/// here, pooled over the settings (Σ (n−1)·s² / Σ (n−1), the usual pooled variance of a
/// one-way layout), and becomes each run's noise: never below the runs' own SE, which a pooled
/// SD of a few degrees of freedom can fall under by chance. Without repeats the runs' own SE
/// stands in for it, and the emulator's fitted nugget for the rest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scatter {
    /// The quantity (the target's name).
    pub name: String,
    /// The SD between seeds at one setting, pooled; `None` without a setting run twice.
    pub between_seed_sd: Option<f64>,
    /// Its degrees of freedom, Σ (n − 1) over the settings.
    pub df: usize,
    /// The runs' own SE of the quantity, root mean square; `None` when they give none.
    pub own_se: Option<f64>,
    /// The SD of one run the emulator takes as its noise: the scatter between seeds (at least
    /// the runs' own SE), or without repeats the runs' own SE.
    pub run_sd: Option<f64>,
    /// Settings and the runs over them.
    pub settings: usize,
    pub runs: usize,
}

impl Scatter {
    /// The scatter of the runs of each setting, `runs[g]` the values and own SEs of setting g.
    pub fn of(name: &str, runs: &[Vec<(f64, Option<f64>)>]) -> Scatter {
        let (mut ss, mut df) = (0.0, 0usize);
        for g in runs.iter().filter(|g| g.len() > 1) {
            let m = g.iter().map(|r| r.0).sum::<f64>() / g.len() as f64;
            ss += g.iter().map(|r| (r.0 - m).powi(2)).sum::<f64>();
            df += g.len() - 1;
        }
        let between_seed_sd = (df > 0).then(|| (ss / df as f64).sqrt());
        let own: Vec<f64> = runs.iter().flatten().filter_map(|r| r.1).map(|s| s * s).collect();
        let own_se = (!own.is_empty()).then(|| (own.iter().sum::<f64>() / own.len() as f64).sqrt());
        let run_sd = match (between_seed_sd, own_se) {
            (Some(b), Some(o)) => Some(b.max(o)),
            (b, o) => b.or(o),
        };
        Scatter {
            name: name.to_string(),
            between_seed_sd,
            df,
            own_se,
            run_sd,
            settings: runs.len(),
            runs: runs.iter().map(Vec::len).sum(),
        }
    }

    /// Each setting's mean and the SE of it the emulator takes: [`Scatter::run_sd`] over √n
    /// with repeats; without them the run's own SE (or none, for the emulator's nugget).
    pub fn means(&self, runs: &[Vec<(f64, Option<f64>)>]) -> Vec<(f64, Option<f64>)> {
        runs.iter()
            .map(|g| {
                let n = g.len() as f64;
                let mean = g.iter().map(|r| r.0).sum::<f64>() / n;
                let se = match self.between_seed_sd {
                    Some(_) => self.run_sd.map(|s| s / n.sqrt()),
                    None => g.first().and_then(|r| r.1),
                };
                (mean, se)
            })
            .collect()
    }
}

/// One target with the emulator of its simulated quantity.
pub struct Emulated<'a> {
    pub target: &'a Target,
    pub emulator: &'a Emulator,
}

impl<'a> Emulated<'a> {
    /// Each target with its emulator, in order.
    pub fn pair(targets: &'a [Target], emulators: &'a [Emulator]) -> Vec<Emulated<'a>> {
        targets.iter().zip(emulators).map(|(target, emulator)| Emulated { target, emulator }).collect()
    }
}

/// The log density of the posterior at `u`, up to a constant (module docs).
pub fn log_density(outputs: &[Emulated], u: &[f64]) -> f64 {
    outputs
        .iter()
        .map(|o| {
            let (m, s) = o.emulator.predict(u);
            let v = o.target.sd.powi(2) + s * s;
            -0.5 * (o.target.value - m).powi(2) / v - 0.5 * (std::f64::consts::TAU * v).ln()
        })
        .sum()
}

/// One parameter's posterior, in unit coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Marginal {
    pub mean: f64,
    pub sd: f64,
    /// 2.5, 50 and 97.5 % quantiles.
    pub lo: f64,
    pub median: f64,
    pub hi: f64,
}

impl Marginal {
    /// Posterior SD over the prior's (uniform over the unit interval: 1/√12).
    pub fn sd_ratio(&self) -> f64 {
        self.sd * 12f64.sqrt()
    }

    /// How well the targets identify the parameter, in words.
    pub fn identification(&self) -> &'static str {
        match self.sd_ratio() {
            r if r < IDENTIFIED => "identified",
            r if r < PARTLY => "partly identified",
            _ => "not identified",
        }
    }
}

/// The posterior over the unit cube of the free parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Posterior {
    pub marginals: Vec<Marginal>,
    /// Posterior correlations, row-major d × d.
    pub correlation: Vec<f64>,
    /// The sampled point of highest density.
    pub best: Vec<f64>,
    /// Effective sample size of the weighted sample (Σw)²/Σw².
    pub ess: f64,
    /// The zoom box the sample was drawn from: its lower and upper corners.
    pub box_lo: Vec<f64>,
    pub box_hi: Vec<f64>,
}

impl Posterior {
    /// The credible intervals (2.5–97.5 %) of every parameter.
    pub fn intervals(&self) -> Vec<(f64, f64)> {
        self.marginals.iter().map(|m| (m.lo, m.hi)).collect()
    }

    pub fn corr(&self, i: usize, j: usize) -> f64 {
        self.correlation[i * self.marginals.len() + j]
    }

    /// The pairs on a ridge: (i, j, correlation), i < j.
    pub fn ridges(&self) -> Vec<(usize, usize, f64)> {
        let d = self.marginals.len();
        let mut out = Vec::new();
        for i in 0..d {
            for j in i + 1..d {
                let r = self.corr(i, j);
                if r.abs() > RIDGE {
                    out.push((i, j, r));
                }
            }
        }
        out
    }
}

/// Points of a box given by its corners, quasi-random.
fn box_points(lo: &[f64], hi: &[f64], n: usize, start: u64, seed: u64) -> Vec<Vec<f64>> {
    halton_range(lo.len(), start, n, Scrambling::Random, seed)
        .into_iter()
        .map(|h| h.iter().zip(lo.iter().zip(hi)).map(|(u, (a, b))| a + u * (b - a)).collect())
        .collect()
}

/// The posterior of `outputs` over the unit cube of dimension `dim` (module docs); `None`
/// without an output.
pub fn posterior(outputs: &[Emulated], dim: usize, seed: u64) -> Option<Posterior> {
    if outputs.is_empty() || dim == 0 {
        return None;
    }
    let cube = halton_range(dim, 0, SAMPLES, Scrambling::Random, seed);
    let ld: Vec<f64> = cube.iter().map(|u| log_density(outputs, u)).collect();
    let top = ld.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !top.is_finite() {
        return None;
    }
    // The zoom box: every point within ZOOM_LEVEL of the top, padded by two spacings of the
    // sample (its points are about n^(-1/d) apart).
    let pad = 2.0 * (SAMPLES as f64).powf(-1.0 / dim as f64);
    let (mut lo, mut hi) = (vec![1.0f64; dim], vec![0.0f64; dim]);
    for (u, l) in cube.iter().zip(&ld) {
        if *l >= top + ZOOM_LEVEL.ln() {
            for k in 0..dim {
                lo[k] = lo[k].min(u[k]);
                hi[k] = hi[k].max(u[k]);
            }
        }
    }
    for k in 0..dim {
        lo[k] = (lo[k] - pad).max(0.0);
        hi[k] = (hi[k] + pad).min(1.0);
    }
    let pts = box_points(&lo, &hi, SAMPLES, 0, seed.wrapping_add(ZOOM_STREAM));
    let lz: Vec<f64> = pts.iter().map(|u| log_density(outputs, u)).collect();
    let top = lz.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let w: Vec<f64> = lz.iter().map(|l| (l - top).exp()).collect();
    let sum: f64 = w.iter().sum();
    let ess = sum * sum / w.iter().map(|v| v * v).sum::<f64>();
    let best = pts[lz.iter().enumerate().fold(0, |b, (i, l)| if *l > lz[b] { i } else { b })].clone();
    let mean: Vec<f64> =
        (0..dim).map(|k| pts.iter().zip(&w).map(|(u, w)| w * u[k]).sum::<f64>() / sum).collect();
    let mut cov = vec![0.0; dim * dim];
    for (u, wi) in pts.iter().zip(&w) {
        for i in 0..dim {
            for j in 0..dim {
                cov[i * dim + j] += wi * (u[i] - mean[i]) * (u[j] - mean[j]) / sum;
            }
        }
    }
    let sd: Vec<f64> = (0..dim).map(|k| cov[k * dim + k].max(0.0).sqrt()).collect();
    let correlation = (0..dim * dim)
        .map(|ij| {
            let (i, j) = (ij / dim, ij % dim);
            let s = sd[i] * sd[j];
            if s > 0.0 {
                cov[ij] / s
            } else {
                f64::from(i == j)
            }
        })
        .collect();
    let marginals = (0..dim)
        .map(|k| {
            let mut v: Vec<(f64, f64)> = pts.iter().zip(&w).map(|(u, w)| (u[k], *w)).collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            let q = |p: f64| weighted_quantile(&v, sum, p);
            Marginal { mean: mean[k], sd: sd[k], lo: q(0.025), median: q(0.5), hi: q(0.975) }
        })
        .collect();
    Some(Posterior { marginals, correlation, best, ess, box_lo: lo, box_hi: hi })
}

/// The `p` quantile of values sorted with their weights (summing to `sum`).
fn weighted_quantile(sorted: &[(f64, f64)], sum: f64, p: f64) -> f64 {
    let mut acc = 0.0;
    for (x, w) in sorted {
        acc += w;
        if acc >= p * sum {
            return *x;
        }
    }
    sorted.last().map_or(f64::NAN, |v| v.0)
}

/// The largest move of a credible interval's bound between two batches, over that interval's
/// earlier width (a relative change of the credible region); `None` without an earlier batch.
pub fn interval_change(before: &[(f64, f64)], now: &[(f64, f64)]) -> Option<f64> {
    if before.len() != now.len() || before.is_empty() {
        return None;
    }
    let worst = before
        .iter()
        .zip(now)
        .map(|((a, b), (c, d))| (a - c).abs().max((b - d).abs()) / (b - a).abs().max(1e-9))
        .fold(0.0f64, f64::max);
    Some(worst)
}

/// Whether each batch's posterior holds the rule against the one before, and the batch at
/// which the calibration converged (the rule held `hold` times in a row): `intervals[b]` is
/// batch b's, `None` where it has no posterior.
pub fn judge(
    intervals: &[Option<Vec<(f64, f64)>>],
    tolerance: f64,
    hold: usize,
) -> (Vec<Option<f64>>, Option<usize>) {
    let mut changes = Vec::new();
    let mut streak = 0;
    let mut converged = None;
    for b in 0..intervals.len() {
        let change = match (b.checked_sub(1).and_then(|a| intervals[a].as_ref()), &intervals[b]) {
            (Some(before), Some(now)) => interval_change(before, now),
            _ => None,
        };
        streak = if change.is_some_and(|c| c <= tolerance) { streak + 1 } else { 0 };
        if streak >= hold.max(1) && converged.is_none() {
            converged = Some(b);
        }
        changes.push(change);
    }
    (changes, converged)
}

/// One run of the next batch, and why it was chosen.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pick {
    pub point: Vec<f64>,
    /// `coverage` or `posterior variance`.
    pub why: &'static str,
    /// log Var π at the point when it was chosen (NaN for coverage).
    pub log_var: f64,
}

/// log(Var π) at a candidate from each output's mean, variance and target (module docs).
fn log_var_density(parts: &[(f64, f64, &Target)]) -> f64 {
    let ln_n = |d: f64, v: f64| -0.5 * d * d / v - 0.5 * (std::f64::consts::TAU * v).ln();
    let (mut a, mut b) = (0.0, 0.0);
    for (m, s2, t) in parts {
        let (d, s2t) = (t.value - m, t.sd * t.sd);
        a += ln_n(d, s2 + 0.5 * s2t) - (2.0 * t.sd * std::f64::consts::PI.sqrt()).ln();
        b += 2.0 * ln_n(d, s2 + s2t);
    }
    // Var = e^a − e^b = e^a (1 − e^(b − a)), b ≤ a.
    a + (-(b - a).min(0.0).exp()).ln_1p()
}

/// The candidates of batch `batch`: a fresh block of the cube and points of the posterior's box.
pub fn candidates(dim: usize, batch: usize, seed: u64, post: Option<&Posterior>) -> Vec<Vec<f64>> {
    let start = (batch * CANDIDATES) as u64;
    let mut c = halton_range(dim, start, CANDIDATES, Scrambling::Random, seed.wrapping_add(CANDIDATE_STREAM));
    if let Some(p) = post {
        let start = (batch * ZOOM_CANDIDATES) as u64;
        c.extend(box_points(
            &p.box_lo,
            &p.box_hi,
            ZOOM_CANDIDATES,
            start,
            seed.wrapping_add(ZOOM_CANDIDATE_STREAM),
        ));
    }
    c
}

/// The next `size` runs among `cands` (module docs): `noise[k]` is the noise variance of a new
/// run of output k; `existing` the unit points run so far.
pub fn next_batch(
    outputs: &[Emulated],
    noise: &[f64],
    cands: &[Vec<f64>],
    existing: &[Vec<f64>],
    size: usize,
) -> Vec<Pick> {
    let explore = ((size as f64 * EXPLORE).floor() as usize).min(size);
    let n_out = outputs.len();
    let mean: Vec<Vec<f64>> =
        outputs.iter().map(|o| cands.iter().map(|u| o.emulator.mean(u)).collect()).collect();
    let white: Vec<Vec<Vec<f64>>> =
        outputs.iter().map(|o| cands.iter().map(|u| o.emulator.whitened(u)).collect()).collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut var: Vec<Vec<f64>> = (0..n_out)
        .map(|k| {
            cands
                .iter()
                .zip(&white[k])
                .map(|(u, w)| (outputs[k].emulator.prior_cov(u, u) - dot(w, w)).max(0.0))
                .collect()
        })
        .collect();
    // Per output, the scaled covariance columns of the runs chosen so far (the believer's updates).
    let mut updates: Vec<Vec<Vec<f64>>> = vec![Vec::new(); n_out];
    let d2 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
    let mut nearest: Vec<f64> =
        cands.iter().map(|c| existing.iter().map(|e| d2(c, e)).fold(f64::INFINITY, f64::min)).collect();
    let mut taken = vec![false; cands.len()];
    let mut picks = Vec::new();
    for step in 0..size.min(cands.len()) {
        let score = |c: usize| {
            if step < explore {
                nearest[c]
            } else {
                let parts: Vec<(f64, f64, &Target)> =
                    (0..n_out).map(|k| (mean[k][c], var[k][c], outputs[k].target)).collect();
                log_var_density(&parts)
            }
        };
        let scores: Vec<f64> = (0..cands.len()).map(score).collect();
        let Some(j) =
            (0..cands.len()).filter(|c| !taken[*c]).max_by(|a, b| scores[*a].total_cmp(&scores[*b]))
        else {
            break;
        };
        let coverage = step < explore;
        picks.push(Pick {
            point: cands[j].clone(),
            why: if coverage { "coverage" } else { "posterior variance" },
            log_var: if coverage { f64::NAN } else { scores[j] },
        });
        taken[j] = true;
        for c in 0..cands.len() {
            nearest[c] = nearest[c].min(d2(&cands[c], &cands[j]));
        }
        for k in 0..n_out {
            let em = outputs[k].emulator;
            let col: Vec<f64> = (0..cands.len())
                .map(|c| {
                    let prior = em.prior_cov(&cands[c], &cands[j]) - dot(&white[k][c], &white[k][j]);
                    prior - updates[k].iter().map(|g| g[c] * g[j]).sum::<f64>()
                })
                .collect();
            let denom = (var[k][j] + noise[k]).max(1e-300).sqrt();
            let g: Vec<f64> = col.iter().map(|v| v / denom).collect();
            for c in 0..cands.len() {
                var[k][c] = (var[k][c] - g[c] * g[c]).max(0.0);
            }
            updates[k].push(g);
        }
    }
    picks
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A known 2-D response: an "angle" rising with both coordinates (a ridge against one
    /// target) and a "packing" falling mostly with the first.
    fn angle(u: &[f64]) -> f64 {
        20.0 + 12.0 * u[0] + 12.0 * u[1]
    }
    fn packing(u: &[f64]) -> f64 {
        0.62 - 0.06 * u[0] - 0.01 * u[1]
    }

    fn fit(f: fn(&[f64]) -> f64, n: usize) -> Emulator {
        let x = halton_range(2, 0, n, Scrambling::Random, 5);
        let y: Vec<f64> = x.iter().map(|u| f(u)).collect();
        Emulator::fit(&x, &y, &vec![None; n]).unwrap()
    }

    #[test]
    fn the_scatter_between_seeds_is_pooled_over_the_repeated_settings() {
        // Setting a: 1, 3 (variance 2, 1 df); b: 2, 2, 5 (variance 3, 2 df); c: one run.
        let runs = vec![
            vec![(1.0, Some(0.5)), (3.0, Some(0.5))],
            vec![(2.0, Some(0.5)), (2.0, Some(0.5)), (5.0, Some(0.5))],
            vec![(7.0, Some(0.5))],
        ];
        let s = Scatter::of("angle", &runs);
        assert_eq!((s.df, s.settings, s.runs), (3, 3, 6));
        let pooled = ((2.0 * 1.0 + 3.0 * 2.0) / 3.0f64).sqrt();
        assert!((s.between_seed_sd.unwrap() - pooled).abs() < 1e-12, "{s:?}");
        assert_eq!(s.own_se, Some(0.5));
        // Each setting's mean carries the scatter between seeds over √n, not the runs' own SE.
        let m = s.means(&runs);
        assert_eq!(m.iter().map(|x| x.0).collect::<Vec<_>>(), vec![2.0, 3.0, 7.0]);
        for (got, n) in m.iter().zip([2.0, 3.0, 1.0f64]) {
            assert!((got.1.unwrap() - pooled / n.sqrt()).abs() < 1e-12, "{got:?}");
        }
        // Never below the runs' own SE; without repeats the runs' own SE stands.
        let tight = vec![vec![(1.0, Some(0.5)), (1.1, Some(0.5))]];
        assert_eq!(Scatter::of("a", &tight).run_sd, Some(0.5));
        let single = vec![vec![(1.0, Some(0.4))], vec![(2.0, None)]];
        let s = Scatter::of("a", &single);
        assert_eq!((s.between_seed_sd, s.df), (None, 0));
        assert_eq!(s.means(&single), vec![(1.0, Some(0.4)), (2.0, None)]);
    }

    #[test]
    fn targets_parse_with_either_sign_and_bad_ones_say_what_was_expected() {
        let t = Target::parse("angle_of_repose=34.0±1.0").unwrap();
        assert_eq!(t, Target { name: "angle_of_repose".into(), value: 34.0, sd: 1.0 });
        assert_eq!(Target::parse("bulk_packing = 0.58 +- 0.01").unwrap().sd, 0.01);
        for bad in ["angle", "angle=34", "angle=x±1", "=34±1", "angle=34±0", "angle=34±-1", "angle=34±nan"]
        {
            let e = Target::parse(bad).unwrap_err().to_string();
            assert!(e.contains("expected"), "{bad}: {e}");
        }
    }

    #[test]
    fn one_target_leaves_a_ridge_and_two_identify_both() {
        let (ea, ep) = (fit(angle, 40), fit(packing, 40));
        // Truth u = (0.5, 0.25): angle 29, packing 0.5875.
        let ta = Target { name: "angle".into(), value: 29.0, sd: 0.5 };
        let tp = Target { name: "packing".into(), value: 0.5875, sd: 0.002 };
        let one = posterior(&[Emulated { target: &ta, emulator: &ea }], 2, 1).unwrap();
        // Along the ridge u0 + u1 = 0.75 both range widely, strongly anti-correlated.
        assert!(one.corr(0, 1) < -0.9, "{:?}", one.correlation);
        assert_eq!(one.ridges().len(), 1);
        assert!(one.marginals.iter().all(|m| m.identification() != "identified"), "{:?}", one.marginals);
        let two = posterior(
            &[Emulated { target: &ta, emulator: &ea }, Emulated { target: &tp, emulator: &ep }],
            2,
            1,
        )
        .unwrap();
        for (m, truth) in two.marginals.iter().zip([0.5, 0.25]) {
            assert!(m.lo <= truth && truth <= m.hi, "{m:?} misses {truth}");
            assert_eq!(m.identification(), "identified", "{m:?}");
        }
        assert!(two.ess > 100.0, "{}", two.ess);
        // The ridge's credible region is wider than the identified one's.
        assert!(
            one.marginals[0].hi - one.marginals[0].lo > 3.0 * (two.marginals[0].hi - two.marginals[0].lo)
        );
    }

    #[test]
    fn the_next_runs_go_where_the_targets_may_be_met() {
        let ea = fit(angle, 12);
        let ta = Target { name: "angle".into(), value: 29.0, sd: 0.5 };
        let out = [Emulated { target: &ta, emulator: &ea }];
        let post = posterior(&out, 2, 1).unwrap();
        let cands = candidates(2, 0, 3, Some(&post));
        let existing = halton_range(2, 0, 12, Scrambling::Random, 5);
        let picks = next_batch(&out, &[1e-4], &cands, &existing, 8);
        assert_eq!(picks.len(), 8);
        assert_eq!(picks.iter().filter(|p| p.why == "coverage").count(), 2);
        // The criterion's runs lie near the ridge u0 + u1 = 0.75, no two the same.
        for p in picks.iter().filter(|p| p.why != "coverage") {
            assert!((p.point[0] + p.point[1] - 0.75).abs() < 0.15, "{p:?}");
        }
        let crit: Vec<&Pick> = picks.iter().filter(|p| p.why != "coverage").collect();
        for a in 0..crit.len() {
            for b in a + 1..crit.len() {
                let d: f64 = crit[a].point.iter().zip(&crit[b].point).map(|(x, y)| (x - y).powi(2)).sum();
                assert!(d > 0.0, "{:?} {:?}", crit[a], crit[b]);
            }
        }
    }

    #[test]
    fn the_rule_holds_once_the_intervals_stop_moving() {
        let iv = |w: f64| Some(vec![(0.5 - w, 0.5 + w)]);
        let (ch, conv) = judge(&[None, iv(0.4), iv(0.2), iv(0.19), iv(0.185)], 0.1, 2);
        assert_eq!(ch[0], None);
        assert_eq!(ch[1], None);
        assert!((ch[2].unwrap() - 0.25).abs() < 1e-12);
        assert!((ch[3].unwrap() - 0.025).abs() < 1e-12);
        assert_eq!(conv, Some(4));
        let (_, conv) = judge(&[iv(0.4), iv(0.2), iv(0.19), iv(0.1)], 0.1, 2);
        assert_eq!(conv, None);
    }
}
