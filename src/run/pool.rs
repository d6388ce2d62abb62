//! The job pool: runs the runs of a sweep on `--jobs` slots, as GNU parallel does.
//!
//! - N long-lived worker threads; each takes the next job from one queue as soon as it is free,
//!   so a long run never holds up the slots behind it (thesis §3.3, Fig. 3.9).
//! - Each job is claimed in the [`Store`] first. A run another process holds is put aside and
//!   looked at again once the queue is empty; a run found finished under the claim is reported,
//!   not re-run.
//! - Attempts that fail transiently ([`FailureClass::is_transient`]: could not start, killed by a
//!   signal, timed out) are retried up to `retries` times; a physics failure is final.
//! - The [`CancelToken`] (Ctrl-C, SIGTERM) stops new starts; the running children are killed by
//!   [`crate::sys::process`], their claims released, and their run dirs left incomplete for a resume.
//!   Every child is spawned from its worker thread, which lives until the pool ends, so
//!   its guard, bound by PR_SET_PDEATHSIG, takes the job's whole process group down with this
//!   process even when it is SIGKILLed ([`crate::sys::process`]).
//! - Each worker writes its attempt's joblog line (under the directory lock) before it gives the
//!   claim back, so a finished run always has its line or its claim; otherwise workers only send
//!   [`Event`]s, which the caller's thread consumes (results.csv, progress, the rule). A worker
//!   more than a few events ahead of the consumer waits for it, so the rule stops a sweep a few
//!   runs past the space it judges converged however short the runs are.
//!
//! Not responsible for what a job is (the [`Executor`]) or for what to run (the driver).

use std::collections::{HashMap, VecDeque};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Mutex;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use crate::outcome::{FailureClass, RunOutcome};
use crate::store::{AttemptRecord, ClaimAttempt, ClaimInfo, Joblog, RunState, Store, StoreError};
use crate::sys::process::CancelToken;

/// How often the caller's thread wakes up without events (progress lines, results.csv).
pub const TICK: Duration = Duration::from_millis(250);
/// How often a run held by another process is looked at again.
const BUSY_POLL: Duration = Duration::from_millis(200);
/// Events a slot may have sent that the consumer has not yet taken: a worker waits on the
/// consumer past this, so that while the consumer judges a space (which takes seconds) runs a
/// millisecond long cannot race through the rest of the sweep. A run sends three events.
const EVENTS_AHEAD_PER_SLOT: usize = 6;

/// Runs one attempt of one job. The real one renders and runs a LIGGGHTS deck
/// ([`crate::run::PointExecutor`]); `run::fake::FakeExecutor` stands in for it in tests.
pub trait Executor: Sync {
    /// A prepared job: what `execute` needs, with its content hash.
    type Job: Send + Sync;
    /// What besides the deck determines a run's outcome (template, mesh generator, engine),
    /// recorded in the manifest; a resume refuses when it changed.
    fn identity(&self) -> serde_json::Value;
    /// Prepare the job of one design point (swept values in file order, sweep units). Pure.
    fn prepare(&self, swept: &[f64]) -> crate::Result<Self::Job> {
        self.prepare_seeded(swept, None)
    }
    /// Prepare the job of one design point run with its own `scene.seed` (a repeat of a
    /// setting; `None`: the sweep's seed, as [`Executor::prepare`]). Pure.
    fn prepare_seeded(&self, swept: &[f64], seed: Option<u64>) -> crate::Result<Self::Job>;
    /// The content hash naming the job's run dir.
    fn hash<'a>(&self, job: &'a Self::Job) -> &'a str;
    /// Whether nothing can pass under the blade at this job's point, so that a verified screen
    /// may skip it as MFR = 0 ([`crate::run::screen`]). Engines that model no scene close nothing.
    fn closed(&self, _job: &Self::Job) -> bool {
        false
    }
    /// Run one attempt in `run_dir` (existing, empty but for the claim), writing `result.json`
    /// or `failure.json` there before returning `Done` or `Failed`; `Cancelled` when `cancel`
    /// fired.
    fn execute(&self, job: &Self::Job, run_dir: &Path, cancel: &CancelToken) -> RunOutcome;
}

#[derive(Debug, Clone)]
pub struct PoolOptions {
    /// Concurrent jobs.
    pub slots: usize,
    /// Retries of a transiently failed attempt.
    pub retries: u32,
    /// Re-run failed runs whose `failure.json` is older than this (`--retry-failed`); a failure
    /// written since (by another process of this resume) stands.
    pub retry_failed_before: Option<SystemTime>,
    /// Runs whose `result.json`, when the sweep looked, was not their point's (it holds other
    /// parameters: [`Store::point_state`]), with that file's modification time: found again
    /// under the claim, the same file is run again, not reused; a result written since (by
    /// another process) is its own.
    pub not_theirs: HashMap<String, SystemTime>,
}

