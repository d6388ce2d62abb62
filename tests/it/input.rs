//! Bad input is refused before anything runs: sweep files (unknown keys, values that make no
//! sense, empty designs, syntax), flags, values in metres where the file wants mm, points of
//! millions of particles, and `--out` directories that cannot be made or written. Each exits 2
//! with one line naming the file, key, flag or value (and what was probably meant), writes
//! nothing — not even a LIGGGHTS log in the caller's directory — and never panics. `--force`
//! runs a slip anyway, and `--set` may set any parameter.

use std::path::Path;
use std::process::{Command, Stdio};

use crate::support::{self, cwd, lds_sweep, ok, points, repo, snapshot, stderr, text, Mount, SWEEP};

// ---- sweep files ----

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
fn sweeping_a_parameter_the_scene_does_not_read_is_refused() {
    // Each would have run points differing only in a number no deck reads.
    rejects(
        "name = \"t\"\n[parameters]\ngap = { lo = 0.1, hi = 0.3 }\n[scene]\nlayout = \"layers\"\n",
        &["--lds", "2"],
        &["bad-sweep.toml", "parameters.gap", "swept, but the layers layout", "layer_thickness"],
    );
    rejects(
        "name = \"t\"\n[parameters]\nheap_height = { lo = 1.0, hi = 3.0 }\n[scene]\nlayout = \"gated\"\n",
        &["--lds", "2"],
        &["parameters.heap_height", "swept, but the gated layout", "conveyor"],
    );
    rejects(
        "name = \"t\"\n[parameters]\nlayer_thickness = { lo = 0.05, hi = 0.1 }\n",
        &["--lds", "2"],
        &["parameters.layer_thickness", "swept, but the conveyor layout", "layers layout"],
    );
    rejects(
        "name = \"t\"\n[parameters]\nweibull_shape = { lo = 2.0, hi = 6.0 }\n",
        &["--lds", "2"],
        &["parameters.weibull_shape", "swept, but only a Weibull size distribution reads it"],
    );
    // What each layout does read is still swept.
    for (param, layout) in [
        ("layer_thickness = { lo = 0.05, hi = 0.1 }", "layers"),
        ("heap_height = { lo = 1.0, hi = 3.0 }", "conveyor"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("ok.toml");
        std::fs::write(
            &file,
            format!("name = \"t\"\n[parameters]\n{param}\n[scene]\nlayout = \"{layout}\"\n"),
        )
        .unwrap();
        let out = points(&file, &["--lds", "2"]);
        assert!(out.status.success(), "{layout}: {}", stderr(&out));
    }
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
    for bad in ["[\"median\"]", "[]"] {
        rejects(
            &format!("{BASE}[convergence]\nstatistics = {bad}\n"),
            &["--lds", "2"],
            &[
                "convergence.statistics",
                "expected one or more of \"mean\", \"std\", \"skewness\", \"kurtosis\"",
            ],
        );
    }
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

// ---- flags and the caller's directory ----

/// `sweep ARGS` in `cwd`: exit 2, one stderr line holding every needle, no panic, and nothing
/// in `cwd` changed. Returns the line.
fn refused(cwd: &Path, args: &[&str], needles: &[&str]) -> String {
    let before = snapshot(cwd);
    let o = support::sweep_bin().args(args).current_dir(cwd).stdin(Stdio::null()).output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}\nstderr: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}\nstderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: stderr {err:?} lacks {n:?}");
    }
    assert_eq!(snapshot(cwd), before, "{args:?} wrote in the caller's directory");
    err
}

