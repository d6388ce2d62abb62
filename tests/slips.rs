//! A newcomer's slips: values in metres where the sweep file wants mm, in a range, in a fixed
//! value, in `--set` and in a `unit`; a point of ten million particles; a misspelt `--set`.
//! Each is refused before anything runs: exit 2, one line naming the value, its unit and what
//! was probably meant, and nothing written (not even in the caller's directory). `--force`
//! runs it anyway, and `--set` may set any parameter.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn sweep_bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sweep"))
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// The quick scene with `parameters` as written, in `dir/s.toml`.
fn write_sweep(dir: &Path, parameters: &str) -> PathBuf {
    let body = format!("name = \"s\"\n[parameters]\n{parameters}\n[design.lds]\nstep = 2\nmax = 4\n");
    let path = dir.join("s.toml");
    std::fs::write(&path, body).unwrap();
    path
}

/// Every path under `dir` with its contents.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p.clone());
                out.insert(p, Vec::new());
            } else {
                out.insert(p.clone(), std::fs::read(&p).unwrap_or_default());
            }
        }
    }
    out
}

/// `sweep ARGS` in `cwd`: exit 2, one stderr line holding every needle, nothing in `cwd` changed.
fn refused(cwd: &Path, args: &[&str], needles: &[&str]) -> String {
    let before = snapshot(cwd);
    let o = sweep_bin().args(args).current_dir(cwd).stdin(Stdio::null()).output().unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}\nstderr: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}\nstderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: stderr {err:?} lacks {n:?}");
    }
    assert_eq!(snapshot(cwd), before, "{args:?} wrote in the caller's directory");
    err
}

fn ok(cwd: &Path, args: &[&str]) -> Output {
    let o = sweep_bin().args(args).current_dir(cwd).stdin(Stdio::null()).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{args:?}\nstderr: {}", text(&o.stderr));
    o
}

fn cwd() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path().join("cwd");
    std::fs::create_dir(&cwd).unwrap();
    (tmp, cwd)
}

#[test]
fn a_gap_range_in_metres_is_refused_before_any_run_with_the_mm_it_meant() {
    let (_tmp, cwd) = cwd();
    write_sweep(
        &cwd,
        "gap = { lo = 0.002, hi = 0.004 }\nblade_speed = { lo = 1.2, hi = 1.6 }\ndiameter = 1.5",
    );
    for cmd in ["lds", "lattice"] {
        let err = refused(
            &cwd,
            &[cmd, "s.toml", "--out", "runs/s"],
            &["s.toml", "gap 0.00", " mm: below 0.1 D", "values are in mm — did you mean ", "--force"],
        );
        // The suggestion is the value × 1000: 2 to 4 mm.
        let meant: f64 =
            err.split("did you mean ").nth(1).unwrap().split('?').next().unwrap().parse().unwrap();
        assert!((2.0..=4.0).contains(&meant), "{err}");
    }
    assert!(!cwd.join("runs").exists());
}

#[test]
fn a_fixed_diameter_in_metres_is_refused_by_render_and_run() {
    let (tmp, cwd) = cwd();
    write_sweep(&cwd, "gap = { lo = 2.0, hi = 4.0 }\ndiameter = 0.0015");
    let deck = tmp.path().join("deck");
    let needles = ["diameter 0.0015 mm: below the 10 µm", "values are in mm — did you mean 1.5?"];
    refused(&cwd, &["render", "s.toml", "--out", deck.to_str().unwrap()], &needles);
    refused(&cwd, &["run", "s.toml"], &needles);
    refused(&cwd, &["lds", "s.toml"], &needles);
    assert!(!deck.exists(), "render wrote {}", deck.display());
}

