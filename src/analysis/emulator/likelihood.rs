//! The emulator's hyperparameters (length scales θ, signal variance σ², nugget τ²) by maximum
//! marginal likelihood, Nelder–Mead on their logarithms within bounds, with a log-normal prior
//! on the length scales where the likelihood alone threads the noise.

use crate::analysis::simplex::minimise;

use super::{condition, memo, subset, FIT_POINTS};

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

/// The shortest length scale (unit coordinates) a fit may take.
const MIN_LENGTH: f64 = 0.01;

/// The log-normal prior (median, SD of the logarithm) on each length scale with which
/// [`super::Emulator::fit`] fits again when a length scale ends at [`MIN_LENGTH`]. Why: a dozen noisy
/// runs (a calibration's pours) can have their likelihood highest there — the process then
/// threads every run's scatter as a spike and reverts to its mean between runs, and the
/// posterior of the parameter comes back as its prior (316L's rolling friction from 12 pours,
/// docs/study/calibration.md). The prior costs such a length scale 5.8 nats; a trend, nothing.
pub const LENGTH_PRIOR: (f64, f64) = (0.3, 1.0);

/// Whether a fit's length scales end at [`MIN_LENGTH`] (within its optimiser's reach of it).
pub(super) fn at_length_bound(theta: &[f64]) -> bool {
    theta.iter().any(|t| *t <= MIN_LENGTH * 1.001)
}

/// Length scales, signal variance and nugget maximising the marginal likelihood of `z`, times
/// a log-normal prior (median, SD of the logarithm) on each length scale where one is given.
pub(super) fn likelihood_fit(
    x: &[Vec<f64>],
    z: &[f64],
    se2: &[f64],
    prior: Option<(f64, f64)>,
) -> (Vec<f64>, f64, f64) {
    let d = x[0].len();
    let key = memo::key(x, z, se2, prior);
    if let Some(fit) = memo::recall(&key).filter(|f| f.0.len() == d) {
        return fit;
    }
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
    memo::remember(key, &theta, best[d].exp(), best[d + 1].exp());
    (theta, best[d].exp(), best[d + 1].exp())
}

#[cfg(test)]
mod tests {
    use super::super::{standardise, Emulator};
    use super::*;

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
}
