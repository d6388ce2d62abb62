//! `sweep adapt`: batches planned from the results, reproducible; resume and concurrency as
//! for `lds` (nothing lost, nothing run twice); the verdict from the emulator's statistics; the
//! command on the stand-in engine.

use crate::support as common;
use std::collections::HashMap;
use std::path::Path;
use std::process::Stdio;
use std::time::Duration;

use demsweep::analysis::convergence::Criteria;
use demsweep::run::adapt::{self, AdaptWatch};
use demsweep::run::fake::{fake_mfr, Behaviour, FakeExecutor};
use demsweep::run::{batches, SweepDir};
use demsweep::store::{self, DesignRecord, Store};
use demsweep::sweep::{ConvergenceSettings, Scrambling, Sweep};
use demsweep::sys::process::CancelToken;

const MS: Duration = Duration::from_millis(1);

fn design(first: usize, batch: usize, max: usize) -> DesignRecord {
    DesignRecord::Adapt { first, batch, max, seed: 7, repeats: 1 }
}

/// A rule that never holds (tolerance 0): the sweep runs to its max.
fn never() -> Criteria {
    Criteria::from_settings(&ConvergenceSettings { tolerance: 0.0, ..Default::default() })
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

/// `sweep adapt FILE ARGS --out OUT`, its output.
fn sweep_adapt(file: &Path, out: &Path, args: &[&str]) -> std::process::Output {
    common::sweep_bin()
        .arg("adapt")
        .arg(file)
        .args(args)
        .arg("--out")
        .arg(out)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn manifest(dir: &Path) -> store::Manifest {
    Store::read_manifest(dir).unwrap().0
}

fn run_adapt(
    s: &Sweep,
    d: DesignRecord,
    out: &Path,
    exec: &FakeExecutor,
    c: Criteria,
) -> demsweep::run::Summary {
    let mut watch = AdaptWatch::new(out, s, c);
    adapt::start(SweepDir::new(s, d, out), exec, &common::quiet(2), &mut watch, &CancelToken::new()).unwrap()
}

#[test]
fn batches_follow_the_results_and_the_same_results_give_the_same_points() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    // MFR flat but for a bump in one corner of the unit square (gap high, blade speed high):
    // the spread of MFR over the space, its std and kurtosis, are all decided there.
    let bump = |v: &[f64]| {
        let (g, b) = ((v[0] - 2.0) / 2.0, (v[1] - 1.2) / 0.4);
        0.2 + 0.3 * (-((g - 0.85).powi(2) + (b - 0.85).powi(2)) / 0.02).exp()
    };
    let run = |name: &str| {
        let out = tmp.path().join(name);
        let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS)).with_mfr(bump);
        let sum = run_adapt(&s, design(10, 5, 40), &out, &exec, never());
        assert_eq!((sum.done, sum.pending, sum.exit_code()), (40, 0, 0), "{sum:?}");
        out
    };
    let (a, b) = (run("a"), run("b"));
    let (ma, mb) = (manifest(&a), manifest(&b));
    assert_eq!(ma.points, mb.points, "the same sweep and results plan the same points");
    let labels: Vec<&str> = ma.spaces.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(labels, ["adapt 10", "adapt 15", "adapt 20", "adapt 25", "adapt 30", "adapt 35", "adapt 40"]);
    // The first batch is the scrambled Halton design `sweep lds` would start with.
    let halton = demsweep::design::halton::halton(2, 10, Scrambling::Random, 7);
    for (p, u) in ma.points.iter().zip(&halton) {
        assert_eq!(p.values, demsweep::sweep::space::scale_point(&s, u));
    }
    // The later points crowd where MFR varies: the bump's quarter of the square holds far more
    // than a quarter of them.
    let near = ma.points[10..]
        .iter()
        .filter(|p| (p.values[0] - 2.0) / 2.0 > 0.6 && (p.values[1] - 1.2) / 0.4 > 0.6)
        .count();
    assert!(near as f64 > 0.16 * 1.5 * 30.0, "{near} of 30 adaptive points near the bump");
    // batches.csv: one row per planned point after the first batch, naming its batch.
    let rows = common::csv_rows(&a.join(adapt::BATCHES));
    assert_eq!(rows.len(), 30);
    assert_eq!(rows[0]["batch"], "1");
    assert_eq!(rows[0]["index"], "10");
    assert!(rows.iter().all(|r| r["gain"].parse::<f64>().unwrap() > 0.0));
}

