//! The kinetic energy the collision response's budget takes its payment from
//! (`collide/budget.rs`, `take_kinetic_with_spheres`), a block of particles at a time with the
//! CPU's widest vectors.
//!
//! ```text
//! t_i = ½ |v_i|² / w_i                 for every free particle (w_i ≠ 0)
//! K   = Σ_free t_i                     in particle order, as `Iterator::sum` adds them
//! ```
//! where `w_i` (1/kg) is particle `i`'s inverse mass (zero for a pinned one, which is left
//! out), `v_i` (m/s) its velocity, `t_i` and `K` (J). The terms do not depend on each other:
//! a block of them is computed first (a division each, most of the work, which the compiler
//! then does eight at a time with AVX-512), then the free ones are added in order as the
//! textbook iterator adds them (`.sum()`: the same additions from the same start, so the same
//! bits; tested).

use glam::DVec3;

/// Particles per block of terms.
const BLOCK: usize = 64;

/// `K` of the module docs: `Σ ½ |v_i|² / w_i` over the free particles (`inv_mass[i] ≠ 0`),
/// bit for bit `inv_mass.iter().zip(v).filter(|(w, _)| **w != 0.0).map(|(w, v)| 0.5 *
/// v.length_squared() / w).sum()`.
pub(crate) fn kinetic_of_free(inv_mass: &[f64], v: &[DVec3]) -> f64 {
    let n = inv_mass.len().min(v.len());
    kinetic_best(&inv_mass[..n], &v[..n])
}

on_lanes!(kinetic_best, plain kinetic, (inv_mass: &[f64], v: &[DVec3]) -> f64);

/// The terms a block at a time (every particle's, a pinned one's thrown away), then the free
/// ones added in order to the start of `.sum()` (the sum of nothing): `.sum()`'s additions.
#[inline(always)]
fn kinetic(inv_mass: &[f64], v: &[DVec3]) -> f64 {
    let mut sum: f64 = std::iter::empty::<f64>().sum();
    let mut terms = [0.0; BLOCK];
    for (w, v) in inv_mass.chunks(BLOCK).zip(v.chunks(BLOCK)) {
        let terms = &mut terms[..w.len()];
        for ((t, &w), v) in terms.iter_mut().zip(w).zip(v) {
            *t = 0.5 * v.length_squared() / w;
        }
        for (t, w) in terms.iter().zip(w) {
            if *w != 0.0 {
                sum += t;
            }
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The textbook iterator's sum, bit for bit: empty, all pinned, one free, counts around
    /// the block, pinned particles anywhere, velocities of ±0, huge, infinite and NaN.
    #[test]
    fn the_kinetic_energy_of_the_free_particles_is_the_iterators_sum() {
        let mut generator = crate::random::XorShift64Star::new(0x2545_f491_4f6c_dd1du64);
        let mut random = move || generator.unit();
        for n in [0, 1, 2, 7, 63, 64, 65, 130, 625] {
            for round in 0..6 {
                let inv_mass: Vec<f64> = (0..n)
                    .map(|i| match round {
                        0 => 0.0,
                        1 if i != n / 2 => 0.0,
                        _ if random() < 0.1 => 0.0,
                        _ => 0.1 + 10.0 * random(),
                    })
                    .collect();
                let mut v: Vec<DVec3> = (0..n)
                    .map(|_| DVec3::new(random(), random(), random()) - 0.5)
                    .collect();
                if n > 5 && round >= 3 {
                    v[1] = DVec3::new(-0.0, 0.0, -0.0);
                    v[3] = DVec3::splat([1e200, f64::INFINITY, f64::NAN][round - 3]);
                }
                let want: f64 = (inv_mass.iter().zip(&v))
                    .filter(|(w, _)| **w != 0.0)
                    .map(|(w, v)| 0.5 * v.length_squared() / w)
                    .sum();
                let got = kinetic_of_free(&inv_mass, &v);
                assert!(
                    got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                    "{n} particles, round {round}: {got} vs {want}"
                );
                assert_eq!(got.to_bits(), kinetic(&inv_mass, &v).to_bits());
            }
        }
    }
}
