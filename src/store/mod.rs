//! The sweep directory (DESIGN §4): manifest, content-addressed run dirs, claims, joblog and
//! results.csv.
//!
//! ```text
//! DIR/sweep.toml        the sweep file as resolved
//! DIR/manifest.json     design, points (index → values → hash), identity, tool version
//! DIR/runs/<hash>/      one per distinct deck; result.json or failure.json when finished
//! DIR/runs/<hash>/claim who is running it now: host, pid, process start time, session
//! DIR/joblog.tsv        one line per attempt, appended
//! DIR/results.csv       one row per design point, rewritten atomically
//! ```
//!
//! A run is done when its `result.json` exists (written by rename, so whole or absent) and failed
//! when its `failure.json` does; a directory holding neither is incomplete, whatever logs it
//! holds. Claims are created with `O_EXCL` under a short `flock` of `DIR/.lock`, so two
//! processes never hold the same claim; a claim whose owner is gone (same host, and no live
//! process with that pid *and* that start time) is taken over, and until then marks the run
//! as interrupted. The manifest is created (or extended) and each joblog line numbered under
//! the same lock, so two processes started at once on a new directory share it, and `seq` is
//! unique. `manifest.json` is validated when read. A write error (a full disk) is a
//! [`StoreError`] naming the device and the file; temporaries of writes cut off are removed by
//! [`Store::remove_stale_temporaries`].
//!
//! Across hosts (a cluster on a shared file system) processes cannot be seen, so a claim is a
//! lease: its holder renews `renewed_at` every [`Store::lease`]/4 while it lives
//! ([`Store::heartbeat`]), and a claim of another host not renewed for its `lease_s` is taken
//! over. The hosts' clocks must agree to well within the lease (NTP does).
//!
//! Not responsible for deciding what to run (the driver, [`crate::run`]) or running it
//! ([`crate::run::pool`]).

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::os::unix::fs::OpenOptionsExt;
use std::os::unix::io::AsRawFd;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

mod belongs;
pub mod holders;
pub mod retry;

use crate::outcome::{RunFailure, RunResult, VX_LAYERS};

/// Version of `manifest.json`.
pub const MANIFEST_FORMAT: u32 = 1;
/// The lock file of a sweep directory: claims, joblog lines and the manifest are written under
/// its `flock`.
const LOCK: &str = ".lock";
/// The joblog's file name.
const JOBLOG: &str = "joblog.tsv";
/// Header of `joblog.tsv` (GNU parallel's `--joblog`, plus the run hash and the failure class).
pub const JOBLOG_HEADER: &str = "seq\thost\tpid\tstart\truntime_s\tstatus\tclass\thash";

#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("{}", describe_io(path, source))]
    Io { path: PathBuf, source: std::io::Error },
    /// The directory is not a sweep directory this version can read.
    #[error("{}: {reason}", path.display())]
    NotASweep { path: PathBuf, reason: String },
}

impl From<StoreError> for crate::Error {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::Io { .. } => crate::Error::Internal(e.to_string()),
            StoreError::NotASweep { .. } => crate::Error::Input(e.to_string()),
        }
    }
}

impl StoreError {
    /// Whether the file system is full (or the quota spent): free space, then resume.
    pub fn is_no_space(&self) -> bool {
        matches!(self, StoreError::Io { source, .. } if is_no_space(source))
    }
}

/// Free space under which a failed run is taken for one that ran out of disk: LIGGGHTS does
/// not check its writes, so a full disk shows up as a cut-off dump or log, not as an error.
pub const LOW_SPACE: u64 = 64 * 1024;

/// Whether the file system holding `path` has less than [`LOW_SPACE`] left for us (counting
/// the blocks reserved for root when we are root).
pub fn low_on_space(path: &Path) -> bool {
    use std::os::unix::ffi::OsStrExt;
    let Ok(c) = std::ffi::CString::new(path.as_os_str().as_bytes()) else { return false };
    // SAFETY: statvfs(3) fills the struct we pass for a NUL-terminated path.
    let mut st: libc::statvfs = unsafe { std::mem::zeroed() };
    if unsafe { libc::statvfs(c.as_ptr(), &mut st) } != 0 {
        return false;
    }
    // SAFETY: geteuid cannot fail.
    let blocks = if unsafe { libc::geteuid() } == 0 { st.f_bfree } else { st.f_bavail };
    (blocks as u64).saturating_mul(st.f_frsize as u64) < LOW_SPACE
}

/// `ENOSPC` or `EDQUOT`.
pub fn is_no_space(e: &std::io::Error) -> bool {
    matches!(e.raw_os_error(), Some(libc::ENOSPC) | Some(libc::EDQUOT))
}