#[test]
fn an_interrupted_adapt_resumes_to_the_uninterrupted_design_running_nothing_twice() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let reference = tmp.path().join("reference");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run_adapt(&s, design(8, 4, 24), &reference, &exec, never());

    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(150 * MS));
    let cancel = CancelToken::new();
    let c2 = cancel.clone();
    let watched = out.clone();
    // Interrupted in the third batch, whatever the machine's speed.
    let t = std::thread::spawn(move || {
        let done =
            |d: &Path| store::read_joblog(d).map_or(0, |l| l.iter().filter(|l| l.status == "done").count());
        // A guard only: a sweep that stopped short fails the test instead of hanging it.
        common::wait_until("13 runs done", common::GUARD, || done(&watched) >= 13);
        c2.cancel();
    });
    let mut watch = AdaptWatch::new(&out, &s, never());
    let sum = adapt::start(
        SweepDir::new(&s, design(8, 4, 24), &out),
        &exec,
        &common::quiet(2),
        &mut watch,
        &cancel,
    )
    .unwrap();
    t.join().unwrap();
    assert!(sum.interrupted && sum.exit_code() == 130, "{sum:?}");
    let before = done_attempts(&out);
    assert!(!before.is_empty() && manifest(&out).points.len() < 24, "interrupted part-way: {sum:?}");

    let exec2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let mut watch = AdaptWatch::new(&out, &s, never());
    let sum2 = batches::run(&out, &exec2, &common::quiet(2), &mut watch, &CancelToken::new()).unwrap();
    assert_eq!((sum2.done, sum2.exit_code()), (24, 0), "{sum2:?}");
    for h in before.keys() {
        assert!(!exec2.attempts().contains_key(h), "finished run {h} ran again");
    }
    assert!(done_attempts(&out).values().all(|&n| n == 1));
    assert_eq!(manifest(&out).points, manifest(&reference).points);
    assert_eq!(common::results(&out), common::results(&reference));
}

#[test]
fn two_adapt_processes_on_one_directory_share_its_batches_and_run_nothing_twice() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let reference = tmp.path().join("reference");
    run_adapt(&s, design(6, 3, 18), &reference, &FakeExecutor::new(|_, _| Behaviour::Succeed(MS)), never());

    let out = tmp.path().join("out");
    let a = FakeExecutor::new(|_, _| Behaviour::Succeed(60 * MS));
    let b = FakeExecutor::new(|_, _| Behaviour::Succeed(60 * MS));
    let (sa, sb) = std::thread::scope(|sc| {
        let ha = sc.spawn(|| run_adapt(&s, design(6, 3, 18), &out, &a, never()));
        let hb = sc.spawn(|| run_adapt(&s, design(6, 3, 18), &out, &b, never()));
        (ha.join().unwrap(), hb.join().unwrap())
    });
    assert_eq!((sa.done, sb.done), (18, 18), "each sees every point done");
    let mut runs: HashMap<String, usize> = HashMap::new();
    for (h, n) in a.attempts().into_iter().chain(b.attempts()) {
        *runs.entry(h).or_default() += n;
    }
    assert_eq!(runs.len(), 18);
    assert!(runs.values().all(|&n| n == 1), "{runs:?}");
    assert!(!a.attempts().is_empty() && !b.attempts().is_empty(), "both ran a share");
    assert!(done_attempts(&out).values().all(|&n| n == 1));
    assert_eq!(manifest(&out).points, manifest(&reference).points);
    assert_eq!(manifest(&out).spaces, manifest(&reference).spaces);
}

