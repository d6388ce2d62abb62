//! The screen: points where nothing can pass under the blade are skipped as MFR = 0, but only
//! once a seeded verification sample of them has run and given MFR = 0; a closed point whose run
//! gives MFR > 0 refutes the screen and every closed point runs for real.
//!
//! The pipeline on the fake executor (its "screen" closes the points below a gap, and each test
//! sets what those points give), then a tiny sweep on real LIGGGHTS whose space holds two closed
//! points: the verification run must give MFR = 0 on the engine, the other must be skipped.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Output;

use demsweep::analysis::stats::Bootstrap;
use demsweep::run::fake::{fake_mfr, Behaviour, FakeExecutor};
use demsweep::run::pool::Flow;
use demsweep::run::screen::Verdict;
use demsweep::run::{self, SpaceHook, SweepDir};
use demsweep::store::{
    self, DesignRecord, Manifest, PointRecord, PointStatus, SpaceRecord, Store, MANIFEST_FORMAT,
};
use demsweep::sweep::Sweep;
use demsweep::sys::process::CancelToken;

use crate::support::{self, stderr, sweep, MS};

/// Gap and blade speed swept; the fake closes the points at gap 2 (below 2.5). Equal lattice
/// weights: the screen's zeros are under test here, not the weights.
fn fake_sweep(dir: &Path, run: &str) -> Sweep {
    let text = format!(
        "name = \"t\"\n[parameters]\ngap = {{ lo = 2.0, hi = 4.0 }}\nblade_speed = {{ lo = 1.2, hi = 1.6 }}\n[convergence]\nlattice_weights = \"equal\"\n[run]\n{run}\n"
    );
    let path = dir.join("t.toml");
    std::fs::write(&path, &text).unwrap();
    Sweep::load(&path).unwrap()
}

fn closed(v: &[f64]) -> bool {
    v[0] < 2.5
}

/// Runs of 20 ms whose screen closes the points at gap 2, which measure no flow; the others
/// measure [`fake_mfr`].
fn screened_exec() -> FakeExecutor {
    FakeExecutor::new(|_, _| Behaviour::Succeed(20 * MS)).with_closed(closed).with_mfr(|v| {
        if closed(v) {
            0.0
        } else {
            fake_mfr(v)
        }
    })
}

/// A 3 × 3 lattice: three points at gap 2 are closed.
fn lattice3() -> DesignRecord {
    DesignRecord::Lattice { levels: vec![3] }
}

/// Records the MFR each completed space is judged on (`None`: not a number).
#[derive(Default)]
struct Seen(Vec<Vec<Option<f64>>>);

impl SpaceHook for Seen {
    fn space_complete(&mut self, _: &SpaceRecord, points: &[(&PointRecord, &PointStatus)]) -> Flow {
        self.0.push(
            points
                .iter()
                .map(|(_, s)| match s {
                    PointStatus::Done(r) => Some(r.answer.value),
                    PointStatus::Screened => Some(0.0),
                    _ => None,
                })
                .collect(),
        );
        Flow::Continue
    }
}

/// The 3 × 3 lattice of `s` run into `out` by `exec`, two at a time, with what each batch saw.
fn run_lattice3<E: demsweep::run::pool::Executor>(
    s: &demsweep::sweep::Sweep,
    out: &std::path::Path,
    exec: &E,
) -> (demsweep::run::Summary, Seen) {
    let mut seen = Seen::default();
    let sum = run::start(
        SweepDir::new(s, lattice3(), out),
        exec,
        &support::quiet(2),
        &mut seen,
        &CancelToken::new(),
    )
    .unwrap();
    (sum, seen)
}

