//! Shadows: what tells how high a body is. Bodies, particles and spheres cast soft shadows on
//! the floors and planes; spheres shade the cloth and the jelly under them; the floor's rim and
//! the bowl's own wall shade the inside of a bowl. One light direction for all of it, the one
//! Lambert shading uses ([`colour::LIGHT`]).
//!
//! # Theory
//!
//! **Planar shadows** (Blinn 1988). The shadow of a point `p` on the plane through `q` with unit
//! normal `n̂`, lit from the direction `d̂` (towards the light), is where the ray `p - t d̂` meets
//! the plane:
//!
//! ```text
//! h  = (p - q)·n̂                 height of p above the plane (m)
//! p' = p - d̂ · h / (d̂·n̂)         its shadow on the plane (h ≥ 0; below the plane p' = p - h n̂)
//! |p' - (p - h n̂)| = h tan θ     the shadow's offset from the point right under p
//! ```
//! where `θ` is the angle between `d̂` and `n̂`. Every caster — a body's surface quads (a closed
//! body's quads that face the light), its springs as thin strips, its particles and the spheres
//! as their silhouette circles — is projected this way, the projections are filled as one path
//! (one coverage, so overlaps do not darken twice) and clipped to the plane's own outline, hole
//! cut out.
//!
//! **Soft edges** come from an area light sampled at a few directions: the sun's disc of
//! angular radius [`SUN_RADIUS`] (a penumbra `≈ 2 h tan α`, sharp where a body touches and
//! widening with height). The sky, a cone of half-angle [`SKY_RADIUS`] about the normal, is
//! occluded by a body of size `s` whose lowest point is `h` above the plane about as much as
//! the solid angle the body takes:
//!
//! ```text
//! a_sky = A_sky · s² / (s² + h²)                       darkness right under the body
//! f_k   = 1 + (k / (K - 1)) · 2 h tan β / s,  k < K     spread of layer k
//! ```
//! where `A_sky` ([`SKY_DARK`]) is the darkening under a body that touches the plane, `β` the
//! cone's half-angle and `K` ([`SKY_LAYERS`]) the layers: the footprint right under the body
//! (projected along the normal) scaled by `f_k` about its centre, each layer `1 - (1 -
//! a_sky)^(1/K)` opaque, so that the shadow is darkest in the middle and fades over the width
//! `2 h tan β`. That term is the contact darkening (at `h = 0` all layers coincide), and it
//! makes the floor right under a body darker than beside it even when the sun's shadow falls
//! elsewhere.
//!
//! **Shadows on curved surfaces** are computed per point instead. A sphere (centre `c`, radius
//! `r`) hides the sun from `p` when the ray `p + t L̂` passes within `r` of `c`; with the sun's
//! angular radius `α` the edge is a ramp of width `2 t* tan α`:
//!
//! ```text
//! t* = (c - p)·L̂,   ρ = |c - p - t* L̂|
//! v_sun = clamp(1/2 + (ρ - r) / (2 (t* tan α + r/50)), 0, 1)         (t* > 0, else 1)
//! v_sky = 1 - (r/|c - p|)² max(0, N̂·(c - p)/|c - p|)                  (Quilez 2014)
//! ```
//! A bowl's wall shades its inside: from a point `p` on or inside the sphere (centre `c`,
//! radius `R`) the light ray leaves the sphere at `p + t L̂`,
//! `t = -b + √(b² - |p - c|² + R²)` with `b = (p - c)·L̂` (`t = -2b` on the sphere), and is
//! blocked when that point is below the rim. A floor with a hole blocks the light of a point below it unless the ray
//! `p + t L̂` crosses the plane inside the hole. The intensity is then
//! `k_a v_sky + k_d max(0, N̂·L̂) v_sun` ([`colour::shade_lit`]).
//!
//! References: J. Blinn, "Me and my (fake) shadow", IEEE CG&A 8(1), 1988; I. Quilez, "Sphere
//! ambient occlusion", 2014 (iquilezles.org/articles/sphereao).

use glam::DVec3;
use tiny_skia::{FillRule, Mask, Paint, PathBuilder, Pixmap, Transform};