/// What the pool reports, in the order it happens for each job.
#[derive(Debug, Clone)]
// One per run, moved once: boxing the result would buy nothing.
#[allow(clippy::large_enum_variant)]
pub enum Event {
    /// A slot started running the job.
    Started { hash: String },
    /// One attempt ended; its joblog line is written. `retrying` when another attempt follows.
    Attempt { record: AttemptRecord, retrying: bool },
    /// The job is over: run here (`ran`), or found finished by another process.
    Finished { hash: String, outcome: RunOutcome, ran: bool },
    /// Another live process holds the run; it is waited for.
    Busy { hash: String, owner: ClaimInfo },
    /// The pool could not use the sweep directory for this job (I/O); it is left pending.
    StoreError { hash: String, error: String },
    /// Nothing happened for [`TICK`].
    Tick,
}

/// What the consumer tells the pool after an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    Continue,
    /// Start no more jobs; let the running ones finish (convergence reached).
    Drain,
}

/// Run `jobs` on the pool, writing each attempt's line to `joblog`. `consume` sees every event
/// on the calling thread.
pub fn run<E: Executor>(
    exec: &E,
    store: &Store,
    joblog: Joblog,
    jobs: Vec<E::Job>,
    opts: &PoolOptions,
    cancel: &CancelToken,
    mut consume: impl FnMut(&Event) -> Flow,
) {
    // Keeps this process's claims alive for other hosts while the pool runs.
    let _heartbeat = store.heartbeat();
    let queue = Mutex::new(jobs.into_iter().collect::<VecDeque<_>>());
    let busy: Mutex<VecDeque<(E::Job, Instant)>> = Mutex::new(VecDeque::new());
    let drain = AtomicBool::new(false);
    let joblog = Mutex::new(joblog);
    let (tx, rx) = mpsc::sync_channel::<Event>(opts.slots.max(1) * EVENTS_AHEAD_PER_SLOT);
    std::thread::scope(|scope| {
        for _ in 0..opts.slots.max(1) {
            let tx = tx.clone();
            let w = Worker {
                exec,
                store,
                joblog: &joblog,
                opts,
                cancel,
                queue: &queue,
                busy: &busy,
                drain: &drain,
                tx,
            };
            scope.spawn(move || w.run());
        }
        drop(tx);
        loop {
            let event = match rx.recv_timeout(TICK) {
                Ok(e) => e,
                Err(mpsc::RecvTimeoutError::Timeout) => Event::Tick,
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            };
            if consume(&event) == Flow::Drain {
                drain.store(true, Ordering::SeqCst);
            }
        }
    });
}

struct Worker<'a, E: Executor> {
    exec: &'a E,
    store: &'a Store,
    joblog: &'a Mutex<Joblog>,
    opts: &'a PoolOptions,
    cancel: &'a CancelToken,
    queue: &'a Mutex<VecDeque<E::Job>>,
    busy: &'a Mutex<VecDeque<(E::Job, Instant)>>,
    drain: &'a AtomicBool,
    tx: mpsc::SyncSender<Event>,
}

