//! The camera: where the eye is, how the world is projected onto the image, and a default view
//! that frames a scene.
//!
//! # Theory
//!
//! The camera orbits a target point. Its eye sits on a sphere of radius `distance` around the
//! target, at an orbit angle `a` about the vertical axis and an elevation `e` above the
//! horizontal:
//!
//! ```text
//! eye = target + distance · (cos e · sin a,  sin e,  cos e · cos a)
//! f̂   = (target - eye) / |target - eye|          forward (into the image)
//! r̂   = (f̂ × ŷ) / |f̂ × ŷ|                        right   (x̂ when looking straight down)
//! û   = r̂ × f̂                                    up
//! ```
//! A world point `p` (m) has camera coordinates `(x_c, y_c, z_c) = ((p - eye)·r̂, (p - eye)·û,
//! (p - eye)·f̂)`; `z_c` is its depth (m). The image has `W × H` pixels, `u` to the right and `v`
//! downwards from the top-left corner:
//!
//! ```text
//! perspective:   s = (H/2) / tan(φ/2)     u = W/2 + s x_c / z_c     v = H/2 - s y_c / z_c
//! orthographic:  s = H / h                u = W/2 + s x_c           v = H/2 - s y_c
//! ```
//! where
//! - `φ`: vertical field of view (rad); `s`: focal length in pixels (px)
//! - `h`: height of the world seen by an orthographic camera (m); `s` is then px/m
//!
//! Points with `z_c` below the near distance are behind the eye; lines and polygons are clipped
//! there in camera space before projection ([`View::clip_segment`], [`View::clip_polygon`]).
//!
//! **Framing.** [`Camera::fit`] keeps the view direction and moves the eye so that the eight
//! corners of a box fit in the image with a margin. For a corner with camera coordinates
//! `(x, y, z')` relative to the target, and the target at distance `d`, its depth is `d + z'`;
//! it is inside the image when
//!
//! ```text
//! |x| ≤ t_h (d + z')   and   |y| ≤ t_v (d + z')     t_v = tan(φ/2) / m,  t_h = t_v · W/H
//! ⇔ d ≥ max(|x| / t_h, |y| / t_v) - z'
//! ```
//! where `m > 1` is the margin factor; the smallest `d` that satisfies every corner is taken.

use glam::DVec3;

use crate::scene::Scene;

mod bounds;
pub use bounds::{Aabb, scene_bounds};

/// How the camera projects the world onto the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// A pinhole camera with vertical field of view `fov_y` (rad).
    Perspective {
        /// Vertical field of view (rad), between 0 and π.
        fov_y: f64,
    },
    /// Parallel projection showing `height` metres of the world from the top to the bottom of
    /// the image.
    Orthographic {
        /// World height seen (m), > 0.
        height: f64,
    },
}

impl Default for Projection {
    /// Perspective with a 40° vertical field of view.
    fn default() -> Projection {
        Projection::Perspective {
            fov_y: 40f64.to_radians(),
        }
    }
}

/// An orbiting camera (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Orbit angle about the vertical axis (rad); 0 looks from +z towards -z.
    pub orbit: f64,
    /// Elevation above the horizontal plane (rad); positive looks down.
    pub elevation: f64,
    /// Distance from the eye to the target (m), > 0.
    pub distance: f64,
    /// The point the camera looks at (m).
    pub target: DVec3,
    /// Perspective or orthographic.
    pub projection: Projection,
}

impl Default for Camera {
    /// Looking at the origin from 10 m away, from the front-right and above.
    fn default() -> Camera {
        Camera {
            orbit: DEFAULT_ORBIT.to_radians(),
            elevation: DEFAULT_ELEVATION.to_radians(),
            distance: 10.0,
            target: DVec3::ZERO,
            projection: Projection::default(),
        }
    }
}

/// Default orbit angle of [`Camera::for_scene`] (degrees).
pub const DEFAULT_ORBIT: f64 = 35.0;
/// Default elevation of [`Camera::for_scene`] (degrees).
pub const DEFAULT_ELEVATION: f64 = 24.0;
/// Margin factor of [`Camera::fit`]: the box fills at most `1/MARGIN` of the image.
const MARGIN: f64 = 1.08;

