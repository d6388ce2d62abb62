//! An emulator of MFR over the space: a Gaussian-process (kriging) surrogate fitted to the done
//! points (docs/statistics.md "The emulator").
//!
//! The model: MFR(u) = μ + f(u) + e, u the point in unit coordinates, f a zero-mean GP with an
//! anisotropic Matérn-5/2 covariance σ²·k(r), r² = Σ((u_j − u'_j)/θ_j)², and e independent
//! noise of variance se_i² (the point's `mfr_se`, where its result records one) plus a fitted
//! nugget τ² (the noise no point reports, and what keeps the matrix well conditioned). μ is the
//! generalised-least-squares constant; θ, σ², τ² maximise the marginal likelihood (Nelder–Mead on
//! their logarithms, on at most [`FIT_POINTS`] of the points, spread over the design; the
//! prediction then conditions on every point).
//!
//! Why our own model rather than a kriging crate: `egobox-gp` (the best-kept Rust kriging crate)
//! takes one scalar nugget, not a noise variance per point, and brings ndarray and linfa for a
//! model this size; the closed-form leave-one-out residuals (Rasmussen & Williams 2006, Eq.
//! 5.12) need the inverse covariance, which is a few lines here. The dense linear algebra
//! (Cholesky factor, triangular solves, inverse) is `nalgebra`'s.
//!
//! MFR is fitted by [`Emulator::fit_censored`]: its zeros (jammed runs) are a floor of a latent
//! flow rate that goes on below zero (the censored regression of Tobin 1958, Econometrica 26,
//! 24–36), not values of a smooth surface.
//!
//! Uses: [`Emulator::predict`] (MFR with its predictive SE at a setting), [`Emulator::loo`]
//! (cross-validation on every sweep), [`Emulator::space_statistics`] (the space's MFR statistics
//! from many cheap draws, with their uncertainty), [`Emulator::zero_fraction`] (where MFR is
//! zero) and [`Emulator::rank`] (the best settings among candidates, with SE).

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Serialize;

use crate::analysis::simplex::minimise;
use crate::analysis::stats::{percentile_sorted, Interval, Moments, STATISTICS};

/// Most points the hyperparameters are fitted on (the likelihood costs N³/3 per evaluation).
pub const FIT_POINTS: usize = 250;
/// Fewest points an emulator is fitted to.
pub const MIN_POINTS: usize = 8;

/// A fitted emulator.
#[derive(Debug, Clone)]
pub struct Emulator {
    x: Vec<Vec<f64>>,
    /// Standardisation of y: y = y_mean + y_scale·z.
    y_mean: f64,
    y_scale: f64,
    /// Length scales (unit coordinates), signal variance and nugget, all on the z scale.
    pub theta: Vec<f64>,
    pub sigma2: f64,
    pub nugget: f64,
    mu: f64,
    /// Cholesky factor of K and K⁻¹(z − μ).
    chol: Cholesky<f64, Dyn>,
    alpha: Vec<f64>,
    /// The standardised values conditioned on (a floored run's imputed latent value).
    z: Vec<f64>,
    /// Whether runs at 0 are a floor ([`Emulator::fit_censored`]): their left-out residual is
    /// against the prediction's positive part.
    floored: bool,
}

/// Leave-one-out cross-validation, in MFR units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CrossValidation {
    pub points: usize,
    /// Root mean square of y_i − ŷ_(−i).
    pub rmse: f64,
    /// 1 − Σ(y_i − ŷ_(−i))² / Σ(y_i − ȳ)²: the share of MFR's variance predicted out of sample.
    pub q2: f64,
    /// Share of points whose left-out residual is within 1.96 predictive SE (0.95 if calibrated).
    pub coverage95: f64,
    /// √(mean se² + nugget): the noise the emulator assumes in each point, for comparison.
    pub noise_se: f64,
}

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

fn matern52(r: f64) -> f64 {
    let s = 5f64.sqrt() * r;
    (1.0 + s + s * s / 3.0) * (-s).exp()
}

fn dist(a: &[f64], b: &[f64], theta: &[f64]) -> f64 {
    a.iter().zip(b).zip(theta).map(|((p, q), t)| ((p - q) / t).powi(2)).sum::<f64>().sqrt()
}

/// The Cholesky factor of `k` (its lower triangle read); `None` when `k` is not positive
/// definite or its factor not finite.
fn factor(k: DMatrix<f64>) -> Option<Cholesky<f64, Dyn>> {
    Cholesky::new(k).filter(|c| c.l_dirty().diagonal().iter().all(|d| d.is_finite()))
}

