//! `sweep bench fidelity` for real: one point under the three presets through LIGGGHTS. What is
//! asserted is what each preset must do to a run (the thesis's fixed step, full dumps and full
//! traverse; the reference's deeper domain and longer window), that the tables hold every run
//! with the reference's error zero and the others' bounded, and that a second bench reads the
//! runs back instead of running them again. Speed is measured by the bench, not asserted here
//! (BENCHMARKS.md "Fidelity").

use std::collections::HashMap;
use std::path::Path;

use crate::support;

fn sweep_file(dir: &Path) -> std::path::PathBuf {
    support::write_file(
        &dir.join("space.toml"),
        r#"name = "space"
[parameters]
gap         = { lo = 2.0, hi = 3.0, unit = "mm" }
blade_speed = { lo = 1.2, hi = 1.6, unit = "m/s" }
diameter    = 2.0
[scene]
layout = "gated"   # the presets were measured on the lab-frame scene (BENCHMARKS.md "Fidelity")
# Half the heap: the presets are compared at one supply, so what they must do is unchanged, and
# the test costs 68 CPU s in place of 81 (MFR about 0.055 here, 0.07 at the full supply).
supply_factor = 0.5
"#,
    )
}

fn rows(path: &Path) -> Vec<HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let headers = r.headers().unwrap().clone();
    r.records()
        .map(|rec| {
            headers.iter().zip(rec.unwrap().iter()).map(|(h, v)| (h.to_string(), v.to_string())).collect()
        })
        .collect()
}

