//! Interrupted and killed sweeps resume: finished runs are never run again and the results equal
//! an uninterrupted run's; what a kill leaves — a dead process's claim, a half-written run
//! directory, a result without its joblog line, a torn claim — is cleaned up or completed, and a
//! killed attempt shows as interrupted. On the fake executor, the stand-in, and real LIGGGHTS
//! (a small sweep killed part-way, its resume interrupted part-way, and resumed again).

use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Child, Stdio};
use std::time::Duration;

use demsweep::run::fake::{Behaviour, FakeExecutor};
use demsweep::run::{self, RunAll, SweepDir};
use demsweep::store;
use demsweep::sys::process::CancelToken;

use crate::support::{
    self, assert_unique_seq, attempts, done_per_hash, joblog, lds, now, output, p, plant_claim, results,
    stderr, sweep, wait_until, MS,
};

// ---- on LIGGGHTS ----

/// Every point finished exactly once: one `done` (or final `failed`) line per hash.
fn assert_done_once(dir: &Path) {
    for (hash, a) in attempts(dir) {
        let done = a.iter().filter(|s| *s == "done").count();
        assert!(done <= 1, "run {hash} completed {done} times: {a:?}");
    }
}

/// (pid, ppid, pgrp, state) of every process.
fn processes() -> Vec<(i32, i32, i32, char)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<i32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
            continue;
        };
        let Some(close) = stat.rfind(')') else { continue };
        let f: Vec<&str> = stat[close + 1..].split_whitespace().collect();
        let state = f[0].chars().next().unwrap_or('?');
        out.push((pid, f[1].parse().unwrap(), f[2].parse().unwrap(), state));
    }
    out
}

/// Process groups of the children of `pid` (each job runs in its own group). A child caught
/// between fork and its setpgid is still in `pid`'s own group, which holds this test too: that
/// group is left out.
fn child_groups(pid: u32) -> BTreeSet<i32> {
    let procs = processes();
    let own = procs.iter().find(|p| p.0 == pid as i32).map(|p| p.2);
    procs.into_iter().filter(|p| p.1 == pid as i32 && Some(p.2) != own).map(|p| p.2).collect()
}

/// Live (non-zombie) processes in any of `groups`.
fn alive_in(groups: &BTreeSet<i32>) -> Vec<i32> {
    processes()
        .into_iter()
        .filter(|p| groups.contains(&p.2) && p.3 != 'Z' && p.3 != 'X')
        .map(|p| p.0)
        .collect()
}

fn results_in(dir: &Path) -> usize {
    std::fs::read_dir(dir.join("runs"))
        .map(|d| d.flatten().filter(|e| e.path().join("result.json").exists()).count())
        .unwrap_or(0)
}

/// Run `sweep ARGS` on `out`, wait until a run has finished since it started while another is
/// running, and send `signal`. Returns the child's exit status and its jobs' process groups.
fn interrupt(args: &[&str], out: &Path, signal: i32) -> (std::process::ExitStatus, BTreeSet<i32>) {
    let before = results_in(out);
    let mut child: Child =
        support::sweep_bin().args(args).stdin(Stdio::null()).stderr(Stdio::null()).spawn().unwrap();
    let mut groups = BTreeSet::new();
    wait_until("a finished run with another running", Duration::from_secs(180), || {
        groups = child_groups(child.id());
        results_in(out) > before && !groups.is_empty()
    });
    // SAFETY: signalling the child we spawned.
    unsafe { libc::kill(child.id() as i32, signal) };
    let status = child.wait().unwrap();
    (status, groups)
}

