//! Colours: the palette of the scene renderer and the charts, Lambert shading and the diverging
//! strain colour map.
//!
//! # Theory
//!
//! **Lambert shading.** A matte surface reflects light in proportion to the cosine of the angle
//! between its normal and the direction to the light (Lambert 1760). With an ambient term so
//! that faces turned away from the light are not black:
//!
//! ```text
//! I = k_a + k_d · max(0, N̂·L̂)          intensity, 0..=1
//! c = I · c_base                        per channel
//! ```
//! where
//! - `N̂`: unit surface normal (turned towards the camera for two-sided surfaces)
//! - `L̂`: unit direction to the light ([`LIGHT`]), fixed in the world
//! - `k_a = 0.38`, `k_d = 0.62`: ambient and diffuse weights ([`AMBIENT`], [`DIFFUSE`])
//!
//! **Strain colour map.** A spring's engineering strain `ε = (L - L0)/L0` (dimensionless) is
//! shown on a diverging map: blue for compressed, mid grey at rest (dark enough for thin lines on
//! the light background), red for stretched
//! (Moreland, "Diverging Color Maps for Scientific Visualization", ISVC 2009):
//!
//! ```text
//! s = clamp(ε / ε_max, -1, 1)
//! c = lerp(white, red, s)      s ≥ 0
//! c = lerp(white, blue, -s)    s < 0
//! ```
//! where `ε_max` is the strain shown at full colour (0.1 = 10 % by default).
//!
//! Reference: J. H. Lambert, *Photometria*, 1760; K. Moreland, "Diverging Color Maps for
//! Scientific Visualization", ISVC 2009.

use glam::DVec3;
use tiny_skia::Color;

/// An 8-bit sRGB colour with straight (not premultiplied) alpha.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Colour {
    /// Red, 0..=255.
    pub r: u8,
    /// Green, 0..=255.
    pub g: u8,
    /// Blue, 0..=255.
    pub b: u8,
    /// Opacity, 0 (transparent) ..= 255 (opaque).
    pub a: u8,
}

impl Colour {
    /// An opaque colour.
    #[must_use]
    pub const fn rgb(r: u8, g: u8, b: u8) -> Colour {
        Colour { r, g, b, a: 255 }
    }

    /// A colour with opacity `a` (0..=255).
    #[must_use]
    pub const fn rgba(r: u8, g: u8, b: u8, a: u8) -> Colour {
        Colour { r, g, b, a }
    }

    /// The same colour with opacity `a`.
    #[must_use]
    pub const fn with_alpha(self, a: u8) -> Colour {
        Colour { a, ..self }
    }

    /// Each channel multiplied by `factor` (clamped to 0..=255); alpha unchanged.
    #[must_use]
    pub fn scaled(self, factor: f64) -> Colour {
        let f = |c: u8| (f64::from(c) * factor).round().clamp(0.0, 255.0) as u8;
        Colour {
            r: f(self.r),
            g: f(self.g),
            b: f(self.b),
            a: self.a,
        }
    }

    /// `self + t (other - self)` per channel including alpha, `t` clamped to 0..=1.
    #[must_use]
    pub fn lerp(self, other: Colour, t: f64) -> Colour {
        let t = t.clamp(0.0, 1.0);
        let f = |a: u8, b: u8| {
            (f64::from(a) + t * (f64::from(b) - f64::from(a)))
                .round()
                .clamp(0.0, 255.0) as u8
        };
        Colour {
            r: f(self.r, other.r),
            g: f(self.g, other.g),
            b: f(self.b, other.b),
            a: f(self.a, other.a),
        }
    }

    /// The tiny-skia colour.
    #[must_use]
    pub fn to_skia(self) -> Color {
        Color::from_rgba8(self.r, self.g, self.b, self.a)
    }
}

