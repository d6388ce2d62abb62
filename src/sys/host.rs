//! This process's host and clock: the host name (overridable for a process), the start time of
//! a process (to tell a live pid from a reused one), and the Unix time.

use std::fs;
use std::time::{SystemTime, UNIX_EPOCH};

/// The host name this process's claims give instead of the machine's (`sweep work --host`).
static HOST_OVERRIDE: std::sync::OnceLock<String> = std::sync::OnceLock::new();

/// Name claims of stores opened from now on after `host` (nodes that share a name; tests that
/// play two hosts on one machine). Only the first call counts.
pub fn set_host_name(host: &str) {
    let _ = HOST_OVERRIDE.set(host.to_string());
}

/// Seconds since the Unix epoch (0 for a clock before it).
pub fn unix_now() -> f64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.as_secs_f64()).unwrap_or(0.0)
}

/// This machine's host name.
pub fn hostname() -> String {
    let mut buf = [0u8; 256];
    // SAFETY: gethostname writes at most buf.len() bytes into buf.
    if unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) } != 0 {
        return "localhost".into();
    }
    let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    String::from_utf8_lossy(&buf[..end]).into_owned()
}

/// Start time of a live process in clock ticks since boot (`/proc/<pid>/stat` field 22);
/// `None` when there is no such process or it is a zombie (dead, not yet reaped).
pub fn process_start_ticks(pid: u32) -> Option<u64> {
    let stat = fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name (field 2) is in parentheses and may itself hold spaces or ')'.
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // fields[0] is field 3 (state), so field 22 (starttime) is fields[19].
    if matches!(fields.first(), Some(&"Z") | Some(&"X")) {
        return None;
    }
    fields.get(19)?.parse().ok()
}

/// The host name this process gives its claims: the one [`set_host_name`] set, else the
/// machine's.
pub fn claim_host() -> String {
    HOST_OVERRIDE.get().cloned().unwrap_or_else(hostname)
}
