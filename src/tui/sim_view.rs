//! The live scene on a braille canvas: an orbit camera, an orthographic projection, springs
//! coloured by kind, particles, pinned markers and the colliders' outlines.
//!
//! # Projection
//!
//! ```text
//! d  = p - c                                  c: the point the camera orbits (m)
//! x1 =  d.x cos ψ + d.z sin ψ                 ψ: yaw (angle about +y), rad
//! z1 = -d.x sin ψ + d.z cos ψ
//! view x = x1
//! view y = d.y cos θ - z1 sin θ               θ: elevation (camera above the scene for θ > 0)
//! depth  = d.y sin θ + z1 cos θ               towards the viewer
//! ```
//! Orthographic: distances in the view plane are metres, the same along x and y (the canvas
//! bounds follow the cell aspect, a braille dot is about square), so circles stay round.

use glam::DVec3;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::canvas::{Canvas, Context, Line as CanvasLine, Points};
use ratatui::widgets::{Block, Widget};

use super::Theme;
use super::lesson_view::{LessonRun, SpringFilter};
use crate::physics::SpringKind;
use crate::physics::collide::Collider;
use crate::scene::Scene;
use crate::simulation::Simulation;

/// Degrees the arrow keys turn the camera.
pub const ORBIT_STEP_DEGREES: f64 = 15.0;

/// The view may grow to this many times its first size to follow the particles.
const MAX_GROWTH: f64 = 4.0;

/// An orbit camera with an orthographic projection (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Angle about the vertical axis (rad).
    pub yaw: f64,
    /// Elevation above the horizontal (rad), within ±89°.
    pub pitch: f64,
    /// The point at the centre of the view (m).
    pub center: DVec3,
    /// Radius of the sphere around `center` that the view shows (m).
    pub radius: f64,
    first_radius: f64,
}

impl Camera {
    /// A camera that shows `scene`: its particles, where hanging particles can swing to, and its
    /// colliders. Flat scenes in the x-y plane are seen from the front; others from above at an
    /// angle.
    #[must_use]
    pub fn fit(scene: &Scene) -> Camera {
        let mut bounds = Bounds::default();
        let mut add = |p: DVec3| bounds.add(p);
        let mut flat = true;
        for body in &scene.bodies {
            let (model, state) = (&body.model, &body.state);
            for (p, v) in state.x.iter().zip(&state.v) {
                add(*p);
                flat &= p.z == 0.0 && v.z == 0.0;
            }
            // Where a particle can hang: straight down from its nearest pinned particle.
            let down = model.gravity.normalize_or_zero();
            let pins: Vec<DVec3> = (0..model.particle_count())
                .filter(|&i| model.is_pinned(i))
                .map(|i| state.x[i])
                .collect();
            if down != DVec3::ZERO && !pins.is_empty() {
                for p in &state.x {
                    let (pin, distance) = pins.iter().map(|q| (*q, (*p - *q).length())).fold(
                        (DVec3::ZERO, f64::INFINITY),
                        |a, b| if b.1 < a.1 { b } else { a },
                    );
                    add(pin + down * distance);
                }
            }
            for s in &state.spheres {
                add(s.center - DVec3::splat(s.radius));
                add(s.center + DVec3::splat(s.radius));
                flat = false;
            }
            flat &= model.colliders.is_empty();
        }
        let mid = bounds.mid().unwrap_or(DVec3::ZERO);
        let mut add = |p: DVec3| bounds.add(p);
        for body in &scene.bodies {
            for c in &body.model.colliders {
                match *c {
                    Collider::Plane { point, normal }
                    | Collider::HolePlane { point, normal, .. } => {
                        add(mid - (mid - point).dot(normal) * normal);
                    }
                    Collider::Sphere { center, radius } => {
                        add(center - DVec3::splat(radius));
                        add(center + DVec3::splat(radius));
                    }
                    Collider::Bowl {
                        center,
                        radius,
                        rim_height,
                    } => {
                        add(center - DVec3::splat(radius));
                        add(DVec3::new(
                            center.x + radius,
                            rim_height.min(center.y),
                            center.z + radius,
                        ));
                    }
                }
            }
        }
        let (center, radius) = match bounds.mid() {
            Some(mid) => (
                mid,
                (0.5 * (bounds.hi - bounds.lo).length() * 1.05).max(0.5),
            ),
            None => (DVec3::ZERO, 1.0),
        };
        let (yaw, pitch) = if flat {
            (0.0, 0.0)
        } else {
            ((-30f64).to_radians(), 25f64.to_radians())
        };
        Camera {
            yaw,
            pitch,
            center,
            radius,
            first_radius: radius,
        }
    }