impl Camera {
    /// The eye position `target + distance (cos e sin a, sin e, cos e cos a)` (m).
    #[must_use]
    pub fn eye(&self) -> DVec3 {
        self.target + self.distance * direction(self.orbit, self.elevation)
    }

    /// The unit vectors `(r̂, û, f̂)` of the camera (right, up, forward; module docs).
    #[must_use]
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let forward = -direction(self.orbit, self.elevation);
        let right = forward.cross(DVec3::Y).try_normalize().unwrap_or(DVec3::X);
        let up = right.cross(forward);
        (right, up, forward)
    }

    /// The same camera with its distance (perspective) or height (orthographic) set so that the
    /// box `bounds` fits into an image of aspect ratio `aspect = W/H` with a margin, looking at
    /// the box centre (module docs, "Framing"). An empty box leaves the camera unchanged.
    #[must_use]
    pub fn fit(self, bounds: &Aabb, aspect: f64) -> Camera {
        self.fit_window(bounds, aspect, 0.0, 0.0)
    }

    /// As [`Camera::fit`], but keeping the top `top` and the bottom `bottom` of the image free
    /// (fractions of its height, for the text overlay and the legend). The box is centred in the
    /// band between them by moving the target along `û` by `δ`:
    ///
    /// ```text
    /// band in NDC y:  m ± h,   m = bottom - top,   h = 1 - top - bottom
    /// perspective:    d ≥ |y - m T z'| / (h T / M) - z',   |x| ≤ (T a / M)(d + z'),   δ = -m T d
    /// orthographic:   H ≥ 2 M |y| / h,                     H ≥ 2 M |x| / a,           δ = -m H / 2
    /// ```
    /// where `(x, y, z')` are a corner's camera coordinates relative to the box centre,
    /// `T = tan(φ/2)`, `a = W/H`, `M` the margin factor and `H` the orthographic height (m).
    #[must_use]
    pub fn fit_window(mut self, bounds: &Aabb, aspect: f64, top: f64, bottom: f64) -> Camera {
        if bounds.is_empty() || !(aspect > 0.0 && aspect.is_finite()) {
            return self;
        }
        let (top, bottom) = (top.clamp(0.0, 0.4), bottom.clamp(0.0, 0.4));
        let (m, h) = (bottom - top, 1.0 - top - bottom);
        let centre = bounds.centre();
        let (right, up, forward) = self.basis();
        let corners = bounds.corners().map(|c| {
            let d = c - centre;
            (d.dot(right), d.dot(up), d.dot(forward))
        });
        // A box of zero size still gets a small view.
        let size = bounds.size().max_element().max(1e-3);
        let shift = match self.projection {
            Projection::Perspective { fov_y } => {
                let t = (0.5 * fov_y).tan();
                let mut d: f64 = 0.0;
                for (x, y, z) in corners {
                    let vertical = (y - m * t * z).abs() / (h * t / MARGIN) - z;
                    let horizontal = x.abs() / (t * aspect / MARGIN) - z;
                    d = d.max(vertical).max(horizontal);
                }
                // The eye stays outside the box, at least one box size from its centre.
                self.distance = d.max(size);
                -m * t * self.distance
            }
            Projection::Orthographic { .. } => {
                let (mut half_w, mut half_h): (f64, f64) = (0.0, 0.0);
                for (x, y, _) in corners {
                    half_w = half_w.max(x.abs());
                    half_h = half_h.max(y.abs());
                }
                let height = (2.0 * MARGIN * (half_h / h).max(half_w / aspect)).max(0.1 * size);
                self.projection = Projection::Orthographic { height };
                // Far enough that everything is in front of the eye.
                self.distance = 2.0 * bounds.size().length().max(1.0);
                -m * 0.5 * height
            }
        };
        self.target = centre + shift * up;
        self
    }

    /// A camera that frames `scene` (bodies, spheres and colliders, see [`scene_bounds`]) in an
    /// image of aspect ratio `aspect = W/H`: from the front when every particle lies in one
    /// plane `z = const` and nothing else is in the scene (ropes swing in that plane), else
    /// from the front-right and above.
    #[must_use]
    pub fn for_scene(scene: &Scene, aspect: f64, projection: Projection) -> Camera {
        Camera::for_scene_window(scene, aspect, projection, 0.0, 0.0)
    }

    /// As [`Camera::for_scene`], keeping the top `top` and bottom `bottom` of the image free
    /// (fractions of its height; see [`Camera::fit_window`]).
    #[must_use]
    pub fn for_scene_window(
        scene: &Scene,
        aspect: f64,
        projection: Projection,
        top: f64,
        bottom: f64,
    ) -> Camera {
        let bounds = scene_bounds(scene);
        let flat = scene.bodies.iter().all(|b| {
            b.model.colliders.is_empty()
                && b.state.spheres.is_empty()
                && b.state.x.iter().all(|p| p.z == b.state.x[0].z)
        });
        let (orbit, elevation) = if flat {
            (0.0, 6.0)
        } else {
            (DEFAULT_ORBIT, DEFAULT_ELEVATION)
        };
        Camera {
            orbit: orbit.to_radians(),
            elevation: elevation.to_radians(),
            projection,
            ..Camera::default()
        }
        .fit_window(&bounds, aspect, top, bottom)
    }
}

