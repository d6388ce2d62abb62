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

/// What a command that is not a sweep's run says when a signal stops it: `note` (what stopped,
/// the command that goes on) is also the line the interrupt's watchdog says should the process
/// have to end before the command returns. Returns the mapping of the command's error: an
/// interruption said once, as `interrupted: NOTE`, not a bare `error: interrupted`.
pub(super) fn on_interrupt_say(note: String) -> impl Fn(Error) -> Error {
    demsweep::sys::process::on_interrupt_say(note.clone());
    move |e| match e {
        Error::Interrupted => {
            eprintln!("interrupted: {note}");
            Error::InterruptedSaid
        }
        e => e,
    }
}

/// The command line as typed, `sweep` and its arguments quoted for a shell: the command that
/// goes on where running it again resumes (an interrupted `sweep bench fidelity`).
pub(super) fn this_command() -> String {
    let args: Vec<String> =
        std::env::args().skip(1).map(|a| demsweep::sys::shell::quote(&a).into_owned()).collect();
    format!("sweep {}", args.join(" "))
}
