//! Several processes on one sweep directory: two sweeps started at once on a new directory
//! share the work, two resumes never run a point twice and keep the joblog's seq unique,
//! concurrent `--retry-failed` resumes run each failed point once more, and a claim held by
//! another host is named by `status` and released by `unclaim`. On the fake executor (threads,
//! many rounds), the stand-in, fake engines and real LIGGGHTS.

use std::collections::{BTreeSet, HashMap};
use std::process::{Command, Stdio};

use demsweep::run::fake::{Behaviour, FakeExecutor};
use demsweep::run::{self, RunAll};
use demsweep::store;
use demsweep::sys::process::CancelToken;

use crate::support::{
    self, assert_unique_seq, attempt_counts, attempts, done_per_hash, failed_sweep, joblog, lds, now, p,
    plant_claim, quick_sweep, results, run_two_at_once, stderr, sweep, MS,
};

// ---- two sweeps, two resumes ----

#[test]
fn two_sweeps_started_at_once_on_one_new_directory_share_the_work() {
    // Threads, so that the two creations overlap as closely as possible, many times.
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    for round in 0..25 {
        let out = tmp.path().join(format!("out{round}"));
        let execs = [
            FakeExecutor::new(|_, _| Behaviour::Succeed(2 * MS)),
            FakeExecutor::new(|_, _| Behaviour::Succeed(2 * MS)),
        ];
        let results: Vec<_> = std::thread::scope(|scope| {
            let handles: Vec<_> = execs
                .iter()
                .map(|e| {
                    let (s, out) = (&s, &out);
                    scope.spawn(move || support::run_all(s, lds(6, 3), out, e, 1))
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for r in &results {
            let sum = r.as_ref().unwrap_or_else(|e| panic!("round {round}: {e}"));
            assert_eq!(sum.done, 6, "round {round}");
        }
        let runs: usize = execs.iter().map(|e| e.attempts().values().sum::<usize>()).sum();
        assert_eq!(runs, 6, "round {round}: a point ran twice");
        let done = done_per_hash(&out);
        assert!(done.len() == 6 && done.values().all(|&n| n == 1), "round {round}: {done:?}");
        assert_unique_seq(&out);
    }
}

#[test]
fn joblog_seq_is_unique_when_two_resumes_share_a_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    // A directory with its manifest and nothing run (a copy made elsewhere, a killed start).
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    support::run_all(&s, lds(12, 12), &out, &exec, 1).unwrap();
    std::fs::remove_dir_all(out.join("runs")).unwrap();
    std::fs::write(out.join("joblog.tsv"), format!("{}\n", store::JOBLOG_HEADER)).unwrap();
    let execs = [
        FakeExecutor::new(|_, _| Behaviour::Succeed(5 * MS)),
        FakeExecutor::new(|_, _| Behaviour::Succeed(5 * MS)),
    ];
    std::thread::scope(|scope| {
        for e in &execs {
            let out = &out;
            scope.spawn(move || {
                run::resume(out, e, &support::quiet(2), &mut RunAll, &CancelToken::new()).unwrap()
            });
        }
    });
    assert!(execs.iter().all(|e| !e.attempts().is_empty()), "both resumes should have run points");
    assert_eq!(done_per_hash(&out).len(), 12);
    assert_unique_seq(&out);
}

#[test]
fn two_resumes_on_one_directory_never_run_a_point_twice() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    // A directory with its manifest and nothing run: copied from a finished one.
    let reference = tmp.path().join("reference");
    let first = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    support::run_all(&s, lds(10, 10), &reference, &first, 2).unwrap();
    std::fs::create_dir(&out).unwrap();
    for f in ["sweep.toml", "manifest.json"] {
        std::fs::copy(reference.join(f), out.join(f)).unwrap();
    }

    let a = FakeExecutor::new(|_, _| Behaviour::Succeed(100 * MS));
    let b = FakeExecutor::new(|_, _| Behaviour::Succeed(100 * MS));
    let (sa, sb) = std::thread::scope(|sc| {
        let ha = sc.spawn(|| run::resume(&out, &a, &support::quiet(2), &mut RunAll, &CancelToken::new()));
        let hb = sc.spawn(|| run::resume(&out, &b, &support::quiet(2), &mut RunAll, &CancelToken::new()));
        (ha.join().unwrap().unwrap(), hb.join().unwrap().unwrap())
    });
    assert_eq!((sa.done, sb.done), (10, 10), "each sees every point done");
    let mut runs: HashMap<String, usize> = HashMap::new();
    for (h, n) in a.attempts().into_iter().chain(b.attempts()) {
        *runs.entry(h).or_default() += n;
    }
    assert_eq!(runs.len(), 10);
    assert!(runs.values().all(|&n| n == 1), "{runs:?}");
    assert!(done_per_hash(&out).values().all(|&n| n == 1));
    assert_eq!(results(&out), results(&reference));
}

#[test]
fn two_sweep_processes_started_at_once_on_one_new_directory_share_the_work() {
    support::require_liggghts!("two_sweep_processes_started_at_once_on_one_new_directory_share_the_work");
    let tmp = tempfile::tempdir().unwrap();
    let sweep = quick_sweep(tmp.path(), "pair", "", None);
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

#[test]
fn retry_failed_in_three_concurrent_resumes_runs_each_failed_point_once_more() {
    let tmp = tempfile::tempdir().unwrap();
    let d = failed_sweep(tmp.path());
    let children: Vec<_> = (0..3)
        .map(|_| {
            Command::new(env!("CARGO_BIN_EXE_sweep"))
                .args(["resume", p(&d), "--retry-failed", "-q", "--jobs", "1"])
                .stdin(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let o = c.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    }
    let n = attempt_counts(&d);
    assert!(n.values().all(|&a| a == 2), "attempts per point: {n:?}");
    // A later invocation is a new retry: once more each.
    let o = sweep(&["resume", p(&d), "--retry-failed", "-q"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(attempt_counts(&d).values().all(|&a| a == 3), "{:?}", attempt_counts(&d));
}

// ---- claims of other hosts ----

#[test]
fn status_names_the_holder_of_a_foreign_claim_and_unclaim_releases_it() {
    let tmp = tempfile::tempdir().unwrap();
    let (d, h) = support::finished_standin(tmp.path(), 4);
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
