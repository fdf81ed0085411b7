//! Contacts inside pass 2 of the stencil: a broad phase on a whole chunk in registers
//! (`may_touch`, no square roots: each collider's bounds, [`Collider::broad`], made once per
//! range, `Scratch::broads`), then the contact force of [`super::super::collide`] for the
//! particles that may touch (`contact_lanes`): all eight lanes at once with the scalar code's
//! operations, every branch a mask (`contact_geometry` for each kind of collider, then the
//! push and the friction), the same bits. A body resting on its plane has a whole layer of
//! particles in the band every step, and a jelly resting in the 2023 bowl about a hundred
//! particles within the bowl's and the floor's bounds: through the scalar code one lane at a
//! time, with the bounds made again for every chunk and lane, that run took 6 % more CPU time
//! (semi-implicit Euler, one thread).
#[allow(clippy::wildcard_imports)]
use super::*;
use crate::physics::collide::{Broad, RIM_MARGIN, ROUNDING_SPEED};
use crate::physics::fast::marks::{broad_lanes, dot, minus, radial};

/// The chunk's particles (bit `l` for lane `l`) that may touch one of the colliders whose
/// bounds are `broads` ([`Collider::broad`] at the contact band `ε`: closer than `ε` or
/// inside), eight particles at a time ([`broad_lanes`], `Broad::may_touch` of each lane), so
/// that it never leaves out a particle that [`Collider::contact`] would put within `ε`.
#[inline(always)]
pub(super) fn may_touch<V: Lanes>(broads: &[Broad], x: [V; 3]) -> u8 {
    // A loop, not a fold: a closure does not take the caller's target features, and its
    // vector operations would become calls.
    let mut mask = 0u8;
    for broad in broads {
        mask |= broad_lanes(broad, x);
    }
    mask
}

/// The contact force of `d`'s colliders (bounds `broads`, [`Collider::broad`] of each at the
/// contact band) on the `candidates` lanes of a chunk (positions `x`, velocities `v`, forces
/// before contact `f`): `collide::contact_force`'s operations lane by lane, each branch a mask and
/// both sides computed (`blend` keeps the bits of the side a lane takes), so the same forces and
/// power bit for bit (tested). For each collider in turn, on the lanes its bounds hold (a
/// plane: every lane, as `Collider::may_touch`) and that it answers ([`contact_geometry`]: `φ`
/// and the normal `N`), with `push = N·f` and `v_N = N·v`, the lanes that are not clear of the
/// band (`φ ≥ ε`), are not pushed away (`push ≥ 0`) and do not leave (`v_N > 10⁻⁹` m/s) get
/// `f += λ N + f_f` with `λ = -push` and the friction `f_f` of `collide/force.rs`. Returns the
/// new forces and the contact power `-(f_contact)·v` (W) per lane.
#[inline(always)]
pub(super) fn contact_lanes<V: Lanes>(
    d: &Dynamics,
    broads: &[Broad],
    x: [V; 3],
    v: [V; 3],
    f: [V; 3],
    candidates: u8,
) -> ([V; 3], V) {
    let params = d.contact;
    let (epsilon, rest) = (V::splat(params.epsilon), V::splat(params.rest_speed));
    let mut total = f;
    let mut touched = 0u8;
    for (collider, broad) in d.colliders.iter().zip(broads) {
        let held = if matches!(collider, Collider::Plane { .. }) {
            candidates
        } else {
            candidates & broad_lanes(broad, x)
        };
        if held == 0 {
            continue;
        }
        let (phi, n, answers) = contact_geometry(collider, x);
        // `normal.dot(f)`, `normal.dot(v)`: N's component times the vector's, in axis order.
        let push = dot3(n, total);
        let v_n = dot3(n, v);
        let active = held
            & answers
            & (phi.less_than(epsilon) | phi.nan_lanes())
            & (push.less_than(V::zero()) | push.nan_lanes())
            & !V::splat(ROUNDING_SPEED).less_than(v_n);
        if active == 0 {
            continue;
        }
        let load = neg(push);
        let f_t = sub(total, scale(push, n));
        let v_t = sub(v, scale(v_n, n));
        let limit = V::splat(params.friction).mul(load);
        // Friction (`friction_force`): kinetic where |v_T| > 0 and |v_T| ≥ v_rest.
        let speed = dot3(v_t, v_t).sqrt();
        let kinetic = V::zero().less_than(speed) & !speed.less_than(rest);
        let sliding = scale(neg(limit).div(speed), v_t);
        let damping = if params.rest_speed > 0.0 {
            limit.div(rest)
        } else {
            V::zero()
        };
        let mut f_f = sub([neg(f_t[0]), neg(f_t[1]), neg(f_t[2])], scale(damping, v_t));
        let magnitude = dot3(f_f, f_f).sqrt();
        let over = limit.less_than(magnitude);
        f_f = blend3(scale(limit.div(magnitude), f_f), f_f, over);
        let along = dot3(f_f, v_t);
        let forward = V::zero().less_than(along);
        let back = scale(along.div(speed.mul(speed)), v_t);
        f_f = blend3(sub(f_f, back), f_f, forward);
        let f_f = blend3(sliding, f_f, kinetic);
        total = blend3(add(total, add(scale(load, n), f_f)), total, active);
        touched |= active;
    }
    // P = -f_contact · v on the lanes a collider pushed (`collide::contact_power`), 0 elsewhere.
    let power = neg(dot3(sub(total, f), v)).blend(V::zero(), touched);
    (total, power)
}

