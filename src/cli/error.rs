//! What the command line itself refuses or fails at: a flag's value, the JSON it prints, a
//! directory it writes a deck to.

use std::path::PathBuf;

use demsweep::Error;

#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// A flag and its value, and what was expected: `--jobs 0: expected at least 1`.
    #[error("{given}: {why}")]
    Flag { given: String, why: String },
    /// `--json` output that could not be serialised.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// `sweep run --out DIR` could not be created.
    #[error("cannot create {}: {source}", path.display())]
    Create { path: PathBuf, source: std::io::Error },
    /// `sweep render --out DIR` could not be written.
    #[error("cannot write to {}: {source}", path.display())]
    WriteTo { path: PathBuf, source: std::io::Error },
}

/// A flag is bad input (exit 2); output that cannot be written is internal (4).
impl From<CliError> for Error {
    fn from(e: CliError) -> Self {
        match e {
            CliError::Flag { .. } => Error::Input(Box::new(e)),
            CliError::Json(_) | CliError::Create { .. } | CliError::WriteTo { .. } => {
                Error::Internal(Box::new(e))
            }
        }
    }
}

/// A refused flag: `flag("--jobs 0", "expected at least 1")`; `why` may be a library's error.
pub(super) fn flag(given: impl Into<String>, why: impl std::fmt::Display) -> Error {
    CliError::Flag { given: given.into(), why: why.to_string() }.into()
}