/// Solve L·v = b (forward substitution) for the lower factor L of `chol`, in place.
fn forward(chol: &Cholesky<f64, Dyn>, mut b: DVector<f64>) -> DVector<f64> {
    chol.l_dirty().solve_lower_triangular_unchecked_mut(&mut b);
    b
}

/// The covariance matrix of `x` with noise variances `noise` on the diagonal.
fn covariance(x: &[Vec<f64>], theta: &[f64], sigma2: f64, noise: &[f64]) -> DMatrix<f64> {
    let n = x.len();
    let mut k = DMatrix::zeros(n, n);
    for j in 0..n {
        for i in j + 1..n {
            let v = sigma2 * matern52(dist(&x[i], &x[j], theta));
            k[(i, j)] = v;
            k[(j, i)] = v;
        }
        k[(j, j)] = sigma2 + noise[j];
    }
    k
}

/// GLS constant, K⁻¹(z − μ) and the Cholesky factor; `None` when K is not positive definite.
fn condition(
    x: &[Vec<f64>],
    z: &[f64],
    theta: &[f64],
    sigma2: f64,
    noise: &[f64],
) -> Option<(f64, Vec<f64>, Cholesky<f64, Dyn>)> {
    let n = x.len();
    let chol = factor(covariance(x, theta, sigma2, noise))?;
    let ki1 = chol.solve(&DVector::from_element(n, 1.0));
    let kiz = chol.solve(&DVector::from_column_slice(z));
    let mu = kiz.sum() / ki1.sum();
    let alpha = chol.solve(&DVector::from_iterator(n, z.iter().map(|v| v - mu)));
    Some((mu, alpha.as_slice().to_vec(), chol))
}

/// Negative log marginal likelihood (up to a constant) at log-parameters `p` = (ln θ…, ln σ², ln τ²).
fn nll(x: &[Vec<f64>], z: &[f64], se2: &[f64], p: &[f64]) -> f64 {
    let d = x[0].len();
    let theta: Vec<f64> = p[..d].iter().map(|v| v.exp()).collect();
    let (sigma2, tau2) = (p[d].exp(), p[d + 1].exp());
    let noise: Vec<f64> = se2.iter().map(|s| s + tau2).collect();
    let Some((mu, alpha, l)) = condition(x, z, &theta, sigma2, &noise) else {
        return f64::INFINITY;
    };
    let logdet = l.ln_determinant();
    let quad: f64 = z.iter().zip(&alpha).map(|(v, a)| (v - mu) * a).sum();
    0.5 * (quad + logdet)
}

/// Bounds of the log-parameters: length scales 0.01–10 of the unit cube, σ² 10⁻³–10² and
/// τ² 10⁻⁸–1 of the standardised variance.
fn clamp_params(p: &mut [f64], d: usize) {
    for (i, v) in p.iter_mut().enumerate() {
        let (lo, hi) = if i < d {
            (MIN_LENGTH.ln(), 10f64.ln())
        } else if i == d {
            (1e-3f64.ln(), 1e2f64.ln())
        } else {
            (1e-8f64.ln(), 0.0)
        };
        *v = v.clamp(lo, hi);
    }
}

/// y standardised (mean, scale, z) and the squared SE on z's scale; `None` with too few points
/// or no spread.
fn standardise(x: &[Vec<f64>], y: &[f64], se: &[Option<f64>]) -> Option<(f64, f64, Vec<f64>, Vec<f64>)> {
    let n = x.len();
    if n < MIN_POINTS || y.len() != n || se.len() != n {
        return None;
    }
    let y_mean = y.iter().sum::<f64>() / n as f64;
    let y_scale = (y.iter().map(|v| (v - y_mean).powi(2)).sum::<f64>() / n as f64).sqrt();
    let big = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if y_scale <= 1e-12 * big || !y_scale.is_finite() {
        return None;
    }
    let z: Vec<f64> = y.iter().map(|v| (v - y_mean) / y_scale).collect();
    let se2: Vec<f64> = se.iter().map(|s| s.map_or(0.0, |s| (s / y_scale).powi(2))).collect();
    Some((y_mean, y_scale, z, se2))
}

/// The shortest length scale (unit coordinates) a fit may take.
const MIN_LENGTH: f64 = 0.01;