/// [`Collider::contact`] lane by lane, the same operations: `φ` (m), the normal `N` and the
/// lanes where the collider answers (the scalar code's `Some`).
#[inline(always)]
fn contact_geometry<V: Lanes>(collider: &Collider, x: [V; 3]) -> (V, [V; 3], u8) {
    // No closures here: a closure does not take the caller's target features (its vector
    // operations would become calls).
    match *collider {
        Collider::Plane { point, normal } => (dot(minus(x, point), normal), splat3(normal), !0),
        Collider::Sphere { center, radius } => {
            let (distance, outward) = distance_and_direction(minus(x, center));
            (distance.sub(V::splat(radius)), outward, !0)
        }
        Collider::Bowl {
            center,
            radius,
            rim_height,
        } => {
            let bowl_rim = crate::physics::bowl::Rim::of(center, radius, rim_height);
            // Not above the rim (`x.y > rim`: none), not outside the rim's cylinder with its
            // margin (`ρ² > a² (1 + 10⁻⁹)`: none); ρ² as `powi(2)`, a product.
            let below = !V::splat(bowl_rim.height).less_than(x[1]);
            let (dx, dz) = (x[0].sub(V::splat(center.x)), x[2].sub(V::splat(center.z)));
            let rho2 = dx.mul(dx).add(dz.mul(dz));
            let inside = !V::splat(bowl_rim.radius_squared * (1.0 + RIM_MARGIN)).less_than(rho2);
            let (distance, outward) = distance_and_direction(minus(x, center));
            (
                V::splat(radius).sub(distance),
                [neg(outward[0]), neg(outward[1]), neg(outward[2])],
                below & inside,
            )
        }
        Collider::HolePlane {
            point,
            normal,
            hole_center,
            hole_radius,
        } => {
            let height = dot(minus(x, point), normal);
            let (rho, outward) = distance_and_direction(radial(x, hole_center, normal));
            let r = V::splat(hole_radius);
            let over_floor = at_least(rho, r);
            let up = at_least(height, V::zero());
            // Below the floor beside the shaft: the nearer face, `-h ≤ ρ - R` the floor's.
            let floor_nearer = at_least(rho.sub(r), neg(height));
            let floor = (up & over_floor) | (!up & over_floor & floor_nearer);
            let shaft = !up & (!over_floor | !floor_nearer);
            let n: [V; 3] = splat3(normal);
            (
                height.blend(r.sub(rho), floor),
                [
                    n[0].blend(neg(outward[0]), floor),
                    n[1].blend(neg(outward[1]), floor),
                    n[2].blend(neg(outward[2]), floor),
                ],
                floor | shaft,
            )
        }
    }
}

/// `a ≥ b` lane by lane (false where either is NaN).
#[inline(always)]
fn at_least<V: Lanes>(a: V, b: V) -> u8 {
    !a.less_than(b) & !a.nan_lanes() & !b.nan_lanes()
}

/// `a` in every lane, axis by axis.
#[inline(always)]
fn splat3<V: Lanes>(a: DVec3) -> [V; 3] {
    [V::splat(a.x), V::splat(a.y), V::splat(a.z)]
}

/// `distance_and_direction` of `collide/geometry.rs` lane by lane: `(|d|, d / |d|)`, or
/// `(0, ŷ)` where `|d|` is not positive (zero or NaN).
#[inline(always)]
fn distance_and_direction<V: Lanes>(d: [V; 3]) -> (V, [V; 3]) {
    let length = dot3(d, d).sqrt();
    let positive = V::zero().less_than(length);
    let direction = [
        d[0].div(length).blend(V::zero(), positive),
        d[1].div(length).blend(V::splat(1.0), positive),
        d[2].div(length).blend(V::zero(), positive),
    ];
    (length.blend(V::zero(), positive), direction)
}

