//! Regression tests for issue 9, "what a hostile run of the current tool found": bad flags,
//! hand-edited files, two processes at once, a full disk. Each test is named after what it
//! guards. Bad input must exit 2 with one line naming the flag, file or key, write nothing
//! (not even a LIGGGHTS log in the caller's directory), and never panic.
//!
//! Sweeps that only exercise the directory run on the deterministic fake executor; those whose
//! path involves LIGGGHTS run it for real on small scenes.

mod common;

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

use demsweep::run::fake::{Behaviour, FakeExecutor};
use demsweep::run::{self, RunAll};
use demsweep::store::{self, DesignRecord};
use demsweep::sweep::{Scrambling, Sweep};
use demsweep::sys::process::CancelToken;

const MS: Duration = Duration::from_millis(1);

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The quick scene with gap and blade speed swept (as tests/resume.rs), in `dir/NAME.toml`.
fn write_sweep(dir: &Path, name: &str, extra_run: &str) -> PathBuf {
    let tables = format!(
        r#"[design.lds]
step = 2
max = 4
[run]
{extra_run}
"#
    );
    common::write_file(&dir.join(format!("{name}.toml")), &common::quick_scene(name, &tables))
}

/// Every file under `dir` with its contents, to show that nothing changed.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                out.insert(p.clone(), Vec::new());
                stack.push(p);
            } else {
                out.insert(p.clone(), std::fs::read(&p).unwrap_or_default());
            }
        }
    }
    out
}

/// Run `sweep ARGS` in `cwd` and check: exit 2, one stderr line holding every needle, no
/// panic, and nothing in `cwd` changed.
fn refused(cwd: &Path, args: &[&str], needles: &[&str]) {
    let before = snapshot(cwd);
    let o = common::sweep_bin().args(args).current_dir(cwd).stdin(Stdio::null()).output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}\nstderr: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}\nstderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: stderr {err:?} lacks {n:?}");
    }
    assert_eq!(snapshot(cwd), before, "{args:?} wrote in the caller's directory");
}

fn lds(max: usize, step: usize) -> DesignRecord {
    DesignRecord::Lds { step, max, scrambling: Scrambling::Random, seed: 7 }
}

fn fake_sweep(dir: &Path) -> Sweep {
    let text =
        "name = \"t\"\n[parameters]\ngap = { lo = 2.0, hi = 4.0 }\nblade_speed = { lo = 1.2, hi = 1.6 }\n";
    let path = dir.join("t.toml");
    std::fs::write(&path, text).unwrap();
    Sweep::load(&path).unwrap()
}

/// `done` lines per hash in the joblog.
fn done_per_hash(dir: &Path) -> HashMap<String, usize> {
    let mut m = HashMap::new();
    for l in store::read_joblog(dir).unwrap() {
        if l.status == "done" {
            *m.entry(l.hash).or_default() += 1;
        }
    }
    m
}

fn assert_unique_seq(dir: &Path) {
    let lines = store::read_joblog(dir).unwrap();
    let seqs: BTreeSet<u64> = lines.iter().map(|l| l.seq).collect();
    assert_eq!(seqs.len(), lines.len(), "repeated joblog seq: {lines:?}");
    assert_eq!(seqs, (1..=lines.len() as u64).collect(), "seq is not 1..n");
}

/// Files whose name says they are temporaries of an atomic write.
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    snapshot(dir).into_keys().filter(|p| p.to_string_lossy().contains(".tmp.")).collect()
}

// ---- 1 and 7: refused input writes nothing, names the flag ----

#[test]
fn refused_commands_write_nothing_in_the_callers_directory_not_even_a_liggghts_log() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path().join("cwd");
    std::fs::create_dir(&cwd).unwrap();
    write_sweep(&cwd, "s", "");
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
    let o = common::sweep_bin()
        .args(["render", "s.toml", "--set", "gap=3", "--out", deck])
        .current_dir(&cwd)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(snapshot(&cwd), before, "identifying LIGGGHTS wrote in the caller's directory");
    assert!(Path::new(deck).join("in.liggghts").exists());
}

