//! Colliders and collision response: planes, spheres, bowls, a plane with a hole, dynamic spheres.
//!
//! # Theory
//!
//! **Geometry.** Every static collider describes, for a point `x`, a signed distance `φ(x)` (m) to
//! its surface, positive on the side where particles may be, and the unit normal `N(x)` pointing
//! into that side ([`Collider::contact`]). A particle is *in contact* when it is closer than the
//! contact band `ε` (m) to the surface or already inside (`φ < ε`); the course uses `ε = 0.01` m.
//!
//! **Contact force** (NYCU Computer Animation HW1 2021–2023, `docs/course.md` §2), added in
//! [`super::forces::forces`] after the springs so that every stage of every integrator sees it
//! ([`contact_forces`]). When a particle is in contact, not moving away (`v·N ≤ 0`) and the
//! accumulated force `f` pushes into the surface (`N·f < 0`):
//!
//! ```text
//! λ    = -N·f                          normal load, > 0
//! f_c  = λ N                           cancels the push: N·(f + f_c) = 0
//! f_T  = f - (N·f) N                   tangential part of the applied force
//! v_T  = v - (v·N) N                   tangential velocity
//! f_f  = -k_f λ v_T/|v_T|              Coulomb friction, unit tangent,   if |v_T| ≥ v_rest
//! f_f  = clamp_{k_f λ}(-f_T - (k_f λ / v_rest) v_T)   stick band,        if |v_T| < v_rest
//! ```
//! where
//! - `f`: force on the particle before contact (N), `v`: its velocity (m/s)
//! - `k_f`: friction coefficient (dimensionless; 0.3 in 2021, 0.2 in 2023)
//! - `v_rest`: speed below which a contact counts as resting (m/s), [`ContactParams::rest_speed`]
//! - `clamp_F(g)`: `g` scaled down to length `F` when longer; any part along `+v_T` is removed
//!
//! The course's friction is the first line. Its unit tangent flips sign every step once the
//! particle has almost stopped, because a force does not know the step `dt` and overshoots
//! `v_T = 0`: a block on a slope steeper than its friction angle allows still creeps. Below
//! `v_rest` the friction therefore becomes *static* (Karnopp 1985): it cancels the tangential
//! force, up to the Coulomb limit `k_f λ`, and damps the small sliding speed left. Neither part
//! ever pushes along `v_T`, so friction only removes energy (`f_f·v_T ≤ 0`), and so does `f_c`
//! (`f_c·v = λ (N·v) ≤ 0`, which is why a particle moving away gets no contact force). Pinned
//! particles are skipped. Only the explicit right-hand side sees contact: the implicit method's
//! Jacobian leaves it out, and XPBD, which does not call the force function, gets contact only
//! from [`resolve`].
//!
//! **Velocity response and projection** after every step ([`resolve`]). For each particle in
//! contact, inside the collider (`φ < 0`) it is first moved onto the surface; then, if it moves
//! into the surface, the normal velocity is reflected with restitution `k_r` (0.8 in the course):
//!
//! ```text
//! Δx   = -φ N                          onto the surface, when φ < 0
//! Δu   = -g·Δx                         potential energy per kg that Δx adds (J/kg)
//! v_N  = v·N,  v_T = v - v_N N
//! s    = √(v_N² - 2 Δu)                normal speed the particle had AT the surface (m/s)
//! v_N' = k_r s   if approaching and s > v_rest      (course: v' = -k_r v_N + v_T)
//! v_N' = 0       if approaching and s ≤ v_rest      resting contact, no bounce
//! v_N' = s       if already moving away
//! v_T' = max(0, 1 - k_f (v_N' - v_N) / |v_T|) v_T   friction of the impact
//! v'   = v_T' + v_N' N
//! ```
//! where `g` is gravity (m/s²). Without penetration `Δu = 0` and `s = |v_N|`: this is the course's
//! `v' = -k_r v_N + v_T`. With penetration, the integrator has let the particle fall `|φ|` below
//! the surface and gain the kinetic energy of that fall; moving it back up without taking that
//! energy away would make every bounce *add* `m |g·N| |φ|` joules. Using the speed at the surface
//! instead, the energy after the response is
//!
//! ```text
//! E' = E - (1 - k_r²) (½ m v_N² - m Δu)  ≤  E     for k_r ≤ 1
//! // derivation: E' = ½ m (k_r² s² + |v_T|²) + U + m Δu,  s² = v_N² - 2 Δu,
//! //             E  = ½ m (v_N² + |v_T|²) + U;  subtract.
//! ```
//! If `v_N² < 2 Δu` (the particle is deeper than its speed explains: it was placed there, or
//! springs or a positional solver pushed it in) the missing energy is taken from `v_T`; only when
//! that is not enough either does the projection add energy. The impact friction is the
//! velocity-level Coulomb rule of Bridson, Fedkiw & Anderson (2002): the tangential velocity loses
//! at most `k_f` times the normal velocity change, and never reverses. The resting threshold is
//! Baraff's (1997): an approach slower than `v_rest` is resting contact, not a collision; without
//! it a resting particle would bounce forever in ever smaller hops.
//!
//! No tunnelling: the plane, the sphere and the floor with a hole are solid regions (a
//! half-space, a ball, the ground around a shaft), and a bowl holds everything inside its rim
//! circle, so a particle that crossed a surface in one step is inside and is projected back to
//! the side it came from, however fast it was. (The one gap: a bowl without a floor around it
//! loses a particle that leaves through its wall just below the rim and ends the step outside
//! the rim circle.)
//!
//! **Dynamic spheres** (cloth scenes, NYCU HW1 2022/2024, `docs/course.md` §3; [`step_spheres`]) move by
//! semi-implicit Euler under gravity, or at a set velocity when kinematic. A sphere and a particle,
//! or two spheres, that overlap exchange an impulse along the line of centres and are pushed apart:
//!
//! ```text
//! d̂    = (x_b - x_a) / |x_b - x_a|                      from body a to body b
//! v_rel = (v_b - v_a)·d̂                                 < 0: approaching
//! J     = -(1 + e) v_rel / (w_a + w_b)                  (N·s)
//! v_a  -= w_a J d̂,   v_b += w_b J d̂
//! p     = r_a + r_b - |x_b - x_a|                       penetration (m), r = 0 for a particle
//! x_a  -= w_a / (w_a + w_b) p d̂,   x_b += w_b / (w_a + w_b) p d̂
//! ```
//! where `w = 1/m` (1/kg) is zero for a kinematic sphere and a pinned particle, and `e` is the
//! restitution (sphere–particle 0, sphere–sphere 0.8 in the course). The impulse conserves
//! momentum (`m_a Δv_a + m_b Δv_b = -J d̂ + J d̂ = 0`) and loses `½ μ (1 - e²) v_rel²` of kinetic
//! energy with `μ = 1/(w_a + w_b)`; the separation keeps the centre of mass where it was
//! (`m_a Δx_a + m_b Δx_b = 0`), so the gravitational energy too. The course reference pushes the
//! bodies apart by only 0.15 of the penetration; here the whole penetration is removed at once.
//!
//! References: NYCU Computer Animation HW1 (2021–2024), `docs/course.md` §2–3; D. Baraff, "An
//! Introduction to Physically Based Modeling: Rigid Body Simulation II — Nonpenetration
//! Constraints", SIGGRAPH 1997 course notes (colliding contact, the impulse `J`, the resting
//! threshold); R. Bridson, R. Fedkiw, J. Anderson, "Robust Treatment of Collisions, Contact and
//! Friction for Cloth Animation", SIGGRAPH 2002 (friction of impulses, positional projection);
//! D. Karnopp, "Computer Simulation of Stick-Slip Friction in Mechanical Dynamic Systems",
//! J. Dynamic Systems, Measurement, and Control 107 (1985) (the stick band).

