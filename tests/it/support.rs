//! What the integration tests share: the `sweep` binary and its output, the one check that names
//! a test skipped when LIGGGHTS is missing, the sweep files and engines the tests run (the fake
//! executor, the stand-in, fake LIGGGHTS scripts, the quick scene), and readers of a sweep
//! directory (results.csv, the joblog, the manifest, claims).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use demsweep::store::{self, DesignRecord};
use demsweep::sweep::Scrambling;

// ---- the binary ----

/// The path of the `sweep` binary under test.
pub const SWEEP: &str = env!("CARGO_BIN_EXE_sweep");

/// A command running the `sweep` binary under test.
pub fn sweep_bin() -> Command {
    Command::new(SWEEP)
}

/// `sweep ARGS` run to its end, with no standard input.
pub fn sweep(args: &[&str]) -> Output {
    sweep_bin().args(args).stdin(Stdio::null()).output().unwrap()
}

/// `sweep ARGS` in `cwd`, which must succeed.
pub fn ok(cwd: &Path, args: &[&str]) -> Output {
    let o = sweep_bin().args(args).current_dir(cwd).stdin(Stdio::null()).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{args:?}\nstderr: {}", text(&o.stderr));
    o
}

/// `sweep points FILE ARGS`.
pub fn points(file: &Path, args: &[&str]) -> Output {
    Command::new(SWEEP).arg("points").arg(file).args(args).output().expect("run sweep")
}

/// `cmd` run to its end, with no standard input.
pub fn output(cmd: &mut Command) -> Output {
    cmd.stdin(Stdio::null()).output().unwrap()
}

