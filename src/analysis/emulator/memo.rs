//! Hyperparameters already fitted, recalled by their inputs. A sweep's report fits the same
//! emulators again and again — `sweep resume` on a finished directory, `sweep predict` after a
//! report, the space before the last in the next report — and the likelihood fit is most of a
//! report's CPU. The fit is a pure function of its inputs, so a recalled fit is the one the
//! optimiser would find, to the bit.
//!
//! The fits live for the process; [`export`] and [`import`] carry them across processes (the
//! report keeps them in its sweep directory).

use std::collections::VecDeque;
use std::sync::Mutex;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// Most fits kept: a report fits a handful (the last space, the one before, the sensitivity's
/// surface, each censored fit two or three times).
const KEPT: usize = 32;

/// Changed whenever the likelihood fit changes (its start, bounds, optimiser or subset), so
/// that no fit of an older optimiser is recalled.
const FIT_VERSION: u32 = 1;

/// One fitted set of hyperparameters and the digest of its inputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fit {
    key: String,
    theta: Vec<f64>,
    sigma2: f64,
    nugget: f64,
}

static FITS: Mutex<VecDeque<Fit>> = Mutex::new(VecDeque::new());

fn fits() -> std::sync::MutexGuard<'static, VecDeque<Fit>> {
    // A panic elsewhere while the lock was held leaves a list that is still whole.
    FITS.lock().unwrap_or_else(|e| e.into_inner())
}

/// The digest of a likelihood fit's inputs.
pub(super) fn key(x: &[Vec<f64>], z: &[f64], se2: &[f64], prior: Option<(f64, f64)>) -> String {
    let mut h = Sha256::new();
    h.update(FIT_VERSION.to_le_bytes());
    h.update((x.len() as u64).to_le_bytes());
    h.update((x.first().map_or(0, Vec::len) as u64).to_le_bytes());
    for v in x.iter().flatten().chain(z).chain(se2) {
        h.update(v.to_bits().to_le_bytes());
    }
    match prior {
        Some((m, s)) => {
            h.update([1]);
            h.update(m.to_bits().to_le_bytes());
            h.update(s.to_bits().to_le_bytes());
        }
        None => h.update([0]),
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// The fit remembered for `key`: length scales, signal variance, nugget.
pub(super) fn recall(key: &str) -> Option<(Vec<f64>, f64, f64)> {
    fits().iter().find(|f| f.key == key).map(|f| (f.theta.clone(), f.sigma2, f.nugget))
}

/// Remember a fit, forgetting the oldest past [`KEPT`].
pub(super) fn remember(key: String, theta: &[f64], sigma2: f64, nugget: f64) {
    let mut all = fits();
    all.retain(|f| f.key != key);
    all.push_back(Fit { key, theta: theta.to_vec(), sigma2, nugget });
    while all.len() > KEPT {
        all.pop_front();
    }
}

/// Every fit remembered, oldest first.
pub fn export() -> Vec<Fit> {
    fits().iter().cloned().collect()
}

/// Add fits remembered by another process. One with a value no fit gives (not finite, or not
/// positive) is dropped; one of another dimension is never recalled (see `likelihood_fit`).
pub fn import(list: Vec<Fit>) {
    for f in list {
        if f.theta.iter().chain([&f.sigma2, &f.nugget]).all(|v| v.is_finite() && *v > 0.0) {
            remember(f.key, &f.theta, f.sigma2, f.nugget);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Emulator;
    use super::*;

    fn points(seed: u64) -> (Vec<Vec<f64>>, Vec<f64>) {
        let x = crate::design::halton::halton(2, 40, crate::design::halton::Scrambling::Random, seed);
        let y = x.iter().map(|u| (3.0 * u[0]).sin() + u[1] * u[1]).collect();
        (x, y)
    }

    #[test]
    fn a_fit_is_recalled_by_its_inputs_and_carried_across_processes_as_json() {
        // Inputs no other test fits (the memo is the process's).
        let (x, y) = points(4_417);
        let first = Emulator::fit(&x, &y, &[None; 40]).unwrap();
        // Fitted again: the same to the bit, as the optimiser found it.
        let again = Emulator::fit(&x, &y, &[None; 40]).unwrap();
        assert_eq!((&first.theta, first.sigma2, first.nugget), (&again.theta, again.sigma2, again.nugget));
        // What another process kept is recalled in place of a fit: a planted fit for these
        // inputs comes back as the emulator's.
        let kept = export();
        let json = serde_json::to_string(&kept).unwrap();
        let read: Vec<Fit> = serde_json::from_str(&json).unwrap();
        assert_eq!(read, kept);
        let (x2, y2) = points(4_418);
        let mine = Emulator::fit(&x2, &y2, &[None; 40]).unwrap();
        let mut fake = export().into_iter().rev().find(|f| f.theta == mine.theta).unwrap();
        fake.theta = vec![0.5, 0.25];
        fake.sigma2 = 2.0;
        import(vec![fake.clone()]);
        let recalled = Emulator::fit(&x2, &y2, &[None; 40]).unwrap();
        assert_eq!((recalled.theta.as_slice(), recalled.sigma2), ([0.5, 0.25].as_slice(), 2.0));
        // A fit of another dimension, or of values no fit gives, is never used.
        import(vec![Fit { theta: vec![0.5], ..fake.clone() }]);
        let refit = Emulator::fit(&x2, &y2, &[None; 40]).unwrap();
        assert_eq!((&refit.theta, refit.sigma2), (&mine.theta, mine.sigma2));
        import(vec![Fit { sigma2: f64::NAN, ..fake }]);
        assert!(export().iter().all(|f| f.sigma2.is_finite()));
    }
}