/// "no space left on /dev/sdb1 (/scratch) while writing PATH" for a full file system, else
/// "PATH: the OS error".
pub fn describe_io(path: &Path, e: &std::io::Error) -> String {
    let what = match e.raw_os_error() {
        Some(libc::ENOSPC) => "no space left",
        Some(libc::EDQUOT) => "disk quota exceeded",
        _ => return format!("{}: {e}", path.display()),
    };
    let on = match mount_of(path) {
        Some((source, mount)) => format!("{source} ({})", mount.display()),
        None => "the device".into(),
    };
    format!("{what} on {on} while writing {}", path.display())
}

/// The file system holding `path`: its source (device) and mount point, from
/// `/proc/self/mountinfo` (the longest mount point that contains the path).
fn mount_of(path: &Path) -> Option<(String, PathBuf)> {
    let abs = path.ancestors().find_map(|p| fs::canonicalize(p).ok())?;
    let info = fs::read_to_string("/proc/self/mountinfo").ok()?;
    // "36 35 98:0 /mnt1 /mnt/parent rw,noatime master:1 - ext3 /dev/root rw,errors=continue"
    let unescape = |s: &str| s.replace("\\040", " ").replace("\\011", "\t").replace("\\134", "\\");
    info.lines()
        .filter_map(|l| {
            let (left, right) = l.split_once(" - ")?;
            let mount = PathBuf::from(unescape(left.split(' ').nth(4)?));
            let source = unescape(right.split(' ').nth(1)?);
            abs.starts_with(&mount).then_some((source, mount))
        })
        .max_by_key(|(_, m)| m.components().count())
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> StoreError + '_ {
    move |source| StoreError::Io { path: path.to_path_buf(), source }
}

/// How the points were chosen; enough to extend the design later.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum DesignRecord {
    Lattice { levels: Vec<usize> },
    Lds { step: usize, max: usize, scrambling: crate::sweep::Scrambling, seed: u64 },
}

/// One nested space: a lattice level or an LDS prefix.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SpaceRecord {
    /// `"lattice 5"`, `"lds 400"`.
    pub label: String,
    /// Indices into [`Manifest::points`].
    pub points: Vec<usize>,
}

/// One distinct design point.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct PointRecord {
    pub index: usize,
    /// Swept parameter values in file order, in the sweep file's units.
    pub values: Vec<f64>,
    pub hash: String,
    /// Nothing can pass under the blade here ([`crate::run::screen`]): skipped as MFR = 0 once the
    /// screen is verified. Absent (false) in manifests written before the screen.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub closed: bool,
}

/// `manifest.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    pub format: u32,
    /// `demsweep <version>` that wrote it.
    pub tool: String,
    pub name: String,
    /// Swept parameter names: the columns of [`PointRecord::values`].
    pub parameters: Vec<String>,
    pub design: DesignRecord,
    pub spaces: Vec<SpaceRecord>,
    pub points: Vec<PointRecord>,
    /// Template, mesh generator and engine identity; a resume refuses when it changed.
    pub identity: serde_json::Value,
}

