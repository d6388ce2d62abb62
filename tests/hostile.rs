//! Hangs, orphans, leftovers and deterministic failures under hostile engines: fake LIGGGHTS
//! executables (shell scripts) that hang on `-h`, do not `exec` their children, time out or
//! leave restart files, and claims left by other hosts or by a kill. Each test is named after
//! what it guards.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn sweep_bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sweep"));
    c.stdin(Stdio::null());
    c
}

fn sweep(args: &[&str]) -> Output {
    sweep_bin().args(args).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// An executable shell script `dir/name` holding `text`.
fn script(dir: &Path, name: &str, text: &str) -> PathBuf {
    use std::os::unix::fs::PermissionsExt;
    let path = dir.join(name);
    std::fs::write(&path, format!("#!/bin/sh\n{text}\n")).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    path
}

/// A fake engine: prints a LIGGGHTS version for `-h`, otherwise runs `body` in the run dir.
fn fake_engine(dir: &Path, body: &str) -> PathBuf {
    script(
        dir,
        "liggghts",
        &format!(
            "for a in \"$@\"; do [ \"$a\" = -h ] && {{ echo 'LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, fake)'; exit 0; }}; done\n{body}"
        ),
    )
}

/// A sweep of `max` points in one space on `engine`, with `run` extra `[run]` keys.
fn write_sweep(dir: &Path, engine: &str, max: usize, run: &str) -> PathBuf {
    let text = format!(
        r#"name = "hostile"
[parameters]
gap         = {{ lo = 2.0, hi = 4.0, unit = "mm" }}
blade_speed = {{ lo = 1.2, hi = 1.6, unit = "m/s" }}
diameter    = {{ value = 1.5, unit = "mm" }}
[design.lds]
step = {max}
max = {max}
[run]
engine = "{engine}"
screen = false
{run}
"#
    );
    let path = dir.join("hostile.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn alive(pid: i32) -> bool {
    // A zombie is dead for our purpose: its parent (init, here) reaps it.
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Ok(s) => s.rsplit(')').next().and_then(|r| r.split_whitespace().next()) != Some("Z"),
        Err(_) => false,
    }
}

/// Wait up to `limit` for `f` to hold.
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
    write_sweep(dir, p(&engine), 2, "")
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
    let toml = hanging_check(tmp.path());
    let scratch = tmp.path().join("tmp");
    std::fs::create_dir(&scratch).unwrap();
    let mut child =
        sweep_bin().args(["run", p(&toml)]).env("TMPDIR", &scratch).stderr(Stdio::piped()).spawn().unwrap();
    let status = wait_bounded(&mut child, Duration::from_secs(40));
    let pid = read_pid(&tmp.path().join("hang.pid"));
    let gone = wait_for(Duration::from_secs(2), || pid.is_none_or(|p| !alive(p)));
    kill_if_alive(pid);
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    let status = status.expect("sweep still waits for the engine check after 40 s");
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
        let toml = hanging_check(tmp.path());
        let scratch = tmp.path().join("tmp");
        std::fs::create_dir(&scratch).unwrap();
        let mut child = sweep_bin().args(["run", p(&toml)]).env("TMPDIR", &scratch).spawn().unwrap();
        let pidfile = tmp.path().join("hang.pid");
        let started = wait_for(Duration::from_secs(10), || read_pid(&pidfile).is_some());
        unsafe { libc::kill(child.id() as i32, sig) };
        let status = wait_bounded(&mut child, Duration::from_secs(5));
        let pid = read_pid(&pidfile);
        let gone = wait_for(Duration::from_secs(2), || pid.is_none_or(|p| !alive(p)));
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
    let toml = hanging_check(tmp.path());
    let scratch = tmp.path().join("tmp");
    std::fs::create_dir(&scratch).unwrap();
    let mut child = sweep_bin().args(["run", p(&toml)]).env("TMPDIR", &scratch).spawn().unwrap();
    let pidfile = tmp.path().join("hang.pid");
    let started = wait_for(Duration::from_secs(10), || read_pid(&pidfile).is_some());
    child.kill().unwrap();
    child.wait().unwrap();
    let pid = read_pid(&pidfile);
    let gone = wait_for(Duration::from_secs(2), || pid.is_none_or(|p| !alive(p)));
    kill_if_alive(pid);
    assert!(started, "the check did not start");
    assert!(gone, "the check is an orphan");
    // The next identification of any engine clears what the killed one left.
    let good = fake_engine(tmp.path(), "exit 1");
    let toml = write_sweep(tmp.path(), p(&good), 2, "");
    let _ = sweep_bin().args(["run", p(&toml)]).env("TMPDIR", &scratch).output().unwrap();
    assert!(scratch_dirs(&scratch).is_empty(), "{:?}", scratch_dirs(&scratch));
}

