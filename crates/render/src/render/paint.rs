//! Paint primitives: flat shapes in pixels and the code that fills and strokes them on a
//! [`Pixmap`] with tiny-skia. The scene renderer ([`super::draw`]), the terrain meshes
//! ([`super::terrain`]) and the charts ([`super::chart`]) all paint through these.
//!
//! A run of consecutive lines of one colour and width, or of discs of one colour, is drawn as
//! one path (see [`draw_shapes`]); each projected triangle can be grown by half a pixel
//! ([`grow`]) so that anti-aliased neighbours leave no light seam between them.

use glam::DVec3;
use tiny_skia::{
    FillRule, GradientStop, LinearGradient, Paint, PathBuilder, Pixmap, Point, RadialGradient,
    Rect, Shader, SpreadMode, Stroke, Transform,
};

use super::camera::View;
use super::colour::{self, Colour};

/// One shape waiting to be drawn.
#[derive(Clone, Debug)]
pub(super) enum Shape {
    Line {
        a: Point,
        b: Point,
        width: f32,
        colour: Colour,
    },
    Disc {
        c: Point,
        r: f32,
        colour: Colour,
    },
    Pin {
        c: Point,
        r: f32,
    },
    Triangle {
        p: [Point; 3],
        colour: Colour,
    },
    Ball {
        c: Point,
        r: f32,
        base: Colour,
        highlight: (f32, f32),
    },
}

#[derive(Clone, Debug)]
pub(super) struct Item {
    /// 0: below a plane, 1: above.
    pub(super) layer: u8,
    pub(super) depth: f64,
    pub(super) shape: Shape,
}

pub(super) fn point(x: f32, y: f32) -> Point {
    Point::from_xy(x, y)
}

/// The three camera-space points projected, or `None` if one is behind the eye.
pub(super) fn project3(view: &View, cam: [DVec3; 3]) -> Option<[Point; 3]> {
    let a = view.project_camera(cam[0])?;
    let b = view.project_camera(cam[1])?;
    let c = view.project_camera(cam[2])?;
    Some([point(a.x, a.y), point(b.x, b.y), point(c.x, c.y)])
}

/// The triangle `p` with every edge moved `by` px outwards (a mitred offset): each corner
/// moves to where its two offset edges meet,
///
/// ```text
/// p_i' = p_i + by (n_a + n_b) / (1 + n_a·n_b)
/// ```
/// where `n_a`, `n_b` are the outward unit normals of the two edges at `p_i`; the move is capped
/// at `4 by` for very sharp corners. A degenerate triangle is returned unchanged.
pub(super) fn grow(p: [Point; 3], by: f32) -> [Point; 3] {
    // Twice the signed area, (p_1 - p_0) × (p_2 - p_0): its sign fixes which side is out.
    let area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
    if area.abs() < 1e-6 {
        return p;
    }
    let sign = area.signum();
    // Outward unit normal of edge i (from p_i to p_{i+1}).
    let normal = |i: usize| {
        let (a, b) = (p[i], p[(i + 1) % 3]);
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let len = (dx * dx + dy * dy).sqrt().max(1e-9);
        (sign * dy / len, -sign * dx / len)
    };
    let n = [normal(0), normal(1), normal(2)];
    let mut out = p;
    for i in 0..3 {
        let (na, nb) = (n[(i + 2) % 3], n[i]);
        let denom = (1.0 + na.0 * nb.0 + na.1 * nb.1).max(1.0 / 16.0);
        let (mut mx, mut my) = (by * (na.0 + nb.0) / denom, by * (na.1 + nb.1) / denom);
        let len = (mx * mx + my * my).sqrt();
        if len > 4.0 * by {
            mx *= 4.0 * by / len;
            my *= 4.0 * by / len;
        }
        out[i] = point(p[i].x + mx, p[i].y + my);
    }
    out
}

