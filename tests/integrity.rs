//! Nothing wrong ever becomes a number: what is read back from a sweep directory (result.json,
//! manifest.json) or handed over by an engine (its dump) is accepted only when it belongs where
//! it lies and is physically possible. Each test is named after what it guards; the sweeps run
//! on the stand-in engine, or on small fake engines (shell scripts) where the defect needs one.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn sweep(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sweep")).args(args).stdin(Stdio::null()).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// A 2-D sweep of `max` LDS points in one space (`step` per space) on `engine`.
fn write_sweep(dir: &Path, name: &str, engine: &str, max: usize, step: usize) -> PathBuf {
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
"#
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// A finished stand-in sweep of 8 points in two spaces, in `root/d`.
fn finished_standin(root: &Path) -> PathBuf {
    let toml = write_sweep(root, "integrity", "stand-in", 8, 4);
    let d = root.join("d");
    let o = sweep(&["lds", p(&toml), "--out", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    d
}

/// results.csv by header name: one map per row.
fn results(dir: &Path) -> Vec<BTreeMap<String, String>> {
    let mut r = csv::Reader::from_path(dir.join("results.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    r.records()
        .map(|rec| h.iter().zip(rec.unwrap().iter()).map(|(k, v)| (k.into(), v.into())).collect())
        .collect()
}

fn result_path(d: &Path, hash: &str) -> PathBuf {
    d.join("runs").join(hash).join("result.json")
}

/// Set one field of a run's result.json to `value` (JSON text), as an edit by hand would.
fn edit_result(d: &Path, hash: &str, field: &str, value: &str) {
    let path = result_path(d, hash);
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    v[field] = serde_json::from_str(value).unwrap();
    std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

/// An executable shell script at `dir/name` that prints a LIGGGHTS version for `-h` and
/// otherwise runs `body` in the run directory.
fn fake_engine(dir: &Path, name: &str, body: &str) -> PathBuf {
    use std::os::unix::fs::PermissionsExt;
    let path = dir.join(name);
    let text = format!(
        "#!/bin/sh\nfor a in \"$@\"; do [ \"$a\" = -h ] && {{ echo 'LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, fake)'; exit 0; }}; done\n{body}\n"
    );
    std::fs::write(&path, text).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    path
}

/// No NaN or infinity anywhere in `text` (a CSV, a JSON, a verdict).
fn assert_all_finite(what: &str, text: &str) {
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

#[test]
fn a_result_copied_from_another_run_directory_is_run_again_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished_standin(tmp.path());
    let before = results(&d);
    let (h0, h1) = (before[0]["hash"].clone(), before[1]["hash"].clone());
    assert_ne!(before[0]["mfr"], before[1]["mfr"]);
    std::fs::copy(result_path(&d, &h1), result_path(&d, &h0)).unwrap();

    // The report does not pair point 0 with point 1's MFR, and says which file is wrong.
    let o = sweep(&["report", p(&d)]);
    let err = stderr(&o);
    assert!(err.contains(&format!("runs/{h0}/result.json")), "{err}");
    let after = results(&d);
    assert_ne!(after[0]["mfr"], before[1]["mfr"], "point 0 took point 1's MFR");
    assert_ne!(after[0]["status"], "done");

    // Resume runs it again, and it comes back with its own number.
    let o = sweep(&["resume", p(&d), "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains(&format!("runs/{h0}/result.json")) && err.contains("runs again"), "{err}");
    let after = results(&d);
    assert_eq!(after[0]["mfr"], before[0]["mfr"]);
    assert_eq!(after[0]["status"], "done");
    assert_eq!(after[1]["mfr"], before[1]["mfr"]);
}

#[test]
fn a_result_with_parameters_of_another_point_is_not_accepted() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished_standin(tmp.path());
    let before = results(&d);
    let h0 = before[0]["hash"].clone();
    let gap: f64 = before[0]["gap"].parse().unwrap();
    edit_result(&d, &h0, "parameters", &format!(r#"{{"gap": {}, "blade_speed": 1.3}}"#, gap + 0.5));
    let o = sweep(&["resume", p(&d), "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains(&format!("runs/{h0}/result.json")) && err.contains("parameters"), "{err}");
    assert_eq!(results(&d)[0]["mfr"], before[0]["mfr"]);
}

#[test]
fn an_impossible_mfr_in_a_result_is_run_again_not_accepted_as_done() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished_standin(tmp.path());
    let before = results(&d);
    let (h0, h1, h2) = (before[0]["hash"].clone(), before[1]["hash"].clone(), before[2]["hash"].clone());
    edit_result(&d, &h0, "mfr", "-0.5");
    edit_result(&d, &h1, "mfr", "0.9");
    edit_result(&d, &h2, "mass_flow_is_fine", "true");
    let o = sweep(&["resume", p(&d), "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    for h in [&h0, &h1] {
        assert!(err.contains(&format!("runs/{h}/result.json")), "{err}");
    }
    assert!(err.contains("0.74"), "the warning states the bound: {err}");
    let after = results(&d);
    assert_eq!(after[0]["mfr"], before[0]["mfr"]);
    assert_eq!(after[1]["mfr"], before[1]["mfr"]);
    // An extra field is no defect: that point is not run again.
    assert!(!err.contains(&format!("runs/{h2}/result.json")), "{err}");
}

#[test]
fn an_impossible_vx_in_a_result_is_run_again() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished_standin(tmp.path());
    let before = results(&d);
    let h0 = before[0]["hash"].clone();
    let mut vx = vec!["null".to_string(); 12];
    vx[0] = "1e300".into();
    edit_result(&d, &h0, "vx", &format!("[{}]", vx.join(",")));
    let o = sweep(&["resume", p(&d), "-q"]);
    let err = stderr(&o);
    assert!(err.contains(&format!("runs/{h0}/result.json")) && err.contains("v_x"), "{err}");
    assert_eq!(results(&d)[0]["vx_1"], before[0]["vx_1"]);
}

#[test]
fn an_overflowing_mfr_leaves_no_nan_or_inf_in_convergence_or_the_verdict() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished_standin(tmp.path());
    let h3 = results(&d)[3]["hash"].clone();
    edit_result(&d, &h3, "mfr", "1e308");
    let o = sweep(&["report", p(&d), "--json"]);
    let err = stderr(&o);
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains(&format!("runs/{h3}/result.json")), "{err}");
    assert_all_finite("stdout", &String::from_utf8_lossy(&o.stdout));
    assert_all_finite("stderr", &err);
    for f in ["convergence.csv", "summary.json", "results.csv"] {
        assert_all_finite(f, &std::fs::read_to_string(d.join(f)).unwrap());
    }
}

#[test]
fn a_space_where_every_mfr_is_zero_has_finite_statistics() {
    let tmp = tempfile::tempdir().unwrap();
    // Gaps below the stand-in's jam ratio: every point gives MFR 0, so std is 0.
    let toml = tmp.path().join("zero.toml");
    std::fs::write(
        &toml,
        r#"name = "zero"
[parameters]
gap         = { lo = 1.0, hi = 1.5, unit = "mm" }
blade_speed = { lo = 1.2, hi = 1.6, unit = "m/s" }
diameter    = { value = 2.0, unit = "mm" }
[design.lds]
step = 4
max = 8
[run]
engine = "stand-in"
screen = false
"#,
    )
    .unwrap();
    let d = tmp.path().join("d");
    let o = sweep(&["lds", p(&toml), "--out", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = sweep(&["report", p(&d), "--json"]);
    let err = stderr(&o);
    assert!(results(&d).iter().all(|r| r["mfr"].parse::<f64>().unwrap() == 0.0));
    assert_all_finite("stdout", &String::from_utf8_lossy(&o.stdout));
    assert_all_finite("stderr", &err);
    for f in ["convergence.csv", "summary.json"] {
        assert_all_finite(f, &std::fs::read_to_string(d.join(f)).unwrap());
    }
}

/// Swap the hashes of points `i` and `j` in manifest.json.
fn swap_hashes(d: &Path, i: usize, j: usize) {
    let path = d.join("manifest.json");
    let mut m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let points = m["points"].as_array_mut().unwrap();
    let hi = points[i]["hash"].clone();
    points[i]["hash"] = points[j]["hash"].clone();
    points[j]["hash"] = hi;
    std::fs::write(&path, serde_json::to_string_pretty(&m).unwrap()).unwrap();
}

#[test]
fn swapped_hashes_in_the_manifest_are_named_as_such_by_report_and_resume() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished_standin(tmp.path());
    let before = std::fs::read(d.join("results.csv")).unwrap();
    swap_hashes(&d, 0, 1);
    for args in [vec!["report", p(&d)], vec!["resume", p(&d), "-q"]] {
        let o = sweep(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("manifest.json") && err.contains("swapped"), "{args:?}: {err}");
        assert!(err.contains("points 0 and 1"), "{args:?}: {err}");
        assert!(!err.contains("--force") && !err.contains("templates changed"), "{args:?}: {err}");
        // Nothing was rewritten from the wrong pairing.
        assert_eq!(std::fs::read(d.join("results.csv")).unwrap(), before, "{args:?}");
    }
}

/// Attempts per hash in the joblog.
fn attempts(d: &Path) -> BTreeMap<String, usize> {
    let mut n = BTreeMap::new();
    for line in std::fs::read_to_string(d.join("joblog.tsv")).unwrap().lines().skip(1) {
        let hash = line.split('\t').next_back().unwrap().to_string();
        *n.entry(hash).or_insert(0) += 1;
    }
    n
}

/// A sweep of 20 points whose every run fails (an engine that exits 1), run once.
fn failed_sweep(root: &Path) -> PathBuf {
    let engine = fake_engine(root, "liggghts", "sleep 0.05\necho 'no dump' >&2\nexit 1");
    let toml = write_sweep(root, "failing", p(&engine), 20, 20);
    let d = root.join("d");
    let o = sweep(&["lds", p(&toml), "--out", p(&d), "-q", "--jobs", "2"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let n = attempts(&d);
    assert_eq!(n.len(), 20);
    assert!(n.values().all(|&a| a == 1), "{n:?}");
    d
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
    let n = attempts(&d);
    assert!(n.values().all(|&a| a == 2), "attempts per point: {n:?}");
    // A later invocation is a new retry: once more each.
    let o = sweep(&["resume", p(&d), "--retry-failed", "-q"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(attempts(&d).values().all(|&a| a == 3), "{:?}", attempts(&d));
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
    let n = attempts(&d);
    assert!(n.values().all(|&a| a == 2), "attempts per point: {n:?}");
}
