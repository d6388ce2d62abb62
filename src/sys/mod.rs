//! Operating-system plumbing that knows nothing of sweeps: atomic file writes, child processes
//! (groups, signals, cancellation), the host's identity and disk-space diagnostics.

pub mod atomic;
pub mod disk;
pub mod host;
pub mod process;

pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
