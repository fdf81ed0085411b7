//! A software rasteriser for scenes and charts: PNG frames, animated GIF and APNG, no GPU.
//!
//! # Pipeline
//!
//! ```text
//! Scene (f64, m)  --Camera/View-->  pixels (f32)  --painter's algorithm-->  tiny_skia::Pixmap
//!                                                                             |
//!                              encoder thread (PNG files, GIF, APNG)  <-------+  bounded channel
//! ```
//!
//! - [`camera`]: the orbiting camera, perspective and orthographic projection, the default view
//!   that frames a scene ([`Camera::for_scene`]).
//! - [`draw`]: a [`Renderer`] draws springs (coloured by kind or by strain), particles (pinned
//!   ones marked), cloth and jelly lattices as Lambert-shaded surfaces, colliders (floors with
//!   their hole and grid, bowls, tilted planes, spheres with a radial gradient) and a text
//!   overlay, back to front.
//! - `occlude`: terrain that hides: shapes that cross a floor are cut along it (what is below
//!   shows only through the hole), shapes a sphere hides are sorted behind it.
//! - `shadow`: soft shadows of bodies, particles and spheres on the floors and planes (on by
//!   default, [`Style::shadows`]), spheres shading the surfaces, a bowl's wall and the floor's
//!   rim shading its inside; one light with the Lambert shading.
//! - [`surface`]: recognising a cloth (grid) or jelly (block) from a body's struct springs.
//! - [`text`]: the bundled font (DejaVu Sans Mono) and text drawing; no system fonts.
//! - [`chart`]: line and scatter charts with linear or log-log axes, for `--energy-chart` and
//!   the studies.
//! - [`export`]: PNG files, GIF and APNG, encoded on their own thread.
//!
//! All real numbers stay `f64` until a point is projected; only pixel coordinates are `f32`.
//! Output is deterministic: the same scene, camera and style give the same pixels, and the
//! encoders the same bytes.

pub mod camera;
pub mod chart;
pub mod colour;
pub mod draw;
pub mod export;
mod occlude;
mod paint;
mod shadow;
pub mod style;
pub mod surface;
mod terrain;
pub mod text;

pub use camera::{Aabb, Camera, Projection, View, scene_bounds};
pub use chart::{Chart, Scale, Series, SeriesStyle};
pub use colour::Colour;
pub use draw::{Renderer, check_size};
pub use export::{FrameEncoder, Outputs};
pub use style::{Colouring, KindToggles, Overlay, Style};
pub use surface::Lattice;

/// The largest image side accepted (px).
pub const MAX_SIDE: u32 = 8192;

/// Rasteriser settings shared by scenes and charts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quality {
    /// Anti-aliased edges (default true).
    pub anti_alias: bool,
    /// Always use tiny-skia's f32 pipeline instead of its faster u16 one. Tests set it, as
    /// tiny-skia's own do, so that golden images do not depend on which pipeline a shape gets.
    pub force_hq_pipeline: bool,
}

impl Default for Quality {
    fn default() -> Quality {
        Quality {
            anti_alias: true,
            force_hq_pipeline: false,
        }
    }
}

impl Quality {
    /// Anti-aliased, high-precision pipeline: what golden-image tests use.
    pub const TEST: Quality = Quality {
        anti_alias: true,
        force_hq_pipeline: true,
    };
}

/// What can go wrong when rendering or writing images.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// An image side is zero or too large.
    #[error(
        "image size {width}x{height} is out of range: width and height must be 1 to {max} pixels",
        max = MAX_SIDE
    )]
    Size {
        /// Width asked for (px).
        width: u32,
        /// Height asked for (px).
        height: u32,
    },
    /// A file or directory cannot be created or written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file or directory.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// An encoder failed.
    #[error("cannot encode {path}: {message}")]
    Encode {
        /// The file.
        path: String,
        /// The encoder's message.
        message: String,
    },
}