    /// `p` (m) in view coordinates: `(x, y)` on the screen plane and depth towards the viewer.
    #[must_use]
    pub fn project(&self, p: DVec3) -> DVec3 {
        let d = p - self.center;
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        let x1 = d.x * cy + d.z * sy;
        let z1 = -d.x * sy + d.z * cy;
        DVec3::new(x1, d.y * cp - z1 * sp, d.y * sp + z1 * cp)
    }

    /// The world point (m) at view coordinates `v` (the inverse of [`Camera::project`]).
    #[must_use]
    pub fn unproject(&self, v: DVec3) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        let dy = v.y * cp + v.z * sp;
        let z1 = -v.y * sp + v.z * cp;
        let dx = v.x * cy - z1 * sy;
        let dz = v.x * sy + z1 * cy;
        self.center + DVec3::new(dx, dy, dz)
    }

    /// Turns the camera by `yaw` and `pitch` degrees (the elevation stays within ±89°).
    pub fn orbit(&mut self, yaw: f64, pitch: f64) {
        self.yaw = (self.yaw + yaw.to_radians()).rem_euclid(std::f64::consts::TAU);
        let limit = 89f64.to_radians();
        self.pitch = (self.pitch + pitch.to_radians()).clamp(-limit, limit);
    }

    /// Yaw and elevation in whole degrees, yaw in `(-180, 180]`.
    #[must_use]
    pub fn angles_degrees(&self) -> (i64, i64) {
        let mut yaw = self.yaw.to_degrees().round() as i64 % 360;
        if yaw > 180 {
            yaw -= 360;
        } else if yaw <= -180 {
            yaw += 360;
        }
        (yaw, self.pitch.to_degrees().round() as i64)
    }

    /// Widens the view (up to four times its first size) when a particle leaves it; never
    /// narrows it, so the picture does not jump back and forth.
    pub fn follow(&mut self, sim: &Simulation) {
        let mut far = 0.0f64;
        for p in sim.positions() {
            let d = (p - self.center).length();
            if d.is_finite() {
                far = far.max(d);
            }
        }
        if far > self.radius {
            self.radius = (far * 1.2).min(self.first_radius * MAX_GROWTH);
        }
    }

    /// The canvas bounds `(x, y)` in view coordinates for a canvas of `width × height` cells:
    /// at least `±radius` both ways, with equal scales along x and y (a cell is half as wide as
    /// it is tall, a braille dot about square).
    #[must_use]
    pub fn bounds(&self, width: u16, height: u16) -> ([f64; 2], [f64; 2]) {
        let (w, h) = (f64::from(width.max(1)), f64::from(height.max(1)));
        let r = self.radius;
        let (half_x, half_y) = if w / (2.0 * h) >= 1.0 {
            (r * w / (2.0 * h), r)
        } else {
            (r, r * 2.0 * h / w)
        };
        ([-half_x, half_x], [-half_y, half_y])
    }

    /// View coordinates of the centre of cell `(column, row)` of the canvas at `inner`.
    #[must_use]
    pub fn cell_to_view(&self, inner: Rect, column: u16, row: u16) -> (f64, f64) {
        let ([x0, x1], [y0, y1]) = self.bounds(inner.width, inner.height);
        let fx = (f64::from(column) - f64::from(inner.x) + 0.5) / f64::from(inner.width.max(1));
        let fy = (f64::from(row) - f64::from(inner.y) + 0.5) / f64::from(inner.height.max(1));
        (x0 + fx * (x1 - x0), y1 - fy * (y1 - y0))
    }

    /// The particle nearest to cell `(column, row)`, within 3 columns (rows count double, being
    /// twice as tall): `(body, particle, depth)`.
    #[must_use]
    pub fn pick(
        &self,
        sim: &Simulation,
        inner: Rect,
        column: u16,
        row: u16,
    ) -> Option<(usize, usize, f64)> {
        if !inner_contains(inner, column, row) {
            return None;
        }
        let ([x0, x1], [y0, y1]) = self.bounds(inner.width, inner.height);
        let (w, h) = (f64::from(inner.width), f64::from(inner.height));
        let (cx, cy) = (
            f64::from(column - inner.x) + 0.5,
            f64::from(row - inner.y) + 0.5,
        );
        let mut best: Option<(usize, usize, f64, f64)> = None;
        for (b, body) in sim.scene.bodies.iter().enumerate() {
            for (i, p) in body.state.x.iter().enumerate() {
                let v = self.project(*p);
                let px = (v.x - x0) / (x1 - x0) * w;
                let py = (y1 - v.y) / (y1 - y0) * h;
                let d2 = (px - cx).powi(2) + (2.0 * (py - cy)).powi(2);
                if d2.is_finite() && d2 <= 9.0 && best.is_none_or(|(_, _, _, bd)| d2 < bd) {
                    best = Some((b, i, v.z, d2));
                }
            }
        }
        best.map(|(b, i, z, _)| (b, i, z))
    }
}