#[test]
fn a_converged_adapt_stops_where_the_report_says_and_a_resume_runs_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let s = common::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS)).with_mfr(fake_mfr);
    let criteria = Criteria::from_settings(&ConvergenceSettings { tolerance: 0.05, ..Default::default() });
    let sum = run_adapt(&s, design(10, 4, 200), &out, &exec, criteria);
    let stopped = sum.stopped_after.clone().expect("a smooth 2-D MFR is known well before 200 runs");
    assert!(sum.done < 200, "{sum:?}");
    // The report judges the same spaces with the same emulator: the same verdict.
    let a =
        demsweep::report::analyse(&out, &criteria, &demsweep::analysis::stats::Bootstrap::default()).unwrap();
    assert_eq!(a.verdict.space.as_deref(), Some(stopped.as_str()), "{:?}", a.verdict);
    assert!(a.spaces.iter().all(|r| r.weights == "emulator"));
    // The statistics the sweep judged are kept per space, and the report's are those.
    let cache: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join(adapt::STATS_CACHE)).unwrap()).unwrap();
    let judged = cache.as_object().unwrap();
    assert_eq!(judged.len(), manifest(&out).spaces.len());
    for row in &a.spaces {
        let m = &judged[&row.label]["moments"];
        assert_eq!(m["mean"].as_f64(), row.statistics.mean, "{}", row.label);
        assert_eq!(m["kurtosis"].as_f64(), row.statistics.kurtosis, "{}", row.label);
    }
    // Without it the report computes the same numbers again.
    std::fs::remove_file(out.join(adapt::STATS_CACHE)).unwrap();
    let b =
        demsweep::report::analyse(&out, &criteria, &demsweep::analysis::stats::Bootstrap::default()).unwrap();
    for (x, y) in a.spaces.iter().zip(&b.spaces) {
        assert_eq!(x.statistics, y.statistics, "{}", x.label);
    }
    // Every statistic of the converged space is known within 5 % of its scale.
    let row = a.spaces.iter().find(|r| r.converged).unwrap();
    for ch in row.changes.as_ref().unwrap().values() {
        assert!(ch.within, "{ch:?}");
    }
    let exec2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let mut watch = AdaptWatch::new(&out, &s, criteria);
    let again = batches::run(&out, &exec2, &common::quiet(2), &mut watch, &CancelToken::new()).unwrap();
    assert_eq!(again.ran, 0);
    assert!(exec2.attempts().is_empty());
    assert_eq!(manifest(&out).points.len(), sum.points);
}

/// The thesis space on the stand-in engine.
fn standin_sweep(dir: &Path) -> std::path::PathBuf {
    common::write_file(
        &dir.join("s.toml"),
        r#"name = "s"
[parameters]
friction    = { lo = 0.1, hi = 0.3 }
diameter    = { lo = 1.0, hi = 3.0, unit = "mm" }
gap         = { lo = 1.0, hi = 5.0, unit = "mm" }
blade_speed = { lo = 1.2, hi = 1.6, unit = "m/s" }
[design.adapt]
first = 20
batch = 10
max = 50
[run]
engine = "stand-in"
"#,
    )
}

