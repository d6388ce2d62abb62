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
//! 5.12) need the inverse covariance, which is a few lines here. The dense linear algebra is
//! `nalgebra`'s; the Cholesky factor and the triangular solve with many right-hand sides run it
//! in blocks (`cholesky`).
//!
//! MFR is fitted by [`Emulator::fit_censored`]: its zeros (jammed runs) are a floor of a latent
//! flow rate that goes on below zero (the censored regression of Tobin 1958, Econometrica 26,
//! 24–36), not values of a smooth surface.
//!
//! Here the model, its conditioning and prediction; `likelihood` fits its hyperparameters,
//! `cross_validation` leaves each point out, `paths` draws posterior sample paths for the
//! space's statistics.
//!
//! Uses: [`Emulator::predict`] (MFR with its predictive SE at a setting), [`Emulator::loo`]
//! (cross-validation on every sweep), [`Emulator::space_statistics`] (the space's MFR statistics
//! from many cheap draws, with their uncertainty), [`Emulator::zero_fraction`] (where MFR is
//! zero) and [`Emulator::rank`] (the best settings among candidates, with SE).

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

mod cholesky;
mod cross_validation;
mod likelihood;
pub mod memo;
mod paths;
use cholesky::factor;
pub use cross_validation::CrossValidation;
pub use likelihood::LENGTH_PRIOR;
use likelihood::{at_length_bound, likelihood_fit};
pub use paths::EmulatedStatistics;

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

fn matern52(r: f64) -> f64 {
    let s = 5f64.sqrt() * r;
    (1.0 + s + s * s / 3.0) * (-s).exp()
}

fn dist(a: &[f64], b: &[f64], theta: &[f64]) -> f64 {
    a.iter().zip(b).zip(theta).map(|((p, q), t)| ((p - q) / t).powi(2)).sum::<f64>().sqrt()
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
        // The columns of K⁻¹ at the floored runs only (K⁻¹ is symmetric, so column i is row i):
        // each is the one nalgebra's whole inverse would hold, at a share of its cost.
        let n = self.n();
        let kinv: Vec<DVector<f64>> =
            floor.iter().map(|&i| self.chol.solve(&DVector::from_fn(n, |r, _| f64::from(r == i)))).collect();
        let mut alpha = self.alpha.clone();
        for _sweep in 0..100 {
            let mut largest = 0.0f64;
            for (&i, column) in floor.iter().zip(&kinv) {
                let kii = column[i];
                // The leave-one-out prediction of run i's value (its own noise included).
                let m = z[i] - alpha[i] / kii;
                let s = (1.0 / kii).sqrt();
                let a = (c - m) / s;
                // E[v | v ≤ c] for v ~ N(m, s²); the ratio φ/Φ by its asymptote far below.
                let ratio = if a > -30.0 { normal_pdf(a) / normal_cdf(a) } else { -a };
                let new = (m - s * ratio).min(c);
                let step = new - z[i];
                if step != 0.0 {
                    for (al, k) in alpha.iter_mut().zip(column.iter()) {
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

    /// Where MFR is zero to the emulator among `pts` (unit coordinates): the share where its
    /// mean is below `level` (the estimate), and the share where even its upper 95 % bound
    /// (mean + 1.96 SE) is (zero for sure: the smooth surface rounds the kink, so this share is
    /// the smaller).
    pub fn zero_fraction(&self, pts: &[Vec<f64>], level: f64) -> (f64, f64) {
        let (mut likely, mut sure) = (0usize, 0usize);
        for u in pts {
            // The SE (O(N²) a point) only where the mean is below the level: above it, the
            // upper bound is too.
            let m = self.mean(u);
            if m < level {
                likely += 1;
                sure += usize::from(m + 1.96 * self.predict(u).1 < level);
            }
        }
        let n = pts.len().max(1) as f64;
        (likely as f64 / n, sure as f64 / n)
    }

    /// The `top` candidates (unit coordinates) by the emulator's MFR, highest first: (index into
    /// `candidates`, mean, SE). The SE (O(N²) a candidate) only for those returned.
    pub fn rank(&self, candidates: &[Vec<f64>], top: usize) -> Vec<(usize, f64, f64)> {
        let mut r: Vec<(usize, f64)> =
            candidates.iter().enumerate().map(|(i, u)| (i, self.mean(u).max(0.0))).collect();
        r.sort_by(|a, b| b.1.total_cmp(&a.1));
        r.into_iter().take(top).map(|(i, m)| (i, m, self.predict(&candidates[i]).1)).collect()
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
    pub(super) fn smooth(u: &[f64]) -> f64 {
        (3.0 * u[0]).sin() + u[1] * u[1]
    }

    fn kinked(u: &[f64]) -> f64 {
        (u[0] + 0.5 * u[1] - 0.5).max(0.0)
    }

    pub(super) fn design(n: usize) -> Vec<Vec<f64>> {
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
        let cands = [vec![0.2, 0.2], vec![1.0, 1.0], vec![0.5, 0.5]];
        let r = e.rank(&cands, 2);
        assert_eq!((r.len(), r[0].0, r[1].0), (2, 1, 2));
        // Each with the emulator's own mean and SE there.
        let (m, se) = e.predict(&cands[1]);
        assert_eq!((r[0].1, r[0].2), (m.max(0.0), se));
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
    fn too_few_points_or_a_constant_output_give_no_emulator() {
        let x = design(5);
        assert!(Emulator::fit(&x, &[1.0; 5], &[None; 5]).is_none());
        let x = design(20);
        assert!(Emulator::fit(&x, &[0.3; 20], &[None; 20]).is_none());
    }
}