/// Factor of one zoom step ([`Camera::zoom`]).
pub const ZOOM_STEP: f64 = 1.25;

/// The smallest and largest elevation the orbit controls reach (degrees).
pub const ELEVATION_LIMIT: f64 = 89.0;

impl Camera {
    /// Turns the eye about the target by `orbit` and `elevation` degrees (the elevation stays
    /// within ±89°, so the camera never looks straight along the vertical).
    pub fn turn(&mut self, orbit: f64, elevation: f64) {
        self.orbit = (self.orbit + orbit.to_radians()).rem_euclid(std::f64::consts::TAU);
        let limit = ELEVATION_LIMIT.to_radians();
        self.elevation = (self.elevation + elevation.to_radians()).clamp(-limit, limit);
    }

    /// Orbit and elevation in whole degrees, the orbit in `(-180, 180]`.
    #[must_use]
    pub fn angles_degrees(&self) -> (i64, i64) {
        let mut orbit = self.orbit.to_degrees().round() as i64 % 360;
        if orbit > 180 {
            orbit -= 360;
        } else if orbit <= -180 {
            orbit += 360;
        }
        (orbit, self.elevation.to_degrees().round() as i64)
    }

    /// Moves closer (`factor > 1`) or farther (`factor < 1`): the distance (perspective) or the
    /// height seen (orthographic) is divided by `factor`.
    pub fn zoom(&mut self, factor: f64) {
        if !(factor > 0.0 && factor.is_finite()) {
            return;
        }
        match &mut self.projection {
            Projection::Perspective { .. } => self.distance /= factor,
            Projection::Orthographic { height } => *height /= factor,
        }
    }

    /// The height of the world seen at the target's depth (m): `2 d tan(φ/2)` for perspective,
    /// `h` for orthographic.
    #[must_use]
    pub fn visible_height(&self) -> f64 {
        match self.projection {
            Projection::Perspective { fov_y } => 2.0 * self.distance * (0.5 * fov_y).tan(),
            Projection::Orthographic { height } => height,
        }
    }

    /// Moves the target (and the eye with it) by `right` and `up` times the visible height at
    /// the target, along the camera's right and up vectors.
    pub fn pan(&mut self, right: f64, up: f64) {
        let (r, u, _) = self.basis();
        let h = self.visible_height();
        self.target += h * (right * r + up * u);
    }

