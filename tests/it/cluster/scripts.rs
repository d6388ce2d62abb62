//! What `sweep submit` writes and refuses, as text: the `#PBS`/`#SBATCH` scripts against their
//! snapshots, a planned directory submitted and laid out again, bad input, and the tasks of a
//! `--retry-failed` submission.

use std::path::Path;

use demsweep::store::{ClaimAttempt, Store};

use super::{sweep_text, POINTS};
use crate::support::{
    self, attempt_counts, failed_sweep, output, p, results, stderr, sweep, sweep_bin, text,
};

/// A manifest of `n` points with made-up hashes: enough for rendering.
fn synthetic(dir: &Path, n: usize) {
    let points: Vec<serde_json::Value> = (0..n)
        .map(|i| serde_json::json!({ "index": i, "values": [2.0 + i as f64 * 0.1, 1.4], "hash": format!("{i:064x}") }))
        .collect();
    let manifest = serde_json::json!({
        "format": 1, "tool": "demsweep test", "name": "snap", "parameters": ["gap", "blade_speed"],
        "design": { "kind": "lds", "step": n, "max": n, "scrambling": "random", "seed": 14 },
        "spaces": [{ "label": format!("lds {n}"), "points": (0..n).collect::<Vec<_>>() }],
        "points": points, "identity": {}
    });
    std::fs::create_dir_all(dir.join("runs")).unwrap();
    std::fs::write(dir.join("manifest.json"), manifest.to_string()).unwrap();
    std::fs::write(dir.join("sweep.toml"), sweep_text()).unwrap();
}

#[test]
fn scripts_match_their_snapshots() {
    for (scheduler, extra) in [
        ("slurm", &["--partition", "short", "--account", "dem01"][..]),
        ("pbs", &["--queue", "shortq", "--account", "dem01"][..]),
        ("torque", &["--queue", "shortq"][..]),
    ] {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("snap");
        synthetic(&dir, 10);
        let o = output(
            support::sweep_bin()
                .args([
                    "submit",
                    dir.to_str().unwrap(),
                    "--scheduler",
                    scheduler,
                    "--tasks",
                    "4",
                    "--dry-run",
                ])
                .args(["--jobs-per-task", "2", "--ranks", "2", "--walltime", "02:00:00"])
                .args(extra),
        );
        assert!(o.status.success(), "{scheduler}: {}", text(&o.stderr));
        let ext = if scheduler == "slurm" { "slurm" } else { "pbs" };
        for kind in ["array", "report"] {
            let got = std::fs::read_to_string(dir.join(format!("cluster/{kind}.{ext}"))).unwrap();
            let got = got
                .replace(dir.to_str().unwrap(), "DIR")
                .replace(support::SWEEP, "SWEEP")
                .replace(env!("CARGO_PKG_VERSION"), "VERSION");
            support::compare_snapshot(&format!("{scheduler}-{kind}.txt"), &got);
        }
    }
}