// ---- 3: an --out that cannot be a sweep directory ----

/// A mounted tmpfs, unmounted on drop.
struct Mount(PathBuf);

impl Mount {
    fn tmpfs(at: &Path, options: &str) -> Result<Mount, String> {
        std::fs::create_dir_all(at).unwrap();
        let o = Command::new("mount")
            .args(["-t", "tmpfs", "-o", options, "tmpfs"])
            .arg(at)
            .output()
            .map_err(|e| format!("cannot run mount: {e}"))?;
        if !o.status.success() {
            return Err(format!("mount -t tmpfs -o {options} failed: {}", stderr(&o).trim()));
        }
        Ok(Mount(at.to_path_buf()))
    }

    fn remount(&self, options: &str) {
        let o =
            Command::new("mount").args(["-o", &format!("remount,{options}")]).arg(&self.0).output().unwrap();
        assert!(o.status.success(), "remount: {}", stderr(&o));
    }
}

impl Drop for Mount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(&self.0).status();
    }
}

#[test]
fn an_out_in_a_directory_that_cannot_be_written_is_bad_input_naming_the_path() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path().join("cwd");
    std::fs::create_dir(&cwd).unwrap();
    write_sweep(&cwd, "s", "");
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
            eprintln!("SKIPPED: running as root and cannot mount a read-only tmpfs: {why}");
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

// ---- 2 and 6: two processes on one directory ----