/// An axis-aligned box grown point by point.
struct Bounds {
    lo: DVec3,
    hi: DVec3,
}

impl Default for Bounds {
    fn default() -> Bounds {
        Bounds {
            lo: DVec3::splat(f64::INFINITY),
            hi: DVec3::splat(f64::NEG_INFINITY),
        }
    }
}

impl Bounds {
    fn add(&mut self, p: DVec3) {
        if p.is_finite() {
            self.lo = self.lo.min(p);
            self.hi = self.hi.max(p);
        }
    }

    fn mid(&self) -> Option<DVec3> {
        (self.lo.is_finite() && self.hi.is_finite()).then(|| 0.5 * (self.lo + self.hi))
    }
}

fn inner_contains(inner: Rect, column: u16, row: u16) -> bool {
    column >= inner.x
        && column < inner.x + inner.width
        && row >= inner.y
        && row < inner.y + inner.height
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

/// Draws the scene of `run` into `area` (with its border); returns the canvas's inner area.
pub fn render(run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) -> Rect {
    let sim = run.sim();
    let camera = run.camera();
    let (yaw, pitch) = camera.angles_degrees();
    let plural = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
    let title = format!(
        " {} · {} · {} ",
        sim.scene.name,
        plural(sim.scene.particle_count(), "particle"),
        plural(sim.scene.spring_count(), "spring")
    );
    let bottom = format!(
        " view {yaw}°/{pitch}° (arrows) · springs: {} (t) ",
        run.spring_filter().name()
    );
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
    let (x_bounds, y_bounds) = camera.bounds(inner.width, inner.height);
    let filter = run.spring_filter();
    let drag = run.dragged();
    Canvas::default()
        .marker(Marker::Braille)
        .x_bounds(x_bounds)
        .y_bounds(y_bounds)
        .paint(|ctx| {
            draw_colliders(ctx, sim, camera, theme.color(Color::DarkGray));
            for kind in [SpringKind::Bend, SpringKind::Shear, SpringKind::Struct] {
                if !filter.shows(kind) {
                    continue;
                }
                for (b, body) in sim.scene.bodies.iter().enumerate() {
                    let color = theme.color(spring_color(b, kind));
                    let x = &body.state.x;
                    for s in body.model.springs.iter().filter(|s| s.kind == kind) {
                        let p = camera.project(x[s.a as usize]);
                        let q = camera.project(x[s.b as usize]);
                        ctx.draw(&CanvasLine::new(p.x, p.y, q.x, q.y, color));
                    }
                }
            }
            let many = sim.scene.particle_count() > MAX_POINTS && filter != SpringFilter::None;
            let mut pinned = Vec::new();
            let mut free = Vec::new();
            let marked = sim.scene.particle_count() <= MAX_MARKED;
            for (b, body) in sim.scene.bodies.iter().enumerate() {
                let coords: Vec<(f64, f64)> = body
                    .state
                    .x
                    .iter()
                    .map(|p| {
                        let v = camera.project(*p);
                        (v.x, v.y)
                    })
                    .collect();
                if !many {
                    ctx.draw(&Points::new(&coords, theme.color(Color::White)));
                }
                for (i, c) in coords.iter().enumerate() {
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
                    ((x - x_bounds[0]) / (x_bounds[1] - x_bounds[0]) * f64::from(inner.width))
                        .floor() as i64,
                    ((y_bounds[1] - y) / (y_bounds[1] - y_bounds[0]) * f64::from(inner.height))
                        .floor() as i64,
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
            for (x, y) in free {
                ctx.print(x, y, Span::styled("•", theme.fg(Color::White)));
            }
            for (x, y) in pinned {
                ctx.print(x, y, Span::styled("■", theme.fg(Color::Yellow)));
            }
            if let Some((b, i)) = drag
                && let Some(p) = sim.scene.bodies.get(b).and_then(|body| body.state.x.get(i))
            {
                let v = camera.project(*p);
                ctx.print(v.x, v.y, Span::styled("●", theme.fg(Color::LightRed)));
            }
        })
        .render(inner, buf);
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

/// Simulated time with as many decimals as the time step needs (2 to 6).
#[must_use]
pub fn time_text(t: f64, dt: f64) -> String {
    let decimals = (-dt.log10()).ceil().clamp(2.0, 6.0) as usize;
    format!("{t:.decimals$}")
}

/// Segments of a polyline through `points` (m), projected.
fn polyline(ctx: &mut Context, camera: &Camera, points: &[DVec3], color: Color) {
    for w in points.windows(2) {
        let (p, q) = (camera.project(w[0]), camera.project(w[1]));
        ctx.draw(&CanvasLine::new(p.x, p.y, q.x, q.y, color));
    }
}

/// Points of the circle of `radius` (m) about `center` (m) in the plane normal to `normal`.
fn circle(center: DVec3, normal: DVec3, radius: f64, segments: usize) -> Vec<DVec3> {
    let (u, w) = normal.normalize_or_zero().any_orthonormal_pair();
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
    camera: &Camera,
    origin: DVec3,
    normal: DVec3,
    half: f64,
    color: Color,
    skip: &dyn Fn(DVec3) -> bool,
) {
    let (u, w) = normal.any_orthonormal_pair();
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
                    polyline(ctx, camera, &[p, q], color);
                }
            }
        }
    }
}