#[test]
fn a_verified_screen_skips_the_closed_points_and_counts_them_as_zero() {
    let tmp = tempfile::tempdir().unwrap();
    let s = fake_sweep(tmp.path(), "screen_sample = 0.0\nscreen_sample_min = 1");
    let out = tmp.path().join("out");
    let exec = screened_exec();
    let (sum, seen) = run_lattice3(&s, &out, &exec);
    assert_eq!((sum.done, sum.screened, sum.failed, sum.pending, sum.exit_code()), (7, 2, 0, 0, 0));
    assert_eq!(sum.screen.verdict, Verdict::Verified);
    assert_eq!((sum.screen.closed, sum.screen.sample, sum.screen.ran, sum.screen.skipped), (3, 1, 1, 2));

    let (manifest, _) = Store::read_manifest(&out).unwrap();
    assert_eq!(manifest.points.iter().filter(|p| p.closed).count(), 3);
    let attempts = exec.attempts();
    let rows = support::csv_rows(&out.join("results.csv"));
    for (p, row) in manifest.points.iter().zip(&rows) {
        let run_dir = out.join("runs").join(&p.hash);
        match row["status"].as_str() {
            "screened" => {
                assert!(p.closed && row["screen"] == "closed", "{row:?}");
                assert_eq!(
                    (row["mfr"].as_str(), row["vx_1"].as_str(), row["runtime_s"].as_str()),
                    ("0", "", "")
                );
                assert!(!attempts.contains_key(&p.hash) && !run_dir.exists(), "a screened point never runs");
            }
            "done" => {
                assert_eq!(attempts[&p.hash], 1);
                assert!(run_dir.join("result.json").exists());
                let want = if p.closed { "verification" } else { "" };
                assert_eq!(row["screen"], want, "{row:?}");
            }
            other => panic!("point {}: status {other}", p.index),
        }
    }
    // The space was judged on all nine MFRs, the two screened ones as zeros.
    assert_eq!(seen.0.len(), 1);
    assert_eq!(seen.0[0].iter().filter(|m| **m == Some(0.0)).count(), 3);
    assert!(seen.0[0].iter().all(Option::is_some));

    // The report and `sweep status` count them the same way.
    let criteria = demsweep::analysis::convergence::Criteria::from_settings(&s.file.convergence);
    let a = demsweep::report::analyse(&out, &criteria, &Bootstrap::default()).unwrap();
    assert_eq!((a.counts.done, a.counts.screened, a.counts.pending), (7, 2, 0));
    assert_eq!((a.spaces[0].n, a.spaces[0].done), (9, 9));
    let mfr: Vec<f64> = rows.iter().map(|r| r["mfr"].parse().unwrap()).collect();
    let mean = mfr.iter().sum::<f64>() / 9.0;
    assert!((a.statistics.unwrap().mean.unwrap() - mean).abs() < 1e-12);
    let st = run::status(&out).unwrap();
    assert_eq!((st.done, st.screened, st.pending, st.screen.verdict), (7, 2, 0, Verdict::Verified));

    // A resume decides the same and runs nothing.
    let again =
        run::resume(&out, &exec, &support::quiet(2), &mut Seen::default(), &CancelToken::new()).unwrap();
    assert_eq!((again.ran, again.done, again.screened), (0, 7, 2));
    assert_eq!(exec.attempts(), attempts);
}

#[test]
fn a_verification_run_with_mfr_above_zero_refutes_the_screen_and_every_closed_point_runs() {
    // The fake's criterion closes gap 2, but the points there flow (fake_mfr > 0): a wrong screen.
    let tmp = tempfile::tempdir().unwrap();
    let s = fake_sweep(tmp.path(), "screen_sample = 0.0\nscreen_sample_min = 1");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(20 * MS)).with_closed(closed);
    let (sum, seen) = run_lattice3(&s, &out, &exec);
    assert_eq!((sum.done, sum.screened, sum.pending), (9, 0, 0));
    assert_eq!(sum.screen.verdict, Verdict::Refuted);
    assert_eq!((sum.screen.closed, sum.screen.ran, sum.screen.skipped), (3, 3, 0));
    assert_eq!(sum.screen.refuted_by.len(), 3, "every closed point that ran contradicts it");
    assert!(sum.screen.sentence().unwrap().starts_with("SCREEN REFUTED"));
    // Every point ran once, with its real MFR in results.csv; none is screened.
    let (manifest, _) = Store::read_manifest(&out).unwrap();
    assert!(exec.attempts().values().all(|&n| n == 1) && exec.attempts().len() == 9);
    for (p, row) in manifest.points.iter().zip(support::csv_rows(&out.join("results.csv"))) {
        assert_eq!(row["status"], "done");
        assert!((row["mfr"].parse::<f64>().unwrap() - fake_mfr(&p.values)).abs() < 1e-12);
    }
    assert_eq!(seen.0[0].iter().filter(|m| **m == Some(0.0)).count(), 0);
    // summary.json says so.
    let criteria = demsweep::analysis::convergence::Criteria::from_settings(&s.file.convergence);
    let a = demsweep::report::analyse(&out, &criteria, &Bootstrap::default()).unwrap();
    let json = serde_json::to_value(&a).unwrap();
    assert_eq!(json["screen"]["verdict"], "refuted");
    assert_eq!(json["counts"]["screened"], 0);
}