#[test]
fn a_wrapper_engine_that_does_not_exec_leaves_no_process_behind_when_sweep_is_killed() {
    let tmp = tempfile::tempdir().unwrap();
    let pids = tmp.path().join("pids");
    // The wrapper starts the "engine" as a child and waits for it, as `sh -c` or mpirun would.
    let engine = fake_engine(tmp.path(), &format!("sleep 1000 &\necho $! >> {}\nwait", pids.display()));
    let toml = write_sweep(tmp.path(), p(&engine), 2, "");
    let d = tmp.path().join("d");
    let mut child = sweep_bin().args(["lds", p(&toml), "--out", p(&d), "-q", "--jobs", "2"]).spawn().unwrap();
    let two = || std::fs::read_to_string(&pids).map_or(0, |s| s.lines().count()) >= 2;
    wait_for(Duration::from_secs(20), two);
    child.kill().unwrap();
    child.wait().unwrap();
    let text = std::fs::read_to_string(&pids).unwrap_or_default();
    let pids: Vec<i32> = text.lines().filter_map(|l| l.trim().parse().ok()).collect();
    let survivors: Vec<i32> =
        pids.iter().copied().filter(|&p| !wait_for(Duration::from_secs(3), || !alive(p))).collect();
    for &pid in &survivors {
        kill_if_alive(Some(pid));
    }
    assert!(pids.len() >= 2, "the runs did not start");
    assert!(survivors.is_empty(), "the wrapper's children {survivors:?} survive");
}

/// The hashes of the points of `d`, in manifest order.
fn hashes(d: &Path) -> Vec<String> {
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("manifest.json")).unwrap()).unwrap();
    m["points"].as_array().unwrap().iter().map(|p| p["hash"].as_str().unwrap().to_string()).collect()
}

/// The joblog's attempts, each by its (lower-cased) column names.
fn joblog(d: &Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let text = std::fs::read_to_string(d.join("joblog.tsv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split('\t').map(|h| h.to_lowercase()).collect();
    lines.map(|l| header.iter().cloned().zip(l.split('\t').map(String::from)).collect()).collect()
}

fn standin(dir: &Path, max: usize) -> PathBuf {
    write_sweep(dir, "stand-in", max, "")
}

/// A claim in `runs/<hash>/claim` as another process wrote it.
fn plant_claim(d: &Path, hash: &str, host: &str, pid: u32, claimed_at: f64, lease: Option<(f64, f64)>) {
    let mut c = serde_json::json!({
        "host": host, "pid": pid, "start_ticks": 1, "session": format!("{pid}-0-1"), "claimed_at": claimed_at,
    });
    if let Some((lease_s, renewed_at)) = lease {
        c["lease_s"] = lease_s.into();
        c["renewed_at"] = renewed_at.into();
    }
    let dir = d.join("runs").join(hash);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("claim"), c.to_string()).unwrap();
}

fn now() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs_f64()
}

/// `d`'s joblog without the lines of `hash`.
fn drop_joblog_lines(d: &Path, hash: &str) {
    let text: String = std::fs::read_to_string(d.join("joblog.tsv"))
        .unwrap()
        .lines()
        .filter(|l| !l.contains(hash))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(d.join("joblog.tsv"), text).unwrap();
}

#[test]
fn a_result_without_its_joblog_line_gets_one_and_its_dead_claim_is_removed() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = standin(tmp.path(), 4);
    let d = tmp.path().join("d");
    assert_eq!(sweep(&["lds", p(&toml), "--out", p(&d), "-q"]).status.code(), Some(0));
    let h = hashes(&d);
    // What a kill between result.json and the joblog line leaves: the result, the dead
    // process's claim, and no line.
    drop_joblog_lines(&d, &h[2]);
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap();
    plant_claim(&d, &h[2], host.trim(), 999_999, now() - 5.0, Some((120.0, now() - 5.0)));

    let o = sweep(&["resume", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!d.join("runs").join(&h[2]).join("claim").exists(), "the dead claim stays");
    let lines = joblog(&d);
    let for_h2: Vec<_> = lines.iter().filter(|l| l["hash"] == h[2]).collect();
    assert_eq!(for_h2.len(), 1, "{lines:?}");
    assert_eq!(for_h2[0]["status"], "done", "{for_h2:?}");
    // Found, not run again: every hash has exactly one done line.
    for hash in &h {
        assert_eq!(
            lines.iter().filter(|l| &l["hash"] == hash && l["status"] == "done").count(),
            1,
            "{lines:?}"
        );
    }
}