use glam::DVec3;

mod spheres;

pub use spheres::{
    DynamicSphere, advance_spheres, collide_spheres, collide_spheres_logged, step_spheres,
};

/// What the colliders read of the system: a view of the model, so that this module imports
/// neither the model (`forces`) nor the state (`particles`), which both build on it. `&Model`
/// converts into a `World` and `&mut State` into [`Bodies`], so every function here is called
/// with `&model` and `&mut state` as they are.
#[derive(Clone, Copy, Debug)]
pub struct World<'a> {
    /// Static obstacles, normals of unit length.
    pub colliders: &'a [Collider],
    /// Restitution, friction and contact band.
    pub contact: &'a ContactParams,
    /// Gravitational acceleration (m/s²).
    pub gravity: DVec3,
    /// Inverse mass of each particle (1/kg); zero for a pinned particle. Its length is the
    /// particle count.
    pub inv_mass: &'a [f64],
}

impl<'a> From<&World<'a>> for World<'a> {
    fn from(world: &World<'a>) -> World<'a> {
        *world
    }
}

impl World<'_> {
    /// Number of particles.
    #[must_use]
    pub fn particle_count(&self) -> usize {
        self.inv_mass.len()
    }
}

/// What collisions change after a step: a view of the state's positions (m), velocities (m/s),
/// Verlet history and dynamic spheres.
#[derive(Debug)]
pub struct Bodies<'a> {
    /// Positions (m).
    pub x: &'a mut [DVec3],
    /// Velocities (m/s).
    pub v: &'a mut [DVec3],
    /// Positions one step ago (m), kept consistent for position Verlet.
    pub x_prev: &'a mut [DVec3],
    /// True when `x_prev` holds a Verlet history.
    pub history_valid: bool,
    /// The moving spheres.
    pub spheres: &'a mut [DynamicSphere],
}

