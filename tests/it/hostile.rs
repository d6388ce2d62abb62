//! What a hostile run found, each defect with its regression test: values the stand-in engine
//! let through, implausible speeds and densities, names that cannot be directories, edited or
//! replaced files of a sweep directory (manifest, sweep.toml, result.json, joblog, runs/), and
//! the lines written for another host's attempt, a `[cluster]` prologue. All on the stand-in
//! engine: no LIGGGHTS needed.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::support::{self as common, p, stderr as err};

pub(crate) fn sweep_in(cwd: &Path, args: &[&str]) -> Output {
    let mut c = Command::new(common::SWEEP);
    c.current_dir(cwd).args(args).stdin(Stdio::null());
    finish_within(c, common::GUARD)
}

/// Run `c` to its end, failing the test (and killing it) if it takes longer than `limit`: a
/// read of a FIFO or of /dev/zero must not hang.
pub(crate) fn finish_within(mut c: Command, limit: Duration) -> Output {
    let child = c.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let pid = child.id();
    let start = Instant::now();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    loop {
        if let Ok(o) = rx.recv_timeout(Duration::from_millis(100)) {
            return o.unwrap();
        }
        if start.elapsed() > limit {
            // SAFETY: kill(2) of the child we spawned.
            unsafe { libc::kill(pid as i32, libc::SIGKILL) };
            panic!("{c:?} still running after {limit:?}");
        }
    }
}

