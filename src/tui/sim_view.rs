//! The scene pane: its border and title, and the scene drawn in one of three views — the
//! rasterised frame through a terminal graphics protocol, the same frame as colour half-blocks,
//! or a braille line drawing — all through the one camera of [`crate::render::camera`].
//!
//! Every view projects with [`super::pane`]'s cells-to-pixels grid, so the camera shows the same
//! region of the world in each and the mouse inverts the same projection.

use glam::DVec3;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::canvas::{Canvas, Context, Line as CanvasLine, Points};
use ratatui::widgets::{Block, Widget};

use super::Theme;
use super::lesson_run::LessonRun;
use super::pane::{DOTS, SpringFilter, dot_view};
use crate::physics::SpringKind;
use crate::physics::collide::Collider;
use crate::render::camera::plane_axes;
use crate::render::{Camera, View};
use crate::simulation::Simulation;

/// Draws the scene's content into the pane's inner area (the half-block and raster views).
pub trait Painter {
    /// Draws `run`'s scene into `inner`.
    fn paint(&self, run: &LessonRun, theme: Theme, inner: Rect, buf: &mut Buffer);
}

/// The braille line drawing (no image at all).
pub struct Braille;

impl Painter for Braille {
    fn paint(&self, run: &LessonRun, theme: Theme, inner: Rect, buf: &mut Buffer) {
        braille(run, theme, inner, buf);
    }
}

/// Colour of body `b`'s structural springs (the ropes scene has two bodies).
const BODY_COLORS: [Color; 4] = [Color::Cyan, Color::Green, Color::LightBlue, Color::LightRed];

fn spring_color(body: usize, kind: SpringKind) -> Color {
    match kind {
        SpringKind::Struct => BODY_COLORS[body % BODY_COLORS.len()],
        SpringKind::Shear => Color::Blue,
        SpringKind::Bend => Color::Magenta,
    }
}

/// Scenes with more particles draw springs only (points would hide the lattice).
const MAX_POINTS: usize = 400;

/// Scenes with at most this many particles mark each one with a dot a cell wide.
const MAX_MARKED: usize = 64;

/// The fields (text, priority: the lowest goes first) joined by ` · ` with a space either side,
/// without the lowest-priority fields that do not fit in `room` columns.
fn fit_fields(mut fields: Vec<(String, u8)>, room: usize) -> String {
    let join = |fields: &[(String, u8)]| {
        let texts: Vec<&str> = fields.iter().map(|(t, _)| t.as_str()).collect();
        format!(" {} ", texts.join(" · "))
    };
    while fields.len() > 1 && join(&fields).chars().count() > room {
        let lowest = (0..fields.len()).min_by_key(|&i| fields[i].1).unwrap_or(0);
        fields.remove(lowest);
    }
    join(&fields)
}

