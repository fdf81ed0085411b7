//! Contacts inside pass 2 of the stencil: a broad phase on a whole chunk in registers
//! (`may_touch`, no square roots) and the scalar contact code of [`super::super::collide`] for
//! the few particles that may touch (`contact_lanes`).

#[allow(clippy::wildcard_imports)]
use super::*;
use crate::physics::collide::Broad;

/// The chunk's particles (bit `l` for lane `l`) that may touch one of `colliders` (closer than
/// `epsilon`, m, or inside): the bounds of [`Collider::broad`], eight particles at a time, so
/// that it never leaves out a particle that [`Collider::contact`] would put within `epsilon`.
#[inline(always)]
pub(super) fn may_touch<V: Lanes>(colliders: &[Collider], epsilon: f64, x: [V; 3]) -> u8 {
    let mut mask = 0u8;
    for collider in colliders {
        mask |= match collider.broad(epsilon) {
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
            Broad::Bowl { center, d2_min } => {
                let d2 = squared(minus(x, center));
                !d2.less_than(V::splat(d2_min))
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

// Functions, not closures: a closure does not take its caller's target features, so LLVM kept
// these out of line and called each AVX operation inside them as a function; `inline(always)`
// functions are inlined into the AVX2 kernel, and their operations with them.

/// `p · n` lane by lane.
#[inline(always)]
fn dot<V: Lanes>(p: [V; 3], n: DVec3) -> V {
    p[0].mul(V::splat(n.x))
        .add(p[1].mul(V::splat(n.y)))
        .add(p[2].mul(V::splat(n.z)))
}

/// `x - p` lane by lane.
#[inline(always)]
fn minus<V: Lanes>(x: [V; 3], p: DVec3) -> [V; 3] {
    [
        x[0].sub(V::splat(p.x)),
        x[1].sub(V::splat(p.y)),
        x[2].sub(V::splat(p.z)),
    ]
}

/// `|d|²` lane by lane.
#[inline(always)]
fn squared<V: Lanes>(d: [V; 3]) -> V {
    d[0].mul(d[0]).add(d[1].mul(d[1])).add(d[2].mul(d[2]))
}

/// The contact force of `d`'s colliders on the `candidates` lanes of a chunk (positions `x`,
/// velocities `v`, forces before contact `f`), with [`contact_force`], the function of
/// [`super::collide::contact_forces`]: the new forces, and the contact power
/// `-(f_contact)·v` (W) per lane.
#[inline(always)]
pub(super) fn contact_lanes<V: Lanes>(
    d: &Dynamics,
    x: [V; 3],
    v: [V; 3],
    f: [V; 3],
    candidates: u8,
) -> ([V; 3], V) {
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
        if let Some(total) = contact_force(d.colliders, d.contact, xl, vl, fl) {
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
                    &colliders,
                    epsilon,
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
