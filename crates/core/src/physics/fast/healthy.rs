//! The divergence check's quick pass (`physics/diverge.rs`, run after every single step):
//! whether a state is certainly healthy, eight particles at a time with the CPU's widest
//! vectors.
//!
//! ```text
//! healthy  ⇔  for every particle i:  x_i finite  and  |v_i|² ≤ v2_max
//! |v|² = (v_x v_x + v_y v_y) + v_z v_z            (as `DVec3::length_squared` adds it)
//! ```
//! where `x_i` (m) are the positions, `v_i` (m/s) the velocities and `v2_max` (m²/s²) the bound.
//! A NaN anywhere is not healthy. The same answer as the loop over particles (tested).

use glam::DVec3;

#[cfg(target_arch = "x86_64")]
use super::lanes::{Avx2, Avx512};
use super::lanes::{LANES, Lanes, Plain, first_lanes, load_chunk};

/// True when every position is finite and every `|v|²` at most `v2_max` (m²/s²).
///
/// # Panics
/// If `x` and `v` differ in length.
#[must_use]
pub(crate) fn healthy(x: &[DVec3], v: &[DVec3], v2_max: f64) -> bool {
    assert_eq!(x.len(), v.len(), "a velocity per position");
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked above).
            return unsafe { healthy_avx512(x, v, v2_max) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked above).
            return unsafe { healthy_avx2(x, v, v2_max) };
        }
    }
    healthy_lanes::<Plain>(x, v, v2_max)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn healthy_avx512(x: &[DVec3], v: &[DVec3], v2_max: f64) -> bool {
    healthy_lanes::<Avx512>(x, v, v2_max)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn healthy_avx2(x: &[DVec3], v: &[DVec3], v2_max: f64) -> bool {
    healthy_lanes::<Avx2>(x, v, v2_max)
}

/// [`healthy`] with lanes `V`: the lanes that fail are gathered over the whole state (no
/// branch per chunk); a state is seldom unhealthy.
#[inline(always)]
fn healthy_lanes<V: Lanes>(x: &[DVec3], v: &[DVec3], v2_max: f64) -> bool {
    let bound = V::splat(v2_max);
    let mut bad = 0u8;
    for (xs, vs) in x.chunks(LANES).zip(v.chunks(LANES)) {
        let count = xs.len();
        let p = load_chunk::<V>(xs, count);
        let w = load_chunk::<V>(vs, count);
        // x - x is 0 for a finite x, NaN for an infinite or NaN one.
        let not_finite =
            p[0].sub(p[0]).nan_lanes() | p[1].sub(p[1]).nan_lanes() | p[2].sub(p[2]).nan_lanes();
        let v2 = w[0].mul(w[0]).add(w[1].mul(w[1])).add(w[2].mul(w[2]));
        // Not `v2 ≤ bound`: above it, or NaN.
        let fast = bound.less_than(v2) | v2.nan_lanes();
        bad |= (not_finite | fast) & first_lanes(count);
    }
    bad == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The loop's answer: `x.is_finite()` and `|v|² ≤ v2_max` for every particle.
    fn textbook(x: &[DVec3], v: &[DVec3], v2_max: f64) -> bool {
        (x.iter().zip(v)).all(|(x, v)| x.is_finite() && v.length_squared() <= v2_max)
    }

    /// Healthy states of every length from 0 to 40, then each particle in turn given an
    /// infinite or NaN coordinate, or a speed at, just above and just below the bound: the
    /// same answer as the loop, with every instruction set this CPU has.
    #[test]
    fn healthy_is_the_loop() {
        let bound = 0.999e6;
        let (mut healthy_seen, mut sick_seen) = (0, 0);
        for n in 0..40 {
            let x: Vec<DVec3> = (0..n)
                .map(|i| DVec3::new(i as f64, -0.5 * i as f64, 1e10))
                .collect();
            let v: Vec<DVec3> = (0..n)
                .map(|i| DVec3::new(0.1 * i as f64, -3.0, 2.0))
                .collect();
            let check = |x: &[DVec3], v: &[DVec3]| {
                let expected = textbook(x, v, bound);
                assert_eq!(healthy(x, v, bound), expected, "{n} particles");
                assert_eq!(healthy_lanes::<Plain>(x, v, bound), expected, "{n}, plain");
                expected
            };
            assert!(check(&x, &v));
            healthy_seen += 1;
            let edge = bound.sqrt();
            for i in 0..n {
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    for c in 0..3 {
                        let mut y = x.clone();
                        y[i][c] = bad;
                        assert!(!check(&y, &v));
                        let mut w = v.clone();
                        w[i][c] = bad;
                        assert!(!check(&x, &w));
                        sick_seen += 2;
                    }
                }
                for speed in [edge, edge * (1.0 + 1e-15), edge * (1.0 - 1e-15), 1e3, 1e200] {
                    let mut w = v.clone();
                    w[i] = DVec3::new(0.0, speed, 0.0);
                    if check(&x, &w) {
                        healthy_seen += 1;
                    } else {
                        sick_seen += 1;
                    }
                }
            }
        }
        assert!(healthy_seen > 100 && sick_seen > 100);
    }
}