/// A "nice" number near `x > 0`: 1, 2 or 5 times a power of ten (Heckbert 1990).
#[must_use]
pub(crate) fn nice(x: f64, round: bool) -> f64 {
    let e = x.log10().floor();
    let f = x / 10f64.powf(e);
    let n = if round {
        if f < 1.5 {
            1.0
        } else if f < 3.0 {
            2.0
        } else if f < 7.0 {
            5.0
        } else {
            10.0
        }
    } else if f <= 1.0 {
        1.0
    } else if f <= 2.0 {
        2.0
    } else if f <= 5.0 {
        5.0
    } else {
        10.0
    };
    n * 10f64.powf(e)
}

/// The background: a vertical gradient from [`colour::SKY_TOP`] to [`colour::SKY_BOTTOM`].
pub(super) fn draw_background(pixmap: &mut Pixmap, paint: &mut Paint) {
    let h = pixmap.height() as f32;
    let w = pixmap.width() as f32;
    paint.shader = LinearGradient::new(
        point(0.0, 0.0),
        point(0.0, h),
        vec![
            GradientStop::new(0.0, colour::SKY_TOP.to_skia()),
            GradientStop::new(1.0, colour::SKY_BOTTOM.to_skia()),
        ],
        SpreadMode::Pad,
        Transform::identity(),
    )
    .unwrap_or(Shader::SolidColor(colour::SKY_TOP.to_skia()));
    if let Some(r) = Rect::from_xywh(0.0, 0.0, w, h) {
        pixmap.fill_rect(r, paint, Transform::identity(), None);
    }
}

pub(crate) fn fill_rect(
    pixmap: &mut Pixmap,
    paint: &mut Paint,
    x: f32,
    y: f32,
    w: f32,
    h: f32,
    c: Colour,
) {
    paint.set_color(c.to_skia());
    if let Some(r) = Rect::from_xywh(x, y, w, h) {
        pixmap.fill_rect(r, paint, Transform::identity(), None);
    }
}

pub(crate) fn stroke_line(
    pixmap: &mut Pixmap,
    paint: &mut Paint,
    a: Point,
    b: Point,
    width: f32,
    c: Colour,
) {
    let mut pb = PathBuilder::new();
    pb.move_to(a.x, a.y);
    pb.line_to(b.x, b.y);
    if let Some(path) = pb.finish() {
        paint.set_color(c.to_skia());
        let stroke = Stroke {
            width,
            line_cap: tiny_skia::LineCap::Round,
            ..Stroke::default()
        };
        pixmap.stroke_path(&path, paint, &stroke, Transform::identity(), None);
    }
}

/// Draws `items` in order. A run of consecutive lines of one colour and width, or of discs of
/// one colour, is drawn as one path: the same picture (each run is one paint layer, so where two
/// of its shapes cross the colour is not blended twice) for a fraction of the per-shape cost.
pub(super) fn draw_shapes(pixmap: &mut Pixmap, paint: &mut Paint, items: &[Item]) {
    let mut k = 0;
    while k < items.len() {
        match items[k].shape {
            Shape::Line { width, colour, .. } => {
                let mut pb = PathBuilder::new();
                while let Some(Item {
                    shape:
                        Shape::Line {
                            a,
                            b,
                            width: w,
                            colour: c,
                        },
                    ..
                }) = items.get(k)
                {
                    if *w != width || *c != colour {
                        break;
                    }
                    pb.move_to(a.x, a.y);
                    pb.line_to(b.x, b.y);
                    k += 1;
                }
                if let Some(path) = pb.finish() {
                    paint.set_color(colour.to_skia());
                    let stroke = Stroke {
                        width,
                        line_cap: tiny_skia::LineCap::Round,
                        ..Stroke::default()
                    };
                    pixmap.stroke_path(&path, paint, &stroke, Transform::identity(), None);
                }
            }
            Shape::Disc { colour, .. } => {
                let mut pb = PathBuilder::new();
                while let Some(Item {
                    shape: Shape::Disc { c, r, colour: col },
                    ..
                }) = items.get(k)
                {
                    if *col != colour {
                        break;
                    }
                    pb.push_circle(c.x, c.y, *r);
                    k += 1;
                }
                if let Some(path) = pb.finish() {
                    paint.set_color(colour.to_skia());
                    pixmap.fill_path(&path, paint, FillRule::Winding, Transform::identity(), None);
                }
            }
            _ => {
                draw_shape(pixmap, paint, &items[k].shape);
                k += 1;
            }
        }
    }
}