/// Start `sweep ARGS DIR` twice at once; both must succeed.
pub fn run_two_at_once(args: &[&str], dir: &Path) {
    let spawn =
        || sweep_bin().args(args).arg(dir).stdin(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let (a, b) = (spawn(), spawn());
    for c in [a, b] {
        let o = c.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
}

/// The standard error of a finished command, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Bytes (an output stream) as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A path as a command-line argument.
pub fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// `rel` in the repository (a sweep file of `sweeps/`, a template, a script).
pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// How long a test waits for an event (a child gone, a check started, a claim renewed, sweep
/// ended by a signal) before it gives up: a guard against hanging, not a bound on how fast the
/// event is; they happen in milliseconds on an idle machine, and within it on one loaded by
/// LIGGGHTS runs.
pub const GUARD: Duration = Duration::from_secs(60);

/// Wait up to `limit` for `cond` to hold, looking every 50 ms; fail naming `what` if it never does.
pub fn wait_until(what: &str, limit: Duration, mut cond: impl FnMut() -> bool) {
    let t = Instant::now();
    while !cond() {
        assert!(t.elapsed() < limit, "gave up waiting for {what}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

// ---- what a test needs from the machine ----

/// Whether a missing dependency fails the test instead of skipping it: under CI (`CI` set and
/// not `0`/`false`, as CI services set it) or with `DEMSWEEP_REQUIRE_ENGINE=1` (which `.ci/run`
/// sets). There a skip would count as a pass of a check that never ran.
pub fn skips_fail() -> bool {
    let on = |name: &str| std::env::var(name).is_ok_and(|v| !v.is_empty() && v != "0" && v != "false");
    on("CI") || on("DEMSWEEP_REQUIRE_ENGINE")
}

/// The one way a test skips: `needs` is missing (what, and how to get it). Says SKIPPED and
/// returns, or fails the test when [`skips_fail`].
pub fn skip(test: &str, needs: &str) {
    if skips_fail() {
        panic!("{test}: {needs}; under CI a missing dependency fails the test instead of skipping it");
    }
    eprintln!("SKIPPED {test}: {needs}");
}

/// Whether LIGGGHTS (`liggghts` on PATH) is missing; when it is, says which test is skipped
/// and why (or fails it, see [`skip`]).
pub fn liggghts_missing(test: &str) -> bool {
    let found = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join("liggghts").is_file()));
    if !found {
        skip(test, "needs LIGGGHTS, and `liggghts` is not on PATH (bash scripts/setup.sh installs it)");
    }
    !found
}

/// The one place where a test says it needs LIGGGHTS: `support::require_liggghts!("test name");`
/// as its first line. Without LIGGGHTS the test says it is skipped and returns at once (under
/// CI it fails instead).
macro_rules! require_liggghts {
    ($test:expr) => {
        if $crate::support::liggghts_missing($test) {
            return;
        }
    };
}
pub(crate) use require_liggghts;

/// `sweep run --json` of one point; returns (exit code, parsed JSON, stderr).
pub fn run_point(sweep: &Path, set: &str) -> (i32, serde_json::Value, String) {
    let out = sweep_bin().args(["run"]).arg(sweep).args(["--set", set, "--json"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let json = serde_json::from_slice(&out.stdout).unwrap_or(serde_json::Value::Null);
    (out.status.code().unwrap_or(-1), json, stderr)
}

// ---- sweep files ----

/// Write `text` to `path` and return the path (a sweep file for a test).
pub fn write_file(path: &Path, text: &str) -> PathBuf {
    std::fs::write(path, text).unwrap();
    path.to_path_buf()
}

/// The quick demo scene (D 1.5 mm) with gap and blade speed swept, named `name`, then `tables`.
pub fn quick_scene(name: &str, tables: &str) -> String {
    format!(
        r#"name = "{name}"
[parameters]
gap         = {{ lo = 2.0, hi = 3.0, unit = "mm" }}
blade_speed = {{ lo = 1.2, hi = 1.6, unit = "m/s" }}
diameter    = {{ value = 1.5, unit = "mm" }}
{tables}"#
    )
}

/// The local run of the first `points` LDS points of the sweep file text `sweep`, in a kept
/// temporary directory (`<root>/local`): what runs elsewhere are compared with.
pub fn local_lds(sweep: &str, points: usize) -> PathBuf {
    let root = tempfile::Builder::new().prefix("local-reference-").tempdir().unwrap().keep();
    write_file(&root.join("s.toml"), sweep);
    let n = points.to_string();
    let o = output(
        sweep_bin()
            .args(["lds", "s.toml", "--step", &n, "--max", &n, "--jobs", "2", "-q", "--out", "local"])
            .current_dir(&root),
    );
    assert!(matches!(o.status.code(), Some(0 | 1)), "the local run: {}", text(&o.stderr));
    root.join("local")
}

/// The quick scene's first three LDS points, each from rest and short ([`SHORT_FROM_REST`]),
/// run once per test binary: the local run that resumed, interrupted and cluster runs of the
/// same points are compared with, digit for digit (from rest: a warm start's digits depend on which neighbour had finished
/// first, tests/it/warm.rs). The sweep's name does not enter a point's hash.
pub fn quick_reference() -> &'static Path {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| local_lds(&quick_scene("reference", SHORT_FROM_REST), QUICK_REFERENCE_POINTS))
}

/// The edits (from, to) that turn `sweeps/quick.toml` into a gated sweep: its layout, and the
/// conveyor's own settings it writes (a warm start, a fixed precision) left out, as the gated
/// layout refuses them.
pub const QUICK_AS_GATED: &[(&str, &str)] = &[
    ("layout = \"conveyor\"", "layout = \"gated\""),
    ("warm_start = true", "# warm_start = true"),
    ("precision = \"fixed\"", "# precision = \"fixed\""),
];

/// Points in [`quick_reference`].
pub const QUICK_REFERENCE_POINTS: usize = 3;
/// The `[scene]` table of a sweep whose every point starts from rest and runs short: a 0.05 s
/// warm-up and a 25 % SE, so the least window (8 blocks) ends it, about a quarter of a default
/// point's CPU. For the tests of what happens to runs (resume, cluster arrays), which compare
/// results digit for digit, not with a physical value; the quick scene's physics is checked at
/// its defaults elsewhere.
pub const SHORT_FROM_REST: &str = "[scene]\nwarm_start = false\nwarmup_s = 0.05\nmfr_rel_se = 0.25\n";

/// The quick scene in `dir/NAME.toml`, its deck from `template` when given, `extra_run` in `[run]`.
pub fn quick_sweep(dir: &Path, name: &str, extra_run: &str, template: Option<&Path>) -> PathBuf {
    let template = template.map_or(String::new(), |t| format!("template = {:?}\n", t));
    let tables = format!(
        r#"[scene]
{template}
[run]
{extra_run}
"#
    );
    write_file(&dir.join(format!("{name}.toml")), &quick_scene(name, &tables))
}

/// A caller's working directory `cwd` inside a temporary directory (returned to keep it).
pub fn cwd() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path().join("cwd");
    std::fs::create_dir(&cwd).unwrap();
    (tmp, cwd)
}

/// A sweep `s` with `parameters` as written and an LDS design of 4 points (2 per space), in
/// `dir/s.toml`.
pub fn lds_sweep(dir: &Path, parameters: &str) -> PathBuf {
    let body = format!("name = \"s\"\n[parameters]\n{parameters}\n[design.lds]\nstep = 2\nmax = 4\n");
    write_file(&dir.join("s.toml"), &body)
}

/// The quick scene with an LDS design of 4 points (2 per space), in `dir/NAME.toml`.
pub fn quick_lds_sweep(dir: &Path, name: &str, extra_run: &str) -> PathBuf {
    let tables = format!(
        r#"[design.lds]
step = 2
max = 4
[run]
{extra_run}
"#
    );
    write_file(&dir.join(format!("{name}.toml")), &quick_scene(name, &tables))
}

/// A 2-D sweep of `max` LDS points (`step` per space) on `engine`, unscreened, with `run` extra
/// `[run]` keys, in `dir/NAME.toml`.
pub fn engine_sweep(dir: &Path, name: &str, engine: &str, max: usize, step: usize, run: &str) -> PathBuf {
    let text = format!(
        r#"name = "{name}"
[parameters]
gap         = {{ lo = 2.0, hi = 4.0, unit = "mm" }}
blade_speed = {{ lo = 1.2, hi = 1.6, unit = "m/s" }}
diameter    = {{ value = 1.5, unit = "mm" }}
[design.lds]
step = {step}
max = {max}
[run]
engine = "{engine}"
screen = false
{run}
"#
    );
    write_file(&dir.join(format!("{name}.toml")), &text)
}

/// A sweep of `max` points in one space on the stand-in engine.
pub fn standin(dir: &Path, max: usize) -> PathBuf {
    engine_sweep(dir, "standin", "stand-in", max, max, "")
}

/// A finished stand-in sweep of `max` points in one space, in `root/d`: the directory and its
/// points' hashes in manifest order.
pub fn finished_standin(root: &Path, max: usize) -> (PathBuf, Vec<String>) {
    let toml = standin(root, max);
    let d = root.join("d");
    let o = sweep(&["lds", p(&toml), "--out", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let h = hashes(&d);
    (d, h)
}

/// An executable shell script `dir/name` holding `text`.
pub fn script(dir: &Path, name: &str, text: &str) -> PathBuf {
    use std::os::unix::fs::PermissionsExt;
    let path = dir.join(name);
    std::fs::write(&path, format!("#!/bin/sh\n{text}\n")).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    path
}

/// A fake engine `dir/liggghts`: prints a LIGGGHTS version for `-h`, otherwise runs `body` in
/// the run directory.
pub fn fake_engine(dir: &Path, body: &str) -> PathBuf {
    script(
        dir,
        "liggghts",
        &format!(
            "for a in \"$@\"; do [ \"$a\" = -h ] && {{ echo 'LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, fake)'; exit 0; }}; done\n{body}"
        ),
    )
}

/// A sweep of 20 points whose every run fails (an engine that exits 1), run once, in `root/d`.
pub fn failed_sweep(root: &Path) -> PathBuf {
    let engine = fake_engine(root, "sleep 0.05\necho 'no dump' >&2\nexit 1");
    let toml = engine_sweep(root, "failing", p(&engine), 20, 20, "");
    let d = root.join("d");
    let o = sweep(&["lds", p(&toml), "--out", p(&d), "-q", "--jobs", "2"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let n = attempt_counts(&d);
    assert_eq!(n.len(), 20);
    assert!(n.values().all(|&a| a == 1), "{n:?}");
    d
}

// ---- the fake executor ----

/// A millisecond, the unit of the fake executor's run times.
pub const MS: Duration = Duration::from_millis(1);

/// An LDS design of `max` points, `step` per space, seed 7.
pub fn lds(max: usize, step: usize) -> DesignRecord {
    DesignRecord::Lds { step, max, scrambling: Scrambling::Random, seed: 7 }
}

/// A sweep for the fake executor: gap and blade speed swept, `run` as the [run] table, written
/// to `dir/t.toml`.
pub fn fake_sweep(dir: &Path, run: &str) -> demsweep::sweep::Sweep {
    let text = format!(
        "name = \"t\"\n[parameters]\ngap = {{ lo = 2.0, hi = 4.0 }}\nblade_speed = {{ lo = 1.2, hi = 1.6 }}\n[run]\n{run}\n"
    );
    let path = dir.join("t.toml");
    std::fs::write(&path, &text).unwrap();
    demsweep::sweep::Sweep::load(&path).unwrap()
}

/// Pool options for tests: `jobs` slots, no progress output, failed runs not retried.
pub fn quiet(jobs: usize) -> demsweep::run::RunOptions {
    demsweep::run::RunOptions {
        jobs,
        progress: demsweep::run::progress::ProgressMode::Quiet,
        retry_failed: false,
        force: false,
    }
}

/// `run::start` of `design` in `out` with `jobs` slots, quietly, every space run to its end
/// (`RunAll`) and nothing cancelling it.
pub fn run_all<E: demsweep::run::pool::Executor>(
    sweep: &demsweep::sweep::Sweep,
    design: DesignRecord,
    out: &Path,
    exec: &E,
    jobs: usize,
) -> demsweep::error::Result<demsweep::run::Summary> {
    let dir = demsweep::run::SweepDir::new(sweep, design, out);
    let cancel = demsweep::sys::process::CancelToken::new();
    demsweep::run::start(dir, exec, &quiet(jobs), &mut demsweep::run::RunAll, &cancel)
}

// ---- reading a sweep directory ----

/// results.csv as (hash, status, failure, mfr) per point index.
pub fn results(dir: &Path) -> Vec<(String, String, String, String)> {
    let mut r = csv::Reader::from_path(dir.join("results.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let cols = [col("hash"), col("status"), col("failure"), col("mfr")];
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            let f = |i: usize| rec[cols[i]].to_string();
            (f(0), f(1), f(2), f(3))
        })
        .collect()
}

/// A CSV file by header name: one map per row.
pub fn csv_rows(path: &Path) -> Vec<BTreeMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let h = r.headers().unwrap().clone();
    r.records()
        .map(|rec| h.iter().zip(rec.unwrap().iter()).map(|(k, v)| (k.into(), v.into())).collect())
        .collect()
}

/// results.csv by header name: one map per row.
pub fn result_rows(dir: &Path) -> Vec<BTreeMap<String, String>> {
    csv_rows(&dir.join("results.csv"))
}

/// The hashes of the points of `d`, in manifest order.
pub fn hashes(d: &Path) -> Vec<String> {
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("manifest.json")).unwrap()).unwrap();
    m["points"].as_array().unwrap().iter().map(|p| p["hash"].as_str().unwrap().to_string()).collect()
}

/// The joblog's attempts, each by its (lower-cased) column names.
pub fn joblog(d: &Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(d.join("joblog.tsv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split('\t').map(|h| h.to_lowercase()).collect();
    lines.map(|l| header.iter().cloned().zip(l.split('\t').map(String::from)).collect()).collect()
}

/// Joblog lines by hash: the statuses of its attempts in order.
pub fn attempts(dir: &Path) -> BTreeMap<String, Vec<String>> {
    let mut m: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for l in store::read_joblog(dir).unwrap() {
        m.entry(l.hash).or_default().push(l.status);
    }
    m
}

/// Attempts per hash in the joblog.
pub fn attempt_counts(d: &Path) -> BTreeMap<String, usize> {
    let mut n = BTreeMap::new();
    let text = std::fs::read_to_string(d.join("joblog.tsv")).unwrap();
    let mut lines = text.lines();
    let column = lines.next().unwrap().split('\t').position(|h| h.eq_ignore_ascii_case("hash")).unwrap();
    for line in lines {
        let hash = line.split('\t').nth(column).unwrap().to_string();
        *n.entry(hash).or_insert(0) += 1;
    }
    n
}

/// `done` lines per hash in the joblog.
pub fn done_per_hash(dir: &Path) -> HashMap<String, usize> {
    let mut m = HashMap::new();
    for l in store::read_joblog(dir).unwrap() {
        if l.status == "done" {
            *m.entry(l.hash).or_default() += 1;
        }
    }
    m
}

/// The joblog's seq column is 1..n, each once.
pub fn assert_unique_seq(dir: &Path) {
    let lines = store::read_joblog(dir).unwrap();
    let seqs: BTreeSet<u64> = lines.iter().map(|l| l.seq).collect();
    assert_eq!(seqs.len(), lines.len(), "repeated joblog seq: {lines:?}");
    assert_eq!(seqs, (1..=lines.len() as u64).collect(), "seq is not 1..n");
}

/// Three points of a fake sweep (`lds(3, 3)`), each run once to success, one at a time, in
/// `root/out`: the directory and its manifest.
pub fn fake_finished(root: &Path) -> (PathBuf, demsweep::store::Manifest) {
    let s = fake_sweep(root, "");
    let out = root.join("out");
    let exec = demsweep::run::fake::FakeExecutor::new(|_, _| demsweep::run::fake::Behaviour::Succeed(MS));
    run_all(&s, lds(3, 3), &out, &exec, 1).unwrap();
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    (out, manifest)
}

/// The pid of a process that has ended and been reaped: what a killed run's claim names.
pub fn dead_pid() -> u32 {
    let mut c = Command::new("true").spawn().unwrap();
    let pid = c.id();
    c.wait().unwrap();
    pid
}

/// A point's MFR measured over pile seeds (`sweep run FILE --set … --seeds 5`): their mean and
/// standard deviation. A regression test's reference: one run is one seed's draw from it.
pub struct Measured {
    pub mean: f64,
    pub sd: f64,
}

/// MFR within 4 noise of the seeds' mean, the noise the larger of their SD and the run's own SE
/// `se` (0 where the scene reports none): a run that far off happens about once in 16,000 by
/// chance, and a change that moves MFR further is caught (the former bound, MFR under random
/// close packing's 0.64, let through any MFR up to 5–60 times the measured ones).
pub fn assert_measured(mfr: f64, se: f64, m: &Measured, what: &str) {
    let noise = m.sd.max(se);
    assert!(
        (mfr - m.mean).abs() <= 4.0 * noise,
        "{what}: MFR {mfr} ± {se} against {} ± {} (SD over the seeds measured)",
        m.mean,
        m.sd
    );
}

/// A claim in `runs/<hash>/claim` as another process wrote it.
pub fn plant_claim(d: &Path, hash: &str, host: &str, pid: u32, claimed_at: f64, lease: Option<(f64, f64)>) {
    let mut c = serde_json::json!({
        "host": host, "pid": pid, "start_ticks": 1, "session": format!("{pid}-0-1"), "claimed_at": claimed_at,
    });
    if let Some((lease_s, renewed_at)) = lease {
        c["lease_s"] = lease_s.into();
        c["renewed_at"] = renewed_at.into();
    }
    let dir = d.join("runs").join(hash);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("claim"), c.to_string()).unwrap();
}

/// The time now, in seconds since the Unix epoch (a claim's clock).
pub fn now() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs_f64()
}

/// Every path under `dir` with its contents (directories with none), to show that nothing changed.
pub fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                out.insert(p.clone(), Vec::new());
                stack.push(p);
            } else {
                out.insert(p.clone(), std::fs::read(&p).unwrap_or_default());
            }
        }
    }
    out
}

