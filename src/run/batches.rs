//! A sequential design run batch by batch in one sweep directory (`sweep adapt`, `sweep
//! calibrate`): run the planned points, let the design judge the batch (its [`SpaceHook`]), plan
//! the next batch from the results, and go round until the design's rule holds, its `max` is
//! reached or the run is cut off.
//!
//! A planned batch is appended to the manifest as one more space (the first N points), under
//! the directory's lock. Two processes that finish a batch plan the same next one (a batch is a
//! pure function of the results before it); the first appends it, and the other finds it there
//! and runs its share of it.

use std::path::Path;

use super::{RunOptions, Summary};
use crate::error::{Error, Result};
use crate::run::pool::Executor;
use crate::run::pool::Flow;
use crate::run::RunError;
use crate::run::SpaceHook;
use crate::store::{DesignRecord, Manifest, PointRecord, PointStatus, SpaceRecord, Store};
use crate::sweep::Sweep;
use crate::sys::process::CancelToken;

/// The unit-cube coordinates of a design's points (run, failed or screened alike): what its next
/// batch must not plan again, since a setting run again is the same deck.
pub fn taken(sweep: &Sweep, points: &[PointRecord]) -> Vec<Vec<f64>> {
    points.iter().map(|p| crate::sweep::space::unit_point(sweep, &p.values)).collect()
}

/// What a sequential design adds to a space hook: what it says of its batches, whether its rule
/// has held, and its next batch.
pub trait Sequential: SpaceHook {
    /// The design, as a directory that is not one of it is told (`not an adaptive sweep`).
    const DESIGN: &'static str;
    /// The lines said about the batches judged since the last call.
    fn take_lines(&mut self) -> Vec<String>;
    /// Whether the design's rule has held.
    fn converged(&self) -> bool;
    /// Plan the next batch `from` the directory as it stands and append it ([`append`]). `true`
    /// when there are new points to run, planned here or by another process; `false` when the
    /// design's `max` is reached or the last space was not judged (unfinished).
    fn plan_next<E: Executor>(&self, exec: &E, from: &PlanFrom) -> Result<bool>;
}

/// What a sequential design plans its next batch from.
pub struct PlanFrom<'a> {
    pub dir: &'a Path,
    /// The directory's manifest, every point of it run.
    pub manifest: &'a Manifest,
    pub sweep: &'a Sweep,
    /// The label of the manifest's last space: the batch the design must have judged.
    pub last: &'a str,
    /// Settings in the next batch: the design's `batch`, or as many as its `max` (which counts
    /// runs, `repeats` of each setting) leaves room for; never 0.
    pub size: usize,
    /// The design's seed.
    pub seed: u64,
    /// Runs of each setting.
    pub repeats: usize,
}

/// Append the next batch of the design in `dir`, planned by `watch` (`ran`: the points of the
/// manifest just run; a manifest that has grown past them holds a batch another process
/// planned). `true` when there are new points to run.
pub fn plan_next<E: Executor, W: Sequential>(dir: &Path, exec: &E, watch: &W, ran: usize) -> Result<bool> {
    let (manifest, toml) = Store::read_manifest(dir)?;
    if manifest.points.len() > ran {
        return Ok(true);
    }
    let sweep = Sweep::parse(&toml, &dir.join("sweep.toml"))?;
    let Some(last) = manifest.spaces.last() else { return Ok(false) };
    let DesignRecord::Adapt { batch, max, seed, repeats, .. } = manifest.design else {
        return Err(RunError::Dir { path: dir.to_path_buf(), why: format!("not {}", W::DESIGN) }.into());
    };
    let size = batch.min(max.saturating_sub(manifest.points.len()) / repeats.max(1));
    if size == 0 {
        return Ok(false);
    }
    let from = PlanFrom { dir, manifest: &manifest, sweep: &sweep, last: &last.label, size, seed, repeats };
    watch.plan_next(exec, &from)
}

/// Run the sequential design in `dir` until its rule holds, `max` points have run, a point is
/// left unfinished, or it is interrupted: batch by batch, each planned from the results before.
pub fn run<E: Executor, W: Sequential>(
    dir: &Path,
    exec: &E,
    opts: &RunOptions,
    watch: &mut W,
    cancel: &CancelToken,
) -> Result<Summary> {
    let mut ran = 0;
    let mut reused = None;
    let mut before: Option<Summary> = None;
    loop {
        let mut s = match super::resume(dir, exec, opts, watch, cancel) {
            // Interrupted while preparing the next batch's runs: the sweep as it stood.
            Err(Error::Interrupted) if before.is_some() => {
                let mut s = before.take().expect("checked");
                s.interrupted = true;
                return Ok(s);
            }
            r => r?,
        };
        ran += s.ran;
        if opts.progress != crate::run::progress::ProgressMode::Quiet {
            for line in watch.take_lines() {
                eprintln!("{line}");
            }
        }
        let reused_first = *reused.get_or_insert(s.reused);
        s.ran = ran;
        s.reused = reused_first;
        let stop = s.interrupted || s.stopped_after.is_some() || s.pending > 0 || watch.converged();
        if stop || !plan_next(dir, exec, watch, s.points)? {
            return Ok(s);
        }
        before = Some(s);
    }
}