pub(crate) fn out(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A 2-D stand-in sweep of 8 points with `edit` applied to its text, in `dir/t.toml`.
pub(crate) fn sweep_file(dir: &Path, edit: &dyn Fn(String) -> String) -> PathBuf {
    let text = r#"name = "h"
[parameters]
gap         = { lo = 2.0, hi = 4.0, unit = "mm" }
blade_speed = { lo = 1.2, hi = 1.6, unit = "m/s" }
diameter    = { value = 1.5, unit = "mm" }
[design.lds]
step = 4
max = 8
[run]
engine = "stand-in"
"#;
    let path = dir.join("t.toml");
    std::fs::write(&path, edit(text.to_string())).unwrap();
    path
}

/// Every entry under `dir`, recursively, as paths relative to it.
fn tree(dir: &Path) -> Vec<String> {
    fn walk(root: &Path, d: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(d).unwrap().flatten() {
            out.push(e.path().strip_prefix(root).unwrap().display().to_string());
            if e.file_type().unwrap().is_dir() {
                walk(root, &e.path(), out);
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// Exit 2 with one line holding every needle, and nothing written next to the sweep file.
fn refused(dir: &Path, args: &[&str], needles: &[&str]) {
    let before = tree(dir);
    let o = sweep_in(dir, args);
    let e = err(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
    assert_eq!(e.lines().count(), 1, "{args:?}: {e}");
    for n in needles {
        assert!(e.contains(n), "{args:?}: {e:?} lacks {n:?}");
    }
    assert_eq!(tree(dir), before, "{args:?} wrote something");
}

// ---- the stand-in engine checks what LIGGGHTS's executor checks ----

#[test]
fn the_stand_in_refuses_what_liggghts_would_refuse() {
    let cases: Vec<(&str, &str, &str)> = vec![
        ("lo = 2.0, hi = 4.0", "lo = 0.002, hi = 0.004", "did you mean"),
        ("value = 1.5", "value = 0.0015", "diameter 0.0015 mm"),
        ("hi = 4.0", "hi = 1e300", "particles"),
        ("[run]", "[scene]\ntemplate = \"missing.tera\"\n[run]", "missing.tera"),
    ];
    for (from, to, needle) in cases {
        let tmp = tempfile::tempdir().unwrap();
        sweep_file(tmp.path(), &|t| t.replace(from, to));
        for cmd in ["lds", "lattice"] {
            refused(tmp.path(), &[cmd, "t.toml", "-q"], &["t.toml", needle]);
        }
    }
}

#[test]
fn blade_speed_and_density_outside_what_a_recoater_runs_are_refused_naming_the_slip() {
    let cases: Vec<(&str, &str, Vec<&str>)> = vec![
        ("lo = 1.2, hi = 1.6", "lo = 1200, hi = 1600", vec!["blade_speed", "m/s", "written in mm/s"]),
        ("[design.lds]", "density = 7.98\n[design.lds]", vec!["density 7.98", "did you mean 7980"]),
        ("[design.lds]", "density = 1e30\n[design.lds]", vec!["density 1e30", "kg/m3"]),
        ("[design.lds]", "density = 1e-3\n[design.lds]", vec!["density 0.001"]),
    ];
    for (from, to, needles) in cases {
        let tmp = tempfile::tempdir().unwrap();
        sweep_file(tmp.path(), &|t| t.replace(from, to));
        refused(tmp.path(), &["lds", "t.toml", "-q"], &needles);
        // --force runs such a point anyway.
        let o = sweep_in(tmp.path(), &["lds", "t.toml", "-q", "--force"]);
        assert_ne!(o.status.code(), Some(2), "{to}: {}", err(&o));
    }
    // A real recoater's speed and a polymer's density pass.
    let tmp = tempfile::tempdir().unwrap();
    sweep_file(tmp.path(), &|t| {
        t.replace("lo = 1.2, hi = 1.6", "lo = 0.05, hi = 0.2")
            .replace("[design.lds]", "density = 1050\n[design.lds]")
    });
    let o = sweep_in(tmp.path(), &["lds", "t.toml", "-q"]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", err(&o));
}

// ---- names ----

#[test]
fn a_name_too_long_for_a_directory_is_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let long = "a".repeat(300);
    sweep_file(tmp.path(), &|t| t.replace("name = \"h\"", &format!("name = \"{long}\"")));
    refused(tmp.path(), &["lds", "t.toml", "-q"], &["t.toml", "name", "300 bytes"]);
    assert!(!tmp.path().join("runs").exists());
}

#[test]
fn invisible_formatting_characters_in_a_name_are_refused() {
    for c in ["\\u202e", "\\u200b", "\\u2066", "\\ufeff"] {
        let tmp = tempfile::tempdir().unwrap();
        sweep_file(tmp.path(), &|t| t.replace("name = \"h\"", &format!("name = \"a{c}b\"")));
        refused(tmp.path(), &["lds", "t.toml", "-q"], &["t.toml", "name", "invisible"]);
    }
}

// ---- one point ----

#[test]
fn sweep_run_checks_the_bounds_before_the_engine_and_runs_the_stand_in() {
    let tmp = tempfile::tempdir().unwrap();
    sweep_file(tmp.path(), &|t| t);
    // A slip is bad input (2), not a missing engine (3).
    refused(tmp.path(), &["run", "t.toml", "--set", "gap=0.003"], &["--set gap=0.003", "did you mean 3"]);
    refused(tmp.path(), &["render", "t.toml", "--set", "gap=0.003", "--out", "deck"], &["did you mean 3"]);
    let o = sweep_in(tmp.path(), &["run", "t.toml", "--set", "gap=3"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let text = out(&o);
    // The parameters used, with where each came from; v_x with its heights.
    assert!(text.contains("gap = 3 mm (--set)"), "{text}");
    assert!(text.contains("blade_speed = 1.4 m/s (middle of 1.2–1.6)"), "{text}");
    let z = text.lines().find(|l| l.trim_start().starts_with("z (mm)")).expect("a row of heights");
    let heights: Vec<f64> = z.split_whitespace().skip(2).map(|v| v.parse().unwrap()).collect();
    // Layer k at gap + k·D/2: 3.75, 4.5, ... 12 mm at D = 1.5 mm, gap 3 mm.
    let expected: Vec<f64> = (1..=12).map(|k| 3.0 + k as f64 * 0.75).collect();
    assert_eq!(heights, expected, "{text}");
    let vx = text.lines().find(|l| l.trim_start().starts_with("v_x (m/s)")).expect("a row of v_x");
    assert_eq!(vx.split_whitespace().count(), 2 + 12, "{text}");
}

#[test]
fn predict_refuses_a_parameter_set_twice() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    let o = sweep_in(tmp.path(), &["predict", p(&d), "--set", "gap=2.5,gap=2.6"]);
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert!(err(&o).contains("--set gap: given twice (2.5 and 2.6)"), "{}", err(&o));
}

// ---- the sweep directory, edited or replaced ----

/// A finished 8-point stand-in sweep in `dir/d`.
pub(crate) fn finished(dir: &Path) -> PathBuf {
    sweep_file(dir, &|t| t);
    let d = dir.join("d");
    let o = sweep_in(dir, &["lds", "t.toml", "--out", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    d
}

fn manifest(d: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(d.join("manifest.json")).unwrap()).unwrap()
}

pub(crate) fn hash(d: &Path, i: usize) -> String {
    manifest(d)["points"][i]["hash"].as_str().unwrap().to_string()
}

#[test]
fn a_fixed_value_edited_in_the_directory_sweep_file_is_named_by_its_key() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    let path = d.join("sweep.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let at = text.find("[parameters.diameter]").unwrap();
    let edited = format!("{}{}", &text[..at], text[at..].replacen("value = 1.5", "value = 1.6", 1));
    assert_ne!(edited, text);
    std::fs::write(&path, edited).unwrap();
    let o = sweep_in(tmp.path(), &["resume", p(&d), "-q"]);
    let e = err(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("sweep.toml: parameters.diameter.value = 1.6 (the sweep ran with 1.5)"), "{e}");
    assert!(!e.contains("engine or templates"), "{e}");
}

#[cfg(unix)]
fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo on a NUL-terminated path we own.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
}

#[test]
fn a_manifest_that_is_a_fifo_or_a_device_is_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    let m = d.join("manifest.json");
    for (make, what) in [
        (&(|m: &Path| mkfifo(m)) as &dyn Fn(&Path), "a FIFO"),
        (&|m: &Path| std::os::unix::fs::symlink("/dev/zero", m).unwrap(), "a device"),
    ] {
        std::fs::remove_file(&m).unwrap();
        make(&m);
        for cmd in ["status", "report", "resume"] {
            let o = sweep_in(tmp.path(), &[cmd, p(&d)]);
            assert_eq!(o.status.code(), Some(2), "{cmd}: {}", err(&o));
            assert!(err(&o).contains("manifest.json") && err(&o).contains(what), "{cmd}: {}", err(&o));
        }
    }
}

#[test]
fn a_sweep_file_or_include_that_is_a_fifo_a_device_or_huge_is_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    mkfifo(&dir.join("fifo.toml"));
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.toml")).unwrap();
    // 3 GB on disk's books, no blocks: read whole, it would take the memory of it.
    std::fs::File::create(dir.join("huge.toml")).unwrap().set_len(3 << 30).unwrap();
    let including = |name: &str| {
        let file = format!("inc-{name}");
        sweep_file(dir, &|t| t.replace("[parameters]", &format!("include = [\"{name}\"]\n[parameters]")));
        std::fs::rename(dir.join("t.toml"), dir.join(&file)).unwrap();
        file
    };
    let cases = [
        ("fifo.toml".to_string(), "a FIFO, not a regular file"),
        ("zero.toml".to_string(), "a device, not a regular file"),
        ("huge.toml".to_string(), "over the 16777216 expected at most"),
        (including("fifo.toml"), "include: cannot read"),
        (including("zero.toml"), "a device, not a regular file"),
        (including("huge.toml"), "over the 16777216 expected at most"),
    ];
    for (file, says) in &cases {
        for args in [
            vec!["run", file.as_str(), "--set", "gap=3,blade_speed=1.4"],
            vec!["points", file.as_str(), "--lds", "4"],
            vec!["lds", file.as_str(), "--plan", "--out", "planned"],
            vec!["render", file.as_str(), "--set", "gap=3,blade_speed=1.4", "--out", "deck"],
        ] {
            let mut c = Command::new(common::SWEEP);
            c.current_dir(dir).args(&args).stdin(Stdio::null());
            let o = finish_within(c, common::GUARD);
            let e = err(&o);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
            assert!(e.contains(file.as_str()) && e.contains(says), "{args:?}: {e}");
            assert_eq!(e.lines().count(), 1, "{args:?}: {e}");
        }
    }
    assert!(!dir.join("planned").exists() && !dir.join("deck").exists());
}

#[test]
fn a_result_that_is_a_fifo_or_a_device_is_not_read_and_the_point_runs_again() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    for make in [&(|r: &Path| mkfifo(r)) as &dyn Fn(&Path), &|r: &Path| {
        std::os::unix::fs::symlink("/dev/zero", r).unwrap()
    }] {
        let r = d.join("runs").join(hash(&d, 0)).join("result.json");
        std::fs::remove_file(&r).unwrap();
        make(&r);
        let o = sweep_in(tmp.path(), &["status", p(&d)]);
        assert!(out(&o).contains("pending  1"), "{}{}", out(&o), err(&o));
        let o = sweep_in(tmp.path(), &["report", p(&d)]);
        assert!(err(&o).contains("not a regular file"), "{}", err(&o));
        let o = sweep_in(tmp.path(), &["resume", p(&d), "-q"]);
        assert_eq!(o.status.code(), Some(0), "{}", err(&o));
        assert!(std::fs::symlink_metadata(&r).unwrap().is_file(), "run again, its result written");
    }
}

/// Edit point 0's result.json with `f`; the point must count as not done, with a warning
/// holding `needle`, and run again on resume.
fn damaged_result(f: &dyn Fn(&mut serde_json::Value), needle: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    let r = d.join("runs").join(hash(&d, 0)).join("result.json");
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&r).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(&r, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let o = sweep_in(tmp.path(), &["status", p(&d)]);
    let text = out(&o);
    assert!(text.contains("done     7") && text.contains("pending  1"), "{needle}: {text}");
    assert!(text.contains(needle), "{needle}: {text}");
    let o = sweep_in(tmp.path(), &["report", p(&d)]);
    assert!(err(&o).contains(needle), "{needle}: {}", err(&o));
    let o = sweep_in(tmp.path(), &["resume", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let rows = common::csv_rows(&d.join("results.csv"));
    assert!(rows.iter().all(|r| r["status"] == "done"), "{rows:?}");
    let again: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&r).unwrap()).unwrap();
    assert_eq!(again["format"], 1);
    assert_eq!(again["vx"].as_array().unwrap().len(), 12);
}

#[test]
fn a_result_of_another_format_is_not_counted_as_done() {
    damaged_result(&|v| v["format"] = 2.into(), "format 2: expected 1");
}

#[test]
fn a_result_that_is_not_steady_is_not_counted_as_done() {
    damaged_result(&|v| v["steady"] = false.into(), "steady = false");
}

#[test]
fn a_result_with_too_few_vx_layers_is_not_counted_as_done() {
    damaged_result(&|v| v["vx"] = serde_json::json!([1.0, 1.1]), "vx: 2 layers, expected 12");
}

#[test]
fn a_result_whose_fixed_parameter_is_not_the_sweep_s_or_missing_is_not_counted_as_done() {
    damaged_result(
        &|v| v["parameters"]["diameter"] = 0.9.into(),
        "its fixed diameter = 0.9 is not the sweep's 1.5",
    );
    damaged_result(
        &|v| {
            v["parameters"].as_object_mut().unwrap().remove("diameter");
        },
        "it does not give the fixed diameter (the sweep's is 1.5)",
    );
}

#[test]
fn a_huge_number_in_a_result_is_named_in_a_few_characters() {
    damaged_result(&|v| v["answer_windows"][0] = 1e300.into(), "answer_windows[0] = 1e300: expected");
}

#[test]
fn a_symbolic_link_where_a_run_directory_belongs_is_refused_and_nothing_is_written_through_it() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    let h = hash(&d, 0);
    let run = d.join("runs").join(&h);
    std::fs::remove_dir_all(&run).unwrap();
    let outside = tmp.path().join("outside");
    std::fs::create_dir(&outside).unwrap();
    std::os::unix::fs::symlink(&outside, &run).unwrap();
    let o = sweep_in(tmp.path(), &["resume", p(&d), "-q"]);
    let e = err(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains(&format!("runs/{h}: a symbolic link")) && e.contains("remove the link"), "{e}");
    assert!(tree(&outside).is_empty(), "written outside the sweep directory: {:?}", tree(&outside));
}

#[test]
fn an_edited_hash_or_values_in_the_manifest_is_refused_naming_the_point() {
    type Edit<'a> = &'a dyn Fn(&mut serde_json::Value);
    let cases: Vec<(Edit, &str)> = vec![
        (&|m| m["points"][3]["hash"] = "0".repeat(64).into(), "points[3].values or points[3].hash"),
        (&|m| m["points"][2]["values"][0] = 2.5.into(), "points[2].values or points[2].hash"),
        (
            &|m| {
                let h1 = m["points"][1]["hash"].clone();
                m["points"][1]["hash"] = m["points"][5]["hash"].clone();
                m["points"][5]["hash"] = h1;
            },
            "the hashes of points 1 and 5 are swapped",
        ),
    ];
    for (edit, needle) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let d = finished(tmp.path());
        let mut m = manifest(&d);
        edit(&mut m);
        std::fs::write(d.join("manifest.json"), serde_json::to_string_pretty(&m).unwrap()).unwrap();
        let before = tree(&d);
        for cmd in [vec!["status"], vec!["report"], vec!["resume", "-q"]] {
            let mut args = cmd.clone();
            args.insert(1, p(&d));
            let o = sweep_in(tmp.path(), &args);
            let e = err(&o);
            assert_eq!(o.status.code(), Some(2), "{cmd:?} {needle}: {e}");
            assert_eq!(e.lines().count(), 1, "{e}");
            assert!(e.contains("manifest.json") && e.contains(needle), "{cmd:?}: {e}");
            assert!(!e.contains("engine or templates"), "{e}");
        }
        assert_eq!(tree(&d), before, "{needle}: a refused command wrote");
    }
}

#[test]
fn a_joblog_of_gnu_parallel_is_refused_rather_than_appended_to() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    std::fs::remove_dir_all(d.join("runs").join(hash(&d, 0))).unwrap();
    let gnu = "Seq\tHost\tStarttime\tJobRuntime\tSend\tReceive\tExitval\tSignal\tCommand\n\
               1\t:\t1700000000.000\t1.000\t0\t0\t0\t0\techo hi\n";
    std::fs::write(d.join("joblog.tsv"), gnu).unwrap();
    // `status` says so before `resume` is tried.
    let o = sweep_in(tmp.path(), &["status", p(&d)]);
    let text = out(&o);
    assert!(
        text.contains("warning: ") && text.contains("9 columns") && text.contains("`sweep resume` refuses"),
        "{text}"
    );
    let o = sweep_in(tmp.path(), &["resume", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert!(err(&o).contains("joblog.tsv") && err(&o).contains("9 columns"), "{}", err(&o));
    assert_eq!(std::fs::read_to_string(d.join("joblog.tsv")).unwrap(), gnu);
}

#[test]
fn a_joblog_with_invalid_utf8_does_not_stop_a_resume() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    std::fs::remove_dir_all(d.join("runs").join(hash(&d, 0))).unwrap();
    let mut log = std::fs::read(d.join("joblog.tsv")).unwrap();
    log.extend_from_slice(b"\xff\xfe not text\n");
    std::fs::write(d.join("joblog.tsv"), log).unwrap();
    for cmd in [vec!["status"], vec!["resume", "-q"]] {
        let mut args = cmd.clone();
        args.insert(1, p(&d));
        let o = sweep_in(tmp.path(), &args);
        assert_eq!(o.status.code(), Some(0), "{cmd:?}: {}", err(&o));
    }
    let rows = common::csv_rows(&d.join("results.csv"));
    assert!(rows.iter().all(|r| r["status"] == "done"), "{rows:?}");
}

#[test]
fn a_file_where_a_run_directory_belongs_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    let h = hash(&d, 0);
    std::fs::remove_dir_all(d.join("runs").join(&h)).unwrap();
    std::fs::write(d.join("runs").join(&h), "not a directory").unwrap();
    let o = sweep_in(tmp.path(), &["resume", p(&d), "-q"]);
    let e = err(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains(&format!("runs/{h}: not a directory")) && e.contains("remove it"), "{e}");
}

#[test]
fn the_line_of_a_cut_off_attempt_names_the_host_and_pid_that_made_it() {
    let tmp = tempfile::tempdir().unwrap();
    let d = finished(tmp.path());
    let h = hash(&d, 0);
    let run = d.join("runs").join(&h);
    std::fs::remove_dir_all(&run).unwrap();
    std::fs::create_dir(&run).unwrap();
    // Host A's claim, its lease long expired: A was cut off.
    let claim = r#"{"host":"node-a","pid":4242,"start_ticks":1,"session":"a","claimed_at":1000.0,"lease_s":1.0,"renewed_at":1000.0}"#;
    std::fs::write(run.join("claim"), claim).unwrap();
    let o = sweep_in(tmp.path(), &["resume", p(&d), "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let log = std::fs::read_to_string(d.join("joblog.tsv")).unwrap();
    let line = log.lines().find(|l| l.contains("\tinterrupted\t")).expect("an interrupted line");
    let f: Vec<&str> = line.split('\t').collect();
    assert_eq!((f[1], f[13]), ("node-a", "4242"), "{line}");
    // The finder's own attempt is its own.
    let done = log.lines().rfind(|l| l.contains(&h) && l.contains("\tdone\t")).unwrap();
    assert_ne!(done.split('\t').nth(1), Some("node-a"), "{done}");
}

// ---- the sweep file's [cluster] ----

#[test]
fn cluster_scripts_run_the_configured_command_after_the_prologue() {
    let tmp = tempfile::tempdir().unwrap();
    sweep_file(tmp.path(), &|t| {
        format!("{t}[cluster]\ncommand = \"sweep\"\nprologue = [\"module load liggghts/3.8\", \"module load demsweep\"]\n")
    });
    let d = tmp.path().join("d");
    let o = sweep_in(tmp.path(), &["lds", "t.toml", "--out", p(&d), "--plan", "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    for (scheduler, file) in [("slurm", "array.slurm"), ("pbs", "array.pbs")] {
        let o =
            sweep_in(tmp.path(), &["submit", p(&d), "--scheduler", scheduler, "--tasks", "2", "--dry-run"]);
        assert_eq!(o.status.code(), Some(0), "{}", err(&o));
        let script = std::fs::read_to_string(d.join("cluster").join(file)).unwrap();
        let at = |s: &str| script.find(s).unwrap_or_else(|| panic!("{s:?} not in {script}"));
        assert!(at("module load liggghts/3.8\nmodule load demsweep\n") < at("exec sweep work "), "{script}");
        assert!(!script.contains(common::SWEEP), "{script}");
    }
    // Without [cluster]: the submitting executable by its path, nothing loaded.
    let tmp = tempfile::tempdir().unwrap();
    sweep_file(tmp.path(), &|t| t);
    let d = tmp.path().join("d");
    sweep_in(tmp.path(), &["lds", "t.toml", "--out", p(&d), "--plan", "-q"]);
    let o = sweep_in(tmp.path(), &["submit", p(&d), "--scheduler", "slurm", "--tasks", "2", "--dry-run"]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let script = std::fs::read_to_string(d.join("cluster/array.slurm")).unwrap();
    assert!(
        script.contains(&format!("exec {} work ", common::SWEEP)) && !script.contains("module"),
        "{script}"
    );
    // A prologue line with a newline is refused, naming the key.
    let tmp = tempfile::tempdir().unwrap();
    sweep_file(tmp.path(), &|t| format!("{t}[cluster]\nprologue = [\"a\\nb\"]\n"));
    refused(tmp.path(), &["lds", "t.toml", "--plan", "-q"], &["cluster.prologue[0]"]);
}
