//! The collision response's broad phase point by point (`collide/response.rs`, `near_any`):
//! which of up to 64 points a collider's bounds ([`Broad`], `collide/geometry.rs`) do not rule
//! out, eight points at a time with the CPU's widest vectors. The tests are
//! [`Broad::may_touch`]'s, with the same operations in the same order (no fused multiply-add),
//! so the same answers, NaN included (tested):
//!
//! ```text
//! plane       φ = (x - p)·n < φ_max                  or NaN
//! sphere      |x - c|² < d2_max                      or NaN
//! bowl        (|x - c|² ≥ d2_min or NaN)  and  (y ≤ rim or y NaN)
//! hole plane  (h < h_max or NaN)  and  (h ≥ h_floor  or  ρ² ≥ rho2_min  or  ρ² NaN)
//!             h = (x - p)·n,  q = x - c_hole,  ρ² = |q - (q·n) n|²
//! ```
//! where `x` (m) is the point, `c` (m) the sphere's or bowl's centre, `d2_max`, `d2_min` (m²)
//! the squared bounds, `rim` (m) the bowl's rim height, `p` and `n` a point of the floor and its
//! unit normal (a plane's too, with `φ_max` (m) its height bound), `c_hole` (m) the hole's
//! centre and `ρ` (m) the distance from the hole's axis. (`bounds::plane_bits` is the plane's
//! test with the calm test, for the summaries of parts.)
//!
//! Why: a body resting in the 2023 bowl (`jelly-bowl`) has every tile near both colliders, so
//! the response tests all its particles against both after every step; one point at a time
//! that was about a tenth of such a run (measured, one thread).

use glam::DVec3;

#[cfg(target_arch = "x86_64")]
use super::lanes::{Avx2, Avx512};
use super::lanes::{LANES, Lanes, Plain, first_lanes, load_chunk};
use crate::physics::collide::Broad;

