//! Scene files in TOML (placeholder replaced below).
use std::path::Path;

use super::{Scene, SceneError};

/// Loads a scene file.
///
/// # Errors
/// Always, for now.
pub fn load(path: &Path, _sets: &[String]) -> Result<Scene, SceneError> {
    Err(SceneError::Invalid(format!(
        "{}: scene files are not supported yet",
        path.display()
    )))
}