use super::camera::{View, plane_axes};
use super::colour::{self, Colour};
use super::terrain::{Bowl, Floor, floor_path};

mod pit;
use crate::physics::collide::Collider;
use crate::scene::Scene;
pub(super) use pit::{draw_bowl_shadows, draw_pit_shade};

/// Angular radius of the sun's disc (rad): how fast the penumbra widens with height.
pub(super) const SUN_RADIUS: f64 = 0.045;
/// Half-angle of the sky's cone about a plane's normal (rad).
pub(super) const SKY_RADIUS: f64 = 0.4;
/// Opacity of a full sun shadow on a plane (black over the plane's colour).
pub(super) const SUN_DARK: f64 = 0.42;
/// Opacity of the sky's shadow right under a body that touches a plane.
pub(super) const SKY_DARK: f64 = 0.38;
/// Directions the sun's disc is sampled at: a ring.
const SUN_SAMPLES: usize = 4;
/// Layers of the sky's shadow: the footprint right under a group, spread ever wider.
const SKY_LAYERS: usize = 3;
/// Segments of a sphere's silhouette circle.
const CIRCLE: usize = 20;

/// The unit direction to the light.
fn light() -> DVec3 {
    colour::LIGHT.normalize()
}

/// `count` unit directions on the ring at half-angle `angle` about `axis`.
fn cone(axis: DVec3, angle: f64, count: usize) -> Vec<DVec3> {
    let (u, w) = plane_axes(axis);
    (0..count)
        .map(|k| {
            let phi = std::f64::consts::TAU * (k as f64 + 0.5) / count as f64;
            (axis + angle.tan() * (phi.cos() * u + phi.sin() * w)).normalize()
        })
        .collect()
}

/// Per-sample opacity so that `count` layers add up to `total`: `1 - (1 - a)^count = total`.
fn layer_alpha(total: f64, count: usize) -> f64 {
    1.0 - (1.0 - total.clamp(0.0, 0.999)).powf(1.0 / count.max(1) as f64)
}

/// What casts shadows on the planes, in world coordinates, found once per frame.
#[derive(Clone, Debug, Default)]
pub(super) struct Casters {
    /// Corners of the polygons, one after the other.
    points: Vec<DVec3>,
    /// `(start, len)` of each polygon in `points`.
    polys: Vec<(u32, u32)>,
    /// Strips: end points and half-width (m).
    strips: Vec<(DVec3, DVec3, f64)>,
    /// Balls: centre and radius (m).
    balls: Vec<(DVec3, f64)>,
    /// Groups (a body with its spheres): ends of its polygons, strips and balls.
    groups: Vec<[usize; 3]>,
}

impl Casters {
    /// An empty set.
    pub(super) fn new() -> Casters {
        Casters::default()
    }

    /// Adds a polygon (a quad of a surface).
    pub(super) fn polygon(&mut self, corners: &[DVec3]) {
        self.polys
            .push((self.points.len() as u32, corners.len() as u32));
        self.points.extend_from_slice(corners);
    }

    /// Adds a strip from `a` to `b` of half-width `half` (m): a spring.
    pub(super) fn strip(&mut self, a: DVec3, b: DVec3, half: f64) {
        self.strips.push((a, b, half));
    }

    /// Adds a ball: a sphere or a particle.
    pub(super) fn ball(&mut self, center: DVec3, radius: f64) {
        if radius > 0.0 && radius.is_finite() {
            self.balls.push((center, radius));
        }
    }

    /// Ends the current group (one body with its spheres).
    pub(super) fn end_group(&mut self) {
        let g = [self.polys.len(), self.strips.len(), self.balls.len()];
        if self.groups.last() != Some(&g) {
            self.groups.push(g);
        }
    }