fn result(dir: &Path, hash: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("runs").join(hash).join("result.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn one_point_under_each_preset_is_measured_against_the_reference_and_read_back_on_a_rerun() {
    support::require_liggghts!(
        "one_point_under_each_preset_is_measured_against_the_reference_and_read_back_on_a_rerun"
    );
    let tmp = tempfile::tempdir().unwrap();
    let file = sweep_file(tmp.path());
    let out = tmp.path().join("bench");
    let bench = || {
        support::sweep_bin()
            .args([
                "bench",
                "fidelity",
                file.to_str().unwrap(),
                "--points",
                "1",
                "--seeds",
                "1",
                "--jobs",
                "2",
            ])
            .args(["--out", out.to_str().unwrap()])
            .output()
            .unwrap()
    };
    let first = bench();
    let stdout = String::from_utf8_lossy(&first.stdout).to_string();
    assert_eq!(first.status.code(), Some(0), "{stdout}\n{}", String::from_utf8_lossy(&first.stderr));
    for f in ["fidelity-runs.csv", "fidelity.csv", "fidelity-summary.csv", "fidelity.svg", "fidelity.png"] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let runs = rows(&out.join("fidelity-runs.csv"));
    assert_eq!(runs.len(), 3, "{runs:?}");
    let by: HashMap<&str, &HashMap<String, String>> =
        runs.iter().map(|r| (r["variant"].as_str(), r)).collect();
    for r in &runs {
        assert_eq!(r["status"], "ok", "{r:?}");
        assert_eq!(r["reused"], "false");
    }
    let fast = result(&out, &by["fast"]["hash"]);
    let reference = result(&out, &by["reference"]["hash"]);
    let thesis = result(&out, &by["thesis"]["hash"]);
    // The reference: twice the depth (and a longer window) at a finer step.
    let particles = |r: &serde_json::Value| r["particles"].as_f64().unwrap();
    assert!(
        particles(&reference) > 1.8 * particles(&fast),
        "{} vs {}",
        particles(&reference),
        particles(&fast)
    );
    let dt = |r: &serde_json::Value| r["simulated_time"].as_f64().unwrap() / r["steps"].as_f64().unwrap();
    assert!(dt(&reference) < dt(&fast));
    // The thesis: its fixed 1e-5 s step, every column dumped over the whole run, the full
    // traverse (the run goes on after the window, so its deck runs more steps than it counts).
    assert!((dt(&thesis) - 1e-5).abs() < 1e-9, "{}", dt(&thesis));
    let thesis_dir = out.join("runs").join(&by["thesis"]["hash"]);
    for dump in ["dump.full.settle", "dump.full"] {
        let text = std::fs::read_to_string(thesis_dir.join(dump)).unwrap();
        assert!(
            text.contains("ITEM: ATOMS id type x y z vx vy vz fx fy fz omegax omegay omegaz radius mass"),
            "{dump}"
        );
    }
    let deck = std::fs::read_to_string(thesis_dir.join("in.liggghts")).unwrap();
    assert!(deck.contains("The thesis's full traverse"), "{deck}");
    let fast_dir = out.join("runs").join(&by["fast"]["hash"]);
    assert!(!fast_dir.join("dump.full").exists());
    // Errors against the reference: zero for itself; for the others within the presets' measured
    // bias and the scatter of a one-seed difference. `sweep bench fidelity space.toml --points 1
    // --seeds 3` of this file (seeds 12345–12347, LIGGGHTS 3.8, 2026-12-06) gave MFR fast 0.0554,
    // 0.0626, 0.0447; reference 0.0547, 0.0596, 0.0586; thesis 0.0645, 0.0609, 0.0645: a pooled
    // SD between seeds of 0.0055 (6 df), so 0.0078 for the difference of two one-seed runs, and
    // biases against the reference of −0.0034 ± 0.0054 (fast) and +0.0056 ± 0.0019 (thesis).
    // The bound is the larger bias and 3 SD of the difference: 0.0056 + 3 × 0.0078 = 0.029, about
    // half the reference's MFR — a one-seed comparison at this point cannot be held tighter. (It
    // was 60 % of the reference's MFR; a preset that doubles or zeroes MFR fails either way.)
    const WORST_ERROR: f64 = 0.029;
    let ref_mfr = reference["mfr"].as_f64().unwrap();
    // The reference flows as it did on those seeds (mean 0.0577, the pooled SD for its noise).
    let measured = support::Measured { mean: 0.0577, sd: 0.0055 };
    support::assert_measured(ref_mfr, 0.0, &measured, "the reference point");
    let summary = rows(&out.join("fidelity-summary.csv"));
    assert_eq!(summary.len(), 3);
    for s in &summary {
        let worst: f64 = s["worst_mfr_error"].parse().unwrap();
        if s["variant"] == "reference" {
            assert_eq!(worst, 0.0);
            assert_eq!(s["speedup_vs_reference"], "1.00");
        } else {
            assert!(worst <= WORST_ERROR, "{s:?} against the reference's MFR {ref_mfr}");
        }
        assert!(s["speedup_vs_thesis"].parse::<f64>().unwrap() > 0.0);
    }
    assert!(stdout.contains("×thesis"), "{stdout}");
    // A second bench reads every run back.
    let second = bench();
    assert_eq!(second.status.code(), Some(0));
    let again = rows(&out.join("fidelity-runs.csv"));
    assert!(again.iter().all(|r| r["reused"] == "true"), "{again:?}");
    assert_eq!(
        again.iter().map(|r| r["mfr"].clone()).collect::<Vec<_>>(),
        runs.iter().map(|r| r["mfr"].clone()).collect::<Vec<_>>()
    );
}

#[test]
fn bad_bench_input_is_one_line_and_writes_nothing() {
    support::require_liggghts!("bad_bench_input_is_one_line_and_writes_nothing");
    let tmp = tempfile::tempdir().unwrap();
    let file = sweep_file(tmp.path());
    let out = tmp.path().join("bench");
    for extra in [
        vec!["--points", "0"],
        vec!["--seeds", "0"],
        vec!["--presets", "fastest"],
        vec!["--variant", "nocolon"],
        vec!["--variant", "x:supply_factor=2"],
        vec!["--variant", "x:rayleigh_fraction=0.9"],
        // A knob of the conveyor's on this gated sweep: refused, not compared as a variant.
        vec!["--variant", "x:block_diameters=7"],
    ] {
        let r = support::sweep_bin()
            .args(["bench", "fidelity", file.to_str().unwrap(), "--out", out.to_str().unwrap()])
            .args(&extra)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{extra:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{extra:?}: {err}");
        assert!(!out.exists(), "{extra:?} wrote {}", out.display());
    }
}
