//! Running one child process the way a job pool must: in its own process group, bound to our
//! death, with a timeout and cooperative cancellation, never leaving an orphan behind.
//!
//! Not responsible for what the process is (see [`crate::engine`]) or for scheduling many of
//! them (see the pool). Output goes to files given by the caller, so no pipe is ever left
//! undrained.

use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::process::{Child, Command};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How often a running child is polled for exit, timeout and cancellation: starting at
/// POLL_MIN and doubling up to POLL, so a short job is noticed within a millisecond and a long
/// one costs 50 wake-ups a second.
const POLL_MIN: Duration = Duration::from_millis(1);
const POLL: Duration = Duration::from_millis(20);
/// Time between SIGTERM and SIGKILL when a job is stopped.
pub const KILL_GRACE: Duration = Duration::from_secs(2);

/// A flag that stops running children and new starts; cloned into every worker.
#[derive(Clone, Debug, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst)
    }
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst) || interrupted()
    }
}

/// How a child process ended. Outcomes are data, not errors.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ProcessOutcome {
    /// Exited by itself with this code.
    Exited(i32),
    /// Killed by a signal it did not get from us.
    Signalled(i32),
    /// Ran past its timeout and was killed.
    TimedOut,
    /// Stopped by the cancel token (Ctrl-C, SIGTERM).
    Cancelled,
    /// Stopped because the watcher saw it going wrong; the watcher's reason.
    Stopped(String),
    /// Could not be started (no such executable, permission, ...).
    SpawnFailed(String),
}

/// Start `cmd` in its own process group with PR_SET_PDEATHSIG = SIGKILL, so that the whole job
/// dies with us even when we are SIGKILLed, and wait for it with a timeout and cancellation.
///
/// PR_SET_PDEATHSIG fires when the *thread* that forked the child exits, so call this from a
/// thread that outlives the child (a pool worker, the main thread).
pub fn run(cmd: Command, timeout: Duration, cancel: &CancelToken) -> (ProcessOutcome, Duration) {
    run_watched(cmd, timeout, cancel, &mut || None)
}

/// How often [`run_watched`] calls its watcher.
pub const WATCH_EVERY: Duration = Duration::from_secs(1);

/// [`run`], also calling `watch` every [`WATCH_EVERY`] while the child runs; when it returns a
/// reason, the job is stopped at once (so a run that has already failed costs no more time).
pub fn run_watched(
    mut cmd: Command,
    timeout: Duration,
    cancel: &CancelToken,
    watch: &mut dyn FnMut() -> Option<String>,
) -> (ProcessOutcome, Duration) {
    let start = Instant::now();
    // SAFETY: only async-signal-safe calls (setpgid, prctl, getppid) between fork and exec.
    unsafe {
        cmd.pre_exec(|| {
            if libc::setpgid(0, 0) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            #[cfg(target_os = "linux")]
            {
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                // The parent may have died between fork and prctl.
                if libc::getppid() == 1 {
                    return Err(std::io::Error::other("parent exited before the job started"));
                }
            }
            Ok(())
        });
    }
    let mut child = match cmd.spawn() {
        Ok(c) => c,
        Err(e) => return (ProcessOutcome::SpawnFailed(e.to_string()), start.elapsed()),
    };
    let mut poll = POLL_MIN;
    let mut last_watch = Instant::now();
    let outcome = loop {
        match child.try_wait() {
            Ok(Some(status)) => {
                break match (status.code(), status.signal()) {
                    (Some(code), _) => ProcessOutcome::Exited(code),
                    (None, Some(sig)) => ProcessOutcome::Signalled(sig),
                    (None, None) => ProcessOutcome::Exited(-1),
                };
            }
            Ok(None) => {}
            Err(e) => {
                kill_group(&mut child);
                break ProcessOutcome::SpawnFailed(format!("cannot wait for the job: {e}"));
            }
        }
        if cancel.is_cancelled() {
            kill_group(&mut child);
            break ProcessOutcome::Cancelled;
        }
        if start.elapsed() > timeout {
            kill_group(&mut child);
            break ProcessOutcome::TimedOut;
        }
        if last_watch.elapsed() >= WATCH_EVERY {
            last_watch = Instant::now();
            if let Some(reason) = watch() {
                kill_group(&mut child);
                break ProcessOutcome::Stopped(reason);
            }
        }
        std::thread::sleep(poll);
        poll = (poll * 2).min(POLL);
    };
    (outcome, start.elapsed())
}