pub(super) fn draw_shape(pixmap: &mut Pixmap, paint: &mut Paint, shape: &Shape) {
    match *shape {
        Shape::Line {
            a,
            b,
            width,
            colour,
        } => stroke_line(pixmap, paint, a, b, width, colour),
        Shape::Disc { c, r, colour } => {
            if let Some(path) = PathBuilder::from_circle(c.x, c.y, r) {
                paint.set_color(colour.to_skia());
                pixmap.fill_path(&path, paint, FillRule::Winding, Transform::identity(), None);
            }
        }
        Shape::Pin { c, r } => {
            if let Some(rect) = Rect::from_xywh(c.x - r, c.y - r, 2.0 * r, 2.0 * r) {
                let path = PathBuilder::from_rect(rect);
                paint.set_color(colour::PINNED.to_skia());
                pixmap.fill_path(&path, paint, FillRule::Winding, Transform::identity(), None);
                paint.set_color(colour::PARTICLE.to_skia());
                let stroke = Stroke {
                    width: (0.35 * r).max(1.0),
                    ..Stroke::default()
                };
                pixmap.stroke_path(&path, paint, &stroke, Transform::identity(), None);
            }
        }
        Shape::Triangle { p, colour } => {
            let mut pb = PathBuilder::new();
            pb.move_to(p[0].x, p[0].y);
            pb.line_to(p[1].x, p[1].y);
            pb.line_to(p[2].x, p[2].y);
            pb.close();
            if let Some(path) = pb.finish() {
                paint.set_color(colour.to_skia());
                pixmap.fill_path(&path, paint, FillRule::Winding, Transform::identity(), None);
            }
        }
        Shape::Ball {
            c,
            r,
            base,
            highlight,
        } => {
            let Some(path) = PathBuilder::from_circle(c.x, c.y, r) else {
                return;
            };
            let spot = point(c.x + highlight.0, c.y + highlight.1);
            paint.shader = RadialGradient::new(
                spot,
                0.0,
                c,
                r,
                vec![
                    GradientStop::new(0.0, base.lerp(Colour::rgb(255, 255, 255), 0.6).to_skia()),
                    GradientStop::new(0.55, base.to_skia()),
                    GradientStop::new(1.0, base.scaled(0.45).to_skia()),
                ],
                SpreadMode::Pad,
                Transform::identity(),
            )
            .unwrap_or(Shader::SolidColor(base.to_skia()));
            pixmap.fill_path(&path, paint, FillRule::Winding, Transform::identity(), None);
            paint.set_color(base.scaled(0.35).with_alpha(160).to_skia());
            let stroke = Stroke {
                width: 0.8,
                ..Stroke::default()
            };
            pixmap.stroke_path(&path, paint, &stroke, Transform::identity(), None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grown_triangles_contain_the_original_corners_pushed_out() {
        for p in [
            [point(0.0, 0.0), point(10.0, 0.0), point(0.0, 10.0)],
            [point(0.0, 0.0), point(0.0, 10.0), point(10.0, 0.0)],
        ] {
            let g = grow(p, 0.5);
            // Corner (0, 0) moves to (-0.5, -0.5); the legs move out by 0.5 px.
            let c = g.iter().find(|q| q.x < 1.0 && q.y < 1.0).expect("corner");
            assert!(
                (c.x + 0.5).abs() < 1e-5 && (c.y + 0.5).abs() < 1e-5,
                "{c:?}"
            );
        }
    }

    #[test]
    fn nice_numbers() {
        assert_eq!(nice(0.34, true), 0.5);
        assert_eq!(nice(7.5, true), 10.0);
        assert_eq!(nice(1.2, false), 2.0);
        assert_eq!(nice(0.9, false), 1.0);
    }
}
