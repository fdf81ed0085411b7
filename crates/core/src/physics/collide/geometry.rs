//! Collider geometry: signed distance and normal of each static collider, and the broad phase
//! bounds (module docs of `collide`, "Geometry").

use glam::DVec3;

/// Relative margin on a bowl's rim circle (`ρ² ≤ a² (1 + margin)`): points on the circle up to
/// rounding still belong to the bowl (see [`Collider::contact`]).
pub(crate) const RIM_MARGIN: f64 = 1e-9;

/// A static obstacle. Normals are unit vectors: build colliders with the constructors
/// ([`Collider::plane`] etc.) or pass them through
/// [`Model::with_colliders`](crate::physics::Model::with_colliders), which normalises.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Collider {
    /// The half-space `(x - point)·normal ≥ 0`: particles stay on the side the normal points to.
    /// A tilted normal gives the course's tilted plane. `point` in m.
    Plane {
        /// A point of the plane (m).
        point: DVec3,
        /// Unit normal pointing into the free side.
        normal: DVec3,
    },
    /// A solid ball: particles stay outside `|x - center| ≥ radius` (m).
    Sphere {
        /// Centre (m).
        center: DVec3,
        /// Radius (m).
        radius: f64,
    },
    /// A bowl: the inside of a sphere below a cut at height `rim_height` (m), with a vertical
    /// axis (+y up). Particles that are below the rim and within the rim circle
    /// (horizontal distance from the axis `≤ √(radius² - (center.y - rim_height)²)`) stay inside
    /// the sphere; above the rim or outside that circle the bowl is not there (a particle can
    /// fly out over the rim and fall past the bowl). The 2021 bowl is cut at `center.y` (a
    /// hemisphere), the 2023 bowl at `0` (where it meets the floor's hole). A cut above
    /// `center.y` is treated as `center.y`. Nothing is solid around the bowl: give it a floor
    /// ([`Collider::HolePlane`]) to stop what leaves through the wall just below the rim.
    Bowl {
        /// Centre of the sphere (m).
        center: DVec3,
        /// Radius of the sphere (m).
        radius: f64,
        /// Height of the rim, the cut plane `y = rim_height` (m).
        rim_height: f64,
    },
    /// A floor with a round hole: the half-space below the plane through `point` is solid except
    /// for a vertical shaft of radius `hole_radius` around `hole_center` (a point of the plane).
    /// Over the hole particles fall through; under the floor they stay in the shaft; elsewhere it
    /// is [`Collider::Plane`]. Distances "from the hole" are measured within the plane.
    HolePlane {
        /// A point of the plane (m).
        point: DVec3,
        /// Unit normal pointing into the free side (up).
        normal: DVec3,
        /// Centre of the hole, on the plane (m).
        hole_center: DVec3,
        /// Radius of the hole (m).
        hole_radius: f64,
    },
}

/// Where a point is with respect to a collider's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Signed distance `φ` to the surface (m): positive on the free side, negative inside.
    pub phi: f64,
    /// Unit normal `N` of the nearest surface, pointing into the free side.
    pub normal: DVec3,
}

impl Collider {
    /// The half-space on the side `normal` points to (normalised; a zero normal gives a plane
    /// that touches nothing).
    #[must_use]
    pub fn plane(point: DVec3, normal: DVec3) -> Collider {
        Collider::Plane {
            point,
            normal: normal.normalize_or_zero(),
        }
    }

    /// A solid ball of `radius` (m) at `center` (m).
    #[must_use]
    pub fn sphere(center: DVec3, radius: f64) -> Collider {
        Collider::Sphere { center, radius }
    }

    /// The inside of the sphere (`center`, `radius`, m) below `rim_height` (m).
    #[must_use]
    pub fn bowl(center: DVec3, radius: f64, rim_height: f64) -> Collider {
        Collider::Bowl {
            center,
            radius,
            rim_height,
        }
    }

    /// A floor through `point` with unit `normal` (normalised) and a round hole.
    #[must_use]
    pub fn hole_plane(
        point: DVec3,
        normal: DVec3,
        hole_center: DVec3,
        hole_radius: f64,
    ) -> Collider {
        Collider::HolePlane {
            point,
            normal: normal.normalize_or_zero(),
            hole_center,
            hole_radius,
        }
    }

    /// 2021 ground: the plane `y = -1`, normal `+y`.
    #[must_use]
    pub fn course_2021_plane() -> Collider {
        Collider::plane(DVec3::new(0.0, -1.0, 0.0), DVec3::Y)
    }

