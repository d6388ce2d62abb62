//! The one consumer of the pool's events: joblog lines, results.csv (rewritten as points
//! finish), progress, and the per-space hook ([`SpaceHook`]) where the convergence rule plugs in
//! ([`Watch`]).

use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

use super::Summary;
use crate::error::Result;
use crate::outcome::RunOutcome;
use crate::run::pool::{Event, Flow};
use crate::run::progress::{Counts, Progress, ProgressMode};
use crate::run::screen::{Screen, Verdict};
use crate::run::RunError;
use crate::store::{self, Manifest, PointRecord, PointStatus, SpaceRecord, Store};

use crate::analysis::convergence::{judge, space_values, Criteria, SpaceStats};
use crate::analysis::stats::Bootstrap;

/// Least time between two rewrites of results.csv while points finish.
const RESULTS_EVERY: std::time::Duration = std::time::Duration::from_secs(1);

/// Called after each nested space has all its points finished, in space order, with that
/// space's points. [`Watch`] (the convergence rule) and [`RunAll`] implement it; `Flow::Drain`
/// stops starting new runs.
pub trait SpaceHook {
    fn space_complete(&mut self, space: &SpaceRecord, points: &[(&PointRecord, &PointStatus)]) -> Flow;
}

/// The hook that never stops a sweep.
pub struct RunAll;

impl SpaceHook for RunAll {
    fn space_complete(&mut self, _: &SpaceRecord, _: &[(&PointRecord, &PointStatus)]) -> Flow {
        Flow::Continue
    }
}

/// The one consumer of pool events: joblog, results.csv, progress, spaces, the screen's verdict.
pub(super) struct Reporter<'a> {
    store: &'a Store,
    manifest: &'a Manifest,
    status: Vec<PointStatus>,
    by_hash: BTreeMap<&'a str, usize>,
    /// Unfinished points per space, and the spaces each point is in.
    unfinished: Vec<usize>,
    member_of: Vec<Vec<usize>>,
    next_space: usize,
    hook: &'a mut dyn SpaceHook,
    pub(super) stopped_after: Option<String>,
    joblog: store::Joblog,
    counts: Counts,
    ran: usize,
    progress: Progress,
    results_dirty: bool,
    results_written: Instant,
    pub(super) errors: Vec<String>,
    screen: Screen,
    /// The screen's verification sample (point indices).
    sample: BTreeSet<usize>,
    /// Closed points queued to run (again) and not finished yet.
    awaiting: BTreeSet<usize>,
    /// Runs another process holds, waited for: the progress line names the holder.
    held: BTreeMap<String, store::ClaimInfo>,
    pub(super) verdict: Verdict,
    /// results.csv's columns of the fixed parameters and of the layout's own quantities.
    columns: store::Columns,
}

/// `1 held by node7 (pid 4242, lease renewed 12 s ago)`: the runs other processes hold, which
/// this one waits for, and who holds the first; `None` when none is held.
fn held_note(held: &BTreeMap<String, store::ClaimInfo>, now: f64) -> Option<String> {
    let c = held.values().next()?;
    let renewed = c.renewed_at.unwrap_or(c.claimed_at);
    let lease = match c.lease_s {
        Some(l) => format!("lease {:.0} s, renewed {:.0} s ago", l, (now - renewed).max(0.0)),
        None => "a claim without a lease: it stands until its holder ends".into(),
    };
    let others = if held.len() > 1 { " (and others)" } else { "" };
    Some(format!("{} held by {} pid {} ({lease}){others}, waited for", held.len(), c.host, c.pid))
}

