//! `e` on a lesson: the current frame as a PNG file, drawn by the render module (tiny-skia).

use std::path::{Path, PathBuf};

use crate::render::{Projection, Renderer, Style, export};
use crate::simulation::Simulation;

/// Size of an exported frame (pixels).
pub const EXPORT_SIZE: (u32, u32) = (1280, 720);

/// Writes the scene of `sim` as it is now, seen from the terminal view's angles (`yaw`, `pitch`
/// in rad), to the PNG file `path`; returns the path written.
///
/// # Errors
/// A message for the status line when the file cannot be written.
pub fn export_png(sim: &Simulation, yaw: f64, pitch: f64, path: &Path) -> Result<PathBuf, String> {
    let (w, h) = EXPORT_SIZE;
    let mut renderer = Renderer::new(&sim.scene, w, h, Projection::default(), Style::default())
        .map_err(|e| e.to_string())?;
    // The terminal view turns the world by `yaw` about the vertical axis (its right vector is
    // (cos yaw, 0, sin yaw)); the render camera orbits its eye by `orbit` (right vector
    // (cos orbit, 0, -sin orbit)): the same view has orbit = -yaw. Both raise the eye by the
    // elevation angle.
    renderer.camera.orbit = -yaw;
    renderer.camera.elevation = pitch;
    renderer.refit(&sim.scene);
    let pixmap = renderer.draw_simulation(sim);
    export::save_png(&pixmap, path).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path.to_path_buf())
}
