//! The PBS task body under the environment PBS gives a task (PBS Pro and Torque), with no
//! scheduler installed.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use super::{assert_same_as_reference, fresh_copy, reference};
use crate::support::{self, output, results, text};

/// Run a rendered PBS script as PBS would run array index `index`: its environment, a node
/// file, and another working directory to start from.
fn pbs_task(script: &Path, index: usize, torque: bool, workdir: &Path) -> Child {
    let nodefile = workdir.join(format!("nodes.{index}"));
    std::fs::write(&nodefile, "node01\nnode01\n").unwrap();
    let mut c = Command::new("bash");
    c.arg(script)
        .env(if torque { "PBS_ARRAYID" } else { "PBS_ARRAY_INDEX" }, index.to_string())
        .env("PBS_O_WORKDIR", workdir)
        .env("PBS_NODEFILE", &nodefile)
        .env("PBS_JOBID", format!("77[{index}].pbs"))
        .current_dir("/")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c.spawn().unwrap()
}

/// The PBS Pro task body under PBS's environment, run for indices 0 and 2 at once, leaves the
/// same directory as a local run: index 1 never ran (a lost task), and they did its point
/// once their own were done. Then Torque's form for the failures (PBS_ARRAYID).
#[test]
fn pbs_task_bodies_under_the_pbs_environment_equal_a_local_run() {
    let (root, dir) = fresh_copy("cluster-pbs-");
    let o = output(support::sweep_bin().args([
        "submit",
        dir.to_str().unwrap(),
        "--scheduler",
        "pbs",
        "--tasks",
        "3",
        "--dry-run",
    ]));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let script = PathBuf::from(text(&o.stdout).trim());
    let body = std::fs::read_to_string(&script).unwrap();
    assert!(body.contains("#PBS -J 0-2\n"), "{body}");
    let tasks: Vec<(usize, Child)> =
        [0, 2].into_iter().map(|i| (i, pbs_task(&script, i, false, root.path()))).collect();
    for (i, t) in tasks {
        let o = t.wait_with_output().unwrap();
        let out = text(&o.stdout);
        assert!(matches!(o.status.code(), Some(0 | 1)), "task {i}: {out}{}", text(&o.stderr));
        assert!(out.starts_with(&format!("task {i} on ")) && out.contains("(node01 )"), "{out}");
    }
    assert_same_as_reference(&dir);

    let o = output(support::sweep_bin().args([
        "submit",
        dir.to_str().unwrap(),
        "--scheduler",
        "torque",
        "--dry-run",
        "--only",
        "missing,failed",
    ]));
    assert!(o.status.success(), "{}", text(&o.stderr));
    // With every point done, only a failed one (if the sweep has one) is left to submit.
    let failed: Vec<usize> =
        results(reference()).iter().enumerate().filter(|(_, r)| r.1 == "failed").map(|(i, _)| i).collect();
    if failed.is_empty() {
        assert!(text(&o.stderr).contains("nothing to submit"), "{}", text(&o.stderr));
        return;
    }
    let script = PathBuf::from(text(&o.stdout).trim());
    let body = std::fs::read_to_string(&script).unwrap();
    let want = failed.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(",");
    assert!(body.contains(&format!("#PBS -t {want}\n")) && body.contains("--retry-failed"), "{body}");
}