/// `--plan` writes a directory with every point pending and runs nothing; `submit` takes it; a
/// second `--tasks` with another value lays the points out again when no task holds a run, and
/// keeps the layout (saying so) while one does.
#[test]
fn a_planned_directory_is_submitted_and_another_tasks_says_what_it_does() {
    let root = tempfile::tempdir().unwrap();
    std::fs::write(root.path().join("s.toml"), sweep_text()).unwrap();
    let o = output(
        sweep_bin()
            .args(["lds", "s.toml", "--step", "3", "--max", "3", "--out", "planned", "--plan"])
            .current_dir(root.path()),
    );
    let err = text(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("planned 3 points") && err.contains("nothing run") && err.contains("sweep submit"),
        "{err}"
    );
    let dir = root.path().join("planned");
    let rows = results(&dir);
    assert_eq!(rows.len(), POINTS);
    assert!(rows.iter().all(|r| r.1 == "pending" && r.3.is_empty()), "{rows:?}");
    // Nothing ran: no run directory, no joblog attempt, no LIGGGHTS log anywhere.
    let runs: Vec<_> = std::fs::read_dir(dir.join("runs")).map(|d| d.flatten().collect()).unwrap_or_default();
    assert!(runs.is_empty(), "{runs:?}");
    assert!(!root.path().join("log.liggghts").exists());
    let attempts = std::fs::read_to_string(dir.join("joblog.tsv")).unwrap_or_default();
    assert!(attempts.lines().count() <= 1, "{attempts}");

    let submit = |tasks: &str| {
        let o = output(sweep_bin().args([
            "submit",
            dir.to_str().unwrap(),
            "--scheduler",
            "slurm",
            "--tasks",
            tasks,
            "--dry-run",
        ]));
        assert!(o.status.success(), "--tasks {tasks}: {}", text(&o.stderr));
        text(&o.stderr)
    };
    let per_task = || -> u64 {
        let l: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("cluster/layout.json")).unwrap()).unwrap();
        l["per_task"].as_u64().unwrap()
    };
    let msg = submit("3");
    assert!(msg.contains("array tasks 0-2 (1 per task)") && msg.contains("afterany"), "{msg}");
    assert_eq!(per_task(), 1);
    let msg = submit("1");
    assert!(
        msg.contains("--tasks 1: no task holds a run") && msg.contains("3 per task instead of 1"),
        "{msg}"
    );
    assert_eq!(per_task(), 3);
    // A live task holds a run: the layout stays.
    let (manifest, _) = Store::read_manifest(&dir).unwrap();
    let held = Store::open(&dir).claim(&manifest.points[0].hash).unwrap();
    assert!(matches!(held, ClaimAttempt::Claimed(..)));
    let msg = submit("3");
    assert!(
        msg.contains("--tasks 3: keeping the layout of 3 points per task") && msg.contains("hold 1 runs"),
        "{msg}"
    );
    assert_eq!(per_task(), 3);
    drop(held);
}

#[test]
fn bad_submit_input_is_refused_and_writes_nothing() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("snap");
    synthetic(&dir, 4);
    let d = dir.to_str().unwrap();
    for (args, needle) in [
        (&["--scheduler", "slurm", "--dry-run"][..], "--tasks: required"),
        (&["--scheduler", "slurm", "--tasks", "0", "--dry-run"][..], "--tasks 0"),
        (&["--scheduler", "slurm", "--tasks", "2", "--walltime", "2h", "--dry-run"][..], "--walltime \"2h\""),
        (&["--scheduler", "slurm", "--tasks", "2", "--walltime", "0", "--dry-run"][..], "--walltime \"0\""),
        (
            &["--scheduler", "slurm", "--tasks", "2", "--walltime", "99:99:99", "--dry-run"][..],
            "--walltime \"99:99:99\"",
        ),
        (&["--scheduler", "pbs", "--tasks", "2", "--queue", "a b", "--dry-run"][..], "--queue \"a b\""),
        (&["--scheduler", "pbs", "--tasks", "2", "--ranks", "0", "--dry-run"][..], "--ranks 0"),
    ] {
        let o = output(support::sweep_bin().arg("submit").arg(d).args(args));
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle) && err.lines().count() == 1, "{args:?}: {err}");
        assert!(!dir.join("cluster").exists(), "{args:?} wrote something");
    }
    let o = output(support::sweep_bin().args([
        "submit",
        root.path().to_str().unwrap(),
        "--scheduler",
        "slurm",
        "--tasks",
        "1",
    ]));
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("not a sweep directory"), "{}", text(&o.stderr));
}

#[test]
fn retry_failed_in_the_tasks_of_one_submission_runs_each_failed_point_once_more() {
    let tmp = tempfile::tempdir().unwrap();
    let d = failed_sweep(tmp.path());
    let o =
        sweep(&["submit", p(&d), "--scheduler", "slurm", "--tasks", "2", "--only", "failed", "--dry-run"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let array = std::fs::read_dir(d.join("cluster"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.file_stem().is_some_and(|s| s == "array"))
        .expect("submit wrote the array script");
    let script = std::fs::read_to_string(array).unwrap();
    let per_task = script
        .split("--per-task ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .expect("the script gives --per-task")
        .to_string();
    assert!(script.contains("--retry-failed"), "{script}");
    // The array's tasks one after the other, each helping with the other's points.
    for task in ["0", "1"] {
        let o = sweep(&["work", p(&d), "--task", task, "--per-task", &per_task, "--retry-failed", "-q"]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    }
    let n = attempt_counts(&d);
    assert!(n.values().all(|&a| a == 2), "attempts per point: {n:?}");
}
