//! Contacts inside pass 2 of the stencil: a broad phase on a whole chunk in registers
//! (`may_touch`, no square roots), then the contact force of [`super::super::collide`] for the
//! particles that may touch (`contact_lanes`): against planes alone all eight lanes at once with
//! the scalar code's operations (`plane_lanes`, the same bits: a plane's contact is a few dot
//! products, and a body resting on its plane has a whole layer of particles in the band every
//! step), against other colliders the scalar code lane by lane. Each collider's bounds
//! ([`Collider::broad`]) are made once per range (`Scratch::broads`), not again for every chunk
//! and every particle that may touch (a jelly resting in the 2023 bowl has a hundred of those a
//! step; the scalar code is given the bounds, `contact_force_within`).

#[allow(clippy::wildcard_imports)]
use super::*;
use crate::physics::collide::{Broad, ROUNDING_SPEED};
use crate::physics::fast::marks::{dot, minus, squared};

/// The chunk's particles (bit `l` for lane `l`) that may touch one of the colliders whose
/// bounds are `broads` ([`Collider::broad`] at the contact band `ε`: closer than `ε` or
/// inside), eight particles at a time, so that it never leaves out a particle that
/// [`Collider::contact`] would put within `ε`.
#[inline(always)]
pub(super) fn may_touch<V: Lanes>(broads: &[Broad], x: [V; 3]) -> u8 {
    let mut mask = 0u8;
    for &broad in broads {
        mask |= match broad {
            Broad::Plane {
                point,
                normal,
                phi_max,
            } => {
                // NaN: let the exact test decide.
                let phi = dot(minus(x, point), normal);
                phi.less_than(V::splat(phi_max)) | phi.nan_lanes()
            }
            Broad::Sphere { center, d2_max } => {
                let d2 = squared(minus(x, center));
                d2.less_than(V::splat(d2_max)) | d2.nan_lanes()
            }
            Broad::Bowl {
                center,
                d2_min,
                rim,
            } => {
                // Outside the inner sphere (or NaN) and not above the rim (NaN: not above).
                let d2 = squared(minus(x, center));
                !d2.less_than(V::splat(d2_min)) & !V::splat(rim).less_than(x[1])
            }
            Broad::HolePlane {
                point,
                normal,
                hole_center,
                h_max,
                h_floor,
                rho2_min,
            } => {
                let h = dot(minus(x, point), normal);
                let low = h.less_than(V::splat(h_max)) | h.nan_lanes();
                let q = minus(x, hole_center);
                let along = dot(q, normal);
                let radial = [
                    q[0].sub(along.mul(V::splat(normal.x))),
                    q[1].sub(along.mul(V::splat(normal.y))),
                    q[2].sub(along.mul(V::splat(normal.z))),
                ];
                let near_wall = !squared(radial).less_than(V::splat(rho2_min));
                let above = !h.less_than(V::splat(h_floor));
                low & (above | near_wall)
            }
        };
    }
    mask
}

/// The contact force of `d`'s colliders (bounds `broads`, [`Collider::broad`] of each at the
/// contact band) on the `candidates` lanes of a chunk (positions `x`, velocities `v`, forces
/// before contact `f`), with [`contact_force`], the function of
/// [`super::collide::contact_forces`], given the bounds (`contact_force_within`, the same
/// tests on the same numbers): the new forces, and the contact power `-(f_contact)·v` (W) per
/// lane.
#[inline(always)]
pub(super) fn contact_lanes<V: Lanes>(
    d: &Dynamics,
    broads: &[Broad],
    x: [V; 3],
    v: [V; 3],
    f: [V; 3],
    candidates: u8,
) -> ([V; 3], V) {
    if d.colliders
        .iter()
        .all(|c| matches!(c, Collider::Plane { .. }))
    {
        return plane_lanes(d, x, v, f, candidates);
    }
    let unpack = |lanes: [V; 3]| {
        let mut values = [[0.0; LANES]; 3];
        for (c, lane) in lanes.into_iter().enumerate() {
            lane.store(&mut values[c]);
        }
        values
    };
    let (xs, vs, mut fs) = (unpack(x), unpack(v), unpack(f));
    let mut power = [0.0; LANES];
    for l in (0..LANES).filter(|l| candidates & (1 << l) != 0) {
        let at = |a: &[[f64; LANES]; 3]| DVec3::new(a[0][l], a[1][l], a[2][l]);
        let (xl, vl, fl) = (at(&xs), at(&vs), at(&fs));
        if let Some(total) = contact_force_within(d.colliders, broads, d.contact, xl, vl, fl) {
            // P = -f_contact · v (see `collide::contact_power`).
            power[l] = -(total - fl).dot(vl);
            fs[0][l] = total.x;
            fs[1][l] = total.y;
            fs[2][l] = total.z;
        }
    }
    (
        [V::load(&fs[0]), V::load(&fs[1]), V::load(&fs[2])],
        V::load(&power),
    )
}

/// [`contact_lanes`] when every collider is a plane: [`contact_force`]'s operations lane by
/// lane, each branch a mask and both sides computed (`blend` keeps the bits of the side a lane
/// takes), so the same forces and power bit for bit (tested): for each plane in turn, with
/// `φ = (x - p)·N`, `push = N·f`, `v_N = N·v`, the lanes that may touch, are not clear of the
/// band (`φ ≥ ε`), are not pushed away (`push ≥ 0`) and do not leave (`v_N > 10⁻⁹` m/s) get
/// `f += λ N + f_f` with `λ = -push` and the friction `f_f` of `collide/force.rs`.
#[inline(always)]
fn plane_lanes<V: Lanes>(
    d: &Dynamics,
    x: [V; 3],
    v: [V; 3],
    f: [V; 3],
    candidates: u8,
) -> ([V; 3], V) {
    let neg = |a: V| a.mul(V::splat(-1.0));
    let scale = |s: V, a: [V; 3]| [s.mul(a[0]), s.mul(a[1]), s.mul(a[2])];
    let sub = |a: [V; 3], b: [V; 3]| [a[0].sub(b[0]), a[1].sub(b[1]), a[2].sub(b[2])];
    let add = |a: [V; 3], b: [V; 3]| [a[0].add(b[0]), a[1].add(b[1]), a[2].add(b[2])];
    let dot3 = |a: [V; 3], b: [V; 3]| a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2]));
    let blend3 = |a: [V; 3], b: [V; 3], m: u8| {
        [
            a[0].blend(b[0], m),
            a[1].blend(b[1], m),
            a[2].blend(b[2], m),
        ]
    };
    let params = d.contact;
    let (epsilon, rest) = (V::splat(params.epsilon), V::splat(params.rest_speed));
    let mut total = f;
    let mut touched = 0u8;
    for collider in d.colliders {
        let Collider::Plane { point, normal } = *collider else {
            continue;
        };
        let n = [V::splat(normal.x), V::splat(normal.y), V::splat(normal.z)];
        let phi = dot(minus(x, point), normal);
        // `normal.dot(f)`, `normal.dot(v)`: N's component times the vector's, in axis order.
        let push = dot3(n, total);
        let v_n = dot3(n, v);
        let active = candidates
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
    // P = -f_contact · v on the lanes a plane pushed (`collide::contact_power`), 0 elsewhere.
    let power = neg(dot3(sub(total, f), v)).blend(V::zero(), touched);
    (total, power)
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
