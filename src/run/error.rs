//! What the drivers refuse or fail at: a design, an output directory that is not this sweep's, a
//! sweep directory whose manifest disagrees with itself, the writes of a session; and for a
//! cluster, the flags of a submission, its layout file, the scheduler.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// A design that cannot be laid out: `lattice level 1: expected at least 2 values ...`.
    #[error("{design}: {why}")]
    Design { design: String, why: String },
    /// An `--out` that cannot become (or is not) this sweep's directory.
    #[error("{}: {why}; choose another --out", dir.display())]
    OutDir { dir: PathBuf, why: String },
    /// A sweep directory (or its manifest) that does not match itself or the sweep.
    #[error("{}: {why}", path.display())]
    Dir { path: PathBuf, why: String },
    /// A file of the sweep directory could not be written.
    #[error("{}: {source}", path.display())]
    Write { path: PathBuf, source: std::io::Error },
    /// The resolved sweep file could not be written out (a broken invariant).
    #[error("resolved sweep: {0}")]
    Resolve(String),
    /// Results or joblog lines could not be written; no run started after the first failure.
    #[error(
        "{first}{}; started no run after it; once that is fixed, `sweep resume {}` finishes the sweep",
        in_all(*count),
        crate::sys::shell::quote_path(dir)
    )]
    Writes { first: String, count: usize, dir: PathBuf },
}

fn in_all(count: usize) -> String {
    match count {
        0 | 1 => String::new(),
        n => format!(" ({n} write errors in all)"),
    }
}

/// Failed writes are internal (exit 4); everything else is what the user gave (exit 2).
impl From<RunError> for crate::Error {
    fn from(e: RunError) -> Self {
        match e {
            RunError::Write { .. } | RunError::Resolve(_) | RunError::Writes { .. } => {
                crate::Error::Internal(Box::new(e))
            }
            _ => crate::Error::Input(Box::new(e)),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ClusterError {
    /// A flag or value of `sweep submit` / `sweep work`: `--tasks 0: expected at least 1`.
    #[error("{given}: {why}")]
    Flag { given: String, why: String },
    /// A file of `DIR/cluster/` (or the directory itself) that is not what it should be.
    #[error("{}: {why}", path.display())]
    File { path: PathBuf, why: String },
    /// A file of `DIR/cluster/` that could not be read or written.
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    /// The scheduler script template does not render.
    #[error("{name}: {why}")]
    Template { name: String, why: String },
    /// The scheduler's submit command could not be started.
    #[error("cannot run {cmd}: {source}")]
    Start { cmd: String, source: std::io::Error },
    /// The scheduler refused a script.
    #[error("{cmd} {} failed ({status}): {stderr}", script.display())]
    Submit { cmd: String, script: PathBuf, status: String, stderr: String },
}

/// The cluster's files and scheduler are internal (exit 4); the flags and layout are input (2).
impl From<ClusterError> for crate::Error {
    fn from(e: ClusterError) -> Self {
        match e {
            ClusterError::Io { .. } | ClusterError::Start { .. } | ClusterError::Submit { .. } => {
                crate::Error::Internal(Box::new(e))
            }
            _ => crate::Error::Input(Box::new(e)),
        }
    }
}
