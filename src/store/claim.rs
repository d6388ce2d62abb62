//! Claims of runs: who is running a point now, as an `O_EXCL` file under the directory lock;
//! leases and their heartbeat across hosts; the state of a run as read from its directory.

use std::fs::{self, OpenOptions};
use std::io::Write;
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, SystemTime};

use serde::{Deserialize, Serialize};

use super::joblog::JOBLOG;
use super::{io, DirLock, Store, StoreError, LOCK};
use crate::outcome::{RunFailure, RunResult, RESULT_FORMAT, VX_LAYERS};
use crate::scenes::Layout;
use crate::sys::host::{process_start_ticks, unix_now};

impl Store {
    /// Renew this store's claims every lease/4 until the returned guard is dropped, so that
    /// other hosts see them live. Renewal is a rewrite of the claim under the directory lock,
    /// and only of a claim that is still ours.
    pub fn heartbeat(&self) -> Heartbeat {
        let (stop, stopped) = std::sync::mpsc::channel::<()>();
        let every = self.lease() / 4;
        let held = Arc::clone(&self.held);
        let lock = self.dir.join(".lock");
        let session = self.me.session.clone();
        let thread = std::thread::spawn(move || {
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) = stopped.recv_timeout(every) {
                let paths = held.lock().unwrap().clone();
                for path in paths {
                    // A failed renewal is retried at the next beat; the lease covers a few.
                    let _ = renew(&lock, &path, &session);
                }
            }
        });
        Heartbeat { stop: Some(stop), thread: Some(thread) }
    }

    /// The state of the run `hash`, read without taking its claim.
    pub fn state(&self, hash: &str) -> RunState {
        let dir = self.run_dir(hash);
        if let Some(s) = finished_state(&dir, self.layout()) {
            return s;
        }
        if let Some(c) = read_claim(&dir.join("claim")) {
            if self.owner_alive(&c) {
                return RunState::Running(c);
            }
            return RunState::Interrupted(c);
        }
        if dir.exists() {
            RunState::Incomplete
        } else {
            RunState::Pending
        }
    }

    /// Whether the run `hash` has finished: its result or failure, if any.
    pub fn finished(&self, hash: &str) -> Option<RunState> {
        finished_state(&self.run_dir(hash), self.layout())
    }

    /// When the run's outcome (`result.json` or `failure.json`) was written, if it has one.
    pub fn outcome_time(&self, hash: &str) -> Option<SystemTime> {
        let dir = self.run_dir(hash);
        ["result.json", "failure.json"]
            .iter()
            .find_map(|f| fs::metadata(dir.join(f)).and_then(|m| m.modified()).ok())
    }

    /// Modification time of the run's `failure.json`, if it has one.
    pub fn failure_time(&self, hash: &str) -> Option<SystemTime> {
        fs::metadata(self.run_dir(hash).join("failure.json")).and_then(|m| m.modified()).ok()
    }

    /// Claim the run `hash`: create `runs/<hash>/claim` exclusively, taking over a claim whose
    /// owner is gone.
    pub fn claim(&self, hash: &str) -> Result<ClaimAttempt, StoreError> {
        let dir = self.run_dir(hash);
        super::check_run_dir(&dir, hash)?;
        fs::create_dir_all(&dir).map_err(io(&dir))?;
        // A link put there between the check and now: refused all the same.
        super::check_run_dir(&dir, hash)?;
        let path = dir.join("claim");
        let _lock = DirLock::take(&self.dir.join(LOCK))?;
        let mut stale = None;
        for _ in 0..2 {
            match OpenOptions::new().write(true).create_new(true).mode(0o644).open(&path) {
                Ok(mut f) => {
                    let mut me = self.me.clone();
                    me.claimed_at = unix_now();
                    me.renewed_at = Some(me.claimed_at);
                    let text = serde_json::to_string(&me).expect("claim serialises");
                    f.write_all(text.as_bytes()).map_err(io(&path))?;
                    self.held.lock().unwrap().push(path.clone());
                    return Ok(ClaimAttempt::Claimed(Claim { path, session: me.session }, stale));
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    // Written under the lock, so an unreadable claim means its writer died.
                    match read_claim(&path) {
                        Some(c) if self.owner_alive(&c) => return Ok(ClaimAttempt::Busy(c)),
                        old => {
                            fs::remove_file(&path).map_err(io(&path))?;
                            stale = old;
                        }
                    }
                }
                Err(e) => return Err(io(&path)(e)),
            }
        }
        unreachable!("a removed claim can be created again under the lock")
    }

    /// Give a claim back. Only removes the file if it is still ours.
    pub fn release(&self, claim: Claim) -> Result<(), StoreError> {
        self.held.lock().unwrap().retain(|p| *p != claim.path);
        // Under the lock, so that a renewal in flight cannot write the claim back.
        let _lock = DirLock::take(&self.dir.join(".lock"))?;
        if read_claim(&claim.path).is_some_and(|c| c.session == claim.session) {
            fs::remove_file(&claim.path).map_err(io(&claim.path))?;
        }
        Ok(())
    }

    /// Whether the process named by a claim is still running it.
    pub(super) fn owner_alive(&self, c: &ClaimInfo) -> bool {
        if c.host != self.host {
            // Cannot look at another host's processes: its claim stands while its lease does.
            return lease_alive(c, unix_now());
        }
        if c.session == self.me.session {
            return true;
        }
        process_start_ticks(c.pid) == Some(c.start_ticks)
    }
}