impl Bodies<'_> {
    /// The same view for a shorter borrow (to pass it on and use it again).
    pub fn reborrow(&mut self) -> Bodies<'_> {
        Bodies {
            x: self.x,
            v: self.v,
            x_prev: self.x_prev,
            history_valid: self.history_valid,
            spheres: self.spheres,
        }
    }
}

/// `v·N` (m/s) up to which a particle counts as not moving away, so that the contact force still
/// holds it: the velocity response sets `v·N = 0`, which rounding may turn into `+1e-17`.
const ROUNDING_SPEED: f64 = 1e-9;

/// Relative margin on a bowl's rim circle (`ρ² ≤ a² (1 + margin)`): points on the circle up to
/// rounding still belong to the bowl (see [`Collider::contact`]).
const RIM_MARGIN: f64 = 1e-9;

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
                let bowl_rim = super::bowl::Rim::of(center, radius, rim_height);
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
    /// `r - |x - c| < ε  ⇔  |x - c|² > (r - ε)²` (the rim is left to the exact test): may touch
    /// when `|x - center|² ≥ d2_min` (m²).
    Bowl { center: DVec3, d2_min: f64 },
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
            Collider::Bowl { center, radius, .. } => {
                let inner = (radius - epsilon).max(0.0);
                Broad::Bowl {
                    center,
                    d2_min: inner * inner * (1.0 - MARGIN),
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
        match self.broad(epsilon) {
            Broad::Plane { .. } => true,
            Broad::Sphere { center, d2_max } => {
                let d2 = (x - center).length_squared();
                d2 < d2_max || d2.is_nan()
            }
            Broad::Bowl { center, d2_min } => {
                let d2 = (x - center).length_squared();
                d2 >= d2_min || d2.is_nan()
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

/// `(|d|, d/|d|)`, with the direction `+y` when `d = 0`.
fn distance_and_direction(d: DVec3) -> (f64, DVec3) {
    let length = d.length();
    if length > 0.0 {
        (length, d / length)
    } else {
        (0.0, DVec3::Y)
    }
}

/// Coefficients of contact and collision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Restitution `k_r` of particle–collider collisions (dimensionless, 0..=1; course 0.8).
    pub restitution: f64,
    /// Coulomb friction coefficient `k_f` (dimensionless; course 0.3 in 2021, 0.2 in 2023).
    pub friction: f64,
    /// Contact band `ε` (m): closer than this to a surface counts as touching (course 0.01).
    pub epsilon: f64,
    /// Speed `v_rest` (m/s) below which a contact is resting: no bounce, static friction.
    pub rest_speed: f64,
    /// Restitution `e` of sphere–particle impulses (course 0: the cloth does not bounce).
    pub sphere_particle_restitution: f64,
    /// Restitution `e` of sphere–sphere impulses (course 0.8).
    pub sphere_sphere_restitution: f64,
}

impl ContactParams {
    /// NYCU HW1 2021: restitution 0.8, friction 0.3, ε = 0.01 m; with this crate's resting
    /// speed 0.05 m/s and the 2022 sphere restitutions (sphere–particle 0, sphere–sphere 0.8).
    #[must_use]
    pub fn course_2021() -> ContactParams {
        ContactParams {
            restitution: 0.8,
            friction: 0.3,
            epsilon: 0.01,
            rest_speed: 0.05,
            sphere_particle_restitution: 0.0,
            sphere_sphere_restitution: 0.8,
        }
    }

    /// NYCU HW1 2023: as 2021 with friction 0.2.
    #[must_use]
    pub fn course_2023() -> ContactParams {
        ContactParams {
            friction: 0.2,
            ..ContactParams::course_2021()
        }
    }
}

impl Default for ContactParams {
    /// [`ContactParams::course_2021`]. Its `v_rest = 0.05` m/s is about five steps of gravity at
    /// the course's `dt = 0.001` s: slower approaches are resting contact.
    fn default() -> ContactParams {
        ContactParams::course_2021()
    }
}

/// Adds the contact force and friction of the model's colliders to `f` (N); see the module
/// documentation for the formulas. Called by [`super::forces()`] after the springs, only when
/// the model has colliders. Pure and allocation-free.
pub fn contact_forces<'a>(model: impl Into<World<'a>>, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
    let model = model.into();
    for i in 0..model.particle_count() {
        if model.inv_mass[i] == 0.0 {
            continue;
        }
        if let Some(total) = with_contact(&model, x[i], v[i], f[i]) {
            f[i] = total;
        }
    }
}

/// The power the contact forces and friction take out of the particles (W, ≥ 0):
///
/// ```text
/// P_contact = -Σ_i f_contact,i · v_i = -Σ_i (λ N + f_f) · v_i
/// ```
/// where `f_applied` are the forces on the particles before contact (N): weight, drag and
/// springs, as [`super::forces::applied_forces`] computes them. Each term is ≥ 0 by
/// construction (`f_c·v = λ N·v ≤ 0`, `f_f·v_T ≤ 0`, module docs).
#[must_use]
pub fn contact_power<'a>(
    model: impl Into<World<'a>>,
    x: &[DVec3],
    v: &[DVec3],
    f_applied: &[DVec3],
) -> f64 {
    let model = model.into();
    let mut power = 0.0;
    for i in 0..model.particle_count() {
        if model.inv_mass[i] == 0.0 {
            continue;
        }
        if let Some(total) = with_contact(&model, x[i], v[i], f_applied[i]) {
            power -= (total - f_applied[i]).dot(v[i]);
        }
    }
    power
}

/// The force on particle `i` at `x` moving at `v` after the colliders added their contact force
/// and friction to the applied force `f` (N), each collider in order seeing what the previous
/// ones left (module docs); `None` when no collider pushes it.
fn with_contact(model: &World<'_>, x: DVec3, v: DVec3, f: DVec3) -> Option<DVec3> {
    contact_force(model.colliders, model.contact, x, v, f)
}

/// [`contact_forces`] for one particle at `x` (m) moving at `v` (m/s) with applied force `f`
/// (N): the force after `colliders` added their contact force and friction, or `None` when no
/// collider pushes it. The stencil's fused pass calls this for the particles that may touch.
pub(crate) fn contact_force(
    colliders: &[Collider],
    params: &ContactParams,
    x: DVec3,
    v: DVec3,
    f: DVec3,
) -> Option<DVec3> {
    let mut f = f;
    let mut touched = false;
    for collider in colliders {
        if !collider.may_touch(x, params.epsilon) {
            continue;
        }
        let Some(Contact { phi, normal }) = collider.contact(x) else {
            continue;
        };
        let push = normal.dot(f);
        let v_n = normal.dot(v);
        if phi >= params.epsilon || push >= 0.0 || v_n > ROUNDING_SPEED {
            continue;
        }
        // λ = -N·f > 0; f_T = f - (N·f) N; v_T = v - (v·N) N.
        let load = -push;
        let f_t = f - push * normal;
        let v_t = v - v_n * normal;
        // f_c = λ N cancels the push; f_f resists sliding.
        f += load * normal + friction_force(params.friction * load, f_t, v_t, params.rest_speed);
        touched = true;
    }
    touched.then_some(f)
}

/// Coulomb friction (N) with limit `limit = k_f λ` (N), for tangential force `f_t` (N) and
/// tangential velocity `v_t` (m/s): kinetic above `rest_speed`, static below (module docs).
fn friction_force(limit: f64, f_t: DVec3, v_t: DVec3, rest_speed: f64) -> DVec3 {
    let speed = v_t.length();
    if speed > 0.0 && speed >= rest_speed {
        // Kinetic: -k_f λ t̂ with the unit tangent t̂ = v_T/|v_T|.
        return (-limit / speed) * v_t;
    }
    // Static: cancel f_T and damp v_T at the rate that reaches the limit at |v_T| = v_rest.
    let damping = if rest_speed > 0.0 {
        limit / rest_speed
    } else {
        0.0
    };
    let mut f_f = -f_t - damping * v_t;
    // Coulomb limit: |f_f| ≤ k_f λ.
    let magnitude = f_f.length();
    if magnitude > limit {
        f_f *= limit / magnitude;
    }
    // Never push along the sliding direction (f_f·v_T ≤ 0): friction only dissipates.
    let along = f_f.dot(v_t);
    if along > 0.0 {
        f_f -= (along / (speed * speed)) * v_t;
    }
    f_f
}

/// Velocity response and positional projection of every free particle against the model's
/// colliders, after a step of `dt` seconds (module docs). Keeps position Verlet's history
/// consistent: a particle whose velocity changed gets `x_prev = x - dt v`.
pub fn resolve<'a, 'b>(model: impl Into<World<'a>>, state: impl Into<Bodies<'b>>, dt: f64) {
    resolve_logged(model, state, dt, None);
}

/// [`resolve`], recording in `log` (when given) every particle it changes.
pub fn resolve_logged<'a, 'b>(
    model: impl Into<World<'a>>,
    state: impl Into<Bodies<'b>>,
    dt: f64,
    mut log: Option<&mut Changes>,
) {
    let (model, state) = (model.into(), state.into());
    if model.colliders.is_empty() {
        return;
    }
    let params = &model.contact;
    for i in 0..state.x.len().min(model.particle_count()) {
        if model.inv_mass[i] == 0.0 {
            continue;
        }
        let (x_old, v_old) = (state.x[i], state.v[i]);
        let mut touched = false;
        for collider in model.colliders {
            touched |= respond(
                collider,
                0.0,
                params,
                model.gravity,
                &mut state.x[i],
                &mut state.v[i],
            );
        }
        if touched {
            keep_verlet_history(
                state.history_valid,
                &mut state.x_prev[i],
                state.x[i],
                state.v[i],
                dt,
            );
            if let Some(log) = log.as_deref_mut() {
                log.record(i, x_old, v_old);
            }
        }
    }
}

/// What a collision response changed, for the energy it removed without a pass over the whole
/// system ([`super::energy::energy_change`]): every particle it moved or slowed, with its
/// position (m) and velocity (m/s) before the first change, and the dynamic spheres' energy
/// before (J).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Changes {
    /// `(particle, x before, v before)`, sorted by particle, each once after [`Changes::finish`].
    pub(crate) particles: Vec<(u32, DVec3, DVec3)>,
    /// Kinetic and gravitational energy of the non-kinematic spheres before (J).
    pub(crate) spheres_before: f64,
    /// After [`Changes::finish`]: `slot[i]` is the index of particle `i` in `particles`, or
    /// `u32::MAX` when it did not change (grown to the particle count on first use).
    slot: Vec<u32>,
}

