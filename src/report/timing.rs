//! How long a sweep's runs took: wall time (the union of their attempts) and core-seconds, from
//! `joblog.tsv` (summary.json `timing`).

use std::path::Path;

use serde::Serialize;

#[derive(Debug, Clone, Serialize)]
pub struct Timing {
    /// Time during which at least one run was going (union of the joblog's attempts), s.
    pub wall_time_s: f64,
    /// Sum of every attempt's run time, s.
    pub core_seconds: f64,
    pub attempts: usize,
}

/// Wall time (union of attempts) and core-seconds from `joblog.tsv`, read by column name.
pub(super) fn of(dir: &Path) -> Timing {
    let text = crate::sys::read::read_text_capped(&dir.join("joblog.tsv"), crate::store::JOBLOG_CAP)
        .unwrap_or_default();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    // The columns of GNU parallel's joblog, or of an earlier version's.
    let (Some(si), Some(ri)) = (col("Starttime").or(col("start")), col("JobRuntime").or(col("runtime_s")))
    else {
        return Timing { wall_time_s: 0.0, core_seconds: 0.0, attempts: 0 };
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
    Timing { wall_time_s: wall, core_seconds, attempts }
}