#[test]
fn an_array_task_runs_the_verification_sample_before_it_skips_its_own_closed_points() {
    // A task whose share holds closed points but not the sample point runs the sample point
    // first (the screen is trusted only once verified), then skips its own.
    let tmp = tempfile::tempdir().unwrap();
    let s = fake_sweep(tmp.path(), "screen_sample = 0.0\nscreen_sample_min = 1");
    let out = tmp.path().join("out");
    let exec = screened_exec();
    // Lay the sweep out without running it, as `sweep lds` does before its first run.
    let plan = run::plan(&exec, &s, &lattice3(), &CancelToken::new()).unwrap();
    let manifest = Manifest {
        format: MANIFEST_FORMAT,
        tool: "test".into(),
        name: "t".into(),
        parameters: s.names().iter().map(|n| n.to_string()).collect(),
        design: lattice3(),
        spaces: plan.spaces,
        points: plan.points,
        identity: demsweep::run::pool::Executor::identity(&exec),
    };
    std::fs::create_dir_all(&out).unwrap();
    Store::open(&out).write_manifest(&run::resolved_toml(&s, &lattice3()).unwrap(), &manifest).unwrap();
    let sample: BTreeSet<usize> = demsweep::run::screen::Screen::of(&s).sample(&manifest.points);
    let sample_point = *sample.first().unwrap();
    let share: Vec<usize> =
        manifest.points.iter().filter(|p| p.closed && p.index != sample_point).map(|p| p.index).collect();
    let order = |u: &[usize]| u.iter().copied().filter(|i| share.contains(i)).collect::<Vec<_>>();
    let sum = run::resume_share(
        &out,
        &exec,
        &support::quiet(1),
        Some(&order),
        &mut Seen::default(),
        &CancelToken::new(),
    )
    .unwrap();
    assert_eq!(sum.screen.verdict, Verdict::Verified);
    let ran: BTreeSet<String> = exec.attempts().into_keys().collect();
    assert_eq!(ran, BTreeSet::from([manifest.points[sample_point].hash.clone()]));
    assert_eq!(sum.screened, 2);
    let st = store::read_joblog(&out).unwrap();
    assert_eq!(st.len(), 1);
}

// ---- real LIGGGHTS ----

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stdout)))
}

