//! Terrain meshes: floors and planes (a square patch with a grid and, for a floor with a hole,
//! the hole cut out) and bowls (the inside of a sphere below its rim), found once from a
//! scene's colliders in world coordinates and painted each frame.
//!
//! **Floors and planes** are infinite; they are drawn as a square patch around the content, in a
//! layer of their own (see [`super::draw`] for the order). **Bowls** are tessellated into
//! [`BOWL_RINGS`] rings of [`BOWL_SEGMENTS`] segments from the bottom to the rim, whose height
//! [`crate::physics::bowl::Rim`] gives.

use glam::DVec3;
use tiny_skia::{FillRule, LineCap, Paint, Path, PathBuilder, Pixmap, Stroke, Transform};

use super::camera::{View, plane_axes, scene_bounds};
use super::colour;
use super::occlude::Occluders;
use super::paint::{Item, Shape, grow, nice, project3};
use crate::physics::bowl::Rim;
use crate::physics::collide::Collider;
use crate::scene::Scene;

/// A floor or plane patch in world coordinates.
#[derive(Clone, Debug)]
pub(super) struct Floor {
    /// A point of the plane and its unit normal (into the free side).
    pub(super) point: DVec3,
    pub(super) normal: DVec3,
    /// Outer rectangle, counter-clockwise seen from the free side.
    pub(super) outline: [DVec3; 4],
    /// Hole polygon (empty when there is none).
    pub(super) hole: Vec<DVec3>,
    /// The hole's centre and radius (m).
    pub(super) hole_circle: Option<(DVec3, f64)>,
    /// Grid segments.
    pub(super) grid: Vec<(DVec3, DVec3)>,
}

/// A bowl's tessellation in world coordinates.
#[derive(Clone, Debug)]
pub(super) struct Bowl {
    /// Centre of the bowl's sphere (m).
    pub(super) center: DVec3,
    /// Radius of the bowl's sphere (m).
    pub(super) radius: f64,
    /// Height of the rim (m).
    pub(super) rim: f64,
    /// Corners of the tessellation, ring by ring from the bottom.
    pub(super) vertices: Vec<DVec3>,
    /// Triangles from the bottom to the rim, as indices into `vertices`.
    pub(super) triangles: Vec<[u32; 3]>,
    /// The floor whose hole opens onto the bowl and hides the rest of it (a pit: the rim at or
    /// below the floor, the hole inside the rim circle), as an index into the floors.
    pub(super) pit: Option<usize>,
}

/// Segments of a bowl's tessellation: around and from the bottom to the rim.
pub(super) const BOWL_SEGMENTS: usize = 48;

pub(super) const BOWL_RINGS: usize = 12;

/// The floors and bowls of a scene, in world coordinates.
pub(super) fn static_geometry(scene: &Scene) -> (Vec<Floor>, Vec<Bowl>) {
    let bounds = scene_bounds(scene);
    let mut floors = Vec::new();
    let mut bowls = Vec::new();
    let mut seen: Vec<Collider> = Vec::new();
    for body in &scene.bodies {
        for c in &body.model.colliders {
            if seen.contains(c) {
                continue;
            }
            seen.push(*c);
            match *c {
                Collider::Plane { point, normal } => {
                    floors.push(floor(point, normal, None, &bounds));
                }
                Collider::HolePlane {
                    point,
                    normal,
                    hole_center,
                    hole_radius,
                } => floors.push(floor(
                    point,
                    normal,
                    Some((hole_center, hole_radius)),
                    &bounds,
                )),
                Collider::Bowl {
                    center,
                    radius,
                    rim_height,
                } => {
                    let (vertices, triangles) = bowl_mesh(center, radius, rim_height);
                    bowls.push(Bowl {
                        center,
                        radius,
                        rim: Rim::of(center, radius, rim_height).height,
                        vertices,
                        triangles,
                        pit: None,
                    });
                }
                Collider::Sphere { .. } => {}
            }
        }
    }
    for bowl in &mut bowls {
        bowl.pit = floors.iter().position(|f| covers(f, bowl));
    }
    (floors, bowls)
}