/// Who holds a claim: `runs/<hash>/claim`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ClaimInfo {
    pub host: String,
    pub pid: u32,
    /// Start time of `pid` in clock ticks since boot (`/proc/<pid>/stat` field 22), which tells
    /// a live owner from a new process that reused its pid.
    pub start_ticks: u64,
    /// Distinguishes two stores in one process (tests) and two sessions of one pid.
    pub session: String,
    /// Unix time of the claim, seconds.
    pub claimed_at: f64,
    /// How long the claim stands without renewal, seconds (absent in claims written before
    /// leases existed: those stand, as they did).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lease_s: Option<f64>,
    /// Unix time of the last renewal, seconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub renewed_at: Option<f64>,
}

/// Default lease of a claim: long against a busy NFS server's delays and clock skew, short
/// against a run (minutes to hours) whose node was lost.
pub const DEFAULT_LEASE: Duration = Duration::from_secs(120);

/// The lease of the claims of every store this process opens from now on (`sweep work
/// --lease`), milliseconds.
pub(super) static LEASE_MS: std::sync::atomic::AtomicU64 =
    std::sync::atomic::AtomicU64::new(DEFAULT_LEASE.as_millis() as u64);

/// Set the lease of the claims of stores opened from now on.
pub fn set_default_lease(lease: Duration) {
    LEASE_MS.store(lease.as_millis() as u64, std::sync::atomic::Ordering::SeqCst);
}

/// What the run dir of one hash holds.
#[derive(Debug, Clone, PartialEq)]
pub enum RunState {
    Done(Box<RunResult>),
    Failed(Box<RunFailure>),
    /// Claimed by a live process.
    Running(ClaimInfo),
    /// Claimed by a process that is gone (killed): an attempt was cut off. Re-run it.
    Interrupted(ClaimInfo),
    /// `result.json` or `failure.json` is there but cannot be read (edited, damaged, an
    /// older format): the file and why. Re-run it, saying so.
    Damaged {
        file: PathBuf,
        reason: RunDamage,
    },
    /// A directory without a result, not claimed by a live process: re-run it.
    Incomplete,
    /// Never started.
    Pending,
}

