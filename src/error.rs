//! The top-level error type and the exit codes it maps to.
//!
//! Each folder returns its own `thiserror` enum naming the file, key, value or run it is about
//! (`sweep::SweepError`, `store::StoreError`, `run::RunError`, ...). This file sits below them
//! all, so it cannot name them: each folder converts its enum into [`Error`] in its own file
//! (`impl From<SweepError> for crate::Error`), choosing per variant what kind of failure it is —
//! bad input, the engine, or internal — and keeping the folder's error as the source. What a
//! kind means to the shell is decided here, once, in [`Error::code`].

/// Exit codes, documented in `sweep --help` and docs/results.md "Exit codes".
pub mod exit {
    /// Everything asked for was done.
    pub const SUCCESS: i32 = 0;
    /// A sweep finished, but some runs failed (they are listed, never averaged in).
    pub const RUNS_FAILED: i32 = 1;
    /// Bad input: a sweep file, a flag or a value. Nothing on disk was changed.
    pub const BAD_INPUT: i32 = 2;
    /// The engine (LIGGGHTS) could not be found, started, or failed on a single run.
    pub const ENGINE: i32 = 3;
    /// An I/O or internal failure.
    pub const INTERNAL: i32 = 4;
    /// Interrupted (Ctrl-C); the sweep directory is resumable. Death by signal n is 128 + n, so
    /// SIGTERM is 143.
    pub const INTERRUPTED: i32 = 130;
}

/// A folder's error, kept whole as the source of an [`Error`].
pub type Source = Box<dyn std::error::Error + Send + Sync + 'static>;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad user input; the message names the file, key or value and what was expected.
    #[error(transparent)]
    Input(Source),
    /// The engine failed (not found, or a single run failed).
    #[error(transparent)]
    Engine(Source),
    /// An I/O failure or a broken invariant.
    #[error(transparent)]
    Internal(Source),
    /// Interrupted (Ctrl-C / SIGTERM) before anything was said about it.
    #[error("interrupted")]
    Interrupted,
    /// Interrupted (Ctrl-C / SIGTERM); the command said what stopped and the command that goes
    /// on (`sweep extend`, `sweep bench`).
    #[error("interrupted")]
    InterruptedSaid,
    /// A sweep stopped by a signal; it said how far it got and how to resume.
    #[error("interrupted: {finished} of {total} points finished")]
    SweepInterrupted { finished: usize, total: usize },
    /// A sweep, a run or a check finished with `failed` of its `total` runs failed; they were
    /// listed where they happened, never averaged in.
    #[error("{failed} of {total} runs failed")]
    RunsFailed { failed: usize, total: usize },
}

impl Error {
    /// The process exit code: the one place where a failure becomes a number.
    pub fn code(&self) -> i32 {
        match self {
            Error::Input(_) => exit::BAD_INPUT,
            Error::Engine(_) => exit::ENGINE,
            Error::Internal(_) => exit::INTERNAL,
            // Death by signal n is 128 + n (SIGINT: 130, SIGTERM: 143).
            Error::Interrupted | Error::InterruptedSaid | Error::SweepInterrupted { .. } => {
                crate::sys::process::interrupt_signal().map_or(exit::INTERRUPTED, |s| 128 + s)
            }
            Error::RunsFailed { .. } => exit::RUNS_FAILED,
        }
    }

    /// Whether the command has already said this on stderr (the failed runs with their reasons,
    /// how far an interrupted sweep got), so that `main` adds no line of its own.
    pub fn told(&self) -> bool {
        matches!(self, Error::RunsFailed { .. } | Error::InterruptedSaid | Error::SweepInterrupted { .. })
    }
}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error::Internal(Box::new(e))
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// The closest candidate to `word` for a "did you mean" hint, if any is close enough.
/// Close means a Jaro–Winkler similarity above 0.8, or for short words one edit or swap of two
/// neighbours (`gpa` for `gap`, where Jaro–Winkler sees too little).
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let candidates: Vec<&str> = candidates.into_iter().collect();
    candidates
        .iter()
        .map(|c| (strsim::jaro_winkler(word, c), *c))
        .filter(|(score, _)| *score > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| c)
        .or_else(|| {
            (word.chars().count() >= 3)
                .then(|| candidates.iter().find(|c| strsim::osa_distance(word, c) == 1).copied())
                .flatten()
        })
}

/// `" (did you mean `x`?)"` or an empty string.
pub fn hint<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    did_you_mean(word, candidates).map(|c| format!(" (did you mean `{c}`?)")).unwrap_or_default()
}

/// The result of drawing a figure: plotters and resvg fail with errors of their own types.
pub type Res<T> = std::result::Result<T, Box<dyn std::error::Error>>;

#[cfg(test)]
mod tests {
    use super::{exit, Error};

    #[test]
    fn each_kind_of_failure_ends_with_its_documented_exit_code() {
        let io = || std::io::Error::other("disk on fire");
        assert_eq!(Error::Input("a flag".into()).code(), exit::BAD_INPUT);
        assert_eq!(Error::Engine("no LIGGGHTS".into()).code(), exit::ENGINE);
        assert_eq!(Error::from(io()).code(), exit::INTERNAL);
        assert_eq!(Error::RunsFailed { failed: 2, total: 9 }.code(), exit::RUNS_FAILED);
        // The folder's error is the message, unchanged.
        assert_eq!(Error::from(io()).to_string(), "disk on fire");
        // Failed runs and a stopped sweep were reported where they happened; the rest is not.
        assert!(Error::RunsFailed { failed: 2, total: 9 }.told());
        assert!(Error::SweepInterrupted { finished: 3, total: 9 }.told());
        assert!(Error::InterruptedSaid.told());
        assert!(!Error::Interrupted.told() && !Error::from(io()).told());
    }

    #[test]
    fn swapped_letters_of_a_short_name_get_a_suggestion() {
        assert_eq!(super::did_you_mean("gpa", ["gap", "diameter"]), Some("gap"));
        assert_eq!(super::did_you_mean("frction", ["gap", "friction"]), Some("friction"));
        assert_eq!(super::did_you_mean("xyz", ["gap", "diameter"]), None);
    }
}