/// Draws the pane of `run` into `area`: its border and titles, then the scene by `painter`
/// (or the divergence message); returns the pane's inner area.
pub fn render(
    run: &LessonRun,
    theme: Theme,
    painter: &dyn Painter,
    area: Rect,
    buf: &mut Buffer,
) -> Rect {
    let sim = run.sim();
    let camera = run.camera();
    let (orbit, elevation) = camera.angles_degrees();
    let plural = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    // The border's titles keep whole fields only: the least needed go first on a narrow pane.
    let room = usize::from(area.width.saturating_sub(2));
    let title = fit_fields(
        vec![
            (sim.scene.name.clone(), 3),
            (plural(sim.scene.particle_count(), "particle"), 2),
            (plural(sim.scene.spring_count(), "spring"), 1),
        ],
        room,
    );
    let mut bottom = vec![(format!("view {orbit}°/{elevation}°"), 0)];
    if run.follows() {
        bottom.push(("follow".to_string(), 2));
    }
    bottom.push((format!("springs: {} (t)", run.spring_filter().name()), 1));
    let bottom = fit_fields(bottom, room);
    let block = Block::bordered()
        .title(Line::from(title))
        .title_bottom(Line::from(bottom).right_aligned())
        .border_style(theme.dim());
    let inner = block.inner(area);
    block.render(area, buf);
    if inner.width < 4 || inner.height < 2 {
        return inner;
    }
    if let Some(d) = &sim.diverged {
        let text = vec![
            Line::from(Span::styled(
                format!(
                    "unstable at step {}, t = {} s",
                    d.step,
                    time_text(d.time, sim.dt())
                ),
                theme.fg(Color::LightRed),
            )),
            Line::from(format!("{}.", d.reason)),
            Line::from(""),
            Line::from("r: start over · m: another method · -: halve dt"),
        ];
        let top = inner.height.saturating_sub(4) / 2;
        let rect = Rect::new(inner.x, inner.y + top, inner.width, inner.height - top);
        ratatui::widgets::Paragraph::new(text)
            .alignment(ratatui::layout::Alignment::Center)
            .wrap(ratatui::widgets::Wrap { trim: true })
            .render(rect, buf);
        return inner;
    }
    painter.paint(run, theme, inner, buf);
    // With several bodies, a legend: which colour is which body and method.
    if sim.scene.bodies.len() > 1 {
        for (b, body) in sim
            .scene
            .bodies
            .iter()
            .enumerate()
            .take(inner.height as usize)
        {
            let line = Line::from(vec![
                Span::styled("── ", theme.fg(spring_color(b, SpringKind::Struct))),
                Span::raw(format!("{} ({})", body.label, body.method.name())),
            ]);
            buf.set_line(inner.x, inner.y + b as u16, &line, inner.width);
        }
    }
    inner
}

/// Projection onto the braille canvas: pixels of [`dot_view`], y flipped (the canvas's y axis
/// points up).
struct Dots {
    view: View,
}

impl Dots {
    fn point(&self, p: DVec3) -> Option<(f64, f64)> {
        self.view
            .project(p)
            .map(|q| (f64::from(q.x), self.view.height - f64::from(q.y)))
    }

    fn line(&self, ctx: &mut Context, a: DVec3, b: DVec3, color: Color) {
        let (ca, cb) = (self.view.to_camera(a), self.view.to_camera(b));
        if let Some((ca, cb)) = self.view.clip_segment(ca, cb)
            && let (Some(p), Some(q)) = (self.view.project_camera(ca), self.view.project_camera(cb))
        {
            let h = self.view.height;
            ctx.draw(&CanvasLine::new(
                f64::from(p.x),
                h - f64::from(p.y),
                f64::from(q.x),
                h - f64::from(q.y),
                color,
            ));
        }
    }

    fn polyline(&self, ctx: &mut Context, points: &[DVec3], color: Color) {
        for w in points.windows(2) {
            self.line(ctx, w[0], w[1], color);
        }
    }
}