/// The log-normal prior (median, SD of the logarithm) on each length scale with which
/// [`Emulator::fit`] fits again when a length scale ends at [`MIN_LENGTH`]. Why: a dozen noisy
/// runs (a calibration's pours) can have their likelihood highest there — the process then
/// threads every run's scatter as a spike and reverts to its mean between runs, and the
/// posterior of the parameter comes back as its prior (316L's rolling friction from 12 pours,
/// docs/study/calibration.md). The prior costs such a length scale 5.8 nats; a trend, nothing.
pub const LENGTH_PRIOR: (f64, f64) = (0.3, 1.0);

/// Whether a fit's length scales end at [`MIN_LENGTH`] (within its optimiser's reach of it).
fn at_length_bound(theta: &[f64]) -> bool {
    theta.iter().any(|t| *t <= MIN_LENGTH * 1.001)
}

/// Length scales, signal variance and nugget maximising the marginal likelihood of `z`, times
/// a log-normal prior (median, SD of the logarithm) on each length scale where one is given.
fn likelihood_fit(x: &[Vec<f64>], z: &[f64], se2: &[f64], prior: Option<(f64, f64)>) -> (Vec<f64>, f64, f64) {
    let d = x[0].len();
    // The fit subset: a seeded random one (every k-th point of a Halton sequence would share
    // its leading digits, and sit in one slice of the box).
    let idx = subset(x.len(), FIT_POINTS, 1);
    let fx: Vec<Vec<f64>> = idx.iter().map(|&i| x[i].clone()).collect();
    let fz: Vec<f64> = idx.iter().map(|&i| z[i]).collect();
    let fs: Vec<f64> = idx.iter().map(|&i| se2[i]).collect();
    let penalty = |p: &[f64]| {
        prior.map_or(0.0, |(median, sd)| p[..d].iter().map(|l| 0.5 * ((l - median.ln()) / sd).powi(2)).sum())
    };
    let f = |p: &[f64]| nll(&fx, &fz, &fs, p) + penalty(p);
    let mut start = vec![0.3f64.ln(); d];
    start.extend([0.0, 1e-3f64.ln()]);
    let mut best = minimise(&f, &start, 1.0, 300 * (d + 2), &|p| clamp_params(p, d));
    // A restart from the optimum escapes an early collapse of the simplex.
    best = minimise(&f, &best, 0.5, 150 * (d + 2), &|p| clamp_params(p, d));
    let theta: Vec<f64> = best[..d].iter().map(|v| v.exp()).collect();
    (theta, best[d].exp(), best[d + 1].exp())
}

fn normal_pdf(a: f64) -> f64 {
    (-0.5 * a * a).exp() / (std::f64::consts::TAU).sqrt()
}

fn normal_cdf(a: f64) -> f64 {
    0.5 * statrs::function::erf::erfc(-a / std::f64::consts::SQRT_2)
}

impl Emulator {
    /// Fit to points `x` (unit coordinates), values `y` and their standard errors `se` (`None`:
    /// not recorded). `None` when there are fewer than [`MIN_POINTS`] points, y has no spread, or
    /// no covariance could be factorised.
    pub fn fit(x: &[Vec<f64>], y: &[f64], se: &[Option<f64>]) -> Option<Emulator> {
        let (y_mean, y_scale, z, se2) = standardise(x, y, se)?;
        let (mut theta, mut sigma2, mut nugget) = likelihood_fit(x, &z, &se2, None);
        if at_length_bound(&theta) {
            (theta, sigma2, nugget) = likelihood_fit(x, &z, &se2, Some(LENGTH_PRIOR));
        }
        Emulator::condition_all(x, &z, &se2, y_mean, y_scale, theta, sigma2, nugget)
    }

    /// Fit MFR, whose zeros (jammed points) are a floor, not a value: the emulator is of a latent
    /// flow rate that goes on below zero, and MFR is its positive part (a Tobit model). A zero
    /// run says only that the latent value there is at most 0; it is replaced by its expected
    /// value given that and the other runs (the truncated-normal mean of its leave-one-out
    /// prediction, iterated to a fixed point), and the hyperparameters are fitted again on the
    /// result. Why: fitted as values, the zeros flatten the surface and the smooth emulator
    /// rounds the kink where flow stops upwards — too much flow near it, too little spread and
    /// skewness in the space's statistics; on the latent surface the kink is where it crosses 0,
    /// as sharp as the truth's. Without zeros this is [`Emulator::fit`].
    pub fn fit_censored(x: &[Vec<f64>], y: &[f64], se: &[Option<f64>]) -> Option<Emulator> {
        let floor: Vec<usize> = (0..y.len()).filter(|&i| y[i] <= 0.0).collect();
        let (y_mean, y_scale, mut z, se2) = standardise(x, y, se)?;
        let (theta, sigma2, nugget) = likelihood_fit(x, &z, &se2, None);
        let mut em = Emulator::condition_all(x, &z, &se2, y_mean, y_scale, theta, sigma2, nugget)?;
        if floor.is_empty() {
            return Some(em);
        }
        let c = -y_mean / y_scale;
        for _round in 0..2 {
            em.impute_below(&mut z, &floor, c);
            let (theta, sigma2, nugget) = likelihood_fit(x, &z, &se2, None);
            // Should the refit not factorise, the fit before it stands.
            let Some(next) = Emulator::condition_all(x, &z, &se2, y_mean, y_scale, theta, sigma2, nugget)
            else {
                break;
            };
            em = Emulator { floored: true, ..next };
        }
        Some(em)
    }