/// Bit `k` set for `xs[k]` (at most 64 points) when `broad` does not rule it out:
/// [`Broad::may_touch`] of each point, eight at a time.
///
/// # Panics
/// If `xs` holds more than 64 points.
#[must_use]
pub(crate) fn marks(broad: &Broad, xs: &[DVec3]) -> u64 {
    assert!(xs.len() <= 64, "at most 64 points");
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked above).
            return unsafe { marks_avx512(broad, xs) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked above).
            return unsafe { marks_avx2(broad, xs) };
        }
    }
    marks_lanes::<Plain>(broad, xs)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn marks_avx512(broad: &Broad, xs: &[DVec3]) -> u64 {
    marks_lanes::<Avx512>(broad, xs)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn marks_avx2(broad: &Broad, xs: &[DVec3]) -> u64 {
    marks_lanes::<Avx2>(broad, xs)
}

/// [`marks`] with lanes `V`: [`broad_lanes`] chunk after chunk.
#[inline(always)]
fn marks_lanes<V: Lanes>(broad: &Broad, xs: &[DVec3]) -> u64 {
    let mut bits = 0u64;
    for (k, chunk) in xs.chunks(LANES).enumerate() {
        let count = chunk.len();
        let mask = broad_lanes(broad, load_chunk::<V>(chunk, count));
        bits |= u64::from(mask & first_lanes(count)) << (LANES * k);
    }
    bits
}

/// Bit `l` set when `broad` does not rule out the point in lane `l` of `x` (m):
/// [`Broad::may_touch`] of each lane, the same operations and answers (module docs).
#[inline(always)]
pub(crate) fn broad_lanes<V: Lanes>(broad: &Broad, x: [V; 3]) -> u8 {
    match *broad {
        Broad::Plane {
            point,
            normal,
            phi_max,
        } => {
            // `φ < φ_max or φ NaN`: with a NaN bound, the NaN lanes only (as the point test).
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
            let d2 = squared(minus(x, center));
            at_least_or_nan(d2, d2_min) & at_most_or_nan(x[1], rim)
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
            let rho2 = squared(radial(x, hole_center, normal));
            below_or_nan(h, h_max) & (at_least(h, h_floor) | at_least_or_nan(rho2, rho2_min))
        }
    }
}

// The comparisons with a bound `b` (a number of the bounds, never a lane): one compare each
// when `b` is a number, as `>=`, `<=` and `is_nan` answer with NaN on either side.

/// `not a ≥ b` lane by lane: `a < b`, or either is NaN.
#[inline(always)]
fn below_or_nan<V: Lanes>(a: V, b: f64) -> u8 {
    if b.is_nan() {
        !0
    } else {
        a.less_than(V::splat(b)) | a.nan_lanes()
    }
}

/// `a ≥ b` lane by lane (false for a NaN lane).
#[inline(always)]
fn at_least<V: Lanes>(a: V, b: f64) -> u8 {
    if b.is_nan() {
        0
    } else {
        !a.less_than(V::splat(b)) & !a.nan_lanes()
    }
}

/// `a ≥ b or a is NaN` lane by lane.
#[inline(always)]
fn at_least_or_nan<V: Lanes>(a: V, b: f64) -> u8 {
    if b.is_nan() {
        a.nan_lanes()
    } else {
        !a.less_than(V::splat(b))
    }
}

/// `a ≤ b or a is NaN` lane by lane.
#[inline(always)]
fn at_most_or_nan<V: Lanes>(a: V, b: f64) -> u8 {
    if b.is_nan() {
        a.nan_lanes()
    } else {
        !V::splat(b).less_than(a)
    }
}

/// `p · n` lane by lane, as `DVec3::dot` adds it: `(x n_x + y n_y) + z n_z`.
#[inline(always)]
pub(crate) fn dot<V: Lanes>(p: [V; 3], n: DVec3) -> V {
    p[0].mul(V::splat(n.x))
        .add(p[1].mul(V::splat(n.y)))
        .add(p[2].mul(V::splat(n.z)))
}

/// The offset of `x` from the axis through `c` along the unit normal `n`, lane by lane:
/// `q - (q·n) n` with `q = x - c`, as glam computes `q - q.dot(n) * n`.
#[inline(always)]
pub(crate) fn radial<V: Lanes>(x: [V; 3], c: DVec3, n: DVec3) -> [V; 3] {
    let q = minus(x, c);
    let along = dot(q, n);
    [
        q[0].sub(along.mul(V::splat(n.x))),
        q[1].sub(along.mul(V::splat(n.y))),
        q[2].sub(along.mul(V::splat(n.z))),
    ]
}

/// `x - p` lane by lane.
#[inline(always)]
pub(crate) fn minus<V: Lanes>(x: [V; 3], p: DVec3) -> [V; 3] {
    [
        x[0].sub(V::splat(p.x)),
        x[1].sub(V::splat(p.y)),
        x[2].sub(V::splat(p.z)),
    ]
}

/// `|d|²` lane by lane, as `DVec3::length_squared` adds it.
#[inline(always)]
pub(crate) fn squared<V: Lanes>(d: [V; 3]) -> V {
    d[0].mul(d[0]).add(d[1].mul(d[1])).add(d[2].mul(d[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::collide::Collider;

    /// Every kind of collider, its bounds at two contact bands, on points around and on its
    /// surfaces (a grid with points a hair from each bound), NaN and infinite coordinates, and
    /// every count from 1 to 64: the marks are `Broad::may_touch` of each point, bit for bit,
    /// on every instruction set this CPU has.
    #[test]
    fn the_marks_are_the_point_tests() {
        let colliders = [
            Collider::Plane {
                point: DVec3::new(0.1, -0.5, 0.2),
                normal: DVec3::new(0.3, 1.0, -0.2).normalize(),
            },
            Collider::Sphere {
                center: DVec3::new(0.5, 0.0, -0.25),
                radius: 1.5,
            },
            Collider::Bowl {
                center: DVec3::new(0.0, 2.0, 0.5),
                radius: 2.0,
                rim_height: 1.5,
            },
            Collider::HolePlane {
                point: DVec3::new(0.0, 0.0, 0.0),
                normal: DVec3::Y,
                hole_center: DVec3::new(1.0, 0.0, 1.0),
                hole_radius: 1.5,
            },
            Collider::HolePlane {
                point: DVec3::new(0.0, 0.25, 0.0),
                normal: DVec3::new(0.0, 1.0, 1.0).normalize(),
                hole_center: DVec3::new(0.5, 0.25, -0.25),
                hole_radius: 1.0,
            },
        ];
        let mut points = Vec::new();
        for i in -12..=12 {
            for j in -12..=12 {
                for k in [-1, 0, 1] {
                    let s = 0.25 * (1.0 + 1e-9 * f64::from(k));
                    points.push(DVec3::new(
                        f64::from(i) * s,
                        f64::from(j) * s,
                        f64::from(i - j) * 0.5 * s,
                    ));
                }
            }
        }
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            points.push(DVec3::new(bad, 0.0, 0.0));
            points.push(DVec3::new(0.0, bad, 0.0));
            points.push(DVec3::new(0.5, 0.5, bad));
        }
        let mut broads: Vec<Broad> = (colliders.iter())
            .flat_map(|c| [c.broad(0.0), c.broad(0.01)])
            .collect();
        // Bounds that are NaN (which `Collider::broad` never makes: it clamps): the
        // comparisons' own answers all the same.
        let nan = f64::NAN;
        for (d2, rim) in [(nan, 1.0), (2.0, nan)] {
            broads.push(Broad::Bowl {
                center: DVec3::ZERO,
                d2_min: d2,
                rim,
            });
        }
        for (h_max, h_floor, rho2_min) in [(nan, 0.0, 1.0), (0.5, nan, 1.0), (0.5, -0.5, nan)] {
            broads.push(Broad::HolePlane {
                point: DVec3::ZERO,
                normal: DVec3::Y,
                hole_center: DVec3::ZERO,
                h_max,
                h_floor,
                rho2_min,
            });
        }
        let mut checked = 0;
        let (mut marked, mut left) = (0, 0);
        for broad in broads {
            {
                for count in 1..=64 {
                    for xs in points.chunks(count) {
                        let expected = (xs.iter().enumerate())
                            .fold(0u64, |b, (k, p)| b | (u64::from(broad.may_touch(*p)) << k));
                        assert_eq!(marks(&broad, xs), expected, "{broad:?}, {count} points");
                        assert_eq!(
                            marks_lanes::<Plain>(&broad, xs),
                            expected,
                            "{broad:?}, {count} points, plain lanes"
                        );
                        marked += expected.count_ones();
                        left += xs.len() as u32 - expected.count_ones();
                        checked += 1;
                    }
                }
            }
        }
        // Both answers occur (the test can fail either way).
        assert!(
            checked > 10_000 && marked > 1_000 && left > 1_000,
            "{marked} {left}"
        );
    }
}
