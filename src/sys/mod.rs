//! Operating-system plumbing that knows nothing of sweeps: atomic file writes, child processes
//! (groups, signals, cancellation), the host's identity, disk-space diagnostics, bounded reads
//! of files others may have replaced, and quoting a word for the shell.

pub mod atomic;
pub mod disk;
pub mod host;
pub mod process;
pub mod read;
pub mod shell;

pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