    /// Follows `points` (m): moves the target by the least amount (in the view plane) that brings
    /// every point within `zone` (a fraction, e.g. 0.9) of the half-width and half-height of an
    /// image of aspect `aspect = W/H`, and moves the eye back (perspective) or widens the view
    /// (orthographic) when the points do not fit at all, never beyond `max_distance` (m) or
    /// `max_height` (m). Returns true when the camera moved.
    ///
    /// With `(x, y, z')` a point's camera coordinates relative to the target, the target at
    /// distance `d`, `T = tan(φ/2)` and `a` the aspect, a shift `(s_x, s_y)` of the target along
    /// `(r̂, û)` keeps the point in the zone when
    ///
    /// ```text
    /// |x - s_x| ≤ ζ T a (d + z')    and    |y - s_y| ≤ ζ T (d + z')      (perspective)
    /// |x - s_x| ≤ ζ a h / 2         and    |y - s_y| ≤ ζ h / 2           (orthographic)
    /// ```
    /// where ζ is `zone` and `h` the orthographic height: every point bounds `s_x` and `s_y` to an
    /// interval, and the shift is the point of the intersection of all intervals nearest to 0.
    /// When an intersection is empty, `d` (or `h`) grows by 10 % until it is not.
    pub fn follow(
        &mut self,
        points: &[DVec3],
        aspect: f64,
        zone: f64,
        max_distance: f64,
        max_height: f64,
    ) -> bool {
        let points: Vec<DVec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
        if points.is_empty() || !(aspect > 0.0 && aspect.is_finite()) {
            return false;
        }
        let (right, up, forward) = self.basis();
        let rel: Vec<(f64, f64, f64)> = points
            .iter()
            .map(|p| {
                let d = *p - self.target;
                (d.dot(right), d.dot(up), d.dot(forward))
            })
            .collect();
        let before = *self;
        for _ in 0..64 {
            let (t, d, half_h) = match self.projection {
                Projection::Perspective { fov_y } => ((0.5 * fov_y).tan(), self.distance, 0.0),
                Projection::Orthographic { height } => (0.0, 0.0, 0.5 * height),
            };
            let (mut x_lo, mut x_hi) = (f64::NEG_INFINITY, f64::INFINITY);
            let (mut y_lo, mut y_hi) = (f64::NEG_INFINITY, f64::INFINITY);
            let mut behind = false;
            for &(x, y, z) in &rel {
                let half_v = if t > 0.0 {
                    let depth = d + z;
                    behind |= depth <= 1e-3 * d;
                    zone * t * depth
                } else {
                    zone * half_h
                };
                let half_x = half_v * aspect;
                x_lo = x_lo.max(x - half_x);
                x_hi = x_hi.min(x + half_x);
                y_lo = y_lo.max(y - half_v);
                y_hi = y_hi.min(y + half_v);
            }
            if !behind && x_lo <= x_hi && y_lo <= y_hi {
                let sx = 0.0f64.clamp(x_lo, x_hi);
                let sy = 0.0f64.clamp(y_lo, y_hi);
                self.target += sx * right + sy * up;
                return *self != before;
            }
            match &mut self.projection {
                Projection::Perspective { .. } => {
                    if self.distance >= max_distance {
                        break;
                    }
                    self.distance = (self.distance * 1.1).min(max_distance);
                }
                Projection::Orthographic { height } => {
                    if *height >= max_height {
                        break;
                    }
                    *height = (*height * 1.1).min(max_height);
                }
            }
        }
        // Too far apart even at the largest view: centre on their middle.
        let mut b = Aabb::EMPTY;
        for p in &points {
            b.add(*p);
        }
        let c = b.centre() - self.target;
        self.target += c.dot(right) * right + c.dot(up) * up;
        *self != before
    }
}

/// `(cos e sin a, sin e, cos e cos a)`: the unit vector from the target to the eye.
fn direction(orbit: f64, elevation: f64) -> DVec3 {
    DVec3::new(
        elevation.cos() * orbit.sin(),
        elevation.sin(),
        elevation.cos() * orbit.cos(),
    )
}

