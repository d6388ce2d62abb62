//! `sweep extend`: a finished point's run continued from the restart it wrote, on LIGGGHTS. The
//! continued run is the run a tighter target would have made from the start — the same blocks
//! up to the join and for the blocks after it that the insertion's fresh random state leaves
//! alone —, it meets the new target, its result keeps every part's time, and what a user gets
//! wrong is refused with nothing changed.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::support::{self, csv_rows, ok, output, quick_scene, stderr, sweep_bin, write_file};

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
        // The new target met, or the window cap reached.
        let stop = after[i]["steady_state"]["stop"].as_str().unwrap();
        assert!(
            se(&after[i]) <= target * (1.0 + 1e-9) || stop == "cap",
            "#{i}: SE {} > {target}, stop {stop}",
            se(&after[i])
        );
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
    // Again at the same target: nothing to do, nothing changes.
    let o = ok(cwd, &["extend", "loose", "--se", &se_flag]);
    let said = support::text(&o.stdout);
    assert!(said.contains("0 extended") || said.contains("not extendable"), "{said}");
    assert_eq!(results(&cwd.join("loose")), after);
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
