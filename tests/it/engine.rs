//! The engine: its check (`liggghts -h`) times out when it hangs, and a signal or a kill during
//! it leaves no process and no scratch directory behind; a wrapper engine that does not `exec`
//! its child leaves no process behind when `sweep` is killed; an engine reached through a
//! symlink is the same engine; a changed engine is refused unless forced. Fake LIGGGHTS
//! executables (shell scripts), the fake executor, and the installed LIGGGHTS.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use demsweep::run::fake::{Behaviour, FakeExecutor};
use demsweep::run::{self, RunAll, RunOptions};
use demsweep::sweep::Sweep;
use demsweep::sys::process::CancelToken;

use crate::support::{self, engine_sweep, fake_engine, lds, p, script, GUARD, MS};

/// `sweep` with no standard input.
fn sweep_bin() -> Command {
    let mut c = support::sweep_bin();
    c.stdin(Stdio::null());
    c
}

// ---- the engine check ----

fn alive(pid: i32) -> bool {
    // A zombie is dead for our purpose: its parent (init, here) reaps it.
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Ok(s) => s.rsplit(')').next().and_then(|r| r.split_whitespace().next()) != Some("Z"),
        Err(_) => false,
    }
}

/// Wait up to `limit` for `f` to hold; whether it did.
fn wait_for(limit: Duration, mut f: impl FnMut() -> bool) -> bool {
    let t = Instant::now();
    while t.elapsed() < limit {
        if f() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    f()
}

fn read_pid(path: &Path) -> Option<i32> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

fn scratch_dirs(tmp: &Path) -> Vec<String> {
    std::fs::read_dir(tmp)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("sweep-engine-"))
        .collect()
}

/// An engine whose `-h` hangs (its pid in `dir/hang.pid`), and a sweep file using it.
fn hanging_check(dir: &Path) -> PathBuf {
    let pidfile = dir.join("hang.pid");
    let engine = script(dir, "liggghts", &format!("echo $$ > {}\nexec sleep 1000", pidfile.display()));
    engine_sweep(dir, "engine", p(&engine), 2, 2, "")
}

/// `sweep run` of [`hanging_check`]'s sweep in `dir`, with `dir/tmp` as its TMPDIR: the running
/// process and that scratch directory.
fn run_hanging_check(dir: &Path, stderr: Stdio) -> (std::process::Child, PathBuf) {
    let toml = hanging_check(dir);
    let scratch = dir.join("tmp");
    std::fs::create_dir(&scratch).unwrap();
    let child = sweep_bin().args(["run", p(&toml)]).env("TMPDIR", &scratch).stderr(stderr).spawn().unwrap();
    (child, scratch)
}

/// Kill what a test started and may have left behind (by pid), so a failing test leaves no
/// process running.
fn kill_if_alive(pid: Option<i32>) {
    if let Some(pid) = pid.filter(|&p| alive(p)) {
        unsafe { libc::kill(pid, libc::SIGKILL) };
    }
}

/// Wait at most `limit` for `child`; kill it if it is still running then. Its exit status if it
/// ended by itself.
fn wait_bounded(child: &mut std::process::Child, limit: Duration) -> Option<std::process::ExitStatus> {
    let ended = wait_for(limit, || child.try_wait().unwrap().is_some());
    if !ended {
        let _ = child.kill();
    }
    let status = child.wait().unwrap();
    ended.then_some(status)
}

#[test]
fn a_hanging_engine_check_times_out_naming_the_engine_and_leaves_no_scratch_dir() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut child, scratch) = run_hanging_check(tmp.path(), Stdio::piped());
    // The check's own time limit, then the guard.
    let status = wait_bounded(&mut child, GUARD + Duration::from_secs(40));
    let pid = read_pid(&tmp.path().join("hang.pid"));
    let gone = wait_for(GUARD, || pid.is_none_or(|p| !alive(p)));
    kill_if_alive(pid);
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    let status = status.expect("sweep still waits for the engine check after 100 s");
    assert!(!status.success(), "{err}");
    assert!(err.contains("liggghts") && err.contains("-h") && err.contains("did not answer"), "{err}");
    assert!(pid.is_some(), "the check did not run");
    assert!(gone, "the hanging check survives");
    assert!(scratch_dirs(&scratch).is_empty(), "{:?}", scratch_dirs(&scratch));
}

#[test]
fn sigterm_or_sigint_during_the_engine_check_ends_sweep_its_child_and_scratch_dir() {
    for sig in [libc::SIGTERM, libc::SIGINT] {
        let tmp = tempfile::tempdir().unwrap();
        let (mut child, scratch) = run_hanging_check(tmp.path(), Stdio::inherit());
        let pidfile = tmp.path().join("hang.pid");
        let started = wait_for(GUARD, || read_pid(&pidfile).is_some());
        unsafe { libc::kill(child.id() as i32, sig) };
        let status = wait_bounded(&mut child, GUARD);
        let pid = read_pid(&pidfile);
        let gone = wait_for(GUARD, || pid.is_none_or(|p| !alive(p)));
        kill_if_alive(pid);
        assert!(started, "the check did not start");
        let status = status.unwrap_or_else(|| panic!("sweep ignored signal {sig}"));
        assert_eq!(status.code(), Some(128 + sig), "signal {sig}");
        assert!(gone, "the check survives signal {sig}");
        assert!(scratch_dirs(&scratch).is_empty(), "{:?}", scratch_dirs(&scratch));
    }
}

