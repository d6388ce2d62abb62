//! Overhead of the job pool against GNU parallel, on the same trivial jobs, side by side.
//!
//! `cargo bench --bench pool_overhead -- [--jobs N] [--count N] [--rounds N]` (defaults: the
//! machine's cores, 1000 jobs, 3 rounds alternating pool and parallel; the median ratio counts).
//! Each job runs `true`. The pool path is the one a sweep takes: claim the run dir, run the child
//! under its guard and the timeout, write result.json, append a joblog line, release the claim;
//! GNU parallel runs the same `true` with `--joblog`. Prints both wall times, the per-job cost
//! and the ratio.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use demsweep::outcome::{RunOutcome, RunResult};
use demsweep::run::pool::{self, Executor, Flow, PoolOptions};
use demsweep::store::Store;
use demsweep::sys::atomic::write_json;
use demsweep::sys::process::{self, CancelToken, ProcessOutcome};

/// Runs `true` and records a trivial result.
struct TrueExecutor;

impl Executor for TrueExecutor {
    type Job = String;

    fn identity(&self) -> serde_json::Value {
        serde_json::json!("true")
    }

    fn prepare_seeded(&self, swept: &[f64], _seed: Option<u64>) -> demsweep::Result<String> {
        Ok(format!("job{:06}", swept[0] as u64))
    }

    fn hash<'a>(&self, job: &'a String) -> &'a str {
        job
    }

    fn execute(&self, job: &String, run_dir: &Path, cancel: &CancelToken) -> RunOutcome {
        let (o, took) = process::run(Command::new("true"), Duration::from_secs(60), cancel);
        assert_eq!(o, ProcessOutcome::Exited(0));
        let r = RunResult {
            hash: job.clone(),
            wall_time: took.as_secs_f64(),
            engine_version: "true".into(),
            ..RunResult::default()
        };
        write_json(&run_dir.join("result.json"), &r).unwrap();
        RunOutcome::Done(r)
    }
}

fn arg(name: &str, default: usize) -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(|v| v.parse().expect("a number"))
        .unwrap_or(default)
}

/// Wall time of `count` jobs through the pool, in a fresh sweep directory under `tmp`.
fn ours(tmp: &Path, round: usize, jobs: usize, count: usize) -> Duration {
    let dir = tmp.join(format!("sweep{round}"));
    std::fs::create_dir_all(dir.join("runs")).unwrap();
    let store = Store::open(&dir);
    let exec = TrueExecutor;
    let work: Vec<String> = (0..count).map(|i| exec.prepare(&[i as f64]).unwrap()).collect();
    let opts =
        PoolOptions { slots: jobs, retries: 0, retry_failed_before: None, not_theirs: Default::default() };
    let t = Instant::now();
    let mut done = 0;
    pool::run(&exec, &store, store.joblog().unwrap(), work, &opts, &CancelToken::new(), |e| {
        if let pool::Event::Finished { .. } = e {
            done += 1;
        }
        Flow::Continue
    });
    let took = t.elapsed();
    assert_eq!(done, count);
    took
}

/// Wall time of the same jobs through GNU parallel with a joblog.
fn theirs(tmp: &Path, round: usize, jobs: usize, count: usize) -> Duration {
    let joblog = tmp.join(format!("parallel{round}.joblog"));
    let t = Instant::now();
    let status = Command::new("sh")
        .arg("-c")
        .arg(format!("seq {count} | parallel --will-cite -j {jobs} --joblog {} true", joblog.display()))
        .status()
        .expect("GNU parallel (apt-get install parallel)");
    let took = t.elapsed();
    assert!(status.success());
    took
}

fn main() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = arg("--jobs", cores);
    let count = arg("--count", 1000);
    let rounds = arg("--rounds", 3);
    let tmp = tempfile::tempdir().unwrap();
    let per = |d: Duration| d.as_secs_f64() * 1e3 / count as f64;
    println!("pool overhead: {count} jobs of `true` on {jobs} slots, {rounds} alternating rounds");
    let mut ratios = Vec::new();
    for round in 0..rounds {
        let a = ours(tmp.path(), round, jobs, count);
        let b = theirs(tmp.path(), round, jobs, count);
        ratios.push(a.as_secs_f64() / b.as_secs_f64());
        println!(
            "  round {round}: sweep pool {:6.3} s ({:5.2} ms/job)  GNU parallel {:6.3} s ({:5.2} ms/job)  ratio {:.2}",
            a.as_secs_f64(),
            per(a),
            b.as_secs_f64(),
            per(b),
            ratios[round]
        );
    }
    ratios.sort_by(f64::total_cmp);
    println!("  median ratio pool / parallel = {:.2}", ratios[ratios.len() / 2]);
}