    /// 2021 obstacle: a sphere of radius 3 at `(0, -1, 0)`.
    #[must_use]
    pub fn course_2021_sphere() -> Collider {
        Collider::sphere(DVec3::new(0.0, -1.0, 0.0), 3.0)
    }

    /// 2021 bowl: the lower half of the sphere of radius 7 at `(2, 7, 1)` (rim at `y = 7`).
    #[must_use]
    pub fn course_2021_bowl() -> Collider {
        Collider::bowl(DVec3::new(2.0, 7.0, 1.0), 7.0, 7.0)
    }

    /// 2021 tilted plane: through the origin with normal `(1, 1, 0)/√2` (a 45° slope).
    #[must_use]
    pub fn course_2021_tilted_plane() -> Collider {
        Collider::plane(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0))
    }

    /// 2023 terrain: the floor `y = 0` with a hole of radius `9/√2 ≈ 6.364` at `(2, 0, 1)`, and
    /// under it the bowl of radius 9 centred at `(2, 9/√2, 1)` cut at `y = 0`.
    ///
    /// ```text
    /// a = √(r² - c_y²) = √(81 - 81/2) = 9/√2      the sphere meets y = 0 at the hole's edge
    /// ```
    /// where `r = 9` m is the bowl's radius and `c_y = 9/√2` m its centre's height.
    #[must_use]
    pub fn course_2023_terrain() -> Vec<Collider> {
        let a = 9.0 / 2f64.sqrt();
        vec![
            Collider::hole_plane(DVec3::ZERO, DVec3::Y, DVec3::new(2.0, 0.0, 1.0), a),
            Collider::bowl(DVec3::new(2.0, a, 1.0), 9.0, 0.0),
        ]
    }

    /// The same collider with its normal scaled to unit length (a zero normal stays zero, and
    /// the collider then touches nothing).
    #[must_use]
    pub fn normalized(self) -> Collider {
        match self {
            Collider::Plane { point, normal } => Collider::plane(point, normal),
            Collider::HolePlane {
                point,
                normal,
                hole_center,
                hole_radius,
            } => Collider::hole_plane(point, normal, hole_center, hole_radius),
            other => other,
        }
    }

    /// Signed distance and normal at `x` (m), or `None` where the collider does not act (above
    /// a bowl's rim or outside its rim circle; over a floor's hole).
    ///
    /// ```text
    /// plane:   φ = (x - p)·n,                N = n
    /// sphere:  φ = |x - c| - r,              N = (x - c)/|x - c|
    /// bowl:    φ = r - |x - c|,              N = (c - x)/|x - c|       (y ≤ rim, ρ ≤ a)
    /// floor with hole, h = (x - p)·n height, ρ = distance from the hole's axis:
    ///   ρ ≥ R, h ≥ 0:   φ = h,      N = n                 over the floor
    ///   ρ < R, h ≥ 0:   none                               over the hole
    ///   ρ < R, h < 0:   φ = R - ρ,  N = towards the axis    in the shaft
    ///   ρ ≥ R, h < 0:   in the solid: φ = -min(-h, ρ - R), through the nearer face
    /// ```
    /// where `p`, `c` are the collider's point and centre (m), `n` its unit normal, `r`, `R` the
    /// radii (m) and `a = √(r² - (c_y - rim)²)` the bowl's rim radius (m). At a sphere's centre
    /// the normal is taken as `+y`.
    #[must_use]
    pub fn contact(&self, x: DVec3) -> Option<Contact> {
        match *self {
            Collider::Plane { point, normal } => Some(Contact {
                phi: (x - point).dot(normal),
                normal,
            }),
            Collider::Sphere { center, radius } => {
                let (distance, outward) = distance_and_direction(x - center);
                Some(Contact {
                    phi: distance - radius,
                    normal: outward,
                })
            }
            Collider::Bowl {
                center,
                radius,
                rim_height,
            } => {
                // At most a hemisphere: the rim circle is the widest part of the bowl.
                let bowl_rim = crate::physics::bowl::Rim::of(center, radius, rim_height);
                let (rim, a2) = (bowl_rim.height, bowl_rim.radius_squared);
                if x.y > rim {
                    return None;
                }
                // ρ² = horizontal distance² from the axis; a² = r² - (c_y - rim)².
                let rho2 = (x.x - center.x).powi(2) + (x.z - center.z).powi(2);
                // A floor's shaft of radius a (the 2023 terrain) projects a particle that
                // crossed the floor beside the hole onto ρ = a just below the rim, where the
                // bowl's wall has already turned inwards; ρ² then exceeds a² by rounding only.
                // The margin keeps such a particle the bowl's, so it goes back into the bowl.
                if rho2 > a2 * (1.0 + RIM_MARGIN) {
                    return None;
                }
                let (distance, outward) = distance_and_direction(x - center);
                Some(Contact {
                    phi: radius - distance,
                    normal: -outward,
                })
            }
            Collider::HolePlane {
                point,
                normal,
                hole_center,
                hole_radius,
            } => {
                let height = (x - point).dot(normal);
                // Offset from the hole's axis within the plane: q - (q·n) n.
                let q = x - hole_center;
                let (rho, outward) = distance_and_direction(q - q.dot(normal) * normal);
                let over_floor = rho >= hole_radius;
                let floor = Contact {
                    phi: height,
                    normal,
                };
                let shaft = Contact {
                    phi: hole_radius - rho,
                    normal: -outward,
                };
                match (height >= 0.0, over_floor) {
                    (true, true) => Some(floor),
                    (true, false) => None,
                    (false, false) => Some(shaft),
                    // In the solid: leave through the nearer face (depth -h below the floor,
                    // ρ - R beside the shaft).
                    (false, true) => Some(if -height <= rho - hole_radius {
                        floor
                    } else {
                        shaft
                    }),
                }
            }
        }
    }
}