#[test]
fn a_set_in_metres_names_the_set_and_the_mm_it_meant() {
    let (tmp, cwd) = cwd();
    write_sweep(&cwd, "gap = { lo = 2.0, hi = 4.0 }\nblade_speed = { lo = 1.2, hi = 1.6 }\ndiameter = 1.5");
    let deck = tmp.path().join("deck");
    let needles = ["--set gap=0.003", "gap 0.003 mm", "values are in mm — did you mean 3?"];
    refused(&cwd, &["run", "s.toml", "--set", "gap=0.003"], &needles);
    refused(&cwd, &["render", "s.toml", "--set", "gap=0.003", "--out", deck.to_str().unwrap()], &needles);
    assert!(!deck.exists());
    // A misspelt name gets a suggestion, from every parameter the scene knows.
    refused(&cwd, &["run", "s.toml", "--set", "gpa=3"], &["--set gpa", "did you mean `gap`"]);
    refused(&cwd, &["run", "s.toml", "--set", "diamter=1"], &["--set diamter", "did you mean `diameter`"]);
}

#[test]
fn a_unit_in_metres_says_what_to_write_instead() {
    let (_tmp, cwd) = cwd();
    write_sweep(&cwd, "gap = { lo = 0.002, hi = 0.004, unit = \"m\" }");
    refused(
        &cwd,
        &["points", "s.toml"],
        &["parameters.gap.unit", "values are in mm — did you mean lo = 2, hi = 4, unit = \"mm\"?"],
    );
}

#[test]
fn a_point_of_millions_of_particles_is_refused_with_its_count() {
    let (tmp, cwd) = cwd();
    // D = 20 µm is inside the bounds; a 25 mm gap over it is a heap 1,260 D tall.
    write_sweep(&cwd, "gap = { lo = 24.0, hi = 26.0 }\ndiameter = 0.02");
    let deck = tmp.path().join("deck");
    let err = refused(
        &cwd,
        &["render", "s.toml", "--out", deck.to_str().unwrap()],
        &[
            " particles at gap 25 mm and diameter 0.02 mm (gap = 1250 D): more than the 200000",
            "values are in mm",
        ],
    );
    let count: u64 = err.split(": ").nth(2).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(count > 5_000_000, "{err}");
    assert!(!deck.exists());
}

#[test]
fn force_renders_a_slip_and_set_takes_any_parameter() {
    let (tmp, cwd) = cwd();
    write_sweep(&cwd, "gap = { lo = 2.0, hi = 4.0 }\nblade_speed = { lo = 1.2, hi = 1.6 }\ndiameter = 1.5");
    let deck = tmp.path().join("deck");
    let d = deck.to_str().unwrap();
    let o = ok(&cwd, &["render", "s.toml", "--set", "gap=0.003", "--out", d, "--force"]);
    assert!(deck.join("in.liggghts").exists(), "{}", text(&o.stderr));
    // A fixed parameter and a value outside the sweep's range: one point, said so.
    let o = ok(&cwd, &["render", "s.toml", "--set", "diameter=1.2,gap=5", "--out", d]);
    let err = text(&o.stderr);
    assert!(err.contains("note: --set gap=5: outside the sweep's range [2, 4] mm"), "{err}");
    let deck_text = std::fs::read_to_string(deck.join("in.liggghts")).unwrap();
    assert!(
        deck_text.contains("diameter = 1.2 mm") && deck_text.contains("gap = 5 mm"),
        "deck header: {deck_text}"
    );
}

#[test]
fn points_prints_the_files_design_and_round_values() {
    let (_tmp, cwd) = cwd();
    write_sweep(&cwd, "friction = { lo = 0.1, hi = 0.5 }\ngap = { lo = 2.0, hi = 4.0 }");
    let o = ok(&cwd, &["points", "s.toml"]);
    let out = text(&o.stdout);
    assert_eq!(out.lines().count(), 1 + 4, "design.lds.max = 4 points:\n{out}");
    let o = ok(&cwd, &["points", "s.toml", "--lattice", "3"]);
    let out = text(&o.stdout);
    assert!(out.lines().any(|l| l.starts_with("0.3,")), "{out}");
    assert!(!out.contains("0000000"), "float noise printed:\n{out}");
}