#[test]
fn killed_and_interrupted_sweeps_resume_to_the_uninterrupted_results() {
    support::require_liggghts!("killed_and_interrupted_sweeps_resume_to_the_uninterrupted_results");
    let tmp = tempfile::tempdir().unwrap();
    // Compared digit for digit with the uninterrupted run of the same three points, each from
    // rest (support::quick_reference, shared with the cluster tests).
    let sweep = support::write_file(
        &tmp.path().join("kr.toml"),
        &support::quick_scene("kr", support::SHORT_FROM_REST),
    );
    let want = results(support::quick_reference());
    assert_eq!(want.len(), support::QUICK_REFERENCE_POINTS);
    assert!(want.iter().all(|r| r.1 == "done"), "{want:?}");
    let dir = tmp.path().join("kr");
    let d = dir.to_str().unwrap();

    // SIGKILL: no chance to clean up; each run's guard takes its LIGGGHTS down with us. One run
    // at a time, so the kill comes with one point finished and two left: two at a time, the
    // first two short points end together and the kill would leave one, which the interrupted
    // resume below needs two of.
    let lds = ["lds", sweep.to_str().unwrap(), "--max", "3", "--step", "3", "--jobs", "1", "-q", "--out", d];
    let (status, groups) = interrupt(&lds, &dir, libc::SIGKILL);
    assert_eq!(std::os::unix::process::ExitStatusExt::signal(&status), Some(libc::SIGKILL));
    wait_until("the killed sweep's jobs to die", support::GUARD, || alive_in(&groups).is_empty());
    let finished_before: Vec<String> = attempts(&dir).into_keys().collect();
    // The run cut off by the kill left its claim: status shows it as interrupted.
    let st = output(support::sweep_bin().args(["status", "--json"]).arg(&dir));
    let st: serde_json::Value = serde_json::from_slice(&st.stdout).unwrap();
    assert!(st["interrupted"].as_u64().unwrap() >= 1, "{st}");

    // SIGINT to the resume, one run at a time, once one of the killed runs has finished again:
    // stop, kill the running job, record it as cancelled, exit 130.
    let (status, groups) = interrupt(&["resume", "--jobs", "1", "-q", d], &dir, libc::SIGINT);
    assert_eq!(status.code(), Some(130));
    assert_eq!(alive_in(&groups), Vec::<i32>::new(), "a LIGGGHTS job outlived `sweep`");
    let a = attempts(&dir);
    assert!(a.values().flatten().any(|s| s == "cancelled"), "{a:?}");
    for h in &finished_before {
        assert_eq!(a[h], vec!["done"], "run {h} finished before the kill and ran again");
    }
    let st = output(support::sweep_bin().args(["status", "--json"]).arg(&dir));
    let st: serde_json::Value = serde_json::from_slice(&st.stdout).unwrap();
    assert_eq!(st["running"], 0, "no claim is left behind");
    assert!(st["pending"].as_u64().unwrap() >= 1);

    let o = output(support::sweep_bin().args(["resume", "--jobs", "2", "-q"]).arg(&dir));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_done_once(&dir);
    assert_eq!(results(&dir), want);
}

// ---- on the fake executor ----

#[test]
fn an_interrupted_sweep_resumes_without_rerunning_finished_points() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let design = lds(12, 4);
    // The reference: one uninterrupted run.
    let reference = tmp.path().join("reference");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(50 * MS));
    support::run_all(&s, design.clone(), &reference, &exec, 2).unwrap();

    let out = tmp.path().join("out");
    // Interrupted as the fifth run starts (three have finished by then with two at a time): an
    // event, not a clock, so a busy machine cannot turn it into "nothing done yet".
    let cancel = CancelToken::new();
    let (c2, started) = (cancel.clone(), std::sync::atomic::AtomicUsize::new(0));
    let exec = FakeExecutor::new(move |_, _| {
        if started.fetch_add(1, std::sync::atomic::Ordering::SeqCst) == 4 {
            c2.cancel();
        }
        Behaviour::Succeed(200 * MS)
    });
    let sum =
        run::start(SweepDir::new(&s, design, &out), &exec, &support::quiet(2), &mut RunAll, &cancel).unwrap();
    assert!(sum.interrupted);
    assert_eq!(sum.exit_code(), 130);
    assert!(sum.done > 0 && sum.done < 12, "{sum:?}");
    let before = done_per_hash(&out);
    // Cancelled run dirs are left incomplete, without claims.
    let status = run::status(&out).unwrap();
    assert_eq!((status.done, status.running), (sum.done, 0));

    let exec2 = FakeExecutor::new(|_, _| Behaviour::Succeed(50 * MS));
    let sum2 = run::resume(&out, &exec2, &support::quiet(2), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum2.done, sum2.reused, sum2.exit_code()), (12, before.len(), 0));
    for h in before.keys() {
        assert!(!exec2.attempts().contains_key(h), "finished run {h} ran again");
    }
    assert!(done_per_hash(&out).values().all(|&n| n == 1));
    assert_eq!(results(&out), results(&reference));
}

