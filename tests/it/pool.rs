//! The job pool on the deterministic fake executor (real child processes that sleep, no
//! LIGGGHTS): every point runs once on the slots it is given, a free slot takes the next job,
//! `status` sees the runs in progress, the space hook sees each completed space, and planning
//! shows its progress and writes nothing when interrupted.

use std::process::Stdio;
use std::sync::atomic::Ordering;

use demsweep::run::fake::{fake_mfr, Behaviour, FakeExecutor};
use demsweep::run::pool::Flow;
use demsweep::run::{self, RunAll, SpaceHook, SweepDir};
use demsweep::store::{self, PointRecord, PointStatus, SpaceRecord};
use demsweep::sys::process::CancelToken;

use crate::support::{self, done_per_hash, lds, results, MS};

#[test]
fn every_point_runs_once_with_its_result_in_results_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(100 * MS));
    let sum = support::run_all(&s, lds(8, 4), &out, &exec, 3).unwrap();
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
    assert!(done_per_hash(&out).values().all(|&n| n == 1));
    assert!(exec.attempts().values().all(|&n| n == 1));
}

#[test]
fn a_free_slot_takes_the_next_job_while_a_long_one_runs() {
    // Static partitioning (half the jobs per slot) would finish the long job's slot last with
    // its share still to run; a pool keeps the other slot busy with everything else.
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    // Whichever job a worker starts first is the long one (two workers race for the queue): it
    // runs until the other seven have started, which only a free slot taking them can do. No
    // clock decides it: the long job is released by the seventh start, or fails the test after
    // a minute without it.
    use std::sync::{Arc, Condvar, Mutex};
    use std::time::Duration;
    let state = Arc::new((Mutex::new((None::<Vec<f64>>, 0usize)), Condvar::new()));
    let seen = state.clone();
    let exec = FakeExecutor::new(move |v, _| {
        let (lock, started) = &*seen;
        let mut s = lock.lock().unwrap();
        if s.0.get_or_insert_with(|| v.to_vec()) != v {
            s.1 += 1;
            started.notify_all();
            return Behaviour::Succeed(MS);
        }
        let (s, wait) = started.wait_timeout_while(s, Duration::from_secs(60), |s| s.1 < 7).unwrap();
        assert!(
            !wait.timed_out(),
            "the other slot started {} of the 7 other jobs while the long one ran",
            s.1
        );
        Behaviour::Succeed(MS)
    });
    support::run_all(&s, lds(8, 8), &out, &exec, 2).unwrap();
    let log = store::read_joblog(&out).unwrap();
    assert_eq!(log.len(), 8);
    assert!(log.iter().all(|l| l.status == "done"), "{log:?}");
    assert_eq!(state.0.lock().unwrap().1, 7, "the other seven ran beside the long one");
}

#[test]
fn status_counts_runs_claimed_by_a_live_sweep_as_running() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Hang);
    let cancel = CancelToken::new();
    std::thread::scope(|sc| {
        let h = sc.spawn(|| {
            run::start(SweepDir::new(&s, lds(4, 4), &out), &exec, &support::quiet(2), &mut RunAll, &cancel)
        });
        // The runs hang: two running is the event waited on, the deadline only a guard.
        let mut seen = None;
        support::wait_until("two runs seen running", support::GUARD, || {
            seen = run::status(&out).ok().filter(|st| st.running == 2);
            seen.is_some()
        });
        cancel.cancel();
        let sum = h.join().unwrap().unwrap();
        let st = seen.unwrap();
        assert_eq!((st.running, st.pending, st.done), (2, 2, 0));
        assert_eq!((sum.done, sum.pending, sum.exit_code()), (0, 4, 130));
    });
    assert_eq!(run::status(&out).unwrap().running, 0, "claims released on interrupt");
}

#[test]
fn an_interrupt_while_planning_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let cancel = CancelToken::new();
    cancel.cancel();
    let err =
        run::start(SweepDir::new(&s, lds(10, 10), &out), &exec, &support::quiet(1), &mut RunAll, &cancel)
            .unwrap_err();
    assert_eq!(err.code(), 130);
    assert!(!out.exists());
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
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(20 * MS));
    let mut hook = StopAfterFirst(vec![]);
    let sum = run::start(
        SweepDir::new(&s, lds(40, 4), &out),
        &exec,
        &support::quiet(1),
        &mut hook,
        &CancelToken::new(),
    )
    .unwrap();
    assert_eq!(hook.0, vec![("lds 4".to_string(), 4, 4)]);
    assert_eq!(sum.stopped_after.as_deref(), Some("lds 4"));
    assert!(sum.done < 40 && sum.done >= 4, "{sum:?}");
    assert_eq!(sum.exit_code(), 0);
}

#[test]
fn planning_a_large_lattice_shows_progress_and_an_interrupt_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let sweep = support::quick_lds_sweep(tmp.path(), "big", "");
    let out = tmp.path().join("out");
    // 2-D level 150: 22,500 decks to render and hash, several seconds of planning.
    let mut child = support::sweep_bin()
        .args(["lattice", sweep.to_str().unwrap(), "--levels", "150", "--out"])
        .arg(&out)
        .stdin(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    std::io::BufRead::read_line(&mut err, &mut line).unwrap();
    assert!(line.starts_with("sweep: planning: ") && line.contains("of 22500 decks"), "{line:?}");
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    assert!(!out.exists(), "an interrupted plan wrote the directory");
}
