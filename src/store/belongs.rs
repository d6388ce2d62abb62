//! Whether a run's result belongs to the design point the manifest pairs it with: a result is
//! read back only for the point whose parameters it holds, and a manifest whose hashes were
//! swapped is refused, naming the points, rather than pairing each point with another's MFR.
//!
//! The run directory (hash) and the plausibility of the numbers are checked where the result is
//! read ([`super::Store::finished`]); this adds the point.

use std::collections::HashMap;
use std::path::PathBuf;

use super::{Manifest, PointRecord, RunDamage, RunState, Store, StoreError};
use crate::outcome::RunResult;

/// Relative difference below which two parameter values are the same (they went through JSON
/// with every digit; this only absorbs the last bit of a unit conversion).
const SAME: f64 = 1e-9;

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= SAME * a.abs().max(b.abs()).max(1e-300)
}

/// Whether `r` holds the swept `values` under `names`. A parameter the result does not name
/// is not compared (results of the test executors name only what they know).
fn holds(r: &RunResult, names: &[String], values: &[f64]) -> Result<(), RunDamage> {
    for (n, v) in names.iter().zip(values) {
        if let Some(&got) = r.parameters.get(n) {
            if !same(got, *v) {
                return Err(RunDamage::OtherPoint { name: n.clone(), got, expected: *v });
            }
        }
    }
    Ok(())
}

/// Whether `r` holds the sweep's `fixed` values. A result that names the swept parameters
/// (every real run names them all) must name each fixed one with its value; one that names none
/// of them (a test executor's) is not compared.
fn holds_fixed(r: &RunResult, swept: &[String], fixed: &[(String, f64)]) -> Result<(), RunDamage> {
    if !swept.iter().any(|n| r.parameters.contains_key(n)) {
        return Ok(());
    }
    for (n, v) in fixed {
        match r.parameters.get(n) {
            Some(&got) if same(got, *v) => {}
            Some(&got) => return Err(RunDamage::OtherFixed { name: n.clone(), got, sweep: *v }),
            None => return Err(RunDamage::NoFixed { name: n.clone(), sweep: *v }),
        }
    }
    Ok(())
}

impl Store {
    /// The state of point `p`'s run ([`Store::state`]), with a result that holds another
    /// point's parameters turned into [`RunState::Damaged`] (run again, saying why).
    pub fn point_state(&self, manifest: &Manifest, p: &PointRecord) -> RunState {
        self.belongs(manifest, p, self.state(&p.hash))
    }

    /// [`Store::finished`] of point `p`'s run, checked as [`Store::point_state`].
    pub fn point_finished(&self, manifest: &Manifest, p: &PointRecord) -> Option<RunState> {
        self.finished(&p.hash).map(|s| self.belongs(manifest, p, s))
    }

    fn belongs(&self, manifest: &Manifest, p: &PointRecord, state: RunState) -> RunState {
        match state {
            RunState::Done(r) => match holds(&r, &manifest.parameters, &p.values)
                .and_then(|()| holds_fixed(&r, &manifest.parameters, self.fixed()))
            {
                Ok(()) => RunState::Done(r),
                Err(reason) => RunState::Damaged { file: self.result_path(&p.hash), reason },
            },
            s => s,
        }
    }

    fn result_path(&self, hash: &str) -> PathBuf {
        self.run_dir(hash).join("result.json")
    }

    /// Refuse a manifest whose points name each other's runs: for every point whose run's
    /// result holds another point's parameters, look for that point; two points that hold
    /// each other's are a swap, and the error names them.
    pub fn check_pairing(&self, manifest: &Manifest) -> Result<(), StoreError> {
        let key = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        let by_values: HashMap<Vec<u64>, usize> =
            manifest.points.iter().map(|p| (key(&p.values), p.index)).collect();
        // Point i's hash leads to the run of point j.
        let mut leads: HashMap<usize, usize> = HashMap::new();
        for p in &manifest.points {
            let Some(RunState::Done(r)) = self.finished(&p.hash) else { continue };
            if holds(&r, &manifest.parameters, &p.values).is_ok() {
                continue;
            }
            let Some(theirs) = manifest
                .parameters
                .iter()
                .map(|n| r.parameters.get(n).copied())
                .collect::<Option<Vec<f64>>>()
            else {
                continue;
            };
            let found = by_values.get(&key(&theirs)).copied().or_else(|| {
                manifest
                    .points
                    .iter()
                    .find(|q| q.values.iter().zip(&theirs).all(|(a, b)| same(*a, *b)))
                    .map(|q| q.index)
            });
            if let Some(j) = found {
                leads.insert(p.index, j);
            }
        }
        let mut swaps: Vec<(usize, usize)> = leads
            .iter()
            .filter(|&(&i, &j)| i < j && leads.get(&j) == Some(&i))
            .map(|(&i, &j)| (i, j))
            .collect();
        swaps.sort();
        let Some(&(i, j)) = swaps.first() else { return Ok(()) };
        let more = match swaps.len() {
            1 => String::new(),
            n => format!(" (and {} more pairs)", n - 1),
        };
        Err(StoreError::NotASweep {
            path: Store::manifest_path(&self.dir),
            reason: format!(
                "the hashes of points {i} and {j} are swapped{more}: each names the run of the other, \
                 whose result.json holds the other's parameters; the manifest was edited or is damaged \
                 (swap them back, or start the sweep in a new directory)"
            ),
        })
    }
}