#[test]
fn sigkill_during_the_engine_check_leaves_no_orphan_and_the_next_start_removes_its_scratch_dir() {
    let tmp = tempfile::tempdir().unwrap();
    let (mut child, scratch) = run_hanging_check(tmp.path(), Stdio::inherit());
    let pidfile = tmp.path().join("hang.pid");
    let started = wait_for(GUARD, || read_pid(&pidfile).is_some());
    child.kill().unwrap();
    child.wait().unwrap();
    let pid = read_pid(&pidfile);
    let gone = wait_for(GUARD, || pid.is_none_or(|p| !alive(p)));
    kill_if_alive(pid);
    assert!(started, "the check did not start");
    assert!(gone, "the check is an orphan");
    // The next identification of any engine clears what the killed one left.
    let good = fake_engine(tmp.path(), "exit 1");
    let toml = engine_sweep(tmp.path(), "engine", p(&good), 2, 2, "");
    let _ = sweep_bin().args(["run", p(&toml)]).env("TMPDIR", &scratch).output().unwrap();
    assert!(scratch_dirs(&scratch).is_empty(), "{:?}", scratch_dirs(&scratch));
}

#[test]
fn a_wrapper_engine_that_does_not_exec_leaves_no_process_behind_when_sweep_is_killed() {
    let tmp = tempfile::tempdir().unwrap();
    let pids = tmp.path().join("pids");
    // The wrapper starts the "engine" as a child and waits for it, as `sh -c` or mpirun would.
    let engine = fake_engine(tmp.path(), &format!("sleep 1000 &\necho $! >> {}\nwait", pids.display()));
    let toml = engine_sweep(tmp.path(), "engine", p(&engine), 2, 2, "");
    let d = tmp.path().join("d");
    let mut child = sweep_bin().args(["lds", p(&toml), "--out", p(&d), "-q", "--jobs", "2"]).spawn().unwrap();
    let two = || std::fs::read_to_string(&pids).map_or(0, |s| s.lines().count()) >= 2;
    wait_for(GUARD, two);
    child.kill().unwrap();
    child.wait().unwrap();
    let text = std::fs::read_to_string(&pids).unwrap_or_default();
    let pids: Vec<i32> = text.lines().filter_map(|l| l.trim().parse().ok()).collect();
    let survivors: Vec<i32> = pids.iter().copied().filter(|&p| !wait_for(GUARD, || !alive(p))).collect();
    for &pid in &survivors {
        kill_if_alive(Some(pid));
    }
    assert!(pids.len() >= 2, "the runs did not start");
    assert!(survivors.is_empty(), "the wrapper's children {survivors:?} survive");
}

// ---- the engine's identity ----

#[test]
fn an_engine_reached_through_a_symlink_is_the_same_engine() {
    let tmp = tempfile::tempdir().unwrap();
    let Some(real) = ["/usr/bin/liggghts"].into_iter().map(Path::new).find(|p| p.exists()) else {
        support::skip(
            "an_engine_reached_through_a_symlink_is_the_same_engine",
            "no /usr/bin/liggghts (bash scripts/setup.sh installs it)",
        );
        return;
    };
    let link = tmp.path().join("bin/liggghts");
    std::fs::create_dir_all(link.parent().unwrap()).unwrap();
    std::os::unix::fs::symlink(real, &link).unwrap();
    let exec = |engine: &Path| {
        let path = support::quick_lds_sweep(tmp.path(), "e", &format!("engine = {:?}", engine));
        run::PointExecutor::new(Sweep::load(&path).unwrap()).unwrap()
    };
    let (a, b) = (exec(real), exec(&link));
    use demsweep::run::pool::Executor;
    assert_ne!(a.identity()["engine_path"], b.identity()["engine_path"]);
    assert_eq!(run::identity_diff(&a.identity(), &b.identity()), Vec::<String>::new());
    let (ja, jb) = (a.prepare(&[2.5, 1.4]).unwrap(), b.prepare(&[2.5, 1.4]).unwrap());
    assert_eq!(a.hash(&ja), b.hash(&jb), "the same deck on the same engine is the same run");
}

#[test]
fn a_changed_engine_is_refused_unless_forced_and_nothing_changes_on_disk() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let v1 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    support::run_all(&s, lds(3, 3), &out, &v1, 1).unwrap();
    let manifest_before = std::fs::read(out.join("manifest.json")).unwrap();
    let mut v2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    v2.identity = "fake-2".into();
    let err = run::resume(&out, &v2, &support::quiet(1), &mut RunAll, &CancelToken::new()).unwrap_err();
    assert_eq!(err.code(), 2);
    let msg = err.to_string();
    assert!(msg.contains("engine: \"fake-1\" → \"fake-2\""), "{msg}");
    assert!(msg.contains("--force"), "{msg}");
    assert_eq!(std::fs::read(out.join("manifest.json")).unwrap(), manifest_before);
    assert!(v2.attempts().is_empty());

    let forced = RunOptions { force: true, ..support::quiet(1) };
    let sum = run::resume(&out, &v2, &forced, &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.done, sum.ran), (3, 3), "new decks, new runs");
}