fn draw_colliders(ctx: &mut Context, sim: &Simulation, camera: &Camera, color: Color) {
    let half = camera.radius;
    for body in &sim.scene.bodies {
        for c in &body.model.colliders {
            match *c {
                Collider::Plane { point, normal } => {
                    let origin = camera.center - (camera.center - point).dot(normal) * normal;
                    plane_grid(ctx, camera, origin, normal, half, color, &|_| false);
                }
                Collider::HolePlane {
                    point,
                    normal,
                    hole_center,
                    hole_radius,
                } => {
                    let origin = camera.center - (camera.center - point).dot(normal) * normal;
                    let in_hole = move |m: DVec3| {
                        let r = m - hole_center;
                        (r - r.dot(normal) * normal).length() < hole_radius
                    };
                    plane_grid(ctx, camera, origin, normal, half, color, &in_hole);
                    polyline(
                        ctx,
                        camera,
                        &circle(hole_center, normal, hole_radius, 64),
                        color,
                    );
                }
                Collider::Sphere { center, radius } => sphere(ctx, camera, center, radius, color),
                Collider::Bowl {
                    center,
                    radius,
                    rim_height,
                } => {
                    let rim = rim_height.min(center.y);
                    let rim_radius = (radius * radius - (center.y - rim).powi(2)).max(0.0).sqrt();
                    let rim_center = DVec3::new(center.x, rim, center.z);
                    polyline(
                        ctx,
                        camera,
                        &circle(rim_center, DVec3::Y, rim_radius, 64),
                        color,
                    );
                    // The arc of the bowl in the vertical plane facing the camera.
                    let right = camera.unproject(DVec3::X) - camera.unproject(DVec3::ZERO);
                    let across = DVec3::new(right.x, 0.0, right.z).normalize_or(DVec3::X);
                    let arc: Vec<DVec3> = (0..=64)
                        .map(|i| {
                            let a = std::f64::consts::TAU * f64::from(i) / 64.0;
                            center + radius * (a.cos() * across + a.sin() * DVec3::Y)
                        })
                        .collect();
                    for w in arc.windows(2) {
                        if w[0].y <= rim + 1e-9 && w[1].y <= rim + 1e-9 {
                            polyline(ctx, camera, w, color);
                        }
                    }
                }
            }
        }
        for s in &body.state.spheres {
            sphere(ctx, camera, s.center, s.radius, color);
        }
    }
}

/// A sphere's outline (a circle in the view plane) and its equator.
fn sphere(ctx: &mut Context, camera: &Camera, center: DVec3, radius: f64, color: Color) {
    let c = camera.project(center);
    let outline: Vec<(f64, f64)> = (0..=64)
        .map(|i| {
            let a = std::f64::consts::TAU * f64::from(i) / 64.0;
            (c.x + radius * a.cos(), c.y + radius * a.sin())
        })
        .collect();
    for w in outline.windows(2) {
        ctx.draw(&CanvasLine::new(w[0].0, w[0].1, w[1].0, w[1].1, color));
    }
    polyline(ctx, camera, &circle(center, DVec3::Y, radius, 64), color);
}