#[test]
fn the_command_runs_reports_and_resumes_on_the_stand_in() {
    let tmp = tempfile::tempdir().unwrap();
    let file = standin_sweep(tmp.path());
    let out = tmp.path().join("out");
    let o = sweep_adapt(&file, &out, &["-q", "--jobs", "2"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let m = manifest(&out);
    assert!(matches!(m.design, DesignRecord::Adapt { first: 20, batch: 10, max: 50, .. }));
    assert!(out.join("report/report.html").exists() && out.join("summary.json").exists());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["spaces"][0]["weights"], "emulator");
    let results = common::results(&out);
    assert_eq!(results.len(), m.points.len());
    // Resume of a finished directory: nothing runs, nothing planned.
    let o = common::sweep_bin().args(["resume", "-q"]).arg(&out).stdin(Stdio::null()).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert_eq!(manifest(&out).points, m.points);
    assert_eq!(common::results(&out), results);
    // The emulator answers at a setting.
    let o = common::sweep_bin()
        .args(["predict"])
        .arg(&out)
        .args(["--set", "friction=0.2,diameter=2,gap=4,blade_speed=1.4"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
}

/// One swept parameter on the stand-in, whose MFR is highest at the slowest blade: the
/// criterion keeps wanting the face the first batch already ran, and the design must still grow
/// by new points to its max (it once chose that run again, added nothing and stopped at 12).
/// Its 31 batches of one (one job slot) fold in the report's table: the first 4 and last 12.
#[test]
fn a_one_dimensional_adapt_runs_new_points_to_its_max() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("speed.toml");
    std::fs::write(
        &file,
        "name = \"speed\"\n[parameters]\nblade_speed = { lo = 1.2, hi = 1.6, unit = \"m/s\" }\n\
         [convergence]\ntolerance = 0.0001\n[run]\nengine = \"stand-in\"\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = sweep_adapt(&file, &out, &["-q", "--jobs", "1", "--max", "40"]);
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let m = manifest(&out);
    assert_eq!(m.points.len(), 40, "{err}");
    let mut speeds: Vec<f64> = m.points.iter().map(|p| p.values[0]).collect();
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    assert_eq!(speeds.len(), 40, "a setting planned twice");
    let said = format!("{}{err}", String::from_utf8_lossy(&o.stdout));
    assert!(said.contains("keeps the 40 points run"), "{said}");
    assert!(said.contains("what matters: blade_speed alone is swept: there is nothing to rank"), "{said}");
    let html = std::fs::read_to_string(out.join("report/report.html")).unwrap();
    for row in ["1 (adapt 10)", "4 (adapt 13)", "20 (adapt 29)", "31 (adapt 40)"] {
        assert!(html.contains(&format!("<td class=\"l\">{row}</td>")), "no row {row}");
    }
    assert!(!html.contains("<td class=\"l\">5 (adapt 14)</td>"), "the table did not fold");
    assert!(html.contains("… 15 more batches (convergence.csv has every one)"));
    assert_eq!(common::csv_rows(&out.join("convergence.csv")).len(), 31);
}

#[test]
fn bad_adapt_sizes_are_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let file = standin_sweep(tmp.path());
    let out = tmp.path().join("out");
    for (args, says) in [
        (vec!["--first", "0"], "--first 0"),
        (vec!["--batch", "0"], "--batch 0"),
        (vec!["--max", "10"], "--max 10 is less than design.adapt.first"),
    ] {
        let o = common::sweep_bin()
            .args(["adapt", file.to_str().unwrap(), "--out"])
            .arg(&out)
            .args(&args)
            .output()
            .unwrap();
        let err = common::stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
    // A file that leaves `first` out is not named as the one that set it.
    let text = std::fs::read_to_string(&file).unwrap().replace("first = 20\n", "");
    let bare = common::write_file(&tmp.path().join("bare.toml"), &text);
    let o = common::sweep_bin()
        .args(["adapt", bare.to_str().unwrap(), "--max", "10", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--max 10 is less than the default first batch (10 per swept parameter) 40"),
        "{err}"
    );
    assert!(!err.contains("bare.toml"), "{err}");
    // An adaptive sweep on a cluster goes batch by batch: all at once is refused.
    let made = tmp.path().join("made");
    let o = common::sweep_bin()
        .args(["adapt", file.to_str().unwrap(), "-q", "--max", "20", "--out"])
        .arg(&made)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let o = common::sweep_bin()
        .args(["submit"])
        .arg(&made)
        .args(["--scheduler", "slurm", "--tasks", "2", "--all-at-once", "--dry-run"])
        .output()
        .unwrap();
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--all-at-once") && err.contains("batch by batch"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!made.join("cluster").exists());
    // At its max with the rule not held, there is nothing to submit, and it says how to go on.
    let o = common::sweep_bin()
        .args(["submit"])
        .arg(&made)
        .args(["--scheduler", "slurm", "--tasks", "2", "--dry-run"])
        .output()
        .unwrap();
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("nothing to submit: the rule has not held by design.adapt.max (20 points)"),
        "{err}"
    );
    assert!(err.contains("--max M"), "{err}");
}

/// The terminal says each batch as it is judged (its statistics with their intervals and the
/// rule's verdict), and the report's convergence table is the table of batches, with the same
/// numbers as summary.json.
#[test]
fn each_batch_is_said_on_the_terminal_and_tabled_in_the_report() {
    let tmp = tempfile::tempdir().unwrap();
    let file = common::write_file(
        &tmp.path().join("s.toml"),
        "name = \"b\"\n[parameters]\ngap = { lo = 2.0, hi = 4.0 }\nblade_speed = { lo = 1.2, hi = 1.6 }\n\
         [design.adapt]\nfirst = 8\nbatch = 4\nmax = 24\n[convergence]\ntolerance = 2.0\nfloor = 2.0\nhold = 1\n\
         [run]\nengine = \"stand-in\"\n",
    );
    let out = tmp.path().join("out");
    let o = sweep_adapt(&file, &out, &["--jobs", "2"]);
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let spaces = summary["spaces"].as_array().unwrap();
    assert_eq!(spaces.len(), 2, "{summary}");
    for (k, s) in spaces.iter().enumerate() {
        let label = s["label"].as_str().unwrap();
        let line = err
            .lines()
            .find(|l| l.starts_with(&format!("batch {} ({label}, {} points): ", k + 1, s["n"])))
            .unwrap_or_else(|| panic!("no line for {label}: {err}"));
        for stat in ["mean", "std", "skewness", "kurtosis"] {
            let (v, iv) = (&s["statistics"][stat], &s["intervals"][stat]);
            let said = format!(
                "{stat} {:.4} [{:.4}, {:.4}]",
                v.as_f64().unwrap(),
                iv["lo"].as_f64().unwrap(),
                iv["hi"].as_f64().unwrap()
            );
            assert!(line.contains(&said), "{said} not in {line}");
        }
        let converged = s["converged"].as_bool().unwrap();
        assert_eq!(line.ends_with("converged"), converged, "{line}");
    }
    assert!(
        err.contains("batch 1 (adapt 8, 8 points)") && err.contains("nothing to compare with yet"),
        "{err}"
    );
    let html = std::fs::read_to_string(out.join("report/report.html")).unwrap();
    assert!(html.contains("<th class=\"l\">batch</th><th>points</th><th>new</th>"), "no batch table");
    assert!(html.contains("<td class=\"l\">2 (adapt 12)</td><td>12</td><td>4</td>"), "no row of batch 2");
}

/// An adaptive sweep's statistics are known to their emulator's posterior interval, and its
/// verdict and its report say so (not a bootstrap's, which an adaptive design has none of); the
/// report draws one histogram of its runs, not one per batch.
#[test]
fn a_noisy_verdict_names_the_posterior_interval() {
    let tmp = tempfile::tempdir().unwrap();
    let file = standin_sweep(tmp.path());
    let out = tmp.path().join("out");
    let o = common::sweep_bin()
        .args([
            "adapt",
            file.to_str().unwrap(),
            "-q",
            "--jobs",
            "2",
            "--max",
            "30",
            "--tolerance",
            "0.001",
            "--out",
        ])
        .arg(&out)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), common::stderr(&o));
    let verdict = text.lines().find(|l| l.starts_with("verdict:")).unwrap_or_else(|| panic!("{text}"));
    assert!(verdict.contains("not converged after N = 30"), "{verdict}");
    assert!(verdict.contains("95% posterior interval") && !verdict.contains("bootstrap"), "{verdict}");
    // So does the report's figure of the statistics against N.
    let html = std::fs::read_to_string(out.join("report/report.html")).unwrap();
    assert!(html.contains("with the emulator's 95% posterior intervals"), "no posterior caption");
    assert!(!html.contains("95% bootstrap intervals"), "a bootstrap caption in an adaptive report");
    // Its spaces are its batches: one histogram, of every run, not one per batch.
    let spaces = manifest(&out).spaces.len();
    assert!(spaces >= 2, "{spaces} spaces");
    assert!(html.contains("MFR of the runs"));
    assert!(html.contains("its runs (not a sample of the space)") && !html.contains("<th>raw sample</th>"));
    assert_eq!(html.matches("alt=\"MFR distribution of").count(), 1);
}