/// SIGTERM the child's process group, wait [`KILL_GRACE`], then SIGKILL it, and reap the child.
fn kill_group(child: &mut Child) {
    let pgid = child.id() as libc::pid_t;
    // SAFETY: plain kill(2) on the group we created for this child.
    unsafe { libc::kill(-pgid, libc::SIGTERM) };
    let deadline = Instant::now() + KILL_GRACE;
    while Instant::now() < deadline {
        if let Ok(Some(_)) = child.try_wait() {
            // The leader is gone; make sure no other member of the group survives it.
            unsafe { libc::kill(-pgid, libc::SIGKILL) };
            return;
        }
        std::thread::sleep(POLL);
    }
    unsafe { libc::kill(-pgid, libc::SIGKILL) };
    let _ = child.wait();
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    INTERRUPTED.store(true, Ordering::SeqCst);
}

/// Install SIGINT and SIGTERM handlers that set the global interrupt flag, which every
/// [`CancelToken`] observes. Call once from `main` before starting jobs.
pub fn install_interrupt_handler() {
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t);
    }
}

/// Whether SIGINT or SIGTERM has been received.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sh(script: &str) -> Command {
        let mut c = Command::new("sh");
        c.arg("-c").arg(script);
        c
    }

    #[test]
    fn exit_codes_are_reported() {
        let (o, _) = run(sh("exit 3"), Duration::from_secs(5), &CancelToken::new());
        assert_eq!(o, ProcessOutcome::Exited(3));
    }

    #[test]
    fn a_missing_executable_is_spawn_failed() {
        let (o, _) = run(Command::new("/nonexistent/liggghts"), Duration::from_secs(5), &CancelToken::new());
        assert!(matches!(o, ProcessOutcome::SpawnFailed(_)), "{o:?}");
    }

    #[test]
    fn a_hanging_job_is_killed_at_its_timeout_with_its_children() {
        let dir = tempfile::tempdir().unwrap();
        let pidfile = dir.path().join("grandchild.pid");
        // The grandchild ignores SIGTERM: only the group SIGKILL stops it.
        let script = format!("sh -c 'trap \"\" TERM; echo $$ > {}; sleep 30' & wait", pidfile.display());
        let (o, took) = run(sh(&script), Duration::from_millis(300), &CancelToken::new());
        assert_eq!(o, ProcessOutcome::TimedOut);
        assert!(took < Duration::from_secs(10));
        let pid: i32 = std::fs::read_to_string(&pidfile).unwrap().trim().parse().unwrap();
        std::thread::sleep(Duration::from_millis(100));
        // kill(pid, 0) fails with ESRCH once the process is gone (it is reaped by init).
        let alive = unsafe { libc::kill(pid, 0) } == 0
            && std::fs::read_to_string(format!("/proc/{pid}/stat"))
                .map(|s| !s.contains(") Z "))
                .unwrap_or(false);
        assert!(!alive, "grandchild {pid} survived the timeout");
    }

    #[test]
    fn a_watcher_stops_a_job_that_went_wrong() {
        let mut calls = 0;
        let mut watch = || {
            calls += 1;
            (calls == 2).then(|| "energy exploded".to_string())
        };
        let (o, took) = run_watched(sh("sleep 30"), Duration::from_secs(60), &CancelToken::new(), &mut watch);
        assert_eq!(o, ProcessOutcome::Stopped("energy exploded".into()));
        assert!(took < Duration::from_secs(10));
    }

    #[test]
    fn cancellation_stops_a_running_job() {
        let token = CancelToken::new();
        let t2 = token.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(200));
            t2.cancel();
        });
        let (o, took) = run(sh("sleep 30"), Duration::from_secs(60), &token);
        assert_eq!(o, ProcessOutcome::Cancelled);
        assert!(took < Duration::from_secs(10));
    }
}
