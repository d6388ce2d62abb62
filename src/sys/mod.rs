//! Operating-system plumbing that knows nothing of sweeps: atomic file writes and child
//! processes (groups, signals, cancellation).

pub mod atomic;
pub mod process;