#[test]
fn a_stale_claim_and_a_half_written_run_dir_are_cleaned_and_rerun() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, manifest) = support::fake_finished(tmp.path());
    let run = out.join("runs").join(&manifest.points[1].hash);
    // A process that died mid-run: no result, a log, and its claim.
    std::fs::remove_file(run.join("result.json")).unwrap();
    std::fs::write(run.join("log.liggghts"), "half").unwrap();
    plant_claim(
        &out,
        &manifest.points[1].hash,
        &demsweep::sys::host::hostname(),
        support::dead_pid(),
        0.0,
        None,
    );
    assert_eq!(run::status(&out).unwrap().pending, 1);

    let exec2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let sum = run::resume(&out, &exec2, &support::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!(sum.done, 3);
    assert_eq!(exec2.attempts().keys().collect::<Vec<_>>(), vec![&manifest.points[1].hash]);
    assert!(!run.join("log.liggghts").exists());
    assert!(!run.join("claim").exists());
}

#[test]
fn a_killed_attempt_shows_as_interrupted_in_status_and_the_joblog() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, manifest) = support::fake_finished(tmp.path());
    let hash = &manifest.points[2].hash;
    let run = out.join("runs").join(hash);
    // What a SIGKILL mid-run leaves: the claim of a process that is gone, no result.
    std::fs::remove_file(run.join("result.json")).unwrap();
    plant_claim(&out, hash, &demsweep::sys::host::hostname(), support::dead_pid(), 1.7e9, None);
    let st = run::status(&out).unwrap();
    assert_eq!((st.done, st.pending, st.interrupted), (2, 1, 1));
    let o = support::sweep_bin().arg("status").arg(&out).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("(1 interrupted"), "{text}");

    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::resume(&out, &exec, &support::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    let lines: Vec<_> = store::read_joblog(&out).unwrap().into_iter().filter(|l| &l.hash == hash).collect();
    let statuses: Vec<&str> = lines.iter().map(|l| l.status.as_str()).collect();
    assert_eq!(statuses, ["done", "interrupted", "done"], "the killed attempt is in the joblog");
    let raw = std::fs::read_to_string(out.join("joblog.tsv")).unwrap();
    let line = raw.lines().find(|l| l.contains("\tinterrupted\t")).unwrap();
    // Starttime, JobRuntime, Exitval and Status of GNU parallel's columns plus ours.
    let f: Vec<&str> = line.split('\t').collect();
    assert_eq!(
        (f[2], f[3], f[6], f[11]),
        ("1700000000.000", "-", "130", "interrupted"),
        "start = the claim's time, runtime unknown: {line}"
    );
    assert_eq!(run::status(&out).unwrap().interrupted, 0);
    assert_unique_seq(&out);
}

// ---- what a kill leaves, on the stand-in ----

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
    let (d, h) = support::finished_standin(tmp.path(), 4);
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
    let (d, h) = support::finished_standin(tmp.path(), 4);
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
    let (d, h) = support::finished_standin(tmp.path(), 4);
    let claim = d.join("runs").join(&h[3]).join("claim");
    std::fs::write(&claim, "").unwrap();
    let o = sweep(&["resume", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!claim.exists(), "the torn claim stays");
    assert_eq!(joblog(&d).len(), h.len(), "a run ran again");
}

// ---- an interrupt obeyed in every step ----

/// Whether process `pid` catches signal `sig` (its handler is installed): bit sig − 1 of SigCgt
/// in /proc/PID/status.
fn catches(pid: u32, sig: i32) -> bool {
    let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) else { return false };
    status
        .lines()
        .find_map(|l| l.strip_prefix("SigCgt:"))
        .and_then(|m| u64::from_str_radix(m.trim(), 16).ok())
        .is_some_and(|m| m & (1 << (sig - 1)) != 0)
}

