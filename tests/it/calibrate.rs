//! `sweep calibrate`: known parameters recovered on the stand-in's pour (a closed-form angle of
//! repose and packing in sliding and rolling friction, with noise of known SD); one target
//! leaves a ridge; an interrupted calibration resumes to the uninterrupted one running nothing
//! twice; bad input is one line and writes nothing; the calibrated parameters are included by a
//! spreading sweep.

use crate::support as common;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use demsweep::analysis::calibration::Target;
use demsweep::run::calibrate::{self, CalibrationWatch, Settings};
use demsweep::run::fake::{Behaviour, FakeExecutor};
use demsweep::run::{batches, SweepDir};
use demsweep::scenes::pour::stand_in::PourPoint;
use demsweep::store::{self, DesignRecord, Store};
use demsweep::sys::process::CancelToken;

/// The pour on the stand-in, sliding and rolling friction free.
fn pour_sweep(dir: &Path) -> std::path::PathBuf {
    common::write_file(
        &dir.join("pour.toml"),
        r#"name = "pour"
[parameters]
friction         = { lo = 0.1, hi = 0.5 }
rolling_friction = { lo = 0.05, hi = 0.3 }
diameter         = { value = 2.0, unit = "mm" }
[scene]
layout = "pour"
[run]
engine = "stand-in"
"#,
    )
}

/// The stand-in's noiseless angle and packing at friction 0.3, rolling friction 0.2: the truth
/// the targets are made from.
fn truth() -> PourPoint {
    PourPoint { friction: 0.3, rolling_friction: 0.2, surface_energy: 0.0, diameter: 2.0 }
}

fn calibrate(file: &Path, out: &Path, targets: &[String], extra: &[&str]) -> std::process::Output {
    let mut cmd = common::sweep_bin();
    cmd.args(["calibrate", common::p(file), "-q", "--jobs", "2", "--out", common::p(out)]);
    for t in targets {
        cmd.args(["--target", t]);
    }
    common::output(cmd.args(extra))
}

fn posterior(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("posterior.json")).unwrap()).unwrap()
}

