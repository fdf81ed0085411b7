//! What the scene pane shows and where: which springs (`t`) and the projection between the
//! pane's cells and the world.
//!
//! Every view projects with [`View`]: the pane's inner `w × h` cells are an image of
//! `2w × 4h` braille dots (a dot is square on a cell of aspect 1 : 2), `w × 2h` half-block
//! pixels, or `w·c_w × h·c_h` pixels of the terminal's font cell (raster). These have the same
//! aspect ratio, so the camera shows the same region of the world in each, and [`pick`] and
//! [`cell_to_world`] (the mouse) invert the same projection.

use glam::DVec3;
use ratatui::layout::Rect;

use crate::physics::SpringKind;
use crate::render::{Camera, View};
use crate::simulation::Simulation;

/// Which spring kinds are drawn (`t` cycles through them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SpringFilter {
    /// Every spring.
    All,
    /// Structural springs only.
    Struct,
    /// Shear springs only.
    Shear,
    /// Bend springs only.
    Bend,
    /// No springs, particles only.
    None,
}

impl SpringFilter {
    /// The next filter in the cycle all → struct → shear → bend → none → all.
    #[must_use]
    pub fn next(self) -> SpringFilter {
        match self {
            SpringFilter::All => SpringFilter::Struct,
            SpringFilter::Struct => SpringFilter::Shear,
            SpringFilter::Shear => SpringFilter::Bend,
            SpringFilter::Bend => SpringFilter::None,
            SpringFilter::None => SpringFilter::All,
        }
    }

    /// Whether springs of `kind` are drawn.
    #[must_use]
    pub fn shows(self, kind: SpringKind) -> bool {
        match self {
            SpringFilter::All => true,
            SpringFilter::Struct => kind == SpringKind::Struct,
            SpringFilter::Shear => kind == SpringKind::Shear,
            SpringFilter::Bend => kind == SpringKind::Bend,
            SpringFilter::None => false,
        }
    }

    /// Its name in the status line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            SpringFilter::All => "all",
            SpringFilter::Struct => "struct",
            SpringFilter::Shear => "shear",
            SpringFilter::Bend => "bend",
            SpringFilter::None => "none",
        }
    }
}

/// Braille dots per cell across and down (the grid of the braille and half-block views: a
/// half-block pixel is two dots square).
pub const DOTS: (u32, u32) = (2, 4);

/// The view of `camera` on a pane with inner area `inner` whose cells are `grid` pixels (dots)
/// across and down: [`DOTS`] for the braille and half-block views, the font cell for raster.
#[must_use]
pub fn grid_view(camera: &Camera, inner: Rect, grid: (u32, u32)) -> View {
    View::new(
        camera,
        u32::from(inner.width.max(1)) * grid.0.max(1),
        u32::from(inner.height.max(1)) * grid.1.max(1),
    )
}

/// The view of `camera` on the braille dots of a pane with inner area `inner`.
#[must_use]
pub fn dot_view(camera: &Camera, inner: Rect) -> View {
    grid_view(camera, inner, DOTS)
}

/// The world point (m) under the centre of cell `(column, row)` of the pane `inner` (cells of
/// `grid` pixels), at depth `depth` (m) from the eye.
#[must_use]
pub fn cell_to_world(
    camera: &Camera,
    inner: Rect,
    grid: (u32, u32),
    column: u16,
    row: u16,
    depth: f64,
) -> DVec3 {
    let view = grid_view(camera, inner, grid);
    let x = (f64::from(column) - f64::from(inner.x) + 0.5) * f64::from(grid.0);
    let y = (f64::from(row) - f64::from(inner.y) + 0.5) * f64::from(grid.1);
    view.unproject(x, y, depth)
}

/// The particle nearest to cell `(column, row)` of the pane `inner` (cells of `grid` pixels),
/// within 3 columns (distances measured in pixels, so rows count by their height):
/// `(body, particle, depth)`; the nearest to the eye wins a tie.
#[must_use]
pub fn pick(
    camera: &Camera,
    sim: &Simulation,
    inner: Rect,
    grid: (u32, u32),
    column: u16,
    row: u16,
) -> Option<(usize, usize, f64)> {
    if !contains(inner, column, row) {
        return None;
    }
    let view = grid_view(camera, inner, grid);
    let cx = (f64::from(column - inner.x) + 0.5) * f64::from(grid.0);
    let cy = (f64::from(row - inner.y) + 0.5) * f64::from(grid.1);
    let reach2 = (3.0 * f64::from(grid.0)).powi(2);
    let mut best: Option<(usize, usize, f64, f64)> = None;
    for (b, body) in sim.scene.bodies.iter().enumerate() {
        for (i, p) in body.state.x.iter().enumerate() {
            let Some(q) = view.project(*p) else {
                continue;
            };
            let d2 = (f64::from(q.x) - cx).powi(2) + (f64::from(q.y) - cy).powi(2);
            let better = best.is_none_or(|(_, _, bz, bd)| {
                d2 < bd - 1e-9 || ((d2 - bd).abs() <= 1e-9 && q.depth < bz)
            });
            if d2.is_finite() && d2 <= reach2 && better {
                best = Some((b, i, q.depth, d2));
            }
        }
    }
    best.map(|(b, i, z, _)| (b, i, z))
}

/// Whether cell `(column, row)` lies in `r`.
#[must_use]
pub fn contains(r: Rect, column: u16, row: u16) -> bool {
    column >= r.x && column < r.x + r.width && row >= r.y && row < r.y + r.height
}