/// No NaN or infinity anywhere in `text` (a CSV, a JSON, a verdict).
pub fn assert_all_finite(what: &str, text: &str) {
    let lower = text.to_lowercase();
    for bad in ["nan", "inf"] {
        assert!(
            !lower
                .split(|c: char| !c.is_ascii_alphanumeric())
                .any(|w| w == bad || w == "-inf" || w == "infinity"),
            "{what} holds {bad}:\n{text}"
        );
    }
}

// ---- file systems ----

/// A mounted tmpfs, unmounted on drop.
pub struct Mount(PathBuf);

impl Mount {
    pub fn tmpfs(at: &Path, options: &str) -> Result<Mount, String> {
        std::fs::create_dir_all(at).unwrap();
        let o = Command::new("mount")
            .args(["-t", "tmpfs", "-o", options, "tmpfs"])
            .arg(at)
            .output()
            .map_err(|e| format!("cannot run mount: {e}"))?;
        if !o.status.success() {
            return Err(format!("mount -t tmpfs -o {options} failed: {}", stderr(&o).trim()));
        }
        Ok(Mount(at.to_path_buf()))
    }

    pub fn remount(&self, options: &str) {
        let o =
            Command::new("mount").args(["-o", &format!("remount,{options}")]).arg(&self.0).output().unwrap();
        assert!(o.status.success(), "remount: {}", stderr(&o));
    }
}

impl Drop for Mount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(&self.0).status();
    }
}

/// Compare `got` with `tests/snapshots/NAME`; with `UPDATE_SNAPSHOTS=1` write it instead.
pub fn compare_snapshot(name: &str, got: &str) {
    let path = repo("tests/snapshots").join(name);
    if std::env::var_os("UPDATE_SNAPSHOTS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, got).unwrap();
        return;
    }
    let want = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(got, want, "{name} changed (UPDATE_SNAPSHOTS=1 rewrites it)");
}
