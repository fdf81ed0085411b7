//! The box around a scene's content that the default camera frames and the floors surround:
//! particles, spheres and colliders, with room for a pinned body to swing.

use glam::DVec3;

use super::plane_axes;
use crate::physics::bowl::Rim;
use crate::physics::collide::Collider;
use crate::scene::Scene;

/// An axis-aligned box (m); empty until a point is added.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest x, y, z.
    pub min: DVec3,
    /// Largest x, y, z.
    pub max: DVec3,
}

impl Default for Aabb {
    fn default() -> Aabb {
        Aabb::EMPTY
    }
}

impl Aabb {
    /// The box that contains nothing.
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// True when no point has been added.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    /// Grows the box to contain `p` (non-finite points are ignored).
    pub fn add(&mut self, p: DVec3) {
        if p.is_finite() {
            self.min = self.min.min(p);
            self.max = self.max.max(p);
        }
    }

    /// Grows the box to contain the ball of `radius` (m) around `center`.
    pub fn add_ball(&mut self, center: DVec3, radius: f64) {
        self.add(center - DVec3::splat(radius));
        self.add(center + DVec3::splat(radius));
    }

    /// Centre of the box (m).
    #[must_use]
    pub fn centre(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    /// Edge lengths (m); zero for an empty box.
    #[must_use]
    pub fn size(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// The eight corners.
    #[must_use]
    pub fn corners(&self) -> [DVec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            DVec3::new(a.x, a.y, a.z),
            DVec3::new(b.x, a.y, a.z),
            DVec3::new(a.x, b.y, a.z),
            DVec3::new(b.x, b.y, a.z),
            DVec3::new(a.x, a.y, b.z),
            DVec3::new(b.x, a.y, b.z),
            DVec3::new(a.x, b.y, b.z),
            DVec3::new(b.x, b.y, b.z),
        ]
    }
}

/// The region a scene's default camera frames (m):
///
/// - every particle, every dynamic sphere, static spheres and bowls (the bowl's rim circle and
///   its bottom), the hole of a floor with a hole;
/// - where the content lands on every plane collider (an infinite plane has no box of its
///   own): the corners of the box so far dropped along gravity onto the plane, and on a slope
///   also one content size further downhill;
/// - room to swing for a body whose particles lie on one line and hang from a pinned particle
///   (a rope): every point within the body's size of a pinned particle, in the plane of the line
///   and gravity, below the pin.
#[must_use]
pub fn scene_bounds(scene: &Scene) -> Aabb {
    let mut b = Aabb::EMPTY;
    for body in &scene.bodies {
        let mut own = Aabb::EMPTY;
        for &p in &body.state.x {
            own.add(p);
        }
        b.add(own.min);
        b.add(own.max);
        swing_room(&mut b, body, &own);
        for s in &body.state.spheres {
            b.add_ball(s.center, s.radius);
        }
        for c in &body.model.colliders {
            match *c {
                Collider::Sphere { center, radius } => b.add_ball(center, radius),
                Collider::Bowl {
                    center,
                    radius,
                    rim_height,
                } => {
                    let bowl_rim = Rim::of(center, radius, rim_height);
                    let (rim, a) = (bowl_rim.height, bowl_rim.radius());
                    b.add(DVec3::new(center.x - a, rim, center.z - a));
                    b.add(DVec3::new(center.x + a, rim, center.z + a));
                    b.add(center - DVec3::new(0.0, radius, 0.0));
                }
                Collider::HolePlane {
                    hole_center,
                    hole_radius,
                    normal,
                    ..
                } => {
                    let (u, w) = plane_axes(normal);
                    for (su, sw) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                        b.add(hole_center + hole_radius * (su * u + sw * w));
                    }
                }
                Collider::Plane { .. } => {}
            }
        }
    }
    if b.is_empty() {
        return b;
    }
    // Where the content lands on each plane: the corners dropped along gravity (along the
    // normal when gravity is parallel to the plane or zero), and on a slope one content size
    // further downhill.
    let corners = b.corners();
    let size = b.size().max_element();
    for body in &scene.bodies {
        let down = body.model.gravity.normalize_or_zero();
        for c in &body.model.colliders {
            if let Collider::Plane { point, normal } | Collider::HolePlane { point, normal, .. } =
                *c
            {
                let along = down.dot(normal);
                let (dir, rate) = if along < -1e-6 {
                    (down, along)
                } else {
                    (-normal, -1.0)
                };
                let downhill = (down - along * normal).normalize_or_zero();
                for p in corners {
                    // p + s dir on the plane: (p + s dir - point)·n = 0.
                    let landing = p + (-(p - point).dot(normal) / rate) * dir;
                    b.add(landing);
                    b.add(landing + size * downhill);
                }
            }
        }
    }
    b
}

/// Adds room to hang or swing for a body with pinned particles under gravity (see
/// [`scene_bounds`]): a rope (particles on one line) gets every point within its length of a
/// pin, below the pin, in the plane of the line and gravity; any other body (a cloth) gets room
/// to sag by a third of its size below its lowest pin.
fn swing_room(b: &mut Aabb, body: &crate::scene::Body, own: &Aabb) {
    let g = body.model.gravity;
    let pins: Vec<DVec3> = body
        .state
        .x
        .iter()
        .enumerate()
        .filter(|&(i, _)| i < body.model.particle_count() && body.model.is_pinned(i))
        .map(|(_, &p)| p)
        .collect();
    if g == DVec3::ZERO || body.state.x.len() < 2 || pins.is_empty() {
        return;
    }
    let size = own.size();
    let reach = size.max_element();
    let down = g.normalize();
    let along: Vec<usize> = (0..3).filter(|&k| size[k] > 0.0).collect();
    if let [axis] = along.as_slice() {
        let axis = DVec3::AXES[*axis];
        for p in pins {
            b.add(p + reach * down);
            b.add(p + reach * axis);
            b.add(p - reach * axis);
        }
    } else {
        for p in pins {
            b.add(p + reach / 3.0 * down);
        }
    }
}