/// Judge the spaces of `manifest` whose points have all finished (`status`), in order, as a run
/// does, until one has not or the design's rule holds: the space it held at, if it did.
pub fn judge_finished<'m, W: SpaceHook>(
    manifest: &'m Manifest,
    status: &[PointStatus],
    watch: &mut W,
) -> Option<&'m SpaceRecord> {
    for space in &manifest.spaces {
        if space.points.iter().any(|&i| !status[i].is_finished()) {
            break;
        }
        let rows: Vec<(&PointRecord, &PointStatus)> =
            space.points.iter().map(|&i| (&manifest.points[i], &status[i])).collect();
        if watch.space_complete(space, &rows) == Flow::Drain {
            return Some(space);
        }
    }
    None
}

/// One planned point: its parameter values and what the design says of it.
pub struct Planned<'a, T> {
    pub values: Vec<f64>,
    /// Its own `scene.seed` (a repeat of a setting), or the sweep's.
    pub seed: Option<u64>,
    pub note: &'a T,
}

/// Append `planned` to the manifest of `dir` as one new space named `{name} N` (N its points),
/// if the manifest still stands as `from` (the one it was planned from); a point whose deck is
/// already in the manifest is left out. `closed(job)` marks points the screen will not run;
/// `record` writes the design's own account of the new rows (point index, note) under the
/// lock. `true` when the batch was appended here or another process had appended one first.
pub fn append<E: Executor, T>(
    dir: &Path,
    exec: &E,
    from: &Manifest,
    planned: &[Planned<T>],
    name: &str,
    closed: impl Fn(&E::Job) -> bool,
    record: impl FnOnce(&[(usize, &T)]) -> Result<()>,
) -> Result<bool> {
    let jobs: Vec<E::Job> =
        planned.iter().map(|p| exec.prepare_seeded(&p.values, p.seed)).collect::<Result<_>>()?;
    let base = from.points.len();
    let mut appended = false;
    Store::open(dir).update_manifest(
        |now: Option<(Manifest, String)>| -> Result<Option<(Manifest, String)>> {
            let Some((mut m, t)) = now else { return Ok(None) };
            // Another process planned this batch first: run its.
            if m.spaces.len() != from.spaces.len() || m.points.len() != base {
                appended = true;
                return Ok(None);
            }
            let mut rows = Vec::new();
            for (p, job) in planned.iter().zip(&jobs) {
                let hash = exec.hash(job);
                if m.points.iter().any(|q| q.hash == hash) {
                    continue;
                }
                let index = m.points.len();
                m.points.push(PointRecord {
                    index,
                    values: p.values.clone(),
                    hash: hash.to_string(),
                    closed: closed(job),
                    seed: p.seed,
                });
                rows.push((index, p.note));
            }
            if rows.is_empty() {
                return Ok(None);
            }
            let n = m.points.len();
            m.spaces.push(SpaceRecord { label: format!("{name} {n}"), points: (0..n).collect() });
            record(&rows)?;
            appended = true;
            Ok(Some((m, t)))
        },
    )?;
    Ok(appended)
}

/// `text`, a design's CSV of planned rows (`batch,index,…` under a header), without the rows of
/// the point indices in `rows`: those of a batch written before a kill cut off the manifest's
/// append, which plans the same points again under the same indices.
pub fn without_replanned<T>(text: String, rows: &[(usize, T)]) -> String {
    let again = |line: &str| {
        let index = line.split(',').nth(1).and_then(|i| i.parse::<usize>().ok());
        index.is_some_and(|i| rows.iter().any(|(r, _)| *r == i))
    };
    if !text.lines().skip(1).any(again) {
        return text;
    }
    let mut kept: String = text
        .lines()
        .enumerate()
        .filter(|(n, l)| *n == 0 || !again(l))
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    kept.shrink_to_fit();
    kept
}

#[cfg(test)]
mod tests {
    #[test]
    fn rows_planned_again_replace_those_a_kill_left() {
        let text = "batch,index,x\n1,0,0.5\n1,1,0.6\n2,2,0.7\n2,3,0.8\n".to_string();
        let again = [(2, ()), (3, ())];
        assert_eq!(super::without_replanned(text.clone(), &again), "batch,index,x\n1,0,0.5\n1,1,0.6\n");
        assert_eq!(super::without_replanned(text.clone(), &[(4, ())]), text, "nothing to drop: unchanged");
    }
}
