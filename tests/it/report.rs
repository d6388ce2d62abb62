//! Convergence and the report end to end, through the `sweep` binary: the stand-in engine
//! (`[run] engine = "stand-in"`) for sweeps that stop by themselves, resume and extension, and
//! real LIGGGHTS on `sweeps/quick.toml` for one sweep that ends with a report. Statistics are
//! checked against values recomputed here from results.csv, never against our own output, and
//! are finite even where every MFR is zero.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::support::{self, assert_all_finite, p, result_rows, stderr, sweep};

/// The thesis's 4-D space on the stand-in.
fn standin_sweep(dir: &Path, name: &str, convergence: &str) -> PathBuf {
    let text = format!(
        r#"name = "{name}"
[parameters]
friction    = {{ lo = 0.1, hi = 0.3 }}
diameter    = {{ lo = 1.0, hi = 3.0, unit = "mm" }}
gap         = {{ lo = 1.0, hi = 5.0, unit = "mm" }}
blade_speed = {{ lo = 1.2, hi = 1.6, unit = "m/s" }}
[convergence]
{convergence}
[run]
engine = "stand-in"
"#
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

fn joblog_lines(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("joblog.tsv")).unwrap().lines().count() - 1
}

/// Mean, std (divisor N), median, Pearson 2 and m4/S⁴ written out plainly.
fn plain_stats(x: &[f64]) -> [f64; 4] {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let s = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    let mut sorted = x.to_vec();
    sorted.sort_by(f64::total_cmp);
    let k = sorted.len();
    let median = if k % 2 == 1 { sorted[k / 2] } else { 0.5 * (sorted[k / 2 - 1] + sorted[k / 2]) };
    let kurt = x.iter().map(|v| (v - mean).powi(4)).sum::<f64>() / n / s.powi(4);
    [mean, s, 3.0 * (mean - median) / s, kurt]
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + b.abs())
}

/// Every `src=` and `href=` of report.html points inside the file itself.
fn assert_self_contained(html_path: &Path) {
    let html = std::fs::read_to_string(html_path).unwrap();
    for attr in ["src=", "href=", "srcset="] {
        for (i, _) in html.match_indices(attr) {
            let rest = html[i + attr.len()..].trim_start_matches(['"', '\'']);
            assert!(
                rest.starts_with("data:") || rest.starts_with('#'),
                "external {attr} at {i}: {}",
                &rest[..40.min(rest.len())]
            );
        }
    }
    for bad in ["@import", "url(", "<link", "<script", "<iframe"] {
        assert!(!html.contains(bad), "report.html holds {bad}");
    }
}