impl Manifest {
    /// Check what the types cannot: every index in range, one hash per point, as many values
    /// as parameters. The error names the field.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.points.len();
        if self.parameters.is_empty() {
            return Err("parameters: expected at least one swept parameter".into());
        }
        let mut hashes: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
        for (i, p) in self.points.iter().enumerate() {
            if p.index != i {
                return Err(format!("points[{i}].index = {}: expected {i}", p.index));
            }
            if p.values.len() != self.parameters.len() {
                return Err(format!(
                    "points[{i}].values: {} values for {} parameters",
                    p.values.len(),
                    self.parameters.len()
                ));
            }
            // The hash names a directory under runs/: 64 hex digits, nothing else.
            if p.hash.len() != 64 || !p.hash.bytes().all(|b| b.is_ascii_hexdigit()) {
                return Err(format!("points[{i}].hash = {:?}: expected 64 hex digits", p.hash));
            }
            if let Some(j) = hashes.insert(&p.hash, i) {
                return Err(format!("points[{i}].hash: the same as points[{j}].hash"));
            }
        }
        if self.spaces.is_empty() {
            return Err("spaces: expected at least one space".into());
        }
        for (k, s) in self.spaces.iter().enumerate() {
            if s.points.is_empty() {
                return Err(format!("spaces[{k}].points: empty"));
            }
            if let Some((j, &v)) = s.points.iter().enumerate().find(|(_, &v)| v >= n) {
                return Err(format!("spaces[{k}].points[{j}] = {v}: no such point (the manifest has {n})"));
            }
        }
        match &self.design {
            DesignRecord::Lds { step, max, .. } if *step == 0 || max < step => {
                Err(format!("design: lds step {step}, max {max}: expected 1 ≤ step ≤ max"))
            }
            DesignRecord::Lattice { levels } if levels.iter().any(|&l| l < 2) => {
                Err(format!("design: lattice levels {levels:?}: expected each at least 2"))
            }
            _ => Ok(()),
        }
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
static LEASE_MS: std::sync::atomic::AtomicU64 =
    std::sync::atomic::AtomicU64::new(DEFAULT_LEASE.as_millis() as u64);
/// The host name this process's claims give instead of the machine's (`sweep work --host`).
static HOST_OVERRIDE: std::sync::OnceLock<String> = std::sync::OnceLock::new();

/// Set the lease of the claims of stores opened from now on.
pub fn set_default_lease(lease: Duration) {
    LEASE_MS.store(lease.as_millis() as u64, std::sync::atomic::Ordering::SeqCst);
}

/// Name claims of stores opened from now on after `host` (nodes that share a name; tests that
/// play two hosts on one machine). Only the first call counts.
pub fn set_host_name(host: &str) {
    let _ = HOST_OVERRIDE.set(host.to_string());
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
        reason: String,
    },
    /// A directory without a result, not claimed by a live process: re-run it.
    Incomplete,
    /// Never started.
    Pending,
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

/// An open sweep directory.
#[derive(Debug)]
pub struct Store {
    dir: PathBuf,
    host: String,
    me: ClaimInfo,
    /// Claim files held now, renewed by the heartbeat.
    held: Arc<Mutex<Vec<PathBuf>>>,
}

impl Store {
    /// Open `dir` (which must exist) for running: this process's identity is fixed here.
    pub fn open(dir: &Path) -> Store {
        let pid = std::process::id();
        let host = HOST_OVERRIDE.get().cloned().unwrap_or_else(hostname);
        static SESSIONS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = SESSIONS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        let now = unix_now();
        Store {
            dir: dir.to_path_buf(),
            host: host.clone(),
            me: ClaimInfo {
                host,
                pid,
                start_ticks: process_start_ticks(pid).unwrap_or(0),
                session: format!("{pid}-{n}-{}", (now * 1e6) as u64),
                claimed_at: now,
                lease_s: Some(LEASE_MS.load(std::sync::atomic::Ordering::SeqCst) as f64 / 1e3),
                renewed_at: None,
            },
            held: Arc::default(),
        }
    }

    /// Claims of this store last `lease` without renewal (default [`DEFAULT_LEASE`]).
    pub fn with_lease(mut self, lease: Duration) -> Store {
        self.me.lease_s = Some(lease.as_secs_f64());
        self
    }

    /// Claims of this store name `host` instead of this machine's name: for nodes that share a
    /// name, and for tests that play two hosts on one machine.
    pub fn with_host(mut self, host: &str) -> Store {
        self.host = host.to_string();
        self.me.host = host.to_string();
        self
    }

    /// The lease of this store's claims.
    pub fn lease(&self) -> Duration {
        Duration::from_secs_f64(self.me.lease_s.unwrap_or(DEFAULT_LEASE.as_secs_f64()))
    }

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

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    pub fn manifest_path(dir: &Path) -> PathBuf {
        dir.join("manifest.json")
    }

    pub fn run_dir(&self, hash: &str) -> PathBuf {
        self.dir.join("runs").join(hash)
    }

    /// Write `sweep.toml` and `manifest.json` (atomically each) and create `runs/` and the joblog.
    pub fn write_manifest(&self, sweep_toml: &str, manifest: &Manifest) -> Result<(), StoreError> {
        self.write_manifest_checked(sweep_toml, manifest, |_| Ok(()))
    }

    /// [`Store::write_manifest`], creating the directory if needed, under the directory's lock,
    /// after `check` has accepted the manifest already there (`None` for a new directory).
    ///
    /// `manifest.json` is written last: a directory without it holds at most `runs/`, the
    /// joblog and `sweep.toml` of a creation that was killed, which the next creation redoes.
    pub fn write_manifest_checked<E: From<StoreError>>(
        &self,
        sweep_toml: &str,
        manifest: &Manifest,
        check: impl FnOnce(Option<(Manifest, String)>) -> Result<(), E>,
    ) -> Result<(), E> {
        fs::create_dir_all(&self.dir).map_err(io(&self.dir))?;
        let _lock = DirLock::take(&self.dir.join(LOCK))?;
        let path = Self::manifest_path(&self.dir);
        let old = if path.exists() { Some(Self::read_manifest(&self.dir)?) } else { None };
        check(old)?;
        let runs = self.dir.join("runs");
        fs::create_dir_all(&runs).map_err(io(&runs))?;
        self.joblog_header()?;
        let toml_path = self.dir.join("sweep.toml");
        write_atomic(&toml_path, sweep_toml.as_bytes())?;
        crate::outcome::write_json_atomic(&path, manifest).map_err(io(&path))?;
        Ok(())
    }

