//! Scheduling, retries, claims, resume and extension of sweeps, on the deterministic fake
//! executor (real child processes that sleep, no LIGGGHTS).

mod common;

use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::Ordering;
use std::time::Duration;

use demsweep::outcome::FailureClass;
use demsweep::run::fake::{fake_mfr, Behaviour, FakeExecutor};
use demsweep::run::pool::Flow;
use demsweep::run::{self, RunAll, RunOptions, SpaceHook};
use demsweep::store::{self, DesignRecord, PointRecord, PointStatus, SpaceRecord};
use demsweep::sweep::Scrambling;
use demsweep::sys::process::CancelToken;

const MS: Duration = Duration::from_millis(1);

fn lds(max: usize, step: usize) -> DesignRecord {
    DesignRecord::Lds { step, max, scrambling: Scrambling::Random, seed: 7 }
}

/// results.csv as (hash, status, failure, mfr) rows.
fn results(dir: &Path) -> Vec<(String, String, String, String)> {
    let mut r = csv::Reader::from_path(dir.join("results.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let (hash, status, failure, mfr) = (col("hash"), col("status"), col("failure"), col("mfr"));
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            (rec[hash].to_string(), rec[status].to_string(), rec[failure].to_string(), rec[mfr].to_string())
        })
        .collect()
}

fn done_attempts(dir: &Path) -> HashMap<String, usize> {
    let mut m = HashMap::new();
    for l in store::read_joblog(dir).unwrap() {
        if l.status == "done" {
            *m.entry(l.hash).or_default() += 1;
        }
    }
    m
}

#[test]
fn every_point_runs_once_with_its_result_in_results_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(100 * MS));
    let sum =
        run::start(&s, lds(8, 4), &out, &exec, &common::quiet(3), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.done, sum.failed, sum.pending, sum.exit_code()), (8, 0, 0, 0));
    assert_eq!(exec.peak.load(Ordering::SeqCst), 3, "three slots were all used");
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    let rows = results(&out);
    assert_eq!(rows.len(), 8);
    for (p, row) in manifest.points.iter().zip(&rows) {
        assert_eq!(row.0, p.hash);
        assert_eq!(row.1, "done");
        let mfr: f64 = row.3.parse().unwrap();
        assert!((mfr - fake_mfr(&p.values)).abs() < 1e-12);
    }
    assert!(done_attempts(&out).values().all(|&n| n == 1));
    assert!(exec.attempts().values().all(|&n| n == 1));
}

#[test]
fn a_free_slot_takes_the_next_job_while_a_long_one_runs() {
    // Static partitioning (half the jobs per slot) would finish the long job's slot last with
    // its share still to run; a pool keeps the other slot busy with everything else.
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    // Whichever job a worker starts first is the long one (two workers race for the queue).
    let first = std::sync::Arc::new(std::sync::Mutex::new(None::<Vec<f64>>));
    let seen = first.clone();
    let exec = FakeExecutor::new(move |v, _| {
        let mut f = seen.lock().unwrap();
        let long = f.get_or_insert_with(|| v.to_vec()) == v;
        Behaviour::Succeed(if long { 1500 * MS } else { 20 * MS })
    });
    run::start(&s, lds(8, 8), &out, &exec, &common::quiet(2), &mut RunAll, &CancelToken::new()).unwrap();
    let log = store::read_joblog(&out).unwrap();
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    assert_eq!(log.len(), 8);
    let long_values = first.lock().unwrap().clone().unwrap();
    let long = manifest.points.iter().find(|p| p.values == long_values).unwrap();
    assert_eq!(log.last().unwrap().hash, long.hash, "the long job ends last");
}