impl Changes {
    /// Forgets everything recorded.
    pub fn clear(&mut self) {
        for &(i, ..) in &self.particles {
            if let Some(s) = self.slot.get_mut(i as usize) {
                *s = u32::MAX;
            }
        }
        self.particles.clear();
        self.spheres_before = 0.0;
    }

    fn record(&mut self, i: usize, x: DVec3, v: DVec3) {
        self.particles.push((i as u32, x, v));
    }

    /// Sorts the records by particle and keeps each particle's first (its state before any
    /// change); `particles` is the system's particle count.
    pub fn finish(&mut self, particles: usize) {
        // A stable sort keeps the records of one particle in the order they were made.
        self.particles.sort_by_key(|p| p.0);
        self.particles.dedup_by_key(|p| p.0);
        if self.slot.len() < particles {
            self.slot.resize(particles, u32::MAX);
        }
        for (k, &(i, ..)) in self.particles.iter().enumerate() {
            self.slot[i as usize] = k as u32;
        }
    }

    /// The record of particle `i`, if it changed.
    pub(crate) fn of(&self, i: usize) -> Option<&(u32, DVec3, DVec3)> {
        let k = *self.slot.get(i)?;
        self.particles.get(k as usize)
    }
}

/// Kinetic and gravitational energy of the non-kinematic dynamic `spheres` under `gravity`
/// (m/s²), in J, as [`super::energy::energy`] counts them.
#[must_use]
pub fn spheres_energy(gravity: DVec3, spheres: &[DynamicSphere]) -> f64 {
    spheres
        .iter()
        .filter(|s| !s.kinematic)
        .map(|s| 0.5 * s.mass * s.velocity.length_squared() - s.mass * gravity.dot(s.center))
        .sum()
}

