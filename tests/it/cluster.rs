//! `sweep submit` and `sweep work` for real: a Slurm array on the local Slurm of
//! `scripts/slurm_local.sh` (one task cancelled mid-run, then re-submitted), the PBS task body
//! under the environment PBS gives a task, the `#PBS`/`#SBATCH` headers as text, and claim
//! leases across (played) hosts with real processes.
//!
//! Every sweep result is compared with a local run of the same sweep directory (same hashes,
//! same MFR to the last digit: LIGGGHTS is deterministic), never with copied figures. The Slurm
//! tests skip, saying so, when Slurm is not installed, and fail instead under CI (`.ci/run`
//! installs and starts it with `bash scripts/slurm_local.sh up`, as root).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::Duration;

use demsweep::store::{ClaimAttempt, ClaimInfo, Store};

use crate::support::{
    self, attempt_counts, failed_sweep, output, p, repo, results, stderr, sweep, sweep_bin, text, wait_until,
};

/// Three points of the quick scene (D = 1.5 mm, gap and blade speed swept), each from rest: the
/// points of [`support::quick_reference`], whose local run the cluster runs are compared with.
fn sweep_text() -> String {
    support::quick_scene("cluster-test", support::SHORT_FROM_REST)
}
const POINTS: usize = support::QUICK_REFERENCE_POINTS;

/// The same scene, one point, for the lease test, which watches a claim for twice its lease
/// while the run is still going: the knobs of the previous defaults keep a run ~2× longer than
/// the fast preset's (BENCHMARKS.md "Fidelity").
fn lease_sweep_text() -> String {
    support::quick_scene(
        "cluster-lease",
        "[scene]\nrayleigh_fraction = 0.2\nmesh_cells_across = 6\nskin_diameters = 0.25\nwarm_start = false\n",
    )
}

/// The local run every cluster run is compared with: [`sweep_text`]'s points, made once per test
/// binary and shared with the resume tests.
fn reference() -> &'static Path {
    support::quick_reference()
}

/// The lease test's local run (one point of [`lease_sweep_text`]).
fn lease_reference() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| support::local_lds(&lease_sweep_text(), 1))
}

/// A sweep directory of the reference's sweep with nothing run: what a user takes to a cluster
/// (its manifest and resolved sweep file).
fn fresh_copy(name: &str) -> (tempfile::TempDir, PathBuf) {
    fresh_copy_of(reference(), name)
}

/// A sweep directory of the sweep of the local run `local`, with nothing run.
fn fresh_copy_of(local: &Path, name: &str) -> (tempfile::TempDir, PathBuf) {
    let root = tempfile::Builder::new().prefix(name).tempdir().unwrap();
    let dir = root.path().join("sweep");
    std::fs::create_dir_all(dir.join("runs")).unwrap();
    for f in ["manifest.json", "sweep.toml"] {
        std::fs::copy(local.join(f), dir.join(f)).unwrap();
    }
    (root, dir)
}

/// Joblog statuses by hash, in order, with the host of each line.
fn attempts(dir: &Path) -> BTreeMap<String, Vec<(String, String)>> {
    let mut m: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    for l in demsweep::store::read_joblog(dir).unwrap() {
        m.entry(l.hash).or_default().push((l.host, l.status));
    }
    m
}

/// Every point finished once: at most one `done` or `failed` line per hash, none after it.
fn assert_finished_once(dir: &Path) {
    for (hash, a) in attempts(dir) {
        let finals = a.iter().filter(|(_, s)| s == "done" || s == "failed").count();
        assert!(finals <= 1, "run {hash} finished {finals} times: {a:?}");
    }
}

fn assert_same_as_reference(dir: &Path) {
    let (got, want) = (results(dir), results(reference()));
    assert_eq!(got.len(), POINTS);
    assert_eq!(got, want, "cluster results differ from the local run");
    assert!(want.iter().any(|r| r.1 == "done"), "the reference has no successful run: {want:?}");
    assert_finished_once(dir);
}

// ---------------------------------------------------------------------------------------------
// Slurm

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

// ---------------------------------------------------------------------------------------------
// PBS

/// Run a rendered PBS script as PBS would run array index `index`: its environment, a node
/// file, and another working directory to start from.
fn pbs_task(script: &Path, index: usize, torque: bool, workdir: &Path) -> Child {
    let nodefile = workdir.join(format!("nodes.{index}"));
    std::fs::write(&nodefile, "node01\nnode01\n").unwrap();
    let mut c = Command::new("bash");
    c.arg(script)
        .env(if torque { "PBS_ARRAYID" } else { "PBS_ARRAY_INDEX" }, index.to_string())
        .env("PBS_O_WORKDIR", workdir)
        .env("PBS_NODEFILE", &nodefile)
        .env("PBS_JOBID", format!("77[{index}].pbs"))
        .current_dir("/")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c.spawn().unwrap()
}