#[test]
fn transient_failures_are_retried_and_physics_failures_are_not() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "retries = 2");
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
    let sum = run::start(&s, lds(16, 16), &out, &exec, &common::quiet(2), &mut RunAll, &CancelToken::new())
        .unwrap();
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
    let s = common::fake_sweep(tmp.path(), "retries = 1");
    let out = tmp.path().join("out");
    let mut exec =
        FakeExecutor::new(|v, _| if v[0] < 2.5 { Behaviour::Hang } else { Behaviour::Succeed(MS) });
    exec.timeout = 300 * MS;
    let sum =
        run::start(&s, lds(8, 8), &out, &exec, &common::quiet(2), &mut RunAll, &CancelToken::new()).unwrap();
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
fn an_interrupted_sweep_resumes_without_rerunning_finished_points() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let design = lds(12, 4);
    // The reference: one uninterrupted run.
    let reference = tmp.path().join("reference");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(50 * MS));
    run::start(&s, design.clone(), &reference, &exec, &common::quiet(2), &mut RunAll, &CancelToken::new())
        .unwrap();

    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(200 * MS));
    let cancel = CancelToken::new();
    let c2 = cancel.clone();
    let t = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(700));
        c2.cancel();
    });
    let sum = run::start(&s, design, &out, &exec, &common::quiet(2), &mut RunAll, &cancel).unwrap();
    t.join().unwrap();
    assert!(sum.interrupted);
    assert_eq!(sum.exit_code(), 130);
    assert!(sum.done > 0 && sum.done < 12, "{sum:?}");
    let before = done_attempts(&out);
    // Cancelled run dirs are left incomplete, without claims.
    let status = run::status(&out).unwrap();
    assert_eq!((status.done, status.running), (sum.done, 0));

    let exec2 = FakeExecutor::new(|_, _| Behaviour::Succeed(50 * MS));
    let sum2 = run::resume(&out, &exec2, &common::quiet(2), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum2.done, sum2.reused, sum2.exit_code()), (12, before.len(), 0));
    for h in before.keys() {
        assert!(!exec2.attempts().contains_key(h), "finished run {h} ran again");
    }
    assert!(done_attempts(&out).values().all(|&n| n == 1));
    assert_eq!(results(&out), results(&reference));
}

#[test]
fn two_resumes_on_one_directory_never_run_a_point_twice() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    // A directory with its manifest and nothing run: copied from a finished one.
    let reference = tmp.path().join("reference");
    let first = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::start(&s, lds(10, 10), &reference, &first, &common::quiet(2), &mut RunAll, &CancelToken::new())
        .unwrap();
    std::fs::create_dir(&out).unwrap();
    for f in ["sweep.toml", "manifest.json"] {
        std::fs::copy(reference.join(f), out.join(f)).unwrap();
    }

    let a = FakeExecutor::new(|_, _| Behaviour::Succeed(100 * MS));
    let b = FakeExecutor::new(|_, _| Behaviour::Succeed(100 * MS));
    let (sa, sb) = std::thread::scope(|sc| {
        let ha = sc.spawn(|| run::resume(&out, &a, &common::quiet(2), &mut RunAll, &CancelToken::new()));
        let hb = sc.spawn(|| run::resume(&out, &b, &common::quiet(2), &mut RunAll, &CancelToken::new()));
        (ha.join().unwrap().unwrap(), hb.join().unwrap().unwrap())
    });
    assert_eq!((sa.done, sb.done), (10, 10), "each sees every point done");
    let mut runs: HashMap<String, usize> = HashMap::new();
    for (h, n) in a.attempts().into_iter().chain(b.attempts()) {
        *runs.entry(h).or_default() += n;
    }
    assert_eq!(runs.len(), 10);
    assert!(runs.values().all(|&n| n == 1), "{runs:?}");
    assert!(done_attempts(&out).values().all(|&n| n == 1));
    assert_eq!(results(&out), results(&reference));
}

#[test]
fn status_counts_runs_claimed_by_a_live_sweep_as_running() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Hang);
    let cancel = CancelToken::new();
    std::thread::scope(|sc| {
        let h = sc.spawn(|| run::start(&s, lds(4, 4), &out, &exec, &common::quiet(2), &mut RunAll, &cancel));
        let mut seen = None;
        for _ in 0..200 {
            if let Ok(st) = run::status(&out) {
                if st.running == 2 {
                    seen = Some(st);
                    break;
                }
            }
            std::thread::sleep(50 * MS);
        }
        cancel.cancel();
        let sum = h.join().unwrap().unwrap();
        let st = seen.expect("two runs seen running");
        assert_eq!((st.running, st.pending, st.done), (2, 2, 0));
        assert_eq!((sum.done, sum.pending, sum.exit_code()), (0, 4, 130));
    });
    assert_eq!(run::status(&out).unwrap().running, 0, "claims released on interrupt");
}

