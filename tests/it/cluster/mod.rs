//! `sweep submit` and `sweep work` for real: a Slurm array on the local Slurm of
//! `scripts/slurm_local.sh` (one task cancelled mid-run, then re-submitted), the PBS task body
//! under the environment PBS gives a task, the `#PBS`/`#SBATCH` headers as text, and claim
//! leases across (played) hosts with real processes.
//!
//! Every sweep result is compared with a local run of the same sweep directory (same hashes,
//! same MFR to the last digit: LIGGGHTS is deterministic), never with copied figures. The Slurm
//! tests skip, saying so, when Slurm is not installed, and fail instead under CI (`.ci/run`
//! installs and starts it with `bash scripts/slurm_local.sh up`, as root).

mod leases;
mod pbs;
mod scripts;
mod slurm;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::support::{self, results};

/// Three points of the quick scene (D = 1.5 mm, gap and blade speed swept), each from rest: the
/// points of [`support::quick_reference`], whose local run the cluster runs are compared with.
fn sweep_text() -> String {
    support::quick_scene("cluster-test", support::SHORT_FROM_REST)
}
const POINTS: usize = support::QUICK_REFERENCE_POINTS;

/// The local run every cluster run is compared with: [`sweep_text`]'s points, made once per test
/// binary and shared with the resume tests.
fn reference() -> &'static Path {
    support::quick_reference()
}

/// A sweep directory of the reference's sweep with nothing run: what a user takes to a cluster
/// (its manifest and resolved sweep file).
fn fresh_copy(name: &str) -> (tempfile::TempDir, PathBuf) {
    fresh_copy_of(reference(), name)
}

/// A sweep directory of the sweep of the local run `local`, with nothing run.
fn fresh_copy_of(local: &Path, name: &str) -> (tempfile::TempDir, PathBuf) {
    let root = tempfile::Builder::new().prefix(name).tempdir().unwrap();
    let dir = root.path().join("sweep");
    std::fs::create_dir_all(dir.join("runs")).unwrap();
    for f in ["manifest.json", "sweep.toml"] {
        std::fs::copy(local.join(f), dir.join(f)).unwrap();
    }
    (root, dir)
}

/// Joblog statuses by hash, in order, with the host of each line.
fn attempts(dir: &Path) -> BTreeMap<String, Vec<(String, String)>> {
    let mut m: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    for l in demsweep::store::read_joblog(dir).unwrap() {
        m.entry(l.hash).or_default().push((l.host, l.status));
    }
    m
}

/// Every point finished once: at most one `done` or `failed` line per hash, none after it.
fn assert_finished_once(dir: &Path) {
    for (hash, a) in attempts(dir) {
        let finals = a.iter().filter(|(_, s)| s == "done" || s == "failed").count();
        assert!(finals <= 1, "run {hash} finished {finals} times: {a:?}");
    }
}

fn assert_same_as_reference(dir: &Path) {
    let (got, want) = (results(dir), results(reference()));
    assert_eq!(got.len(), POINTS);
    assert_eq!(got, want, "cluster results differ from the local run");
    assert!(want.iter().any(|r| r.1 == "done"), "the reference has no successful run: {want:?}");
    assert_finished_once(dir);
}