/// True when `floor` hides all of `bowl` but what its hole shows: a horizontal floor at or
/// above the rim whose hole lies inside the rim circle. Seen from above such a floor, a ray
/// through the hole is inside the bowl's sphere until it meets the bowl's inside, so the
/// outside is never seen and the inside is behind everything in the bowl.
fn covers(floor: &Floor, bowl: &Bowl) -> bool {
    let Some((centre, radius)) = floor.hole_circle else {
        return false;
    };
    let rim = Rim::of(bowl.center, bowl.radius, bowl.rim);
    let axis = DVec3::new(centre.x - bowl.center.x, 0.0, centre.z - bowl.center.z).length();
    floor.normal.dot(DVec3::Y) > 1.0 - 1e-9
        && floor.point.y >= bowl.rim - 1e-9
        && axis + radius <= rim.radius_squared.max(0.0).sqrt() + 1e-6 * bowl.radius
}

/// A plane patch around the content `bounds` with grid lines every nice distance, and the hole.
pub(super) fn floor(
    point: DVec3,
    normal: DVec3,
    hole: Option<(DVec3, f64)>,
    bounds: &super::camera::Aabb,
) -> Floor {
    let n = normal.try_normalize().unwrap_or(DVec3::Y);
    let (u, w) = plane_axes(n);
    // Plane coordinates (along û, ŵ) of the content's corners, measured from `point`.
    let (mut u0, mut u1, mut w0, mut w1) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut first = true;
    let corners = if bounds.is_empty() {
        [point; 8]
    } else {
        bounds.corners()
    };
    // The content's corners and, for those above the plane, their shadows along the light
    // (`super::shadow`): the patch holds the shadows too.
    let l = colour::LIGHT.normalize();
    let shadows = corners.map(|c| {
        let h = (c - point).dot(n);
        if h > 0.0 && l.dot(n) > 0.1 {
            c - l * (h / l.dot(n))
        } else {
            c
        }
    });
    for c in corners {
        let (cu, cw) = ((c - point).dot(u), (c - point).dot(w));
        if first {
            (u0, u1, w0, w1) = (cu, cu, cw, cw);
            first = false;
        }
        u0 = u0.min(cu);
        u1 = u1.max(cu);
        w0 = w0.min(cw);
        w1 = w1.max(cw);
    }
    // Half the content's size more on every side, at least 1 m across.
    let margin = 0.5 * (u1 - u0).max(w1 - w0).max(1.0);
    for c in shadows {
        let (cu, cw) = ((c - point).dot(u), (c - point).dot(w));
        u0 = u0.min(cu);
        u1 = u1.max(cu);
        w0 = w0.min(cw);
        w1 = w1.max(cw);
    }
    let spacing = nice((u1 - u0 + w1 - w0 + 4.0 * margin) / 24.0, true);
    let snap_down = |v: f64| (v / spacing).floor() * spacing;
    let snap_up = |v: f64| (v / spacing).ceil() * spacing;
    let (u0, u1, w0, w1) = (
        snap_down(u0 - margin),
        snap_up(u1 + margin),
        snap_down(w0 - margin),
        snap_up(w1 + margin),
    );
    let at = |a: f64, b: f64| point + a * u + b * w;
    let outline = [at(u0, w0), at(u1, w0), at(u1, w1), at(u0, w1)];
    let hole_uv = hole.map(|(c, r)| ((c - point).dot(u), (c - point).dot(w), r));
    let hole_poly = hole_uv
        .map(|(hu, hw, r)| {
            (0..96)
                .map(|k| {
                    let phi = std::f64::consts::TAU * k as f64 / 96.0;
                    at(hu + r * phi.cos(), hw + r * phi.sin())
                })
                .collect()
        })
        .unwrap_or_default();
    let mut grid = Vec::new();
    // Lines u = const from w0 to w1, cut where they cross the hole; then w = const likewise.
    let count_u = ((u1 - u0) / spacing).round() as i64;
    let count_w = ((w1 - w0) / spacing).round() as i64;
    for k in 0..=count_u {
        let a = u0 + k as f64 * spacing;
        for (b0, b1) in cut(w0, w1, hole_uv.map(|(hu, hw, r)| (a - hu, hw, r))) {
            grid.push((at(a, b0), at(a, b1)));
        }
    }
    for k in 0..=count_w {
        let b = w0 + k as f64 * spacing;
        for (a0, a1) in cut(u0, u1, hole_uv.map(|(hu, hw, r)| (b - hw, hu, r))) {
            grid.push((at(a0, b), at(a1, b)));
        }
    }
    Floor {
        point,
        normal: n,
        outline,
        hole: hole_poly,
        hole_circle: hole,
        grid,
    }
}

