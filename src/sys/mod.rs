//! Operating-system plumbing that knows nothing of sweeps: atomic file writes, child processes
//! (groups, signals, cancellation), the host's identity, disk-space diagnostics and bounded reads
//! of files others may have replaced.

pub mod atomic;
pub mod disk;
pub mod host;
pub mod process;
pub mod read;

pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
