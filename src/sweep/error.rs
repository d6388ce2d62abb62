//! What can be wrong with a sweep file: each error names the file and the key.

use std::path::PathBuf;

/// A sweep file that cannot be read or is not a valid sweep. Always bad input.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// The file cannot be read: missing, a directory, not permitted.
    #[error("cannot read sweep file {}: {why}", path.display())]
    Read { path: PathBuf, why: String },
    /// Not TOML, or a key the schema does not know: `file:line: key: message`.
    #[error("{}{}:{} {why}", path.display(), at_line(*line), at_key(key.as_deref()))]
    Syntax { path: PathBuf, line: Option<usize>, key: Option<String>, why: String },
    /// A key whose value makes no sense: `file: key: what was expected`.
    #[error("{}: {key}: {why}", path.display())]
    Key { path: PathBuf, key: String, why: String },
}

fn at_line(line: Option<usize>) -> String {
    line.map(|l| format!(":{l}")).unwrap_or_default()
}

fn at_key(key: Option<&str>) -> String {
    key.map(|k| format!(" {k}:")).unwrap_or_default()
}

impl From<SweepError> for crate::Error {
    fn from(e: SweepError) -> Self {
        crate::Error::Input(Box::new(e))
    }
}