/// A collider as the broad phase sees it, for contacts closer than `epsilon` (m): its
/// geometry and the bounds of the tests without square roots that [`Collider::may_touch`] (one
/// particle) and the stencil's chunk test (eight at a time) both make, each bound widened by a
/// relative margin of 10⁻⁹ against rounding, so that no particle the exact
/// [`Collider::contact`] would put within `epsilon` is left out. Points in m, `normal` a unit
/// vector.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Broad {
    /// May touch when the height `φ = (x - point)·normal < phi_max` (m).
    Plane {
        point: DVec3,
        normal: DVec3,
        phi_max: f64,
    },
    /// `|x - c| - r < ε  ⇔  |x - c|² < (r + ε)²`: may touch when `|x - center|² < d2_max` (m²).
    Sphere { center: DVec3, d2_max: f64 },
    /// `r - |x - c| < ε  ⇔  |x - c|² > (r - ε)²`, and not above the rim (the exact test's first
    /// question, asked with the same comparison; the rim circle is left to it): may touch when
    /// `|x - center|² ≥ d2_min` (m²) and not `y > rim` (m). A body falling towards the bowl from
    /// above its rim is outside the sphere, but no particle of it is a candidate until it is
    /// down in the bowl.
    Bowl {
        center: DVec3,
        d2_min: f64,
        rim: f64,
    },
    /// Every contact has the height `h = (x - point)·normal < h_max`; below the floor
    /// (`h < h_floor`) only the shaft's wall band `ρ > R - ε` and the solid touch: `ρ² ≥
    /// rho2_min` (m²), `ρ` the distance from the hole's axis through `hole_center`.
    HolePlane {
        point: DVec3,
        normal: DVec3,
        hole_center: DVec3,
        h_max: f64,
        h_floor: f64,
        rho2_min: f64,
    },
}

impl Collider {
    /// The collider as the broad phase sees it for contacts closer than `epsilon` (m).
    #[must_use]
    pub(crate) fn broad(&self, epsilon: f64) -> Broad {
        const MARGIN: f64 = 1e-9;
        match *self {
            Collider::Plane { point, normal } => {
                let scale = point.abs().max_element() + 1.0;
                Broad::Plane {
                    point,
                    normal,
                    phi_max: epsilon + MARGIN * scale,
                }
            }
            Collider::Sphere { center, radius } => {
                let reach = (radius + epsilon).max(0.0);
                Broad::Sphere {
                    center,
                    d2_max: reach * reach * (1.0 + MARGIN) + MARGIN,
                }
            }
            Collider::Bowl {
                center,
                radius,
                rim_height,
            } => {
                let inner = (radius - epsilon).max(0.0);
                Broad::Bowl {
                    center,
                    d2_min: inner * inner * (1.0 - MARGIN),
                    rim: crate::physics::bowl::Rim::of(center, radius, rim_height).height,
                }
            }
            Collider::HolePlane {
                point,
                normal,
                hole_center,
                hole_radius,
            } => {
                let scale = point.abs().max_element() + hole_center.abs().max_element() + 1.0;
                let inner = (hole_radius - epsilon).max(0.0);
                Broad::HolePlane {
                    point,
                    normal,
                    hole_center,
                    h_max: epsilon + MARGIN * scale,
                    h_floor: -MARGIN * scale,
                    rho2_min: inner * inner * (1.0 - MARGIN),
                }
            }
        }
    }