#[inline(always)]
fn neg<V: Lanes>(a: V) -> V {
    a.mul(V::splat(-1.0))
}

#[inline(always)]
fn scale<V: Lanes>(s: V, a: [V; 3]) -> [V; 3] {
    [s.mul(a[0]), s.mul(a[1]), s.mul(a[2])]
}

#[inline(always)]
fn sub<V: Lanes>(a: [V; 3], b: [V; 3]) -> [V; 3] {
    [a[0].sub(b[0]), a[1].sub(b[1]), a[2].sub(b[2])]
}

#[inline(always)]
fn add<V: Lanes>(a: [V; 3], b: [V; 3]) -> [V; 3] {
    [a[0].add(b[0]), a[1].add(b[1]), a[2].add(b[2])]
}

/// `a · b` lane by lane, in axis order (`DVec3::dot`).
#[inline(always)]
fn dot3<V: Lanes>(a: [V; 3], b: [V; 3]) -> V {
    a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2]))
}

#[inline(always)]
fn blend3<V: Lanes>(a: [V; 3], b: [V; 3], m: u8) -> [V; 3] {
    [
        a[0].blend(b[0], m),
        a[1].blend(b[1], m),
        a[2].blend(b[2], m),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact test the bounds stand in for (the collision response's): some collider puts `x` within `epsilon` of its
    /// surface or inside it (`φ < ε`), or `φ` is NaN.
    fn exact(colliders: &[Collider], epsilon: f64, x: DVec3) -> bool {
        colliders.iter().any(|c| {
            c.contact(x)
                .is_some_and(|contact| contact.phi < epsilon || contact.phi.is_nan())
        })
    }

    /// Every collider kind, every point of a grid through and around it (and NaN): the bounds
    /// never rule out a point the exact test accepts, the scalar form agrees with the eight-lane
    /// one point by point, and they rule out a good share of the points (else they would save
    /// nothing).
    #[test]
    fn the_broad_bounds_never_leave_out_a_point_the_exact_test_accepts() {
        let epsilon = 1e-3;
        let kinds = [
            Collider::Plane {
                point: DVec3::new(0.0, -1.0, 0.0),
                normal: DVec3::new(1.0, 1.0, 0.0).normalize(),
            },
            Collider::Sphere {
                center: DVec3::new(0.5, 0.2, -0.3),
                radius: 1.0,
            },
            Collider::Bowl {
                center: DVec3::new(2.0, 7.0, 1.0),
                radius: 7.0,
                rim_height: 7.0,
            },
            Collider::HolePlane {
                point: DVec3::new(0.0, 0.0, 0.0),
                normal: DVec3::Y,
                hole_center: DVec3::new(1.0, 0.0, 1.0),
                hole_radius: 1.5,
            },
        ];
        for collider in kinds {
            let colliders = [collider];
            let broad = collider.broad(epsilon);
            let (mut accepted, mut ruled_out) = (0, 0);
            let mut points: Vec<DVec3> = Vec::new();
            for i in -40..=40 {
                for j in -40..=40 {
                    for k in [-3, 0, 2] {
                        // Steps of 0.25 m, and points a hair from the surfaces (…0.999 and
                        // …1.001 of a step).
                        let s = 0.25 * (1.0 + 1e-3 * f64::from(k));
                        points.push(DVec3::new(
                            f64::from(i) * s,
                            f64::from(j) * s,
                            f64::from(i + j) * 0.5 * s,
                        ));
                    }
                }
            }
            points.push(DVec3::new(f64::NAN, 0.0, 0.0));
            for &p in &points {
                let touches = exact(&colliders, epsilon, p);
                let passes = broad.may_touch(p);
                assert!(
                    !touches || passes,
                    "{collider:?}: {p} ruled out but touches"
                );
                let mut lanes = [p; LANES];
                lanes[1] = DVec3::splat(1e6);
                let mask = may_touch(
                    &[broad],
                    crate::physics::fast::lanes::load_chunk::<Plain>(&lanes, LANES),
                );
                assert_eq!(mask & 1 != 0, passes, "{collider:?}: {p} lanes vs scalar");
                accepted += usize::from(touches);
                ruled_out += usize::from(!passes);
            }
            assert!(accepted > 0, "{collider:?}: no point touches");
            assert!(
                ruled_out > points.len() / 10,
                "{collider:?}: {ruled_out} ruled out"
            );
        }
    }
}

#[cfg(test)]
mod lane_tests {
    use super::*;
    use crate::physics::collide::contact_force;

    /// Eight particles of 1 kg under gravity, without drag, against `colliders`.
    fn unit_masses<'a>(colliders: &'a [Collider], params: &'a ContactParams) -> Dynamics<'a> {
        Dynamics {
            mass: &[1.0; LANES],
            inv_mass: &[1.0; LANES],
            gravity: DVec3::new(0.0, -9.8, 0.0),
            drag: 0.0,
            colliders,
            contact: params,
        }
    }

    /// Asserts that the `candidates` lanes of a chunk at `x`, `v` with forces `f` get
    /// `contact_force`'s forces and power bit for bit (a NaN force: NaN) and the others keep
    /// theirs, through `contact_lanes` with the bounds made once; returns how many lanes a
    /// collider pushed.
    fn same_as_scalar(
        d: &Dynamics,
        x: &[DVec3; LANES],
        v: &[DVec3; LANES],
        f: &[DVec3; LANES],
        candidates: u8,
    ) -> usize {
        let bits = |a: DVec3| a.to_array().map(f64::to_bits);
        let lanes = |a: &[DVec3; LANES]| load_chunk::<Plain>(a, LANES);
        let broads: Vec<Broad> = (d.colliders.iter())
            .map(|c| c.broad(d.contact.epsilon))
            .collect();
        let (total, power) = contact_lanes(d, &broads, lanes(x), lanes(v), lanes(f), candidates);
        let mut out = [[0.0; LANES]; 3];
        for (c, lane) in total.into_iter().enumerate() {
            lane.store(&mut out[c]);
        }
        let mut p = [0.0; LANES];
        power.store(&mut p);
        let mut touched = 0;
        for l in 0..LANES {
            let got = DVec3::new(out[0][l], out[1][l], out[2][l]);
            let scalar = (candidates & (1 << l) != 0)
                .then(|| contact_force(d.colliders, d.contact, x[l], v[l], f[l]))
                .flatten();
            let (want, want_power) = match scalar {
                Some(t) => (t, -(t - f[l]).dot(v[l])),
                None => (f[l], 0.0),
            };
            touched += usize::from(scalar.is_some());
            if want.is_nan() {
                assert!(got.is_nan(), "lane {l}");
                continue;
            }
            assert_eq!(bits(got), bits(want), "lane {l}: {got} {want}");
            assert_eq!(p[l].to_bits(), want_power.to_bits(), "lane {l} power");
        }
        touched
    }
    use crate::physics::fast::lanes::load_chunk;

    /// The planes' lanes give `contact_force`'s forces and power bit for bit, lane by lane:
    /// one and two planes, with and without friction and a resting speed, particles inside,
    /// in the band and clear of it, pushed in and pulled out, sliding fast, slowly and not at
    /// all, moving away, signed zeros and a NaN; lanes that are not candidates unchanged.
    #[test]
    fn the_planes_lanes_are_the_scalar_contact_force() {
        let planes = [
            Collider::Plane {
                point: DVec3::new(0.0, -0.5, 0.0),
                normal: DVec3::Y,
            },
            Collider::Plane {
                point: DVec3::new(0.2, 0.0, 0.1),
                normal: DVec3::new(1.0, 0.4, -0.3).normalize(),
            },
        ];
        let mut checked = 0;
        for count in [1, 2] {
            for (friction, rest_speed) in [(0.0, 0.0), (0.0, 0.05), (0.3, 0.0), (0.2, 0.01)] {
                let params = ContactParams {
                    friction,
                    rest_speed,
                    ..ContactParams::course_2021()
                };
                let d = unit_masses(&planes[..count], &params);
                for seed in 0..200u32 {
                    let r = |k: u32| {
                        let t =
                            f64::from(seed.wrapping_mul(2_654_435_761).wrapping_add(k * 97)) * 1e-4;
                        (t.sin() * 1e4).fract()
                    };
                    let mut x = [DVec3::ZERO; LANES];
                    let mut v = [DVec3::ZERO; LANES];
                    let mut f = [DVec3::ZERO; LANES];
                    for l in 0..LANES {
                        let k = 10 * l as u32;
                        x[l] = DVec3::new(0.3 * r(k), -0.5 + 0.02 * r(k + 1), 0.3 * r(k + 2));
                        v[l] = DVec3::new(r(k + 3), 0.1 * r(k + 4), r(k + 5))
                            * [1.0, 0.01, 0.0][l % 3];
                        f[l] = DVec3::new(r(k + 6), -1.0 + r(k + 7), r(k + 8));
                    }
                    v[1] = DVec3::new(-0.0, 0.0, 0.0);
                    f[2] = DVec3::new(0.0, -0.0, 0.0);
                    x[3].y = -0.51;
                    v[4].y = 2e-9;
                    if seed == 7 {
                        x[5] = DVec3::new(f64::NAN, 0.0, 0.0);
                    }
                    let candidates = (seed as u8) | 0b1010_1010;
                    checked += same_as_scalar(&d, &x, &v, &f, candidates);
                }
            }
        }
        assert!(checked > 1000, "{checked} lanes touched");
    }

    /// With colliders of every kind (the plane among them, so the lanes take the scalar path
    /// with the bounds made once, `contact_force_within`), the lanes' forces and power are
    /// `contact_force`'s lane by lane, bit for bit: points inside, on and around the bowl, the
    /// sphere, the floor with a hole and the plane, moving in and out, and a NaN.
    #[test]
    fn the_lanes_with_bounds_are_the_scalar_contact_force() {
        let colliders = [
            Collider::Bowl {
                center: DVec3::new(0.0, 2.0, 0.0),
                radius: 2.0,
                rim_height: 1.5,
            },
            Collider::HolePlane {
                point: DVec3::ZERO,
                normal: DVec3::Y,
                hole_center: DVec3::new(0.0, 0.0, 0.0),
                hole_radius: 1.2,
            },
            Collider::Sphere {
                center: DVec3::new(0.8, 0.3, 0.0),
                radius: 0.4,
            },
            Collider::Plane {
                point: DVec3::new(0.0, 0.05, 0.0),
                normal: DVec3::Y,
            },
        ];
        let params = ContactParams::course_2023();
        let d = unit_masses(&colliders, &params);
        let (mut touched, mut candidate_lanes) = (0, 0);
        for seed in 0..400u32 {
            let r = |k: u32| {
                let t = f64::from(seed.wrapping_mul(2_654_435_761).wrapping_add(k * 97)) * 1e-4;
                (t.sin() * 1e4).fract()
            };
            let (mut x, mut v, mut f) = (
                [DVec3::ZERO; LANES],
                [DVec3::ZERO; LANES],
                [DVec3::ZERO; LANES],
            );
            for l in 0..LANES {
                let k = 10 * l as u32;
                x[l] = DVec3::new(1.6 * r(k), 0.3 * r(k + 1) + 0.05, 1.6 * r(k + 2));
                v[l] = DVec3::new(r(k + 3), r(k + 4), r(k + 5));
                f[l] = DVec3::new(r(k + 6), -1.0 + r(k + 7), r(k + 8));
            }
            if seed == 11 {
                x[2] = DVec3::new(f64::NAN, 0.1, 0.0);
            }
            // Now and then the edge cases of the geometry: on the hole's axis (no direction:
            // ŷ), on the shaft's wall, below the floor beside the shaft (the nearer face), on
            // the rim's height, on the rim's cylinder, at the bowl's and the sphere's centres
            // (no direction: ŷ), infinities and NaN in each axis, at rest.
            if seed % 5 == 0 {
                let special = [
                    DVec3::new(0.0, -0.1, 0.0),
                    DVec3::new(1.2, -0.004, 0.0),
                    DVec3::new(1.25, -0.003, 0.0),
                    DVec3::new(0.0, 1.5, -1.9364916731037085),
                    DVec3::new(0.0, 2.0, 0.0),
                    DVec3::new(f64::INFINITY, 0.0, 0.0),
                    DVec3::new(0.3, f64::NEG_INFINITY, 0.1),
                    DVec3::new(0.2, 0.003, f64::NAN),
                    DVec3::new(0.8, -0.005, 0.0),
                    DVec3::new(-0.6, 0.001, 0.7),
                    DVec3::new(0.8, 0.3, 0.0),
                ];
                for l in 0..LANES {
                    x[l] = special[(l + seed as usize / 5) % special.len()];
                    if l % 3 == 0 {
                        v[l] = DVec3::ZERO;
                    }
                }
            }
            let candidates = (seed as u8) | 0b0101_0101;
            candidate_lanes += candidates.count_ones();
            touched += same_as_scalar(&d, &x, &v, &f, candidates);
        }
        // Both answers occur (the test can fail either way).
        assert!(
            touched > 100 && touched + 100 < candidate_lanes as usize,
            "{touched} of {candidate_lanes} lanes touched"
        );
    }
}
