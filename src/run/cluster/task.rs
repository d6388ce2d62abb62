//! One array task of a cluster sweep (`sweep work`): the design points that are its own, the
//! order in which it runs them and then helps with the others', and its body.
//!
//! Not responsible for the submission (the parent module) or for running points (the pool).

use std::collections::BTreeSet;
use std::path::Path;

use crate::error::Result;
use crate::store::{Manifest, RunState, Store};

use super::flag;

/// The design points of array index `task`: `[task·per_task, (task+1)·per_task)` cut to `n`.
pub fn task_points(task: usize, per_task: usize, n: usize) -> std::ops::Range<usize> {
    let start = task.saturating_mul(per_task).min(n);
    start..start.saturating_add(per_task).min(n)
}

/// The order in which task `task` runs the unfinished points `unfinished` (manifest order):
/// its own first, then — with `steal` — the others that nobody holds (`held`, read when its
/// own are done), beginning after its own block and wrapping, so that tasks helping each other
/// spread out instead of all starting on the same block.
pub fn share_order(
    task: usize,
    per_task: usize,
    steal: bool,
    held: &BTreeSet<usize>,
    unfinished: &[usize],
) -> Vec<usize> {
    let own = task_points(task, per_task, usize::MAX);
    let mut order: Vec<usize> = unfinished.iter().copied().filter(|i| own.contains(i)).collect();
    if steal {
        let (before, after): (Vec<usize>, Vec<usize>) = unfinished
            .iter()
            .copied()
            .filter(|i| !own.contains(i) && !held.contains(i))
            .partition(|&i| i < own.start);
        order.extend(after);
        order.extend(before);
    }
    order
}

/// Points of `dir` held by a live claim now (other tasks are running them).
pub fn held_points(manifest: &Manifest, store: &Store) -> BTreeSet<usize> {
    manifest
        .points
        .iter()
        .filter(|p| matches!(store.state(&p.hash), RunState::Running(_)))
        .map(|p| p.index)
        .collect()
}

/// Rewrite `DIR/results.csv` from what the run dirs hold now, under the directory's lock: each
/// task's pool wrote it from its own view, and the last task to end must leave every task's
/// points in it.
pub fn refresh_results(dir: &Path) -> Result<()> {
    Store::open(dir).locked(|| crate::run::rewrite_results(dir))?
}

/// What one array task runs (`sweep work`).
#[derive(Debug, Clone)]
pub struct WorkOptions {
    /// The array index.
    pub task: usize,
    /// Points per index, from the layout.
    pub per_task: usize,
    /// Help with other tasks' unfinished points once its own are done.
    pub steal: bool,
    /// Run only points below this index (one batch of a chain).
    pub upto: Option<usize>,
    /// MPI ranks per LIGGGHTS run; the pool runs `jobs / ranks` runs at once.
    pub ranks: u32,
}

/// The body of one array task: resume `dir` on this task's share (see [`share_order`]), then
/// rewrite results.csv from the whole directory.
pub fn work(
    dir: &Path,
    w: &WorkOptions,
    opts: &crate::run::RunOptions,
    cancel: &crate::sys::process::CancelToken,
) -> Result<crate::run::Summary> {
    let (manifest, _) = Store::read_manifest(dir)?;
    let n = manifest.points.len();
    if task_points(w.task, w.per_task, n).is_empty() {
        let why = format!(
            "no such task; {n} points at {} per task make tasks 0-{}",
            w.per_task,
            n.div_ceil(w.per_task).saturating_sub(1)
        );
        return Err(flag(format!("--task {}", w.task), why));
    }
    let sweep = crate::run::load_dir_sweep(dir)?;
    if crate::run::standin::selected(&sweep) {
        let exec = crate::run::standin::StandIn::new(sweep)?;
        return work_with(dir, &manifest, &exec, w, opts, cancel);
    }
    let exec = crate::run::PointExecutor::new(sweep)?.with_ranks(w.ranks);
    work_with(dir, &manifest, &exec, w, opts, cancel)
}

/// [`work`] on an executor: the real engine, or the stand-in of a demo sweep.
fn work_with<E: crate::run::pool::Executor>(
    dir: &Path,
    manifest: &Manifest,
    exec: &E,
    w: &WorkOptions,
    opts: &crate::run::RunOptions,
    cancel: &crate::sys::process::CancelToken,
) -> Result<crate::run::Summary> {
    let n = manifest.points.len();
    let upto = w.upto.unwrap_or(usize::MAX);
    let run = |order: crate::run::Order| {
        let batch = |u: &[usize]| order(u).into_iter().filter(|&i| i < upto).collect();
        crate::run::resume_share(dir, exec, opts, Some(&batch), &mut crate::run::RunAll, cancel)
    };
    // Its own points first, waiting for any another task holds (and taking them over if that
    // task is lost); then, in a second pass, the leftovers nobody holds *now*: a helper must
    // not wait on runs that live tasks are doing.
    let none = BTreeSet::new();
    let mut summary = run(&|u: &[usize]| share_order(w.task, w.per_task, false, &none, u))?;
    if w.steal && !summary.interrupted {
        let held = held_points(manifest, &Store::open(dir));
        let own = task_points(w.task, w.per_task, n);
        let others = |u: &[usize]| {
            share_order(w.task, w.per_task, true, &held, u).into_iter().filter(|i| !own.contains(i)).collect()
        };
        let first_ran = summary.ran;
        summary = run(&others)?;
        summary.ran += first_ran;
    }
    refresh_results(dir)?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn task_points_cover_every_point_once() {
        let (n, per) = (10usize, 3usize);
        let all: Vec<usize> = (0..n.div_ceil(per)).flat_map(|t| task_points(t, per, n)).collect();
        assert_eq!(all, (0..n).collect::<Vec<_>>());
        assert!(task_points(7, per, n).is_empty());
    }

    #[test]
    fn a_task_runs_its_own_points_first_then_helps_after_its_block() {
        let unfinished: Vec<usize> = (0..9).collect();
        let held = BTreeSet::from([7]);
        assert_eq!(share_order(1, 3, true, &held, &unfinished), vec![3, 4, 5, 6, 8, 0, 1, 2]);
        assert_eq!(share_order(1, 3, false, &held, &unfinished), vec![3, 4, 5]);
        // Its own points run even when held: it waits for them (and takes them over if the
        // holder is lost).
        assert_eq!(share_order(2, 3, false, &held, &unfinished), vec![6, 7, 8]);
    }
}