/// The parts of the interval `[lo, hi]` outside a circle: `hole = (offset of the line from the
/// centre, centre along the line, radius)`.
pub(super) fn cut(lo: f64, hi: f64, hole: Option<(f64, f64, f64)>) -> Vec<(f64, f64)> {
    match hole {
        Some((off, centre, r)) if off.abs() < r => {
            let half = (r * r - off * off).sqrt();
            let (c0, c1) = (centre - half, centre + half);
            let mut out = Vec::new();
            if c0 > lo {
                out.push((lo, c0.min(hi)));
            }
            if c1 < hi {
                out.push((c1.max(lo), hi));
            }
            out
        }
        _ => vec![(lo, hi)],
    }
}

/// The bowl's tessellation: the sphere below the rim, from the bottom (polar angle 0) to the
/// rim angle `θ_rim = acos((c_y - rim)/r)`, corners `c + r (sin θ cos φ, -cos θ, sin θ sin φ)`
/// ring by ring, and triangles as indices into them.
pub(super) fn bowl_mesh(
    center: DVec3,
    radius: f64,
    rim_height: f64,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let rim = Rim::of(center, radius, rim_height).height;
    let theta_rim = ((center.y - rim) / radius).clamp(-1.0, 1.0).acos();
    let mut vertices = Vec::with_capacity((BOWL_RINGS + 1) * (BOWL_SEGMENTS + 1));
    for i in 0..=BOWL_RINGS {
        for j in 0..=BOWL_SEGMENTS {
            let theta = theta_rim * i as f64 / BOWL_RINGS as f64;
            let phi = std::f64::consts::TAU * j as f64 / BOWL_SEGMENTS as f64;
            vertices.push(
                center
                    + radius
                        * DVec3::new(
                            theta.sin() * phi.cos(),
                            -theta.cos(),
                            theta.sin() * phi.sin(),
                        ),
            );
        }
    }
    let at = |i: usize, j: usize| (i * (BOWL_SEGMENTS + 1) + j) as u32;
    let mut t = Vec::with_capacity(2 * BOWL_RINGS * BOWL_SEGMENTS);
    for i in 0..BOWL_RINGS {
        for j in 0..BOWL_SEGMENTS {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // At the bottom (i = 0) a = d is the pole: one triangle per segment.
            t.push([a, b, c]);
            if i > 0 {
                t.push([a, c, d]);
            }
        }
    }
    (vertices, t)
}

/// The bowl's triangles, inside and outside coloured differently, shaded by the share of the
/// sun `sun` that reaches each corner (none: no shadows), cut by the planes of `occ`; the
/// triangles whose outside the camera sees are left out when `inside_only`.
pub(super) fn bowl_items(
    view: &View,
    bowl: &Bowl,
    occ: &Occluders,
    sun: Option<&[f64]>,
    inside_only: bool,
    items: &mut Vec<Item>,
) {
    for &tri in &bowl.triangles {
        let [a, b, c] = tri.map(|i| bowl.vertices[i as usize]);
        let centroid = (a + b + c) / 3.0;
        let mut n = (b - a).cross(c - a).normalize_or_zero();
        let to_eye = if view.perspective {
            view.eye - centroid
        } else {
            -view.forward
        };
        // The normal of the side the camera sees.
        if n.dot(to_eye) < 0.0 {
            n = -n;
        }
        // That side is the inside when its normal points towards the sphere's centre.
        let inside = n.dot(bowl.center - centroid) > 0.0;
        if inside_only && !inside {
            continue;
        }
        let base = if inside {
            colour::BOWL_INSIDE
        } else {
            colour::BOWL_OUTSIDE
        };
        let colour = match sun {
            Some(v) => {
                let share = tri.iter().map(|&i| v[i as usize]).sum::<f64>() / 3.0;
                colour::shade_lit(base, n, share, 1.0)
            }
            None => colour::shade(base, n),
        };
        push_polygon(view, occ, &[a, b, c], colour, items);
    }
}

