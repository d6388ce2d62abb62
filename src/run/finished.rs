//! The finished points beside a run, in its sweep directory: the nearest one it starts from (a
//! warm start), and the MFRs the sweep's precision is chosen from ([`crate::run::precision`]).
//!
//! Only what is finished counts (its `result.json` is written last and atomically), so a point
//! still running on another process or node is never waited for, and a sweep run by several
//! processes, resumed, or run as a cluster array sees the same kind of neighbours. Which one a
//! run starts from may differ from run to run; its result records it, and its hash does not
//! depend on it.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::Mutex;

use crate::outcome::RunResult;
use crate::point::{Neighbour, RESULT};
use crate::sweep::space::unit_point;
use crate::sweep::Sweep;

/// A neighbour must have deposited at least this MFR: a jammed heap is no head start.
pub const MIN_FLOW: f64 = 0.01;

/// The finished points of one sweep directory seen so far, by hash.
#[derive(Default)]
pub struct FinishedPoints {
    seen: Mutex<HashMap<String, Point>>,
}

#[derive(Clone)]
struct Point {
    mfr: f64,
    /// Where it is in the design's unit cube, if it can start others (flowing and steady, every
    /// swept value recorded).
    start: Option<Vec<f64>>,
    parameters: BTreeMap<String, f64>,
}

impl FinishedPoints {
    /// Look at `runs_dir` again: read the result of every run finished since.
    fn refresh(
        &self,
        sweep: &Sweep,
        runs_dir: &Path,
    ) -> Option<std::sync::MutexGuard<'_, HashMap<String, Point>>> {
        let mut seen = self.seen.lock().ok()?;
        for entry in std::fs::read_dir(runs_dir).ok()?.flatten() {
            let Some(hash) = entry.file_name().to_str().map(str::to_string) else { continue };
            if seen.contains_key(&hash) {
                continue;
            }
            // Not finished yet (or failed): looked at again next time.
            let Some(r) = read_result(&entry.path().join(RESULT)) else { continue };
            seen.insert(hash, point(sweep, &r));
        }
        Some(seen)
    }

    /// The nearest finished point to `values` (swept values, file order) in `runs_dir` that can
    /// start it, other than `own` (ties: the smaller hash).
    pub fn nearest(&self, sweep: &Sweep, runs_dir: &Path, values: &[f64], own: &str) -> Option<Neighbour> {
        let state = crate::scenes::of(&sweep.file.scene).ok()?.warm_start_files()?.state;
        let here = unit_point(sweep, values);
        let seen = self.refresh(sweep, runs_dir)?;
        let mut best: Option<(f64, &String, &Point)> = None;
        for (hash, p) in seen.iter().filter(|(h, _)| *h != own) {
            let Some(unit) = &p.start else { continue };
            if !runs_dir.join(hash).join(state).is_file() {
                continue;
            }
            let d = here.iter().zip(unit).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
            if best.is_none_or(|(bd, bh, _)| d < bd || (d == bd && hash < bh)) {
                best = Some((d, hash, p));
            }
        }
        let (distance, hash, p) = best?;
        Some(Neighbour {
            dir: runs_dir.join(hash),
            hash: hash.clone(),
            parameters: p.parameters.clone(),
            distance,
        })
    }

    /// The MFR of every point finished in `runs_dir` (in no particular order).
    pub fn mfrs(&self, sweep: &Sweep, runs_dir: &Path) -> Vec<f64> {
        self.refresh(sweep, runs_dir).map(|seen| seen.values().map(|p| p.mfr).collect()).unwrap_or_default()
    }
}

fn read_result(path: &Path) -> Option<RunResult> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

fn point(sweep: &Sweep, r: &RunResult) -> Point {
    let values: Option<Vec<f64>> = sweep.swept.iter().map(|p| r.parameters.get(&p.name).copied()).collect();
    let start = values.filter(|_| r.steady && r.answer.value >= MIN_FLOW).map(|v| unit_point(sweep, &v));
    Point { mfr: r.answer.value, start, parameters: r.parameters.clone() }
}