#[test]
fn on_liggghts_the_verification_run_gives_mfr_zero_and_the_other_closed_point_is_skipped() {
    support::require_liggghts!(
        "on_liggghts_the_verification_run_gives_mfr_zero_and_the_other_closed_point_is_skipped"
    );
    // D = 2.5 mm on the rough substrate at 1.4 m/s: the screen closes gaps below 0.538 D
    // = 1.34 mm. Gaps 0.5, 1.25 (closed), 2.0 and 2.75 mm (0.8 D and 1.1 D: open, they run).
    // A narrow domain and the conveyor's cap, after its warm-up of 35 blocks here, keep each run
    // to a few seconds (the 0.8 D gap dribbles a particle or two per block).
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("screen.toml");
    std::fs::write(
        &file,
        r#"name = "screen"
[parameters]
gap      = { lo = 0.5, hi = 2.75, unit = "mm" }
diameter = { value = 2.5, unit = "mm" }
[convergence]
lattice_weights = "equal"   # the screen's zeros are under test here, not the weights
[scene]
depth_diameters = 3
window_cap_diameters = 400
[run]
screen_sample = 0.0
screen_sample_min = 1
"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    let (f, o) = (file.to_str().unwrap(), out.to_str().unwrap());
    let run = sweep(&["lattice", f, "--levels", "4", "--jobs", "2", "-q", "--out", o]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(0), "{err}");
    assert!(err.contains("screen verified: 1 of 2 closed point(s) ran and gave MFR = 0; 1 skipped"), "{err}");

    let table = support::csv_rows(&out.join("results.csv"));
    let gaps: Vec<f64> = table.iter().map(|r| r["gap"].parse().unwrap()).collect();
    assert_eq!(gaps, [0.5, 1.25, 2.0, 2.75]);
    let joblog = std::fs::read_to_string(out.join("joblog.tsv")).unwrap();
    // The verification run: one of the two closed points, run on LIGGGHTS, MFR = 0.
    let verification: Vec<&BTreeMap<String, String>> =
        table.iter().filter(|r| r["screen"] == "verification").collect();
    assert_eq!(verification.len(), 1);
    let v = verification[0];
    assert_eq!((v["status"].as_str(), v["mfr"].parse::<f64>().unwrap()), ("done", 0.0), "{v:?}");
    let vdir = out.join("runs").join(&v["hash"]);
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(vdir.join("result.json")).unwrap()).unwrap();
    assert!(result["engine_version"].as_str().unwrap().contains("LIGGGHTS"), "{result}");
    assert!(vdir.join("log.liggghts").exists() && vdir.join("in.liggghts").exists());
    assert!(joblog.lines().any(|l| l.contains(&format!("\t{}\tdone\t", v["hash"]))), "{joblog}");
    // The other closed point: screened, MFR 0, no v_x, no run directory, no joblog line.
    let screened: Vec<&BTreeMap<String, String>> =
        table.iter().filter(|r| r["status"] == "screened").collect();
    assert_eq!(screened.len(), 1);
    let s = screened[0];
    assert_eq!((s["screen"].as_str(), s["mfr"].as_str(), s["vx_1"].as_str()), ("closed", "0", ""));
    assert!(!out.join("runs").join(&s["hash"]).exists());
    assert!(!joblog.contains(&s["hash"]));
    // The two open points ran; the 1.1 D gap flows. The 0.8 D gap dribbles a particle or two
    // a block, or jams for good, as its pile's seed has it.
    let open: Vec<&BTreeMap<String, String>> = table.iter().filter(|r| r["screen"].is_empty()).collect();
    assert!(open.iter().all(|r| r["status"] == "done"), "{open:?}");
    let mfr_at = |gap: f64| -> f64 {
        let r = open.iter().find(|r| (r["gap"].parse::<f64>().unwrap() - gap).abs() < 1e-9);
        r.unwrap_or_else(|| panic!("no open point at gap {gap}"))["mfr"].parse().unwrap()
    };
    // The 1.1 D gap flows; the 0.8 D gap dribbles or jams, so it passes less than the 1.1 D one.
    assert!(mfr_at(2.75) > 0.0, "{open:?}");
    assert!(mfr_at(2.0) < mfr_at(2.75), "{open:?}");
    assert_eq!(std::fs::read_dir(out.join("runs")).unwrap().count(), 3);

    // The statistics count the screened point as MFR = 0: the four values of results.csv.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["counts"]["screened"], 1);
    assert_eq!(summary["counts"]["done"], 3);
    assert_eq!(summary["screen"]["verdict"], "verified");
    assert_eq!(
        (summary["screen"]["closed"].as_u64(), summary["screen"]["skipped"].as_u64()),
        (Some(2), Some(1))
    );
    assert_eq!(
        (summary["spaces"][0]["n"].as_u64(), summary["spaces"][0]["done"].as_u64()),
        (Some(4), Some(4))
    );
    let mfr: Vec<f64> = table.iter().map(|r| r["mfr"].parse().unwrap()).collect();
    let mean = mfr.iter().sum::<f64>() / 4.0;
    let got = summary["statistics"]["mean"].as_f64().unwrap();
    assert!((got - mean).abs() < 1e-12, "{got} vs {mean}");
    let stats =
        json(&sweep(&["stats", out.join("results.csv").to_str().unwrap(), "--column", "mfr", "--json"]));
    assert_eq!(stats["n"], 4);

    // `sweep status` shows it; a resume keeps the decision and runs nothing.
    let st = json(&sweep(&["status", o, "--json"]));
    assert_eq!((st["screened"].as_u64(), st["pending"].as_u64()), (Some(1), Some(0)));
    let text = String::from_utf8_lossy(&sweep(&["status", o]).stdout).into_owned();
    assert!(text.contains("screened 1"), "{text}");
    let resumed = sweep(&["resume", o, "-q"]);
    assert_eq!(resumed.status.code(), Some(0), "{}", stderr(&resumed));
    assert_eq!(std::fs::read_to_string(out.join("joblog.tsv")).unwrap(), joblog);
    assert_eq!(support::csv_rows(&out.join("results.csv")), table);
}

