//! Failed runs: transient failures are retried and physics failures are not; a run past its
//! timeout is killed, not retried, and reported with its reason; a deck that makes LIGGGHTS
//! fail is reported and the sweep goes on; a failed run leaves no restart files; `status` lists
//! the failures; failed runs run again only with `--retry-failed`. On the fake executor, on
//! fake engines (shell scripts) and on real LIGGGHTS.

use std::path::Path;

use demsweep::outcome::FailureClass;
use demsweep::run::fake::{Behaviour, FakeExecutor};
use demsweep::run::{self, RunAll, RunOptions};
use demsweep::store;
use demsweep::sys::process::CancelToken;

use crate::support::{
    self, attempts, engine_sweep, fake_engine, hashes, joblog, lds, output, p, quick_sweep, results, stderr,
    sweep, MS,
};

// ---- retries and timeouts ----

#[test]
fn transient_failures_are_retried_and_physics_failures_are_not() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "retries = 2");
    let out = tmp.path().join("out");
    // The gap value decides the behaviour: four bands of [2, 4] mm.
    let exec = FakeExecutor::new(|v, attempt| {
        let gap = v[0];
        if gap < 2.5 {
            // Could not start once, then fine.
            if attempt == 0 {
                Behaviour::Fail(MS, FailureClass::CouldNotStart)
            } else {
                Behaviour::Succeed(MS)
            }
        } else if gap < 3.0 {
            Behaviour::Fail(MS, FailureClass::Unstable)
        } else if gap < 3.5 {
            Behaviour::Fail(MS, FailureClass::Signalled)
        } else {
            Behaviour::Succeed(MS)
        }
    });
    let sum = support::run_all(&s, lds(16, 16), &out, &exec, 2).unwrap();
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    let attempts = exec.attempts();
    let rows = results(&out);
    let mut seen = [false; 4];
    for (p, row) in manifest.points.iter().zip(&rows) {
        let gap = p.values[0];
        let n = attempts[&p.hash];
        if gap < 2.5 {
            assert_eq!((n, row.1.as_str()), (2, "done"), "{gap}");
            seen[0] = true;
        } else if gap < 3.0 {
            assert_eq!((n, row.1.as_str(), row.2.as_str()), (1, "failed", "unstable"));
            seen[1] = true;
        } else if gap < 3.5 {
            assert_eq!((n, row.1.as_str(), row.2.as_str()), (3, "failed", "signalled"));
            seen[2] = true;
        } else {
            assert_eq!((n, row.1.as_str()), (1, "done"));
            seen[3] = true;
        }
    }
    assert_eq!(seen, [true; 4], "16 Halton points cover every gap band");
    assert!(sum.failed > 0);
    assert_eq!(sum.exit_code(), 1);
    // One joblog line per attempt.
    let total: usize = attempts.values().sum();
    assert_eq!(store::read_joblog(&out).unwrap().len(), total);
}

#[test]
fn a_hanging_job_is_killed_at_its_timeout_and_the_sweep_goes_on() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "retries = 1");
    let out = tmp.path().join("out");
    let mut exec =
        FakeExecutor::new(|v, _| if v[0] < 2.5 { Behaviour::Hang } else { Behaviour::Succeed(MS) });
    // The timeout is the event the hanging jobs end on; for the 1 ms jobs it is only a guard,
    // far beyond a start and end on a loaded machine (tests run beside LIGGGHTS, where 2 s was
    // once too short). The hanging points run at once on the two slots: the test waits one
    // timeout.
    exec.timeout = 10_000 * MS;
    let sum = support::run_all(&s, lds(8, 8), &out, &exec, 2).unwrap();
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    let rows = results(&out);
    let mut hung = 0;
    for (p, row) in manifest.points.iter().zip(&rows) {
        if p.values[0] < 2.5 {
            hung += 1;
            assert_eq!((row.1.as_str(), row.2.as_str()), ("failed", "timed-out"));
            assert_eq!(
                exec.attempts()[&p.hash],
                1,
                "a timeout is not retried: the same deck times out again"
            );
            let f: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(out.join("runs").join(&p.hash).join("failure.json")).unwrap(),
            )
            .unwrap();
            assert!(f["reason"].as_str().unwrap().contains("timeout"));
        } else {
            assert_eq!(row.1, "done");
        }
    }
    assert!(hung > 0 && hung < 8);
    assert_eq!((sum.failed, sum.exit_code()), (hung, 1));
    let status = run::status(&out).unwrap();
    assert_eq!(status.failures["timed-out"].count, hung);
}

#[test]
fn failed_runs_are_rerun_only_with_retry_failed() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let fail_all = FakeExecutor::new(|_, _| Behaviour::Fail(MS, FailureClass::EngineError));
    let sum = support::run_all(&s, lds(3, 3), &out, &fail_all, 1).unwrap();
    assert_eq!((sum.failed, sum.exit_code()), (3, 1));

    let ok = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let sum = run::resume(&out, &ok, &support::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.failed, sum.ran), (3, 0));
    assert!(ok.attempts().is_empty(), "a failure is a result, not a missing run");

    let retry = RunOptions { retry_failed: true, ..support::quiet(1) };
    let sum = run::resume(&out, &ok, &retry, &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.done, sum.failed, sum.exit_code()), (3, 0, 0));
    assert!(results(&out).iter().all(|r| r.1 == "done"));
}