/// The response of one point (a particle, or a sphere's centre with `offset` its radius, m) to
/// one collider: projection, climb, bounce, impact friction (module docs). Returns whether
/// anything changed.
fn respond(
    collider: &Collider,
    offset: f64,
    params: &ContactParams,
    gravity: DVec3,
    x: &mut DVec3,
    v: &mut DVec3,
) -> bool {
    if !collider.may_touch(*x, params.epsilon + offset) {
        return false;
    }
    let Some(Contact { phi, normal }) = collider.contact(*x) else {
        return false;
    };
    // A sphere touches when its centre is within its radius of the surface.
    let phi = phi - offset;
    let v_n = v.dot(normal);
    if phi >= params.epsilon || (phi >= 0.0 && v_n >= 0.0) {
        return false;
    }
    let mut v_t = *v - v_n * normal;
    // Squared normal speed at the surface: s² = v_N² - 2 Δu, with Δu = -g·Δx and Δx = -φ N.
    let mut s2 = v_n * v_n;
    if phi < 0.0 {
        let dx = -phi * normal;
        *x += dx;
        s2 += 2.0 * gravity.dot(dx);
    }
    if s2 < 0.0 {
        // Deeper than its speed explains: take the missing ½|s²| (J/kg) from the tangential
        // kinetic energy, ½|v_T|² → max(0, ½|v_T|² - ½|s²|).
        let t2 = v_t.length_squared();
        v_t *= if t2 > 0.0 {
            ((t2 + s2).max(0.0) / t2).sqrt()
        } else {
            0.0
        };
        s2 = 0.0;
    }
    let s = s2.sqrt();
    let v_n_new = if v_n >= 0.0 {
        // Already moving away: only the climb to the surface slows it.
        s
    } else if s > params.rest_speed {
        // Colliding: v_N' = -k_r v_N at the surface.
        params.restitution * s
    } else {
        // Resting contact: no bounce.
        0.0
    };
    // Impact friction: |v_T| loses k_f times the normal velocity gained, never reversing.
    let gained = v_n_new - v_n;
    let t = v_t.length();
    if gained > 0.0 && t > 0.0 {
        v_t *= (1.0 - params.friction * gained / t).max(0.0);
    }
    *v = v_t + v_n_new * normal;
    true
}

/// After a particle's `x` or `v` changed outside the integrator: Verlet's implied velocity
/// `(x - x_prev)/dt` becomes the new `v` again (`x_prev = x - dt v`), if Verlet has a history.
fn keep_verlet_history(history_valid: bool, x_prev: &mut DVec3, x: DVec3, v: DVec3, dt: f64) {
    if history_valid {
        *x_prev = x - dt * v;
    }
}

/// Everything collisions do after an integrator step of `dt` seconds: [`step_spheres`], then
/// [`resolve`]. Returns at once when the model has no colliders and the state no spheres, so
/// scenes without obstacles pay nothing. `Simulation::step` calls it for every body.
pub fn after_step<'a, 'b>(model: impl Into<World<'a>>, state: impl Into<Bodies<'b>>, dt: f64) {
    let (model, mut state) = (model.into(), state.into());
    step_spheres(model, state.reborrow(), dt);
    resolve(model, state, dt);
}