#[test]
fn refused_commands_write_nothing_in_the_callers_directory_not_even_a_liggghts_log() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path().join("cwd");
    std::fs::create_dir(&cwd).unwrap();
    support::quick_lds_sweep(&cwd, "s", "");
    std::fs::write(cwd.join("a-file"), "not a directory").unwrap();
    let deck = tmp.path().join("deck");
    let deck = deck.to_str().unwrap();
    refused(&cwd, &["lds", "s.toml", "--step", "0"], &["--step 0", "positive"]);
    refused(&cwd, &["lds", "s.toml", "--max", "0"], &["--max 0", "positive"]);
    refused(&cwd, &["lds", "s.toml", "--max", "3", "--step", "4"], &["--max 3 is less than --step 4"]);
    refused(&cwd, &["lds", "s.toml", "--max", "1"], &["--max 1 is less than design.lds.step", "s.toml"]);
    refused(&cwd, &["lattice", "s.toml", "--levels", "1"], &["--levels", "level 1", "at least 2"]);
    refused(&cwd, &["lattice", "s.toml", "--levels", "3,2"], &["--levels 3,2", "increasing"]);
    refused(
        &cwd,
        &["render", "s.toml", "--set", "gap=3,gap=2.5", "--out", deck],
        &["--set gap", "given twice"],
    );
    refused(&cwd, &["run", "s.toml", "--set", "gap=3,gap=2.5"], &["--set gap", "given twice"]);
    refused(
        &cwd,
        &["render", "s.toml", "--set", "gapp=3", "--out", deck],
        &["--set gapp", "did you mean `gap`"],
    );
    refused(
        &cwd,
        &["render", "s.toml", "--set", "gap=3", "--out", "a-file"],
        &["--out a-file", "not a directory"],
    );
    refused(&cwd, &["lds", "s.toml", "--out", "a-file"], &["a-file", "exists and is not a directory"]);
    refused(&cwd, &["lds", "s.toml", "--out", "a-file/sub"], &["a-file/sub", "is not a directory"]);
    assert!(!Path::new(deck).exists());

    // A command that identifies the engine and succeeds writes only where it was told to.
    let before = snapshot(&cwd);
    let o = support::sweep_bin()
        .args(["render", "s.toml", "--set", "gap=3", "--out", deck])
        .current_dir(&cwd)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(snapshot(&cwd), before, "identifying LIGGGHTS wrote in the caller's directory");
    assert!(Path::new(deck).join("in.liggghts").exists());
}

#[test]
fn an_out_in_a_directory_that_cannot_be_written_is_bad_input_naming_the_path() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path().join("cwd");
    std::fs::create_dir(&cwd).unwrap();
    support::quick_lds_sweep(&cwd, "s", "");
    let ro = tmp.path().join("ro");
    // A read-only file system stops root too; without one, a mode-0555 directory stops others.
    let _mount = match Mount::tmpfs(&ro, "ro,size=64k") {
        Ok(m) => Some(m),
        Err(why) if unsafe { libc::geteuid() } != 0 => {
            eprintln!("no read-only tmpfs ({why}); using a mode-0555 directory");
            std::fs::create_dir_all(&ro).unwrap();
            std::fs::set_permissions(&ro, std::os::unix::fs::PermissionsExt::from_mode(0o555)).unwrap();
            None
        }
        Err(why) => {
            support::skip(
                "an_out_in_a_directory_that_cannot_be_written_is_bad_input_naming_the_path",
                &format!("running as root and cannot mount a read-only tmpfs: {why}"),
            );
            return;
        }
    };
    let new = ro.join("new/out");
    refused(
        &cwd,
        &["lds", "s.toml", "--out", new.to_str().unwrap()],
        &[new.to_str().unwrap(), &format!("cannot create it: {} is not writable", ro.display())],
    );
    refused(
        &cwd,
        &["lds", "s.toml", "--out", ro.to_str().unwrap()],
        &[ro.to_str().unwrap(), "cannot write in it"],
    );
    assert_eq!(std::fs::read_dir(&ro).unwrap().count(), 0);
}

// ---- values in the wrong unit, points too large ----

#[test]
fn a_gap_range_in_metres_is_refused_before_any_run_with_the_mm_it_meant() {
    let (_tmp, cwd) = cwd();
    lds_sweep(&cwd, "gap = { lo = 0.002, hi = 0.004 }\nblade_speed = { lo = 1.2, hi = 1.6 }\ndiameter = 1.5");
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
    lds_sweep(&cwd, "gap = { lo = 2.0, hi = 4.0 }\ndiameter = 0.0015");
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
    lds_sweep(&cwd, "gap = { lo = 2.0, hi = 4.0 }\nblade_speed = { lo = 1.2, hi = 1.6 }\ndiameter = 1.5");
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
    lds_sweep(&cwd, "gap = { lo = 0.002, hi = 0.004, unit = \"m\" }");
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
    lds_sweep(&cwd, "gap = { lo = 24.0, hi = 26.0 }\ndiameter = 0.02");
    let deck = tmp.path().join("deck");
    let err = refused(
        &cwd,
        &["render", "s.toml", "--out", deck.to_str().unwrap()],
        &[
            " particles at gap 25 mm, a heap of 20 mm and diameter 0.02 mm (gap = 1250 D): more than the 200000",
            "values are in mm",
        ],
    );
    let count: u64 = err.split(": ").nth(2).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(count > 5_000_000, "{err}");
    assert!(!deck.exists());
}