    /// Read `manifest.json` and `sweep.toml` of `dir`.
    pub fn read_manifest(dir: &Path) -> Result<(Manifest, String), StoreError> {
        let path = Self::manifest_path(dir);
        let text = fs::read_to_string(&path).map_err(|e| StoreError::NotASweep {
            path: dir.to_path_buf(),
            reason: format!(
                "not a sweep directory (cannot read manifest.json: {})",
                match e.kind() {
                    std::io::ErrorKind::NotFound => "no such file".to_string(),
                    _ => e.to_string(),
                }
            ),
        })?;
        let not_a_sweep = |reason: String| StoreError::NotASweep { path: path.clone(), reason };
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| not_a_sweep(format!("truncated or not JSON ({e}); the manifest is damaged")))?;
        let format = value.get("format").and_then(|f| f.as_u64());
        if format != Some(MANIFEST_FORMAT as u64) {
            return Err(not_a_sweep(format!(
                "manifest format {}: expected {MANIFEST_FORMAT}",
                format.map_or("missing".into(), |f| f.to_string())
            )));
        }
        let manifest: Manifest =
            serde_json::from_str(&text).map_err(|e| not_a_sweep(format!("unreadable manifest: {e}")))?;
        manifest
            .validate()
            .map_err(|e| not_a_sweep(format!("{e}; the manifest was edited or is damaged")))?;
        let toml_path = dir.join("sweep.toml");
        let sweep = fs::read_to_string(&toml_path).map_err(|e| StoreError::NotASweep {
            path: toml_path.clone(),
            reason: format!("cannot read the resolved sweep file: {e}"),
        })?;
        Ok((manifest, sweep))
    }