/// Why a `result.json` or `failure.json` does not count: read after the file's name.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunDamage {
    /// Not readable as its type; `why` is the reader's or the parser's message.
    #[error("unreadable ({why})")]
    Unreadable { why: String },
    /// The result of another run directory: its hash (shortened) and this directory's name.
    #[error("holds the result of another run ({theirs}), not of {ours}")]
    OtherRun { theirs: String, ours: String },
    #[error(
        "format {format}: expected {RESULT_FORMAT} (written by another version of sweep, which this one cannot read)"
    )]
    Format { format: u32 },
    #[error(
        "steady = false: a done run is steady (an unsteady run is a failure); the file was edited or is damaged"
    )]
    Unsteady,
    /// `vx` or `vx_se` with another number of layers than [`VX_LAYERS`].
    #[error("{what}: {layers} layers, expected {VX_LAYERS}")]
    Layers { what: &'static str, layers: usize },
    /// A number no run can produce.
    #[error(transparent)]
    Implausible(#[from] crate::measure::plausible::Implausible),
    /// A swept parameter whose value is not the point's.
    #[error("its parameters are not this point's ({name} = {got}, expected {expected})")]
    OtherPoint { name: String, got: f64, expected: f64 },
    /// A fixed parameter whose value is not the sweep's.
    #[error("its fixed {name} = {got} is not the sweep's {sweep}")]
    OtherFixed { name: String, got: f64, sweep: f64 },
    #[error("it does not give the fixed {name} (the sweep's is {sweep})")]
    NoFixed { name: String, sweep: f64 },
}

/// The outcome of [`Store::claim`].
#[derive(Debug)]
pub enum ClaimAttempt {
    /// The claim is ours; the previous claim, if any, was stale and is returned.
    Claimed(Claim, Option<ClaimInfo>),
    /// A live process holds it.
    Busy(ClaimInfo),
}

/// A held claim; [`Store::release`] gives it back.
#[derive(Debug)]
pub struct Claim {
    path: PathBuf,
    session: String,
}

/// Done, failed, or damaged (a result file that is there but cannot be read, or one that
/// `layout`'s results would not count as, [`counts`]); `None` when the directory holds neither
/// file.
pub(super) fn finished_state(dir: &Path, layout: &dyn Layout) -> Option<RunState> {
    fn read<T: serde::de::DeserializeOwned>(path: &Path) -> Option<Result<T, RunDamage>> {
        let unreadable = |why: String| RunDamage::Unreadable { why };
        match crate::sys::read::read_capped(path, super::OUTCOME_CAP) {
            Ok(bytes) => Some(serde_json::from_slice(&bytes).map_err(|e| unreadable(e.to_string()))),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => Some(Err(unreadable(e.to_string()))),
        }
    }
    let mut damaged = None;
    let result = dir.join("result.json");
    // A result counts only if it is this directory's run and every number in it is possible.
    let own = |r: &RunResult| -> Result<(), RunDamage> {
        let name = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if r.hash != name {
            return Err(RunDamage::OtherRun { theirs: super::short(&r.hash).to_string(), ours: name });
        }
        counts(layout, r)
    };
    match read::<RunResult>(&result).map(|r| r.and_then(|r| own(&r).map(|()| r))) {
        Some(Ok(r)) => return Some(RunState::Done(Box::new(r))),
        Some(Err(reason)) => damaged = Some(RunState::Damaged { file: result, reason }),
        None => {}
    }
    let failure = dir.join("failure.json");
    let failure_format = |f: RunFailure| match f.format {
        RESULT_FORMAT => Ok(f),
        format => Err(RunDamage::Format { format }),
    };
    match read::<RunFailure>(&failure).map(|f| f.and_then(failure_format)) {
        Some(Ok(f)) => return Some(RunState::Failed(Box::new(f))),
        Some(Err(reason)) => damaged = damaged.or(Some(RunState::Damaged { file: failure, reason })),
        None => {}
    }
    damaged
}

/// Whether a result of `layout` counts as done when it is read back, whoever wrote it (its
/// directory and point aside): [`well_formed`], and every number in it possible
/// ([`Layout::check_result`]).
pub fn counts(layout: &dyn Layout, r: &RunResult) -> Result<(), RunDamage> {
    well_formed(r)?;
    Ok(layout.check_result(r)?)
}

/// What the types of a `result.json` cannot say: it is of this version's format, a done run is
/// steady (an unsteady one is a failure), and it has one v_x per layer.
fn well_formed(r: &RunResult) -> Result<(), RunDamage> {
    if r.format != RESULT_FORMAT {
        return Err(RunDamage::Format { format: r.format });
    }
    if !r.steady {
        return Err(RunDamage::Unsteady);
    }
    for (what, n) in [("vx", r.vx.len()), ("vx_se", r.vx_se.len())] {
        // vx_se is absent from results of the gated layouts.
        if n != VX_LAYERS && !(what == "vx_se" && n == 0) {
            return Err(RunDamage::Layers { what, layers: n });
        }
    }
    Ok(())
}

/// The first entry of `dir` that a sweep does not write (a user's file), if any: a directory
/// holding only these is one whose creation was cut off before `manifest.json`.
pub fn foreign_entry(dir: &Path) -> Option<String> {
    let entries = fs::read_dir(dir).ok()?;
    entries.flatten().map(|e| e.file_name().to_string_lossy().into_owned()).find(|n| {
        !matches!(n.as_str(), LOCK | JOBLOG | "runs" | "sweep.toml" | "results.csv")
            && crate::sys::atomic::temporary_owner(n).is_none()
    })
}

pub(super) fn read_claim(path: &Path) -> Option<ClaimInfo> {
    serde_json::from_slice(&crate::sys::read::read_capped(path, super::CLAIM_CAP).ok()?).ok()
}

/// Whether a claim's lease still runs at `now` (Unix seconds). A claim without a lease (written
/// before leases) always stands.
pub fn lease_alive(c: &ClaimInfo, now: f64) -> bool {
    match (c.lease_s, c.renewed_at) {
        (Some(lease), Some(renewed)) => now - renewed <= lease,
        _ => true,
    }
}

/// Renew the claim at `path` if `session` still holds it.
fn renew(lock: &Path, path: &Path, session: &str) -> Result<(), StoreError> {
    let _lock = DirLock::take(lock)?;
    let Some(mut c) = read_claim(path) else { return Ok(()) };
    if c.session != session {
        return Ok(());
    }
    c.renewed_at = Some(unix_now());
    crate::sys::atomic::write(path, serde_json::to_string(&c).expect("claim serialises").as_bytes())
        .map_err(io(path))
}

/// The running heartbeat of a [`Store`]; stops when dropped.
#[derive(Debug)]
pub struct Heartbeat {
    stop: Option<std::sync::mpsc::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Drop for Heartbeat {
    fn drop(&mut self) {
        drop(self.stop.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