#[test]
fn a_timed_out_run_is_not_retried_and_its_reason_keeps_the_fraction() {
    let tmp = tempfile::tempdir().unwrap();
    let engine = fake_engine(tmp.path(), "exec sleep 30");
    let toml = engine_sweep(tmp.path(), "engine", p(&engine), 2, 2, "timeout_s = 0.5\nretries = 2");
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
    let toml = engine_sweep(tmp.path(), "engine", p(&engine), 2, 2, "");
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
    let toml = engine_sweep(tmp.path(), "engine", p(&engine), 5, 5, "");
    let d = tmp.path().join("d");
    assert_eq!(sweep(&["lds", p(&toml), "--out", p(&d), "-q"]).status.code(), Some(1));
    let out = String::from_utf8_lossy(&sweep(&["status", p(&d)]).stdout).into_owned();
    let listed = out.lines().filter(|l| l.trim_start().starts_with("point ")).count();
    assert!(listed < 5, "{out}");
    assert!(out.contains(&format!("and {} more", 5 - listed)), "{out}");
}

// ---- on LIGGGHTS ----

#[test]
fn a_run_past_its_timeout_is_killed_not_retried_and_reported() {
    support::require_liggghts!("a_run_past_its_timeout_is_killed_not_retried_and_reported");
    let tmp = tempfile::tempdir().unwrap();
    let sweep = quick_sweep(tmp.path(), "slow", "timeout_s = 0.5\nretries = 1", None);
    let out = tmp.path().join("out");
    let o = output(
        support::sweep_bin()
            .args(["lds", sweep.to_str().unwrap(), "--max", "1", "--step", "1", "-q", "--out"])
            .arg(&out),
    );
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
    let st = output(support::sweep_bin().arg("status").arg(&out));
    let text = String::from_utf8_lossy(&st.stdout);
    assert!(text.contains("timed-out: 1"), "{text}");
}

#[test]
fn a_deck_that_makes_liggghts_fail_is_reported_and_the_sweep_goes_on() {
    support::require_liggghts!("a_deck_that_makes_liggghts_fail_is_reported_and_the_sweep_goes_on");
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
    let sweep = quick_sweep(tmp.path(), "broken", "", Some(&template));
    let out = tmp.path().join("out");
    // A 2 x 2 lattice: gap 2 mm (runs) and 3 mm (fails), each at two blade speeds.
    let o = output(
        support::sweep_bin()
            .args(["lattice", sweep.to_str().unwrap(), "--levels", "2", "--jobs", "2", "-q", "--out"])
            .arg(&out),
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let mut seen = (0, 0);
    for rec in support::csv_rows(&out.join("results.csv")) {
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
    let st = output(support::sweep_bin().args(["status", "--json"]).arg(&out));
    let st: serde_json::Value = serde_json::from_slice(&st.stdout).unwrap();
    assert_eq!((st["done"].as_u64(), st["failed"].as_u64()), (Some(2), Some(2)));
    let reason = st["failures"]["engine-error"]["first"][0]["reason"].as_str().unwrap();
    assert!(reason.contains("no_such_command"), "{reason}");

    // The template changes: resume refuses, naming what changed, and touches nothing.
    std::fs::write(&template, format!("# edited\n{}", std::fs::read_to_string(&template).unwrap())).unwrap();
    let manifest = std::fs::read(out.join("manifest.json")).unwrap();
    let o = output(support::sweep_bin().args(["resume", "--retry-failed", "-q"]).arg(&out));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("template_hash"), "{}", stderr(&o));
    assert!(stderr(&o).contains("--force"), "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("manifest.json")).unwrap(), manifest);
    assert_eq!(attempts(&out).values().map(Vec::len).sum::<usize>(), 4, "nothing ran");

    // A template edit that renders every deck as before (a Tera comment) changes no run: resume
    // goes on without `--force`, takes the new template's identity and runs nothing again.
    let edited = std::fs::read_to_string(&template).unwrap().replacen("# edited\n", "{# a note #}", 1);
    std::fs::write(&template, edited).unwrap();
    let o = output(support::sweep_bin().args(["resume", "-q"]).arg(&out));
    assert_eq!(o.status.code(), Some(1), "the two failed points stay failed: {}", stderr(&o));
    assert!(!stderr(&o).contains("changed"), "{}", stderr(&o));
    let now: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("manifest.json")).unwrap()).unwrap();
    let was: serde_json::Value = serde_json::from_slice(&manifest).unwrap();
    assert_ne!(
        now["identity"]["template_hash"], was["identity"]["template_hash"],
        "the new template recorded"
    );
    assert_eq!(now["points"], was["points"], "the same points and runs");
    assert_eq!(attempts(&out).values().map(Vec::len).sum::<usize>(), 4, "nothing ran again");
}
