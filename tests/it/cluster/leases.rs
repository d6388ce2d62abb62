//! Claim leases across (played) hosts: a claim renewed by its heartbeat stands past its lease
//! and is taken over once the heartbeat stops, in one process and with real `sweep work`
//! processes, one of them frozen as a lost node is.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::sync::OnceLock;
use std::time::Duration;

use demsweep::store::{ClaimAttempt, ClaimInfo, Store};

use super::{attempts, fresh_copy_of};
use crate::support::{self, results, text, wait_until};

/// The same scene, one point, for the lease test, which watches a claim for twice its lease
/// while the run is still going: the knobs of the previous defaults keep a run ~2× longer than
/// the fast preset's (BENCHMARKS.md "Fidelity").
fn lease_sweep_text() -> String {
    support::quick_scene(
        "cluster-lease",
        "[scene]\nrayleigh_fraction = 0.2\nmesh_cells_across = 6\nskin_diameters = 0.25\nwarm_start = false\n",
    )
}

/// The lease test's local run (one point of [`lease_sweep_text`]).
fn lease_reference() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| support::local_lds(&lease_sweep_text(), 1))
}

fn claim_of(dir: &Path, hash: &str) -> Option<ClaimInfo> {
    serde_json::from_str(&std::fs::read_to_string(dir.join("runs").join(hash).join("claim")).ok()?).ok()
}

/// A claim of another host stands while its heartbeat runs, past its lease, and is taken over
/// once the heartbeat stops and the lease has run out. Judged on the claim's own times, which
/// the rule reads: not on how long the test slept.
#[test]
fn a_remote_claim_stands_while_renewed_and_is_taken_over_after_its_lease() {
    let dir = tempfile::tempdir().unwrap();
    let lease = Duration::from_millis(1200);
    let a = Store::open(dir.path()).with_host("node-a").with_lease(lease);
    let b = Store::open(dir.path()).with_host("node-b").with_lease(lease);
    let ClaimAttempt::Claimed(_held, None) = a.claim("h").unwrap() else { panic!("first claim") };
    let claimed_at = claim_of(dir.path(), "h").unwrap().claimed_at;
    let beat = a.heartbeat();
    // Renewed past three leases after the claim, refused to node-b at every look: the claim's
    // own times are the event waited on; the deadline only guards against a heartbeat that
    // stopped. Four renewals seen, so the claim stood on renewals, not on its first lease.
    let mut renewals = std::collections::BTreeSet::new();
    wait_until("node-a's renewals past three leases", support::GUARD, || {
        let renewed = claim_of(dir.path(), "h").and_then(|c| c.renewed_at).unwrap();
        renewals.insert(renewed.to_bits());
        match b.claim("h").unwrap() {
            ClaimAttempt::Busy(c) => assert_eq!(c.host, "node-a"),
            ClaimAttempt::Claimed(..) => panic!("a claim renewed at {renewed} taken over"),
        }
        renewals.len() >= 4 && renewed - claimed_at > 3.0 * lease.as_secs_f64()
    });
    drop(beat);
    let last = claim_of(dir.path(), "h").unwrap().renewed_at.unwrap();
    let mut taken = None;
    wait_until("node-b's takeover", support::GUARD, || match b.claim("h").unwrap() {
        ClaimAttempt::Busy(_) => false,
        ClaimAttempt::Claimed(_, stale) => {
            taken = stale;
            true
        }
    });
    // Taken over once a lease had passed since the last renewal, and not before: the rule read
    // on the two claims' own records (a loaded machine only makes the gap longer), not on how
    // long the test waited.
    let mine = claim_of(dir.path(), "h").unwrap();
    assert_eq!(mine.host, "node-b");
    assert!(
        mine.claimed_at - last >= lease.as_secs_f64(),
        "taken {} s after the last renewal",
        mine.claimed_at - last
    );
    let taken = taken.expect("node-b's claim displaced node-a's");
    assert_eq!((taken.host.as_str(), taken.renewed_at), ("node-a", Some(last)));
}

/// Process groups of the children of `pid`, and `pid` itself.
fn tree(pid: u32) -> Vec<i32> {
    let mut out = vec![pid as i32];
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(p) = e.file_name().to_string_lossy().parse::<i32>() else { continue };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{p}/stat")) else { continue };
        let Some(close) = stat.rfind(')') else { continue };
        let f: Vec<&str> = stat[close + 1..].split_whitespace().collect();
        if f[1] == pid.to_string() {
            out.push(-f[2].parse::<i32>().unwrap());
        }
    }
    out
}

