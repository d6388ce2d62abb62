//! Arrays and chains on the local Slurm of `scripts/slurm_local.sh`: a task cancelled mid-run
//! and re-submitted, an LDS chain and an adaptive chain that stop at the verdict (the adaptive
//! one also run by hand, with no scheduler), and `sweep extend` in two Slurm jobs.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use demsweep::store::Store;

use super::{assert_finished_once, assert_same_as_reference, attempts, fresh_copy};
use crate::support::{self, output, p, repo, results, sweep_bin, text, wait_until};

/// Bring the local Slurm up; `None` (with the reason printed) when Slurm is not installed.
fn local_slurm() -> Option<String> {
    let have = |c: &str| {
        Command::new("sh").args(["-c", &format!("command -v {c}")]).output().unwrap().status.success()
    };
    if !(have("slurmctld") && have("slurmd") && have("munged") && have("sbatch")) {
        support::skip(
            "a real-Slurm test",
            "Slurm is not installed; `bash scripts/slurm_local.sh up` (as root) installs and starts a \
             single-node Slurm, and this test then runs",
        );
        return None;
    }
    let o = output(Command::new("bash").arg(repo("scripts/slurm_local.sh")).arg("up"));
    assert!(o.status.success(), "slurm_local.sh up: {}{}", text(&o.stdout), text(&o.stderr));
    let conf = text(&o.stdout).lines().last().unwrap().trim_start_matches("export SLURM_CONF=").to_string();
    Some(conf)
}

/// Jobs of `job` (an array id) still known to squeue.
fn squeue(conf: &str, job: &str) -> Vec<(String, String)> {
    let o =
        output(Command::new("squeue").env("SLURM_CONF", conf).args(["-h", "-r", "-j", job, "-o", "%i %T"]));
    text(&o.stdout)
        .lines()
        .filter_map(|l| l.split_once(' ').map(|(a, b)| (a.to_string(), b.to_string())))
        .collect()
}

fn submit(conf: &str, dir: &Path, extra: &[&str]) -> (String, String) {
    let o = output(
        support::sweep_bin()
            .env("SLURM_CONF", conf)
            .args(["submit", dir.to_str().unwrap(), "--scheduler", "slurm", "--walltime", "00:20:00"])
            .args(extra),
    );
    assert!(o.status.success(), "submit: {}", text(&o.stderr));
    (text(&o.stdout).trim().to_string(), text(&o.stderr))
}

