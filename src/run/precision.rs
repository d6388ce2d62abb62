//! The precision a sweep chooses for its points (`[scene] precision = "sweep"`): once its first
//! batch has finished, every later point runs until the standard error of its MFR is at most
//! σ·√(τ/3), σ the spread (standard deviation) of MFR over those points and τ the convergence
//! rule's tolerance (0.129 σ at τ = 0.05); half of that in an adaptive sweep.
//!
//! Why: the sweep's statistics are of MFR over the space, and each point's own noise (variance
//! SE², a share r = SE²/σ² of the spread's) biases them: the standard deviation up by about r/2,
//! the skewness towards 0 by a factor (1 + r)^(−3/2), the excess kurtosis by (1 + r)^(−2). On
//! the convergence rule's scales (docs/statistics.md) the skewness's bias is the largest, at most
//! about 1.5 r; r = τ/3 keeps every statistic's bias within half the tolerance. A tighter point
//! buys a sample (LDS, lattice) nothing; a looser one biases its answer.
//!
//! An adaptive sweep (`sweep adapt`) reads its statistics through the noise-aware emulator,
//! which removes that bias; what the rule waits for there is the width of the emulator's
//! interval on the skewness, which every run's noise sets. On the replayed thesis sweep
//! (BENCHMARKS.md "The answer's cost") runs at σ·√(τ/3) left it 1.1–1.3 times the tolerance
//! after 480 runs, and the rule never held; at half that SE it held on every seed, at 300–420
//! runs, with every target met there, for 540–760 runs' CPU at σ·√(τ/3) (a run at half the SE
//! costs 1.8 of one: the warm-up is most of it). A quarter of the SE cost more (910–1,210),
//! and 0.35 of it more again at the median (760–820). So an adaptive sweep's points run to
//! [`ADAPTIVE_SHARE`] of σ·√(τ/3). The choice is recorded in the sweep
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

/// An adaptive sweep's points run to this share of [`noise_fraction`] (module docs).
pub const ADAPTIVE_SHARE: f64 = 0.5;

/// The precision a sweep chose, and what it was chosen from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepPrecision {
    /// The SE target of MFR every later point runs to.
    pub mfr_abs_se: f64,
    /// The standard deviation of MFR over the first batch.
    pub spread: f64,
    /// The points it was estimated from.
    pub points: usize,
    /// Chosen for an adaptive sweep: [`ADAPTIVE_SHARE`] of σ·√(τ/3). Absent (false) in
    /// records written before adaptive sweeps chose their own.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub adaptive: bool,
}

/// The points the spread is estimated from: four per swept parameter, at least 16.
pub fn first_batch(dim: usize) -> usize {
    (4 * dim).max(16)
}

/// The sweep's precision: the one recorded in `dir`, else, once `mfrs` (every finished point's
/// MFR) holds the first batch, one chosen from their spread and recorded (`adaptive`: for an
/// adaptive sweep). The first process to record it wins; the others read its record.
pub fn settle(dir: &Path, dim: usize, tau: f64, adaptive: bool, mfrs: &[f64]) -> Option<SweepPrecision> {
    if let Some(p) = read(dir) {
        return Some(p);
    }
    let chosen = choose(mfrs, first_batch(dim), tau, adaptive)?;
    // Never over a record another process made first: then that one is read.
    crate::sys::atomic::create_json(&dir.join(PRECISION), &chosen).ok()?;
    read(dir)
}

/// Whether `dir` holds a `sweep adapt` sweep (not a calibration, whose batches are planned alike
/// but whose answer is not the four statistics).
pub fn is_adaptive_sweep(dir: &Path) -> bool {
    let adaptive = crate::store::Store::read_manifest(dir).is_ok_and(|(m, _)| m.design.is_adaptive());
    adaptive && !dir.join(crate::run::calibrate::SETTINGS).exists()
}

/// The recorded precision of the sweep in `dir`.
pub fn read(dir: &Path) -> Option<SweepPrecision> {
    serde_json::from_str(&std::fs::read_to_string(dir.join(PRECISION)).ok()?).ok()
}