#[test]
fn lds_on_the_stand_in_stops_by_itself_and_its_statistics_are_the_prefixes() {
    let tmp = tempfile::tempdir().unwrap();
    // The default rule wants the skewness known within ±τ: 0.2 brings that well inside 4,000 runs
    // (0.15 converges near 3,600, too close to --max to see the sweep stop by itself).
    let file = standin_sweep(tmp.path(), "stop", "tolerance = 0.2");
    let out = tmp.path().join("out");
    let o =
        sweep(&["lds", p(&file), "--step", "400", "--max", "4000", "--jobs", "2", "-q", "--out", p(&out)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let s = summary(&out);
    let n = s["verdict"]["n"].as_u64().expect("converged") as usize;
    assert_eq!(s["verdict"]["status"], "converged");
    assert!(err.contains(&format!("converged at N = {n} (lds {n})")), "{err}");
    assert!(err.contains("report.html"), "{err}");
    // It stopped: far fewer runs than --max, and no space past the converged one was judged.
    let rows = support::csv_rows(&out.join("results.csv"));
    let done: Vec<&BTreeMap<String, String>> = rows.iter().filter(|r| r["status"] == "done").collect();
    // The stand-in's runs take microseconds, far less than the rule's bootstrap of a space
    // (1,000 resamples): the workers wait for the rule, so only the few runs in flight or
    // unread when it judged finish past the converged space, however loaded the machine.
    assert!(done.len() >= n && done.len() <= n + 40, "done {} n {n}", done.len());
    assert_eq!(joblog_lines(&out), done.len());
    let conv = support::csv_rows(&out.join("convergence.csv"));
    // The verdict's space is the first converged one, and no space past it was completed.
    let at = conv.iter().position(|r| r["converged"] == "true").unwrap();
    assert_eq!(conv[at]["space"], format!("lds {n}"));
    assert_eq!(at, conv.len() - 1, "spaces judged past the converged one");
    // The default rule needs two consecutive spaces that hold.
    assert!(at >= 2);
    assert_eq!(conv[at - 1]["holds"], "true");
    // Each space's statistics are those of the first n points' MFR, recomputed here.
    for row in &conv {
        let k: usize = row["n"].parse().unwrap();
        let mfr: Vec<f64> = rows[..k].iter().map(|r| r["mfr"].parse().unwrap()).collect();
        let want = plain_stats(&mfr);
        for (name, w) in ["mean", "std", "skewness", "kurtosis"].iter().zip(want) {
            let got: f64 = row[*name].parse().unwrap();
            assert!(close(got, w), "{} {name}: {got} vs {w}", row["space"]);
            let (lo, hi): (f64, f64) =
                (row[&format!("{name}_lo")].parse().unwrap(), row[&format!("{name}_hi")].parse().unwrap());
            assert!(lo <= got && got <= hi, "{name} interval [{lo}, {hi}] misses {got}");
        }
    }
    // Quality column filled for every done point; the report is there and self-contained.
    assert!(done.iter().all(|r| ["ideal", "inefficient", "unstable"].contains(&r["quality"].as_str())));
    for f in ["statistics.svg", "statistics.png", "histogram-1.png", "scatter.svg", "profiles.png"] {
        assert!(out.join("report").join(f).exists(), "{f}");
    }
    assert_self_contained(&out.join("report/report.html"));
    // The stand-in's MFR depends on gap and diameter far more than on friction or speed.
    let sens = s["sensitivity"].as_array().unwrap();
    let top: Vec<&str> = sens[..2].iter().map(|v| v["parameter"].as_str().unwrap()).collect();
    assert!(top.contains(&"gap") && top.contains(&"diameter"), "{sens:?}");

    // Resume respects the verdict: nothing new runs.
    let before = joblog_lines(&out);
    let spaces_before = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    let o = sweep(&["resume", p(&out), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(joblog_lines(&out), before, "resume ran points past a converged space");
    assert!(stderr(&o).contains(&format!("converged at N = {n}")), "{}", stderr(&o));
    // Its report judged the same spaces, recalled the emulator fits the first one kept, and
    // read the same from them.
    assert!(out.join("emulator-fits.json").exists());
    assert_eq!(std::fs::read_to_string(out.join("convergence.csv")).unwrap(), spaces_before);
    assert_eq!(summary(&out)["emulator"], s["emulator"]);

    // A larger --max extends on purpose and judges again past the old extent.
    let o =
        sweep(&["lds", p(&file), "--step", "200", "--max", "6000", "--jobs", "2", "-q", "--out", p(&out)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let s2 = summary(&out);
    let n2 = s2["verdict"]["n"].as_u64().map(|v| v as usize);
    match n2 {
        Some(n2) => assert!(n2 > 4000, "re-judged at {n2}, inside the old extent"),
        None => assert_eq!(s2["verdict"]["status"], "not-converged"),
    }
    assert!(joblog_lines(&out) > 4000);
}

#[test]
fn lattice_on_the_stand_in_names_its_converged_level_and_the_thesis_rule_is_weaker() {
    let tmp = tempfile::tempdir().unwrap();
    let file = standin_sweep(tmp.path(), "lat", "");
    let out = tmp.path().join("all");
    // The skewness's bootstrap half-width is about 0.24 at level 7 (2,401 points), so 25 %,
    // held once.
    let o = sweep(&[
        "lattice",
        p(&file),
        "--levels",
        "3,4,5,6,7,8",
        "--tolerance",
        "0.25",
        "--hold",
        "1",
        "-q",
        "--out",
        p(&out),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let s = summary(&out);
    let level = s["verdict"]["space"].as_str().expect("converged").to_string();
    assert!(err.contains(&format!("({level})")), "{err}");
    let conv = support::csv_rows(&out.join("convergence.csv"));
    assert_eq!(conv.last().unwrap()["space"], level);
    assert_ne!(level, "lattice 8", "stopped before the last level");
    assert!(s["counts"]["pending"].as_u64().unwrap() > 0);
    // Under the thesis rule (any one statistic) on the same points, convergence comes no later.
    // The lattice's weights: trapezoid by default, and how far equal weights would be.
    assert_eq!(conv.last().unwrap()["weights"], "trapezoid");
    assert!(s["spaces"][0]["equal_weights"]["mean"].is_f64());
    // Lattice 3's trapezoid mean, recomputed from results.csv: its points are those whose every
    // value is lo, mid or hi; each coordinate at lo or hi halves the weight.
    let box_ = [("friction", 0.1, 0.3), ("diameter", 1.0, 3.0), ("gap", 1.0, 5.0), ("blade_speed", 1.2, 1.6)];
    let (mut sw, mut swy, mut n3) = (0.0, 0.0, 0);
    for r in support::csv_rows(&out.join("results.csv")) {
        let on = |v: f64, lo: f64, hi: f64| [lo, (lo + hi) / 2.0, hi].iter().any(|g| (v - g).abs() < 1e-9);
        let v: Vec<f64> = box_.iter().map(|(k, _, _)| r[*k].parse().unwrap()).collect();
        if !v.iter().zip(&box_).all(|(v, (_, lo, hi))| on(*v, *lo, *hi)) {
            continue;
        }
        let w: f64 = v
            .iter()
            .zip(&box_)
            .map(|(v, (_, lo, hi))| if (v - lo).abs() < 1e-9 || (v - hi).abs() < 1e-9 { 0.5 } else { 1.0 })
            .product();
        n3 += 1;
        sw += w;
        swy += w * r["mfr"].parse::<f64>().unwrap();
    }
    assert_eq!(n3, 81);
    let got: f64 = conv[0]["mean"].parse().unwrap();
    assert!(close(got, swy / sw), "trapezoid mean {got} vs {}", swy / sw);
    let o = sweep(&["report", p(&out), "--rule", "any"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let any_n = summary(&out)["verdict"]["n"].as_u64().unwrap();
    assert!(any_n <= s["verdict"]["n"].as_u64().unwrap());
    assert_eq!(summary(&out)["criteria"]["rule"], "any");
    // The one-factor panels of the last level with ≥ 3 values per dimension.
    assert!(out.join("report/lattice-friction-by-gap.png").exists());
    assert_self_contained(&out.join("report/report.html"));
}

#[test]
fn a_tolerance_nothing_meets_is_not_converged_with_its_last_changes() {
    let tmp = tempfile::tempdir().unwrap();
    let file = standin_sweep(tmp.path(), "never", "tolerance = 0.0\nfloor = 0.0");
    let out = tmp.path().join("out");
    let o = sweep(&["lds", p(&file), "--step", "50", "--max", "200", "-q", "--out", p(&out)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("not converged after N = 200") && err.contains("last space (lds 200): mean failed"),
        "{err}"
    );
    let s = summary(&out);
    assert_eq!(s["verdict"]["status"], "not-converged");
    assert!(s["verdict"]["last_changes"]["mean"].as_f64().unwrap() > 0.0);
    assert_eq!(s["counts"]["done"], 200);
}

#[test]
fn stats_of_a_column_hand_worked_with_skipped_cells() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("t.csv");
    // 1, 2, 3, 4, 10 plus an empty cell and a word: mean 4, S = √10, median 3,
    // Pearson 2 = 3/√10, m4/S⁴ = 278.8/100.
    std::fs::write(&csv, "a,x\n1,1\n2,\n3,abc\n4,4\n10,10\n,\nfoo,\n").unwrap();
    let o = sweep(&["stats", p(&csv), "--column", "a", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["n"], 5);
    assert_eq!((v["skipped_empty"].as_u64(), v["skipped_non_numeric"].as_u64()), (Some(1), Some(1)));
    assert!(close(v["mean"].as_f64().unwrap(), 4.0));
    assert!(close(v["std"].as_f64().unwrap(), 10f64.sqrt()));
    assert!(close(v["skewness"].as_f64().unwrap(), 3.0 / 10f64.sqrt()));
    assert!(close(v["kurtosis"].as_f64().unwrap(), 2.788));
    assert!(v["intervals"]["mean"]["lo"].as_f64().unwrap() < 4.0);
    // Equal values: defined mean, undefined shape (null, never NaN).
    std::fs::write(&csv, "a\n0\n0\n0\n").unwrap();
    let o = sweep(&["stats", p(&csv), "--column", "a", "--json"]);
    let text = String::from_utf8_lossy(&o.stdout);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        (v["mean"].as_f64(), v["skewness"].is_null(), v["kurtosis"].is_null()),
        (Some(0.0), true, true)
    );
    assert!(!text.contains("NaN"));
    let o = sweep(&["stats", p(&csv), "--column", "a"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("undefined"));
}

#[test]
fn bad_input_is_one_line_and_exit_2_with_nothing_written() {
    let tmp = tempfile::tempdir().unwrap();
    let not_sweep = tmp.path().join("plain");
    std::fs::create_dir(&not_sweep).unwrap();
    let csv = tmp.path().join("r.csv");
    std::fs::write(&csv, "index,mfr\n0,0.1\n").unwrap();
    let empty = tmp.path().join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    let nope = tmp.path().join("nope");
    let missing = tmp.path().join("missing.csv");
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (vec!["report", p(&not_sweep)], vec![p(&not_sweep), "not a sweep directory"]),
        (vec!["report", p(&nope)], vec!["nope", "not a sweep directory"]),
        (vec!["stats", p(&csv), "--column", "mfrr"], vec![p(&csv), "`mfrr`", "did you mean `mfr`"]),
        (vec!["stats", p(&empty), "--column", "mfr"], vec![p(&empty), "empty"]),
        (vec!["stats", p(&missing), "--column", "mfr"], vec!["missing.csv", "no such file"]),
        (vec!["report", p(&not_sweep), "--rule", "some"], vec![p(&not_sweep)]),
    ];
    for (args, want) in cases {
        let o = sweep(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        for w in want {
            assert!(err.contains(w), "{args:?}: {err} lacks {w}");
        }
        assert!(!err.contains("panicked"));
    }
    assert_eq!(std::fs::read_dir(&not_sweep).unwrap().count(), 0, "nothing written");
    // A bad override is refused before anything runs or is written.
    let file = standin_sweep(tmp.path(), "bad", "");
    let out = tmp.path().join("out");
    let o = sweep(&["lds", p(&file), "--tolerance", "-1", "--out", p(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--tolerance -1"), "{}", stderr(&o));
    assert!(!out.exists());
}

/// The README's main command on real LIGGGHTS: a small sweep that ends with a report.
#[test]
fn quick_sweep_on_liggghts_ends_with_a_report() {
    support::require_liggghts!("quick_sweep_on_liggghts_ends_with_a_report");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("quick");
    let quick = Path::new(env!("CARGO_MANIFEST_DIR")).join("sweeps/quick.toml");
    let o = sweep(&["lds", p(&quick), "--max", "4", "--step", "2", "--jobs", "2", "-q", "--out", p(&out)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "every run of the demo succeeds: {err}");
    let s = summary(&out);
    // Two spaces give one comparison, and the rule must hold for `hold = 2`: not converged,
    // and the verdict says why.
    assert_eq!(s["verdict"]["status"], "not-converged", "{s}");
    assert_eq!(s["counts"]["done"], 4, "{s}");
    assert!(err.contains(&format!("report: {}", out.join("report/report.html").display())), "{err}");
    let rows = support::csv_rows(&out.join("results.csv"));
    let done: Vec<f64> =
        rows.iter().filter(|r| r["status"] == "done").map(|r| r["mfr"].parse().unwrap()).collect();
    assert_eq!(s["counts"]["done"].as_u64().unwrap() as usize, done.len());
    // The last space is all four points: its mean is the mean of results.csv's MFR.
    let conv = support::csv_rows(&out.join("convergence.csv"));
    let last = conv.last().unwrap();
    assert_eq!(last["n"], "4");
    assert_eq!(last["done"], done.len().to_string());
    if !done.is_empty() {
        let mean: f64 = last["mean"].parse().unwrap();
        assert!(close(mean, done.iter().sum::<f64>() / done.len() as f64));
    }
    assert!(rows.iter().filter(|r| r["status"] == "done").all(|r| !r["quality"].is_empty()));
    assert!(out.join("report/histogram-2.png").exists() && out.join("report/profiles.svg").exists());
    assert_self_contained(&out.join("report/report.html"));
}

/// Failed runs are left out of every statistic and counted, per space and by class.
#[test]
fn failed_runs_are_excluded_and_counted() {
    use demsweep::outcome::FailureClass;
    use demsweep::run::fake::{fake_mfr, Behaviour, FakeExecutor};
    use demsweep::run::{self, RunOptions, SweepDir};
    let tmp = tempfile::tempdir().unwrap();
    let text = r#"name = "fails"
[parameters]
gap         = { lo = 2.0, hi = 4.0, unit = "mm" }
blade_speed = { lo = 1.2, hi = 1.6, unit = "m/s" }
"#;
    let sweep = demsweep::sweep::Sweep::parse(text, &tmp.path().join("f.toml")).unwrap();
    // Every point at the lowest gap fails.
    let exec = FakeExecutor::new(|v, _| {
        if v[0] == 2.0 {
            Behaviour::Fail(std::time::Duration::ZERO, FailureClass::EngineError)
        } else {
            Behaviour::Succeed(std::time::Duration::ZERO)
        }
    });
    let out = tmp.path().join("out");
    let opts = RunOptions {
        jobs: 2,
        progress: demsweep::run::progress::ProgressMode::Quiet,
        retry_failed: false,
        force: false,
    };
    let design = demsweep::store::DesignRecord::Lattice { levels: vec![3, 5] };
    let mut hook = run::RunAll;
    run::start(SweepDir::new(&sweep, design, &out), &exec, &opts, &mut hook, &Default::default()).unwrap();
    let criteria = demsweep::analysis::convergence::Criteria::from_settings(&sweep.file.convergence);
    let a = demsweep::report::analyse(&out, &criteria, &Default::default()).unwrap();
    // Lattice 3: 3 of 9 points at gap 2; lattice 5: 5 of 25; they share the 3 points of the
    // gap-2 edge at blade speed 1.2, 1.4, 1.6, so 3 + 5 − 3 = 5 failures among 9 + 25 − 9 = 25.
    assert_eq!((a.counts.points, a.counts.failed, a.counts.done), (25, 5, 20));
    assert_eq!(a.counts.failures_by_class.get("engine-error"), Some(&5));
    assert_eq!((a.spaces[0].failed, a.spaces[0].done), (3, 6));
    assert_eq!((a.spaces[1].failed, a.spaces[1].done), (5, 20));
    // The statistics are those of the done points' MFR only, trapezoid-weighted (½ for each
    // coordinate on a face of the box; the failed gap-2 face drops out with its weights).
    for (space, members) in a.spaces.iter().zip([3usize, 5]) {
        let step = 2.0 / (members - 1) as f64;
        let speed = 0.4 / (members - 1) as f64;
        let face = |k: usize| if k == 0 || k == members - 1 { 0.5 } else { 1.0 };
        let (mut sw, mut swy) = (0.0, 0.0);
        for i in 1..members {
            for j in 0..members {
                let w = face(i) * face(j);
                sw += w;
                swy += w * fake_mfr(&[2.0 + i as f64 * step, 1.2 + j as f64 * speed]);
            }
        }
        assert_eq!(space.weights, "trapezoid");
        assert!((space.statistics.mean.unwrap() - swy / sw).abs() < 1e-12, "{}", space.label);
    }
    demsweep::report::write(&a).unwrap();
    let conv = support::csv_rows(&out.join("convergence.csv"));
    assert_eq!((conv[1]["failed"].as_str(), conv[1]["done"].as_str()), ("5", "20"));

    // Every run failed: undefined statistics, empty cells, a report all the same.
    let exec = FakeExecutor::new(|_, _| Behaviour::Fail(std::time::Duration::ZERO, FailureClass::Unstable));
    let out = tmp.path().join("all-failed");
    let design = demsweep::store::DesignRecord::Lds {
        step: 2,
        max: 4,
        scrambling: demsweep::sweep::Scrambling::None,
        seed: 0,
    };
    run::start(SweepDir::new(&sweep, design, &out), &exec, &opts, &mut hook, &Default::default()).unwrap();
    let a = demsweep::report::analyse(&out, &criteria, &Default::default()).unwrap();
    assert_eq!((a.counts.failed, a.counts.done), (4, 0));
    assert_eq!(a.verdict.status, "not-converged");
    assert_eq!(a.spaces[1].statistics.mean, None);
    demsweep::report::write(&a).unwrap();
    let conv = support::csv_rows(&out.join("convergence.csv"));
    assert_eq!((conv[1]["mean"].as_str(), conv[1]["kurtosis"].as_str()), ("", ""));
    let json = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(!json.contains("NaN") && !json.contains("inf"));
    assert_self_contained(&out.join("report/report.html"));
}

#[test]
fn predict_recovers_the_stand_in_between_its_points_and_refuses_bad_input() {
    let tmp = tempfile::tempdir().unwrap();
    let file = standin_sweep(tmp.path(), "emu", "tolerance = 0.0");
    let out = tmp.path().join("out");
    let o = sweep(&["lds", p(&file), "--step", "100", "--max", "300", "-q", "--out", p(&out)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // The emulator's cross-validation and statistics are in summary.json.
    let s = summary(&out);
    let cv = &s["emulator"]["cross_validation"];
    assert!(cv["q2"].as_f64().unwrap() > 0.9, "{cv}");
    let raw = s["statistics"]["mean"].as_f64().unwrap();
    let emu = s["emulator"]["statistics"]["statistics"]["mean"].as_f64().unwrap();
    assert!((emu / raw - 1.0).abs() < 0.05, "{emu} vs {raw}");
    // At settings that are not design points the prediction is the model's noiseless MFR within
    // 4 predictive SE (plus 0.003 for the stand-in's own per-point noise the emulator smooths).
    for (f, d, g, v) in [(0.2, 1.5, 4.0, 1.4), (0.15, 2.5, 3.0, 1.3), (0.25, 1.2, 2.0, 1.5)] {
        let set = format!("friction={f},diameter={d},gap={g},blade_speed={v}");
        let o = sweep(&["predict", p(&out), "--set", &set, "--json"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let truth =
            demsweep::scenes::stand_in::FlowPoint { friction: f, diameter: d, gap: g, blade_speed: v }
                .mean_mfr();
        let (m, se) = (j["mfr"].as_f64().unwrap(), j["se"].as_f64().unwrap());
        assert!((m - truth).abs() <= 4.0 * se + 0.003, "{set}: {m} ± {se} vs {truth}");
        assert!(j["outside"].as_array().unwrap().is_empty());
    }
    // Outside the swept range: a warning, and a larger SE than inside.
    let o = sweep(&["predict", p(&out), "--set", "gap=7", "--json"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(stderr(&o).contains("gap = 7 lies outside the sampled range"), "{}", stderr(&o));
    // Bad input: exit 2, one line naming the key.
    for (args, want) in [
        (vec!["predict", p(&out), "--set", "gapp=3"], "--set gapp: not a swept parameter"),
        (vec!["predict", p(&out), "--set", "gap=x"], "--set gap=x: expected a finite number"),
        // Issue 70, defect 8: values `sweep run --set` refuses were extrapolated to.
        (vec!["predict", p(&out), "--set", "gap=-3"], "--set gap=-3: outside the domain of gap (0, inf)"),
        (vec!["predict", p(&out), "--set", "gap=0"], "--set gap=0: outside the domain of gap (0, inf)"),
        (vec!["predict", p(&tmp.path().join("none")), "--set", "gap=3"], "not a sweep directory"),
    ] {
        let o = sweep(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains(want) && stderr(&o).lines().count() == 1, "{}", stderr(&o));
    }
}

/// The report's sections for a sweep whose runs all fail, one with some failures and one with
/// screened points (the fake executor), and `sweep show` on its points.
#[test]
fn report_sections_for_failed_and_screened_sweeps_and_a_points_page() {
    use demsweep::outcome::FailureClass;
    use demsweep::run::fake::{Behaviour, FakeExecutor};
    use demsweep::run::{self, RunOptions, SweepDir};
    use std::time::Duration;
    let tmp = tempfile::tempdir().unwrap();
    let text = "name = \"sections\"\n[parameters]\ngap = { lo = 2.0, hi = 4.0, unit = \"mm\" }\n\
                blade_speed = { lo = 1.2, hi = 1.6, unit = \"m/s\" }\nfriction = 0.3\n[run]\nscreen_sample = 0.0\nscreen_sample_min = 1\n";
    let sw = demsweep::sweep::Sweep::parse(text, &tmp.path().join("s.toml")).unwrap();
    let opts = RunOptions {
        jobs: 2,
        progress: demsweep::run::progress::ProgressMode::Quiet,
        retry_failed: false,
        force: false,
    };
    let criteria = demsweep::analysis::convergence::Criteria::from_settings(&sw.file.convergence);
    let build = |name: &str, exec: &FakeExecutor| -> (PathBuf, String) {
        let out = tmp.path().join(name);
        let design = demsweep::store::DesignRecord::Lattice { levels: vec![3] };
        run::start(SweepDir::new(&sw, design, &out), exec, &opts, &mut run::RunAll, &Default::default())
            .unwrap();
        let a = demsweep::report::analyse(&out, &criteria, &Default::default()).unwrap();
        demsweep::report::write(&a).unwrap();
        demsweep::run::rewrite_results(&out).unwrap();
        assert_self_contained(&out.join("report/report.html"));
        let html = std::fs::read_to_string(out.join("report/report.html")).unwrap();
        (out, html)
    };
    let manifest_hashes = |out: &Path| -> Vec<String> {
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
        m["points"].as_array().unwrap().iter().map(|p| p["hash"].as_str().unwrap().to_string()).collect()
    };

    // Every run timed out: a banner, the failure table and map, and no empty plots.
    let exec = FakeExecutor::new(|_, _| Behaviour::Fail(Duration::ZERO, FailureClass::TimedOut));
    let (out, html) = build("all-failed", &exec);
    assert!(html.contains("Every run failed") && html.contains("9 of 9 points"), "banner");
    assert!(html.contains("Failures (9 of 9 points)"));
    let hashes = manifest_hashes(&out);
    for (i, h) in hashes.iter().enumerate() {
        assert!(html.contains(&format!("<td>#{i}</td>")), "row of point {i}");
        assert!(html.contains(&format!("runs/{h}")), "run dir of point {i}");
    }
    assert_eq!(html.matches("fake timed-out failure").count(), 9);
    assert!(out.join("report/failures.png").exists());
    for absent in ["statistics.png", "histogram-1.png", "scatter.png", "profiles.png"] {
        assert!(!out.join("report").join(absent).exists(), "{absent} drawn with no MFR");
    }
    assert!(!html.contains("<h2>Convergence</h2>") && !html.contains("mean undefined"));
    let s = summary(&out);
    assert_eq!(s["failures"].as_array().unwrap().len(), 9);
    assert_eq!(s["failures"][0]["class"], "timed-out");
    assert!(Path::new(s["failures"][0]["run_dir"].as_str().unwrap()).join("failure.json").exists());
    // The whole setup: the fixed friction as written, rolling friction as the default nobody wrote.
    let fixed = s["setup"]["fixed"].as_array().unwrap();
    let get = |n: &str| fixed.iter().find(|f| f["name"] == n).unwrap().clone();
    assert_eq!(
        (get("friction")["value"].as_f64(), get("friction")["written"].as_bool()),
        (Some(0.3), Some(true))
    );
    assert_eq!(
        (get("rolling_friction")["value"].as_f64(), get("rolling_friction")["written"].as_bool()),
        (Some(0.1), Some(false))
    );
    assert_eq!(s["setup"]["scene"]["layout"], "conveyor");
    assert!(
        html.contains("rolling_friction")
            && html.contains("<i>default</i>")
            && html.contains("fidelity preset")
    );

    // Some failures (the points at the lowest blade speed): the table lists those, the rest of
    // the report is there, and results.csv holds the fixed parameters on every row.
    let exec = FakeExecutor::new(|v, _| {
        if v[1] == 1.2 {
            Behaviour::Fail(Duration::ZERO, FailureClass::Unsteady)
        } else {
            Behaviour::Succeed(Duration::ZERO)
        }
    });
    let (out, html) = build("some-failed", &exec);
    assert!(!html.contains("Every run failed"));
    assert!(html.contains("Failures (3 of 9 points)"));
    assert_eq!(html.matches("fake unsteady failure").count(), 3);
    for f in ["failures.png", "statistics.png", "scatter.png", "map-mfr-gap-blade_speed.png"] {
        assert!(out.join("report").join(f).exists(), "{f}");
    }
    assert!(html.contains("<h2>Convergence</h2>") && html.contains("Maps over pairs of parameters"));
    assert!(html.contains("<th>gap (mm)</th>") && html.contains("<th>blade_speed (m/s)</th>"));
    let rows = support::csv_rows(&out.join("results.csv"));
    assert!(rows
        .iter()
        .all(|r| r["friction"] == "0.3" && r["rolling_friction"] == "0.1" && r["density"] == "7980"));
    assert_eq!(rows.iter().filter(|r| r["status"] == "failed").count(), 3);

    // `sweep show`: a failed point's class, reason and run directory; a done point's result.
    let failed = rows.iter().find(|r| r["status"] == "failed").unwrap()["index"].clone();
    let o = sweep(&["show", p(&out), &failed]);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let hash = &rows[failed.parse::<usize>().unwrap()]["hash"];
    assert!(text.contains("failed: unsteady — fake unsteady failure"), "{text}");
    assert!(text.contains(&out.join("runs").join(hash).display().to_string()), "{text}");
    assert!(text.contains("rolling_friction") && text.contains("(default)") && text.contains("--vtk"));
    let done = rows.iter().find(|r| r["status"] == "done").unwrap();
    let o = sweep(&["show", p(&out), &done["index"], "--json"]);
    let page: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(page["status"], "done");
    assert_eq!(page["result"]["mfr"].as_f64().unwrap().to_string(), done["mfr"]);
    let o = sweep(&["show", p(&out), "9"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no point 9") && stderr(&o).contains("9 points"), "{}", stderr(&o));

    // Screened points (the closed gap-2 edge, verified by one run with MFR = 0): no failure
    // section, the screen stated, and the zero-MFR cells drawn.
    let closed = |v: &[f64]| v[0] < 2.5;
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(Duration::ZERO))
        .with_closed(closed)
        .with_mfr(move |v| if closed(v) { 0.0 } else { demsweep::run::fake::fake_mfr(v) });
    let (out, html) = build("screened", &exec);
    let s = summary(&out);
    assert_eq!((s["counts"]["screened"].as_u64(), s["counts"]["failed"].as_u64()), (Some(2), Some(0)));
    assert!(!html.contains("id=\"failures\"") && !out.join("report/failures.png").exists());
    assert!(html.to_lowercase().contains("screen"));
    // The map's grey: the colour bar's "= 0" swatch, and here the gap-2 cells as well.
    let grey = |out: &Path| {
        std::fs::read_to_string(out.join("report/map-mfr-gap-blade_speed.svg"))
            .unwrap()
            .matches("#C8C8C8")
            .count()
    };
    assert!(grey(&out) > 1, "no zero-MFR cell drawn");
    assert_eq!(grey(&tmp.path().join("some-failed")), 1, "a zero-MFR cell where every MFR > 0");
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
    assert!(result_rows(&d).iter().all(|r| r["mfr"].parse::<f64>().unwrap() == 0.0));
    assert_all_finite("stdout", &String::from_utf8_lossy(&o.stdout));
    assert_all_finite("stderr", &err);
    for f in ["convergence.csv", "summary.json"] {
        assert_all_finite(f, &std::fs::read_to_string(d.join(f)).unwrap());
    }
}

#[test]
fn a_one_parameter_lds_weighs_every_point_alike() {
    // Four scrambled-Halton values of one parameter are four distinct values, one point each, as
    // a lattice's would be; but its two extremes are no faces of the box: no trapezoid weights.
    let root = tempfile::tempdir().unwrap();
    let file = support::write_file(
        &root.path().join("one.toml"),
        "name = \"one\"\n[parameters]\nblade_speed = { lo = 1.2, hi = 1.6, unit = \"m/s\" }\n\
         [design.lds]\nstep = 4\nmax = 4\n[run]\nengine = \"stand-in\"\n",
    );
    let out = root.path().join("one");
    let o = sweep(&["lds", p(&file), "--out", p(&out), "-q"]);
    assert!(matches!(o.status.code(), Some(0) | Some(1)), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["spaces"][0]["weights"], "equal", "{}", s["spaces"][0]);
    assert!(s["spaces"][0]["equal_weights"].is_null(), "{}", s["spaces"][0]);
}
