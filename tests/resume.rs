//! Real LIGGGHTS sweeps through the `sweep` binary: killed (SIGKILL, SIGINT) part-way and
//! resumed, two resumes at once, a run past its timeout, a deck that makes LIGGGHTS fail.
//!
//! Small on purpose (3 points of the quick scene); every check compares with an uninterrupted
//! run of the same sweep or with the joblog, never with figures copied from our own output.

mod common;
use common::results;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The quick demo scene, with gap and blade speed swept.
fn write_sweep(dir: &Path, name: &str, extra_run: &str, template: Option<&Path>) -> PathBuf {
    let template = template.map_or(String::new(), |t| format!("template = {:?}\n", t));
    let tables = format!(
        r#"[scene]
{template}
[run]
{extra_run}
"#
    );
    common::write_file(&dir.join(format!("{name}.toml")), &common::quick_scene(name, &tables))
}

fn run(cmd: &mut Command) -> Output {
    cmd.stdin(Stdio::null()).output().unwrap()
}

/// Start `sweep ARGS DIR` twice at once; both must succeed.
fn run_two_at_once(args: &[&str], dir: &Path) {
    let spawn = || {
        common::sweep_bin().args(args).arg(dir).stdin(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap()
    };
    let (a, b) = (spawn(), spawn());
    for c in [a, b] {
        let o = c.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Joblog lines by hash: the statuses of its attempts in order.
fn attempts(dir: &Path) -> BTreeMap<String, Vec<String>> {
    let mut m: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for l in demsweep::store::read_joblog(dir).unwrap() {
        m.entry(l.hash).or_default().push(l.status);
    }
    m
}

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

fn wait_until(what: &str, limit: Duration, mut cond: impl FnMut() -> bool) {
    let t = Instant::now();
    while !cond() {
        assert!(t.elapsed() < limit, "gave up waiting for {what}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn any_result(dir: &Path) -> bool {
    std::fs::read_dir(dir.join("runs"))
        .map(|d| d.flatten().any(|e| e.path().join("result.json").exists()))
        .unwrap_or(false)
}

/// Start `sweep lds` on `out`, wait until one run has finished while another is running, and
/// send `signal`. Returns the child's exit status and its jobs' process groups.
fn interrupt(sweep: &Path, out: &Path, signal: i32) -> (std::process::ExitStatus, BTreeSet<i32>) {
    let mut child: Child = common::sweep_bin()
        .args(["lds", sweep.to_str().unwrap(), "--max", "3", "--step", "3"])
        .args(["--jobs", "2", "-q", "--out"])
        .arg(out)
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut groups = BTreeSet::new();
    wait_until("a finished run with another running", Duration::from_secs(180), || {
        groups = child_groups(child.id());
        any_result(out) && !groups.is_empty()
    });
    // SAFETY: signalling the child we spawned.
    unsafe { libc::kill(child.id() as i32, signal) };
    let status = child.wait().unwrap();
    (status, groups)
}

#[test]
fn killed_and_interrupted_sweeps_resume_to_the_uninterrupted_results() {
    common::require_liggghts!("killed_and_interrupted_sweeps_resume_to_the_uninterrupted_results");
    let tmp = tempfile::tempdir().unwrap();
    let sweep = write_sweep(tmp.path(), "kr", "", None);
    let lds = |out: &Path| {
        let mut c = common::sweep_bin();
        c.args(["lds", sweep.to_str().unwrap(), "--max", "3", "--step", "3", "--jobs", "2", "-q", "--out"])
            .arg(out);
        c
    };

    let reference = tmp.path().join("reference");
    let o = run(&mut lds(&reference));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let want = results(&reference);
    assert_eq!(want.len(), 3);
    assert!(want.iter().all(|r| r.1 == "done"), "{want:?}");

    // SIGKILL: no chance to clean up; each run's guard takes its LIGGGHTS down with us.
    let killed = tmp.path().join("killed");
    let (status, groups) = interrupt(&sweep, &killed, libc::SIGKILL);
    assert_eq!(std::os::unix::process::ExitStatusExt::signal(&status), Some(libc::SIGKILL));
    wait_until("the killed sweep's jobs to die", Duration::from_secs(10), || alive_in(&groups).is_empty());
    let finished_before: Vec<String> = attempts(&killed).into_keys().collect();
    // The run cut off by the kill left its claim: status shows it as interrupted.
    let st = run(common::sweep_bin().args(["status", "--json"]).arg(&killed));
    let st: serde_json::Value = serde_json::from_slice(&st.stdout).unwrap();
    assert!(st["interrupted"].as_u64().unwrap() >= 1, "{st}");
    let o = run(common::sweep_bin().args(["resume", "--jobs", "2", "-q"]).arg(&killed));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_done_once(&killed);
    let a = attempts(&killed);
    for h in &finished_before {
        assert_eq!(a[h], vec!["done"], "run {h} finished before the kill and ran again");
    }
    assert_eq!(results(&killed), want);

    // SIGINT: stop, kill the running jobs, record them as cancelled, exit 130.
    let interrupted = tmp.path().join("interrupted");
    let (status, groups) = interrupt(&sweep, &interrupted, libc::SIGINT);
    assert_eq!(status.code(), Some(130));
    assert_eq!(alive_in(&groups), Vec::<i32>::new(), "a LIGGGHTS job outlived `sweep`");
    let a = attempts(&interrupted);
    assert!(a.values().flatten().any(|s| s == "cancelled"), "{a:?}");
    let st = run(common::sweep_bin().args(["status", "--json"]).arg(&interrupted));
    let st: serde_json::Value = serde_json::from_slice(&st.stdout).unwrap();
    assert_eq!(st["running"], 0, "no claim is left behind");
    assert!(st["pending"].as_u64().unwrap() >= 1);
    let o = run(common::sweep_bin().args(["resume", "--jobs", "2", "-q"]).arg(&interrupted));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_done_once(&interrupted);
    assert_eq!(results(&interrupted), want);

    // Two resumes at once on a directory with nothing run yet: each point runs once.
    let pair = tmp.path().join("pair");
    std::fs::create_dir(&pair).unwrap();
    for f in ["sweep.toml", "manifest.json"] {
        std::fs::copy(reference.join(f), pair.join(f)).unwrap();
    }
    run_two_at_once(&["resume", "--jobs", "1", "-q"], &pair);
    let a = attempts(&pair);
    assert_eq!(a.len(), 3);
    assert!(a.values().all(|v| v == &vec!["done".to_string()]), "{a:?}");
    assert_eq!(results(&pair), want);
}

#[test]
fn a_run_past_its_timeout_is_killed_not_retried_and_reported() {
    common::require_liggghts!("a_run_past_its_timeout_is_killed_not_retried_and_reported");
    let tmp = tempfile::tempdir().unwrap();
    let sweep = write_sweep(tmp.path(), "slow", "timeout_s = 0.5\nretries = 1", None);
    let out = tmp.path().join("out");
    let o = run(common::sweep_bin()
        .args(["lds", sweep.to_str().unwrap(), "--max", "1", "--step", "1", "-q", "--out"])
        .arg(&out));
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("1 of 1 runs failed"), "{}", stderr(&o));
    let a = attempts(&out);
    assert_eq!(
        a.values().next().unwrap(),
        &vec!["failed"],
        "a timeout is not retried: the deck would run as long again"
    );
    let r = results(&out);
    assert_eq!((r[0].1.as_str(), r[0].2.as_str()), ("failed", "timed-out"));
    let st = run(common::sweep_bin().arg("status").arg(&out));
    let text = String::from_utf8_lossy(&st.stdout);
    assert!(text.contains("timed-out: 1"), "{text}");
}

#[test]
fn a_deck_that_makes_liggghts_fail_is_reported_and_the_sweep_goes_on() {
    common::require_liggghts!("a_deck_that_makes_liggghts_fail_is_reported_and_the_sweep_goes_on");
    let tmp = tempfile::tempdir().unwrap();
    // The built-in deck with an unknown command for gaps above 2.5 mm.
    let builtin = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("templates/conveyor.liggghts.tera"),
    )
    .unwrap();
    let template = tmp.path().join("broken.liggghts.tera");
    std::fs::write(
        &template,
        format!("{{% if scene.gap > 0.0025 %}}no_such_command 1\n{{% endif %}}{builtin}"),
    )
    .unwrap();
    let sweep = write_sweep(tmp.path(), "broken", "", Some(&template));
    let out = tmp.path().join("out");
    // A 2 x 2 lattice: gap 2 mm (runs) and 3 mm (fails), each at two blade speeds.
    let o = run(common::sweep_bin()
        .args(["lattice", sweep.to_str().unwrap(), "--levels", "2", "--jobs", "2", "-q", "--out"])
        .arg(&out));
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let mut seen = (0, 0);
    for rec in common::csv_rows(&out.join("results.csv")) {
        let (gap, status, failure) = (rec["gap"].as_str(), rec["status"].as_str(), rec["failure"].as_str());
        if gap == "2" {
            assert_eq!(status, "done");
            seen.0 += 1;
        } else {
            assert_eq!((gap, status, failure), ("3", "failed", "engine-error"));
            seen.1 += 1;
        }
    }
    assert_eq!(seen, (2, 2));
    let st = run(common::sweep_bin().args(["status", "--json"]).arg(&out));
    let st: serde_json::Value = serde_json::from_slice(&st.stdout).unwrap();
    assert_eq!((st["done"].as_u64(), st["failed"].as_u64()), (Some(2), Some(2)));
    let reason = st["failures"]["engine-error"]["first"][0]["reason"].as_str().unwrap();
    assert!(reason.contains("no_such_command"), "{reason}");

    // The template changes: resume refuses, naming what changed, and touches nothing.
    std::fs::write(&template, format!("# edited\n{}", std::fs::read_to_string(&template).unwrap())).unwrap();
    let manifest = std::fs::read(out.join("manifest.json")).unwrap();
    let o = run(common::sweep_bin().args(["resume", "--retry-failed", "-q"]).arg(&out));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("template_hash"), "{}", stderr(&o));
    assert!(stderr(&o).contains("--force"), "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("manifest.json")).unwrap(), manifest);
    assert_eq!(attempts(&out).values().map(Vec::len).sum::<usize>(), 4, "nothing ran");
}

#[test]
fn two_sweep_processes_started_at_once_on_one_new_directory_share_the_work() {
    common::require_liggghts!("two_sweep_processes_started_at_once_on_one_new_directory_share_the_work");
    let tmp = tempfile::tempdir().unwrap();
    let sweep = write_sweep(tmp.path(), "pair", "", None);
    let out = tmp.path().join("out");
    run_two_at_once(
        &["lds", sweep.to_str().unwrap(), "--max", "2", "--step", "2", "--jobs", "1", "-q", "--out"],
        &out,
    );
    let a = attempts(&out);
    assert_eq!(a.len(), 2);
    assert!(a.values().all(|v| v == &vec!["done".to_string()]), "{a:?}");
    let text = std::fs::read_to_string(out.join("joblog.tsv")).unwrap();
    let seqs: BTreeSet<&str> = text.lines().skip(1).map(|l| l.split('\t').next().unwrap()).collect();
    assert_eq!(seqs, BTreeSet::from(["1", "2"]), "{text}");
}
