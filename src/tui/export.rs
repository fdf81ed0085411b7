//! `e` on a lesson: the current frame as a PNG file.
//!
//! The picture is drawn by the render module (tiny-skia); until it is part of the crate this
//! returns an error that says so, and the lesson shows it in its message line.

use std::path::{Path, PathBuf};

use crate::simulation::Simulation;

/// Writes the scene of `sim` as it is now to the PNG file `path`; returns the path written.
///
/// # Errors
/// A message for the status line: for now always that the render module is missing.
pub fn export_png(sim: &Simulation, path: &Path) -> Result<PathBuf, String> {
    let _ = (sim, path);
    Err("PNG export needs the render module".to_string())
}