#[test]
fn a_held_heap_too_big_for_a_fine_powder_names_the_heap_and_the_powders_mean() {
    let (tmp, cwd) = cwd();
    // A 60 µm powder from a measured table, on the conveyor at its default millimetre heap: the
    // heap, not the gap, is what holds too many particles, and the `diameter` parameter (2 mm by
    // default) is not the powder's size.
    lds_sweep(
        &cwd,
        "blade_speed = { lo = 0.05, hi = 0.2 }\ngap = 0.1\n[scene.size_distribution]\nkind = \"classes\"\n\
         classes = [[0.06, 1.0]]",
    );
    let deck = tmp.path().join("deck");
    let err = refused(
        &cwd,
        &["render", "s.toml", "--out", deck.to_str().unwrap()],
        &["at gap 0.1 mm, a heap of ", "the size distribution's mean 0.06 mm", "lower the heap_height"],
    );
    assert!(!err.contains("diameter 2 mm"), "{err}");
    assert!(!deck.exists());
}

#[test]
fn force_renders_a_slip_and_set_takes_any_parameter() {
    let (tmp, cwd) = cwd();
    lds_sweep(&cwd, "gap = { lo = 2.0, hi = 4.0 }\nblade_speed = { lo = 1.2, hi = 1.6 }\ndiameter = 1.5");
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

// ---- size distributions, layouts, calibration targets ----

#[test]
fn a_size_distribution_of_more_classes_than_a_deck_can_take_is_refused_at_once() {
    // 100,000 bins kept `sweep lds` planning for 11 minutes, deaf to SIGINT.
    let lognormal =
        "[scene.size_distribution]\nkind = \"lognormal\"\nd10_um = 20.0\nd50_um = 31.0\nd90_um = 42.0\n";
    rejects(
        &format!("{BASE}{lognormal}bins = 100000\n"),
        &["--lds", "2"],
        &["bad-sweep.toml", "scene.size_distribution.bins", "100000", "expected 2 to 100"],
    );
    rejects(
        &format!("{BASE}[scene.size_distribution]\nkind = \"weibull\"\nbins = 101\n"),
        &["--lds", "2"],
        &["scene.size_distribution.bins", "101: expected 1 to 100"],
    );
    let many: Vec<String> = (1..=101).map(|i| format!("[{}, 1.0]", 0.01 + i as f64 * 0.001)).collect();
    rejects(
        &format!("{BASE}[scene.size_distribution]\nkind = \"classes\"\nclasses = [{}]\n", many.join(", ")),
        &["--lds", "2"],
        &["scene.size_distribution.classes", "101 classes: expected 1 to 100"],
    );
    // The largest allowed plans in a moment.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("s.toml");
    std::fs::write(&file, format!("{BASE}{lognormal}bins = 100\n")).unwrap();
    let out = points(&file, &["--lds", "2"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn a_key_a_monodisperse_powder_does_not_take_is_refused_not_dropped() {
    let mono = |key: &str| format!("{BASE}[scene.size_distribution]\nkind = \"mono\"\n{key}\n");
    rejects(
        &mono("classes = [[0.02, 0.5], [0.04, 0.5]]"),
        &["--lds", "2"],
        &["bad-sweep.toml", "scene.size_distribution.classes", "not a key of kind = \"mono\""],
    );
    rejects(&mono("d50um = 31"), &["--lds", "2"], &["scene.size_distribution.d50um", "\"mono\""]);
}

#[test]
fn a_classes_table_that_misses_its_total_repeats_a_size_or_holds_dust_is_refused() {
    let classes = |c: &str| format!("{BASE}[scene.size_distribution]\nkind = \"classes\"\nclasses = {c}\n");
    for (table, sum) in [("[[0.02, 0.1], [0.04, 0.2]]", "0.3"), ("[[0.02, 0.4], [0.04, 0.4]]", "0.8")] {
        rejects(
            &classes(table),
            &["--lds", "2"],
            &[
                "scene.size_distribution.classes",
                &format!("fractions sum to {sum}"),
                "expected 1 (fractions) or 100 (%)",
            ],
        );
    }
    rejects(
        &classes("[[0.02, 0.5], [0.02, 0.5]]"),
        &["--lds", "2"],
        &["scene.size_distribution.classes[1]", "diameter 0.02 is also class [0]"],
    );
    rejects(
        &classes("[[0.003, 0.2], [0.05, 0.8]]"),
        &["--lds", "2"],
        &["scene.size_distribution.classes[0]", "0.003 mm is below the 10 µm", "did you mean 3?"],
    );
    // A measured table in % with its rounding, and fractions, pass.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("s.toml");
    for ok in ["[[0.02, 30.1], [0.04, 70.3]]", "[[0.02, 0.3], [0.04, 0.7]]", "[[0.5, 0.5], [1.5, 0.5]]"] {
        std::fs::write(&file, classes(ok)).unwrap();
        let out = points(&file, &["--lds", "2"]);
        assert!(out.status.success(), "{ok}: {}", String::from_utf8_lossy(&out.stderr));
    }
}

#[test]
fn a_scene_key_only_other_layouts_read_is_refused_naming_them_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let write = |layout: &str, key: &str| {
        let scene = format!("[scene]\nlayout = \"{layout}\"\n{key}\n");
        std::fs::write(dir.path().join("x.toml"), format!("{BASE}{scene}")).unwrap();
    };
    let tail = "(remove the key, or change the layout)";
    for (layout, key, why) in [
        ("conveyor", "bed = \"fused\"", "scene.bed: \"fused\" is read only by the layers layout"),
        ("layers", "block_diameters = 7", "scene.block_diameters: 7.0 is read only by the conveyor layout"),
        ("layers", "warmup_s = 0.1", "scene.warmup_s: 0.1 is read only by the conveyor layout"),
        (
            "pour",
            "window_diameters = 60",
            "scene.window_diameters: 60.0 is read only by the gated and thesis layouts",
        ),
        (
            "gated",
            "warm_start = true",
            "scene.warm_start: true is read only by the conveyor and layers layouts",
        ),
    ] {
        write(layout, key);
        for args in [&["render", "x.toml", "--out", "o"][..], &["lds", "x.toml", "--out", "o", "--plan"]] {
            let out = support::sweep_bin()
                .current_dir(dir.path())
                .args(args)
                .stdin(Stdio::null())
                .output()
                .unwrap();
            assert_eq!(out.status.code(), Some(2), "{layout} {key} {args:?}: {}", stderr(&out));
            assert_eq!(
                stderr(&out),
                format!("error: x.toml: {why}; this sweep's layout is {layout} {tail}\n")
            );
            assert!(!dir.path().join("o").exists(), "{layout} {key} {args:?} wrote its --out");
        }
    }
    // At its default (a resolved DIR/sweep.toml writes every key), or where the layout reads it,
    // the key is taken.
    for (layout, key) in
        [("conveyor", "bed = \"loose\""), ("layers", "bed = \"fused\""), ("conveyor", "block_diameters = 7")]
    {
        write(layout, key);
        let out = points(&dir.path().join("x.toml"), &["--lds", "2"]);
        assert!(out.status.success(), "{layout} {key}: {}", stderr(&out));
    }
    // A misspelt key is still serde's, with its line and what was meant.
    rejects(
        &format!("{BASE}[scene]\nlayout = \"conveyor\"\nbedd = \"fused\"\n"),
        &["--lds", "2"],
        &["bad-sweep.toml:6", "scene.bedd", "unknown field `bedd`", "did you mean `bed`?"],
    );
}

#[test]
fn a_pour_on_a_bed_of_powder_is_refused_naming_the_layouts_that_read_a_substrate() {
    rejects(
        &format!("{BASE}[scene]\nlayout = \"pour\"\nsubstrate = \"powder\"\n"),
        &["--lds", "2"],
        &[
            "bad-sweep.toml",
            "scene.substrate",
            "\"powder\"",
            "the gated and conveyor layouts",
            "layout is pour",
        ],
    );
}

#[test]
fn a_missing_template_is_named_by_its_sweep_file_and_key_before_anything_is_said_to_run() {
    let dir = tempfile::tempdir().unwrap();
    for engine in ["", "[run]\nengine = \"stand-in\"\n"] {
        let file = dir.path().join("t.toml");
        std::fs::write(
            &file,
            format!("name = \"t\"\n[parameters]\ngap = {{ lo = 2.0, hi = 3.0 }}\n[scene]\ntemplate = \"nowhere.tera\"\n{engine}"),
        )
        .unwrap();
        for cmd in ["render", "run"] {
            let out = support::sweep_bin()
                .current_dir(dir.path())
                .args([cmd, "t.toml", "--set", "gap=2.5", "--out", "o"])
                .stdin(Stdio::null())
                .output()
                .unwrap();
            let err = stderr(&out);
            assert_eq!(out.status.code(), Some(2), "{cmd} {engine:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{cmd} {engine:?}: {err}");
            assert!(
                err.contains("t.toml") && err.contains("scene.template") && err.contains("nowhere.tera"),
                "{err}"
            );
            assert!(!dir.path().join("o").exists(), "{cmd} wrote its --out");
        }
    }
}