/// The convex world polygon `poly` as shaded triangles: cut by the planes of `occ`, clipped to
/// the near distance, each piece at its own depth. Returns the nearest sort depth pushed.
pub(super) fn push_polygon(
    view: &View,
    occ: &Occluders,
    poly: &[DVec3],
    colour: colour::Colour,
    items: &mut Vec<Item>,
) -> f64 {
    let mut nearest = f64::INFINITY;
    occ.split_polygon(poly, |layer, piece| {
        let mut buf = [DVec3::ZERO; 8];
        if piece.len() > buf.len() {
            return;
        }
        let cam = &mut buf[..piece.len()];
        for (c, &p) in cam.iter_mut().zip(piece) {
            *c = view.to_camera(p);
        }
        if cam.iter().any(|p| p.z < view.near) {
            return;
        }
        let centroid = piece.iter().copied().sum::<DVec3>() / piece.len() as f64;
        let depth = occ.key(
            centroid,
            cam.iter().map(|p| p.z).sum::<f64>() / cam.len() as f64,
        );
        nearest = nearest.min(depth);
        for k in 1..cam.len() - 1 {
            let Some(p) = project3(view, [cam[0], cam[k], cam[k + 1]]) else {
                continue;
            };
            items.push(Item {
                layer,
                depth,
                shape: Shape::Triangle {
                    p: grow(p, 0.5),
                    colour,
                },
            });
        }
    });
    nearest
}

/// The floor's region on the screen: its outline with the hole cut out (even-odd).
pub(super) fn floor_path(view: &View, floor: &Floor) -> Option<Path> {
    let mut pb = PathBuilder::new();
    add_ring(&mut pb, view, &floor.outline);
    if !floor.hole.is_empty() {
        add_ring(&mut pb, view, &floor.hole);
    }
    pb.finish()
}

/// Adds the closed polygon `ring` (world points), clipped to the view and projected, to `pb`.
pub(super) fn add_ring(pb: &mut PathBuilder, view: &View, ring: &[DVec3]) {
    let cam: Vec<DVec3> = ring.iter().map(|&p| view.to_camera(p)).collect();
    let mut first = true;
    for c in view.clip_polygon(&cam) {
        if let Some(p) = view.project_camera(c) {
            if first {
                pb.move_to(p.x, p.y);
                first = false;
            } else {
                pb.line_to(p.x, p.y);
            }
        }
    }
    if !first {
        pb.close();
    }
}

/// A floor: the shaded patch with its hole cut out, its grid and the hole's rim.
pub(super) fn draw_floor(
    pixmap: &mut Pixmap,
    paint: &mut Paint,
    view: &View,
    floor: &Floor,
    s: f32,
) {
    let camera_above = (view.eye - floor.point).dot(floor.normal) > 0.0;
    let alpha = if camera_above { 255 } else { 70 };
    if let Some(path) = floor_path(view, floor) {
        paint.set_color(
            colour::shade(colour::GROUND, floor.normal)
                .with_alpha(alpha)
                .to_skia(),
        );
        pixmap.fill_path(&path, paint, FillRule::EvenOdd, Transform::identity(), None);
    }
    // The grid and the hole's rim, each one path: one paint layer, one call.
    stroke_world_segments(
        pixmap,
        paint,
        view,
        floor.grid.iter().copied(),
        0.8 * s,
        colour::GROUND_GRID,
    );
    let n = floor.hole.len();
    stroke_world_segments(
        pixmap,
        paint,
        view,
        (0..n).map(|k| (floor.hole[k], floor.hole[(k + 1) % n])),
        1.5 * s,
        colour::GROUND.scaled(0.45),
    );
}

/// The world segments, clipped to the view, stroked `width` px wide as one path.
fn stroke_world_segments(
    pixmap: &mut Pixmap,
    paint: &mut Paint,
    view: &View,
    segments: impl Iterator<Item = (DVec3, DVec3)>,
    width: f32,
    c: colour::Colour,
) {
    let mut pb = PathBuilder::new();
    for (a, b) in segments {
        if let Some((ca, cb)) = view.clip_segment(view.to_camera(a), view.to_camera(b))
            && let (Some(pa), Some(pb2)) = (view.project_camera(ca), view.project_camera(cb))
        {
            pb.move_to(pa.x, pa.y);
            pb.line_to(pb2.x, pb2.y);
        }
    }
    if let Some(path) = pb.finish() {
        paint.set_color(c.to_skia());
        let stroke = Stroke {
            width,
            line_cap: LineCap::Round,
            ..Stroke::default()
        };
        pixmap.stroke_path(&path, paint, &stroke, Transform::identity(), None);
    }
}