#[test]
fn a_result_with_neither_its_joblog_line_nor_a_claim_gets_its_line() {
    // A kill after the claim was given back and before the line (as the chaos storms found):
    // the result alone.
    let tmp = tempfile::tempdir().unwrap();
    let toml = standin(tmp.path(), 4);
    let d = tmp.path().join("d");
    assert_eq!(sweep(&["lds", p(&toml), "--out", p(&d), "-q"]).status.code(), Some(0));
    let h = hashes(&d);
    drop_joblog_lines(&d, &h[1]);
    let o = sweep(&["resume", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = joblog(&d);
    let for_h1: Vec<_> = lines.iter().filter(|l| l["hash"] == h[1]).collect();
    assert_eq!(for_h1.len(), 1, "{lines:?}");
    assert_eq!(for_h1[0]["status"], "done", "{for_h1:?}");
    assert_eq!(lines.len(), h.len(), "a run ran again: {lines:?}");
}

#[test]
fn a_claim_torn_by_a_kill_in_a_finished_run_is_removed_on_resume() {
    // A kill between creating the claim file and writing it leaves it empty.
    let tmp = tempfile::tempdir().unwrap();
    let toml = standin(tmp.path(), 4);
    let d = tmp.path().join("d");
    assert_eq!(sweep(&["lds", p(&toml), "--out", p(&d), "-q"]).status.code(), Some(0));
    let h = hashes(&d);
    let claim = d.join("runs").join(&h[3]).join("claim");
    std::fs::write(&claim, "").unwrap();
    let o = sweep(&["resume", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!claim.exists(), "the torn claim stays");
    assert_eq!(joblog(&d).len(), h.len(), "a run ran again");
}

#[test]
fn status_names_the_holder_of_a_foreign_claim_and_unclaim_releases_it() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = standin(tmp.path(), 4);
    let d = tmp.path().join("d");
    assert_eq!(sweep(&["lds", p(&toml), "--out", p(&d), "-q"]).status.code(), Some(0));
    let h = hashes(&d);
    // Two runs not done yet, claimed elsewhere.
    for hash in &h[..2] {
        std::fs::remove_dir_all(d.join("runs").join(hash)).unwrap();
    }
    // No lease (an older tool), and one renewed an hour in the future (a clock far ahead).
    plant_claim(&d, &h[0], "node-a", 4242, now() - 7200.0, None);
    plant_claim(&d, &h[1], "node-b", 4343, now() - 60.0, Some((120.0, now() + 3600.0)));
    let o = sweep(&["status", p(&d)]);
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for needle in ["node-a", "4242", "no lease", "node-b", "4343", "future", "sweep unclaim"] {
        assert!(out.contains(needle), "status lacks {needle:?}:\n{out}");
    }
    let o = sweep(&["unclaim", p(&d)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("node-a") && err.contains("node-b"), "{err}");
    assert!(!d.join("runs").join(&h[0]).join("claim").exists());
    assert!(!d.join("runs").join(&h[1]).join("claim").exists());
    let o = sweep(&["resume", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = joblog(&d);
    for hash in &h[..2] {
        assert_eq!(
            lines.iter().filter(|l| l["status"] == "done" && &l["hash"] == hash).count(),
            2,
            "{lines:?}"
        );
    }
}

#[test]
fn a_timed_out_run_is_not_retried_and_its_reason_keeps_the_fraction() {
    let tmp = tempfile::tempdir().unwrap();
    let engine = fake_engine(tmp.path(), "exec sleep 30");
    let toml = write_sweep(tmp.path(), p(&engine), 2, "timeout_s = 0.5\nretries = 2");
    let d = tmp.path().join("d");
    let o = sweep(&["lds", p(&toml), "--out", p(&d), "-q", "--jobs", "2"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let lines = joblog(&d);
    assert_eq!(lines.len(), 2, "a timeout is retried: {lines:?}");
    let status = String::from_utf8_lossy(&sweep(&["status", p(&d)]).stdout).into_owned();
    assert!(status.contains("after 0.5 s"), "{status}");
}

#[test]
fn forced_restart_files_are_removed_from_a_failed_run() {
    let tmp = tempfile::tempdir().unwrap();
    let engine = fake_engine(
        tmp.path(),
        "head -c 100000 /dev/zero > restart_forced_liggghts_1.data\necho 'ERROR: boom' > log.liggghts\nexit 1",
    );
    let toml = write_sweep(tmp.path(), p(&engine), 2, "");
    let d = tmp.path().join("d");
    assert_eq!(sweep(&["lds", p(&toml), "--out", p(&d), "-q"]).status.code(), Some(1));
    for h in hashes(&d) {
        let dir = d.join("runs").join(&h);
        assert!(dir.join("failure.json").exists());
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with("restart_forced"))
            .collect();
        assert!(left.is_empty(), "{left:?} in {}", dir.display());
    }
}

#[test]
fn status_says_how_many_more_failures_it_does_not_list() {
    let tmp = tempfile::tempdir().unwrap();
    let engine = fake_engine(tmp.path(), "exit 1");
    let toml = write_sweep(tmp.path(), p(&engine), 5, "");
    let d = tmp.path().join("d");
    assert_eq!(sweep(&["lds", p(&toml), "--out", p(&d), "-q"]).status.code(), Some(1));
    let out = String::from_utf8_lossy(&sweep(&["status", p(&d)]).stdout).into_owned();
    let listed = out.lines().filter(|l| l.trim_start().starts_with("point ")).count();
    assert!(listed < 5, "{out}");
    assert!(out.contains(&format!("and {} more", 5 - listed)), "{out}");
}
