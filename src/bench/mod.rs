//! Benchmarks behind `sweep bench`: run time against error of the fidelity presets
//! ([`fidelity`]), the scene's stability edge ([`stability`]), the contact reference
//! solver's own stability ([`contact`]), and the designs against a known answer ([`designs`]).
//!
//! The top of the pipeline beside the command line: a bench may use every stage below it.

pub mod contact;
pub mod designs;
pub mod fidelity;
pub mod stability;

/// An optional number with `digits` decimals, or `absent` when there is none: the one formatter
/// of the benches' fixed-point cells.
pub fn opt_or(v: Option<f64>, digits: usize, absent: &str) -> String {
    v.map_or_else(|| absent.to_string(), |v| format!("{v:.digits$}"))
}

/// An optional number with `digits` decimals, empty when absent (a CSV cell).
pub fn opt(v: Option<f64>, digits: usize) -> String {
    opt_or(v, digits, "")
}

/// `v` in scientific notation for a table cell, or "-".
pub fn cell(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.2e}"))
}

/// What a bench refuses or fails at: a flag, a file of its output, a plot, LIGGGHTS.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A flag's value: `--variant fine: expected NAME:key=value,...`.
    #[error("{given}: {why}")]
    Flag { given: String, why: String },
    /// The output directory could not be created.
    #[error("cannot create {}: {source}", path.display())]
    Create { path: std::path::PathBuf, source: std::io::Error },
    /// An output file could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Write { path: std::path::PathBuf, source: std::io::Error },
    /// The bench's figure could not be drawn.
    #[error("{bench} plot: {why}")]
    Plot { bench: &'static str, why: String },
    /// A thread running one case panicked.
    #[error("run thread panicked")]
    Panicked,
    /// LIGGGHTS ran none of the contact timestep ladder's cases.
    #[error("LIGGGHTS failed on every ladder case: {first}")]
    NoLadderCase { first: String },
}

/// A flag is bad input (exit 2), LIGGGHTS failing every case is the engine (3), the rest is
/// internal (4).
impl From<BenchError> for crate::Error {
    fn from(e: BenchError) -> Self {
        match e {
            BenchError::Flag { .. } => crate::Error::Input(Box::new(e)),
            BenchError::NoLadderCase { .. } => crate::Error::Engine(Box::new(e)),
            _ => crate::Error::Internal(Box::new(e)),
        }
    }
}