#[test]
fn an_interrupt_while_planning_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let cancel = CancelToken::new();
    cancel.cancel();
    let err = run::start(&s, lds(10, 10), &out, &exec, &common::quiet(1), &mut RunAll, &cancel).unwrap_err();
    assert_eq!(err.code(), 130);
    assert!(!out.exists());
}

#[test]
fn a_stale_claim_and_a_half_written_run_dir_are_cleaned_and_rerun() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::start(&s, lds(3, 3), &out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    let run = out.join("runs").join(&manifest.points[1].hash);
    // A process that died mid-run: no result, a log, and its claim.
    std::fs::remove_file(run.join("result.json")).unwrap();
    std::fs::write(run.join("log.liggghts"), "half").unwrap();
    let mut dead = std::process::Command::new("true").spawn().unwrap();
    let pid = dead.id();
    dead.wait().unwrap();
    let claim = serde_json::json!({
        "host": demsweep::sys::host::hostname(), "pid": pid, "start_ticks": 1, "session": "x", "claimed_at": 0.0
    });
    std::fs::write(run.join("claim"), claim.to_string()).unwrap();
    assert_eq!(run::status(&out).unwrap().pending, 1);

    let exec2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let sum = run::resume(&out, &exec2, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!(sum.done, 3);
    assert_eq!(exec2.attempts().keys().collect::<Vec<_>>(), vec![&manifest.points[1].hash]);
    assert!(!run.join("log.liggghts").exists());
    assert!(!run.join("claim").exists());
}

#[test]
fn failed_runs_are_rerun_only_with_retry_failed() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let fail_all = FakeExecutor::new(|_, _| Behaviour::Fail(MS, FailureClass::EngineError));
    let sum = run::start(&s, lds(3, 3), &out, &fail_all, &common::quiet(1), &mut RunAll, &CancelToken::new())
        .unwrap();
    assert_eq!((sum.failed, sum.exit_code()), (3, 1));

    let ok = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let sum = run::resume(&out, &ok, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.failed, sum.ran), (3, 0));
    assert!(ok.attempts().is_empty(), "a failure is a result, not a missing run");

    let retry = RunOptions { retry_failed: true, ..common::quiet(1) };
    let sum = run::resume(&out, &ok, &retry, &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.done, sum.failed, sum.exit_code()), (3, 0, 0));
    assert!(results(&out).iter().all(|r| r.1 == "done"));
}

#[test]
fn a_changed_engine_is_refused_unless_forced_and_nothing_changes_on_disk() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let v1 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::start(&s, lds(3, 3), &out, &v1, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    let manifest_before = std::fs::read(out.join("manifest.json")).unwrap();
    let mut v2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    v2.identity = "fake-2".into();
    let err = run::resume(&out, &v2, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap_err();
    assert_eq!(err.code(), 2);
    let msg = err.to_string();
    assert!(msg.contains("engine: \"fake-1\" → \"fake-2\""), "{msg}");
    assert!(msg.contains("--force"), "{msg}");
    assert_eq!(std::fs::read(out.join("manifest.json")).unwrap(), manifest_before);
    assert!(v2.attempts().is_empty());

    let forced = RunOptions { force: true, ..common::quiet(1) };
    let sum = run::resume(&out, &v2, &forced, &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.done, sum.ran), (3, 3), "new decks, new runs");
}