/// The braille line drawing of `run`'s scene in `inner`.
fn braille(run: &LessonRun, theme: Theme, inner: Rect, buf: &mut Buffer) {
    let sim = run.sim();
    let dots = Dots {
        view: dot_view(run.camera(), inner),
    };
    let (w, h) = (dots.view.width, dots.view.height);
    let filter = run.spring_filter();
    let drag = run.dragged();
    let camera = run.camera();
    Canvas::default()
        .marker(Marker::Braille)
        .x_bounds([0.0, w])
        .y_bounds([0.0, h])
        .paint(|ctx| {
            draw_colliders(ctx, sim, camera, &dots, theme.color(Color::DarkGray));
            for kind in [SpringKind::Bend, SpringKind::Shear, SpringKind::Struct] {
                if !filter.shows(kind) {
                    continue;
                }
                for (b, body) in sim.scene.bodies.iter().enumerate() {
                    let color = theme.color(spring_color(b, kind));
                    let x = &body.state.x;
                    for s in body.model.springs().iter().filter(|s| s.kind == kind) {
                        dots.line(ctx, x[s.a as usize], x[s.b as usize], color);
                    }
                }
            }
            let many = sim.scene.particle_count() > MAX_POINTS && filter != SpringFilter::None;
            let mut pinned = Vec::new();
            let mut free = Vec::new();
            let marked = sim.scene.particle_count() <= MAX_MARKED;
            for (b, body) in sim.scene.bodies.iter().enumerate() {
                let coords: Vec<Option<(f64, f64)>> =
                    body.state.x.iter().map(|p| dots.point(*p)).collect();
                if !many {
                    let shown: Vec<(f64, f64)> = coords.iter().flatten().copied().collect();
                    ctx.draw(&Points::new(&shown, theme.color(Color::White)));
                }
                for (i, c) in coords.iter().enumerate() {
                    let Some(c) = c else { continue };
                    let held = drag.is_some_and(|(db, di)| db == b && di == i);
                    if body.model.is_pinned(i) && !held {
                        pinned.push(*c);
                    } else if marked && !held {
                        free.push(*c);
                    }
                }
            }
            ctx.layer();
            // Marks only where they stay apart: neighbouring marks would hide the springs.
            let cell = |(x, y): (f64, f64)| {
                (
                    (x / f64::from(DOTS.0)).floor() as i64,
                    ((h - y) / f64::from(DOTS.1)).floor() as i64,
                )
            };
            let cells: Vec<(i64, i64)> = free.iter().map(|&p| cell(p)).collect();
            let crowded = cells.iter().enumerate().any(|(i, a)| {
                cells[i + 1..]
                    .iter()
                    .any(|b| (a.0 - b.0).abs() <= 1 && (a.1 - b.1).abs() <= 1)
            });
            if crowded {
                free.clear();
            }
            // A mark goes in the cell whose braille dots hold its point: ratatui maps text
            // labels with (cells - 1) and dots with (dots - 1) per extent, which puts a label up
            // to a cell away from its dot; snap the label to the dot's cell.
            let (cols, rows) = (f64::from(inner.width), f64::from(inner.height));
            let snap = |(x, y): (f64, f64)| {
                let dot_x = (x * (2.0 * cols - 1.0) / w).round().max(0.0);
                let dot_y = ((h - y) * (4.0 * rows - 1.0) / h).round().max(0.0);
                let (cx, cy) = ((dot_x / 2.0).floor(), (dot_y / 4.0).floor());
                let lx = if cols > 1.0 {
                    (cx + 0.5) * w / (cols - 1.0)
                } else {
                    x
                };
                let ly = if rows > 1.0 {
                    h - (cy + 0.5) * h / (rows - 1.0)
                } else {
                    y
                };
                (lx.min(w), ly.max(0.0))
            };
            for p in free {
                let (x, y) = snap(p);
                ctx.print(x, y, Span::styled("•", theme.fg(Color::White)));
            }
            for p in pinned {
                let (x, y) = snap(p);
                ctx.print(x, y, Span::styled("■", theme.fg(Color::Yellow)));
            }
            if let Some((b, i)) = drag
                && let Some(p) = sim.scene.bodies.get(b).and_then(|body| body.state.x.get(i))
                && let Some(c) = dots.point(*p)
            {
                let (x, y) = snap(c);
                ctx.print(x, y, Span::styled("●", theme.fg(Color::LightRed)));
            }
        })
        .render(inner, buf);
}

/// Simulated time with as many decimals as the time step needs (2 to 6).
#[must_use]
pub fn time_text(t: f64, dt: f64) -> String {
    let decimals = (-dt.log10()).ceil().clamp(2.0, 6.0) as usize;
    format!("{t:.decimals$}")
}

/// Points of the circle of `radius` (m) about `center` (m) in the plane normal to `normal`.
fn circle(center: DVec3, normal: DVec3, radius: f64, segments: usize) -> Vec<DVec3> {
    let (u, w) = plane_axes(normal);
    (0..=segments)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / segments as f64;
            center + radius * (a.cos() * u + a.sin() * w)
        })
        .collect()
}

