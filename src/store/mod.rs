//! The sweep directory: manifest, content-addressed run dirs, claims, joblog and
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

mod belongs;
mod claim;
pub mod holders;
mod joblog;
mod manifest;
mod results;
pub mod retry;

pub use claim::{
    counts, foreign_entry, lease_alive, set_default_lease, Claim, ClaimAttempt, ClaimInfo, Heartbeat,
    RunDamage, RunState, DEFAULT_LEASE,
};
pub use joblog::{logged_outcomes, read_joblog, AttemptRecord, Joblog, JoblogLine, JOBLOG_HEADER};
pub use manifest::{DesignRecord, Manifest, ManifestError, PointRecord, SpaceRecord, MANIFEST_FORMAT};
pub use results::{write_results, Columns, PointStatus};

use std::fs::{self, File, OpenOptions};
use std::os::unix::io::AsRawFd;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::sys::disk::{describe_io, is_no_space};
use crate::sys::host::{process_start_ticks, unix_now};
use claim::{finished_state, LEASE_MS};

/// Most bytes read of each file of a sweep directory: a manifest of a million points is about
/// 300 MB, a run's outcome a few MB with its block series; a file past these was not written by
/// `sweep` (or is `/dev/zero` behind a link) and is refused rather than read into memory.
pub const MANIFEST_CAP: u64 = 2 << 30;
pub const SWEEP_TOML_CAP: u64 = 16 << 20;
pub const OUTCOME_CAP: u64 = 256 << 20;
pub const CLAIM_CAP: u64 = 1 << 20;
pub const JOBLOG_CAP: u64 = 16 << 30;

/// The lock file of a sweep directory: claims, joblog lines and the manifest are written under
/// its `flock`.
const LOCK: &str = ".lock";
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("{}", describe_io(path, source))]
    Io { path: PathBuf, source: std::io::Error },
    /// The directory is not a sweep directory this version can read.
    #[error("{}: {reason}", path.display())]
    NotASweep { path: PathBuf, reason: String },
    /// `manifest.json` parsed but contradicts itself or its seals: a hand edit or a damaged copy.
    #[error("{}: {source}; the manifest was edited or is damaged", path.display())]
    Damaged { path: PathBuf, source: ManifestError },
    /// The directory cannot be written (a read-only mount, no permission): `why` as the
    /// system says it, without its error number.
    #[error(
        "{}: cannot write in it ({why}); a sweep directory is written as it runs (claims, results, the \
         joblog): make it writable, or copy it somewhere writable and give the copy",
        dir.display()
    )]
    NotWritable { dir: PathBuf, why: String },
}

/// A write that failed is internal (exit 4; a full disk says so); a directory that is not a
/// sweep's is bad input (exit 2).
impl From<StoreError> for crate::Error {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::Io { .. } => crate::Error::Internal(Box::new(e)),
            StoreError::NotASweep { .. } | StoreError::Damaged { .. } | StoreError::NotWritable { .. } => {
                crate::Error::Input(Box::new(e))
            }
        }
    }
}

impl StoreError {
    /// Whether the file system is full (or the quota spent): free space, then resume.
    pub fn is_no_space(&self) -> bool {
        matches!(self, StoreError::Io { source, .. } if is_no_space(source))
    }
}

/// The first 12 characters of a hash, as status and warnings show it.
pub fn short(hash: &str) -> &str {
    &hash[..12.min(hash.len())]
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> StoreError + '_ {
    move |source| StoreError::Io { path: path.to_path_buf(), source }
}

/// An open sweep directory.
#[derive(Debug)]
pub struct Store {
    dir: PathBuf,
    host: String,
    me: ClaimInfo,
    /// Claim files held now, renewed by the heartbeat.
    held: Arc<Mutex<Vec<PathBuf>>>,
    sweep_file: Arc<std::sync::OnceLock<SweepFile>>,
}

/// What a store reads of its directory's sweep file (`DIR/sweep.toml`), once.
struct SweepFile {
    /// The fixed parameters.
    fixed: Vec<(String, f64)>,
    /// The layout whose results the directory holds, which checks them as they are read back.
    layout: &'static dyn crate::scenes::Layout,
}