/// Two unit vectors `(û, ŵ)` spanning the plane with unit normal `normal`, with `û × ŵ` along
/// the normal: `û = normalize(n × e)` for the world axis `e` least aligned with `n`, `ŵ = û × n`
/// reversed so that the triple is right-handed.
#[must_use]
pub fn plane_axes(normal: DVec3) -> (DVec3, DVec3) {
    let n = normal.try_normalize().unwrap_or(DVec3::Y);
    let a = n.abs();
    let e = if a.x <= a.y && a.x <= a.z {
        DVec3::X
    } else if a.z <= a.y {
        DVec3::Z
    } else {
        DVec3::Y
    };
    let u = e.cross(n).normalize();
    let w = n.cross(u);
    (u, w)
}

/// A point projected onto the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    /// Pixels from the left edge.
    pub x: f32,
    /// Pixels from the top edge.
    pub y: f32,
    /// Depth `z_c` along the view direction (m).
    pub depth: f64,
}

/// A camera bound to an image size: projects world points to pixels (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Eye position (m).
    pub eye: DVec3,
    /// Right, up and forward unit vectors.
    pub right: DVec3,
    /// Up unit vector.
    pub up: DVec3,
    /// Forward unit vector (into the image).
    pub forward: DVec3,
    /// Image width (px).
    pub width: f64,
    /// Image height (px).
    pub height: f64,
    /// Focal length `s` (px) for perspective, or the scale (px/m) for orthographic.
    pub scale: f64,
    /// True for perspective, false for orthographic.
    pub perspective: bool,
    /// Depth below which points are behind the eye (m).
    pub near: f64,
}

impl View {
    /// The view of `camera` on a `width × height` image.
    #[must_use]
    pub fn new(camera: &Camera, width: u32, height: u32) -> View {
        let (right, up, forward) = camera.basis();
        let h = f64::from(height);
        let (scale, perspective) = match camera.projection {
            Projection::Perspective { fov_y } => (0.5 * h / (0.5 * fov_y).tan(), true),
            Projection::Orthographic { height } => (h / height, false),
        };
        View {
            eye: camera.eye(),
            right,
            up,
            forward,
            width: f64::from(width),
            height: h,
            scale,
            perspective,
            near: if perspective {
                1e-3 * camera.distance
            } else {
                f64::NEG_INFINITY
            },
        }
    }

