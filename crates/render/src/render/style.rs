//! What a frame shows and how: which spring kinds, the colouring, the overlay text.
//!
//! [`Style`] and [`Overlay`] are plain data chosen by the user (CLI flags, lesson keys);
//! [`super::draw::Renderer`] reads them when it turns a scene into shapes.

use super::Quality;
use crate::physics::SpringKind;
use crate::simulation::Simulation;

/// Which spring kinds are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KindToggles {
    /// Draw struct springs.
    pub struct_: bool,
    /// Draw shear springs.
    pub shear: bool,
    /// Draw bend springs.
    pub bend: bool,
}

impl KindToggles {
    /// Every kind on.
    pub const ALL: KindToggles = KindToggles {
        struct_: true,
        shear: true,
        bend: true,
    };
    /// Every kind off.
    pub const NONE: KindToggles = KindToggles {
        struct_: false,
        shear: false,
        bend: false,
    };

    /// True when springs of `kind` are drawn.
    #[must_use]
    pub fn shows(&self, kind: SpringKind) -> bool {
        match kind {
            SpringKind::Struct => self.struct_,
            SpringKind::Shear => self.shear,
            SpringKind::Bend => self.bend,
        }
    }

    /// The toggles with `kind` set to `on`.
    #[must_use]
    pub fn with(mut self, kind: SpringKind, on: bool) -> KindToggles {
        match kind {
            SpringKind::Struct => self.struct_ = on,
            SpringKind::Shear => self.shear = on,
            SpringKind::Bend => self.bend = on,
        }
        self
    }
}

impl Default for KindToggles {
    fn default() -> KindToggles {
        KindToggles::ALL
    }
}

/// How springs (and surfaces) are coloured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Colouring {
    /// Each spring kind its own colour ([`colour::STRUCT`], [`colour::SHEAR`], [`colour::BEND`]);
    /// surfaces their material colour.
    #[default]
    ByKind,
    /// Strain `(L - L0)/L0` on the diverging map of [`colour::strain_colour`], full colour at
    /// `±max_strain` (dimensionless); surfaces by the mean strain of the struct springs at each
    /// corner.
    ByStrain {
        /// Strain shown at full colour (0.1 = 10 %), > 0.
        max_strain: f64,
    },
}

/// What to draw and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    /// Spring kinds drawn (for bodies not drawn as surfaces).
    pub springs: KindToggles,
    /// Colours of springs and surfaces.
    pub colouring: Colouring,
    /// Draw particles as discs (pinned ones are always marked).
    pub particles: bool,
    /// Draw cloth lattices as a shaded surface instead of springs.
    pub cloth_surface: bool,
    /// Draw jelly (cube) lattices as a shaded surface instead of springs.
    pub jelly_surface: bool,
    /// Thin lines along the edges of surface cells.
    pub mesh_lines: bool,
    /// Draw colliders and dynamic spheres.
    pub colliders: bool,
    /// Draw the text overlay (scene, method, dt, t, energy) and the colour legend.
    pub overlay: bool,
    /// Shadows: bodies, particles and spheres on the floors and planes, spheres on the
    /// surfaces, a bowl's rim on its inside (`super::shadow`).
    pub shadows: bool,
    /// Rasteriser settings.
    pub quality: Quality,
    /// Extra thickness of the springs of bodies that are not dense lattices, of particle discs
    /// and of pin markers (1: the files `springlab render` writes; the terminal's small panes
    /// use [`Style::PANE_LINE_WEIGHT`], so a rope reads as a line and its pins as squares).
    pub line_weight: f32,
}

impl Style {
    /// The line weight of the terminal's scene pane: at the pane's typical 200–400 px height a
    /// rope is 2–4 px wide (1 px at weight 1).
    pub const PANE_LINE_WEIGHT: f32 = 2.5;
}

impl Default for Style {
    /// Every spring kind coloured by kind, particles, cloth and jelly as surfaces with mesh
    /// lines, colliders, shadows and the overlay.
    fn default() -> Style {
        Style {
            springs: KindToggles::ALL,
            colouring: Colouring::ByKind,
            particles: true,
            cloth_surface: true,
            jelly_surface: true,
            mesh_lines: true,
            colliders: true,
            overlay: true,
            shadows: true,
            quality: Quality::default(),
            line_weight: 1.0,
        }
    }
}

/// The text of the overlay.
#[derive(Clone, Debug, PartialEq)]
pub struct Overlay {
    /// Scene name.
    pub scene: String,
    /// Method name(s).
    pub method: String,
    /// Time step (s).
    pub dt: f64,
    /// Simulated time (s).
    pub time: f64,
    /// Total mechanical energy (J).
    pub energy: f64,
}

impl Overlay {
    /// The overlay of a running simulation.
    #[must_use]
    pub fn of(sim: &Simulation) -> Overlay {
        Overlay {
            scene: sim.scene.name.clone(),
            method: sim.scene.method_label(),
            dt: sim.dt(),
            time: sim.time(),
            energy: sim.energy().total,
        }
    }

    /// The two lines shown: `scene · method · dt = … s` and `t = … s · E = … J`.
    #[must_use]
    pub fn lines(&self) -> [String; 2] {
        [
            format!("{} · {} · dt = {} s", self.scene, self.method, self.dt),
            format!(
                "t = {:.3} s · E = {} J",
                self.time,
                format_energy(self.energy)
            ),
        ]
    }
}

/// `E` with 5 significant digits, in plain notation between 0.001 and 100 000.
pub(super) fn format_energy(e: f64) -> String {
    let a = e.abs();
    if a == 0.0 || (1e-3..1e5).contains(&a) {
        let digits = if a == 0.0 {
            1
        } else {
            (4 - a.log10().floor() as i32).clamp(0, 7) as usize
        };
        format!("{e:.digits$}")
    } else {
        format!("{e:.4e}")
    }
}