/// Background at the top of the image.
pub const SKY_TOP: Colour = Colour::rgb(246, 248, 252);
/// Background at the bottom of the image.
pub const SKY_BOTTOM: Colour = Colour::rgb(214, 222, 233);
/// Struct springs.
pub const STRUCT: Colour = Colour::rgb(31, 78, 154);
/// Shear springs.
pub const SHEAR: Colour = Colour::rgb(224, 123, 26);
/// Bend springs.
pub const BEND: Colour = Colour::rgb(42, 157, 92);
/// Free particles.
pub const PARTICLE: Colour = Colour::rgb(40, 44, 52);
/// Pinned particles (drawn as a square with a ring).
pub const PINNED: Colour = Colour::rgb(214, 39, 40);
/// The front of a cloth (the side its normal `(x_c - x_a) × (x_b - x_a)` points to, +y for the
/// course cloth).
pub const CLOTH_FRONT: Colour = Colour::rgb(74, 144, 217);
/// The back of a cloth.
pub const CLOTH_BACK: Colour = Colour::rgb(230, 168, 80);
/// The outside of a jelly (a cube lattice drawn as a surface).
pub const JELLY: Colour = Colour::rgb(232, 80, 91);
/// Floors and tilted planes.
pub const GROUND: Colour = Colour::rgb(222, 215, 200);
/// Grid lines on floors.
pub const GROUND_GRID: Colour = Colour::rgba(120, 110, 95, 150);
/// The inside of a bowl.
pub const BOWL_INSIDE: Colour = Colour::rgb(176, 190, 212);
/// The outside of a bowl.
pub const BOWL_OUTSIDE: Colour = Colour::rgb(132, 150, 178);
/// Static spheres.
pub const SPHERE: Colour = Colour::rgb(150, 156, 168);
/// Dynamic spheres.
pub const BALL: Colour = Colour::rgb(200, 120, 60);
/// Text.
pub const TEXT: Colour = Colour::rgb(25, 28, 34);
/// The box behind the text overlay.
pub const OVERLAY_BOX: Colour = Colour::rgba(255, 255, 255, 200);
/// Strain map: most compressed.
pub const COMPRESSED: Colour = Colour::rgb(59, 76, 192);
/// Strain map: at rest.
pub const NEUTRAL: Colour = Colour::rgb(150, 150, 156);
/// Strain map: most stretched.
pub const STRETCHED: Colour = Colour::rgb(180, 4, 38);

/// Default colours of chart series, in order (Tableau 10).
pub const SERIES: [Colour; 10] = [
    Colour::rgb(31, 119, 180),
    Colour::rgb(255, 127, 14),
    Colour::rgb(44, 160, 44),
    Colour::rgb(214, 39, 40),
    Colour::rgb(148, 103, 189),
    Colour::rgb(140, 86, 75),
    Colour::rgb(227, 119, 194),
    Colour::rgb(127, 127, 127),
    Colour::rgb(188, 189, 34),
    Colour::rgb(23, 190, 207),
];

/// Ambient weight `k_a` of [`lambert`].
pub const AMBIENT: f64 = 0.38;
/// Diffuse weight `k_d` of [`lambert`].
pub const DIFFUSE: f64 = 0.62;

/// Unit direction to the light, in world coordinates: 60° above the horizon, from -x and +z,
/// that is from the upper left of the default camera (orbit 35°), so that shadows fall to the
/// right and a little away from the viewer, where they can be seen.
pub const LIGHT: DVec3 = DVec3::new(-0.25, 0.866_025_403_784_438_6, 0.433_012_701_892_219_3);

/// Lambert intensity `k_a + k_d max(0, N̂·L̂)` for the unit normal `normal` (module docs).
#[must_use]
pub fn lambert(normal: DVec3) -> f64 {
    AMBIENT + DIFFUSE * normal.dot(LIGHT.normalize()).max(0.0)
}

/// `base` shaded by [`lambert`] for the unit normal `normal`.
#[must_use]
pub fn shade(base: Colour, normal: DVec3) -> Colour {
    base.scaled(lambert(normal))
}

/// `base` shaded by `k_a v_sky + k_d max(0, N̂·L̂) v_sun`: Lambert's law with the shares of
/// the sun `sun` and of the sky `sky` (0..=1) that reach the point (`super::shadow`).
#[must_use]
pub fn shade_lit(base: Colour, normal: DVec3, sun: f64, sky: f64) -> Colour {
    let i = AMBIENT * sky.clamp(0.0, 1.0)
        + DIFFUSE * normal.dot(LIGHT.normalize()).max(0.0) * sun.clamp(0.0, 1.0);
    base.scaled(i)
}

/// The diverging strain colour of `strain` (dimensionless, `(L - L0)/L0`) with full colour at
/// `±max_strain` (module docs). A non-positive or non-finite `max_strain` maps everything to
/// the neutral colour.
#[must_use]
pub fn strain_colour(strain: f64, max_strain: f64) -> Colour {
    if !(max_strain > 0.0 && max_strain.is_finite() && strain.is_finite()) {
        return NEUTRAL;
    }
    let s = (strain / max_strain).clamp(-1.0, 1.0);
    if s >= 0.0 {
        NEUTRAL.lerp(STRETCHED, s)
    } else {
        NEUTRAL.lerp(COMPRESSED, -s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strain_map_ends_and_middle() {
        assert_eq!(strain_colour(0.0, 0.1), NEUTRAL);
        assert_eq!(strain_colour(0.1, 0.1), STRETCHED);
        assert_eq!(strain_colour(0.5, 0.1), STRETCHED);
        assert_eq!(strain_colour(-0.2, 0.1), COMPRESSED);
        assert_eq!(strain_colour(f64::NAN, 0.1), NEUTRAL);
    }

    #[test]
    fn lambert_is_brightest_facing_the_light() {
        let l = LIGHT.normalize();
        assert!((lambert(l) - 1.0).abs() < 1e-12);
        assert!((lambert(-l) - AMBIENT).abs() < 1e-12);
    }
}