    /// Condition on every point, adding jitter to the nugget until the factorisation succeeds.
    #[allow(clippy::too_many_arguments)]
    fn condition_all(
        x: &[Vec<f64>],
        z: &[f64],
        se2: &[f64],
        y_mean: f64,
        y_scale: f64,
        theta: Vec<f64>,
        sigma2: f64,
        mut nugget: f64,
    ) -> Option<Emulator> {
        for _ in 0..6 {
            let noise: Vec<f64> = se2.iter().map(|s| s + nugget).collect();
            if let Some((mu, alpha, chol)) = condition(x, z, &theta, sigma2, &noise) {
                let (x, z) = (x.to_vec(), z.to_vec());
                return Some(Emulator {
                    x,
                    y_mean,
                    y_scale,
                    theta,
                    sigma2,
                    nugget,
                    mu,
                    chol,
                    alpha,
                    z,
                    floored: false,
                });
            }
            nugget = (nugget * 10.0).max(1e-8);
        }
        None
    }

    /// Replace the standardised values `z` at `floor` (runs known only to be at most `c`) by
    /// their expected value given that bound and every other value: Gauss–Seidel sweeps of the
    /// truncated-normal mean of each one's leave-one-out prediction, with the covariance held.
    fn impute_below(&self, z: &mut [f64], floor: &[usize], c: f64) {
        // K⁻¹; it is symmetric, so column i is row i.
        let kinv = self.chol.inverse();
        let mut alpha = self.alpha.clone();
        for _sweep in 0..100 {
            let mut largest = 0.0f64;
            for &i in floor {
                let kii = kinv[(i, i)];
                // The leave-one-out prediction of run i's value (its own noise included).
                let m = z[i] - alpha[i] / kii;
                let s = (1.0 / kii).sqrt();
                let a = (c - m) / s;
                // E[v | v ≤ c] for v ~ N(m, s²); the ratio φ/Φ by its asymptote far below.
                let ratio = if a > -30.0 { normal_pdf(a) / normal_cdf(a) } else { -a };
                let new = (m - s * ratio).min(c);
                let step = new - z[i];
                if step != 0.0 {
                    for (al, k) in alpha.iter_mut().zip(kinv.column(i).iter()) {
                        *al += step * k;
                    }
                    z[i] = new;
                }
                largest = largest.max(step.abs());
            }
            if largest < 1e-5 {
                break;
            }
        }
    }

    fn n(&self) -> usize {
        self.x.len()
    }

    fn kstar(&self, u: &[f64]) -> Vec<f64> {
        self.x.iter().map(|p| self.sigma2 * matern52(dist(p, u, &self.theta))).collect()
    }

    /// The emulator's MFR at `u` (unit coordinates) and its predictive SE (of the latent MFR,
    /// without the point noise). The mean is not clamped: callers read a negative value as 0.
    pub fn predict(&self, u: &[f64]) -> (f64, f64) {
        let k = self.kstar(u);
        let mean = self.mu + k.iter().zip(&self.alpha).map(|(a, b)| a * b).sum::<f64>();
        let v = forward(&self.chol, DVector::from_vec(k));
        let var = (self.sigma2 - v.norm_squared()).max(0.0);
        (self.y_mean + self.y_scale * mean, self.y_scale * var.sqrt())
    }

    /// The emulator's MFR at `u` without its SE: O(N) rather than O(N²), for many points.
    pub fn mean(&self, u: &[f64]) -> f64 {
        let m: f64 = self
            .x
            .iter()
            .zip(&self.alpha)
            .map(|(p, a)| self.sigma2 * matern52(dist(p, u, &self.theta)) * a)
            .sum();
        self.y_mean + self.y_scale * (self.mu + m)
    }

