//! `sweep extend`: a finished point's run continued from the restart it wrote, on LIGGGHTS. The
//! continued run is the run a tighter target would have made from the start — the same blocks
//! up to the join and for the blocks after it that the insertion's fresh random state leaves
//! alone —, it meets the new target, its result keeps every part's time, and what a user gets
//! wrong is refused with nothing changed.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::support::{self, csv_rows, ok, output, quick_scene, stderr, sweep_bin, write_file};

/// A copy of the finished quick reference sweep ([`support::quick_reference`]: three points
/// from rest, short), in `root/sweep`, and the SE target every point must be extended to (0.6
/// of the least SE).
pub fn finished_copy(root: &Path) -> (PathBuf, Vec<Value>, f64) {
    let dir = root.join("sweep");
    let o = output(std::process::Command::new("cp").arg("-a").arg(support::quick_reference()).arg(&dir));
    assert!(o.status.success(), "cp: {}", stderr(&o));
    let before = results(&dir);
    let target = 0.6 * before.iter().map(se).fold(f64::INFINITY, f64::min);
    (dir, before, target)
}

/// Each point of `dir` (its results `before` as they were) extended once to `target`: in
/// `extension-1/` and no other.
pub fn assert_extended_once(dir: &Path, before: &[Value], target: f64) {
    for (i, r) in results(dir).iter().enumerate() {
        assert_eq!(r["extensions"], 1, "#{i}: {r}");
        assert_eq!(r["mfr_se_target"].as_f64(), Some(target), "#{i}");
        assert_ran_on(r, &before[i], i);
        let run = dir.join("runs").join(r["hash"].as_str().unwrap());
        assert!(
            run.join("extension-1/restart.end.gz").is_file() && !run.join("extension-2").exists(),
            "#{i}"
        );
    }
}

/// Two LDS points of the quick scene, short and from rest, with `scene` in `[scene]`.
fn two_points(dir: &Path, name: &str, scene: &str) -> PathBuf {
    let tables =
        format!("[scene]\nwarm_start = false\nwarmup_s = 0.05\n{scene}\n[design.lds]\nstep = 2\nmax = 2\n");
    write_file(&dir.join(format!("{name}.toml")), &quick_scene(name, &tables))
}

/// Every point's result.json in the sweep directory `dir`, by point index.
fn results(dir: &Path) -> Vec<Value> {
    csv_rows(&dir.join("results.csv"))
        .iter()
        .map(|row| {
            let path = dir.join("runs").join(&row["hash"]).join("result.json");
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap()
        })
        .collect()
}

/// The extended result `after` ran on until the deck's rule met its new target or the window's
/// cap, and its SE fell. (The deck judges the blocks' own SE; the result's is widened where the
/// blocks are correlated, docs/statistics.md, so it may end a little above the target.)
fn assert_ran_on(after: &Value, before: &Value, i: usize) {
    let stop = after["steady_state"]["stop"].as_str().unwrap();
    assert!(["target", "cap"].contains(&stop), "#{i}: stop {stop}");
    assert!(se(after) < se(before), "#{i}: SE {} after, {} before", se(after), se(before));
    assert!(blocks(after).len() > blocks(before).len(), "#{i}");
}