/// Stop the process tree of `pid` at a moment it does not hold the sweep directory's lock; its
/// pids. A lost node's locks lapse with its lease on the file server, while a stopped process
/// here keeps its `flock`: frozen inside a claim's renewal (under the lock, a few ms in every
/// lease/4 on a loaded machine), it would block every other process, which no lost node does.
fn freeze_outside_the_lock(pid: u32, dir: &Path) -> Vec<i32> {
    let lock = std::fs::OpenOptions::new().write(true).open(dir.join(".lock")).unwrap();
    loop {
        let frozen = tree(pid);
        signal(&frozen, libc::SIGSTOP);
        // A stop is delivered, not done, when kill(2) returns: look once every thread has stopped.
        wait_until("node-a's threads to stop", support::GUARD, || frozen.iter().all(|&p| all_stopped(p)));
        // SAFETY: flock on a descriptor we own; a lock taken is given back at once.
        let free =
            unsafe { libc::flock(std::os::fd::AsRawFd::as_raw_fd(&lock), libc::LOCK_EX | libc::LOCK_NB) }
                == 0;
        if free {
            unsafe { libc::flock(std::os::fd::AsRawFd::as_raw_fd(&lock), libc::LOCK_UN) };
            return frozen;
        }
        signal(&frozen, libc::SIGCONT);
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Whether every thread of `pid` is stopped (state `T`), or the process is gone.
fn all_stopped(pid: i32) -> bool {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else { return true };
    tasks.flatten().all(|t| {
        let stat = std::fs::read_to_string(t.path().join("stat")).unwrap_or_default();
        // The state follows the parenthesised command name, which may itself hold spaces.
        stat.rsplit_once(") ").is_none_or(|(_, rest)| rest.starts_with('T') || rest.starts_with('t'))
    })
}

fn signal(targets: &[i32], sig: i32) {
    for &t in targets {
        // SAFETY: kill(2) on a pid or a process group (negative).
        unsafe { libc::kill(t, sig) };
    }
}

/// Real `sweep work` processes playing two hosts: node-b waits on node-a's live run past the
/// lease; when node-a freezes (a lost node: no heartbeat), node-b takes the run over after the
/// lease and completes it with the local run's MFR.
#[test]
fn a_frozen_task_is_taken_over_after_its_lease_and_a_live_one_is_not() {
    let (_root, dir) = fresh_copy_of(lease_reference(), "cluster-lease-");
    let want = results(lease_reference());
    let k = want.iter().position(|r| r.1 == "done").expect("a successful point");
    let hash = want[k].0.clone();
    let task = k.to_string();
    let work = |host: &str| {
        support::sweep_bin()
            .args(["work", dir.to_str().unwrap(), "--task", &task, "--per-task", "1", "--jobs", "1"])
            .args(["--lease", "3", "--no-steal", "-q", "--host", host])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let mut a = work("node-a");
    // Every wait is on an event (a claim, its renewals, the takeover, node-b's end); the
    // deadlines only guard against hanging.
    wait_until("node-a's claim", support::GUARD, || claim_of(&dir, &hash).is_some());
    let mut b = work("node-b");
    // Live: renewed past twice the lease after node-b started, the claim is still node-a's.
    let b_started = support::now();
    wait_until("node-a's renewals past two leases", support::GUARD, || {
        let Some(c) = claim_of(&dir, &hash) else { return false };
        assert_eq!(c.host, "node-a", "a live claim was taken over");
        c.renewed_at.is_some_and(|r| r - b_started > 6.0)
    });
    // Frozen: node-a and its LIGGGHTS stop, as on a lost node.
    let frozen = freeze_outside_the_lock(a.id(), &dir);
    let held = claim_of(&dir, &hash).expect("node-a's claim");
    let (last, lease) = (held.renewed_at.expect("a renewed claim"), held.lease_s.expect("a lease"));
    assert_eq!(lease, 3.0, "the lease of --lease 3");
    let mut took = 0.0;
    wait_until("node-b's takeover", support::GUARD, || {
        let b = claim_of(&dir, &hash).filter(|c| c.host == "node-b");
        took = b.as_ref().map_or(0.0, |c| c.claimed_at);
        b.is_some()
    });
    // The lost node never comes back; killed now, so that no failure below leaves it stopped.
    signal(&frozen, libc::SIGKILL);
    let _ = a.wait();
    // Not before node-a's lease had passed since its last renewal: the rule read on the two
    // claims' own records (a loaded machine only makes the gap longer), not on the test's waits.
    assert!(took - last >= lease, "taken over {} s after the last renewal", took - last);
    // node-b runs the point to its end (a LIGGGHTS run of a minute or so here).
    wait_until("node-b to finish the point", Duration::from_secs(600), || b.try_wait().unwrap().is_some());
    let o = b.wait_with_output().unwrap();
    assert!(matches!(o.status.code(), Some(0 | 1)), "node-b: {}", text(&o.stderr));
    let lines = &attempts(&dir)[&hash];
    let last = lines.last().unwrap();
    assert_eq!(last.0, "node-b", "{lines:?}");
    assert!(!lines.iter().any(|(h, s)| h == "node-a" && (s == "done" || s == "failed")), "{lines:?}");
    assert_eq!(results(&dir)[k], want[k]);
}