#[test]
fn two_targets_recover_known_frictions_within_their_credible_intervals() {
    let tmp = tempfile::tempdir().unwrap();
    let file = pour_sweep(tmp.path());
    let out = tmp.path().join("out");
    let t = truth();
    let targets = [
        format!("angle_of_repose={}±0.5", t.mean_angle()),
        format!("bulk_packing={}+-0.003", t.mean_packing()),
    ];
    let o = calibrate(&file, &out, &targets, &["--first", "20", "--batch", "4", "--max", "60"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let p = posterior(&out);
    let params = p["parameters"].as_array().unwrap();
    for (par, truth) in params.iter().zip([t.friction, t.rolling_friction]) {
        let (lo, hi) = (par["lo"].as_f64().unwrap(), par["hi"].as_f64().unwrap());
        assert!(lo <= truth && truth <= hi, "{par} misses {truth}");
        // Narrower than the prior: the targets say something about each.
        let (plo, phi) = (par["prior"][0].as_f64().unwrap(), par["prior"][1].as_f64().unwrap());
        assert!(hi - lo < 0.6 * (phi - plo), "{par}");
    }
    // The best run reproduces both targets to within a few of their SDs.
    for r in p["best_run"]["residuals"].as_array().unwrap() {
        assert!(r["in_sd"].as_f64().unwrap().abs() < 3.0, "{r}");
    }
    let runs = p["runs_done"].as_u64().unwrap();
    assert!((20..=60).contains(&runs), "{runs}");
    // The criterion's runs go where the targets are met: their noiseless angles and packings
    // are within a few target SDs of the targets, where the first batch's mostly are not.
    let dist = |r: &std::collections::BTreeMap<String, String>| {
        let at = PourPoint {
            friction: r["friction"].parse::<f64>().unwrap(),
            rolling_friction: r["rolling_friction"].parse::<f64>().unwrap(),
            ..t
        };
        (((at.mean_angle() - t.mean_angle()) / 0.5).powi(2)
            + ((at.mean_packing() - t.mean_packing()) / 0.003).powi(2))
        .sqrt()
    };
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let first = median(common::result_rows(&out)[..20].iter().map(dist).collect());
    let planned = common::csv_rows(&out.join(calibrate::BATCHES));
    let chosen: Vec<f64> = planned.iter().filter(|r| r["why"] == "posterior variance").map(dist).collect();
    assert!(chosen.len() >= 6, "{planned:?}");
    assert!(median(chosen.clone()) < 2.0 && first > 5.0, "{chosen:?}, first batch {first}");
    // The report with its map, and the parameters for a sweep.
    assert!(out.join("report/report.html").exists());
    let map = out.join("report/map-posterior-friction-rolling_friction.png");
    assert!(std::fs::metadata(&map).unwrap().len() > 5000, "{}", map.display());
    let cal: toml::Table =
        toml::from_str(&std::fs::read_to_string(out.join("calibrated.toml")).unwrap()).unwrap();
    let median = params[0]["median"].as_f64().unwrap();
    let written = cal["parameters"]["friction"]["value"].as_float().unwrap();
    assert!((written - median).abs() < 1e-3 * median, "{written} vs {median}");
    let ranges: toml::Table =
        toml::from_str(&std::fs::read_to_string(out.join("calibrated-ranges.toml")).unwrap()).unwrap();
    let lo = ranges["parameters"]["rolling_friction"]["lo"].as_float().unwrap();
    assert!((lo - params[1]["lo"].as_f64().unwrap()).abs() < 1e-3, "{lo}");
    assert_eq!(cal["parameters"]["diameter"]["value"].as_float(), Some(2.0));
    // Then the recoater: a spreading sweep includes the calibrated powder and sweeps the gap.
    let spread = common::write_file(
        &tmp.path().join("spread.toml"),
        &format!(
            "name = \"spread\"\ninclude = [{:?}]\n[parameters]\ngap = {{ lo = 3.0, hi = 5.0, unit = \"mm\" }}\n[run]\nengine = \"stand-in\"\n",
            out.join("calibrated.toml")
        ),
    );
    let o = common::output(common::sweep_bin().args(["run", common::p(&spread), "--set", "gap=4", "--json"]));
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let run: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(run["parameters"]["friction"].as_f64(), Some(written), "{run}");
}

#[test]
fn one_angle_leaves_a_ridge_of_friction_pairs() {
    let tmp = tempfile::tempdir().unwrap();
    let file = pour_sweep(tmp.path());
    let out = tmp.path().join("out");
    let targets = [format!("angle_of_repose={}±0.5", truth().mean_angle())];
    let o = calibrate(&file, &out, &targets, &["--first", "20", "--batch", "4", "--max", "40"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let p = posterior(&out);
    // Higher sliding friction is matched by lower rolling friction: strongly anti-correlated,
    // and neither pinned down on its own.
    assert!(p["correlation"][1].as_f64().unwrap() < -0.7, "{}", p["correlation"]);
    assert_eq!(p["ridges"].as_array().unwrap().len(), 1, "{}", p["ridges"]);
    for par in p["parameters"].as_array().unwrap() {
        assert_ne!(par["identification"], "identified", "{par}");
    }
    let said = common::text(&o.stdout);
    assert!(said.contains("ridge: friction and rolling_friction trade off"), "{said}");
    // The truth is on the ridge: inside both intervals.
    for (par, truth) in p["parameters"].as_array().unwrap().iter().zip([0.3, 0.2]) {
        assert!(par["lo"].as_f64().unwrap() <= truth && truth <= par["hi"].as_f64().unwrap(), "{par}");
    }
}

#[test]
fn a_cohesive_powder_s_rolling_friction_and_surface_energy_are_recovered() {
    let tmp = tempfile::tempdir().unwrap();
    let file = common::write_file(
        &tmp.path().join("cohesive.toml"),
        r#"name = "cohesive"
[parameters]
friction         = 0.3
rolling_friction = { lo = 0.05, hi = 0.3 }
surface_energy   = { lo = 0.0, hi = 0.2, unit = "J/m2" }
diameter         = { value = 2.0, unit = "mm" }
[scene]
layout = "pour"
[run]
engine = "stand-in"
"#,
    );
    let t = PourPoint { surface_energy: 0.05, ..truth() };
    let targets = [
        format!("angle_of_repose={}±0.5", t.mean_angle()),
        format!("bulk_packing={}±0.003", t.mean_packing()),
    ];
    let out = tmp.path().join("out");
    let o = calibrate(&file, &out, &targets, &["--first", "20", "--batch", "4", "--max", "60"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let p = posterior(&out);
    for (par, truth) in p["parameters"].as_array().unwrap().iter().zip([t.rolling_friction, t.surface_energy])
    {
        let (lo, hi) = (par["lo"].as_f64().unwrap(), par["hi"].as_f64().unwrap());
        assert!(lo <= truth && truth <= hi, "{par} misses {truth}");
        assert!(
            hi - lo < 0.6 * (par["prior"][1].as_f64().unwrap() - par["prior"][0].as_f64().unwrap()),
            "{par}"
        );
    }
    // `sweep status` reads the calibration's verdict.
    assert_eq!(p["status"], "converged", "{}", p["reason"]);
    let o = common::output(common::sweep_bin().args(["status", common::p(&out)]));
    let said = common::text(&o.stdout);
    assert!(said.contains("converged: yes"), "{said}");
}

/// A stand-in pour with one free parameter, rolling friction 0.05–0.3 at friction 0.3, in
/// `dir/rolling.toml`.
fn rolling_pour(dir: &Path) -> PathBuf {
    common::write_file(
        &dir.join("rolling.toml"),
        "name = \"r\"\n[parameters]\nfriction = 0.3\nrolling_friction = { lo = 0.05, hi = 0.3 }\n\
         [scene]\nlayout = \"pour\"\n[run]\nengine = \"stand-in\"\n",
    )
}

#[test]
fn one_free_parameter_is_recovered_and_drawn_as_a_curve() {
    let tmp = tempfile::tempdir().unwrap();
    let file = rolling_pour(tmp.path());
    let out = tmp.path().join("out");
    let targets = [format!("angle_of_repose={}±0.5", truth().mean_angle())];
    let o = calibrate(&file, &out, &targets, &["--first", "8", "--batch", "2", "--max", "20"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    // Every batch is labelled as the calibration's, the first (8 settings × 2 seeds) too: it
    // was "adapt 16", after the design that plans it.
    let (manifest, _) = demsweep::store::Store::read_manifest(&out).unwrap();
    let labels: Vec<&str> = manifest.spaces.iter().map(|s| s.label.as_str()).collect();
    assert!(labels[0] == "calibrate 16" && labels.iter().all(|l| l.starts_with("calibrate ")), "{labels:?}");
    let par = &posterior(&out)["parameters"][0];
    let (lo, hi) = (par["lo"].as_f64().unwrap(), par["hi"].as_f64().unwrap());
    // The stand-in's heap scatters by 1° between seeds against a target of ±0.5°: pinned to
    // about half the prior's range, no better.
    assert!(lo <= 0.2 && 0.2 <= hi && hi - lo < 0.15, "{par}");
    assert_ne!(par["identification"], "not identified", "{par}");
    assert!(std::fs::metadata(out.join("report/posterior-rolling_friction.png")).unwrap().len() > 5000);
    // The directory is this calibration's: other targets, or cluster arrays, are refused in one line.
    let other = calibrate(&file, &out, &["angle_of_repose=30±1".to_string()], &[]);
    let submit = common::output(common::sweep_bin().args([
        "submit",
        common::p(&out),
        "--scheduler",
        "slurm",
        "--tasks",
        "2",
        "--dry-run",
    ]));
    for (o, says) in
        [(other, "holds a calibration against angle_of_repose="), (submit, "plans each batch from the last")]
    {
        let err = common::stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(says) && err.trim().lines().count() == 1, "{err}");
    }
    assert!(!out.join("cluster").exists());
    assert_eq!(calibrate::settings(&out).unwrap().targets[0].sd, 0.5);
}

#[test]
fn the_emulator_takes_the_scatter_between_seeds_as_each_run_s_noise() {
    // The stand-in's heap scatters between seeds by ANGLE_SCATTER but reports an SE of half
    // that (ANGLE_SE), as a real pour's sectors do: repeats measure the scatter, and it, not the
    // SE, is each run's noise in the emulator and so in the likelihood.
    use demsweep::scenes::pour::stand_in::{ANGLE_SCATTER, ANGLE_SE};
    let tmp = tempfile::tempdir().unwrap();
    let file = rolling_pour(tmp.path());
    let targets = [format!("angle_of_repose={}±0.5", truth().mean_angle())];
    let out = tmp.path().join("out");
    let o =
        calibrate(&file, &out, &targets, &["--first", "8", "--batch", "2", "--max", "36", "--repeats", "3"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let p = posterior(&out);
    let noise = &p["noise"][0];
    let between = noise["between_seed_sd"].as_f64().unwrap();
    let df = noise["df"].as_u64().unwrap();
    assert!(df >= 16, "{noise}");
    // Within about 2 SE of the truth (an SD from ≥ 16 df is known to about ±18 %).
    assert!((between / ANGLE_SCATTER - 1.0).abs() < 0.4, "{noise}");
    assert_eq!(noise["own_se"].as_f64(), Some(ANGLE_SE), "{noise}");
    assert_eq!(noise["run_sd"].as_f64(), Some(between), "{noise}");
    // Each setting ran three times, with three seeds: three runs of the same values.
    let rows = common::result_rows(&out);
    assert_eq!(rows.len() % 3, 0, "{}", rows.len());
    // results.csv names the heap's quantities: each done row's angle is its result's.
    for row in rows.iter().filter(|r| r["status"] == "done") {
        let r: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join("runs").join(&row["hash"]).join("result.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(
            row["angle_of_repose_deg"].parse::<f64>().ok(),
            r["heap"]["angle_deg"].as_f64(),
            "{row:?}"
        );
        assert_eq!(row["bulk_packing"].parse::<f64>().ok(), r["heap"]["packing"].as_f64(), "{row:?}");
    }
    let (manifest, _) = Store::read_manifest(&out).unwrap();
    for k in (0..manifest.points.len()).step_by(3) {
        let p = &manifest.points[k..k + 3];
        assert!(p.iter().all(|q| q.values == p[0].values), "{p:?}");
        assert_eq!(p.iter().map(|q| q.seed).collect::<Vec<_>>(), vec![None, Some(12346), Some(12347)]);
    }
    let said = common::text(&o.stdout);
    assert!(said.contains("noise of angle_of_repose: scatter between seeds"), "{said}");
    let par = &p["parameters"][0];
    assert!(par["lo"].as_f64().unwrap() <= 0.2 && 0.2 <= par["hi"].as_f64().unwrap(), "{par}");
    // One run per setting measures no scatter, and says so.
    let single = tmp.path().join("single");
    let o = calibrate(
        &file,
        &single,
        &targets,
        &["--first", "8", "--batch", "2", "--max", "12", "--repeats", "1"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let noise = &posterior(&single)["noise"][0];
    assert!(noise["between_seed_sd"].is_null() && noise["df"] == 0, "{noise}");
    assert!(common::text(&o.stdout).contains("scatter between seeds not measured"));
}

#[test]
fn apparent_density_beside_the_angle_narrows_the_friction_ridge() {
    // One angle leaves sliding and rolling friction on a ridge; a datasheet's apparent density
    // (ASTM B212: the packing times the material's density, 7980 kg/m³ here) cuts it, as the
    // stand-in's packing falls with sliding friction twice as fast as with rolling friction.
    let tmp = tempfile::tempdir().unwrap();
    let file = pour_sweep(tmp.path());
    let t = truth();
    let angle = format!("angle_of_repose={}±0.5", t.mean_angle());
    let density = format!("apparent_density={}±0.02", t.mean_packing() * 7.98);
    let args = ["--first", "12", "--batch", "4", "--max", "56"];
    let width = |out: &Path| {
        let p = posterior(out);
        let f = &p["parameters"][0];
        assert_eq!(f["name"], "friction");
        let (lo, hi) = (f["lo"].as_f64().unwrap(), f["hi"].as_f64().unwrap());
        assert!(lo <= t.friction && t.friction <= hi, "{f} misses {}", t.friction);
        (hi - lo, p)
    };
    let (one, two) = (tmp.path().join("one"), tmp.path().join("two"));
    let o = calibrate(&file, &one, std::slice::from_ref(&angle), &args);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let o = calibrate(&file, &two, &[angle.clone(), density], &args);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let ((w1, p1), (w2, p2)) = (width(&one), width(&two));
    assert!(w2 < 0.7 * w1, "friction's 95 % interval: {w2} with the apparent density, {w1} without");
    assert_eq!(p1["ridges"].as_array().unwrap().len(), 1, "{}", p1["ridges"]);
    let ratio = |p: &serde_json::Value| p["parameters"][0]["sd_ratio"].as_f64().unwrap();
    assert!(
        ratio(&p2) < 0.6 * ratio(&p1),
        "posterior SD over the prior's: {} against {}",
        ratio(&p2),
        ratio(&p1)
    );
    // The apparent density is read in g/cm³ from the heap's packing.
    let best = &p2["best_run"]["residuals"][1];
    assert_eq!(best["target"]["name"], "apparent_density");
    assert!((best["simulated"].as_f64().unwrap() - t.mean_packing() * 7.98).abs() < 0.1, "{best}");
}

#[test]
fn a_target_no_setting_reaches_is_out_of_reach_not_converged_or_identified() {
    // Issue 70, defect 4: steel at 7.98 g/cm³ reaches an apparent density of about 5.9; a target
    // of 9 ± 0.1 ended "converged", friction "identified", its best run 40 SD off.
    let tmp = tempfile::tempdir().unwrap();
    let file = pour_sweep(tmp.path());
    let out = tmp.path().join("out");
    let targets = ["angle_of_repose=34±1".to_string(), "apparent_density=9±0.1".to_string()];
    let o = calibrate(&file, &out, &targets, &["--first", "8", "--batch", "4", "--max", "16"]);
    let said = common::text(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let p = posterior(&out);
    assert_eq!(p["status"], "out of reach", "{said}");
    assert!(
        said.starts_with(
            "out of reach: no setting in the sweep file's ranges reproduces apparent_density = 9"
        ),
        "{said}"
    );
    assert!(!said.contains("angle_of_repose = 34"), "the angle is reached: {said}");
    for par in p["parameters"].as_array().unwrap() {
        assert_eq!(par["identification"], "not identified: the targets are out of reach", "{par}");
    }
    let o = common::output(common::sweep_bin().args(["status", common::p(&out)]));
    assert!(common::text(&o.stdout).contains("converged: no"), "{}", common::text(&o.stdout));
    // Issue 70, defect 15: predict of a calibration said it "needs at least 8 done points".
    let o = common::output(common::sweep_bin().args(["predict", common::p(&out), "--set", "friction=0.3"]));
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("a calibration directory: predict reads a spreading sweep's MFR"), "{err}");
    // Issue 70, defect 9: a pour point's page showed "MFR NaN" and v_x heights "inf".
    let o = common::output(common::sweep_bin().args(["show", common::p(&out), "0"]));
    let page = common::text(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(page.contains("angle of repose") && !page.contains("MFR") && !page.contains("inf"), "{page}");
}

/// Issue 70, defect 15: messages that named the wrong thing.
#[test]
fn a_huge_first_batch_and_another_sweep_s_directory_are_named_as_such() {
    let tmp = tempfile::tempdir().unwrap();
    let file = pour_sweep(tmp.path());
    let target = ["angle_of_repose=30±1".to_string()];
    // It named design.adapt.max, which the file does not hold.
    let o = calibrate(&file, &tmp.path().join("x"), &target, &["--first", "99999999999"]);
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--first 99999999999 (× 2 repeats): expected at most") && !err.contains("max"),
        "{err}"
    );
    // It said "not a adapt one".
    let lds = common::engine_sweep(tmp.path(), "spread", "stand-in", 2, 2, "");
    let d = tmp.path().join("lds");
    let o = common::sweep(&["lds", common::p(&lds), "--out", common::p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let o = calibrate(&file, &d, &target, &[]);
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("holds an lds sweep, not an adapt one"), "{err}");
}

#[test]
fn sweep_run_of_a_pour_prints_its_angle_of_repose_not_an_mfr() {
    // Issue 70, defect 9: on the stand-in it printed "MFR NaN" and v_x heights "inf".
    let tmp = tempfile::tempdir().unwrap();
    let file = pour_sweep(tmp.path());
    let o = common::output(common::sweep_bin().args(["run", common::p(&file), "--set", "friction=0.3"]));
    let said = common::text(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(said.contains("angle of repose") && !said.contains("NaN") && !said.contains("inf"), "{said}");
}

/// MFR as a calibration target on the fake executor (gap and blade speed free): a smooth,
/// known response.
fn fake_mfr(v: &[f64]) -> f64 {
    0.1 + 0.05 * (v[0] - 2.0) - 0.1 * (v[1] - 1.2)
}

fn run_fake(dir: &Path, out: &Path, exec: &FakeExecutor, cancel: &CancelToken) -> demsweep::run::Summary {
    let s = common::fake_sweep(dir, "");
    let settings = settings();
    let mut watch = CalibrationWatch::new(&s, settings.clone(), 7);
    let design = DesignRecord::Adapt { first: 10, batch: 4, max: 30, seed: 7, repeats: 1 };
    calibrate::start(SweepDir::new(&s, design, out), &settings, exec, &common::quiet(2), &mut watch, cancel)
        .unwrap()
}

fn settings() -> Settings {
    // The truth: gap 3, blade speed 1.4 give MFR 0.13; a tight target so the rule never holds.
    Settings {
        targets: vec![Target { name: "mfr".into(), value: 0.13, sd: 0.002 }],
        tolerance: 1e-9,
        hold: 2,
    }
}

#[test]
fn an_interrupted_calibration_resumes_to_the_uninterrupted_one_running_nothing_twice() {
    let tmp = tempfile::tempdir().unwrap();
    let ms = Duration::from_millis(1);
    let reference = tmp.path().join("reference");
    let sum = run_fake(
        tmp.path(),
        &reference,
        &FakeExecutor::new(move |_, _| Behaviour::Succeed(ms)).with_mfr(fake_mfr),
        &CancelToken::new(),
    );
    assert_eq!(sum.exit_code(), 0, "{sum:?}");
    let planned = sum.done;
    assert!(planned > 14, "{sum:?}");

    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(move |_, _| Behaviour::Succeed(120 * ms)).with_mfr(fake_mfr);
    let cancel = CancelToken::new();
    let c2 = cancel.clone();
    let watched = out.clone();
    let t = std::thread::spawn(move || {
        let done =
            |d: &Path| store::read_joblog(d).map_or(0, |l| l.iter().filter(|l| l.status == "done").count());
        // A guard only: a sweep that stopped short fails the test instead of hanging it.
        common::wait_until("12 runs done", common::GUARD, || done(&watched) >= 12);
        c2.cancel();
    });
    let sum = run_fake(tmp.path(), &out, &exec, &cancel);
    t.join().unwrap();
    assert!(sum.interrupted && sum.exit_code() == 130, "{sum:?}");
    let before: Vec<String> = store::read_joblog(&out)
        .unwrap()
        .into_iter()
        .filter(|l| l.status == "done")
        .map(|l| l.hash)
        .collect();
    let n = Store::read_manifest(&out).unwrap().0.points.len();
    assert!(n < planned);
    // A kill between writing a batch's rows and appending it to the manifest leaves rows of
    // points the manifest does not hold; the batch planned again replaces them.
    let batches = out.join("calibration-batches.csv");
    let mut text = std::fs::read_to_string(&batches).unwrap();
    text.push_str(&format!("9,{n},cut off,coverage,,3,1.4\n9,{},cut off,coverage,,3,1.4\n", n + 1));
    std::fs::write(&batches, text).unwrap();

    // `sweep resume` reads the calibration's settings from the directory.
    assert_eq!(calibrate::settings(&out), Some(settings()));
    let exec2 = FakeExecutor::new(move |_, _| Behaviour::Succeed(ms)).with_mfr(fake_mfr);
    let s = common::fake_sweep(tmp.path(), "");
    let mut watch = CalibrationWatch::new(&s, settings(), 7);
    let sum2 = batches::run(&out, &exec2, &common::quiet(2), &mut watch, &CancelToken::new()).unwrap();
    assert_eq!((sum2.done, sum2.exit_code()), (planned, 0), "{sum2:?}");
    for h in &before {
        assert!(!exec2.attempts().contains_key(h), "finished run {h} ran again");
    }
    let mut runs: HashMap<String, usize> = HashMap::new();
    for l in store::read_joblog(&out).unwrap().into_iter().filter(|l| l.status == "done") {
        *runs.entry(l.hash).or_default() += 1;
    }
    assert!(runs.values().all(|&n| n == 1), "{runs:?}");
    let (m, r) = (Store::read_manifest(&out).unwrap().0, Store::read_manifest(&reference).unwrap().0);
    assert_eq!(m.points, r.points, "the same batches as without the interruption");
    assert_eq!(common::results(&out), common::results(&reference));
    let rows = |d: &Path| std::fs::read_to_string(d.join("calibration-batches.csv")).unwrap();
    assert_eq!(rows(&out), rows(&reference), "one row per planned point, as without the kill");
    // The posterior holds the truth (on a ridge: one target, two parameters).
    let c = demsweep::report::calibration::write(&out).unwrap();
    for (p, truth) in c.parameters.iter().zip([3.0, 1.4]) {
        assert!(p.lo <= truth && truth <= p.hi, "{p:?} misses {truth}");
    }
}

#[test]
fn bad_input_is_one_line_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let file = pour_sweep(tmp.path());
    let fixed = common::write_file(
        &tmp.path().join("fixed.toml"),
        "name = \"f\"\n[parameters]\nfriction = 0.3\n[scene]\nlayout = \"pour\"\n[run]\nengine = \"stand-in\"\n",
    );
    let spreading = common::write_file(
        &tmp.path().join("spread.toml"),
        "name = \"s\"\n[parameters]\ngap = { lo = 2.0, hi = 4.0 }\n[run]\nengine = \"stand-in\"\n",
    );
    let out = tmp.path().join("out");
    let cases: [(&Path, &str, &str); 15] = [
        (&file, "angle_of_repose=34", "--target angle_of_repose=34: no ± SD"),
        // Values no powder can have, and SDs that make every residual rounding or nothing.
        (&file, "angle_of_repose=400±1", "--target angle_of_repose=400: outside (0, 90]°"),
        (&file, "angle_of_repose=-30±1", "--target angle_of_repose=-30: outside (0, 90]°"),
        (&file, "bulk_packing=1.5±0.01", "--target bulk_packing=1.5: outside (0, 0.7405]"),
        // No heap is empty (issue 70, defect 4: apparent_density=0±0.1 was accepted).
        (&file, "apparent_density=0±0.1", "--target apparent_density=0: outside (0, 20]g/cm³"),
        (&file, "angle_of_repose=0±1", "--target angle_of_repose=0: outside (0, 90]°"),
        (&file, "bulk_packing=-0.2±0.01", "--target bulk_packing=-0.2: outside"),
        (&file, "angle_of_repose=34±1e-300", "--target angle_of_repose: SD 1e-300°: expected 0.00009 to 90°"),
        (&file, "angle_of_repose=34±1e300", "--target angle_of_repose: SD 1e300°: expected"),
        (&file, "angle_of_repose=abc±1", "is not a number"),
        (&file, "angle_of_repose=34±0", "expected a positive uncertainty"),
        (&file, "porosity=0.4±0.01", "--target porosity: not a quantity a run measures"),
        (&file, "mfr=0.2±0.01", "--target mfr: scene.layout \"pour\" does not measure it"),
        (&spreading, "angle_of_repose=34±1", "scene.layout \"conveyor\" does not measure it"),
        (&fixed, "angle_of_repose=34±1", "expected at least one swept parameter"),
    ];
    for (f, target, says) in cases {
        let o = calibrate(f, &out, &[target.to_string()], &[]);
        let err = common::stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{target}: {err}");
        assert!(err.contains(says), "{target}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!out.exists(), "{target} wrote {}", out.display());
    }
}