    /// False when `x` (m) is certainly farther than `epsilon` (m) from the collider's surface on
    /// its free side, so that [`Collider::contact`] would give no `φ < epsilon`: the bounds of
    /// [`Collider::broad`] (squared distances, a height). True also for NaN.
    #[must_use]
    pub fn may_touch(&self, x: DVec3, epsilon: f64) -> bool {
        if let Collider::Plane { .. } = self {
            // A plane's φ costs no more than any test (and no bounds are needed).
            return true;
        }
        self.broad(epsilon).may_touch(x)
    }
}

impl Broad {
    /// A plane's bounds: `φ = (x - p)·n` below `φ_max` (m), or NaN.
    #[must_use]
    #[inline]
    pub(crate) fn plane_may_touch(x: DVec3, point: DVec3, normal: DVec3, phi_max: f64) -> bool {
        let phi = (x - point).dot(normal);
        phi < phi_max || phi.is_nan()
    }

    /// A sphere's bounds: `|x - c|²` below `d2_max` (m²), or NaN.
    #[must_use]
    #[inline]
    pub(crate) fn sphere_may_touch(x: DVec3, center: DVec3, d2_max: f64) -> bool {
        let d2 = (x - center).length_squared();
        d2 < d2_max || d2.is_nan()
    }

    /// False when the bounds rule `x` (m) out; true also for NaN (the exact test decides). The
    /// scalar form of the stencil's eight-lane broad phase (`stencil::contacts::may_touch`).
    #[must_use]
    #[inline]
    pub(crate) fn may_touch(&self, x: DVec3) -> bool {
        match *self {
            Broad::Plane {
                point,
                normal,
                phi_max,
            } => Self::plane_may_touch(x, point, normal, phi_max),
            Broad::Sphere { center, d2_max } => Self::sphere_may_touch(x, center, d2_max),
            Broad::Bowl {
                center,
                d2_min,
                rim,
            } => {
                let d2 = (x - center).length_squared();
                (d2 >= d2_min || d2.is_nan()) && (x.y <= rim || x.y.is_nan())
            }
            Broad::HolePlane {
                point,
                normal,
                hole_center,
                h_max,
                h_floor,
                rho2_min,
            } => {
                let h = (x - point).dot(normal);
                if h >= h_max {
                    return false;
                }
                if h >= h_floor {
                    return true;
                }
                let q = x - hole_center;
                let rho2 = (q - q.dot(normal) * normal).length_squared();
                rho2 >= rho2_min || rho2.is_nan()
            }
        }
    }
}

impl Broad {
    /// False when the bounds rule out every point of the box `[lo, hi]` (m): no point of it is
    /// one [`Broad::may_touch`] (or [`Broad::marks`]) lets through, so a whole box of particles
    /// is left out at once. Each test takes the box's corner where the quantity the bounds
    /// compare is most favourable (the smallest height, the largest or smallest distance) and
    /// computes it with the same operations as the point test: a rounded subtraction,
    /// product and sum never decrease when an operand grows (and a square when its operand
    /// grows in size), so that corner's value bounds every point's, rounding included, and
    /// the answer never differs from the points' own. A box with an infinite side (a NaN or
    /// infinite coordinate, `fast::bounds`) is never ruled out.
    ///
    /// ```text
    /// plane:        min_box φ ≥ φ_max                   φ = (x - p)·n, per axis the end
    ///                                                   n_c points away from
    /// sphere:       min_box |x - c|² ≥ d2_max            per axis the end nearest c (c inside: c)
    /// bowl:         lo_y > rim   or   max_box |x - c|² < d2_min      per axis the farther end
    /// floor, hole:  min_box h ≥ h_max   or   (max_box h < h_floor  and  max_box ρ² < ρ²_min)
    /// ```
    /// where `ρ² = |q - (q·n) n|²`, `q = x - hole_center`, is bounded this way only for a
    /// normal along an axis (`±e_k`: then `ρ² = |q|²` without axis `k`, exactly); a tilted
    /// floor's box is ruled out by its height alone.
    #[must_use]
    pub(crate) fn box_may_touch(&self, lo: DVec3, hi: DVec3) -> bool {
        if !(lo.is_finite() && hi.is_finite()) {
            return true;
        }
        // The box's corner where `(x - point)·normal` is smallest, and where it is largest.
        let low_corner = |normal: DVec3| DVec3::select(normal.cmpge(DVec3::ZERO), lo, hi);
        let high_corner = |normal: DVec3| DVec3::select(normal.cmpge(DVec3::ZERO), hi, lo);
        // Per axis the largest |x_c - c_c| over the box.
        let farthest = |center: DVec3| (lo - center).abs().max((hi - center).abs());
        match *self {
            Broad::Plane {
                point,
                normal,
                phi_max,
            } => {
                let phi = (low_corner(normal) - point).dot(normal);
                phi < phi_max || phi.is_nan()
            }
            Broad::Sphere { center, d2_max } => {
                let nearest = hi.min(lo.max(center));
                let d2 = (nearest - center).length_squared();
                d2 < d2_max || d2.is_nan()
            }
            Broad::Bowl {
                center,
                d2_min,
                rim,
            } => {
                let inside = farthest(center).length_squared() < d2_min;
                !(lo.y > rim || inside)
            }
            Broad::HolePlane {
                point,
                normal,
                hole_center,
                h_max,
                h_floor,
                rho2_min,
            } => {
                if (low_corner(normal) - point).dot(normal) >= h_max {
                    return false;
                }
                let Some(axis) = axis_of(normal) else {
                    return true;
                };
                let mut radial = farthest(hole_center);
                radial[axis] = 0.0;
                let in_shaft = (high_corner(normal) - point).dot(normal) < h_floor
                    && radial.length_squared() < rho2_min;
                !in_shaft
            }
        }
    }