impl<'a> Reporter<'a> {
    /// Write the joblog line of each finished run whose process was killed before writing it,
    /// unless a line is there (`recovered`: finished runs no live process holds, with the time
    /// their last attempt claimed them if its claim said; else the outcome file's time).
    pub(super) fn log_recovered(&mut self, store: &Store, recovered: &[(String, Option<f64>)]) -> Result<()> {
        let logged = store::logged_outcomes(store.dir())?;
        for (hash, claimed_at) in recovered.iter().filter(|(h, _)| !logged.contains(h)) {
            let outcome = match store.finished(hash) {
                Some(store::RunState::Done(r)) => RunOutcome::Done(*r),
                Some(store::RunState::Failed(f)) => RunOutcome::Failed(*f),
                _ => continue,
            };
            let claimed_at = claimed_at.unwrap_or_else(|| {
                let t = store.outcome_time(hash).and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok());
                t.map_or(0.0, |d| d.as_secs_f64())
            });
            self.joblog.append(&store::AttemptRecord::finished(hash, &outcome, claimed_at))?;
        }
        Ok(())
    }

    #[expect(clippy::too_many_arguments, reason = "the reporter's whole starting state, one call site")]
    pub(super) fn new(
        store: &'a Store,
        manifest: &'a Manifest,
        status: Vec<PointStatus>,
        mode: ProgressMode,
        hook: &'a mut dyn SpaceHook,
        screen: Screen,
        sample: BTreeSet<usize>,
        awaiting: BTreeSet<usize>,
        columns: store::Columns,
    ) -> Result<Reporter<'a>> {
        let mut member_of = vec![Vec::new(); manifest.points.len()];
        for (k, s) in manifest.spaces.iter().enumerate() {
            for &i in &s.points {
                member_of[i].push(k);
            }
        }
        let done = status.iter().filter(|s| matches!(s, PointStatus::Done(_))).count();
        let failed = status.iter().filter(|s| matches!(s, PointStatus::Failed(_))).count();
        let counts =
            Counts { total: status.len(), done, failed, running: 0, reused: done + failed, screened: 0 };
        let mut rep = Reporter {
            store,
            manifest,
            by_hash: manifest.points.iter().map(|p| (p.hash.as_str(), p.index)).collect(),
            status,
            unfinished: vec![0; manifest.spaces.len()],
            member_of,
            next_space: 0,
            hook,
            stopped_after: None,
            joblog: store
                .joblog()?
                .with_indices(manifest.points.iter().map(|p| (p.hash.clone(), p.index)).collect()),
            counts,
            ran: 0,
            progress: Progress::new(mode, manifest.points.len()),
            results_dirty: true,
            results_written: Instant::now(),
            errors: Vec::new(),
            screen,
            sample,
            awaiting,
            held: BTreeMap::new(),
            verdict: Verdict::Pending,
            columns,
        };
        rep.judge_screen();
        for (k, s) in manifest.spaces.iter().enumerate() {
            rep.unfinished[k] = s.points.iter().filter(|&&i| !rep.status[i].is_finished()).count();
        }
        store::write_results(
            store.dir(),
            &manifest.parameters,
            &rep.columns,
            &manifest.points,
            &rep.status,
            &rep.sample,
        )?;
        Ok(rep)
    }

    /// Judge the screen while it is pending; once verified, screen the held-back closed points
    /// (they finish, as MFR = 0); once refuted, say so loudly (the driver runs them). Both
    /// verdicts are final for the session: after either no closed point's outcome is awaited.
    fn judge_screen(&mut self) {
        if self.verdict != Verdict::Pending {
            return;
        }
        let (verdict, refuted_by) =
            self.screen.judge(&self.manifest.points, &self.status, &self.sample, &self.awaiting);
        match verdict {
            Verdict::Verified if self.awaiting.is_empty() => {
                let before: Vec<bool> = self.status.iter().map(PointStatus::is_finished).collect();
                self.counts.screened = self.screen.apply(verdict, &self.manifest.points, &mut self.status);
                for (i, was) in before.into_iter().enumerate() {
                    if !was && self.status[i].is_finished() {
                        for &k in &self.member_of[i] {
                            self.unfinished[k] = self.unfinished[k].saturating_sub(1);
                        }
                    }
                }
                self.results_dirty = true;
                self.verdict = verdict;
            }
            // A closed point still queued may yet contradict it.
            Verdict::Verified | Verdict::Pending => {}
            Verdict::Refuted => {
                let held = (self.manifest.points.iter())
                    .filter(|p| p.closed && !self.awaiting.contains(&p.index))
                    .filter(|p| matches!(self.status[p.index], PointStatus::Pending))
                    .count();
                self.progress.warn(&format!(
                    "warning: SCREEN REFUTED: {}; it is not trusted in this sweep: the {held} closed \
                     point(s) it would skip run for real",
                    crate::run::screen::refutation(&refuted_by)
                ));
                self.verdict = verdict;
            }
            Verdict::Off | Verdict::NoneClosed => self.verdict = verdict,
        }
    }

    /// Call the hook for every space, in order, whose points have all finished.
    pub(super) fn fire_spaces(&mut self) -> Flow {
        while self.stopped_after.is_none()
            && self.next_space < self.manifest.spaces.len()
            && self.unfinished[self.next_space] == 0
        {
            let space = &self.manifest.spaces[self.next_space];
            let rows: Vec<(&PointRecord, &PointStatus)> =
                space.points.iter().map(|&i| (&self.manifest.points[i], &self.status[i])).collect();
            if self.hook.space_complete(space, &rows) == Flow::Drain {
                self.stopped_after = Some(space.label.clone());
            }
            self.next_space += 1;
        }
        if self.stopped_after.is_some() {
            Flow::Drain
        } else {
            Flow::Continue
        }
    }

    pub(super) fn event(&mut self, e: &Event) -> Flow {
        match e {
            Event::Started { hash } => {
                self.counts.running += 1;
                self.ran += 1;
                self.held.remove(hash);
            }
            Event::Busy { hash, owner } => {
                self.held.insert(hash.clone(), owner.clone());
            }
            // The pool wrote its joblog line.
            Event::Attempt { .. } => {}
            Event::Finished { hash, outcome, ran } => {
                self.held.remove(hash);
                if *ran {
                    self.counts.running -= 1;
                }
                if let Some(&i) = self.by_hash.get(hash.as_str()) {
                    let new = match outcome {
                        RunOutcome::Done(r) => Some(PointStatus::Done(Box::new(r.clone()))),
                        RunOutcome::Failed(f) => Some(PointStatus::Failed(Box::new(f.clone()))),
                        RunOutcome::Cancelled => None,
                    };
                    if let Some(new) = new {
                        let was_finished = self.status[i].is_finished();
                        match &self.status[i] {
                            PointStatus::Done(_) => self.counts.done -= 1,
                            PointStatus::Failed(_) => self.counts.failed -= 1,
                            PointStatus::Screened => self.counts.screened -= 1,
                            PointStatus::Pending => {}
                        }
                        match &new {
                            PointStatus::Done(_) => self.counts.done += 1,
                            PointStatus::Failed(_) => self.counts.failed += 1,
                            PointStatus::Screened => self.counts.screened += 1,
                            PointStatus::Pending => {}
                        }
                        self.status[i] = new;
                        self.results_dirty = true;
                        if !was_finished {
                            for &k in &self.member_of[i] {
                                self.unfinished[k] -= 1;
                            }
                        }
                        if self.awaiting.remove(&i) || self.manifest.points[i].closed {
                            self.judge_screen();
                        }
                    }
                }
            }
            Event::StoreError { hash, error } => {
                self.errors.push(format!("{error} (run {})", &hash[..12.min(hash.len())]));
            }
            Event::Tick => {}
        }
        self.progress.set_held(held_note(&self.held, crate::sys::host::unix_now()));
        self.progress.update(&self.counts);
        if self.results_dirty && self.results_written.elapsed() >= RESULTS_EVERY {
            self.write_results();
        }
        let flow = self.fire_spaces();
        // A write error of the sweep directory stops new starts: their outcomes could not be
        // kept either.
        if self.errors.is_empty() {
            flow
        } else {
            Flow::Drain
        }
    }

    fn write_results(&mut self) {
        match store::write_results(
            self.store.dir(),
            &self.manifest.parameters,
            &self.columns,
            &self.manifest.points,
            &self.status,
            &self.sample,
        ) {
            Ok(()) => {
                self.results_dirty = false;
                self.results_written = Instant::now();
            }
            Err(e) => self.errors.push(e.to_string()),
        }
    }

    pub(super) fn finish(mut self, interrupted: bool) -> Result<Summary> {
        self.write_results();
        self.progress.finish(&self.counts);
        if let Some(e) = self.errors.first() {
            let (first, count, dir) = (e.to_string(), self.errors.len(), self.store.dir().to_path_buf());
            return Err(RunError::Writes { first, count, dir }.into());
        }
        let c = self.counts;
        let judged = self.screen.judge(&self.manifest.points, &self.status, &self.sample, &BTreeSet::new());
        let screen = self.screen.report(&self.manifest.points, &self.status, &self.sample, judged);
        Ok(Summary {
            dir: self.store.dir().to_path_buf(),
            points: c.total,
            done: c.done,
            failed: c.failed,
            screened: c.screened,
            pending: c.total - c.done - c.failed - c.screened,
            ran: self.ran,
            reused: c.reused,
            interrupted,
            stopped_after: self.stopped_after,
            screen,
        })
    }
}