#[test]
fn the_points_preview_marks_the_closed_points_of_the_thesis_space() {
    support::require_liggghts!("the_points_preview_marks_the_closed_points_of_the_thesis_space");
    // `sweep points --screen`: closed exactly where gap/D is below 0.670 D less the margin,
    // 0.1472 D × (v / 1.6 m/s)^0.8 (v 1.2–1.6 m/s: the bound is 0.523–0.553 D).
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("sweeps/thesis-lds.toml");
    let o = sweep(&["points", file.to_str().unwrap(), "--lds", "400", "--screen"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout.clone()).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "friction,diameter,gap,blade_speed,screen");
    let (mut closed, mut sample) = (0, 0);
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let (d, gap, v): (f64, f64, f64) =
            (f[1].parse().unwrap(), f[2].parse().unwrap(), f[3].parse().unwrap());
        let bound = 0.44875f64.sqrt() - 0.147234 * (v / 1.6).powf(0.8);
        let is_closed = !f[4].is_empty();
        assert_eq!(is_closed, gap / d < bound, "{line}: gap/D {} bound {bound}", gap / d);
        closed += is_closed as usize;
        sample += (f[4] == "verification") as usize;
    }
    // A tenth of the closed points, at least 3.
    assert!(closed > 5 && sample >= 3 && sample < closed, "{closed} {sample}");
    let err = stderr(&o);
    assert!(err.contains(&format!("{closed} of 400 points closed; {} skipped", closed - sample)), "{err}");
}

#[test]
fn on_liggghts_a_failed_verification_run_refutes_the_screen_loudly() {
    support::require_liggghts!("on_liggghts_a_failed_verification_run_refutes_the_screen_loudly");
    // Every run is cut off at 0.3 s (LIGGGHTS takes seconds), so the verification run fails:
    // the screen is refuted, said so on stderr and in summary.json, and the other closed point
    // runs too (here, failing the same way) instead of being counted as MFR = 0.
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("refuted.toml");
    std::fs::write(
        &file,
        r#"name = "refuted"
[parameters]
gap      = { lo = 0.5, hi = 2.75, unit = "mm" }
diameter = { value = 2.5, unit = "mm" }
[scene]
depth_diameters = 3
[run]
screen_sample = 0.0
screen_sample_min = 1
timeout_s = 0.3
retries = 0
"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = out.to_str().unwrap();
    let run = sweep(&["lattice", file.to_str().unwrap(), "--levels", "4", "--jobs", "2", "-q", "--out", o]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("warning: SCREEN REFUTED: point ") && err.contains("failed (timed-out)"), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["screen"]["verdict"], "refuted", "{}", summary["screen"]);
    assert_eq!(
        (summary["screen"]["ran"].as_u64(), summary["counts"]["screened"].as_u64()),
        (Some(2), Some(0))
    );
    let table = support::csv_rows(&out.join("results.csv"));
    assert!(table.iter().all(|r| r["status"] == "failed"), "{table:?}");
    let joblog = std::fs::read_to_string(out.join("joblog.tsv")).unwrap();
    assert!(table.iter().all(|r| joblog.contains(&r["hash"])), "every point was attempted");
}