    /// The prior covariance of the latent MFR at `a` and `b`, in MFR units².
    pub fn prior_cov(&self, a: &[f64], b: &[f64]) -> f64 {
        self.y_scale.powi(2) * self.sigma2 * matern52(dist(a, b, &self.theta))
    }

    /// L⁻¹k(X, u) in MFR units: the posterior covariance of the latent MFR at `a` and `b` is
    /// `prior_cov(a, b) − whitened(a)·whitened(b)` (what a sequential design updates).
    pub fn whitened(&self, u: &[f64]) -> Vec<f64> {
        forward(&self.chol, DVector::from_vec(self.kstar(u))).iter().map(|v| v * self.y_scale).collect()
    }

    /// The fitted nugget in MFR units²: the noise no point reports.
    pub fn nugget_variance(&self) -> f64 {
        self.nugget * self.y_scale.powi(2)
    }

    /// Leave-one-out residuals in closed form (hyperparameters held), given the true `y`.
    pub fn loo(&self, y: &[f64], se: &[Option<f64>]) -> CrossValidation {
        let n = self.n();
        // K⁻¹ = L⁻ᵀL⁻¹: its diagonal is the column sums of squares of L⁻¹.
        let mut linv = DMatrix::identity(n, n);
        self.chol.l_dirty().solve_lower_triangular_unchecked_mut(&mut linv);
        let diag: Vec<f64> = linv.column_iter().map(|c| c.norm_squared()).collect();
        let ybar = y.iter().sum::<f64>() / n as f64;
        let (mut ss, mut st, mut inside) = (0.0, 0.0, 0usize);
        for i in 0..n {
            // The left-out prediction of run i, from the value the fit conditioned on.
            let pred = self.y_mean + self.y_scale * (self.z[i] - self.alpha[i] / diag[i]);
            let r = if self.floored && y[i] <= 0.0 { y[i] - pred.max(0.0) } else { y[i] - pred };
            let sd = (1.0 / diag[i]).sqrt() * self.y_scale;
            ss += r * r;
            st += (y[i] - ybar).powi(2);
            if r.abs() <= 1.96 * sd {
                inside += 1;
            }
        }
        let se2: Vec<f64> = se.iter().flatten().map(|s| s * s).collect();
        let mean_se2 = if se2.is_empty() { 0.0 } else { se2.iter().sum::<f64>() / se2.len() as f64 };
        CrossValidation {
            points: n,
            rmse: (ss / n as f64).sqrt(),
            q2: if st > 0.0 { 1.0 - ss / st } else { 0.0 },
            coverage95: inside as f64 / n as f64,
            noise_se: (mean_se2 + self.nugget * self.y_scale.powi(2)).sqrt(),
        }
    }

