//! Terrain that hides: planes cut shapes in two, spheres order the shapes around them.
//!
//! # Theory
//!
//! **Planes.** A plane the camera is above hides everything below it except what is seen through
//! its hole. The painter's algorithm gets this exactly when nothing *straddles* the plane: first
//! what lies below, then the plane (opaque, the hole cut out), then what lies above. A ray from an
//! eye on the free side crosses the free half-space before the plane, so no point above the plane
//! can be behind a point below it. Shapes that cross the plane (the jelly sinking into the hole,
//! a spring through the floor) are therefore cut along it, each piece drawn in its own layer:
//!
//! ```text
//! d_i = (x_i - q)·n̂                                signed height of corner i above the plane
//! x = x_i + (x_j - x_i) · d_i / (d_i - d_j)        where an edge with d_i d_j < 0 meets it
//! ```
//! where
//! - `q` (m): a point of the plane; `n̂`: its unit normal into the free side
//! - `x_i`, `x_j` (m): the corners of one edge of the polygon
//!
//! (Sutherland & Hodgman 1974: clipping a polygon by one plane at a time.)
//!
//! **Spheres.** A sphere is one disc drawn at the depth of its centre `z_c`. A shape that the
//! sphere hides must come before that disc, one in front of it after, whatever its own depth
//! says. A point `p` is hidden when the ray from the eye meets the sphere before it:
//!
//! ```text
//! o + t d,  t ∈ [0, 1]            the ray from the eye o to p, d = p - o
//! t_0 = t_c - √(r² - ρ²) / |d|    where it enters the sphere
//! hidden  ⇔  ρ < r  and  t_0 |d| < |d| - τ
//! ```
//! where
//! - `t_c = (c - o)·d / |d|²`: the ray's closest approach to the centre `c` (m)
//! - `ρ` (m): the distance of the ray from `c` there; `r` (m): the radius
//! - `τ = r/20` (m): a tolerance, so that a point lying on the visible surface (a cloth resting
//!   on the ball) counts as in front
//!
//! A hidden shape's sort depth is raised just behind `z_c`, one in front of the ball (its ray
//! within `1.1 r` of the centre) lowered just before it.
//!
//! Reference: I. E. Sutherland, G. W. Hodgman, "Reentrant polygon clipping", CACM 17(1), 1974.

use glam::DVec3;

use super::camera::View;

/// How far a point may be below a plane and still count as on it (m).
const ON_PLANE: f64 = 1e-9;

/// A ball that orders the shapes around it.
#[derive(Clone, Copy, Debug)]
struct Ball {
    center: DVec3,
    radius: f64,
    /// Camera depth of the centre: the sort depth of the ball's disc (m).
    depth: f64,
}

/// The planes and balls of one frame that hide what is below or behind them.
#[derive(Clone, Debug)]
pub(super) struct Occluders {
    /// Planes the camera is above: `(point, unit normal)`.
    planes: Vec<(DVec3, DVec3)>,
    balls: Vec<Ball>,
    eye: DVec3,
    forward: DVec3,
    perspective: bool,
}

impl Occluders {
    /// The occluders of `view`: the planes `(point, normal)` the eye is above and the balls
    /// `(centre, radius)`.
    pub(super) fn new(
        view: &View,
        planes: impl IntoIterator<Item = (DVec3, DVec3)>,
        balls: impl IntoIterator<Item = (DVec3, f64)>,
    ) -> Occluders {
        Occluders {
            planes: planes
                .into_iter()
                .filter(|&(q, n)| (view.eye - q).dot(n) > 0.0)
                .collect(),
            balls: balls
                .into_iter()
                .filter(|&(_, r)| r > 0.0 && r.is_finite())
                .map(|(center, radius)| Ball {
                    center,
                    radius,
                    depth: view.depth(center),
                })
                .collect(),
            eye: view.eye,
            forward: view.forward,
            perspective: view.perspective,
        }
    }

    /// 0 when `p` is below one of the planes, 1 otherwise.
    pub(super) fn layer(&self, p: DVec3) -> u8 {
        u8::from(!self.planes.iter().any(|&(q, n)| (p - q).dot(n) < -ON_PLANE))
    }