    /// True when the shadows of every caster (along the light, with room for the penumbra)
    /// fall inside the patch of `floor`.
    fn fit(&self, floor: &Floor) -> bool {
        let (q, n) = (floor.point, floor.normal);
        let l = light();
        if l.dot(n) <= 1e-6 {
            return false;
        }
        let (u, w) = plane_axes(n);
        let coords = |p: DVec3| ((p - q).dot(u), (p - q).dot(w));
        let (a, b) = (coords(floor.outline[0]), coords(floor.outline[2]));
        let (u0, u1, w0, w1) = (a.0.min(b.0), a.0.max(b.0), a.1.min(b.1), a.1.max(b.1));
        let within = |(pu, pw): (f64, f64), r: f64| {
            pu - r >= u0 && pu + r <= u1 && pw - r >= w0 && pw + r <= w1
        };
        // The sun's shadow along the light, the sky's under the point, spread.
        let inside = |p: DVec3, r: f64| {
            let h = (p - q).dot(n).max(0.0);
            within(
                coords(p - l * (h / l.dot(n))),
                r + h * SUN_RADIUS.tan() + 0.05,
            ) && within(coords(p), r + 2.0 * h * SKY_RADIUS.tan() + 0.05)
        };
        self.points.iter().all(|&p| inside(p, 0.0))
            && self
                .strips
                .iter()
                .all(|&(a, b, r)| inside(a, r) && inside(b, r))
            && self.balls.iter().all(|&(c, r)| inside(c, r))
    }

    fn is_empty(&self) -> bool {
        self.polys.is_empty() && self.strips.is_empty() && self.balls.is_empty()
    }

    /// Lowest height above the plane, size across the plane and the centre of the box under
    /// the casters of group `g` (m).
    fn group_extent(&self, g: usize, q: DVec3, n: DVec3) -> (f64, f64, DVec3) {
        let [p0, s0, b0] = if g == 0 { [0; 3] } else { self.groups[g - 1] };
        let [p1, s1, b1] = self.groups[g];
        let mut lo = f64::INFINITY;
        let mut min = DVec3::splat(f64::INFINITY);
        let mut max = DVec3::splat(f64::NEG_INFINITY);
        let mut add = |p: DVec3, r: f64| {
            lo = lo.min((p - q).dot(n) - r);
            min = min.min(p - DVec3::splat(r));
            max = max.max(p + DVec3::splat(r));
        };
        for &(start, len) in &self.polys[p0..p1] {
            for &p in &self.points[start as usize..(start + len) as usize] {
                add(p, 0.0);
            }
        }
        for &(a, b, half) in &self.strips[s0..s1] {
            add(a, half);
            add(b, half);
        }
        for &(c, r) in &self.balls[b0..b1] {
            add(c, r);
        }
        let size = max - min;
        // The size across the plane: the box's extent with the part along the normal removed.
        let across = (size - size.dot(n.abs()) * n.abs()).max_element();
        let mid = 0.5 * (min + max);
        (lo.max(0.0), across.max(0.0), mid - (mid - q).dot(n) * n)
    }

    /// The path of the shadows of groups `groups` on the plane `(q, n)` lit from `d`, in
    /// pixels; every piece turned the same way round so that overlaps stay one coverage.
    fn path(
        &self,
        view: &View,
        q: DVec3,
        n: DVec3,
        d: DVec3,
        groups: std::ops::Range<usize>,
        spread: Option<(DVec3, f64)>,
    ) -> Option<tiny_skia::Path> {
        let dn = d.dot(n);
        if dn <= 1e-6 {
            return None;
        }
        let (centre, factor) = spread.unwrap_or((q, 1.0));
        let onto = |p: DVec3| {
            let h = (p - q).dot(n);
            let on = if h <= 0.0 {
                p - h * n
            } else {
                p - d * (h / dn)
            };
            centre + factor * (on - centre)
        };
        self.path_with(view, groups, d, n, onto)
    }

