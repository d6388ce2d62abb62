//! Running one child process the way a job pool must: in its own process group, bound to our
//! death, with a timeout and cooperative cancellation, never leaving an orphan behind.
//!
//! Not responsible for what the process is (see [`crate::engine`]) or for scheduling many of
//! them (see the pool). Output goes to files given by the caller, so no pipe is ever left
//! undrained.

use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::process::{Child, Command};
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How often a running child is polled for exit, timeout and cancellation: starting at
/// POLL_MIN and doubling up to POLL, so a short job is noticed within a millisecond and a long
/// one costs 50 wake-ups a second.
const POLL_MIN: Duration = Duration::from_millis(1);
const POLL: Duration = Duration::from_millis(20);
/// Time between SIGTERM and SIGKILL when a job is stopped.
pub const KILL_GRACE: Duration = Duration::from_secs(2);
/// How long after a job died of a signal ours may still arrive, when one signal was sent to both.
const SIGNAL_SKEW: Duration = Duration::from_secs(1);

/// Whether `cancel` is set now or within `skew`.
fn cancelled_within(cancel: &CancelToken, skew: Duration) -> bool {
    let until = Instant::now() + skew;
    loop {
        if cancel.is_cancelled() {
            return true;
        }
        if Instant::now() >= until {
            return false;
        }
        std::thread::sleep(POLL);
    }
}

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

/// Start `cmd` as its own process group under a guard bound to us (see [`guard_the_job`]), so
/// that the whole job dies with us even when we are SIGKILLed, and wait for it with a timeout and
/// cancellation.
///
/// PR_SET_PDEATHSIG fires when the *thread* that forked the child exits, so call this from a
/// thread that outlives the child (a pool worker, the main thread).
pub fn run(cmd: Command, timeout: Duration, cancel: &CancelToken) -> (ProcessOutcome, Duration) {
    let f = run_watched(cmd, timeout, cancel, &mut || None);
    (f.outcome, f.wall)
}