    /// The sort depth of a shape at `p` whose own depth is `depth`, moved behind or in front
    /// of each ball as the ball hides it or not (module docs).
    pub(super) fn key(&self, p: DVec3, depth: f64) -> f64 {
        let mut key = depth;
        for b in &self.balls {
            let (o, d) = if self.perspective {
                (self.eye, p - self.eye)
            } else {
                let back = (p - self.eye).dot(self.forward).abs() + (p - b.center).length();
                let back = back + 4.0 * b.radius;
                (p - back * self.forward, back * self.forward)
            };
            let len = d.length();
            if len <= 0.0 || !len.is_finite() {
                continue;
            }
            let u = d / len;
            let along = (b.center - o).dot(u);
            let rho2 = (b.center - o - along * u).length_squared();
            let r = b.radius;
            let hair = 1e-7 * b.depth.abs().max(1.0);
            if rho2 < r * r {
                let entry = along - (r * r - rho2).sqrt();
                if entry < len - 0.05 * r {
                    key = key.max(b.depth + hair);
                } else {
                    key = key.min(b.depth - hair);
                }
            } else if rho2 < 1.21 * r * r {
                // Beside the silhouette: a shape here may overlap the disc's edge.
                if along < len {
                    key = key.max(b.depth + hair);
                } else {
                    key = key.min(b.depth - hair);
                }
            }
        }
        key
    }