/// SIGINT or SIGTERM while `resume` writes the report of a finished 400-point sweep (about a
/// second on a quiet machine, several on a busy one): the process ends within the interrupt's
/// grace with 128 + the signal, and says how to get the report if it was not written. It used to
/// finish the report and exit 0 three to five seconds later, and on a quiet machine, where the
/// report takes less than the grace, it still exited 0.
#[test]
fn an_interrupt_during_the_final_report_ends_the_process_within_its_grace() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("d");
    let file = support::engine_sweep(tmp.path(), "big", "stand-in", 400, 200, "");
    let o = output(support::sweep_bin().args(["lds", p(&file), "-q", "--out", p(&out)]));
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    for sig in [libc::SIGINT, libc::SIGTERM] {
        let _ = std::fs::remove_dir_all(out.join("report"));
        let mut child = support::sweep_bin()
            .args(["resume", p(&out)])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The line that says the report is being written, then the signal.
        let mut lines = std::io::BufRead::lines(std::io::BufReader::new(child.stderr.take().unwrap()));
        let mut err = String::new();
        for line in lines.by_ref() {
            let line = line.unwrap();
            err.push_str(&line);
            err.push('\n');
            if line.starts_with("writing the report of 400 points") {
                break;
            }
        }
        assert!(err.contains("writing the report"), "{err}");
        assert!(catches(child.id(), sig), "no handler of signal {sig}");
        // SAFETY: signalling the child we spawned.
        unsafe { libc::kill(child.id() as i32, sig) };
        // The end is the event waited on; the deadline only guards against a process that
        // never ends (a report of 400 points takes seconds, the grace a few).
        support::wait_until("sweep to end on the signal", Duration::from_secs(120), || {
            child.try_wait().unwrap().is_some()
        });
        let status = child.wait().unwrap();
        for line in lines {
            err.push_str(&line.unwrap());
            err.push('\n');
        }
        assert_eq!(status.code(), Some(128 + sig), "signal {sig}: {err}");
        // Ended by the interrupt, not by finishing; a report that was written before the signal
        // landed is said to be, one that was not says how to get it.
        let name = if sig == libc::SIGINT { "SIGINT" } else { "SIGTERM" };
        assert!(err.contains(&format!("interrupted by {name}: ")), "{err}");
        if out.join("report/report.html").exists() {
            assert!(err.contains("the report written: "), "signal {sig}: {err}");
        } else {
            assert!(err.contains("`sweep report "), "signal {sig}: {err}");
        }
    }
    // Nothing lost: the report is written by asking for it.
    let o = output(support::sweep_bin().args(["report", p(&out)]));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("report/report.html").exists());
}

/// `sweep bench` stopped by SIGINT in a run says what stopped and the command that goes on, once,
/// not a bare `error: interrupted`: the fidelity bench reads its finished runs back, so the same
/// command goes on; the stability bench refuses a directory that is not empty, so it starts again.
#[test]
fn an_interrupted_bench_says_what_stopped_and_the_command_that_goes_on() {
    let tmp = tempfile::tempdir().unwrap();
    let started = tmp.path().join("started");
    // `-h` answers as LIGGGHTS; a run marks that it started, then waits to be stopped.
    let engine = support::fake_engine(tmp.path(), &format!("touch {}\nexec sleep 1000", p(&started)));
    let file = support::engine_sweep(tmp.path(), "bench", p(&engine), 4, 4, "");
    for (bench, flags, says) in [
        (
            "fidelity",
            &["--points", "1", "--seeds", "1", "--presets", "fast"][..],
            "goes on, reading them back",
        ),
        (
            "stability",
            &["--seeds", "1", "--ladder", "timestep", "--fractions", "0.1,0.2"][..],
            "run `sweep bench",
        ),
    ] {
        let out = tmp.path().join(bench);
        let _ = std::fs::remove_file(&started);
        let child = support::sweep_bin()
            .args(["bench", bench, p(&file)])
            .args(flags)
            .args(["--jobs", "1", "--out", p(&out)])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        wait_until("a bench run to start", support::GUARD, || started.exists());
        // SAFETY: signalling the child we spawned.
        unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
        let o = child.wait_with_output().unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(130), "{bench}: {err}");
        assert!(!err.contains("error: interrupted"), "{bench}: {err}");
        // Said by the command or, had the process to end first, by the interrupt's watchdog.
        let line =
            err.lines().find(|l| l.starts_with("interrupted")).unwrap_or_else(|| panic!("{bench}: {err}"));
        assert!(line.contains(&format!("`sweep bench {bench} ")) && line.contains(says), "{bench}: {line}");
        assert!(line.contains(p(&out)), "{bench}: names where its runs are: {line}");
    }
}