/// The rule applied to a running sweep: the driver's [`SpaceHook`]. After each space completes
/// it judges the spaces so far on their done runs' MFR (screened points as 0, failed runs left
/// out) and stops the sweep ([`Flow::Drain`]: no new runs start) at the first converged space.
pub struct Watch {
    criteria: Criteria,
    spaces: Vec<SpaceStats>,
    labels: Vec<String>,
    /// The space (label, point count) the sweep converged at, once it has.
    pub converged_at: Option<(String, usize)>,
}

impl Watch {
    pub fn new(criteria: Criteria) -> Watch {
        Watch { criteria, spaces: Vec::new(), labels: Vec::new(), converged_at: None }
    }
}

impl SpaceHook for Watch {
    fn space_complete(&mut self, space: &SpaceRecord, points: &[(&PointRecord, &PointStatus)]) -> Flow {
        let mfr: Vec<Option<f64>> = points
            .iter()
            .map(|(_, s)| match s {
                PointStatus::Done(r) if r.answer.value.is_finite() => Some(r.answer.value),
                // A closed gap passes nothing: a real zero, not a missing value.
                PointStatus::Screened => Some(0.0),
                _ => None,
            })
            .collect();
        // A complete lattice is weighted as a quadrature; each statistic carries its noise.
        let values: Vec<&[f64]> = points.iter().map(|(p, _)| p.values.as_slice()).collect();
        let (x, w) = space_values(&values, &mfr, self.criteria.lattice_weights);
        self.spaces.push(SpaceStats::of(points.len(), &x, w.as_deref(), &Bootstrap::default()));
        self.labels.push(space.label.clone());
        match judge(&self.spaces, &self.criteria).last() {
            Some(j) if j.converged => {
                self.converged_at = Some((space.label.clone(), points.len()));
                Flow::Drain
            }
            _ => Flow::Continue,
        }
    }
}
