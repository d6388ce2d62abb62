//! The stand-in engine (`[run] engine = "stand-in"`): every layout's model makes results its own
//! checks accept, so a stand-in sweep of each finishes, and a resume finds nothing to run; a
//! point its model cannot make fails once, saying why, and is not run again.

use std::path::{Path, PathBuf};

use crate::support::*;

/// A shipped sweep file on the stand-in engine, with `edits` (from, to) applied, in `dir`.
fn shipped(dir: &Path, file: &str, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(repo(file)).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{file} has no {from:?}");
        text = text.replacen(from, to, 1);
    }
    let text = if text.contains("\n[run]\n") {
        text.replacen("\n[run]\n", "\n[run]\nengine = \"stand-in\"\n", 1)
    } else {
        format!("{text}\n[run]\nengine = \"stand-in\"\n")
    };
    write_file(&dir.join(Path::new(file).file_name().unwrap()), &text)
}

/// Run `args` on the sweep in `out`, then resume it: the exit codes, and how many runs the
/// resume started (from the joblog).
fn run_then_resume(args: &[&str], out: &Path) -> (Option<i32>, Option<i32>, usize) {
    let o = sweep(&[args, &["--out", p(out), "-q", "--jobs", "2"]].concat());
    let first = o.status.code();
    let before = joblog(out).len();
    let r = sweep(&["resume", p(out), "-q", "--jobs", "2"]);
    (first, r.status.code(), joblog(out).len() - before)
}

#[test]
fn a_stand_in_sweep_of_every_layout_finishes_and_a_resume_runs_nothing() {
    let (_tmp, dir) = cwd();
    let cases: Vec<(&str, PathBuf, Vec<&str>)> = vec![
        // A machine's blade speeds, where the flow model once threw v_x beyond ten blade speeds.
        (
            "conveyor at 0.05–0.2 m/s",
            shipped(&dir, "sweeps/ti64-machine.toml", &[("lo = 0.02, hi = 0.2", "lo = 0.05, hi = 0.2")]),
            vec!["lds"],
        ),
        ("gated", shipped(&dir, "sweeps/quick.toml", QUICK_AS_GATED), vec!["lds"]),
        (
            "layers, fused",
            shipped(&dir, "sweeps/ti64-layers.toml", &[("lattice_levels = [2, 3]", "lattice_levels = [2]")]),
            vec!["lattice"],
        ),
        // Twelve points: enough for the report's emulator, which ranks them.
        ("layers, loose", shipped(&dir, "sweeps/layers-gaboriault.toml", &[]), vec!["lds", "--max", "12"]),
    ];
    for (what, file, command) in cases {
        let out = dir.join(file.file_stem().unwrap());
        let args: Vec<&str> = command.iter().copied().chain([p(&file)]).collect();
        let (first, resumed, ran) = run_then_resume(&args, &out);
        let rows = result_rows(&out);
        let not_done: Vec<_> = rows.iter().filter(|r| r["status"] != "done").collect();
        assert!(!rows.is_empty() && not_done.is_empty(), "{what}: {not_done:?}");
        assert_eq!((first, resumed, ran), (Some(0), Some(0), 0), "{what}");
        // A layers point's own quantities by their own names: results.csv's columns are
        // result.json's steady layer, the depth in µm; the report ranks them by its answer, not MFR.
        if what.starts_with("layers") {
            let page = std::fs::read_to_string(out.join("report/report.html")).unwrap();
            assert!(!page.contains("MFR"), "{what}: the report speaks of MFR");
            assert!(!page.contains("v_x profile is"), "{what}: the report classes points by v_x");
            if what == "layers, loose" {
                assert!(page
                    .contains("Highest steady-layer relative density by the emulator among the done points"));
            }
            for row in &rows {
                let r: serde_json::Value = serde_json::from_str(
                    &std::fs::read_to_string(out.join("runs").join(&row["hash"]).join("result.json"))
                        .unwrap(),
                )
                .unwrap();
                let l = &r["layers"];
                let col = |c: &str| row[c].parse::<f64>().unwrap_or_else(|_| panic!("{what}: {c} {row:?}"));
                assert_eq!(col("relative_density"), l["relative_density"].as_f64().unwrap(), "{what}");
                assert_eq!(col("steady_packing_se"), l["packing_se"].as_f64().unwrap(), "{what}");
                assert!((col("depth_um") - 1e6 * l["effective_thickness_m"].as_f64().unwrap()).abs() < 1e-6);
                assert_eq!(col("passes") as usize, l["passes"].as_array().unwrap().len(), "{what}");
                assert_eq!(col("steady_from"), l["steady_from"].as_f64().unwrap(), "{what}");
            }
        }
    }
}

#[test]
fn a_stand_in_pour_runs_its_heap() {
    let (_tmp, dir) = cwd();
    let file = shipped(&dir, "sweeps/pour.toml", &[]);
    let o = sweep(&["run", p(&file), "--set", "rolling_friction=0.1"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // The pour's own lines, not a flow's MFR and v_x.
    let out = text(&o.stdout);
    assert!(out.contains("angle of repose") && out.contains("SE over 8 sectors"), "{out}");
    assert!(!out.contains("MFR"), "{out}");
}

#[test]
fn a_stand_in_sweep_whose_points_cannot_be_made_ends_with_their_failures_and_is_not_run_again() {
    // Two passes leave no steady layer: every point fails as unsteady, as a real run would.
    let (_tmp, dir) = cwd();
    let file = shipped(
        &dir,
        "sweeps/ti64-layers.toml",
        &[
            ("lattice_levels = [2, 3]", "lattice_levels = [2]"),
            ("layers = 14", "layers = 2"),
            ("bed = \"fused\"", "bed = \"loose\""),
        ],
    );
    let out = dir.join("d");
    let (first, resumed, ran) = run_then_resume(&["lattice", p(&file)], &out);
    assert_eq!((first, resumed, ran), (Some(1), Some(1), 0), "a failed point is not run again by a resume");
    let rows = result_rows(&out);
    assert_eq!(rows.len(), 4);
    for r in &rows {
        assert_eq!((r["status"].as_str(), r["failure"].as_str()), ("failed", "unsteady"), "{r:?}");
    }
    let status = text(&sweep(&["status", p(&out)]).stdout);
    assert!(status.contains("layers not steady by pass 2: fewer than 3 passes"), "{status}");
}