    /// The state of the run `hash`, read without taking its claim.
    pub fn state(&self, hash: &str) -> RunState {
        let dir = self.run_dir(hash);
        if let Some(s) = finished_state(&dir) {
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
        finished_state(&self.run_dir(hash))
    }

    /// Modification time of the run's `failure.json`, if it has one.
    pub fn failure_time(&self, hash: &str) -> Option<SystemTime> {
        fs::metadata(self.run_dir(hash).join("failure.json")).and_then(|m| m.modified()).ok()
    }

    /// Claim the run `hash`: create `runs/<hash>/claim` exclusively, taking over a claim whose
    /// owner is gone.
    pub fn claim(&self, hash: &str) -> Result<ClaimAttempt, StoreError> {
        let dir = self.run_dir(hash);
        fs::create_dir_all(&dir).map_err(io(&dir))?;
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

    /// Write the outcome of the run `hash` (`result.json` or `failure.json`) unless it is
    /// already there: the executor writes it, and this makes sure it landed.
    pub fn record(&self, hash: &str, outcome: &crate::outcome::RunOutcome) -> Result<(), StoreError> {
        use crate::outcome::RunOutcome;
        let dir = self.run_dir(hash);
        let (name, written) = match (outcome, finished_state(&dir)) {
            (RunOutcome::Done(r), Some(RunState::Done(d))) if *d == *r => return Ok(()),
            (RunOutcome::Failed(f), Some(RunState::Failed(d))) if *d == *f => return Ok(()),
            (RunOutcome::Done(r), _) => {
                ("result.json", crate::outcome::write_json_atomic(&dir.join("result.json"), r))
            }
            (RunOutcome::Failed(f), _) => {
                ("failure.json", crate::outcome::write_json_atomic(&dir.join("failure.json"), f))
            }
            (RunOutcome::Cancelled, _) => return Ok(()),
        };
        written.map_err(io(&dir.join(name)))
    }

    /// Empty the run dir of a held claim (a stale attempt's files), keeping the claim.
    pub fn clean_run_dir(&self, hash: &str) -> Result<(), StoreError> {
        let dir = self.run_dir(hash);
        for entry in fs::read_dir(&dir).map_err(io(&dir))? {
            let entry = entry.map_err(io(&dir))?;
            if entry.file_name() == "claim" {
                continue;
            }
            let p = entry.path();
            let r = if entry.file_type().map_err(io(&p))?.is_dir() {
                fs::remove_dir_all(&p)
            } else {
                fs::remove_file(&p)
            };
            r.map_err(io(&p))?;
        }
        Ok(())
    }

    /// Remove the temporary files of atomic writes whose writer is gone (killed mid-write, or
    /// a write that failed), in the directory and every run dir; returns how many.
    pub fn remove_stale_temporaries(&self) -> Result<usize, StoreError> {
        let mut removed = 0;
        let mut dirs = vec![self.dir.clone()];
        let runs = self.dir.join("runs");
        match fs::read_dir(&runs) {
            Ok(entries) => dirs.extend(entries.flatten().map(|e| e.path())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(io(&runs)(e)),
        }
        for dir in dirs {
            let Ok(entries) = fs::read_dir(&dir) else { continue };
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                let Some((host, pid)) = crate::sys::atomic::temporary_owner(&name) else {
                    continue;
                };
                // Another host's writer may be alive; a live pid here may be writing it now.
                if host.is_some_and(|h| h != crate::sys::atomic::temporary_host())
                    || process_start_ticks(pid).is_some()
                {
                    continue;
                }
                match fs::remove_file(e.path()) {
                    Ok(()) => removed += 1,
                    Err(err) if err.kind() == std::io::ErrorKind::NotFound => {}
                    Err(err) => return Err(io(&e.path())(err)),
                }
            }
        }
        Ok(removed)
    }

    /// Run `f` under the directory's lock (a consistent read-then-write of a shared file).
    pub fn locked<T>(&self, f: impl FnOnce() -> T) -> Result<T, StoreError> {
        let _lock = DirLock::take(&self.dir.join(".lock"))?;
        Ok(f())
    }

    /// Whether the process named by a claim is still running it.
    fn owner_alive(&self, c: &ClaimInfo) -> bool {
        if c.host != self.host {
            // Cannot look at another host's processes: its claim stands while its lease does.
            return lease_alive(c, unix_now());
        }
        if c.session == self.me.session {
            return true;
        }
        process_start_ticks(c.pid) == Some(c.start_ticks)
    }

    /// Create the joblog with its header if it is missing. Call under the lock, so that no
    /// process appends before the header.
    fn joblog_header(&self) -> Result<(), StoreError> {
        let path = self.dir.join(JOBLOG);
        let mut file = OpenOptions::new().create(true).append(true).open(&path).map_err(io(&path))?;
        if file.metadata().map_err(io(&path))?.len() == 0 {
            file.write_all(format!("{JOBLOG_HEADER}\n").as_bytes()).map_err(io(&path))?;
        }
        Ok(())
    }

    /// Open the joblog for appending attempts, creating it with its header if missing.
    pub fn joblog(&self) -> Result<Joblog, StoreError> {
        let lock = self.dir.join(LOCK);
        let _lock = DirLock::take(&lock)?;
        self.joblog_header()?;
        let path = self.dir.join(JOBLOG);
        let file = OpenOptions::new().read(true).append(true).open(&path).map_err(io(&path))?;
        Ok(Joblog { file, path, lock, host: self.host.clone() })
    }
}

fn is_header(line: &str) -> bool {
    line.starts_with("seq\t")
}

/// Done, failed, or damaged (a result file that is there but cannot be read); `None` when the
/// directory holds neither file.
fn finished_state(dir: &Path) -> Option<RunState> {
    fn read<T: serde::de::DeserializeOwned>(path: &Path) -> Option<Result<T, String>> {
        match fs::read(path) {
            Ok(bytes) => Some(serde_json::from_slice(&bytes).map_err(|e| format!("unreadable ({e})"))),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => Some(Err(format!("unreadable ({e})"))),
        }
    }
    let mut damaged = None;
    let result = dir.join("result.json");
    // A result counts only if it is this directory's run and every number in it is possible.
    let own = |r: &RunResult| -> Result<(), String> {
        let name = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if r.hash != name {
            return Err(format!("holds the result of another run ({}), not of {name}", short(&r.hash)));
        }
        crate::point::plausible::check_result(r)
    };
    match read::<RunResult>(&result).map(|r| r.and_then(|r| own(&r).map(|()| r))) {
        Some(Ok(r)) => return Some(RunState::Done(Box::new(r))),
        Some(Err(reason)) => damaged = Some(RunState::Damaged { file: result, reason }),
        None => {}
    }
    let failure = dir.join("failure.json");
    match read::<RunFailure>(&failure) {
        Some(Ok(f)) => return Some(RunState::Failed(Box::new(f))),
        Some(Err(reason)) => damaged = damaged.or(Some(RunState::Damaged { file: failure, reason })),
        None => {}
    }
    damaged
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

/// The first 12 characters of a hash, as status and warnings show it.
pub fn short(hash: &str) -> &str {
    &hash[..12.min(hash.len())]
}

fn read_claim(path: &Path) -> Option<ClaimInfo> {
    serde_json::from_str(&fs::read_to_string(path).ok()?).ok()
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
    write_atomic(path, serde_json::to_string(&c).expect("claim serialises").as_bytes())
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

/// `flock(2)` on a lock file, held while the guard lives. Released by the kernel if we die.
struct DirLock(File);

impl DirLock {
    fn take(path: &Path) -> Result<DirLock, StoreError> {
        let f = OpenOptions::new().create(true).truncate(false).write(true).open(path).map_err(io(path))?;
        // SAFETY: flock on a file descriptor we own.
        if unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX) } != 0 {
            return Err(io(path)(std::io::Error::last_os_error()));
        }
        Ok(DirLock(f))
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        // SAFETY: unlocking the descriptor we locked.
        unsafe { libc::flock(self.0.as_raw_fd(), libc::LOCK_UN) };
    }
}

/// One attempt, as a joblog line.
#[derive(Debug, Clone, PartialEq)]
pub struct AttemptRecord {
    pub hash: String,
    pub start: SystemTime,
    pub runtime_s: f64,
    /// `done`, `failed` or `cancelled`.
    pub status: &'static str,
    /// The failure class, if it failed.
    pub class: Option<&'static str>,
}

/// `joblog.tsv`, opened for appending. Each line is appended under the directory's lock with
/// the next sequence number after the file's last line, so that two processes sharing the
/// directory never write the same `seq`.
#[derive(Debug)]
pub struct Joblog {
    file: File,
    path: PathBuf,
    lock: PathBuf,
    host: String,
}

impl Joblog {
    /// Append one attempt; returns its sequence number.
    pub fn append(&mut self, a: &AttemptRecord) -> Result<u64, StoreError> {
        let _lock = DirLock::take(&self.lock)?;
        let (last, ends_with_newline) = last_seq(&self.file).map_err(io(&self.path))?;
        let seq = last + 1;
        let start = a.start.duration_since(UNIX_EPOCH).map(|d| d.as_secs_f64()).unwrap_or(0.0);
        // A line cut short (a full disk) is closed first, so that ours starts a line.
        let runtime = if a.runtime_s.is_finite() { format!("{:.3}", a.runtime_s) } else { "-".into() };
        let line = format!(
            "{}{}\t{}\t{}\t{:.3}\t{}\t{}\t{}\t{}\n",
            if ends_with_newline { "" } else { "\n" },
            seq,
            self.host,
            std::process::id(),
            start,
            runtime,
            a.status,
            a.class.unwrap_or("-"),
            a.hash
        );
        self.file.write_all(line.as_bytes()).map_err(io(&self.path))?;
        Ok(seq)
    }
}

/// The sequence number of the last whole line of a joblog (0 when it has none), and whether
/// the file ends with a newline. Reads only the file's tail.
fn last_seq(file: &File) -> std::io::Result<(u64, bool)> {
    use std::os::unix::fs::FileExt;
    let len = file.metadata()?.len();
    let mut from = len.saturating_sub(8192);
    loop {
        let mut buf = vec![0u8; (len - from) as usize];
        file.read_exact_at(&mut buf, from)?;
        let ends = buf.last().is_none_or(|&b| b == b'\n');
        let text = String::from_utf8_lossy(&buf);
        // The first line of a tail may be cut; only whole lines count.
        let whole = if from == 0 { &text[..] } else { text.split_once('\n').map_or("", |(_, r)| r) };
        let seq = whole
            .lines()
            .rev()
            .filter(|l| !is_header(l) && l.split('\t').count() == 8)
            .find_map(|l| l.split('\t').next()?.parse::<u64>().ok());
        match seq {
            Some(s) => return Ok((s, ends)),
            None if from == 0 => return Ok((0, ends)),
            None => from = 0,
        }
    }
}

/// A parsed joblog line (for status and tests).
#[derive(Debug, Clone, PartialEq)]
pub struct JoblogLine {
    pub seq: u64,
    pub pid: u32,
    pub status: String,
    pub class: String,
    pub hash: String,
}

/// Read `DIR/joblog.tsv`.
pub fn read_joblog(dir: &Path) -> Result<Vec<JoblogLine>, StoreError> {
    let path = dir.join(JOBLOG);
    let text = fs::read_to_string(&path).map_err(io(&path))?;
    Ok(text
        .lines()
        .filter(|l| !is_header(l))
        .filter_map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            (f.len() == 8).then(|| JoblogLine {
                seq: f[0].parse().unwrap_or(0),
                pid: f[2].parse().unwrap_or(0),
                status: f[5].to_string(),
                class: f[6].to_string(),
                hash: f[7].to_string(),
            })
        })
        .collect())
}

