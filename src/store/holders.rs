//! Who holds a claim, said plainly, and the ways out of a claim that stands for nobody.
//!
//! A claim from another host stands while its lease runs (and for good if it has no lease, as
//! older versions wrote them); `sweep unclaim DIR` releases such claims once the user knows
//! their owner is gone. A claim left in a finished run directory by a process killed between
//! its result and its joblog line, or torn by a kill as it was written, is removed on resume,
//! which writes any missing line.

use std::fs;

use super::claim::read_claim;
use super::{lease_alive, ClaimInfo, DirLock, RunState, Store, StoreError, LOCK};
use crate::sys::host::unix_now;

/// Who holds a finished run ([`Store::free_finished`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FinishedHolder {
    /// A live process: it writes the run's joblog line itself.
    Live,
    /// Nobody; `claimed_at` (Unix seconds) is when the last attempt claimed it, if its claim said.
    Nobody { claimed_at: Option<f64> },
}

/// One line about a claim's holder: host, pid, age, and its lease.
pub fn describe(c: &ClaimInfo) -> String {
    let now = unix_now();
    let age = |t: f64| {
        let s = (now - t).abs();
        let v = if s < 120.0 {
            format!("{s:.0} s")
        } else if s < 7200.0 {
            format!("{:.0} min", s / 60.0)
        } else {
            format!("{:.1} h", s / 3600.0)
        };
        if t > now {
            format!("{v} in the future")
        } else {
            format!("{v} ago")
        }
    };
    let lease = match (c.lease_s, c.renewed_at) {
        (Some(l), Some(r)) if r > now + l => {
            format!("lease {l:.0} s, renewed {} (its host's clock is ahead; it stands until then)", age(r))
        }
        (Some(l), Some(r)) if lease_alive(c, now) => format!("lease {l:.0} s, renewed {}", age(r)),
        (Some(l), Some(r)) => format!("lease {l:.0} s, expired: last renewed {}", age(r)),
        _ => "no lease: it stands until released".into(),
    };
    format!("held by {} pid {}, claimed {}; {lease}", c.host, c.pid, age(c.claimed_at))
}

impl Store {
    /// Release every claim not held by a live process of this host (other hosts' claims, and
    /// claims of dead processes here): `sweep unclaim DIR`, for when their owners are known to
    /// be gone. Returns the claims released, by hash, and how many live ones were kept.
    pub fn unclaim(&self, hashes: &[String]) -> Result<(Vec<(String, ClaimInfo)>, usize), StoreError> {
        let _lock = DirLock::take(&self.dir.join(LOCK))?;
        let (mut released, mut kept) = (Vec::new(), 0);
        for h in hashes {
            let path = self.run_dir(h).join("claim");
            let Some(c) = read_claim(&path) else {
                if path.exists() {
                    // Unreadable: its writer died mid-write.
                    fs::remove_file(&path).map_err(super::io(&path))?;
                }
                continue;
            };
            if c.host == self.host && self.owner_alive(&c) {
                kept += 1;
                continue;
            }
            fs::remove_file(&path).map_err(super::io(&path))?;
            released.push((h.clone(), c));
        }
        Ok((released, kept))
    }

    /// Clear the finished run `hash` of a claim that stands for nobody: one left by a process
    /// that is gone, or one cut off while it was being written (its writer held the lock, so it
    /// died). Says whether a live process still holds the run.
    pub fn free_finished(&self, hash: &str) -> Result<FinishedHolder, StoreError> {
        let path = self.run_dir(hash).join("claim");
        if !path.exists() {
            return Ok(FinishedHolder::Nobody { claimed_at: None });
        }
        let _lock = DirLock::take(&self.dir.join(LOCK))?;
        let claimed_at = match read_claim(&path) {
            Some(c) if self.owner_alive(&c) => return Ok(FinishedHolder::Live),
            Some(c) => Some(c.claimed_at),
            None if !path.exists() => return Ok(FinishedHolder::Nobody { claimed_at: None }),
            None => None,
        };
        if !matches!(self.finished(hash), Some(RunState::Done(_) | RunState::Failed(_))) {
            return Ok(FinishedHolder::Live);
        }
        fs::remove_file(&path).map_err(super::io(&path))?;
        Ok(FinishedHolder::Nobody { claimed_at })
    }
}
