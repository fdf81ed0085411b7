//! Shadows inside a pit: a bowl under a floor's hole (`terrain::Bowl::pit`), shaded per pixel.
//!
//! # Theory
//!
//! Seen from above the floor, all that shows of such a bowl is its inside through the hole,
//! behind everything in the bowl (`terrain`'s `covers`). It is drawn twice, once in full sun
//! and once in shadow (`k_a v_sky` only, [`colour::shade_lit`] with `v_sun = 0`), and the shadowed
//! picture is laid over the lit one wherever the sun is hidden, clipped to the hole on the
//! screen. Where the sun is hidden comes from projecting along the light onto the bowl's sphere
//! (centre `c`, radius `R`): the shadow of a point `p` lit from the unit direction `d̂` is where
//! the ray `p - t d̂` leaves the sphere,
//!
//! ```text
//! m = p - c,   b = m·d̂
//! t = b + √(b² - |m|² + R²)          the larger root of |m - t d̂|² = R²
//! p' = p - t d̂                      (when p' is above the rim: where the ray crosses the rim's
//!                                    plane, outside the hole on the screen)
//! ```
//! where `p`, `c`, `p'` are in m and `R` in m. The floor around the hole shades what its
//! outline's shadow does not enclose: the hole's circle projected onto the bowl bounds the lit
//! part. A body's shadow is its caster outline projected the same way. Both are sampled at the
//! sun's disc at a ring of directions (`SUN_RADIUS`), which makes the penumbra. Each edge is thus a
//! straight-sided polygon on the screen between projected corners, not a colour averaged over a
//! mesh triangle, so the shadow's outline is as smooth as the casters' outlines.

use glam::DVec3;
use tiny_skia::{
    FillRule, FilterQuality, Mask, Paint, PathBuilder, Pattern, Pixmap, Rect, SpreadMode, Transform,
};

use super::{Casters, SUN_RADIUS, cone, layer_alpha, light, push_polygon};
use crate::render::camera::View;
use crate::render::terrain::{Bowl, Floor};

/// How much of the way to the shadowed picture the sun's full shadow goes.
const PIT_DARK: f64 = 0.97;
/// Directions the sun's disc is sampled at inside a pit: more than on the planes, as a body
/// high above the bowl's bottom has a wide penumbra that fewer samples show as steps.
const PIT_SAMPLES: usize = 8;

/// Where the shadow of `p` lit from `d` falls on the inside of `bowl` (module docs).
fn onto_bowl(bowl: &Bowl, d: DVec3, p: DVec3) -> DVec3 {
    let m = p - bowl.center;
    let b = m.dot(d);
    let disc = b * b - m.length_squared() + bowl.radius * bowl.radius;
    if disc >= 0.0 {
        let hit = p - (b + disc.sqrt()) * d;
        if hit.y <= bowl.rim {
            return hit;
        }
    }
    p - d * ((p.y - bowl.rim) / d.y.max(1e-6))
}

/// Fills `path` with the shadowed picture `dark` at opacity `alpha`, inside `clip`.
fn lay_over(
    pixmap: &mut Pixmap,
    anti_alias: bool,
    dark: &Pixmap,
    path: &tiny_skia::Path,
    rule: FillRule,
    alpha: f64,
    clip: &Mask,
) {
    let paint = Paint {
        shader: Pattern::new(
            dark.as_ref(),
            SpreadMode::Pad,
            FilterQuality::Nearest,
            alpha as f32,
            Transform::identity(),
        ),
        anti_alias,
        ..Paint::default()
    };
    pixmap.fill_path(path, &paint, rule, Transform::identity(), Some(clip));
}

/// The shadows of `casters` inside the pit `bowl`: `dark` (the bowl in shadow) laid over
/// `pixmap` where they fall, clipped to the hole `hole`.
pub(in crate::render) fn draw_bowl_shadows(
    pixmap: &mut Pixmap,
    anti_alias: bool,
    view: &View,
    bowl: &Bowl,
    casters: &Casters,
    hole: &Mask,
    dark: &Pixmap,
) {
    if casters.groups.is_empty() {
        return;
    }
    let suns = cone(light(), SUN_RADIUS, PIT_SAMPLES);
    let a = layer_alpha(PIT_DARK, suns.len());
    for &d in &suns {
        if let Some(path) = casters.path_with(view, 0..casters.groups.len(), d, d, |p| {
            onto_bowl(bowl, d, p)
        }) {
            lay_over(pixmap, anti_alias, dark, &path, FillRule::Winding, a, hole);
        }
    }
}

/// The floor's shadow inside the pit `bowl` under `floor`'s hole: `dark` laid over `pixmap`
/// outside the hole's outline projected along the light, clipped to the hole `hole`.
pub(in crate::render) fn draw_pit_shade(
    pixmap: &mut Pixmap,
    anti_alias: bool,
    view: &View,
    bowl: &Bowl,
    floor: &Floor,
    hole: &Mask,
    dark: &Pixmap,
) {
    let Some(screen) = Rect::from_xywh(-1.0, -1.0, pixmap.width() as f32 + 2.0, {
        pixmap.height() as f32 + 2.0
    }) else {
        return;
    };
    let suns = cone(light(), SUN_RADIUS, PIT_SAMPLES);
    let a = layer_alpha(PIT_DARK, suns.len());
    let mut ring = Vec::with_capacity(floor.hole.len());
    for &d in &suns {
        let mut pb = PathBuilder::new();
        pb.push_rect(screen);
        ring.clear();
        ring.extend(floor.hole.iter().map(|&p| onto_bowl(bowl, d, p)));
        push_polygon(&mut pb, view, &ring);
        if let Some(path) = pb.finish() {
            lay_over(pixmap, anti_alias, dark, &path, FillRule::EvenOdd, a, hole);
        }
    }
}