/// The state of one design point in results.csv.
#[derive(Debug, Clone, PartialEq)]
pub enum PointStatus {
    Pending,
    Done(Box<RunResult>),
    Failed(Box<RunFailure>),
    /// Closed by a verified screen and not run: MFR = 0 ([`crate::run::screen`]).
    Screened,
}

impl PointStatus {
    pub fn is_finished(&self) -> bool {
        !matches!(self, PointStatus::Pending)
    }
}

/// Write `DIR/results.csv`: one row per design point, in index order, atomically.
///
/// Columns: index, the swept parameters, status (`done`, `failed`, `pending`, `screened`),
/// failure (class), mfr (0 when screened), mfr_flux, mfr_particles, steady, vx_1..vx_12 (m/s,
/// empty for an empty layer), runtime_s, hash, quality (of the v_x profile, [`crate::point::quality`];
/// empty unless done), screen (`closed` for a point the screen closes, `verification` for one of
/// its verification sample, empty for an open point).
pub fn write_results(
    dir: &Path,
    parameters: &[String],
    points: &[PointRecord],
    status: &[PointStatus],
    sample: &std::collections::BTreeSet<usize>,
) -> Result<(), StoreError> {
    let path = dir.join("results.csv");
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header: Vec<String> = vec!["index".into()];
    header.extend(parameters.iter().cloned());
    header.extend(["status", "failure", "mfr", "mfr_flux", "mfr_particles", "steady"].map(String::from));
    header.extend((1..=VX_LAYERS).map(|k| format!("vx_{k}")));
    header.extend(["runtime_s", "hash", "quality", "screen"].map(String::from));
    w.write_record(&header).expect("in-memory csv");
    for (p, s) in points.iter().zip(status) {
        let mut row: Vec<String> = vec![p.index.to_string()];
        row.extend(p.values.iter().map(|v| v.to_string()));
        match s {
            PointStatus::Pending => {
                row.push("pending".into());
                row.extend(std::iter::repeat_n(String::new(), 5 + VX_LAYERS + 1));
            }
            PointStatus::Done(r) => {
                row.extend([
                    "done".into(),
                    String::new(),
                    r.mfr.to_string(),
                    r.mfr_flux.to_string(),
                    r.mfr_particles.to_string(),
                    r.steady.to_string(),
                ]);
                row.extend(
                    (0..VX_LAYERS)
                        .map(|k| r.vx.get(k).copied().flatten().map_or(String::new(), |v| v.to_string())),
                );
                row.push(format!("{:.3}", r.wall_time));
            }
            PointStatus::Failed(f) => {
                row.extend(["failed".into(), f.class.as_str().into()]);
                row.extend(std::iter::repeat_n(String::new(), 4 + VX_LAYERS));
                row.push(format!("{:.3}", f.wall_time));
            }
            PointStatus::Screened => {
                row.extend(["screened".into(), String::new(), "0".into()]);
                row.extend(std::iter::repeat_n(String::new(), 3 + VX_LAYERS + 1));
            }
        }
        row.push(p.hash.clone());
        row.push(match s {
            PointStatus::Done(r) => crate::point::quality::of_result(r).as_str().into(),
            _ => String::new(),
        });
        row.push(match (p.closed, sample.contains(&p.index)) {
            (true, true) => "verification".into(),
            (true, false) => "closed".into(),
            (false, _) => String::new(),
        });
        w.write_record(&row).expect("in-memory csv");
    }
    let bytes = w.into_inner().expect("in-memory csv");
    write_atomic(&path, &bytes)
}

