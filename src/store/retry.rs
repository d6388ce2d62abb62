//! Retry rounds: `--retry-failed` re-runs each failed point once per invocation, however many
//! processes that invocation has.
//!
//! A round is a point in time: a failure recorded before it is retried, one recorded after it
//! (by this round's own retry) is not. Processes started with `--retry-failed` while another of
//! them is alive join its round (`DIR/retry.json` names the round and its live members); the
//! tasks of one `sweep submit --only failed` share the round of the submission
//! (`DIR/cluster/retry-round`), however far apart they start.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

use super::{io, DirLock, Store, StoreError, LOCK};
use crate::sys::host::process_start_ticks;

/// The round this process joins instead of one of its own (an array task: its submission's).
static FIXED_ROUND: OnceLock<SystemTime> = OnceLock::new();

/// `DIR/retry.json`.
#[derive(Debug, Default, Serialize, Deserialize)]
struct RoundFile {
    /// Unix time the round began, seconds.
    since: f64,
    /// Processes in the round: (host, pid, start ticks).
    members: Vec<(String, u32, u64)>,
}

fn unix(t: SystemTime) -> f64 {
    t.duration_since(UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64())
}

fn from_unix(s: f64) -> SystemTime {
    UNIX_EPOCH + Duration::from_secs_f64(s.max(0.0))
}

/// Where a submission writes its round.
pub fn submission_round_path(dir: &Path) -> PathBuf {
    dir.join("cluster").join("retry-round")
}

/// Record that a submission re-running failures begins a round now.
pub fn begin_submission_round(dir: &Path) -> Result<(), StoreError> {
    let path = submission_round_path(dir);
    crate::sys::atomic::write(&path, format!("{:.6}\n", unix(SystemTime::now())).as_bytes())
        .map_err(io(&path))
}

/// Join the round of the last submission of `dir` that re-ran failures, if there was one
/// (`sweep work`); the stores this process opens from now on retry in that round.
pub fn join_submission_round(dir: &Path) {
    let text =
        crate::sys::read::read_text_capped(&submission_round_path(dir), super::CLAIM_CAP).unwrap_or_default();
    if let Ok(s) = text.trim().parse::<f64>() {
        let _ = FIXED_ROUND.set(from_unix(s));
    }
}

impl Store {
    /// The round this process retries failures in: the submission's, or the round of the
    /// processes already retrying in this directory, or a new one beginning now.
    pub fn retry_round(&self) -> Result<SystemTime, StoreError> {
        if let Some(&t) = FIXED_ROUND.get() {
            return Ok(t);
        }
        let path = self.dir.join("retry.json");
        let _lock = DirLock::take(&self.dir.join(LOCK))?;
        let old: RoundFile = crate::sys::read::read_capped(&path, super::CLAIM_CAP)
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
            .unwrap_or_default();
        // Members on other hosts cannot be seen: a round spans one host's processes.
        let mut members: Vec<(String, u32, u64)> = old
            .members
            .into_iter()
            .filter(|(host, pid, ticks)| *host == self.host && process_start_ticks(*pid) == Some(*ticks))
            .collect();
        let since = if members.is_empty() { unix(SystemTime::now()) } else { old.since };
        members.push((self.host.clone(), self.me.pid, self.me.start_ticks));
        let text = serde_json::to_vec(&RoundFile { since, members }).expect("round serialises");
        crate::sys::atomic::write(&path, &text).map_err(io(&path))?;
        Ok(from_unix(since))
    }
}
