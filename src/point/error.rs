//! Why one point cannot be built: a `--set` that is not one, a scene the sweep's values cannot
//! make, a template that does not render. All bad input (exit 2).

use std::path::{Path, PathBuf};

use crate::point::deck::DeckError;
use crate::scene::SceneError;

#[derive(Debug, thiserror::Error)]
pub enum PointError {
    /// A `--set name=value` that is not one: `--set gap=x: expected a finite number`.
    #[error("--set {item}: {why}")]
    Set { item: String, why: String },
    /// The sweep names a layout that does not exist.
    #[error(transparent)]
    Layout(SceneError),
    /// The scene of a point cannot be built from the values: `sweep.toml: parameter ...`.
    #[error("{}: {source}", path.display())]
    Scene { path: PathBuf, source: SceneError },
    /// The template cannot be read or rendered.
    #[error(transparent)]
    Deck(#[from] DeckError),
    /// A point of `sweep run` / `render` refused, naming the `--set` it came with.
    #[error("{} with --set {set}: {why}", path.display())]
    WithSet { path: PathBuf, set: String, why: String },
}

impl PointError {
    /// The same refusal, naming the `--set name=value,...` of the point it refuses.
    pub fn with_set(self, path: &Path, set: &[String]) -> PointError {
        let why = match &self {
            PointError::Scene { source, .. } => source.to_string(),
            e => e.to_string(),
        };
        PointError::WithSet { path: path.to_path_buf(), set: set.join(","), why }
    }
}

impl From<PointError> for crate::Error {
    fn from(e: PointError) -> Self {
        crate::Error::Input(Box::new(e))
    }
}