    /// The space's MFR statistics from the emulator, each the posterior median of the statistic
    /// with its 95 % posterior interval. The mean surface, clamped at 0 (MFR cannot be
    /// negative), is evaluated on `draws` scrambled-Halton points of the unit cube; `paths`
    /// posterior sample paths on the first 256 of them give each statistic's shift from the mean
    /// surface's on the same points; the estimate is the mean surface's statistic plus the
    /// median shift, the interval plus the 2.5 and 97.5 % shifts.
    ///
    /// Why the median shift: a statistic of the mean surface is not the mean of that statistic
    /// over the functions the emulator deems possible. The mean surface is smoother than any of
    /// them, so its spread is smaller and its skewness another (a sample path's std is larger,
    /// nearly always); the plain plug-in value can lie outside the posterior's own interval.
    pub fn space_statistics(&self, draws: usize, paths: usize, seed: u64) -> EmulatedStatistics {
        let d = self.x[0].len();
        let pts = crate::design::halton::halton(d, draws, crate::design::halton::Scrambling::Random, seed);
        let surface: Vec<f64> = pts.iter().map(|u| self.predict(u).0.max(0.0)).collect();
        let statistics = crate::analysis::stats::moments(&surface);
        let m = pts.len().min(256);
        let sub = &pts[..m];
        let n = self.n();
        // Posterior covariance on the sub-design: K** − VᵀV, V = L⁻¹K*.
        let mut v =
            DMatrix::from_fn(n, m, |i, j| self.sigma2 * matern52(dist(&self.x[i], &sub[j], &self.theta)));
        self.chol.l_dirty().solve_lower_triangular_unchecked_mut(&mut v);
        let vtv = v.tr_mul(&v);
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
        let mean_sub: Vec<f64> = sub.iter().map(|u| self.predict(u).0).collect();
        let base = crate::analysis::stats::moments(&mean_sub.iter().map(|v| v.max(0.0)).collect::<Vec<_>>());
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
        let mut shifts: [Vec<f64>; 4] = Default::default();
        if let Some(chol) = chol {
            let l = chol.unpack();
            for _ in 0..paths {
                let e = DVector::from_iterator(m, (&mut rng).sample_iter(StandardNormal).take(m));
                let c = &l * e;
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

    /// Where MFR is zero to the emulator among `pts` (unit coordinates): the share where its
    /// mean is below `level` (the estimate), and the share where even its upper 95 % bound
    /// (mean + 1.96 SE) is (zero for sure: the smooth surface rounds the kink, so this share is
    /// the smaller).
    pub fn zero_fraction(&self, pts: &[Vec<f64>], level: f64) -> (f64, f64) {
        let (mut likely, mut sure) = (0usize, 0usize);
        for u in pts {
            let (m, s) = self.predict(u);
            likely += usize::from(m < level);
            sure += usize::from(m + 1.96 * s < level);
        }
        let n = pts.len().max(1) as f64;
        (likely as f64 / n, sure as f64 / n)
    }

    /// Candidates (unit coordinates) ranked by the emulator's MFR, highest first: (index into
    /// `candidates`, mean, SE).
    pub fn rank(&self, candidates: &[Vec<f64>]) -> Vec<(usize, f64, f64)> {
        let mut r: Vec<(usize, f64, f64)> = candidates
            .iter()
            .enumerate()
            .map(|(i, u)| {
                let (m, s) = self.predict(u);
                (i, m.max(0.0), s)
            })
            .collect();
        r.sort_by(|a, b| b.1.total_cmp(&a.1));
        r
    }
}

/// `k` of the indices 0..n (all of them when n ≤ k), a seeded random choice, in order.
pub fn subset(n: usize, k: usize, seed: u64) -> Vec<usize> {
    use rand::seq::SliceRandom;
    let mut idx: Vec<usize> = (0..n).collect();
    if n > k {
        idx.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
        idx.truncate(k);
        idx.sort_unstable();
    }
    idx
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth 2-D function and a kinked one (zero over a third of the square).
    fn smooth(u: &[f64]) -> f64 {
        (3.0 * u[0]).sin() + u[1] * u[1]
    }

    fn kinked(u: &[f64]) -> f64 {
        (u[0] + 0.5 * u[1] - 0.5).max(0.0)
    }

    fn design(n: usize) -> Vec<Vec<f64>> {
        crate::design::halton::halton(2, n, crate::design::halton::Scrambling::Random, 3)
    }

    #[test]
    fn the_factor_solves_a_hand_system_and_refuses_an_indefinite_one() {
        // [[4, 2], [2, 3]] = L Lᵀ with L = [[2, 0], [1, √2]].
        let c = factor(DMatrix::from_row_slice(2, 2, &[4.0, 2.0, 2.0, 3.0])).unwrap();
        let l = c.l();
        assert!(
            (l[(0, 0)] - 2.0).abs() < 1e-15
                && (l[(1, 0)] - 1.0).abs() < 1e-15
                && (l[(1, 1)] - 2f64.sqrt()).abs() < 1e-15
        );
        // Solve [[4, 2], [2, 3]] v = [2, 5]: v = [−0.5, 2]; L w = [2, 5]: w = [1, 4/√2].
        let v = c.solve(&DVector::from_column_slice(&[2.0, 5.0]));
        assert!((v[0] + 0.5).abs() < 1e-14 && (v[1] - 2.0).abs() < 1e-14, "{v:?}");
        let w = forward(&c, DVector::from_column_slice(&[2.0, 5.0]));
        assert!((w[0] - 1.0).abs() < 1e-15 && (w[1] - 4.0 / 2f64.sqrt()).abs() < 1e-14, "{w:?}");
        // Not positive definite, or not finite: no factor (the fit and the paths' jitter loop
        // read `None` as "not positive definite").
        assert!(factor(DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0])).is_none());
        assert!(factor(DMatrix::from_row_slice(2, 2, &[f64::NAN, 0.0, 0.0, 1.0])).is_none());
        assert!(factor(DMatrix::from_row_slice(2, 2, &[f64::INFINITY, 0.0, 0.0, 1.0])).is_none());
    }

    #[test]
    fn interpolates_a_smooth_function_and_knows_its_error() {
        let x = design(60);
        let y: Vec<f64> = x.iter().map(|u| smooth(u)).collect();
        let e = Emulator::fit(&x, &y, &vec![None; 60]).unwrap();
        let test = crate::design::halton::halton(2, 200, crate::design::halton::Scrambling::Random, 99);
        let err: f64 = test.iter().map(|u| (e.predict(u).0 - smooth(u)).powi(2)).sum::<f64>() / 200.0;
        assert!(err.sqrt() < 0.01, "rmse {}", err.sqrt());
        let cv = e.loo(&y, &vec![None; 60]);
        assert!(cv.q2 > 0.99 && cv.rmse < 0.02, "{cv:?}");
        // Far from the data the SE grows.
        let (_, near) = e.predict(&x[5]);
        let (_, far) = e.predict(&[1.6, 1.6]);
        assert!(far > 10.0 * near.max(1e-6), "{near} {far}");
    }

    #[test]
    fn noisy_data_give_a_nugget_and_honest_loo_coverage() {
        let x = design(150);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let y: Vec<f64> = x.iter().map(|u| smooth(u) + 0.05 * rng.sample::<f64, _>(StandardNormal)).collect();
        let se = vec![Some(0.05); 150];
        let e = Emulator::fit(&x, &y, &se).unwrap();
        let cv = e.loo(&y, &se);
        // The left-out residuals are about the noise (0.05), and ~95 % fall inside ±1.96 SE.
        assert!(cv.rmse > 0.04 && cv.rmse < 0.08, "{cv:?}");
        assert!(cv.coverage95 > 0.88, "{cv:?}");
        // The prediction averages the noise out: closer to the truth than the data are.
        let test = crate::design::halton::halton(2, 200, crate::design::halton::Scrambling::Random, 98);
        let err = (test.iter().map(|u| (e.predict(u).0 - smooth(u)).powi(2)).sum::<f64>() / 200.0).sqrt();
        assert!(err < 0.035, "{err}");
    }

    #[test]
    fn statistics_of_a_kinked_function_come_near_the_truth_and_the_zero_region_is_found() {
        // Truth by a dense grid: P(MFR = 0) = P(u + v/2 < 0.5) = 0.3125 - 0.0625 = 0.25 + ... ;
        // computed here on 400 × 400 cell midpoints.
        let g = 400;
        let truth: Vec<f64> = (0..g * g)
            .map(|k| kinked(&[((k / g) as f64 + 0.5) / g as f64, ((k % g) as f64 + 0.5) / g as f64]))
            .collect();
        let tm = crate::analysis::stats::moments(&truth);
        let zero_share = truth.iter().filter(|v| **v == 0.0).count() as f64 / truth.len() as f64;
        let x = design(100);
        let y: Vec<f64> = x.iter().map(|u| kinked(u)).collect();
        let e = Emulator::fit(&x, &y, &vec![None; 100]).unwrap();
        let s = e.space_statistics(4096, 100, 1);
        let (m, sd) = (s.statistics.mean.unwrap(), s.statistics.std.unwrap());
        assert!((m / tm.mean.unwrap() - 1.0).abs() < 0.02, "{m} vs {:?}", tm.mean);
        assert!((sd / tm.std.unwrap() - 1.0).abs() < 0.03, "{sd} vs {:?}", tm.std);
        let iv = s.intervals[0];
        assert!(iv.lo.unwrap() <= m && m <= iv.hi.unwrap());
        let pts = crate::design::halton::halton(2, 2000, crate::design::halton::Scrambling::Random, 7);
        let (likely, sure) = e.zero_fraction(&pts, 0.01);
        assert!((likely - zero_share).abs() < 0.05, "{likely} vs {zero_share}");
        assert!(sure > 0.5 * zero_share && sure <= likely, "{sure} vs {zero_share}");
        // The best candidate is the corner (1, 1), where the function is largest.
        let r = e.rank(&[vec![0.2, 0.2], vec![1.0, 1.0], vec![0.5, 0.5]]);
        assert_eq!(r[0].0, 1);
    }

    #[test]
    fn a_censored_fit_keeps_the_kink_where_flow_stops_sharp() {
        // A curved flow rate that stops (zero over ~30 % of the square), sampled at 60 points:
        // fitted as values, the zeros pull the surface up near the kink; fitted as a floor, the
        // latent surface crosses zero where the truth does.
        let f = |u: &[f64]| ((u[0] + 0.5 * u[1] - 0.55) * (1.0 + u[1])).max(0.0);
        let g = 300;
        let truth: Vec<f64> = (0..g * g)
            .map(|k| f(&[((k / g) as f64 + 0.5) / g as f64, ((k % g) as f64 + 0.5) / g as f64]))
            .collect();
        let tm = crate::analysis::stats::moments(&truth);
        let x = design(60);
        let y: Vec<f64> = x.iter().map(|u| f(u)).collect();
        let se = vec![Some(0.005); 60];
        let pts = crate::design::halton::halton(2, 4096, crate::design::halton::Scrambling::Random, 5);
        let err = |e: &Emulator| {
            let m =
                crate::analysis::stats::moments(&pts.iter().map(|u| e.mean(u).max(0.0)).collect::<Vec<_>>());
            let rel = |a: Option<f64>, b: Option<f64>| (a.unwrap() / b.unwrap() - 1.0).abs();
            (rel(m.mean, tm.mean), rel(m.std, tm.std), (m.skewness.unwrap() - tm.skewness.unwrap()).abs())
        };
        let (plain_fit, floored_fit) =
            (Emulator::fit(&x, &y, &se).unwrap(), Emulator::fit_censored(&x, &y, &se).unwrap());
        let (plain, floored) = (err(&plain_fit), err(&floored_fit));
        // Left out, a zero run is compared with the prediction's positive part, never with
        // its imputed latent value.
        let (cp, cf) = (plain_fit.loo(&y, &se), floored_fit.loo(&y, &se));
        assert!(cf.rmse < 0.5 * cp.rmse && cf.rmse < 0.005, "plain {cp:?} censored {cf:?}");
        assert!(floored.0 < plain.0 && floored.2 < plain.2, "plain {plain:?} censored {floored:?}");
        // Without zeros it is the plain fit.
        let yp: Vec<f64> = y.iter().map(|v| v + 0.1).collect();
        let (a, b) = (Emulator::fit(&x, &yp, &se).unwrap(), Emulator::fit_censored(&x, &yp, &se).unwrap());
        assert_eq!(a.mean(&[0.3, 0.7]), b.mean(&[0.3, 0.7]));
    }

    #[test]
    fn a_fit_that_threads_the_noise_is_fitted_again_with_the_length_prior() {
        // 316L's 12 pours on LIGGGHTS (docs/study/calibration/record-316l-rolling/pours.tsv):
        // rolling friction over its prior 0.02–0.4 in unit coordinates, angle and its SE. The
        // heap rises by about 6° over the range, pour-to-pour scatter about 3°.
        let pours = [
            (0.1413, 22.37, 1.16),
            (0.3313, 32.84, 1.49),
            (0.0463, 25.38, 2.44),
            (0.2363, 30.91, 1.96),
            (0.3487, 31.06, 2.65),
            (0.1587, 29.06, 1.68),
            (0.3485, 30.67, 2.15),
            (0.1585, 26.93, 1.19),
            (0.1680, 28.06, 2.14),
            (0.1751, 26.96, 1.23),
            (0.1849, 24.41, 1.35),
            (0.1938, 32.49, 1.96),
        ];
        let x: Vec<Vec<f64>> = pours.iter().map(|p| vec![(p.0 - 0.02) / 0.38]).collect();
        let y: Vec<f64> = pours.iter().map(|p| p.1).collect();
        let se: Vec<Option<f64>> = pours.iter().map(|p| Some(p.2)).collect();
        // By likelihood alone the length scale ends at its bound: spikes through every pour.
        let (_, _, z, se2) = standardise(&x, &y, &se).unwrap();
        let (theta, _, _) = likelihood_fit(&x, &z, &se2, None);
        assert!(at_length_bound(&theta), "{theta:?}: the case this guards is gone");
        // The fit refits with the prior: a trend, rising over the range, no spike.
        let e = Emulator::fit(&x, &y, &se).unwrap();
        assert!(e.theta[0] > 0.1, "{:?}", e.theta);
        let (lo, hi) = (e.predict(&[0.1]).0, e.predict(&[0.85]).0);
        assert!(hi - lo > 2.0, "{lo} {hi}");
    }

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
        let pts = crate::design::halton::halton(2, 4096, crate::sweep::Scrambling::Random, 14);
        let plain =
            crate::analysis::stats::moments(&pts.iter().map(|u| e.predict(u).0.max(0.0)).collect::<Vec<_>>());
        let (p, iv) = (plain.skewness.unwrap(), s.intervals[2]);
        assert!(p > iv.hi.unwrap(), "plain skewness {p} inside {iv:?}: the test shows nothing");
    }

    #[test]
    fn too_few_points_or_a_constant_output_give_no_emulator() {
        let x = design(5);
        assert!(Emulator::fit(&x, &[1.0; 5], &[None; 5]).is_none());
        let x = design(20);
        assert!(Emulator::fit(&x, &[0.3; 20], &[None; 20]).is_none());
    }
}
