//! What can go wrong reading a sweep directory for a report or writing one: each error names the
//! file, the point or the flag.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file of the report could not be written (exit 4).
    #[error("cannot write {}: {source}", path.display())]
    Write { path: PathBuf, source: std::io::Error },
    /// The plots could not be drawn (exit 4).
    #[error("cannot draw the plots: {0}")]
    Draw(String),
    /// A CSV file given to `sweep stats` cannot be read.
    #[error("cannot read {}: {why}", path.display())]
    Read { path: PathBuf, why: String },
    /// A CSV file given to `sweep stats` is not what it should be: `file: what is wrong`.
    #[error("{}: {why}", path.display())]
    Csv { path: PathBuf, why: String },
    /// `sweep show DIR INDEX` past the last point.
    #[error("{}: no point {index}; the sweep has {points} points (indices 0 to {})", dir.display(), points.saturating_sub(1))]
    NoPoint { dir: PathBuf, index: usize, points: usize },
    /// A `--set name=value` of a prediction that is not one.
    #[error("--set {item}: {why}")]
    Set { item: String, why: String },
    /// Too few done points, or an MFR that does not vary, to fit the emulator.
    #[error("{}: no emulator: it needs at least {min} done points with MFR that varies", dir.display())]
    NoEmulator { dir: PathBuf, min: usize },
}

/// Writing the report is internal (exit 4); what the user asked of it is input (exit 2).
impl From<ReportError> for crate::Error {
    fn from(e: ReportError) -> Self {
        match e {
            ReportError::Write { .. } | ReportError::Draw(_) => crate::Error::Internal(Box::new(e)),
            _ => crate::Error::Input(Box::new(e)),
        }
    }
}
