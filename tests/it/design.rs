//! Which points a sweep runs: the designs `sweep points` prints (the thesis's lattices, LDS
//! prefixes, the file's own design), and a design laid out in a sweep directory — extended by a
//! larger max, refused when it does not extend the directory, a point shared by two lattice
//! levels run once.

use std::process::Output;

use demsweep::run::fake::{Behaviour, FakeExecutor};
use demsweep::run::{self, RunAll};
use demsweep::store::{self, DesignRecord};
use demsweep::sys::process::CancelToken;

use crate::support::{self, cwd, lds, lds_sweep, ok, points, repo, text, MS};

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
fn points_prints_the_files_design_and_round_values() {
    let (_tmp, cwd) = cwd();
    lds_sweep(&cwd, "friction = { lo = 0.1, hi = 0.5 }\ngap = { lo = 2.0, hi = 4.0 }");
    let o = ok(&cwd, &["points", "s.toml"]);
    let out = text(&o.stdout);
    assert_eq!(out.lines().count(), 1 + 4, "design.lds.max = 4 points:\n{out}");
    let o = ok(&cwd, &["points", "s.toml", "--lattice", "3"]);
    let out = text(&o.stdout);
    assert!(out.lines().any(|l| l.starts_with("0.3,")), "{out}");
    assert!(!out.contains("0000000"), "float noise printed:\n{out}");
}

#[test]
fn a_larger_max_extends_an_lds_directory_reusing_its_prefix() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let e1 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    support::run_all(&s, lds(4, 4), &out, &e1, 2).unwrap();
    let e2 = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let sum = support::run_all(&s, lds(8, 4), &out, &e2, 2).unwrap();
    assert_eq!((sum.done, sum.reused, sum.ran), (8, 4, 4));
    assert!(e2.attempts().keys().all(|h| !e1.attempts().contains_key(h)));
    let (manifest, toml) = store::Store::read_manifest(&out).unwrap();
    assert_eq!(manifest.spaces.len(), 2);
    assert!(toml.contains("max = 8"), "{toml}");
}

#[test]
fn a_design_that_does_not_extend_the_directory_is_refused_and_nothing_changes() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let three = DesignRecord::Lattice { levels: vec![3] };
    support::run_all(&s, three, &out, &exec, 2).unwrap();
    let before = std::fs::read(out.join("manifest.json")).unwrap();
    // Levels 2,3 put the 2x2 corners first: the old 3x3 points are not its prefix.
    let two_three = DesignRecord::Lattice { levels: vec![2, 3] };
    let err = support::run_all(&s, two_three, &out, &exec, 2).unwrap_err();
    assert_eq!(err.code(), 2, "{err}");
    assert!(err.to_string().contains("not the first points"), "{err}");
    let err = support::run_all(&s, lds(9, 9), &out, &exec, 2).unwrap_err();
    assert!(err.to_string().contains("holds a lattice sweep"), "{err}");
    assert_eq!(std::fs::read(out.join("manifest.json")).unwrap(), before);
    assert_eq!(exec.attempts().len(), 9);
}

#[test]
fn a_point_shared_by_two_lattice_levels_runs_once() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    let design = DesignRecord::Lattice { levels: vec![2, 3] };
    let sum = support::run_all(&s, design, &out, &exec, 2).unwrap();
    // The 2×2 corners are among the 3×3 points.
    assert_eq!((sum.points, sum.done), (9, 9));
    assert_eq!(exec.attempts().len(), 9);
    let (manifest, _) = store::Store::read_manifest(&out).unwrap();
    assert_eq!(manifest.spaces[0].points.len(), 4);
    assert_eq!(manifest.spaces[1].points.len(), 9);
}

#[test]
fn bad_designs_are_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let s = support::fake_sweep(tmp.path(), "");
    let out = tmp.path().join("out");
    let exec = FakeExecutor::new(|_, _| Behaviour::Succeed(MS));
    for design in
        [DesignRecord::Lattice { levels: vec![1] }, DesignRecord::Lattice { levels: vec![1001] }, lds(0, 4)]
    {
        let err = support::run_all(&s, design, &out, &exec, 1).unwrap_err();
        assert_eq!(err.code(), 2, "{err}");
        assert!(!out.exists());
    }
    // A directory that is not a sweep directory.
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let err = support::run_all(&s, lds(2, 2), &out, &exec, 1).unwrap_err();
    assert_eq!(err.code(), 2);
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);
    let err = run::resume(&out, &exec, &support::quiet(1), &mut RunAll, &CancelToken::new()).unwrap_err();
    assert_eq!(err.code(), 2);
    assert!(err.to_string().contains("not a sweep directory"), "{err}");
}

#[test]
fn the_designs_bench_refuses_a_noise_scale_that_is_not_positive_in_one_line() {
    let file = repo("sweeps/thesis-lds.toml");
    for bad in ["0", "-0.5", "inf", "nan"] {
        let o = support::sweep_bin()
            .args(["bench", "designs"])
            .arg(&file)
            .arg(format!("--noise-scale={bad}"))
            .args(["--seeds", "14", "--max", "40"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{bad}: {err}");
        assert!(err.contains("--noise-scale") && err.to_lowercase().contains(bad), "{err}");
        assert!(o.stdout.is_empty(), "{bad}: the bench ran");
    }
    // A negative value after a space is the value, not a flag.
    let o = support::sweep_bin()
        .args(["bench", "designs"])
        .arg(&file)
        .args(["--noise-scale", "-0.5"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--noise-scale: -0.5 is not a positive number"), "{err}");
}