/// A 3-task Slurm array, one task cancelled in mid-run; the re-submission names only that
/// task, and the directory then equals a local run, with no run finished twice.
///
/// `--no-steal`, so that the other tasks leave the cancelled task's point alone (by default
/// they would finish it: the PBS test checks that).
#[test]
fn slurm_array_with_a_cancelled_task_completes_on_resubmission() {
    let Some(conf) = local_slurm() else { return };
    let (_root, dir) = fresh_copy("cluster-slurm-");
    let (job, msg) = submit(&conf, &dir, &["--tasks", "3", "--no-steal"]);
    assert!(msg.contains("array tasks 0-2 (1 per task)"), "{msg}");
    let script = std::fs::read_to_string(dir.join("cluster/array.slurm")).unwrap();
    assert!(script.contains("#SBATCH --array=0-2\n"), "{script}");

    // Cancel task 1 as soon as its LIGGGHTS run has started (its log is there): an event, not a
    // clock, so a busy machine cannot let the short point finish first.
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap();
    let hash1 = manifest["points"][1]["hash"].as_str().unwrap().to_string();
    let claim1 = dir.join("runs").join(&hash1).join("claim");
    let log1 = dir.join("runs").join(&hash1).join(demsweep::engine::LOG);
    wait_until("task 1's LIGGGHTS to start", Duration::from_secs(120), || claim1.exists() && log1.exists());
    let o = output(Command::new("scancel").env("SLURM_CONF", &conf).arg(format!("{job}_1")));
    assert!(o.status.success(), "scancel: {}", text(&o.stderr));
    wait_until("the array to end", Duration::from_secs(600), || squeue(&conf, &job).is_empty());

    // Task 1's point was cut off; the others finished.
    let first = results(&dir);
    assert_eq!(first[1].1, "pending", "the cancelled task's point: {first:?}");
    assert!(first.iter().enumerate().all(|(i, r)| i == 1 || r.1 != "pending"), "{first:?}");
    assert!(!claim1.exists(), "the cancelled task released its claim");

    // Re-submit: only index 1.
    let (job2, msg) = submit(&conf, &dir, &[]);
    assert!(msg.contains("1 points of the batch lds 3 as array tasks 1 "), "{msg}");
    let script = std::fs::read_to_string(dir.join("cluster/array.slurm")).unwrap();
    assert!(script.contains("#SBATCH --array=1\n"), "{script}");
    wait_until("the re-submitted array to end", Duration::from_secs(600), || squeue(&conf, &job2).is_empty());
    assert_same_as_reference(&dir);
    let a = &attempts(&dir)[&hash1];
    assert_eq!(a.iter().map(|x| x.1.as_str()).collect::<Vec<_>>(), ["cancelled", "done"], "{a:?}");

    // The report job ran after each array (afterany); `sweep report` itself lands with the
    // report work.
    let logs: Vec<String> = std::fs::read_dir(dir.join("cluster/logs"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    wait_until("the report jobs", Duration::from_secs(60), || {
        std::fs::read_dir(dir.join("cluster/logs"))
            .unwrap()
            .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().starts_with("report-"))
            .count()
            == 2
    });
    assert!(logs.iter().any(|l| l.starts_with(&format!("{job}_"))), "{logs:?}");
    let subs = std::fs::read_to_string(dir.join("cluster/submissions.tsv")).unwrap();
    assert_eq!(subs.lines().count(), 2, "{subs}");

    // Nothing left: a third submission says so and submits nothing.
    let o = output(support::sweep_bin().env("SLURM_CONF", &conf).args([
        "submit",
        dir.to_str().unwrap(),
        "--scheduler",
        "slurm",
    ]));
    assert!(o.status.success() && text(&o.stdout).is_empty(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("nothing to submit"), "{}", text(&o.stderr));
}

/// An LDS sweep planned with `--plan` and submitted batch by batch on the local Slurm: each
/// batch of `step` points is one array, the job after it judges the statistics, and the chain
/// stops at the verdict, well before `max`. A stand-in sweep whose rule holds at the second
/// space: 8 of its 20 points run.
#[test]
fn an_lds_chain_on_slurm_stops_at_the_verdict() {
    let Some(conf) = local_slurm() else { return };
    let root = tempfile::Builder::new().prefix("cluster-chain-").tempdir().unwrap();
    let sweep = "name = \"chain\"\n[parameters]\ngap = { lo = 2.0, hi = 4.0 }\nblade_speed = { lo = 1.2, hi = 1.6 }\n\
                 [design.lds]\nstep = 4\nmax = 20\n[convergence]\ntolerance = 2.0\nfloor = 2.0\nhold = 1\n\
                 [run]\nengine = \"stand-in\"\n";
    std::fs::write(root.path().join("s.toml"), sweep).unwrap();
    let o =
        output(sweep_bin().args(["lds", "s.toml", "--out", "planned", "--plan"]).current_dir(root.path()));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let dir = root.path().join("planned");
    let (_job, msg) = submit(&conf, &dir, &["--tasks", "2"]);
    assert!(msg.contains("4 points of the batch lds 4 as array tasks 0-1 (2 per task)"), "{msg}");
    assert!(msg.contains("then the next batch unless the rule has held"), "{msg}");

    // The chain: batch lds 4, its judge submits lds 8, whose judge finds the rule held.
    wait_for_the_verdict(&dir);
    let subs = std::fs::read_to_string(dir.join("cluster/submissions.tsv")).unwrap();
    assert_eq!(subs.lines().count(), 2, "two batches submitted: {subs}");
    let rows = results(&dir);
    assert_eq!(rows.len(), 20);
    let done: Vec<usize> = rows.iter().enumerate().filter(|(_, r)| r.1 == "done").map(|(i, _)| i).collect();
    assert_eq!(done, (0..8).collect::<Vec<_>>(), "{rows:?}");
    assert!(rows[8..].iter().all(|r| r.1 == "pending"), "{rows:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["verdict"]["status"], "converged", "{summary}");
    assert_eq!(summary["verdict"]["n"], 8, "{summary}");
    // Submitting again by hand agrees: nothing to run.
    let o = output(sweep_bin().env("SLURM_CONF", &conf).args([
        "submit",
        dir.to_str().unwrap(),
        "--scheduler",
        "slurm",
    ]));
    assert!(
        o.status.success() && text(&o.stderr).contains("nothing to submit: converged"),
        "{}",
        text(&o.stderr)
    );
}

/// `sweep extend` in two Slurm jobs on one finished directory: each point extended once (the
/// jobs share the points through the directory's claims), as one local extend would.
#[test]
fn two_slurm_jobs_of_sweep_extend_extend_each_point_once() {
    support::require_liggghts!("two_slurm_jobs_of_sweep_extend_extend_each_point_once");
    let Some(conf) = local_slurm() else { return };
    let root = tempfile::Builder::new().prefix("cluster-extend-").tempdir().unwrap();
    let (dir, before, target) = crate::extend::finished_copy(root.path());
    let jobs: Vec<String> = (0..2)
        .map(|k| {
            let wrap = format!("{} extend {} --se {target} --jobs 1", support::SWEEP, p(&dir));
            let out = root.path().join(format!("extend-{k}.out"));
            let o = output(Command::new("sbatch").env("SLURM_CONF", &conf).args([
                "--parsable",
                "--time",
                "00:10:00",
                "--output",
                p(&out),
                "--wrap",
                &wrap,
            ]));
            assert!(o.status.success(), "sbatch: {}", text(&o.stderr));
            text(&o.stdout).trim().to_string()
        })
        .collect();
    wait_until("both extend jobs to leave the queue", Duration::from_secs(600), || {
        jobs.iter().all(|j| squeue(&conf, j).is_empty())
    });
    for k in 0..2 {
        let said = std::fs::read_to_string(root.path().join(format!("extend-{k}.out"))).unwrap_or_default();
        assert!(said.contains("extend to SE") && said.contains("next: sweep report"), "job {k}: {said}");
    }
    crate::extend::assert_extended_once(&dir, &before, target);
}

/// An adaptive stand-in sweep whose rule holds at its second batch (`adapt 12`): its first
/// batch of 8 points, then batches of 4.
const ADAPT: &str = "name = \"achain\"\n[parameters]\ngap = { lo = 2.0, hi = 4.0 }\nblade_speed = { lo = 1.2, hi = 1.6 }\n\
                     [design.adapt]\nfirst = 8\nbatch = 4\nmax = 24\n[convergence]\ntolerance = 2.0\nfloor = 2.0\nhold = 1\n\
                     [run]\nengine = \"stand-in\"\n";

/// `sweep adapt --plan` of [`ADAPT`] into `root/planned`, and a local `sweep adapt` of it into
/// `root/local`, to compare the chain with.
fn adapt_pair(root: &Path) -> (PathBuf, PathBuf) {
    std::fs::write(root.join("s.toml"), ADAPT).unwrap();
    for args in [&["--out", "planned", "--plan"][..], &["--out", "local", "-q"][..]] {
        let o = output(sweep_bin().args(["adapt", "s.toml"]).args(args).current_dir(root));
        assert!(o.status.success(), "{args:?}: {}", text(&o.stderr));
    }
    (root.join("planned"), root.join("local"))
}

/// The chain has planned and run the batches a local `sweep adapt` plans, and stopped where it
/// stopped.
fn assert_same_as_local_adapt(dir: &Path, local: &Path) {
    let (got, want) = (Store::read_manifest(dir).unwrap().0, Store::read_manifest(local).unwrap().0);
    assert_eq!(got.points, want.points, "the chain planned other points than a local adapt");
    assert_eq!(got.spaces, want.spaces);
    assert_eq!(results(dir), results(local));
    assert_eq!(results(dir).len(), 12);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["verdict"]["status"], "converged", "{summary}");
    assert_eq!(summary["verdict"]["n"], 12, "{summary}");
    assert_finished_once(dir);
}

/// Array indices of a rendered Slurm script (`#SBATCH --array=4-5`).
fn slurm_indices(script: &str) -> Vec<usize> {
    let spec = script.lines().find_map(|l| l.strip_prefix("#SBATCH --array=")).expect("an array line");
    spec.split(',')
        .flat_map(|r| match r.split_once('-') {
            Some((a, b)) => (a.parse().unwrap()..=b.parse().unwrap()).collect::<Vec<usize>>(),
            None => vec![r.parse().unwrap()],
        })
        .collect()
}

/// The adaptive chain by hand, with no scheduler: each `submit --dry-run` renders one batch's
/// array, its tasks run as Slurm would run them (the script, under `SLURM_ARRAY_TASK_ID`), and
/// the next `submit` (the job after the batch) plans the next batch. The batches are those of a
/// local `sweep adapt`, and the chain ends at its verdict.
#[test]
fn an_adaptive_chain_run_by_hand_plans_the_batches_of_a_local_adapt() {
    let root = tempfile::Builder::new().prefix("cluster-adapt-").tempdir().unwrap();
    let (dir, local) = adapt_pair(root.path());
    let d = dir.to_str().unwrap();
    let mut arrays = Vec::new();
    let mut first = true;
    loop {
        let tasks: &[&str] = if first { &["--tasks", "2"] } else { &[] };
        let o = output(sweep_bin().args(["submit", d, "--scheduler", "slurm", "--dry-run"]).args(tasks));
        assert!(o.status.success(), "{}", text(&o.stderr));
        if text(&o.stderr).contains("nothing to submit") {
            assert!(text(&o.stderr).contains("nothing to submit: converged"), "{}", text(&o.stderr));
            break;
        }
        first = false;
        let script = std::fs::read_to_string(dir.join("cluster/array.slurm")).unwrap();
        let indices = slurm_indices(&script);
        for &i in &indices {
            let o = output(
                Command::new("bash")
                    .arg(dir.join("cluster/array.slurm"))
                    .env("SLURM_ARRAY_TASK_ID", i.to_string()),
            );
            assert!(o.status.success(), "task {i}: {}", text(&o.stderr));
        }
        let report = std::fs::read_to_string(dir.join("cluster/report.slurm")).unwrap();
        assert!(report.contains(" submit ") && report.contains("--after-batch"), "{report}");
        arrays.push(indices);
        assert!(arrays.len() <= 6, "the chain does not stop: {arrays:?}");
    }
    // The first batch (8 points at 2 per task: --tasks 2 of a batch of 4) on 4 tasks, the
    // second on the next 2.
    assert_eq!(arrays, [vec![0, 1, 2, 3], vec![4, 5]]);
    let o = output(sweep_bin().args(["report", d]));
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_same_as_local_adapt(&dir, &local);
    let batches = std::fs::read_to_string(dir.join("batches.csv")).unwrap();
    assert_eq!(batches, std::fs::read_to_string(local.join("batches.csv")).unwrap());
}

/// The same adaptive chain on the local Slurm: each batch one array, the job after it planning
/// and submitting the next, until the rule holds.
#[test]
fn an_adaptive_chain_on_slurm_plans_each_batch_and_stops_at_the_verdict() {
    let Some(conf) = local_slurm() else { return };
    let root = tempfile::Builder::new().prefix("cluster-adapt-slurm-").tempdir().unwrap();
    let (dir, local) = adapt_pair(root.path());
    let (_job, msg) = submit(&conf, &dir, &["--tasks", "2"]);
    assert!(msg.contains("8 points of the batch adapt 8 as array tasks 0-3 (2 per task)"), "{msg}");
    wait_for_the_verdict(&dir);
    assert!(
        judge_logs(&dir).iter().any(|l| l.contains("planned the next batch, points 8-11 (adapt 12")),
        "{:?}",
        judge_logs(&dir)
    );
    let subs = std::fs::read_to_string(dir.join("cluster/submissions.tsv")).unwrap();
    assert_eq!(subs.lines().count(), 2, "two batches submitted: {subs}");
    assert_same_as_local_adapt(&dir, &local);
}

/// The logs of a chain's judge jobs (`cluster/logs/report-*`).
fn judge_logs(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir.join("cluster/logs"))
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("report-"))
        .map(|e| std::fs::read_to_string(e.path()).unwrap_or_default())
        .collect()
}

/// Wait until a judge of the chain in `dir` finds the rule held and submits nothing more.
fn wait_for_the_verdict(dir: &Path) {
    wait_until("the chain to stop at the verdict", Duration::from_secs(600), || {
        judge_logs(dir).iter().any(|l| l.contains("nothing to submit: converged"))
    });
}