    /// The path of the shadows of groups `groups` lit from `d`, every caster point moved to
    /// where its shadow falls by `onto`; a strip's width is laid out across `n` (the receiver's
    /// normal), every piece turned the same way round on the screen.
    fn path_with(
        &self,
        view: &View,
        groups: std::ops::Range<usize>,
        d: DVec3,
        n: DVec3,
        onto: impl Fn(DVec3) -> DVec3,
    ) -> Option<tiny_skia::Path> {
        let [p0, s0, b0] = if groups.start == 0 {
            [0; 3]
        } else {
            self.groups[groups.start - 1]
        };
        let [p1, s1, b1] = self.groups[groups.end - 1];
        let mut pb = PathBuilder::new();
        let mut ring: Vec<DVec3> = Vec::with_capacity(CIRCLE);
        for &(start, len) in &self.polys[p0..p1] {
            ring.clear();
            ring.extend(
                self.points[start as usize..(start + len) as usize]
                    .iter()
                    .map(|&p| onto(p)),
            );
            push_polygon(&mut pb, view, &ring);
        }
        for &(a, b, half) in &self.strips[s0..s1] {
            let (a, b) = (onto(a), onto(b));
            let side = n
                .cross(b - a)
                .try_normalize()
                .unwrap_or_else(|| plane_axes(n).0)
                * half;
            let along = (b - a).try_normalize().unwrap_or(side.cross(n).normalize()) * half;
            ring.clear();
            ring.extend([
                a + side - along,
                b + side + along,
                b - side + along,
                a - side - along,
            ]);
            push_polygon(&mut pb, view, &ring);
        }
        let (u, w) = plane_axes(d);
        for &(c, r) in &self.balls[b0..b1] {
            ring.clear();
            ring.extend((0..CIRCLE).map(|k| {
                let phi = std::f64::consts::TAU * k as f64 / CIRCLE as f64;
                onto(c + r * (phi.cos() * u + phi.sin() * w))
            }));
            push_polygon(&mut pb, view, &ring);
        }
        pb.finish()
    }
}

/// Adds the world polygon `ring` (on a plane) to `pb` in pixels, clipped to the near distance,
/// counter-clockwise on the screen.
fn push_polygon(pb: &mut PathBuilder, view: &View, ring: &[DVec3]) {
    let cam: Vec<DVec3> = ring.iter().map(|&p| view.to_camera(p)).collect();
    let cam = view.clip_polygon(&cam);
    let pts: Vec<(f32, f32)> = cam
        .iter()
        .filter_map(|&c| view.project_camera(c).map(|p| (p.x, p.y)))
        .collect();
    if pts.len() < 3 {
        return;
    }
    let mut area = 0.0f32;
    for i in 0..pts.len() {
        let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
        area += a.0 * b.1 - b.0 * a.1;
    }
    let mut order: Box<dyn Iterator<Item = &(f32, f32)>> = if area >= 0.0 {
        Box::new(pts.iter())
    } else {
        Box::new(pts.iter().rev())
    };
    if let Some(&(x, y)) = order.next() {
        pb.move_to(x, y);
        for &(x, y) in order {
            pb.line_to(x, y);
        }
        pb.close();
    }
}

/// Draws the shadows of `casters` on `floor` (already painted), clipped to its outline.
pub(super) fn draw_plane_shadows(
    pixmap: &mut Pixmap,
    paint: &mut Paint,
    view: &View,
    floor: &Floor,
    casters: &Casters,
) {
    let (q, n) = (floor.point, floor.normal);
    if casters.is_empty() || casters.groups.is_empty() || (view.eye - q).dot(n) <= 0.0 {
        return;
    }
    // The patch usually holds every shadow (`terrain::floor`): then only a hole needs
    // cutting out.
    let mask = if floor.hole.is_empty() && casters.fit(floor) {
        None
    } else {
        let Some(region) = floor_path(view, floor) else {
            return;
        };
        let Some(mut mask) = Mask::new(pixmap.width(), pixmap.height()) else {
            return;
        };
        mask.fill_path(
            &region,
            FillRule::EvenOdd,
            paint.anti_alias,
            Transform::identity(),
        );
        Some(mask)
    };
    let mut fill = |path: Option<tiny_skia::Path>, alpha: f64| {
        if let Some(path) = path {
            let a = (alpha * 255.0).round().clamp(1.0, 255.0) as u8;
            paint.set_color(Colour::rgba(0, 0, 0, a).to_skia());
            pixmap.fill_path(
                &path,
                paint,
                FillRule::Winding,
                Transform::identity(),
                mask.as_ref(),
            );
        }
    };
    // The sun: every caster at once.
    let suns = cone(light(), SUN_RADIUS, SUN_SAMPLES);
    let a = layer_alpha(SUN_DARK, suns.len());
    for &d in &suns {
        fill(
            casters.path(view, q, n, d, 0..casters.groups.len(), None),
            a,
        );
    }
    // The sky: each group by its own height, its footprint spread about its centre.
    for g in 0..casters.groups.len() {
        let (h, s, centre) = casters.group_extent(g, q, n);
        let total = SKY_DARK * s * s / (s * s + h * h).max(1e-12);
        if total < 0.01 || s <= 0.0 {
            continue;
        }
        let a = layer_alpha(total, SKY_LAYERS);
        for k in 0..SKY_LAYERS {
            let grow = 2.0 * h * SKY_RADIUS.tan() / s * k as f64 / (SKY_LAYERS - 1) as f64;
            fill(
                casters.path(view, q, n, n, g..g + 1, Some((centre, 1.0 + grow))),
                a,
            );
        }
    }
}

