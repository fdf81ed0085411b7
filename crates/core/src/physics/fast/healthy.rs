//! The divergence check's quick pass (`physics/diverge.rs`, run after every single step):
//! whether a state is certainly healthy, with the CPU's widest vectors (the positions by
//! `fast::energy::all_below`, the speeds by a count the compiler vectorises).
//!
//! ```text
//! healthy  ⇔  for every particle i:  x_i finite  and  |v_i|² ≤ v2_max
//! |v|² = (v_x v_x + v_y v_y) + v_z v_z            (as `DVec3::length_squared` adds it)
//! ```
//! where `x_i` (m) are the positions, `v_i` (m/s) the velocities and `v2_max` (m²/s²) the bound.
//! A NaN anywhere is not healthy. The same answer as the loop over particles (tested).

use glam::DVec3;

use super::energy::all_below;

/// True when every position is finite and every `|v|²` at most `v2_max` (m²/s²).
///
/// # Panics
/// If `x` and `v` differ in length.
#[must_use]
pub(crate) fn healthy(x: &[DVec3], v: &[DVec3], v2_max: f64) -> bool {
    assert_eq!(x.len(), v.len(), "a velocity per position");
    // Finite: below +∞ in magnitude (`fast::energy::all_below`, which NaN fails too).
    all_below(x, f64::INFINITY) && speeds_within(v, v2_max)
}

// Every `|v|² ≤ v2_max` (false where one is NaN), with the CPU's widest vectors.
on_lanes!(speeds_within, plain within, (v: &[DVec3], v2_max: f64) -> bool);

/// The count of speeds not within the bound is zero (a count, not a search, so the compiler
/// tests many particles per instruction).
#[inline(always)]
fn within(v: &[DVec3], v2_max: f64) -> bool {
    // Outside: above the bound, or NaN on either side (as `<=` answers).
    let outside = |v: &DVec3| {
        let s = v.length_squared();
        usize::from(s > v2_max || s.is_nan() || v2_max.is_nan())
    };
    v.iter().map(outside).sum::<usize>() == 0
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
    /// same answer as the loop, with the CPU's widest vectors and portably.
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
                assert_eq!(
                    all_below(x, f64::INFINITY) && within(v, bound),
                    expected,
                    "{n}, portable"
                );
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