impl<E: Executor> Worker<'_, E> {
    fn run(&self) {
        loop {
            if self.cancel.is_cancelled() || self.drain.load(Ordering::SeqCst) {
                return;
            }
            let next = self.queue.lock().unwrap().pop_front();
            let job = match next {
                Some(j) => j,
                None => {
                    // Only runs held by other processes are left: look at the oldest again.
                    let mut busy = self.busy.lock().unwrap();
                    match busy.pop_front() {
                        None => return,
                        Some((job, since)) => {
                            drop(busy);
                            let wait = BUSY_POLL.saturating_sub(since.elapsed());
                            std::thread::sleep(wait);
                            job
                        }
                    }
                }
            };
            let hash = self.exec.hash(&job).to_string();
            if let Err(e) = self.one(job, &hash) {
                // Only an I/O failure of the store lands here (a full disk): the job stays
                // unfinished, and no other starts, since its outcome could not be kept either.
                self.drain.store(true, Ordering::SeqCst);
                self.send(Event::StoreError { hash, error: e.to_string() });
            }
        }
    }

    fn send(&self, e: Event) {
        // The receiver lives as long as the scope: a send cannot fail while workers run.
        let _ = self.tx.send(e);
    }

    /// Write an attempt's joblog line, then tell the consumer. Written here, under the run's
    /// claim, so that a kill can never leave a finished run with neither its line nor its claim.
    fn log(&self, record: AttemptRecord, retrying: bool) -> Result<(), StoreError> {
        self.joblog.lock().unwrap().append(&record)?;
        self.send(Event::Attempt { record, retrying });
        Ok(())
    }

    /// Log an attempt of the process that held the stale claim `by` (its host and pid, not ours).
    fn log_for(&self, record: AttemptRecord, by: &ClaimInfo) -> Result<(), StoreError> {
        self.joblog.lock().unwrap().append_as(&record, &by.host, by.pid)?;
        self.send(Event::Attempt { record, retrying: false });
        Ok(())
    }

    fn one(&self, job: E::Job, hash: &str) -> Result<(), StoreError> {
        let hash = hash.to_string();
        let (claim, stale) = match self.store.claim(&hash)? {
            ClaimAttempt::Busy(owner) => {
                self.send(Event::Busy { hash: hash.clone(), owner });
                self.busy.lock().unwrap().push_back((job, Instant::now()));
                return Ok(());
            }
            ClaimAttempt::Claimed(c, stale) => (c, stale),
        };
        let outcome = self.claimed(job, &hash, stale);
        // Give the claim back whatever happened; a store error is the one to report.
        let released = self.store.release(claim);
        let outcome = outcome?;
        released?;
        if let Some((outcome, ran)) = outcome {
            self.send(Event::Finished { hash, outcome, ran });
        }
        Ok(())
    }

    /// The job under its claim: the outcome and whether it ran here, `None` if cancelled first.
    fn claimed(
        &self,
        job: E::Job,
        hash: &str,
        stale: Option<ClaimInfo>,
    ) -> Result<Option<(RunOutcome, bool)>, StoreError> {
        let hash = hash.to_string();
        // Finished while we were not looking (another process), or earlier and not to retry.
        let found = match self.store.finished(&hash) {
            Some(RunState::Done(_))
                if self
                    .opts
                    .not_theirs
                    .get(&hash)
                    .is_some_and(|&t| self.store.outcome_time(&hash) == Some(t)) =>
            {
                None
            }
            Some(RunState::Done(r)) => Some(RunOutcome::Done(*r)),
            Some(RunState::Failed(f)) => {
                let retry = match (self.opts.retry_failed_before, self.store.failure_time(&hash)) {
                    (Some(before), Some(t)) => t < before,
                    _ => false,
                };
                (!retry).then_some(RunOutcome::Failed(*f))
            }
            _ => None,
        };
        if let Some(outcome) = found {
            // Finished by a process killed before its joblog line: write the line it owed.
            if let Some(old) = stale {
                if !crate::store::logged_outcomes(self.store.dir())?.contains(&hash) {
                    self.log_for(AttemptRecord::finished(&hash, &outcome, old.claimed_at), &old)?;
                }
            }
            return Ok(Some((outcome, false)));
        }
        if let Some(old) = stale {
            // The trace of an attempt that was killed: its claim outlived its process.
            let start = UNIX_EPOCH + Duration::from_secs_f64(old.claimed_at.max(0.0));
            let record = AttemptRecord {
                hash: hash.clone(),
                start,
                runtime_s: f64::NAN,
                status: "interrupted",
                class: None,
            };
            self.log_for(record, &old)?;
        }
        if self.cancel.is_cancelled() {
            return Ok(None);
        }
        self.send(Event::Started { hash: hash.clone() });
        let dir = self.store.run_dir(&hash);
        let mut attempt = 0;
        let outcome = loop {
            // A point run by the pass keeps its finished passes and goes on from the last; it
            // removes what an interrupted pass left itself.
            if !crate::point::passes::has_passes(&dir) {
                self.store.clean_run_dir(&hash)?;
            }
            let start = SystemTime::now();
            let t = Instant::now();
            let outcome = self.exec.execute(&job, &dir, self.cancel);
            // The outcome must be on disk before it counts: write it again if it is not (the
            // executor's write may have failed), and stop on a store error.
            let stored = match &outcome {
                // A run that failed on a full disk did not fail: its output could not be kept.
                RunOutcome::Failed(_) if crate::sys::disk::low_on_space(&dir) => Err(StoreError::Io {
                    path: dir.clone(),
                    source: std::io::Error::from_raw_os_error(libc::ENOSPC),
                }),
                _ => self.store.record(&hash, &outcome),
            };
            if let Err(e) = stored {
                // Free what the attempt left (it is re-run on resume) so that the joblog and
                // results.csv can still be written.
                let _ = self.store.clean_run_dir(&hash);
                let record = AttemptRecord {
                    hash: hash.clone(),
                    start,
                    runtime_s: t.elapsed().as_secs_f64(),
                    status: "store-error",
                    class: None,
                };
                // Best effort: the store is failing.
                let _ = self.log(record, false);
                self.send(Event::Finished { hash: hash.clone(), outcome: RunOutcome::Cancelled, ran: true });
                return Err(e);
            }
            let (status, class) = match &outcome {
                RunOutcome::Done(_) => ("done", None),
                RunOutcome::Failed(f) => ("failed", Some(f.class)),
                RunOutcome::Cancelled => ("cancelled", None),
            };
            let retrying = class.is_some_and(FailureClass::is_transient)
                && attempt < self.opts.retries
                && !self.cancel.is_cancelled();
            let record = AttemptRecord {
                hash: hash.clone(),
                start,
                runtime_s: t.elapsed().as_secs_f64(),
                status,
                class: class.map(FailureClass::as_str),
            };
            self.log(record, retrying)?;
            if !retrying {
                break outcome;
            }
            attempt += 1;
        };
        Ok(Some((outcome, true)))
    }
}