/// A caster's outline across the light, its box `(x0, y0, x1, y1)` and its level along the
/// light (m).
type Outline = (Vec<(f64, f64)>, [f64; 4], f64);

/// The casters' shadows on curved receivers (a bowl), point by point: each caster's outline
/// seen from the light, in coordinates across the light, with its level along the light.
#[derive(Clone, Debug, Default)]
pub(super) struct CastShadows {
    across: (DVec3, DVec3),
    /// Outline, its box `(x0, y0, x1, y1)` and its mean level along the light (m).
    rings: Vec<Outline>,
    /// Discs: centre, radius and level (m).
    discs: Vec<((f64, f64), f64, f64)>,
}

impl CastShadows {
    /// The shadows of `casters`' polygons and balls.
    pub(super) fn new(casters: &Casters) -> CastShadows {
        let l = light();
        let (u, w) = plane_axes(l);
        let flat = |p: DVec3| (p.dot(u), p.dot(w));
        let mut rings = Vec::with_capacity(casters.polys.len());
        for &(start, len) in &casters.polys {
            let pts = &casters.points[start as usize..(start + len) as usize];
            let ring: Vec<(f64, f64)> = pts.iter().map(|&p| flat(p)).collect();
            let mut bx = [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ];
            for &(x, y) in &ring {
                bx = [bx[0].min(x), bx[1].min(y), bx[2].max(x), bx[3].max(y)];
            }
            let level = pts.iter().map(|p| p.dot(l)).sum::<f64>() / pts.len().max(1) as f64;
            rings.push((ring, bx, level));
        }
        let discs = casters
            .balls
            .iter()
            .map(|&(c, r)| (flat(c), r, c.dot(l)))
            .collect();
        CastShadows {
            across: (u, w),
            rings,
            discs,
        }
    }

    /// The share of the sun that reaches `p` past the casters (0..=1), with a penumbra of
    /// `t tan α` at a distance `t` from the caster.
    pub(super) fn sun(&self, p: DVec3) -> f64 {
        let l = light();
        let tan = SUN_RADIUS.tan();
        let (x, y) = (p.dot(self.across.0), p.dot(self.across.1));
        let lp = p.dot(l);
        let mut v = 1.0;
        for (ring, bx, level) in &self.rings {
            let t = level - lp;
            if t <= 0.0 {
                continue;
            }
            let w = t * tan + 0.01;
            if x < bx[0] - w || y < bx[1] - w || x > bx[2] + w || y > bx[3] + w {
                continue;
            }
            let (inside, d) = inside_and_distance(ring, x, y);
            let signed = if inside { -d } else { d };
            v *= (0.5 + signed / (2.0 * w)).clamp(0.0, 1.0);
        }
        for &((cx, cy), r, level) in &self.discs {
            let t = level - lp;
            if t <= 0.0 {
                continue;
            }
            let w = t * tan + r / 50.0;
            let rho = ((x - cx).powi(2) + (y - cy).powi(2)).sqrt();
            v *= (0.5 + (rho - r) / (2.0 * w)).clamp(0.0, 1.0);
        }
        v
    }
}

