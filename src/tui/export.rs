//! `e` on a lesson: the scene pane's view as a PNG file, drawn by the render module (tiny-skia).
//!
//! The file shows exactly what the pane shows: the same camera (so the same framing), at
//! [`EXPORT_WIDTH`] pixels across and the pane's aspect ratio, with the text overlay (scene,
//! method, dt, t, energy) in a band above the picture and the colour legend in a band below, so
//! that neither covers a body.

use std::path::{Path, PathBuf};

use super::pane::SpringFilter;
use super::raster::PaneRenderer;
use crate::render::Camera;
use crate::render::{Overlay, export};
use crate::simulation::Simulation;

/// Width of an exported frame (pixels); the height follows the pane's aspect ratio.
pub const EXPORT_WIDTH: u32 = 1280;

/// The size of the exported image for a pane of aspect `aspect` (width / height): 1280 pixels
/// across, the height rounded, between 90 and 4096 pixels.
#[must_use]
pub fn export_size(aspect: f64) -> (u32, u32) {
    let h = (f64::from(EXPORT_WIDTH) / aspect).round();
    let h = if h.is_finite() {
        h.clamp(90.0, 4096.0)
    } else {
        720.0
    };
    (EXPORT_WIDTH, h as u32)
}

/// Writes the scene of `sim` as its pane shows it now (the scene's structure at `generation`,
/// seen by `camera` with springs `filter`, on a pane of aspect `aspect`) to the PNG file `path`;
/// returns the path written.
///
/// # Errors
/// A message for the status line when the file cannot be written.
pub fn export_png(
    sim: &Simulation,
    generation: u64,
    camera: &Camera,
    filter: SpringFilter,
    aspect: f64,
    path: &Path,
) -> Result<PathBuf, String> {
    let pixmap = PaneRenderer::default().draw(
        &sim.scene,
        generation,
        camera,
        filter,
        export_size(aspect),
        Some(&Overlay::of(sim)),
    );
    export::save_png(&pixmap, path).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path.to_path_buf())
}