/// Write `bytes` to a temporary name beside `path` and rename it into place.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), StoreError> {
    crate::sys::atomic::write(path, bytes).map_err(io(path))
}

fn unix_now() -> f64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.as_secs_f64()).unwrap_or(0.0)
}

/// This machine's host name.
pub fn hostname() -> String {
    let mut buf = [0u8; 256];
    // SAFETY: gethostname writes at most buf.len() bytes into buf.
    if unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) } != 0 {
        return "localhost".into();
    }
    let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    String::from_utf8_lossy(&buf[..end]).into_owned()
}

/// Start time of a live process in clock ticks since boot (`/proc/<pid>/stat` field 22);
/// `None` when there is no such process or it is a zombie (dead, not yet reaped).
pub fn process_start_ticks(pid: u32) -> Option<u64> {
    let stat = fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name (field 2) is in parentheses and may itself hold spaces or ')'.
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // fields[0] is field 3 (state), so field 22 (starttime) is fields[19].
    if matches!(fields.first(), Some(&"Z") | Some(&"X")) {
        return None;
    }
    fields.get(19)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dead_pid() -> u32 {
        let mut c = std::process::Command::new("true").spawn().unwrap();
        let pid = c.id();
        c.wait().unwrap();
        pid
    }

    fn claim_file(store: &Store, hash: &str, info: &ClaimInfo) {
        let d = store.run_dir(hash);
        fs::create_dir_all(&d).unwrap();
        fs::write(d.join("claim"), serde_json::to_string(info).unwrap()).unwrap();
    }

    #[test]
    fn a_claim_is_exclusive_between_two_sessions() {
        let dir = tempfile::tempdir().unwrap();
        let a = Store::open(dir.path());
        let b = Store::open(dir.path());
        let ClaimAttempt::Claimed(claim, None) = a.claim("h1").unwrap() else {
            panic!("first claim must succeed")
        };
        match b.claim("h1").unwrap() {
            ClaimAttempt::Busy(owner) => assert_eq!(owner.pid, std::process::id()),
            other => panic!("second claim must be busy, got {other:?}"),
        }
        assert!(matches!(b.state("h1"), RunState::Running(_)));
        a.release(claim).unwrap();
        assert!(matches!(b.claim("h1").unwrap(), ClaimAttempt::Claimed(_, None)));
    }

    #[test]
    fn a_claim_of_a_dead_process_is_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        let s = Store::open(dir.path());
        let dead = ClaimInfo { pid: dead_pid(), session: "gone".into(), ..s.me.clone() };
        claim_file(&s, "h", &dead);
        assert_eq!(s.state("h"), RunState::Interrupted(dead.clone()));
        match s.claim("h").unwrap() {
            ClaimAttempt::Claimed(_, Some(old)) => assert_eq!(old, dead),
            other => panic!("expected a takeover, got {other:?}"),
        }
    }

    #[test]
    fn a_reused_pid_does_not_keep_a_claim_alive() {
        // Our own pid is alive, but with another start time it is a different process.
        let dir = tempfile::tempdir().unwrap();
        let s = Store::open(dir.path());
        let reused =
            ClaimInfo { start_ticks: s.me.start_ticks + 1, session: "earlier".into(), ..s.me.clone() };
        claim_file(&s, "h", &reused);
        assert!(matches!(s.claim("h").unwrap(), ClaimAttempt::Claimed(_, Some(_))));
    }

    #[test]
    fn a_claim_from_another_host_stands() {
        let dir = tempfile::tempdir().unwrap();
        let s = Store::open(dir.path());
        let remote =
            ClaimInfo { host: "elsewhere".into(), pid: dead_pid(), session: "remote".into(), ..s.me.clone() };
        claim_file(&s, "h", &remote);
        assert!(matches!(s.claim("h").unwrap(), ClaimAttempt::Busy(_)));
    }

    #[test]
    fn a_truncated_claim_is_stale() {
        let dir = tempfile::tempdir().unwrap();
        let s = Store::open(dir.path());
        fs::create_dir_all(s.run_dir("h")).unwrap();
        fs::write(s.run_dir("h").join("claim"), "{\"host\": \"x").unwrap();
        assert!(matches!(s.claim("h").unwrap(), ClaimAttempt::Claimed(_, None)));
    }

    #[test]
    fn start_ticks_of_self_and_of_a_zombie() {
        assert!(process_start_ticks(std::process::id()).is_some());
        let c = std::process::Command::new("true").spawn().unwrap();
        let pid = c.id();
        std::thread::sleep(std::time::Duration::from_millis(200));
        // Exited but not reaped: a zombie counts as gone.
        assert_eq!(process_start_ticks(pid), None);
        drop(c);
    }

    #[test]
    fn cleaning_keeps_only_the_claim() {
        let dir = tempfile::tempdir().unwrap();
        let s = Store::open(dir.path());
        let ClaimAttempt::Claimed(claim, _) = s.claim("h").unwrap() else { panic!() };
        let d = s.run_dir("h");
        fs::write(d.join("log.liggghts"), "half a log").unwrap();
        fs::create_dir(d.join("post")).unwrap();
        fs::write(d.join("post/dump.1"), "x").unwrap();
        s.clean_run_dir("h").unwrap();
        let left: Vec<_> = fs::read_dir(&d).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, vec![std::ffi::OsString::from("claim")]);
        s.release(claim).unwrap();
        assert!(!d.join("claim").exists());
    }

    #[test]
    fn joblog_lines_round_trip_and_continue_numbering() {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("joblog.tsv"), format!("{JOBLOG_HEADER}\n")).unwrap();
        let s = Store::open(dir.path());
        let rec = |h: &str, status, class| AttemptRecord {
            hash: h.into(),
            start: SystemTime::now(),
            runtime_s: 1.5,
            status,
            class,
        };
        s.joblog().unwrap().append(&rec("a", "done", None)).unwrap();
        let mut log = s.joblog().unwrap();
        log.append(&rec("b", "failed", Some("timed-out"))).unwrap();
        let lines = read_joblog(dir.path()).unwrap();
        assert_eq!(lines.len(), 2);
        // A directory without a joblog (copied manifest) gets one, header first.
        let other = tempfile::tempdir().unwrap();
        Store::open(other.path()).joblog().unwrap().append(&rec("c", "done", None)).unwrap();
        let text = fs::read_to_string(other.path().join("joblog.tsv")).unwrap();
        assert!(text.starts_with(&format!("{JOBLOG_HEADER}\n1\t")), "{text}");
        assert_eq!((lines[0].seq, lines[0].hash.as_str()), (1, "a"));
        assert_eq!(
            (lines[1].seq, lines[1].status.as_str(), lines[1].class.as_str()),
            (2, "failed", "timed-out")
        );
    }
}