impl std::fmt::Debug for SweepFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SweepFile").field("fixed", &self.fixed).field("layout", &self.layout.name()).finish()
    }
}

impl Store {
    /// Open `dir` (which must exist) for running: this process's identity is fixed here.
    pub fn open(dir: &Path) -> Store {
        let pid = std::process::id();
        let host = crate::sys::host::claim_host();
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
            sweep_file: Arc::default(),
        }
    }

    /// The fixed parameters of the directory's sweep file (`DIR/sweep.toml`), read once; none
    /// when it cannot be read (the manifest check says why elsewhere).
    pub(crate) fn fixed(&self) -> &[(String, f64)] {
        &self.sweep_file().fixed
    }

    /// The layout of the directory's sweep file, whose checks its results pass when read back
    /// ([`counts`]); the default layout's when the file cannot be read (the manifest check says
    /// why elsewhere).
    pub fn layout(&self) -> &'static dyn crate::scenes::Layout {
        self.sweep_file().layout
    }

    fn sweep_file(&self) -> &SweepFile {
        self.sweep_file.get_or_init(|| {
            let default = crate::scene::settings::SceneSettings::default();
            let unread = || SweepFile {
                fixed: Vec::new(),
                layout: crate::scenes::of(&default).expect("the default layout is registered"),
            };
            let path = self.dir.join("sweep.toml");
            let Ok(text) = crate::sys::read::read_text_capped(&path, SWEEP_TOML_CAP) else { return unread() };
            let Ok(sweep) = crate::sweep::Sweep::parse(&text, &path) else { return unread() };
            let fixed = sweep
                .fixed
                .iter()
                .filter_map(|p| match p.kind {
                    crate::sweep::ParamKind::Fixed(v) => Some((p.name.clone(), v)),
                    _ => None,
                })
                .collect();
            let layout = crate::scenes::of(&sweep.file.scene).unwrap_or_else(|_| unread().layout);
            SweepFile { fixed, layout }
        })
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

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    pub fn run_dir(&self, hash: &str) -> PathBuf {
        self.dir.join("runs").join(hash)
    }

    /// Write the outcome of the run `hash` (`result.json` or `failure.json`) unless it is
    /// already there: the executor writes it, and this makes sure it landed.
    pub fn record(&self, hash: &str, outcome: &crate::outcome::RunOutcome) -> Result<(), StoreError> {
        use crate::outcome::RunOutcome;
        let dir = self.run_dir(hash);
        let (name, written) = match (outcome, finished_state(&dir, self.layout())) {
            (RunOutcome::Done(r), Some(RunState::Done(d))) if *d == *r => return Ok(()),
            (RunOutcome::Failed(f), Some(RunState::Failed(d))) if *d == *f => return Ok(()),
            (RunOutcome::Done(r), _) => {
                ("result.json", crate::sys::atomic::write_json(&dir.join("result.json"), r))
            }
            (RunOutcome::Failed(f), _) => {
                ("failure.json", crate::sys::atomic::write_json(&dir.join("failure.json"), f))
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

    /// Refuse an entry of `runs/` that bears the hash of one of `manifest`'s points but is not a
    /// directory (a file put there by hand): the run could neither be read nor started there.
    pub fn check_run_dirs(&self, manifest: &Manifest) -> Result<(), StoreError> {
        let runs = self.dir.join("runs");
        let Ok(entries) = fs::read_dir(&runs) else { return Ok(()) };
        let hashes: std::collections::HashSet<&str> =
            manifest.points.iter().map(|p| p.hash.as_str()).collect();
        for e in entries.flatten() {
            let name = e.file_name();
            let Some(name) = name.to_str().filter(|n| hashes.contains(n)) else { continue };
            check_run_dir(&e.path(), name)?;
        }
        Ok(())
    }

    /// Run `f` under the directory's lock (a consistent read-then-write of a shared file).
    pub fn locked<T>(&self, f: impl FnOnce() -> T) -> Result<T, StoreError> {
        let _lock = DirLock::take(&self.dir.join(".lock"))?;
        Ok(f())
    }
}

/// Refuse `path`, the run directory of the point whose hash is `hash`, unless it is a
/// directory itself (or absent): a file cannot hold a run, and a symbolic link would have the run
/// written wherever it points, outside the sweep directory.
pub(crate) fn check_run_dir(path: &Path, hash: &str) -> Result<(), StoreError> {
    let why = match fs::symlink_metadata(path) {
        Err(_) => return Ok(()),
        Ok(m) if m.is_dir() => return Ok(()),
        Ok(m) if m.file_type().is_symlink() => format!(
            "a symbolic link, where the run of a point ({}) belongs; runs are written only inside the \
             sweep directory: remove the link and resume",
            short(hash)
        ),
        Ok(_) => format!(
            "not a directory, where the run of a point ({}) belongs; remove it and resume",
            short(hash)
        ),
    };
    Err(StoreError::NotASweep { path: path.to_path_buf(), reason: why })
}

/// `flock(2)` on a lock file, held while the guard lives. Released by the kernel if we die.
struct DirLock(File);

impl Store {
    /// Whether the directory can be written: its lock can be taken (then it is given back).
    pub fn check_writable(&self) -> Result<(), StoreError> {
        DirLock::take(&self.dir.join(LOCK)).map(drop)
    }
}

impl DirLock {
    fn take(path: &Path) -> Result<DirLock, StoreError> {
        let f =
            OpenOptions::new().create(true).truncate(false).write(true).open(path).map_err(|e| {
                match e.raw_os_error() {
                    Some(libc::EROFS | libc::EACCES | libc::EPERM) => {
                        let why = e.to_string();
                        let why = why.split(" (os error").next().unwrap_or(&why).to_lowercase();
                        StoreError::NotWritable { dir: path.parent().unwrap_or(path).to_path_buf(), why }
                    }
                    _ => io(path)(e),
                }
            })?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::SystemTime;

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
        // GNU parallel's columns: Exitval 1 for the failure, the deck as the command.
        let text = fs::read_to_string(dir.path().join("joblog.tsv")).unwrap();
        let f: Vec<&str> = text.lines().nth(2).unwrap().split('\t').collect();
        assert_eq!((f[4], f[5], f[6], f[7], f[8]), ("0", "0", "1", "0", "runs/b/in.liggghts"), "{text}");
    }

    #[test]
    fn a_joblog_of_the_earlier_format_is_read_and_continued_in_its_format() {
        let dir = tempfile::tempdir().unwrap();
        let old = "seq\thost\tpid\tstart\truntime_s\tstatus\tclass\thash\n\
                   1\tnode1\t42\t1700000000.000\t2.500\tdone\t-\taaa\n";
        fs::write(dir.path().join("joblog.tsv"), old).unwrap();
        let s = Store::open(dir.path());
        let rec = AttemptRecord {
            hash: "bbb".into(),
            start: SystemTime::now(),
            runtime_s: 1.0,
            status: "failed",
            class: Some("timed-out"),
        };
        let index = [("bbb".to_string(), 7)].into_iter().collect();
        assert_eq!(s.joblog().unwrap().with_indices(index).append(&rec).unwrap(), 2);
        let lines = read_joblog(dir.path()).unwrap();
        assert_eq!(lines.len(), 2);
        assert_eq!((lines[0].host.as_str(), lines[0].pid, lines[0].hash.as_str()), ("node1", 42, "aaa"));
        assert_eq!((lines[1].status.as_str(), lines[1].hash.as_str()), ("failed", "bbb"));
        let text = fs::read_to_string(dir.path().join("joblog.tsv")).unwrap();
        assert!(text.lines().all(|l| l.split('\t').count() == 8), "one format per file: {text}");
        // A new file gets the new columns, with the point's index.
        let new = tempfile::tempdir().unwrap();
        let index = [("bbb".to_string(), 7)].into_iter().collect();
        Store::open(new.path()).joblog().unwrap().with_indices(index).append(&rec).unwrap();
        let text = fs::read_to_string(new.path().join("joblog.tsv")).unwrap();
        let f: Vec<&str> = text.lines().nth(1).unwrap().split('\t').collect();
        assert_eq!((f.len(), f[9], f[10], f[11]), (14, "7", "bbb", "failed"), "{text}");
    }
}