fn blocks(r: &Value) -> Vec<f64> {
    r["steady_state"]["block_mfr"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect()
}

fn se(r: &Value) -> f64 {
    r["mfr_se"].as_f64().unwrap()
}

#[test]
fn an_extended_run_is_the_run_a_tighter_target_makes_from_the_start() {
    support::require_liggghts!("an_extended_run_is_the_run_a_tighter_target_makes_from_the_start");
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    // Loose first: a 25 % SE, so the least window ends each run.
    two_points(cwd, "loose", "mfr_rel_se = 0.25");
    ok(cwd, &["lds", "loose.toml", "--jobs", "2", "-q", "--out", "loose"]);
    let before = results(&cwd.join("loose"));
    let target = 0.6 * before.iter().map(se).fold(f64::INFINITY, f64::min);
    // The same points run to that SE from the start (the scene's own target, no relative one).
    two_points(cwd, "tight", &format!("mfr_rel_se = 0.0\nmfr_abs_se = {target}"));
    ok(cwd, &["lds", "tight.toml", "--jobs", "2", "-q", "--out", "tight"]);
    let fresh = results(&cwd.join("tight"));
    // What an interrupted extension left is started again.
    let stale = cwd.join("loose/runs").join(before[0]["hash"].as_str().unwrap()).join("extension-1");
    std::fs::create_dir_all(&stale).unwrap();
    std::fs::write(stale.join("log.liggghts"), "half a log").unwrap();
    let se_flag = target.to_string();
    let o = ok(cwd, &["extend", "loose", "--se", &se_flag, "--jobs", "2"]);
    let said = support::text(&o.stdout);
    assert!(said.contains("2 extended"), "{said}\n{}", stderr(&o));
    let after = results(&cwd.join("loose"));
    for i in 0..2 {
        let (b, a, f) = (blocks(&before[i]), blocks(&after[i]), blocks(&fresh[i]));
        let n = b.len();
        assert!(a.len() > n, "#{i}: {} blocks after, {n} before", a.len());
        // Up to the join the blocks are the earlier run's; the first two after it are the unbroken
        // run's as well (the restart carries every particle and contact; the insertion's random
        // state it does not, which shows from the third on).
        let same = (n + 2).min(f.len());
        for k in 0..same {
            assert!(
                (a[k] - f[k]).abs() <= 1e-9 * f[k].abs().max(1e-3),
                "#{i} block {k}: {} extended, {} unbroken",
                a[k],
                f[k]
            );
        }
        assert_ran_on(&after[i], &before[i], i);
        assert_eq!(after[i]["extensions"], 1, "#{i}");
        assert_eq!(after[i]["mfr_se_target"].as_f64(), Some(target), "#{i}");
        // Its time is both parts'.
        let (t0, t1) = (before[i]["cpu_time"].as_f64().unwrap(), after[i]["cpu_time"].as_f64().unwrap());
        assert!(t1 > t0, "#{i}: CPU {t0} s before, {t1} s after");
        // The part ran no warm-up: its first block is the one after the earlier run's last.
        let part = cwd.join("loose/runs").join(after[i]["hash"].as_str().unwrap()).join("extension-1");
        let log = std::fs::read_to_string(part.join("log.liggghts")).unwrap();
        let first = log.lines().find(|l| l.starts_with("demsweep: block ")).unwrap().to_string();
        assert!(first.starts_with(&format!("demsweep: block {} ", n + 1)), "#{i}: {first}");
        // The extended MFR agrees with the unbroken run's, within their SEs.
        let (ma, mf) = (after[i]["mfr"].as_f64().unwrap(), fresh[i]["mfr"].as_f64().unwrap());
        let z = (ma - mf).abs() / (se(&after[i]).powi(2) + se(&fresh[i]).powi(2)).sqrt();
        assert!(z < 4.0, "#{i}: MFR {ma} extended vs {mf} unbroken ({z:.1} SE)");
    }
    // results.csv says the new SEs.
    let rows = csv_rows(&cwd.join("loose/results.csv"));
    for (row, r) in rows.iter().zip(&after) {
        assert_eq!(row["mfr_se"].parse::<f64>().unwrap(), se(r));
    }
    // Again at the same target, now the sweep's recorded precision and so the default: nothing
    // to do (a run whose deck stopped on it is not extended again), nothing changes.
    let record = serde_json::json!({ "mfr_abs_se": target, "spread": 0.01, "points": 16 });
    std::fs::write(cwd.join("loose/precision.json"), record.to_string()).unwrap();
    let o = ok(cwd, &["extend", "loose"]);
    let said = support::text(&o.stdout);
    assert!(said.contains(&format!("extend to SE {target}: 2 done points; 0 extended")), "{said}");
    assert_eq!(results(&cwd.join("loose")), after);
    // The report says so; no run is left coarser than the recorded precision.
    ok(cwd, &["report", "loose"]);
    let page = std::fs::read_to_string(cwd.join("loose/report/report.html")).unwrap();
    assert!(page.contains("2 runs were continued to a tighter SE by sweep extend"), "{page}");
    assert!(!page.contains("ran before that"), "{page}");
}

#[test]
fn two_extends_at_once_on_one_directory_extend_each_point_once() {
    support::require_liggghts!("two_extends_at_once_on_one_directory_extend_each_point_once");
    let tmp = tempfile::tempdir().unwrap();
    let (dir, before, target) = finished_copy(tmp.path());
    let se_flag = target.to_string();
    let start = || {
        sweep_bin()
            .args(["extend", support::p(&dir), "--se", &se_flag, "--jobs", "1", "-q"])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (start(), start());
    for c in [a, b] {
        let o = c.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    assert_extended_once(&dir, &before, target);
}

#[test]
fn an_interrupted_extend_leaves_every_result_whole_and_goes_on_when_run_again() {
    support::require_liggghts!("an_interrupted_extend_leaves_every_result_whole_and_goes_on_when_run_again");
    let tmp = tempfile::tempdir().unwrap();
    let (dir, before, target) = finished_copy(tmp.path());
    let se_flag = target.to_string();
    let child = sweep_bin()
        .args(["extend", support::p(&dir), "--se", &se_flag, "--jobs", "1", "-q"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // SIGINT once a part has started running.
    let started = || {
        std::fs::read_dir(dir.join("runs"))
            .unwrap()
            .flatten()
            .any(|e| e.path().join("extension-1/in.liggghts").is_file())
    };
    support::wait_until("a part to start", std::time::Duration::from_secs(60), started);
    // SAFETY: kill(2) on our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    // What stopped and the same extension to go on, said once (not a bare "error: interrupted").
    let said = format!(
        "interrupted: the points not extended keep their results; `sweep extend {} --se {se_flag}` goes on",
        support::p(&dir)
    );
    assert!(stderr(&o).contains(&said) && !stderr(&o).contains("error: interrupted"), "{}", stderr(&o));
    // Every result is whole: the earlier one, or one extended before the signal.
    for (i, r) in results(&dir).iter().enumerate() {
        if r["extensions"].is_null() {
            assert_eq!(r, &before[i], "#{i}");
        } else {
            assert_ran_on(r, &before[i], i);
        }
    }
    // Run again, it finishes the rest: each point extended once.
    ok(tmp.path(), &["extend", support::p(&dir), "--se", &se_flag, "-q"]);
    assert_extended_once(&dir, &before, target);
}

#[test]
fn extend_refuses_what_it_cannot_do_and_changes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let file = support::standin(cwd, 4);
    ok(cwd, &["lds", support::p(&file), "-q", "--out", "s"]);
    let listing = || {
        let mut v: Vec<PathBuf> = walk(&cwd.join("s"));
        v.sort();
        v
    };
    let was = listing();
    for (args, says) in [
        (vec!["extend", "s", "--se", "0"], "--se 0"),
        (vec!["extend", "s", "--se=-1"], "--se -1"),
        (vec!["extend", "s", "--se", "nan"], "--se NaN"),
        (vec!["extend", "s", "--se", "0.01"], "stand-in"),
        (vec!["extend", "nowhere"], "nowhere"),
    ] {
        let o = output(sweep_bin().args(&args).current_dir(cwd));
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says) && err.trim().lines().count() == 1, "{args:?}: {err}");
    }
    assert_eq!(listing(), was, "a refused extend changed the directory");
}

/// Every file under `dir`.
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}