/// The precision `mfrs` call for, once there are at least `least` of them and they differ.
fn choose(mfrs: &[f64], least: usize, tau: f64, adaptive: bool) -> Option<SweepPrecision> {
    let finite: Vec<f64> = mfrs.iter().copied().filter(|m| m.is_finite()).collect();
    let n = finite.len();
    if n < least.max(2) {
        return None;
    }
    let mean = finite.iter().sum::<f64>() / n as f64;
    let spread = (finite.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
    let share = if adaptive { ADAPTIVE_SHARE } else { 1.0 };
    (spread > 0.0).then(|| SweepPrecision {
        mfr_abs_se: share * noise_fraction(tau) * spread,
        spread,
        points: n,
        adaptive,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_target_follows_the_spread_once_the_first_batch_is_in() {
        let mfrs: Vec<f64> = (0..16).map(|i| 0.1 + 0.01 * i as f64).collect();
        assert_eq!(choose(&mfrs[..15], 16, 0.05, false), None);
        let p = choose(&mfrs, 16, 0.05, false).unwrap();
        // The sample standard deviation of 0.10, 0.11, ..., 0.25: 0.01 × √(16·17/12) = 0.04761.
        assert!((p.spread - 0.01 * (16.0 * 17.0 / 12.0f64).sqrt()).abs() < 1e-12, "{}", p.spread);
        assert!((p.mfr_abs_se / p.spread - 0.1291).abs() < 1e-4 && p.points == 16);
        // The skewness's bias at that noise share, (1 + r)^(-3/2), is within half of τ.
        let r = (p.mfr_abs_se / p.spread).powi(2);
        assert!(1.0 - (1.0 + r).powf(-1.5) <= 0.025);
        // No spread, no choice: the scene's own target stays.
        assert_eq!(choose(&[0.0; 20], 16, 0.05, false), None);
        // An adaptive sweep's points run to half of it, and say so.
        let a = choose(&mfrs, 16, 0.05, true).unwrap();
        assert!((a.mfr_abs_se - 0.5 * p.mfr_abs_se).abs() < 1e-15 && a.adaptive && !p.adaptive);
    }

    #[test]
    fn an_adaptive_sweep_is_told_by_its_manifest_and_a_calibration_is_not_one() {
        use crate::store::{DesignRecord, Manifest, PointRecord, SpaceRecord, Store, MANIFEST_FORMAT};
        let at = |design: DesignRecord, calibration: bool| {
            let dir = tempfile::tempdir().unwrap();
            let m = Manifest {
                format: MANIFEST_FORMAT,
                tool: "demsweep test".into(),
                name: "t".into(),
                parameters: vec!["gap".into()],
                design,
                spaces: vec![SpaceRecord { label: "s 1".into(), points: vec![0] }],
                points: vec![PointRecord {
                    index: 0,
                    values: vec![1.0],
                    hash: "a".repeat(64),
                    closed: false,
                    seed: None,
                }],
                identity: serde_json::json!({}),
            };
            Store::open(dir.path()).write_manifest("", &m).unwrap();
            if calibration {
                std::fs::write(dir.path().join(crate::run::calibrate::SETTINGS), "{}").unwrap();
            }
            is_adaptive_sweep(dir.path())
        };
        let adapt = || DesignRecord::Adapt { first: 40, batch: 20, max: 480, seed: 14, repeats: 1 };
        assert!(at(adapt(), false));
        assert!(!at(adapt(), true), "a calibration");
        assert!(!at(DesignRecord::Lattice { levels: vec![3] }, false));
        assert!(!is_adaptive_sweep(tempfile::tempdir().unwrap().path()), "no manifest");
    }

    #[test]
    fn the_first_record_stands() {
        let dir = tempfile::tempdir().unwrap();
        let a: Vec<f64> = (0..32).map(|i| i as f64 / 100.0).collect();
        let first = settle(dir.path(), 4, 0.05, false, &a).unwrap();
        // Another process with more points finished reads the record; it does not choose again.
        let b: Vec<f64> = (0..64).map(|i| i as f64 / 50.0).collect();
        assert_eq!(settle(dir.path(), 4, 0.05, false, &b).unwrap(), first);
        assert_eq!(settle(tempfile::tempdir().unwrap().path(), 4, 0.05, false, &a[..15]), None);
    }
}
