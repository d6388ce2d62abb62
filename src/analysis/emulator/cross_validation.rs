//! Leave-one-out cross-validation of the emulator in closed form (Rasmussen & Williams 2006,
//! Eq. 5.12), hyperparameters held.

use nalgebra::DMatrix;
use serde::Serialize;

use super::Emulator;

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

impl Emulator {
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
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::StandardNormal;

    use super::super::tests::{design, smooth};
    use super::*;

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
}