    /// The points `xs` (at most 64) that the bounds do not rule out, as bits (bit `k` for
    /// `xs[k]`): [`Broad::may_touch`] of each, with the same arithmetic, eight points at a time
    /// (`fast::marks`), so that a body near a collider costs a few vector operations per eight
    /// particles.
    #[must_use]
    pub(crate) fn marks(&self, xs: &[DVec3]) -> u64 {
        crate::physics::fast::marks::marks(self, xs)
    }
}

/// `k` when `normal` is `±e_k` (one component ±1, the others zero), else `None`.
fn axis_of(normal: DVec3) -> Option<usize> {
    let a = normal.to_array();
    let k = (0..3).find(|&k| a[k].abs() == 1.0)?;
    (0..3).all(|j| j == k || a[j] == 0.0).then_some(k)
}

/// `(|d|, d/|d|)`, with the direction `+y` when `d = 0`.
pub(super) fn distance_and_direction(d: DVec3) -> (f64, DVec3) {
    let length = d.length();
    if length > 0.0 {
        (length, d / length)
    } else {
        (0.0, DVec3::Y)
    }
}

#[cfg(test)]
mod tests {
    use super::super::response::near_any;
    use super::*;

    /// A body above a bowl's rim is outside the bowl's sphere, yet no candidate: the exact test
    /// gives no contact there (the bowl is not there), and the bounds leave it out; below the
    /// rim, the same distance from the centre is a candidate. The 2023 bowl (rim at y = 0,
    /// radius 9 about (2, 9/√2, 1)).
    #[test]
    fn a_body_above_the_bowl_s_rim_is_no_candidate() {
        let bowl = Collider::course_2023_terrain()[1];
        let Collider::Bowl { center, radius, .. } = bowl else {
            unreachable!("the terrain's second collider is its bowl")
        };
        let broads = [bowl.broad(0.01)];
        // A 4 m cube 11 m up, over the rim's edge (the jelly's start), and a point on the rim.
        let mut above: Vec<DVec3> = (0..1000)
            .map(|i| {
                let (a, b, c) = (i % 10, (i / 10) % 10, i / 100);
                DVec3::new(-4.8, 11.0, 0.0) + 4.0 / 9.0 * DVec3::new(a as f64, b as f64, c as f64)
            })
            .collect();
        above.push(DVec3::new(center.x, 1e-300, center.z + 20.0));
        let outside = above.iter().filter(|p| p.distance(center) > radius).count();
        assert!(outside > 100, "{outside} points outside the sphere");
        assert!(above.iter().all(|p| bowl.contact(*p).is_none()));
        assert!(near_any(&broads, &above).iter().all(|&w| w == 0));
        // On the sphere or beyond it, at the rim's height (either zero) and below: candidates.
        let below: Vec<DVec3> = [0.0, -0.0, -1e-300, -0.5]
            .iter()
            .map(|&y| center + (DVec3::new(-4.8, y, 0.0) - center).normalize() * radius)
            .map(|p| DVec3::new(p.x, p.y.min(0.0), p.z))
            .collect();
        assert_eq!(near_any(&broads, &below), vec![0b1111]);
    }
}