/// How a child ended and what it cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Finished {
    pub outcome: ProcessOutcome,
    pub wall: Duration,
    /// User + system CPU time of the child and the descendants it waited for; `None` when the
    /// child was killed by us (its cost is then not a property of the job).
    pub cpu: Option<Duration>,
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
) -> Finished {
    let start = Instant::now();
    // SAFETY: between fork and exec only async-signal-safe calls are made (see `guard_the_job`).
    unsafe {
        cmd.pre_exec(guard_the_job);
    }
    let _running = ChildRunning::new();
    let mut child = match cmd.spawn() {
        Ok(c) => c,
        Err(e) => {
            return Finished {
                outcome: ProcessOutcome::SpawnFailed(e.to_string()),
                wall: start.elapsed(),
                cpu: None,
            }
        }
    };
    let mut poll = POLL_MIN;
    let mut last_watch = Instant::now();
    let mut cpu = None;
    let outcome = loop {
        match reap(&child) {
            Ok(Some((status, used))) => {
                cpu = Some(used);
                let ended = match (status.code(), status.signal()) {
                    (Some(code), _) => ProcessOutcome::Exited(code),
                    (None, Some(sig)) => ProcessOutcome::Signalled(sig),
                    (None, None) => ProcessOutcome::Exited(-1),
                };
                // A signal that stops us can reach the job first (Slurm's scancel and a
                // terminal's Ctrl-C signal every process of the job at once): a job killed by a
                // signal while we are being stopped was cancelled, not failed.
                let killed = matches!(ended, ProcessOutcome::Signalled(_) | ProcessOutcome::Exited(128..));
                break if killed && cancelled_within(cancel, SIGNAL_SKEW) {
                    ProcessOutcome::Cancelled
                } else {
                    ended
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
    Finished { outcome, wall: start.elapsed(), cpu }
}

/// Runs in the forked child before exec. The child becomes the job's *guard*: the leader of a new
/// process group, bound to us by PR_SET_PDEATHSIG. It forks once more; that grandchild execs the
/// job, and the guard stays behind to mirror the job's exit status. When we die by any signal,
/// SIGKILL included, the guard gets SIGTERM and SIGKILLs its whole group, so a wrapper engine's
/// own children (an `mpirun`, a script that does not `exec`) die with us instead of only the
/// process we started. A SIGTERM from our own [`kill_group`] leaves the job its grace period.
///
/// Only async-signal-safe calls: the parent may be multi-threaded.
fn guard_the_job() -> std::io::Result<()> {
    // SAFETY: sigset, sigprocmask, setpgid, prctl, getppid, fork, close and waitpid are all
    // async-signal-safe; every pointer is to a local.
    unsafe {
        let parent = libc::getppid();
        let mut stop: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut stop);
        for sig in [libc::SIGTERM, libc::SIGINT, libc::SIGHUP, libc::SIGCHLD] {
            libc::sigaddset(&mut stop, sig);
        }
        // Blocked before PR_SET_PDEATHSIG so that our death is noticed, not obeyed.
        libc::sigprocmask(libc::SIG_BLOCK, &stop, std::ptr::null_mut());
        libc::signal(libc::SIGCHLD, libc::SIG_DFL);
        if libc::setpgid(0, 0) != 0 {
            return Err(std::io::Error::last_os_error());
        }
        #[cfg(target_os = "linux")]
        if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0 {
            return Err(std::io::Error::last_os_error());
        }
        // We may have died between fork and prctl.
        if libc::getppid() != parent {
            return Err(std::io::Error::other("sweep exited before the job started"));
        }
        let guard = libc::getpid();
        let job = libc::fork();
        if job < 0 {
            return Err(std::io::Error::last_os_error());
        }
        if job == 0 {
            // The job: dies if its guard does; signals as the job expects them.
            #[cfg(target_os = "linux")]
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
            if libc::getppid() != guard {
                libc::_exit(128 + libc::SIGKILL);
            }
            libc::sigprocmask(libc::SIG_UNBLOCK, &stop, std::ptr::null_mut());
            return Ok(());
        }
        // The guard holds no file of ours: the spawn's exec-error pipe must close on the job's exec.
        close_from(3);
        // So that `ps` says what it is.
        #[cfg(target_os = "linux")]
        libc::prctl(libc::PR_SET_NAME, c"sweep-guard".as_ptr());
        let mut status: libc::c_int = 0;
        let second = libc::timespec { tv_sec: 1, tv_nsec: 0 };
        loop {
            let sig = libc::sigtimedwait(&stop, std::ptr::null_mut(), &second);
            // Our parent is gone (its SIGTERM, or a missed one seen by polling): end the group.
            if libc::getppid() != parent {
                libc::kill(0, libc::SIGKILL);
            }
            if sig == libc::SIGCHLD || sig < 0 {
                let r = libc::waitpid(job, &mut status, libc::WNOHANG);
                if r == job {
                    break;
                }
            }
        }
        if libc::WIFSIGNALED(status) {
            let sig = libc::WTERMSIG(status);
            libc::signal(sig, libc::SIG_DFL);
            libc::sigprocmask(libc::SIG_UNBLOCK, &stop, std::ptr::null_mut());
            libc::kill(guard, sig);
            libc::_exit(128 + sig);
        }
        libc::_exit(if libc::WIFEXITED(status) { libc::WEXITSTATUS(status) } else { 1 });
    }
}

/// Close every file descriptor from `first` on (async-signal-safe).
unsafe fn close_from(first: libc::c_int) {
    #[cfg(target_os = "linux")]
    if libc::syscall(libc::SYS_close_range, first as libc::c_uint, libc::c_uint::MAX, 0) == 0 {
        return;
    }
    let max = match libc::sysconf(libc::_SC_OPEN_MAX) {
        n if n > 0 => n.min(65_536) as libc::c_int,
        _ => 1024,
    };
    for fd in first..max {
        libc::close(fd);
    }
}

/// `try_wait` that also returns the child's CPU time (wait4(2)'s rusage: the child and every
/// descendant it waited for, so an `mpirun` launcher counts its ranks). The child is reaped:
/// `Child` is not asked about it again.
fn reap(child: &Child) -> std::io::Result<Option<(std::process::ExitStatus, Duration)>> {
    let mut status: libc::c_int = 0;
    // SAFETY: wait4 on our own child's pid with valid pointers to locals.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, libc::WNOHANG, &mut usage) };
    match pid {
        0 => Ok(None),
        p if p < 0 => Err(std::io::Error::last_os_error()),
        _ => {
            let tv = |t: libc::timeval| {
                Duration::from_secs(t.tv_sec as u64) + Duration::from_micros(t.tv_usec as u64)
            };
            let used = tv(usage.ru_utime) + tv(usage.ru_stime);
            Ok(Some((std::process::ExitStatus::from_raw(status), used)))
        }
    }
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

/// The signal that interrupted this process, 0 if none.
static INTERRUPTED: AtomicI32 = AtomicI32::new(0);

extern "C" fn on_signal(sig: libc::c_int) {
    INTERRUPTED.store(sig, Ordering::SeqCst);
}

/// Install SIGINT and SIGTERM handlers that set the global interrupt flag, which every
/// [`CancelToken`] observes, and start the watchdog that makes sure the interrupt is obeyed
/// (see [`INTERRUPT_GRACE`]). Call from `main` before starting jobs; a second call does nothing.
pub fn install_interrupt_handler() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
        unsafe {
            libc::signal(libc::SIGINT, on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t);
            libc::signal(libc::SIGTERM, on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t);
        }
        let _ = std::thread::Builder::new().name("interrupt-watchdog".into()).spawn(watchdog);
    });
}

/// How long the process may go on after an interrupt once no child is being stopped: the time
/// to write the joblog line of a cancelled run and say how far the work got. A step that does
/// not look at the interrupt flag (planning a huge design, reading a large directory, writing
/// the report) is ended by the watchdog when this has passed, with exit code 128 + the signal:
/// every write is atomic and a SIGKILL is already survived, so nothing finished is lost.
pub const INTERRUPT_GRACE: Duration = Duration::from_millis(1500);
/// Longest the process may spend stopping its children after an interrupt: their SIGTERM grace
/// and the SIGKILL after it, with a margin.
const STOPPING_MAX: Duration = Duration::from_secs(KILL_GRACE.as_secs() + 3);

/// Children running under [`run_watched`] right now: while there are some, the interrupt is
/// being obeyed (each is stopped within [`KILL_GRACE`]), so the watchdog waits for them.
static RUNNING_CHILDREN: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
/// What the watchdog says after "interrupted" when it ends the process.
static INTERRUPT_NOTE: std::sync::Mutex<String> = std::sync::Mutex::new(String::new());

/// Say `note` after "interrupted: " if the watchdog has to end the process (e.g. how to
/// continue the sweep).
pub fn on_interrupt_say(note: String) {
    if let Ok(mut n) = INTERRUPT_NOTE.lock() {
        *n = note;
    }
}

/// Counts a running child for the watchdog while it lives.
struct ChildRunning;

impl ChildRunning {
    fn new() -> ChildRunning {
        RUNNING_CHILDREN.fetch_add(1, Ordering::SeqCst);
        ChildRunning
    }
}

impl Drop for ChildRunning {
    fn drop(&mut self) {
        RUNNING_CHILDREN.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Once an interrupt has come, end the process when it has been [`INTERRUPT_GRACE`] without a
/// child to stop, or [`STOPPING_MAX`] after the signal at the latest. Children die with us
/// through their guards.
fn watchdog() {
    let tick = Duration::from_millis(20);
    let sig = loop {
        if let Some(sig) = interrupt_signal() {
            break sig;
        }
        std::thread::sleep(tick);
    };
    let signalled = Instant::now();
    let mut quiet_since = signalled;
    loop {
        if RUNNING_CHILDREN.load(Ordering::SeqCst) > 0 {
            quiet_since = Instant::now();
        }
        if quiet_since.elapsed() >= INTERRUPT_GRACE || signalled.elapsed() >= STOPPING_MAX {
            break;
        }
        std::thread::sleep(tick);
    }
    end_interrupted(sig)
}

/// If an interrupt has come, end the process now as the watchdog would: for a step that
/// finishes faster than [`INTERRUPT_GRACE`] but must not end as if it had not been told to stop.
pub fn end_if_interrupted() {
    if let Some(sig) = interrupt_signal() {
        end_interrupted(sig);
    }
}

/// Say "interrupted by SIG…" and the note set by [`on_interrupt_say`], and exit with 128 + `sig`.
fn end_interrupted(sig: i32) -> ! {
    let note = INTERRUPT_NOTE.lock().map(|n| n.clone()).unwrap_or_default();
    let name = if sig == libc::SIGTERM { "SIGTERM" } else { "SIGINT" };
    if note.is_empty() {
        eprintln!("interrupted by {name}");
    } else {
        eprintln!("interrupted by {name}: {note}");
    }
    std::process::exit(128 + sig);
}

/// Whether SIGINT or SIGTERM has been received.
pub fn interrupted() -> bool {
    interrupt_signal().is_some()
}

/// The signal (SIGINT, SIGTERM) that interrupted this process, if one did.
pub fn interrupt_signal() -> Option<i32> {
    Some(INTERRUPTED.load(Ordering::SeqCst)).filter(|&s| s != 0)
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
    fn a_job_killed_by_a_signal_is_reported_as_signalled_through_its_guard() {
        let (o, _) = run(sh("kill -KILL $$"), Duration::from_secs(5), &CancelToken::new());
        assert_eq!(o, ProcessOutcome::Signalled(libc::SIGKILL));
        let (o, _) = run(sh("kill -USR1 $$"), Duration::from_secs(5), &CancelToken::new());
        assert_eq!(o, ProcessOutcome::Signalled(libc::SIGUSR1));
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
        // Timed out, not ended by its `sleep 30`: the outcome says so, not the clock.
        assert_eq!(o, ProcessOutcome::TimedOut, "after {took:?}");
        let pid: i32 = std::fs::read_to_string(&pidfile).unwrap().trim().parse().unwrap();
        // kill(pid, 0) fails with ESRCH once the process is gone (it is reaped by init); a
        // zombie waiting for init counts as gone. Waited on, with a deadline only as a guard.
        let alive = || {
            // SAFETY: kill(2) with signal 0 only asks whether the process exists.
            let exists = unsafe { libc::kill(pid, 0) } == 0;
            exists
                && std::fs::read_to_string(format!("/proc/{pid}/stat"))
                    .map(|s| !s.contains(") Z "))
                    .unwrap_or(false)
        };
        let t = std::time::Instant::now();
        while alive() && t.elapsed() < Duration::from_secs(60) {
            std::thread::sleep(Duration::from_millis(20));
        }
        assert!(!alive(), "grandchild {pid} survived the timeout");
    }

    #[test]
    fn the_cpu_time_of_a_busy_child_is_measured_and_an_idle_one_costs_none() {
        // A shell loop burns CPU for about as long as it runs; `sleep` burns nearly none.
        let busy = run_watched(
            sh("i=0; while [ $i -lt 300000 ]; do i=$((i+1)); done"),
            Duration::from_secs(60),
            &CancelToken::new(),
            &mut || None,
        );
        assert_eq!(busy.outcome, ProcessOutcome::Exited(0));
        let cpu = busy.cpu.expect("an exited child has a CPU time");
        assert!(cpu > Duration::from_millis(50), "{cpu:?}");
        assert!(cpu <= busy.wall + Duration::from_millis(20), "{cpu:?} > {:?}", busy.wall);
        let idle = run_watched(sh("sleep 0.3"), Duration::from_secs(60), &CancelToken::new(), &mut || None);
        assert!(idle.cpu.unwrap() < Duration::from_millis(100), "{:?}", idle.cpu);
    }

    #[test]
    fn a_watcher_stops_a_job_that_went_wrong() {
        let mut calls = 0;
        let mut watch = || {
            calls += 1;
            (calls == 2).then(|| "energy exploded".to_string())
        };
        let f = run_watched(sh("sleep 30"), Duration::from_secs(60), &CancelToken::new(), &mut watch);
        // Stopped by the watcher, not ended by its `sleep 30`: the outcome says so.
        assert_eq!(f.outcome, ProcessOutcome::Stopped("energy exploded".into()), "after {:?}", f.wall);
        assert_eq!(f.cpu, None);
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
        // Cancelled, not ended by its `sleep 30`: the outcome says so, not the clock.
        assert_eq!(o, ProcessOutcome::Cancelled, "after {took:?}");
    }
}