/// A square grid of 5 lines each way, of half-size `half` (m), on the plane through
/// `origin` with unit `normal`; segments for which `skip(midpoint)` is true are left out.
fn plane_grid(
    ctx: &mut Context,
    dots: &Dots,
    origin: DVec3,
    normal: DVec3,
    half: f64,
    color: Color,
    skip: &dyn Fn(DVec3) -> bool,
) {
    let (u, w) = plane_axes(normal);
    let lines = 4;
    let pieces = 32;
    for (a, b) in [(u, w), (w, u)] {
        for i in 0..=lines {
            let offset = -half + 2.0 * half * f64::from(i) / f64::from(lines);
            for j in 0..pieces {
                let s0 = -half + 2.0 * half * f64::from(j) / f64::from(pieces);
                let s1 = -half + 2.0 * half * f64::from(j + 1) / f64::from(pieces);
                let p = origin + offset * a + s0 * b;
                let q = origin + offset * a + s1 * b;
                if !skip(0.5 * (p + q)) {
                    dots.line(ctx, p, q, color);
                }
            }
        }
    }
}

fn draw_colliders(ctx: &mut Context, sim: &Simulation, camera: &Camera, dots: &Dots, color: Color) {
    // Planes are drawn as a patch around the point the camera looks at, as wide as the view.
    let half = 0.75 * camera.visible_height();
    let centre = camera.target;
    for body in &sim.scene.bodies {
        for c in &body.model.colliders {
            match *c {
                Collider::Plane { point, normal } => {
                    let origin = centre - (centre - point).dot(normal) * normal;
                    plane_grid(ctx, dots, origin, normal, half, color, &|_| false);
                }
                Collider::HolePlane {
                    point,
                    normal,
                    hole_center,
                    hole_radius,
                } => {
                    let origin = centre - (centre - point).dot(normal) * normal;
                    let in_hole = move |m: DVec3| {
                        let r = m - hole_center;
                        (r - r.dot(normal) * normal).length() < hole_radius
                    };
                    plane_grid(ctx, dots, origin, normal, half, color, &in_hole);
                    dots.polyline(ctx, &circle(hole_center, normal, hole_radius, 64), color);
                }
                Collider::Sphere { center, radius } => sphere(ctx, dots, center, radius, color),
                Collider::Bowl {
                    center,
                    radius,
                    rim_height,
                } => {
                    let bowl_rim = crate::physics::bowl::Rim::of(center, radius, rim_height);
                    let (rim, rim_radius) = (bowl_rim.height, bowl_rim.radius());
                    let rim_center = bowl_rim.center(center);
                    dots.polyline(ctx, &circle(rim_center, DVec3::Y, rim_radius, 64), color);
                    // The arc of the bowl in the vertical plane facing the camera.
                    let right = dots.view.right;
                    let across = DVec3::new(right.x, 0.0, right.z).normalize_or(DVec3::X);
                    let arc: Vec<DVec3> = (0..=64)
                        .map(|i| {
                            let a = std::f64::consts::TAU * f64::from(i) / 64.0;
                            center + radius * (a.cos() * across + a.sin() * DVec3::Y)
                        })
                        .collect();
                    for w in arc.windows(2) {
                        if w[0].y <= rim + 1e-9 && w[1].y <= rim + 1e-9 {
                            dots.polyline(ctx, w, color);
                        }
                    }
                }
            }
        }
        for s in &body.state.spheres {
            sphere(ctx, dots, s.center, s.radius, color);
        }
    }
}

/// A sphere's outline (a circle in the view plane) and its equator.
fn sphere(ctx: &mut Context, dots: &Dots, center: DVec3, radius: f64, color: Color) {
    let (r, u) = (dots.view.right, dots.view.up);
    let outline: Vec<DVec3> = (0..=64)
        .map(|i| {
            let a = std::f64::consts::TAU * f64::from(i) / 64.0;
            center + radius * (a.cos() * r + a.sin() * u)
        })
        .collect();
    dots.polyline(ctx, &outline, color);
    dots.polyline(ctx, &circle(center, DVec3::Y, radius, 64), color);
}