/// The PBS Pro task body under PBS's environment, run for indices 0 and 2 at once, leaves the
/// same directory as a local run: index 1 never ran (a lost task), and they did its point
/// once their own were done. Then Torque's form for the failures (PBS_ARRAYID).
#[test]
fn pbs_task_bodies_under_the_pbs_environment_equal_a_local_run() {
    let (root, dir) = fresh_copy("cluster-pbs-");
    let o = output(support::sweep_bin().args([
        "submit",
        dir.to_str().unwrap(),
        "--scheduler",
        "pbs",
        "--tasks",
        "3",
        "--dry-run",
    ]));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let script = PathBuf::from(text(&o.stdout).trim());
    let body = std::fs::read_to_string(&script).unwrap();
    assert!(body.contains("#PBS -J 0-2\n"), "{body}");
    let tasks: Vec<(usize, Child)> =
        [0, 2].into_iter().map(|i| (i, pbs_task(&script, i, false, root.path()))).collect();
    for (i, t) in tasks {
        let o = t.wait_with_output().unwrap();
        let out = text(&o.stdout);
        assert!(matches!(o.status.code(), Some(0 | 1)), "task {i}: {out}{}", text(&o.stderr));
        assert!(out.starts_with(&format!("task {i} on ")) && out.contains("(node01 )"), "{out}");
    }
    assert_same_as_reference(&dir);

    let o = output(support::sweep_bin().args([
        "submit",
        dir.to_str().unwrap(),
        "--scheduler",
        "torque",
        "--dry-run",
        "--only",
        "missing,failed",
    ]));
    assert!(o.status.success(), "{}", text(&o.stderr));
    // With every point done, only a failed one (if the sweep has one) is left to submit.
    let failed: Vec<usize> =
        results(reference()).iter().enumerate().filter(|(_, r)| r.1 == "failed").map(|(i, _)| i).collect();
    if failed.is_empty() {
        assert!(text(&o.stderr).contains("nothing to submit"), "{}", text(&o.stderr));
        return;
    }
    let script = PathBuf::from(text(&o.stdout).trim());
    let body = std::fs::read_to_string(&script).unwrap();
    let want = failed.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(",");
    assert!(body.contains(&format!("#PBS -t {want}\n")) && body.contains("--retry-failed"), "{body}");
}

// ---------------------------------------------------------------------------------------------
// Headers as text

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

// ---------------------------------------------------------------------------------------------
// Leases

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
    // Renewed past three leases after the claim, refused to node-b at every look.
    let mut renewals = std::collections::BTreeSet::new();
    loop {
        let renewed = claim_of(dir.path(), "h").and_then(|c| c.renewed_at).unwrap();
        renewals.insert(renewed.to_bits());
        match b.claim("h").unwrap() {
            ClaimAttempt::Busy(c) => assert_eq!(c.host, "node-a"),
            ClaimAttempt::Claimed(..) => panic!("a claim renewed at {renewed} taken over"),
        }
        if renewed - claimed_at > 3.0 * lease.as_secs_f64() {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(renewals.len() >= 4, "{} renewals", renewals.len());
    drop(beat);
    let last = claim_of(dir.path(), "h").unwrap().renewed_at.unwrap();
    let taken = loop {
        match b.claim("h").unwrap() {
            ClaimAttempt::Busy(_) => std::thread::sleep(Duration::from_millis(50)),
            ClaimAttempt::Claimed(_, stale) => break stale,
        }
    };
    // Taken over once a lease had passed since the last renewal, and not before.
    let mine = claim_of(dir.path(), "h").unwrap();
    assert_eq!(mine.host, "node-b");
    assert!(
        mine.claimed_at - last >= lease.as_secs_f64(),
        "taken {} s after the last renewal",
        mine.claimed_at - last
    );
    let taken = taken.unwrap();
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
        wait_until("node-a's threads to stop", Duration::from_secs(10), || {
            frozen.iter().all(|&p| all_stopped(p))
        });
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
    wait_until("node-a's claim", Duration::from_secs(60), || claim_of(&dir, &hash).is_some());
    let b = work("node-b");
    // Live: renewed past twice the lease after node-b started, the claim is still node-a's.
    let b_started = support::now();
    wait_until("node-a's renewals past two leases", Duration::from_secs(120), || {
        let Some(c) = claim_of(&dir, &hash) else { return false };
        assert_eq!(c.host, "node-a", "a live claim was taken over");
        c.renewed_at.is_some_and(|r| r - b_started > 6.0)
    });
    // Frozen: node-a and its LIGGGHTS stop, as on a lost node.
    let frozen = freeze_outside_the_lock(a.id(), &dir);
    let last = claim_of(&dir, &hash).and_then(|c| c.renewed_at).expect("a renewed claim");
    let mut took = 0.0;
    wait_until("node-b's takeover", Duration::from_secs(60), || {
        let b = claim_of(&dir, &hash).filter(|c| c.host == "node-b");
        took = b.as_ref().map_or(0.0, |c| c.claimed_at);
        b.is_some()
    });
    // Not before the 3 s lease had passed since node-a's last renewal.
    assert!(took - last >= 3.0, "taken over {} s after the last renewal", took - last);
    let o = b.wait_with_output().unwrap();
    signal(&frozen, libc::SIGKILL);
    let _ = a.wait();
    assert!(matches!(o.status.code(), Some(0 | 1)), "node-b: {}", text(&o.stderr));
    let lines = &attempts(&dir)[&hash];
    let last = lines.last().unwrap();
    assert_eq!(last.0, "node-b", "{lines:?}");
    assert!(!lines.iter().any(|(h, s)| h == "node-a" && (s == "done" || s == "failed")), "{lines:?}");
    assert_eq!(results(&dir)[k], want[k]);
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
