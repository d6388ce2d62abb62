//! A deterministic stand-in for LIGGGHTS, for scheduler, retry, claim and resume tests.
//!
//! A job is a point; its "run" is a real child process (`sleep`) under [`crate::sys::process::run`],
//! so timeouts, cancellation and process groups are exercised for real. Its MFR is a made-up
//! function of the parameters ([`fake_mfr`]).
//!
//! Built for this crate's tests and, with the `test-support` feature, for its integration
//! tests and benchmarks; not part of the library otherwise.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Duration;

use sha2::{Digest, Sha256};

use crate::outcome::{FailureClass, RunFailure, RunOutcome, RunResult, RESULT_FORMAT, VX_LAYERS};
use crate::run::pool::Executor;
use crate::sys::atomic::write_json;
use crate::sys::process::{self, CancelToken, ProcessOutcome};

/// What the fake does with one attempt.
#[derive(Debug, Clone, PartialEq)]
pub enum Behaviour {
    /// Sleep this long, then succeed.
    Succeed(Duration),
    /// Sleep this long, then fail with this class.
    Fail(Duration, FailureClass),
    /// Sleep far past any timeout.
    Hang,
}

/// A fake point: its swept values and hash.
#[derive(Debug, Clone)]
pub struct FakeJob {
    pub values: Vec<f64>,
    pub hash: String,
}

type Behaviours = dyn Fn(&[f64], usize) -> Behaviour + Send + Sync;
type Closed = dyn Fn(&[f64]) -> bool + Send + Sync;
type Mfr = dyn Fn(&[f64]) -> f64 + Send + Sync;

pub struct FakeExecutor {
    /// Behaviour of attempt `n` (0-based) of the point with these values.
    plan: Box<Behaviours>,
    /// Which points the fake's screen closes (none by default).
    closed: Box<Closed>,
    /// The MFR of a point ([`fake_mfr`] by default).
    mfr: Box<Mfr>,
    pub timeout: Duration,
    /// Stands for the template/engine identity.
    pub identity: String,
    /// Bytes of "log" each attempt writes in its run dir before its result (as LIGGGHTS
    /// writes logs and dumps), to fill a small file system.
    pub output_bytes: usize,
    attempts: Mutex<HashMap<String, usize>>,
    running: Mutex<HashMap<String, usize>>,
    now: AtomicUsize,
    /// Most jobs seen running at once.
    pub peak: AtomicUsize,
    /// Set when one hash ran twice at the same moment.
    pub overlap: AtomicUsize,
}

/// The fake's MFR: a smooth function of the swept values, in [0.05, 0.65].
pub fn fake_mfr(values: &[f64]) -> f64 {
    let s: f64 = values.iter().enumerate().map(|(i, v)| (i + 1) as f64 * v).sum();
    // Within [0.05, 0.65]: a possible MFR (below the densest packing), never zero.
    0.35 + 0.3 * s.sin()
}

impl FakeExecutor {
    pub fn new(plan: impl Fn(&[f64], usize) -> Behaviour + Send + Sync + 'static) -> Self {
        FakeExecutor {
            plan: Box::new(plan),
            closed: Box::new(|_| false),
            mfr: Box::new(fake_mfr),
            timeout: Duration::from_secs(30),
            identity: "fake-1".into(),
            output_bytes: 0,
            attempts: Mutex::default(),
            running: Mutex::default(),
            now: AtomicUsize::new(0),
            peak: AtomicUsize::new(0),
            overlap: AtomicUsize::new(0),
        }
    }

    /// Close the points (swept values) for which `closed` holds, as a screen would.
    pub fn with_closed(mut self, closed: impl Fn(&[f64]) -> bool + Send + Sync + 'static) -> Self {
        self.closed = Box::new(closed);
        self
    }

    /// Give the points this MFR instead of [`fake_mfr`].
    pub fn with_mfr(mut self, mfr: impl Fn(&[f64]) -> f64 + Send + Sync + 'static) -> Self {
        self.mfr = Box::new(mfr);
        self
    }

    /// Attempts made so far, by hash.
    pub fn attempts(&self) -> HashMap<String, usize> {
        self.attempts.lock().unwrap().clone()
    }
}

