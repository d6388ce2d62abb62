//! The answer a sweep ends with, first: on the terminal (the recommended setting, what matters,
//! the verdict and the next command, quoted to run as printed), in the report and in `sweep
//! show`; the verdict as the docs word it, and the examples in every command's help. All on the
//! stand-in engine: no LIGGGHTS needed.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use crate::hostile::{finish_within, finished, hash, out, sweep_file, sweep_in};
use crate::support::{self as common, p, stderr as err};

/// Give point `i`'s result a layer that covers `covered` of the plate.
fn set_layer(d: &Path, i: usize, covered: f64) {
    let r = d.join("runs").join(hash(d, i)).join("result.json");
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&r).unwrap()).unwrap();
    v["layer"] = serde_json::json!({
        "layer_cv": 0.1, "layer_cv_noise": 0.1, "covered_fraction": covered,
        "roughness_d": 0.4, "height_d": 0.8, "particles": 500
    });
    std::fs::write(&r, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

/// The point the report recommends (the highest MFR among even layers), from `answer` in
/// summary.json.
fn recommended(d: &Path) -> usize {
    let o = sweep_in(d.parent().unwrap(), &["report", p(d)]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap()).unwrap();
    s["advice"]["recommended"][0]["index"].as_u64().unwrap() as usize
}

#[test]
fn a_sweep_ends_with_the_answer_on_stdout() {
    let tmp = tempfile::tempdir().unwrap();
    sweep_file(tmp.path(), &|t| t);
    let o = sweep_in(tmp.path(), &["lds", "t.toml", "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let text = out(&o);
    let lines: Vec<&str> = text.lines().collect();
    assert!(
        lines[0].starts_with("recommended: gap = ") && lines[0].contains("MFR") && lines[0].contains("(SE)"),
        "{text}"
    );
    assert!(lines.iter().any(|l| l.starts_with("what matters: ")), "{text}");
    let verdict = lines.iter().find(|l| l.starts_with("verdict: ")).expect("a verdict line");
    assert!(verdict.starts_with("verdict: not converged after N = 8: "), "{text}");
    // What to do, as a command that works: it extends the directory, keeping its points.
    let next = lines.iter().find(|l| l.starts_with("next: ")).expect("a next line");
    assert!(next.contains("`sweep lds runs/h/sweep.toml --max 16 --out runs/h`"), "{next}");
    let o = sweep_in(tmp.path(), &["lds", "runs/h/sweep.toml", "--max", "16", "--out", "runs/h", "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    assert!(
        out(&o).contains("verdict: not converged after N = 16") || out(&o).contains("verdict: converged"),
        "{}",
        out(&o)
    );
    assert_eq!(common::csv_rows(&tmp.path().join("runs/h/results.csv")).len(), 16);
}

#[test]
fn where_no_parameter_is_shown_to_matter_the_answer_does_not_rank_them() {
    // Ranges so narrow that the MFR's spread is the runs' noise: both intervals reach zero.
    let tmp = tempfile::tempdir().unwrap();
    sweep_file(tmp.path(), &|t| {
        t.replace("lo = 2.0, hi = 4.0", "lo = 3.0, hi = 3.01")
            .replace("lo = 1.2, hi = 1.6", "lo = 1.40, hi = 1.401")
    });
    let o = sweep_in(tmp.path(), &["lds", "t.toml", "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let text = out(&o);
    let m = text.lines().find(|l| l.starts_with("what matters: ")).unwrap_or_else(|| panic!("{text}"));
    assert!(m.starts_with("what matters: cannot rank yet: every parameter's"), "{m}");
    assert!(!m.contains(" > "), "{m}");
    // Where one interval stays clear of zero, the ranking is given.
    let tmp = tempfile::tempdir().unwrap();
    sweep_file(tmp.path(), &|t| t);
    let text = out(&sweep_in(tmp.path(), &["lds", "t.toml", "-q"]));
    let m = text.lines().find(|l| l.starts_with("what matters: ")).unwrap_or_else(|| panic!("{text}"));
    assert!(m.contains(" > ") && !m.contains("cannot rank"), "{m}");
}

#[test]
fn the_next_command_is_quoted_so_a_shell_runs_it_as_printed() {
    for (name, quoted) in [("ok name", "'runs/ok name'"), ("*", "'runs/*'")] {
        let tmp = tempfile::tempdir().unwrap();
        sweep_file(tmp.path(), &|t| t.replace("name = \"h\"", &format!("name = {name:?}")));
        // Something for a `runs/*` a shell expanded to match.
        std::fs::create_dir_all(tmp.path().join("runs/other")).unwrap();
        let o = sweep_in(tmp.path(), &["lds", "t.toml", "-q"]);
        assert_eq!(o.status.code(), Some(0), "{}", err(&o));
        let text = out(&o);
        let next = text.lines().find(|l| l.starts_with("next: ")).expect("a next line");
        let command = next.split('`').nth(1).expect("a command in backquotes");
        assert!(command.ends_with(&format!("--out {quoted}")), "{command}");
        // Pasted into a shell, with this `sweep` first on PATH: it extends the same directory.
        let bin = Path::new(common::SWEEP).parent().unwrap();
        let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
        let mut c = Command::new("sh");
        c.current_dir(tmp.path())
            .env("PATH", path)
            .arg("-c")
            .arg(format!("{command} -q"))
            .stdin(Stdio::null());
        let o = finish_within(c, Duration::from_secs(120));
        assert_eq!(o.status.code(), Some(0), "{command}: {}", err(&o));
        let rows = common::csv_rows(&tmp.path().join("runs").join(name).join("results.csv"));
        assert_eq!(rows.len(), 16, "{command}");
        assert!(!tmp.path().join("runs/other/results.csv").exists(), "{command} ran in the wrong directory");
    }
}

#[test]
fn a_recommended_setting_that_leaves_the_plate_bare_says_so_and_a_whole_layer_comes_first() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    for i in 0..8 {
        set_layer(&d, i, 0.3 + 0.05 * i as f64);
    }
    let best = recommended(&d);
    let o = sweep_in(tmp.path(), &["report", p(&d)]);
    let text = out(&o);
    let warning = text.lines().find(|l| l.starts_with("warning: ")).unwrap_or_else(|| panic!("{text}"));
    let covered = 0.3 + 0.05 * best as f64;
    assert!(
        warning.contains(&format!("leaves {:.0}% of the plate bare", (1.0 - covered) * 100.0)),
        "{warning}"
    );
    assert!(
        warning.contains("no tested setting gives a full layer: the most covered is point #7"),
        "{warning}"
    );
    let html = std::fs::read_to_string(d.join("report/report.html")).unwrap();
    let answer = html.find("The answer").expect("an answer block");
    assert!(answer < html.find("<h2>Convergence</h2>").unwrap(), "the answer comes first");
    assert!(html[answer..].contains("no tested setting gives a full layer"));
    // One point with a full layer: a whole layer before a higher MFR, so it is recommended, and
    // the answer warns of nothing.
    let other = (best + 1) % 8;
    set_layer(&d, other, 0.95);
    assert_eq!(recommended(&d), other);
    let text = out(&sweep_in(tmp.path(), &["report", p(&d)]));
    assert!(text.lines().next().unwrap().contains(&format!("(point #{other})")), "{text}");
    assert!(!text.contains("warning: "), "{text}");
    let summary = std::fs::read_to_string(d.join("summary.json")).unwrap();
    assert!(summary.contains("a whole layer before a higher MFR"), "the criterion says the rule");
}

#[test]
fn the_report_folds_the_tests_and_ranks_within_a_class_without_calling_it_best() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    let html = std::fs::read_to_string(d.join("report/report.html")).unwrap();
    assert!(html.contains("<details><summary>The rule's tests at lds 8"), "collapsed tests");
    assert!(
        !html.contains("Best inefficient") && !html.contains("Best ideal") && !html.contains("Best unstable")
    );
    assert!(html.contains("emulator: posterior median"));
}

#[test]
fn sweep_show_prints_the_standard_error_and_the_height_of_each_layer() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    let o = sweep_in(tmp.path(), &["show", p(&d), "0"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let text = out(&o);
    let r: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(d.join("runs").join(hash(&d, 0)).join("result.json")).unwrap(),
    )
    .unwrap();
    let se = r["mfr_se"].as_f64().unwrap();
    assert!(text.contains(&format!("± {se:.4} (SE)")), "{text}");
    let (gap, dia) =
        (r["parameters"]["gap"].as_f64().unwrap(), r["parameters"]["diameter"].as_f64().unwrap());
    for k in [1, 12] {
        let row = text.lines().find(|l| l.split_whitespace().next() == Some(&k.to_string())).unwrap();
        let z: f64 = row.split_whitespace().nth(1).unwrap().parse().unwrap();
        assert!((z - (gap + k as f64 * dia / 2.0)).abs() < 0.006, "layer {k}: {row}");
    }
}

#[test]
fn the_documented_verdict_is_worded_as_the_default_rule_says() {
    let read = |f: &str| std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(f)).unwrap();
    let usage = read("docs/usage.md");
    let rule = demsweep::analysis::convergence::Criteria::from_settings(&Default::default()).describe();
    assert!(
        usage.contains(&format!("by {rule}")),
        "docs/usage.md's verdict example is not the default rule's: {rule}"
    );
    for f in ["README.md", "docs/usage.md"] {
        assert!(!read(f).contains("mass flow rate"), "{f}: MFR is the mass flow ratio");
    }
}

#[test]
fn the_help_of_every_command_has_examples() {
    for cmd in [
        "lds", "lattice", "resume", "status", "report", "show", "points", "render", "run", "stats", "submit",
        "predict", "unclaim",
    ] {
        let o = sweep_in(Path::new("."), &[cmd, "--help"]);
        let text = out(&o);
        assert!(text.contains("Examples:\n  sweep "), "{cmd}: {text}");
    }
    let text = out(&sweep_in(Path::new("."), &["show", "--help"]));
    let dir = text.lines().find(|l| l.trim_start().starts_with("<DIR>")).unwrap();
    assert!(dir.contains("sweep directory"), "{dir}");
}