    /// Camera coordinates `(x_c, y_c, z_c)` of world point `p` (m).
    #[must_use]
    pub fn to_camera(&self, p: DVec3) -> DVec3 {
        let d = p - self.eye;
        DVec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.forward))
    }

    /// Depth `z_c` of `p` (m).
    #[must_use]
    pub fn depth(&self, p: DVec3) -> f64 {
        (p - self.eye).dot(self.forward)
    }

    /// The pixel of camera-space point `c`, or `None` behind the near distance.
    #[must_use]
    pub fn project_camera(&self, c: DVec3) -> Option<Projected> {
        if c.z < self.near || !c.is_finite() {
            return None;
        }
        let k = if self.perspective {
            self.scale / c.z
        } else {
            self.scale
        };
        Some(Projected {
            x: (0.5 * self.width + k * c.x) as f32,
            y: (0.5 * self.height - k * c.y) as f32,
            depth: c.z,
        })
    }

    /// The pixel of world point `p`, or `None` when it is behind the eye.
    #[must_use]
    pub fn project(&self, p: DVec3) -> Option<Projected> {
        self.project_camera(self.to_camera(p))
    }

    /// The world point (m) at pixel `(x, y)` and depth `depth` (m) along the view direction: the
    /// inverse of [`View::project`] for points in front of the eye.
    #[must_use]
    pub fn unproject(&self, x: f64, y: f64, depth: f64) -> DVec3 {
        let k = if self.perspective {
            depth / self.scale
        } else {
            1.0 / self.scale
        };
        let xc = (x - 0.5 * self.width) * k;
        let yc = (0.5 * self.height - y) * k;
        self.eye + xc * self.right + yc * self.up + depth * self.forward
    }

    /// Pixels per metre at depth `depth` (m): `s / depth` for perspective, `s` for orthographic.
    #[must_use]
    pub fn pixels_per_metre(&self, depth: f64) -> f64 {
        if self.perspective {
            self.scale / depth.max(self.near)
        } else {
            self.scale
        }
    }

    /// The part of the segment `a`–`b` (camera coordinates) in front of the near distance, or
    /// `None` when all of it is behind.
    #[must_use]
    pub fn clip_segment(&self, a: DVec3, b: DVec3) -> Option<(DVec3, DVec3)> {
        let near = self.near;
        match (a.z >= near, b.z >= near) {
            (true, true) => Some((a, b)),
            (false, false) => None,
            (true, false) => Some((a, a + (b - a) * ((near - a.z) / (b.z - a.z)))),
            (false, true) => Some((a + (b - a) * ((near - a.z) / (b.z - a.z)), b)),
        }
    }

    /// The polygon `points` (camera coordinates) clipped to the half-space in front of the near
    /// distance (Sutherland–Hodgman, one plane).
    #[must_use]
    pub fn clip_polygon(&self, points: &[DVec3]) -> Vec<DVec3> {
        let near = self.near;
        if points.iter().all(|p| p.z >= near) {
            return points.to_vec();
        }
        let mut out = Vec::with_capacity(points.len() + 2);
        for (i, &a) in points.iter().enumerate() {
            let b = points[(i + 1) % points.len()];
            if a.z >= near {
                out.push(a);
            }
            if (a.z >= near) != (b.z >= near) {
                out.push(a + (b - a) * ((near - a.z) / (b.z - a.z)));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_projects_to_the_centre() {
        let cam = Camera {
            target: DVec3::new(1.0, 2.0, 3.0),
            ..Camera::default()
        };
        let v = View::new(&cam, 640, 480);
        let p = v.project(cam.target).expect("in front");
        assert!((p.x - 320.0).abs() < 1e-3 && (p.y - 240.0).abs() < 1e-3);
        assert!((p.depth - cam.distance).abs() < 1e-9);
    }

    #[test]
    fn up_is_up_and_right_is_right() {
        let cam = Camera::default();
        let v = View::new(&cam, 100, 100);
        let above = v.project(DVec3::Y).expect("in front");
        assert!(above.y < 50.0);
        let (right, _, _) = cam.basis();
        let r = v.project(right).expect("in front");
        assert!(r.x > 50.0);
    }

    #[test]
    fn fit_keeps_every_corner_inside() {
        let mut b = Aabb::EMPTY;
        b.add(DVec3::new(-3.0, 0.0, -1.0));
        b.add(DVec3::new(5.0, 2.0, 4.0));
        for projection in [
            Projection::default(),
            Projection::Orthographic { height: 1.0 },
        ] {
            for aspect in [0.5, 1.0, 2.0] {
                let cam = Camera {
                    projection,
                    ..Camera::default()
                }
                .fit(&b, aspect);
                let (w, h) = ((200.0 * aspect) as u32, 200);
                let v = View::new(&cam, w, h);
                let mut touches = false;
                for c in b.corners() {
                    let p = v.project(c).expect("in front");
                    assert!(p.x >= 0.0 && p.x <= w as f32 && p.y >= 0.0 && p.y <= h as f32);
                    touches |= p.x < 0.1 * w as f32
                        || p.x > 0.9 * w as f32
                        || p.y < 0.1 * h as f32
                        || p.y > 0.9 * h as f32;
                }
                assert!(touches, "the box fills the image");
            }
        }
    }

    #[test]
    fn clipping_keeps_the_front_part() {
        let v = View::new(&Camera::default(), 10, 10);
        let (a, b) = v
            .clip_segment(DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.0, 0.0, 1.0))
            .expect("half in front");
        assert!(a.z >= v.near - 1e-12 && b.z == 1.0);
        let poly = v.clip_polygon(&[
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(-1.0, 0.0, 1.0),
        ]);
        assert_eq!(poly.len(), 4);
        assert!(poly.iter().all(|p| p.z >= v.near - 1e-12));
    }
}
