//! How long a sweep's runs took: wall time (the union of their attempts) and the attempts' times
//! summed, from `joblog.tsv`, and LIGGGHTS's CPU over the done runs, from their results
//! (summary.json `timing`).

use std::path::Path;

use serde::Serialize;

use crate::outcome::RunResult;

#[derive(Debug, Clone, Serialize)]
pub struct Timing {
    /// Time during which at least one run was going (union of the joblog's attempts), s.
    pub wall_time_s: f64,
    /// Sum of every attempt's run time, s.
    pub core_seconds: f64,
    pub attempts: usize,
    /// LIGGGHTS's CPU time summed over the done runs (their results' `cpu_time`), s: on a
    /// machine shared with other work, the cost that compares across runs.
    pub cpu_seconds: f64,
    /// Done runs whose result has no CPU time (written before it was measured, or by the
    /// stand-in): not in `cpu_seconds`.
    pub runs_without_cpu: usize,
}

/// Wall time (union of attempts) and core-seconds from `joblog.tsv`, read by column name, and
/// the CPU of the `done` runs.
pub(super) fn of(dir: &Path, done: &[&RunResult]) -> Timing {
    let cpu_seconds = done.iter().filter_map(|r| r.cpu_time).sum();
    let runs_without_cpu = done.iter().filter(|r| r.cpu_time.is_none()).count();
    let text = crate::sys::read::read_text_capped(&dir.join("joblog.tsv"), crate::store::JOBLOG_CAP)
        .unwrap_or_default();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    // The columns of GNU parallel's joblog, or of an earlier version's.
    let (Some(si), Some(ri)) = (col("Starttime").or(col("start")), col("JobRuntime").or(col("runtime_s")))
    else {
        return Timing { wall_time_s: 0.0, core_seconds: 0.0, attempts: 0, cpu_seconds, runs_without_cpu };
    };
    let mut spans: Vec<(f64, f64)> = lines
        .filter_map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            let s: f64 = f.get(si)?.parse().ok()?;
            let r: f64 = f.get(ri)?.parse().ok()?;
            (s.is_finite() && r.is_finite()).then_some((s, s + r.max(0.0)))
        })
        .collect();
    let core_seconds = spans.iter().map(|(a, b)| b - a).sum();
    let attempts = spans.len();
    spans.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut wall = 0.0;
    let mut cur: Option<(f64, f64)> = None;
    for (a, b) in spans {
        cur = match cur {
            Some((ca, cb)) if a <= cb => Some((ca, cb.max(b))),
            Some((ca, cb)) => {
                wall += cb - ca;
                Some((a, b))
            }
            None => Some((a, b)),
        };
    }
    if let Some((a, b)) = cur {
        wall += b - a;
    }
    Timing { wall_time_s: wall, core_seconds, attempts, cpu_seconds, runs_without_cpu }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cpu_is_the_done_runs_cpu_summed_and_a_run_without_one_is_counted_apart() {
        let dir = std::env::temp_dir().join(format!("timing-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("joblog.tsv"), "Seq\tStarttime\tJobRuntime\n1\t100\t10\n2\t105\t20\n")
            .unwrap();
        let run = |cpu| RunResult { cpu_time: cpu, ..RunResult::default() };
        let (a, b, c) = (run(Some(3.0)), run(Some(4.5)), run(None));
        let t = of(&dir, &[&a, &b, &c]);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!((t.wall_time_s, t.core_seconds, t.attempts), (25.0, 30.0, 2));
        assert_eq!((t.cpu_seconds, t.runs_without_cpu), (7.5, 1));
    }
}
