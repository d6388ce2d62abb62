//! The top-level error type and the exit codes it maps to.
//!
//! Library modules return their own `thiserror` enums; this type is what the CLI sees, and its
//! [`Error::code`] is the process exit code (`sweep --help` lists them).

/// Exit codes, documented in `sweep --help` and the README.
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
    /// Interrupted (Ctrl-C / SIGTERM); the sweep directory is resumable.
    pub const INTERRUPTED: i32 = 130;
}

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad user input; the message names the file, key or value and what was expected.
    #[error("{0}")]
    Input(String),
    /// The engine failed (not found, or a single run failed).
    #[error("{0}")]
    Engine(String),
    /// A feature that a later release fills.
    #[error("`sweep {0}` is not implemented yet")]
    NotYet(&'static str),
    #[error("{0}")]
    Internal(String),
    #[error("interrupted")]
    Interrupted,
    /// A sweep finished with this many failed runs.
    #[error("{0} run(s) failed")]
    RunsFailed(usize),
}

impl Error {
    pub fn code(&self) -> i32 {
        match self {
            Error::Input(_) | Error::NotYet(_) => exit::BAD_INPUT,
            Error::Engine(_) => exit::ENGINE,
            Error::Internal(_) => exit::INTERNAL,
            // Death by signal n is 128 + n (SIGINT: 130, SIGTERM: 143).
            Error::Interrupted => {
                crate::sys::process::interrupt_signal().map_or(exit::INTERRUPTED, |s| 128 + s)
            }
            Error::RunsFailed(_) => exit::RUNS_FAILED,
        }
    }

    pub fn input(msg: impl Into<String>) -> Self {
        Error::Input(msg.into())
    }
}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error::Internal(e.to_string())
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// The closest candidate to `word` for a "did you mean" hint, if any is close enough.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (strsim::jaro_winkler(word, c), c))
        .filter(|(score, _)| *score > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| c)
}

/// `" (did you mean `x`?)"` or an empty string.
pub fn hint<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    did_you_mean(word, candidates).map(|c| format!(" (did you mean `{c}`?)")).unwrap_or_default()
}

/// The result of drawing a figure: plotters and resvg fail with errors of their own types.
pub type Res<T> = std::result::Result<T, Box<dyn std::error::Error>>;