#[test]
fn two_sweeps_started_at_once_on_one_new_directory_share_the_work() {
    // Threads, so that the two creations overlap as closely as possible, many times.
    let tmp = tempfile::tempdir().unwrap();
    let s = fake_sweep(tmp.path());
    for round in 0..25 {
        let out = tmp.path().join(format!("out{round}"));
        let execs = [
            FakeExecutor::new(|_, _| Behaviour::Succeed(2 * MS)),
            FakeExecutor::new(|_, _| Behaviour::Succeed(2 * MS)),
        ];
        let results: Vec<_> = std::thread::scope(|scope| {
            let handles: Vec<_> = execs
                .iter()
                .map(|e| {
                    let (s, out) = (&s, &out);
                    scope.spawn(move || {
                        run::start(s, lds(6, 3), out, e, &common::quiet(1), &mut RunAll, &CancelToken::new())
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for r in &results {
            let sum = r.as_ref().unwrap_or_else(|e| panic!("round {round}: {e}"));
            assert_eq!(sum.done, 6, "round {round}");
        }
        let runs: usize = execs.iter().map(|e| e.attempts().values().sum::<usize>()).sum();
        assert_eq!(runs, 6, "round {round}: a point ran twice");
        let done = done_per_hash(&out);
        assert!(done.len() == 6 && done.values().all(|&n| n == 1), "round {round}: {done:?}");
        assert_unique_seq(&out);
    }
}

#[test]
fn joblog_seq_is_unique_when_two_resumes_share_a_directory() {
    let tmp = tempfile::tempdir().unwrap();
    let s = fake_sweep(tmp.path());
    let out = tmp.path().join("out");
    // A directory with its manifest and nothing run (a copy made elsewhere, a killed start).
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::start(&s, lds(12, 12), &out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    std::fs::remove_dir_all(out.join("runs")).unwrap();
    std::fs::write(out.join("joblog.tsv"), format!("{}\n", store::JOBLOG_HEADER)).unwrap();
    let execs = [
        FakeExecutor::new(|_, _| Behaviour::Succeed(5 * MS)),
        FakeExecutor::new(|_, _| Behaviour::Succeed(5 * MS)),
    ];
    std::thread::scope(|scope| {
        for e in &execs {
            let out = &out;
            scope.spawn(move || {
                run::resume(out, e, &common::quiet(2), &mut RunAll, &CancelToken::new()).unwrap()
            });
        }
    });
    assert!(execs.iter().all(|e| !e.attempts().is_empty()), "both resumes should have run points");
    assert_eq!(done_per_hash(&out).len(), 12);
    assert_unique_seq(&out);
}

#[test]
fn a_killed_attempt_shows_as_interrupted_in_status_and_the_joblog() {
    let tmp = tempfile::tempdir().unwrap();
    let s = fake_sweep(tmp.path());
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::start(&s, lds(3, 3), &out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    let hash = &manifest.points[2].hash;
    let run = out.join("runs").join(hash);
    // What a SIGKILL mid-run leaves: the claim of a process that is gone, no result.
    std::fs::remove_file(run.join("result.json")).unwrap();
    let mut dead = Command::new("true").spawn().unwrap();
    let pid = dead.id();
    dead.wait().unwrap();
    let claim = serde_json::json!({
        "host": demsweep::sys::host::hostname(), "pid": pid, "start_ticks": 1, "session": "killed", "claimed_at": 1.7e9
    });
    std::fs::write(run.join("claim"), claim.to_string()).unwrap();
    let st = run::status(&out).unwrap();
    assert_eq!((st.done, st.pending, st.interrupted), (2, 1, 1));
    let o = common::sweep_bin().arg("status").arg(&out).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("(1 interrupted"), "{text}");

    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::resume(&out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    let lines: Vec<_> = store::read_joblog(&out).unwrap().into_iter().filter(|l| &l.hash == hash).collect();
    let statuses: Vec<&str> = lines.iter().map(|l| l.status.as_str()).collect();
    assert_eq!(statuses, ["done", "interrupted", "done"], "the killed attempt is in the joblog");
    let raw = std::fs::read_to_string(out.join("joblog.tsv")).unwrap();
    let line = raw.lines().find(|l| l.contains("\tinterrupted\t")).unwrap();
    assert!(
        line.contains("\t1700000000.000\t-\tinterrupted"),
        "start = the claim's time, runtime unknown: {line}"
    );
    assert_eq!(run::status(&out).unwrap().interrupted, 0);
    assert_unique_seq(&out);
}

// ---- 4: a hand-edited manifest ----

#[test]
fn an_inconsistent_or_truncated_manifest_is_refused_naming_the_field() {
    let tmp = tempfile::tempdir().unwrap();
    let s = fake_sweep(tmp.path());
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::start(&s, lds(4, 2), &out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    let path = out.join("manifest.json");
    let good = std::fs::read_to_string(&path).unwrap();
    let edit = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v: serde_json::Value = serde_json::from_str(&good).unwrap();
        f(&mut v);
        serde_json::to_string_pretty(&v).unwrap()
    };
    let hash0 = serde_json::from_str::<serde_json::Value>(&good).unwrap()["points"][0]["hash"].clone();
    let cases: Vec<(String, &str, bool)> = vec![
        (edit(&|v| v["spaces"][0]["points"][1] = 99.into()), "spaces[0].points[1] = 99: no such point", true),
        (edit(&|v| v["points"][2]["index"] = 5.into()), "points[2].index = 5: expected 2", true),
        (edit(&|v| v["points"][1]["hash"] = "../../etc".into()), "points[1].hash = \"../../etc\"", true),
        (
            edit(&|v| v["points"][3]["hash"] = hash0.clone()),
            "points[3].hash: the same as points[0].hash",
            true,
        ),
        (
            edit(&|v| v["points"][0]["values"] = serde_json::json!([2.5])),
            "points[0].values: 1 values for 2",
            true,
        ),
        (edit(&|v| v["spaces"] = serde_json::json!([])), "spaces: expected at least one", true),
        (
            edit(&|v| v["parameters"] = serde_json::json!(["gap", "friction"])),
            "parameters [gap, friction]",
            false,
        ),
        (good[..good.len() / 2].to_string(), "truncated or not JSON", true),
        (String::new(), "truncated or not JSON", true),
    ];
    for (text, needle, status_too) in cases {
        std::fs::write(&path, &text).unwrap();
        let before = snapshot(&out);
        let mut commands = vec![vec!["resume", "-q"]];
        if status_too {
            commands.push(vec!["status"]);
        }
        for args in commands {
            let o = common::sweep_bin().args(&args).arg(&out).output().unwrap();
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{args:?} {needle}: {err}");
            assert_eq!(err.lines().count(), 1, "{err}");
            assert!(
                err.contains(needle) && err.contains("manifest.json"),
                "{args:?}: {err:?} lacks {needle:?}"
            );
            assert!(!err.contains("panicked"), "{err}");
        }
        assert_eq!(snapshot(&out), before, "{needle}: a refused resume changed the directory");
    }
}

// ---- 5: a full disk ----

#[test]
fn a_full_disk_stops_the_sweep_says_where_and_resume_finishes_it() {
    let tmp = tempfile::tempdir().unwrap();
    let s = fake_sweep(tmp.path());
    let fs = tmp.path().join("fs");
    let mount = match Mount::tmpfs(&fs, "size=256k") {
        Ok(m) => m,
        Err(why) => {
            eprintln!("SKIPPED: cannot mount a small tmpfs to fill: {why}");
            return;
        }
    };
    let out = fs.join("out");
    // Each run leaves 40 kB of "log": about five fit.
    let mut exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    exec.output_bytes = 40_000;
    let err = run::start(&s, lds(12, 12), &out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new())
        .unwrap_err();
    let msg = err.to_string();
    assert_ne!(err.code(), 0);
    assert!(msg.contains(&format!("no space left on tmpfs ({})", fs.display())), "{msg}");
    assert!(msg.contains(&format!("while writing {}", out.display())), "{msg}");
    assert!(msg.contains(&format!("sweep resume {}", out.display())), "{msg}");
    // It stopped at the first store error: nothing started after it.
    let attempts: usize = exec.attempts().values().sum();
    let lines = store::read_joblog(&out).unwrap();
    let done = lines.iter().filter(|l| l.status == "done").count();
    assert!((1..12).contains(&done), "{lines:?}");
    assert_eq!(attempts, done + 1, "runs were started after the disk was full");
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    // status and results.csv agree: the lost run is pending, not failed.
    let st = run::status(&out).unwrap();
    assert_eq!((st.done, st.failed, st.pending), (done, 0, 12 - done));
    if let Ok(csv) = std::fs::read_to_string(out.join("results.csv")) {
        assert_eq!(csv.matches(",done,").count(), done, "{csv}");
        assert!(!csv.contains(",failed,"), "{csv}");
    }

    // A killed writer's temporary is removed on the next open.
    let dead = {
        let mut c = Command::new("true").spawn().unwrap();
        let pid = c.id();
        c.wait().unwrap();
        pid
    };
    let stale = out.join(format!(".results.csv.tmp.{}.{dead}.0", demsweep::sys::atomic::temporary_host()));
    mount.remount("size=4m");
    std::fs::write(&stale, "half").unwrap();
    let exec2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let sum = run::resume(&out, &exec2, &common::quiet(2), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.done, sum.failed, sum.reused), (12, 0, done));
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    let per_hash = done_per_hash(&out);
    assert!(per_hash.len() == 12 && per_hash.values().all(|&n| n == 1), "{per_hash:?}");
    assert_unique_seq(&out);
}

#[test]
fn a_full_disk_under_liggghts_is_a_store_error_not_failed_runs_and_resume_finishes_it() {
    let tmp = tempfile::tempdir().unwrap();
    let sweep = write_sweep(tmp.path(), "full", "");
    let fs = tmp.path().join("fs");
    // A run of this scene leaves 0.77 to 0.88 MB (mesh, pile, dump): the first fits, the
    // second does not.
    let mount = match Mount::tmpfs(&fs, "size=1600k") {
        Ok(m) => m,
        Err(why) => {
            eprintln!("SKIPPED: cannot mount a small tmpfs to fill: {why}");
            return;
        }
    };
    let out = fs.join("out");
    let o = common::sweep_bin()
        .args(["lds", sweep.to_str().unwrap(), "--max", "3", "--step", "3", "--jobs", "1", "-q", "--out"])
        .arg(&out)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = stderr(&o);
    eprintln!("the full-disk sweep said: {err}");
    assert!(!matches!(o.status.code(), Some(0) | Some(1) | Some(2)), "{:?}: {err}", o.status);
    assert!(
        err.contains(&format!("no space left on tmpfs ({}) while writing {}", fs.display(), out.display())),
        "{err}"
    );
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    let lines = store::read_joblog(&out).unwrap();
    assert!(lines.iter().all(|l| l.status != "failed"), "a full disk became failed runs: {lines:?}");
    let st = run::status(&out).unwrap();
    let done = lines.iter().filter(|l| l.status == "done").count();
    assert_eq!((st.done, st.failed, st.pending), (done, 0, 3 - done), "{lines:?}");
    assert!(done >= 1, "the first run should have fitted: {lines:?}");

    mount.remount("size=16m");
    let o = common::sweep_bin()
        .args(["resume", "--jobs", "2", "-q"])
        .arg(&out)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let per_hash = done_per_hash(&out);
    assert!(per_hash.len() == 3 && per_hash.values().all(|&n| n == 1), "{per_hash:?}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(csv.matches(",done,").count(), 3, "{csv}");
}

// ---- 8: smaller ones ----

#[test]
fn an_engine_reached_through_a_symlink_is_the_same_engine() {
    let tmp = tempfile::tempdir().unwrap();
    let Some(real) = ["/usr/bin/liggghts"].into_iter().map(Path::new).find(|p| p.exists()) else {
        eprintln!("SKIPPED: no /usr/bin/liggghts (bash scripts/setup.sh installs it)");
        return;
    };
    let link = tmp.path().join("bin/liggghts");
    std::fs::create_dir_all(link.parent().unwrap()).unwrap();
    std::os::unix::fs::symlink(real, &link).unwrap();
    let exec = |engine: &Path| {
        let path = write_sweep(tmp.path(), "e", &format!("engine = {:?}", engine));
        run::PointExecutor::new(Sweep::load(&path).unwrap()).unwrap()
    };
    let (a, b) = (exec(real), exec(&link));
    use demsweep::run::pool::Executor;
    assert_ne!(a.identity()["engine_path"], b.identity()["engine_path"]);
    assert_eq!(run::identity_diff(&a.identity(), &b.identity()), Vec::<String>::new());
    let (ja, jb) = (a.prepare(&[2.5, 1.4]).unwrap(), b.prepare(&[2.5, 1.4]).unwrap());
    assert_eq!(a.hash(&ja), b.hash(&jb), "the same deck on the same engine is the same run");
}

#[test]
fn an_unreadable_result_is_named_in_status_and_run_again() {
    let tmp = tempfile::tempdir().unwrap();
    let s = fake_sweep(tmp.path());
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    run::start(&s, lds(3, 3), &out, &exec, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    let result = out.join("runs").join(&manifest.points[1].hash).join("result.json");
    std::fs::write(&result, "{\"format\": 1, \"hash\": ").unwrap();
    let o = common::sweep_bin().arg("status").arg(&out).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains(&format!("warning: {}: unreadable", result.display())), "{text}");
    let exec2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let sum = run::resume(&out, &exec2, &common::quiet(1), &mut RunAll, &CancelToken::new()).unwrap();
    assert_eq!((sum.done, sum.ran), (3, 1));
    assert_eq!(exec2.attempts().keys().collect::<Vec<_>>(), vec![&manifest.points[1].hash]);
}

#[test]
fn planning_a_large_lattice_shows_progress_and_an_interrupt_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let sweep = write_sweep(tmp.path(), "big", "");
    let out = tmp.path().join("out");
    // 2-D level 150: 22,500 decks to render and hash, several seconds of planning.
    let mut child = common::sweep_bin()
        .args(["lattice", sweep.to_str().unwrap(), "--levels", "150", "--out"])
        .arg(&out)
        .stdin(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    std::io::BufRead::read_line(&mut err, &mut line).unwrap();
    assert!(line.starts_with("sweep: planning: ") && line.contains("of 22500 decks"), "{line:?}");
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    assert!(!out.exists(), "an interrupted plan wrote the directory");
}
