//! `sweep points` end to end: bad sweep files and flags fail with exit code 2 and one line
//! naming the file and the key; good ones print the designs the thesis describes.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::SWEEP;

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn points(file: &Path, args: &[&str]) -> Output {
    Command::new(SWEEP).arg("points").arg(file).args(args).output().expect("run sweep")
}

/// A minimal valid sweep file; `extra` is appended (after `[parameters]` unless it opens a table).
const BASE: &str = "name = \"t\"\n[parameters]\nfriction = { lo = 0.1, hi = 0.3 }\n";

/// Run `sweep points` on `text` and check: exit code 2, exactly one stderr line, naming the
/// file and containing every one of `needles`.
fn rejects(text: &str, args: &[&str], needles: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bad-sweep.toml");
    std::fs::write(&file, text).unwrap();
    let out = points(&file, args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{text}\nstderr: {err}");
    assert!(out.stdout.is_empty(), "{text}: printed a design");
    assert_eq!(err.lines().count(), 1, "{text}\nstderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for needle in needles {
        assert!(err.contains(needle), "{text}\nstderr {err:?} lacks {needle:?}");
    }
}

#[test]
fn unknown_keys_are_named_with_a_suggestion() {
    rejects(
        "nmae = \"t\"\n[parameters]\nfriction = 0.2\n",
        &["--lds", "2"],
        &["bad-sweep.toml:1", "nmae", "did you mean `name`"],
    );
    rejects(
        &format!("{BASE}[design.lds]\nsed = 3\n"),
        &["--lds", "2"],
        &["bad-sweep.toml:5", "design.lds.sed", "did you mean `seed`"],
    );
    rejects(
        &format!("{BASE}[design]\nlatice_levels = [5]\n"),
        &["--lds", "2"],
        &["design.latice_levels", "did you mean `lattice_levels`"],
    );
    rejects(
        "name = \"t\"\n[parameters]\nfrction = { lo = 0.1, hi = 0.3 }\n",
        &["--lds", "2"],
        &["bad-sweep.toml", "parameters.frction", "did you mean `friction`"],
    );
    rejects(
        "name = \"t\"\n[parameters]\nfriction = { lo = 0.1, hii = 0.3 }\n",
        &["--lds", "2"],
        &["parameters.friction", "`hii`", "did you mean `hi`"],
    );
}

#[test]
fn values_that_make_no_sense_are_named() {
    let one = |param: &str| format!("name = \"t\"\n[parameters]\n{param}\n");
    // lo ≥ hi
    rejects(
        &one("friction = { lo = 0.3, hi = 0.3 }"),
        &["--lds", "2"],
        &["bad-sweep.toml", "parameters.friction", "lo = 0.3", "hi = 0.3"],
    );
    rejects(&one("gap = { lo = 5.0, hi = 1.0 }"), &["--lds", "2"], &["parameters.gap"]);
    // non-finite
    rejects(
        &one("friction = { lo = nan, hi = 0.3 }"),
        &["--lds", "2"],
        &["parameters.friction.lo", "finite"],
    );
    rejects(
        &one("diameter = { lo = 1.0, hi = inf }"),
        &["--lds", "2"],
        &["parameters.diameter.hi", "finite"],
    );
    // negative where it makes no sense, swept or fixed
    rejects(&one("diameter = { lo = -1.0, hi = 2.0 }"), &["--lds", "2"], &["parameters.diameter.lo", "-1"]);
    rejects(&format!("{BASE}gap = -2\n"), &["--lds", "2"], &["parameters.gap.value", "-2"]);
    rejects(
        &format!("{BASE}[convergence]\ntolerance = -0.1\n"),
        &["--lds", "2"],
        &["convergence.tolerance", "-0.1"],
    );
    rejects(
        &format!("{BASE}[design.lds]\nseed = -1\n"),
        &["--lds", "2"],
        &["bad-sweep.toml:5", "design.lds.seed", "-1"],
    );
    rejects(&format!("{BASE}[scene]\nparticles = -600\n"), &["--lds", "2"], &["scene.particles"]);
    // a log scale needs a positive range
    rejects(
        &one("friction = { lo = 0.0, hi = 0.3, scale = \"log\" }"),
        &["--lds", "2"],
        &["parameters.friction.scale", "lo > 0"],
    );
}

#[test]
fn empty_designs_are_refused() {
    // zero levels, and no levels at all
    rejects(
        &format!("{BASE}[design]\nlattice_levels = [5, 0]\n"),
        &["--lds", "2"],
        &["bad-sweep.toml", "design.lattice_levels[1]", "at least 2"],
    );
    rejects(&format!("{BASE}[design]\nlattice_levels = []\n"), &["--lds", "2"], &["design.lattice_levels"]);
    // N = 0 in the file and on the command line
    rejects(
        &format!("{BASE}[design.lds]\nmax = 0\n"),
        &["--lds", "2"],
        &["bad-sweep.toml", "design.lds.max", "positive"],
    );
    rejects(&format!("{BASE}[design.lds]\nstep = 0\n"), &["--lds", "2"], &["design.lds.step"]);
    rejects(BASE, &["--lds", "0"], &["--lds 0", "positive"]);
    rejects(BASE, &["--lattice", "1"], &["--lattice 1", "at least 2"]);
    // too many points is an error, not an out-of-memory abort
    rejects(
        "name = \"t\"\n[parameters]\nfriction = { lo = 0.1, hi = 0.3 }\n\
         gap = { lo = 1, hi = 5 }\ndiameter = { lo = 1, hi = 3 }\n",
        &["--lattice", "1000"],
        &["--lattice 1000", "1000^3"],
    );
}

#[test]
fn syntax_errors_and_missing_files() {
    rejects(&format!("{BASE}[design\nx = 1\n"), &["--lds", "2"], &["bad-sweep.toml:4"]);
    rejects("name = \"t\n", &["--lds", "2"], &["bad-sweep.toml:1"]);
    rejects(&format!("{BASE}friction = 0.2\n"), &["--lds", "2"], &["bad-sweep.toml:4", "friction"]);
    rejects(
        &format!("{BASE}[design.lds]\nscrambling = \"owen\"\n"),
        &["--lds", "2"],
        &["design.lds.scrambling", "braaten-weller"],
    );
    let missing = Path::new(env!("CARGO_MANIFEST_DIR")).join("no-such-sweep.toml");
    let out = points(&missing, &["--lds", "2"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("no-such-sweep.toml") && err.contains("no such file"), "{err}");
}

/// Parse `sweep points` CSV output into a header and rows.
fn csv(out: &Output) -> (Vec<String>, Vec<Vec<f64>>) {
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    (header, rows)
}

#[test]
fn thesis_lattices_have_n_to_the_4_points_and_both_ends() {
    let file = repo("sweeps/thesis-lattice.toml");
    let (header, rows) = csv(&points(&file, &["--lattice", "5"]));
    assert_eq!(header, ["friction", "diameter", "gap", "blade_speed"]);
    assert_eq!(rows.len(), 625);
    // Thesis Table 3.1 ranges, both ends exactly present.
    let ranges = [(0.1, 0.3), (1.0, 3.0), (1.0, 5.0), (1.2, 1.6)];
    for (k, (lo, hi)) in ranges.into_iter().enumerate() {
        let column: Vec<f64> = rows.iter().map(|r| r[k]).collect();
        assert!(column.contains(&lo) && column.contains(&hi), "{}", header[k]);
        assert!(column.iter().all(|&v| (lo..=hi).contains(&v)));
        // five distinct values per dimension
        let mut distinct = column.clone();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup();
        assert_eq!(distinct.len(), 5, "{}", header[k]);
    }
    let (_, rows) = csv(&points(&file, &["--lattice", "10"]));
    assert_eq!(rows.len(), 10_000);
}

#[test]
fn lds_prefixes_are_designs_and_discrepancy_goes_to_stderr() {
    let file = repo("sweeps/thesis-lds.toml");
    let (_, long) = csv(&points(&file, &["--lds", "60"]));
    let short = points(&file, &["--lds", "25", "--discrepancy"]);
    let (_, rows) = csv(&short);
    assert_eq!(rows[..], long[..25]);
    let err = String::from_utf8_lossy(&short.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    let cd: f64 = err.rsplit(' ').next().unwrap().trim().parse().unwrap();
    assert!(cd > 0.0 && cd < 0.1, "{err}");
    // --no-scramble is plain Halton from index 1: friction = 0.1 + 0.2·φ₂(1) = 0.2.
    let (_, plain) = csv(&points(&file, &["--lds", "3", "--no-scramble"]));
    assert!((plain[0][0] - 0.2).abs() < 1e-12);
    assert!((plain[1][0] - 0.15).abs() < 1e-12);
}

#[test]
fn screen_settings_that_make_no_sense_are_named() {
    let run = |body: &str| format!("{BASE}[run]\n{body}\n");
    rejects(
        &run("screen_sample = 1.5"),
        &["--lds", "2"],
        &["bad-sweep.toml", "run.screen_sample", "1.5", "[0, 1]"],
    );
    rejects(&run("screen_sample = -0.1"), &["--lds", "2"], &["run.screen_sample", "-0.1"]);
    rejects(&run("screen_sample = nan"), &["--lds", "2"], &["run.screen_sample", "NaN"]);
    rejects(&run("screen_sample_min = 0"), &["--lds", "2"], &["run.screen_sample_min", "at least 1"]);
    rejects(&run("screen = \"yes\""), &["--lds", "2"], &["bad-sweep.toml:5", "run.screen"]);
    rejects(&run("scren = true"), &["--lds", "2"], &["run.scren", "did you mean `screen`"]);
}

#[test]
fn a_bad_flag_or_a_control_character_is_one_line_and_changes_nothing() {
    // A flag's value clap cannot parse, and a missing argument: one line, exit 2.
    let o = Command::new(SWEEP).args(["points", "x.toml", "--lds", "many"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("--lds") && err.contains("many"), "{err}");
    let o = Command::new(SWEEP).args(["render", "x.toml"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!((o.status.code(), err.lines().count()), (Some(2), 1), "{err}");
    assert!(err.contains("--out"), "{err}");
    // A control character in the sweep's name (it becomes a directory and a report line).
    rejects(
        "name = \"a\\u0007b\"\n[parameters]\nfriction = { lo = 0.1, hi = 0.3 }\n",
        &[],
        &["name", "control characters"],
    );
    // A newline inside --set.
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(SWEEP)
        .current_dir(dir.path())
        .args([
            "render",
            repo("sweeps/quick.toml").to_str().unwrap(),
            "--set",
            "gap=3\nfriction=0.1",
            "--out",
            "deck",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!((o.status.code(), err.lines().count()), (Some(2), 1), "{err}");
    assert!(err.contains("--set") && err.contains("control characters"), "{err}");
    assert!(!dir.path().join("deck").exists());
}

#[test]
fn an_out_directory_that_cannot_be_made_is_bad_input() {
    // /proc takes no new directories, whatever access(2) tells root.
    let o = Command::new(SWEEP)
        .args(["lds", repo("sweeps/quick.toml").to_str().unwrap(), "--out", "/proc/sweep-out", "--plan"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!((o.status.code(), err.lines().count()), (Some(2), 1), "{err}");
    assert!(err.contains("/proc/sweep-out") && err.contains("cannot create it"), "{err}");
}
