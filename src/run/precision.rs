//! The precision a sweep chooses for its points (`[scene] precision = "sweep"`): once its first
//! batch has finished, every later point runs until the standard error of its MFR is at most
//! σ·√(τ/3), σ the spread (standard deviation) of MFR over those points and τ the convergence
//! rule's tolerance (0.129 σ at τ = 0.05).
//!
//! Why: the sweep's statistics are of MFR over the space, and each point's own noise (variance
//! SE², a share r = SE²/σ² of the spread's) biases them: the standard deviation up by about r/2,
//! the skewness towards 0 by a factor (1 + r)^(−3/2), the excess kurtosis by (1 + r)^(−2). On
//! the convergence rule's scales (docs/statistics.md) the skewness's bias is the largest, at most
//! about 1.5 r; r = τ/3 keeps every statistic's bias within half the tolerance. A tighter point
//! buys the sweep nothing; a looser one biases its answer. The choice is recorded in the sweep
//! directory (`precision.json`), so a resumed sweep, other processes on the same directory and a
//! cluster array's tasks all run to the same target; the runs' hashes do not depend on it, and
//! each result records the target it ran to.

use std::path::Path;

use serde::{Deserialize, Serialize};

/// The record in the sweep directory.
pub const PRECISION: &str = "precision.json";

/// A point's SE over the spread of MFR across the space, for the convergence tolerance `tau`.
pub fn noise_fraction(tau: f64) -> f64 {
    (tau / 3.0).sqrt()
}

/// The precision a sweep chose, and what it was chosen from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepPrecision {
    /// The SE target of MFR every later point runs to.
    pub mfr_abs_se: f64,
    /// The standard deviation of MFR over the first batch.
    pub spread: f64,
    /// The points it was estimated from.
    pub points: usize,
}

/// The points the spread is estimated from: four per swept parameter, at least 16.
pub fn first_batch(dim: usize) -> usize {
    (4 * dim).max(16)
}

/// The sweep's precision: the one recorded in `dir`, else, once `mfrs` (every finished point's
/// MFR) holds the first batch, one chosen from their spread and recorded. The first process to
/// record it wins; the others read its record.
pub fn settle(dir: &Path, dim: usize, tau: f64, mfrs: &[f64]) -> Option<SweepPrecision> {
    if let Some(p) = read(dir) {
        return Some(p);
    }
    let chosen = choose(mfrs, first_batch(dim), tau)?;
    // Never over a record another process made first: then that one is read.
    crate::sys::atomic::create_json(&dir.join(PRECISION), &chosen).ok()?;
    read(dir)
}

/// The recorded precision of the sweep in `dir`.
pub fn read(dir: &Path) -> Option<SweepPrecision> {
    serde_json::from_str(&std::fs::read_to_string(dir.join(PRECISION)).ok()?).ok()
}

/// The precision `mfrs` call for, once there are at least `least` of them and they differ.
fn choose(mfrs: &[f64], least: usize, tau: f64) -> Option<SweepPrecision> {
    let finite: Vec<f64> = mfrs.iter().copied().filter(|m| m.is_finite()).collect();
    let n = finite.len();
    if n < least.max(2) {
        return None;
    }
    let mean = finite.iter().sum::<f64>() / n as f64;
    let spread = (finite.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
    (spread > 0.0).then(|| SweepPrecision { mfr_abs_se: noise_fraction(tau) * spread, spread, points: n })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_target_follows_the_spread_once_the_first_batch_is_in() {
        let mfrs: Vec<f64> = (0..16).map(|i| 0.1 + 0.01 * i as f64).collect();
        assert_eq!(choose(&mfrs[..15], 16, 0.05), None);
        let p = choose(&mfrs, 16, 0.05).unwrap();
        // The sample standard deviation of 0.10, 0.11, ..., 0.25: 0.01 × √(16·17/12) = 0.04761.
        assert!((p.spread - 0.01 * (16.0 * 17.0 / 12.0f64).sqrt()).abs() < 1e-12, "{}", p.spread);
        assert!((p.mfr_abs_se / p.spread - 0.1291).abs() < 1e-4 && p.points == 16);
        // The skewness's bias at that noise share, (1 + r)^(-3/2), is within half of τ.
        let r = (p.mfr_abs_se / p.spread).powi(2);
        assert!(1.0 - (1.0 + r).powf(-1.5) <= 0.025);
        // No spread, no choice: the scene's own target stays.
        assert_eq!(choose(&[0.0; 20], 16, 0.05), None);
    }

    #[test]
    fn the_first_record_stands() {
        let dir = tempfile::tempdir().unwrap();
        let a: Vec<f64> = (0..32).map(|i| i as f64 / 100.0).collect();
        let first = settle(dir.path(), 4, 0.05, &a).unwrap();
        // Another process with more points finished reads the record; it does not choose again.
        let b: Vec<f64> = (0..64).map(|i| i as f64 / 50.0).collect();
        assert_eq!(settle(dir.path(), 4, 0.05, &b).unwrap(), first);
        assert_eq!(settle(tempfile::tempdir().unwrap().path(), 4, 0.05, &a[..15]), None);
    }
}
