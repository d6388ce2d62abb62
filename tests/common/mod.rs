//! Helpers shared by the integration tests: the `sweep` binary, the check for LIGGGHTS, and
//! readers of a sweep directory.
#![allow(dead_code, unused_macros, unused_imports)] // each test file uses its own share of these

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output};

/// The path of the `sweep` binary under test.
pub const SWEEP: &str = env!("CARGO_BIN_EXE_sweep");

/// A command running the `sweep` binary under test.
pub fn sweep_bin() -> Command {
    Command::new(SWEEP)
}

/// The standard error of a finished command, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Whether LIGGGHTS (`liggghts` on PATH) is missing; when it is, says which test is skipped
/// and why.
pub fn liggghts_missing(test: &str) -> bool {
    let found = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join("liggghts").is_file()));
    if !found {
        eprintln!("SKIPPED {test}: needs LIGGGHTS, and `liggghts` is not on PATH (bash scripts/setup.sh installs it)");
    }
    !found
}

/// results.csv as (hash, status, failure, mfr) per point index.
pub fn results(dir: &Path) -> Vec<(String, String, String, String)> {
    let mut r = csv::Reader::from_path(dir.join("results.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    let cols = [col("hash"), col("status"), col("failure"), col("mfr")];
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            let f = |i: usize| rec[cols[i]].to_string();
            (f(0), f(1), f(2), f(3))
        })
        .collect()
}

/// The one place where a test says it needs LIGGGHTS: `common::require_liggghts!("test name");`
/// as its first line. Without LIGGGHTS the test says it is skipped and returns at once.
macro_rules! require_liggghts {
    ($test:expr) => {
        if $crate::common::liggghts_missing($test) {
            return;
        }
    };
}
pub(crate) use require_liggghts;

/// A CSV file by header name: one map per row.
pub fn csv_rows(path: &Path) -> Vec<BTreeMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let h = r.headers().unwrap().clone();
    r.records()
        .map(|rec| h.iter().zip(rec.unwrap().iter()).map(|(k, v)| (k.into(), v.into())).collect())
        .collect()
}

/// A sweep for the fake executor: gap and blade speed swept, `run` as the [run] table, written
/// to `dir/t.toml`.
pub fn fake_sweep(dir: &Path, run: &str) -> demsweep::sweep::Sweep {
    let text = format!(
        "name = \"t\"\n[parameters]\ngap = {{ lo = 2.0, hi = 4.0 }}\nblade_speed = {{ lo = 1.2, hi = 1.6 }}\n[run]\n{run}\n"
    );
    let path = dir.join("t.toml");
    std::fs::write(&path, &text).unwrap();
    demsweep::sweep::Sweep::load(&path).unwrap()
}

/// Pool options for tests: `jobs` slots, no progress output, failed runs not retried.
pub fn quiet(jobs: usize) -> demsweep::run::RunOptions {
    demsweep::run::RunOptions {
        jobs,
        progress: demsweep::run::progress::ProgressMode::Quiet,
        retry_failed: false,
        force: false,
    }
}

/// Write `text` to `path` and return the path (a sweep file for a test).
pub fn write_file(path: &Path, text: &str) -> std::path::PathBuf {
    std::fs::write(path, text).unwrap();
    path.to_path_buf()
}

/// The quick demo scene (D 1.5 mm) with gap and blade speed swept, named `name`, then `tables`.
pub fn quick_scene(name: &str, tables: &str) -> String {
    format!(
        r#"name = "{name}"
[parameters]
gap         = {{ lo = 2.0, hi = 3.0, unit = "mm" }}
blade_speed = {{ lo = 1.2, hi = 1.6, unit = "m/s" }}
diameter    = {{ value = 1.5, unit = "mm" }}
{tables}"#
    )
}