#[test]
fn status_says_how_many_passes_a_running_layers_point_has_done() {
    support::require_liggghts!("status_says_how_many_passes_a_running_layers_point_has_done");
    use std::os::unix::process::CommandExt;
    let (_tmp, dir) = support::cwd();
    let extra = "layers = 4\nleast_layers = 4\n[design.lds]\nstep = 1\nmax = 1";
    let toml = crate::layers::bed_file(&dir, "layers", "", extra);
    let out = dir.join("out");
    let mut child = support::sweep_bin()
        .args(["lds", p(&toml), "--out", p(&out), "-q"])
        .process_group(0)
        .spawn()
        .unwrap();
    // Pass 2 starts once pass 1 is recorded with its restart.
    let started = |k: usize| -> bool {
        let runs = std::fs::read_dir(out.join("runs")).map(|d| d.flatten().map(|e| e.path()).collect());
        runs.unwrap_or_else(|_| Vec::new())
            .iter()
            .any(|r: &std::path::PathBuf| r.join(format!("in.pass.{k}")).is_file())
    };
    wait_until("pass 2 to start", Duration::from_secs(600), || started(2));
    let o = sweep(&["status", p(&out)]);
    // SAFETY: kill(2) on the child's own process group.
    unsafe { libc::kill(-(child.id() as i32), libc::SIGKILL) };
    let _ = child.wait();
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let line =
        text.lines().find(|l| l.trim_start().starts_with("point 0 (")).unwrap_or_else(|| panic!("{text}"));
    // Pass 2 may have ended too by the time status looked.
    assert!(line.ends_with(", 1 pass done") || line.ends_with(", 2 passes done"), "{text}");
}

/// LIGGGHTS stopped from outside can end a pass without an error and without writing the
/// pass's restart (it writes `restart_forced_*` instead). Such a pass is not recorded as
/// finished: the point fails as signalled, keeps the pass before's restart, and goes on from
/// there when run again — it does not start pass 3 from a restart that is not there.
#[test]
fn a_pass_that_ends_without_its_restart_is_not_recorded_and_the_point_goes_on_from_the_pass_before() {
    support::require_liggghts!(
        "a_pass_that_ends_without_its_restart_is_not_recorded_and_the_point_goes_on_from_the_pass_before"
    );
    let (_tmp, dir) = support::cwd();
    let sweep = crate::layers::bed_file(&dir, "layers", "", "layers = 4\nleast_layers = 4");
    // A `liggghts` first on PATH that runs the real one, and after pass 2's first run removes the
    // restart it wrote, as a stop from outside leaves it.
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let real = std::env::split_paths(&std::env::var_os("PATH").unwrap())
        .map(|d| d.join("liggghts"))
        .find(|f| f.is_file())
        .unwrap();
    let marker = dir.join("stopped-once");
    support::write_file(
        &bin.join("liggghts"),
        &format!(
            "#!/bin/sh\n{} \"$@\"\nstatus=$?\nif [ \"$2\" = in.pass.2 ] && [ ! -e {m} ]; then touch {m}; rm -f restart.pass.2; fi\nexit $status\n",
            real.display(),
            m = marker.display()
        ),
    );
    std::process::Command::new("chmod").args(["+x", p(&bin.join("liggghts"))]).status().unwrap();
    let path = std::env::join_paths(
        std::iter::once(bin.clone()).chain(std::env::split_paths(&std::env::var_os("PATH").unwrap())),
    )
    .unwrap();
    let out = dir.join("point");
    let run = || {
        support::sweep_bin()
            .env("PATH", &path)
            .args(["run", p(&sweep), "--set", "blade_speed=0.5", "--out", p(&out)])
            .output()
            .unwrap()
    };
    let first = run();
    let err = stderr(&first);
    assert!(!first.status.success(), "{err}");
    assert!(err.contains("pass 2: LIGGGHTS ended without writing restart.pass.2"), "{err}");
    assert!(!out.join("pass.2.json").exists(), "pass 2 recorded as finished");
    assert!(out.join("pass.1.json").is_file() && out.join("restart.pass.1").is_file(), "pass 1 kept");

    let again = run();
    let err = stderr(&again);
    assert!(again.status.success(), "{err}");
    let said: Vec<&str> = err.lines().filter(|l| l.starts_with("pass ")).collect();
    assert!(said.first().is_some_and(|l| l.starts_with("pass 2 of at most 4")), "went on from pass 1: {err}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("result.json")).unwrap()).unwrap();
    assert_eq!(r["layers"]["passes"].as_array().map(Vec::len), Some(4), "{r}");
}