/// Even-odd test of `(x, y)` against the polygon `ring` and its distance to the outline.
fn inside_and_distance(ring: &[(f64, f64)], x: f64, y: f64) -> (bool, f64) {
    let mut inside = false;
    let mut dist2 = f64::INFINITY;
    for i in 0..ring.len() {
        let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
        if (a.1 > y) != (b.1 > y) && x < a.0 + (y - a.1) / (b.1 - a.1) * (b.0 - a.0) {
            inside = !inside;
        }
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let t =
            (((x - a.0) * dx + (y - a.1) * dy) / (dx * dx + dy * dy).max(1e-18)).clamp(0.0, 1.0);
        dist2 = dist2.min((a.0 + t * dx - x).powi(2) + (a.1 + t * dy - y).powi(2));
    }
    (inside, dist2.sqrt())
}

/// A bowl as a shadow caster on its own inside.
#[derive(Clone, Copy, Debug)]
struct BowlWall {
    center: DVec3,
    radius: f64,
    rim: f64,
}

/// A floor's hole as a gap that lets light down.
#[derive(Clone, Copy, Debug)]
struct Gap {
    point: DVec3,
    normal: DVec3,
    center: DVec3,
    radius: f64,
}

/// What shades the surfaces (cloth, jelly, bowls) point by point (module docs).
#[derive(Clone, Debug, Default)]
pub(super) struct Lighting {
    balls: Vec<(DVec3, f64)>,
    walls: Vec<BowlWall>,
    gaps: Vec<Gap>,
}

impl Lighting {
    /// The shading occluders of `scene`: its spheres, its bowls and its floors with a hole;
    /// none when `on` is false.
    pub(super) fn new(scene: &Scene, bowls: &[Bowl], floors: &[Floor], on: bool) -> Lighting {
        if !on {
            return Lighting::default();
        }
        Lighting {
            balls: scene_balls(scene),
            ..Lighting::terrain(bowls, floors)
        }
    }

    /// What shades the terrain alone: the bowls' walls and the floors' holes (the light that
    /// reaches a bowl's corners whatever the bodies do).
    pub(super) fn terrain(bowls: &[Bowl], floors: &[Floor]) -> Lighting {
        let mut gaps = Vec::new();
        for f in floors {
            if let Some((center, radius)) = f.hole_circle {
                gaps.push(Gap {
                    point: f.point,
                    normal: f.normal,
                    center,
                    radius,
                });
            }
        }
        Lighting {
            balls: Vec::new(),
            walls: bowls
                .iter()
                .map(|b| BowlWall {
                    center: b.center,
                    radius: b.radius,
                    rim: b.rim,
                })
                .collect(),
            gaps,
        }
    }

    /// True when nothing shades anything.
    pub(super) fn is_empty(&self) -> bool {
        self.balls.is_empty() && self.walls.is_empty() && self.gaps.is_empty()
    }

    /// The share of the sun that reaches `p` (0..=1).
    pub(super) fn sun(&self, p: DVec3) -> f64 {
        let l = light();
        let tan = SUN_RADIUS.tan();
        let mut v = 1.0;
        for &(c, r) in &self.balls {
            let t = (c - p).dot(l);
            if t <= 0.0 {
                continue;
            }
            let rho = (c - p - t * l).length();
            let w = t * tan + r / 50.0;
            v *= (0.5 + (rho - r) / (2.0 * w)).clamp(0.0, 1.0);
        }
        for wall in &self.walls {
            // Where the ray from a point on or inside the sphere leaves it.
            let (b, e) = (
                (p - wall.center).dot(l),
                (p - wall.center).length_squared() - wall.radius * wall.radius,
            );
            if e > 1e-9 * wall.radius * wall.radius {
                continue;
            }
            let t = -b + (b * b - e).max(0.0).sqrt();
            if t <= 0.0 {
                continue;
            }
            let exit = p + t * l;
            let w = t * tan + 1e-3;
            v *= (0.5 + (exit.y - wall.rim) / (2.0 * w)).clamp(0.0, 1.0);
        }
        for g in &self.gaps {
            let h = (p - g.point).dot(g.normal);
            let ln = l.dot(g.normal);
            if h >= 0.0 || ln <= 1e-6 {
                continue;
            }
            let t = -h / ln;
            let s = p + t * l - g.center;
            let rho = (s - s.dot(g.normal) * g.normal).length();
            let w = t * tan + 1e-3;
            v *= (0.5 + (g.radius - rho) / (2.0 * w)).clamp(0.0, 1.0);
        }
        v
    }