#[test]
fn a_larger_max_extends_an_lds_directory_reusing_its_prefix() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let e1 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::start(&s, lds(4, 4), &out, &e1, &common::quiet(2), &mut RunAll, &CancelToken::new()).unwrap();
    let e2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let sum =
        run::start(&s, lds(8, 4), &out, &e2, &common::quiet(2), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.done, sum.reused, sum.ran), (8, 4, 4));
    assert!(e2.attempts().keys().all(|h| !e1.attempts().contains_key(h)));
    let (manifest, toml) = store::Store::read_manifest(&out).unwrap();
    assert_eq!(manifest.spaces.len(), 2);
    assert!(toml.contains("max = 8"), "{toml}");
}

#[test]
fn a_design_that_does_not_extend_the_directory_is_refused_and_nothing_changes() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let three = DesignRecord::Lattice { levels: vec![3] };
    run::start(&s, three, &out, &exec, &common::quiet(2), &mut RunAll, &CancelToken::new()).unwrap();
    let before = std::fs::read(out.join("manifest.json")).unwrap();
    // Levels 2,3 put the 2x2 corners first: the old 3x3 points are not its prefix.
    let two_three = DesignRecord::Lattice { levels: vec![2, 3] };
    let err = run::start(&s, two_three, &out, &exec, &common::quiet(2), &mut RunAll, &CancelToken::new())
        .unwrap_err();
    assert_eq!(err.code(), 2, "{err}");
    assert!(err.to_string().contains("not the first points"), "{err}");
    let err = run::start(&s, lds(9, 9), &out, &exec, &common::quiet(2), &mut RunAll, &CancelToken::new())
        .unwrap_err();
    assert!(err.to_string().contains("holds a lattice sweep"), "{err}");
    assert_eq!(std::fs::read(out.join("manifest.json")).unwrap(), before);
    assert_eq!(exec.attempts().len(), 9);
}

#[test]
fn a_point_shared_by_two_lattice_levels_runs_once() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let design = DesignRecord::Lattice { levels: vec![2, 3] };
    let sum =
        run::start(&s, design, &out, &exec, &common::quiet(2), &mut RunAll, &CancelToken::new()).unwrap();
    // The 2×2 corners are among the 3×3 points.
    assert_eq!((sum.points, sum.done), (9, 9));
    assert_eq!(exec.attempts().len(), 9);
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    assert_eq!(manifest.spaces[0].points.len(), 4);
    assert_eq!(manifest.spaces[1].points.len(), 9);
}

/// Records the spaces it sees and stops after the first.
struct StopAfterFirst(Vec<(String, usize, usize)>);

impl SpaceHook for StopAfterFirst {
    fn space_complete(&mut self, space: &SpaceRecord, points: &[(&PointRecord, &PointStatus)]) -> Flow {
        let done = points.iter().filter(|(_, s)| matches!(s, PointStatus::Done(_))).count();
        self.0.push((space.label.clone(), points.len(), done));
        Flow::Drain
    }
}

#[test]
fn the_space_hook_sees_each_completed_space_and_can_stop_the_sweep() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(20 * MS));
    let mut hook = StopAfterFirst(vec![]);
    let sum =
        run::start(&s, lds(40, 4), &out, &exec, &common::quiet(1), &mut hook, &CancelToken::new()).unwrap();
    assert_eq!(hook.0, vec![("lds 4".to_string(), 4, 4)]);
    assert_eq!(sum.stopped_after.as_deref(), Some("lds 4"));
    assert!(sum.done < 40 && sum.done >= 4, "{sum:?}");
    assert_eq!(sum.exit_code(), 0);
}

#[test]
fn bad_designs_are_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    for design in
        [DesignRecord::Lattice { levels: vec![1] }, DesignRecord::Lattice { levels: vec![1001] }, lds(0, 4)]
    {
        let err = run::start(&s, design, &out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new())
            .unwrap_err();
        assert_eq!(err.code(), 2, "{err}");
        assert!(!out.exists());
    }
    // A directory that is not a sweep directory.
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let err = run::start(&s, lds(2, 2), &out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new())
        .unwrap_err();
    assert_eq!(err.code(), 2);
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);
    let err = run::resume(&out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap_err();
    assert_eq!(err.code(), 2);
    assert!(err.to_string().contains("not a sweep directory"), "{err}");
}
