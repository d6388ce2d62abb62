//! Helpers shared by the integration tests: the `sweep` binary, the check for LIGGGHTS, and
//! readers of a sweep directory.
#![allow(dead_code)] // each test file uses its own share of these

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

/// Whether LIGGGHTS (`liggghts` on PATH) is missing. The one place where a test says it needs
/// LIGGGHTS: when it is missing, this prints which test is skipped and why, and the test
/// returns at once (`if common::liggghts_missing("name") { return; }`).
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