    /// The share of the sky that reaches `p` on a surface of unit normal `normal` (0..=1).
    pub(super) fn sky(&self, p: DVec3, normal: DVec3) -> f64 {
        let mut v = 1.0;
        for &(c, r) in &self.balls {
            let to = c - p;
            let d2 = to.length_squared();
            if d2 <= r * r {
                continue;
            }
            let d = d2.sqrt();
            v *= 1.0 - (r * r / d2) * normal.dot(to / d).max(0.0);
        }
        v.clamp(0.0, 1.0)
    }
}

/// The spheres of `scene`: static sphere colliders (once each) and every body's dynamic ones.
pub(super) fn scene_balls(scene: &Scene) -> Vec<(DVec3, f64)> {
    let mut out: Vec<(DVec3, f64)> = Vec::new();
    for body in &scene.bodies {
        for c in &body.model.colliders {
            if let Collider::Sphere { center, radius } = *c
                && !out.contains(&(center, radius))
            {
                out.push((center, radius));
            }
        }
    }
    for body in &scene.bodies {
        out.extend(body.state.spheres.iter().map(|s| (s.center, s.radius)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampled_layers_add_up_to_the_total() {
        for (total, n) in [(0.42, 5), (0.1, 3), (0.9, 7)] {
            let a = layer_alpha(total, n);
            assert!(((1.0 - (1.0 - a).powi(n as i32)) - total).abs() < 1e-12);
        }
    }

    #[test]
    fn the_cone_spreads_at_its_half_angle() {
        let axis = light();
        let dirs = cone(axis, SUN_RADIUS, SUN_SAMPLES);
        assert_eq!(dirs.len(), SUN_SAMPLES);
        for d in &dirs {
            assert!((d.length() - 1.0).abs() < 1e-12);
            assert!((d.dot(axis).acos() - SUN_RADIUS).abs() < 1e-9);
        }
    }

    #[test]
    fn a_ball_shades_what_is_under_it_towards_the_light() {
        let lights = Lighting {
            balls: vec![(DVec3::ZERO, 1.0)],
            ..Lighting::default()
        };
        let l = light();
        // Straight down the light ray from the centre, 3 m away: full shadow.
        assert_eq!(lights.sun(-3.0 * l), 0.0);
        // Towards the light from the ball: lit.
        assert_eq!(lights.sun(3.0 * l), 1.0);
        // Well to the side: lit; the sky is darkened only by a ball the normal faces.
        let side = 3.0 * plane_axes(l).0;
        assert_eq!(lights.sun(side), 1.0);
        let below = DVec3::new(0.0, -2.0, 0.0);
        // Ball of radius 1 at distance 2, straight above: 1 - 1/4.
        assert!((lights.sky(below, DVec3::Y) - 0.75).abs() < 1e-12);
        assert_eq!(lights.sky(below, -DVec3::Y), 1.0);
    }

    #[test]
    fn the_floor_around_a_hole_shades_what_is_below_it() {
        let lights = Lighting {
            gaps: vec![Gap {
                point: DVec3::ZERO,
                normal: DVec3::Y,
                center: DVec3::ZERO,
                radius: 2.0,
            }],
            ..Lighting::default()
        };
        let l = light();
        // Right under the hole's centre, 1 m down: the light ray leaves through the hole.
        assert_eq!(lights.sun(DVec3::new(0.0, -1.0, 0.0)), 1.0);
        // Under the floor 5 m from the axis, on the far side from the light: blocked.
        let far = -5.0 * DVec3::new(l.x, 0.0, l.z).normalize() - DVec3::Y;
        assert_eq!(lights.sun(far), 0.0);
    }
}