impl Executor for FakeExecutor {
    type Job = FakeJob;

    fn identity(&self) -> serde_json::Value {
        serde_json::json!({ "engine": self.identity })
    }

    fn prepare_seeded(&self, swept: &[f64], seed: Option<u64>) -> crate::Result<FakeJob> {
        let mut h = Sha256::new();
        h.update(self.identity.as_bytes());
        for v in swept {
            h.update(v.to_bits().to_le_bytes());
        }
        if let Some(seed) = seed {
            h.update(format!("seed {seed}"));
        }
        let hash = h.finalize().iter().map(|b| format!("{b:02x}")).collect();
        Ok(FakeJob { values: swept.to_vec(), hash })
    }

    fn hash<'a>(&self, job: &'a FakeJob) -> &'a str {
        &job.hash
    }

    fn closed(&self, job: &FakeJob) -> bool {
        (self.closed)(&job.values)
    }

    fn execute(&self, job: &FakeJob, run_dir: &Path, cancel: &CancelToken) -> RunOutcome {
        let n = {
            let mut a = self.attempts.lock().unwrap();
            let e = a.entry(job.hash.clone()).or_insert(0);
            *e += 1;
            *e - 1
        };
        {
            let mut r = self.running.lock().unwrap();
            let e = r.entry(job.hash.clone()).or_insert(0);
            *e += 1;
            if *e > 1 {
                self.overlap.fetch_add(1, Ordering::SeqCst);
            }
        }
        let now = self.now.fetch_add(1, Ordering::SeqCst) + 1;
        self.peak.fetch_max(now, Ordering::SeqCst);
        let behaviour = (self.plan)(&job.values, n);
        let sleep = match &behaviour {
            Behaviour::Succeed(d) | Behaviour::Fail(d, _) => *d,
            Behaviour::Hang => Duration::from_secs(3600),
        };
        let mut cmd = Command::new("sleep");
        cmd.arg(format!("{}", sleep.as_secs_f64()));
        let (p, took) = process::run(cmd, self.timeout, cancel);
        if self.output_bytes > 0 {
            // Like LIGGGHTS, the fake does not check that its log was written.
            let _ = std::fs::write(run_dir.join("log.fake"), vec![b'x'; self.output_bytes]);
        }
        self.now.fetch_sub(1, Ordering::SeqCst);
        *self.running.lock().unwrap().get_mut(&job.hash).unwrap() -= 1;
        let fail = |class, reason: String| {
            let f = RunFailure {
                format: RESULT_FORMAT,
                hash: job.hash.clone(),
                class,
                reason,
                log_tail: String::new(),
                wall_time: took.as_secs_f64(),
                measured: None,
            };
            // As the real executor: a failed write is found and reported by the pool.
            let _ = write_json(&run_dir.join("failure.json"), &f);
            RunOutcome::Failed(f)
        };
        match (p, behaviour) {
            (ProcessOutcome::Cancelled, _) => RunOutcome::Cancelled,
            (ProcessOutcome::TimedOut, _) => {
                fail(FailureClass::TimedOut, format!("ran past its timeout of {:?}", self.timeout))
            }
            (ProcessOutcome::Exited(0), Behaviour::Fail(_, class)) => {
                fail(class, format!("fake {} failure", class.as_str()))
            }
            (ProcessOutcome::Exited(0), _) => {
                let names = ["a", "b", "c", "d", "e", "f"];
                let r = RunResult {
                    hash: job.hash.clone(),
                    parameters: job
                        .values
                        .iter()
                        .zip(names)
                        .map(|(v, n)| (n.to_string(), *v))
                        .collect::<BTreeMap<_, _>>(),
                    answer: crate::outcome::PointAnswer::mfr((self.mfr)(&job.values)),
                    mfr_flux: (self.mfr)(&job.values),
                    vx: vec![Some(0.5); VX_LAYERS],
                    particles: 1,
                    steps: 1,
                    wall_time: took.as_secs_f64(),
                    engine_version: "fake".into(),
                    ..RunResult::default()
                };
                let _ = write_json(&run_dir.join("result.json"), &r);
                RunOutcome::Done(r)
            }
            (other, _) => fail(FailureClass::Signalled, format!("sleep ended {other:?}")),
        }
    }
}