    /// Calls `out(layer, piece)` for the pieces of the convex polygon `poly` (world, m) cut by
    /// the planes: below one of them layer 0, above all of them layer 1.
    pub(super) fn split_polygon(&self, poly: &[DVec3], mut out: impl FnMut(u8, &[DVec3])) {
        // Most shapes are wholly on one side of every plane: no copy then.
        let mut whole = Some(1u8);
        for &(q, n) in &self.planes {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for &p in poly {
                let h = (p - q).dot(n);
                lo = lo.min(h);
                hi = hi.max(h);
            }
            if lo >= -ON_PLANE {
                continue;
            }
            if hi <= ON_PLANE {
                whole = Some(0);
                break;
            }
            whole = None;
        }
        if let Some(layer) = whole {
            out(layer, poly);
            return;
        }
        let mut rest: Vec<DVec3> = poly.to_vec();
        for &(q, n) in &self.planes {
            let d: Vec<f64> = rest.iter().map(|&p| (p - q).dot(n)).collect();
            if d.iter().all(|&h| h >= -ON_PLANE) {
                continue;
            }
            if d.iter().all(|&h| h <= ON_PLANE) {
                out(0, &rest);
                return;
            }
            let (mut below, mut above) = (Vec::new(), Vec::new());
            for i in 0..rest.len() {
                let j = (i + 1) % rest.len();
                let (a, b) = (rest[i], rest[j]);
                let (da, db) = (d[i], d[j]);
                if da >= 0.0 {
                    above.push(a);
                }
                if da <= 0.0 {
                    below.push(a);
                }
                if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
                    let x = a + (b - a) * (da / (da - db));
                    above.push(x);
                    below.push(x);
                }
            }
            if below.len() >= 3 {
                out(0, &below);
            }
            if above.len() < 3 {
                return;
            }
            rest = above;
        }
        out(1, &rest);
    }

    /// Calls `out(layer, a, b)` for the pieces of the segment `a`–`b` (world, m) cut by the
    /// planes, as [`Occluders::split_polygon`] does.
    pub(super) fn split_segment(&self, a: DVec3, b: DVec3, mut out: impl FnMut(u8, DVec3, DVec3)) {
        let (mut a, mut b) = (a, b);
        for &(q, n) in &self.planes {
            let (da, db) = ((a - q).dot(n), (b - q).dot(n));
            if da >= -ON_PLANE && db >= -ON_PLANE {
                continue;
            }
            if da <= ON_PLANE && db <= ON_PLANE {
                out(0, a, b);
                return;
            }
            let x = a + (b - a) * (da / (da - db));
            if da < 0.0 {
                out(0, a, x);
                a = x;
            } else {
                out(0, x, b);
                b = x;
            }
        }
        out(1, a, b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::camera::Camera;

    fn floor_view() -> View {
        let camera = Camera {
            target: DVec3::ZERO,
            ..Camera::default()
        };
        View::new(&camera, 320, 240)
    }

    fn area(poly: &[DVec3]) -> f64 {
        let mut s = DVec3::ZERO;
        for i in 0..poly.len() {
            s += poly[i].cross(poly[(i + 1) % poly.len()]);
        }
        0.5 * s.length()
    }

    #[test]
    fn a_triangle_through_the_floor_is_cut_into_pieces_of_the_same_total_area() {
        let occ = Occluders::new(&floor_view(), [(DVec3::ZERO, DVec3::Y)], []);
        // A vertical right triangle, legs 2 m, one third of its height below y = 0.
        let tri = [
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(3.0, -1.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ];
        let mut pieces = Vec::new();
        occ.split_polygon(&tri, |layer, p| pieces.push((layer, p.to_vec())));
        assert_eq!(pieces.len(), 2, "{pieces:?}");
        let below: f64 = pieces.iter().filter(|p| p.0 == 0).map(|p| area(&p.1)).sum();
        let above: f64 = pieces.iter().filter(|p| p.0 == 1).map(|p| area(&p.1)).sum();
        // Above y = 0 a similar triangle with legs 2 m: area 2; the whole is 4.5.
        assert!((above - 2.0).abs() < 1e-12, "{above}");
        assert!((below - 2.5).abs() < 1e-12, "{below}");
        for (layer, p) in &pieces {
            for x in p {
                assert!(if *layer == 0 {
                    x.y <= 1e-12
                } else {
                    x.y >= -1e-12
                });
            }
        }
    }

    #[test]
    fn a_segment_through_the_floor_is_cut_where_it_crosses() {
        let occ = Occluders::new(&floor_view(), [(DVec3::ZERO, DVec3::Y)], []);
        let mut pieces = Vec::new();
        occ.split_segment(
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(4.0, 3.0, 0.0),
            |l, a, b| {
                pieces.push((l, a, b));
            },
        );
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[0].0, 0);
        assert!((pieces[0].2 - DVec3::new(1.0, 0.0, 0.0)).length() < 1e-12);
        assert_eq!(pieces[1].0, 1);
        assert!((pieces[1].1 - DVec3::new(1.0, 0.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn a_plane_seen_from_below_hides_nothing() {
        let view = floor_view();
        // The camera looks down on the origin: a plane above the eye, normal up, is seen from
        // below and cuts nothing.
        let high = view.eye + DVec3::Y;
        let occ = Occluders::new(&view, [(high, DVec3::Y)], []);
        assert_eq!(occ.layer(DVec3::ZERO), 1);
        let mut n = 0;
        occ.split_segment(DVec3::ZERO, 2.0 * high, |l, _, _| {
            assert_eq!(l, 1);
            n += 1;
        });
        assert_eq!(n, 1);
    }

    #[test]
    fn a_point_behind_a_ball_sorts_behind_it_and_one_in_front_before_it() {
        let view = floor_view();
        let c = DVec3::ZERO;
        let occ = Occluders::new(&view, [], [(c, 1.0)]);
        let zc = view.depth(c);
        let towards_eye = (view.eye - c).normalize();
        // Just behind the far side, in line with the eye: hidden; its own depth is larger
        // anyway. Inside the ball near the front: hidden although nearer than the centre.
        let inside = c + 0.5 * towards_eye;
        assert!(view.depth(inside) < zc);
        assert!(occ.key(inside, view.depth(inside)) > zc);
        // On the visible surface: in front, whatever depth it is given.
        let front = c + 1.0 * towards_eye;
        assert!(occ.key(front, zc + 5.0) < zc);
        // Far off to the side: untouched.
        let side = c + 10.0 * view.right;
        assert_eq!(occ.key(side, 123.0), 123.0);
    }
}
