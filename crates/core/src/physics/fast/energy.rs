//! The kinetic and gravitational terms of Verlet's mechanical energy
//! (`integrators/verlet.rs`, its energy accounting), a block of particles at a time with the
//! CPU's widest vectors.
//!
//! ```text
//! t_i = ½ m_i |(x_i - x_prev,i) / dt|² - m_i g·x_i
//! E   = ((0 + t_0) + t_1) + … + t_{n-1}
//! ```
//! where `m_i` (kg) is particle `i`'s mass, `x_i`, `x_prev,i` (m) its position now and one
//! step earlier, `dt` (s) the step, `g` (m/s²) gravity, `t_i` and `E` (J). The terms do not
//! depend on each other: they are computed for a block of particles first (three divisions
//! each, most of the work, which the compiler then does four or eight at a time with AVX2 or
//! AVX-512), then added in particle order as the textbook loop adds them. The operations are
//! the loop's (no fused multiply-add: Rust does not contract), so the sum is the same bits
//! (tested).

use glam::DVec3;

use super::stencil::Kernel;

/// Particles per block of terms.
const BLOCK: usize = 64;

/// `E` of the module docs: the kinetic energy with the velocities `(x - x_prev) / dt` plus
/// the gravitational energy `-m g·x` (J), summed in particle order.
///
/// # Panics
/// If `mass` or `x_prev` is shorter than `x`.
#[must_use]
pub(crate) fn kinetic_gravity(
    mass: &[f64],
    gravity: DVec3,
    x: &[DVec3],
    x_prev: &[DVec3],
    dt: f64,
) -> f64 {
    let (mass, x_prev) = (&mass[..x.len()], &x_prev[..x.len()]);
    match Kernel::best() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Kernel::best` chooses `Avx512` only on a CPU with AVX-512F.
        Kernel::Avx512 => unsafe { kinetic_gravity_avx512(mass, gravity, x, x_prev, dt) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above, AVX2.
        Kernel::Avx2 => unsafe { kinetic_gravity_avx2(mass, gravity, x, x_prev, dt) },
        _ => blocks(mass, gravity, x, x_prev, dt),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn kinetic_gravity_avx512(
    mass: &[f64],
    gravity: DVec3,
    x: &[DVec3],
    x_prev: &[DVec3],
    dt: f64,
) -> f64 {
    blocks(mass, gravity, x, x_prev, dt)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn kinetic_gravity_avx2(
    mass: &[f64],
    gravity: DVec3,
    x: &[DVec3],
    x_prev: &[DVec3],
    dt: f64,
) -> f64 {
    blocks(mass, gravity, x, x_prev, dt)
}

/// The terms of a block, then their sum (module docs).
#[inline(always)]
fn blocks(mass: &[f64], gravity: DVec3, x: &[DVec3], x_prev: &[DVec3], dt: f64) -> f64 {
    let mut e = 0.0;
    let mut terms = [0.0; BLOCK];
    for ((m, x), x_prev) in mass
        .chunks(BLOCK)
        .zip(x.chunks(BLOCK))
        .zip(x_prev.chunks(BLOCK))
    {
        let terms = &mut terms[..x.len()];
        for (((t, &m), &x), &x_prev) in terms.iter_mut().zip(m).zip(x).zip(x_prev) {
            let v = (x - x_prev) / dt;
            *t = 0.5 * m * v.length_squared() - m * gravity.dot(x);
        }
        for t in terms.iter() {
            e += t;
        }
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The loop of the module docs, one particle after the other.
    fn textbook(mass: &[f64], gravity: DVec3, x: &[DVec3], x_prev: &[DVec3], dt: f64) -> f64 {
        let mut e = 0.0;
        for i in 0..x.len() {
            let v = (x[i] - x_prev[i]) / dt;
            e += 0.5 * mass[i] * v.length_squared() - mass[i] * gravity.dot(x[i]);
        }
        e
    }

    #[test]
    fn blocks_sum_the_textbook_loop_bit_for_bit() {
        let mut rng = crate::random::XorShift64Star::new(7);
        let mut next = || rng.unit() - 0.5;
        let gravity = DVec3::new(0.1, -9.81, 0.3);
        // Sizes below, at and above a vector and a block, not multiples of either.
        for n in [0, 1, 3, 8, 13, 64, 65, 150] {
            let x: Vec<DVec3> = (0..n).map(|_| DVec3::new(next(), next(), next())).collect();
            let x_prev: Vec<DVec3> = (x.iter())
                .map(|p| *p + 1e-3 * DVec3::new(next(), next(), next()))
                .collect();
            let mass: Vec<f64> = (0..n).map(|_| 0.5 + next()).collect();
            for dt in [1e-3, 1.0 / 60.0, 0.7] {
                let want = textbook(&mass, gravity, &x, &x_prev, dt);
                assert_eq!(
                    blocks(&mass, gravity, &x, &x_prev, dt).to_bits(),
                    want.to_bits()
                );
                assert_eq!(
                    kinetic_gravity(&mass, gravity, &x, &x_prev, dt).to_bits(),
                    want.to_bits(),
                    "n = {n}, dt = {dt}"
                );
                #[cfg(target_arch = "x86_64")]
                for (kernel, f) in [
                    (
                        Kernel::Avx2,
                        kinetic_gravity_avx2 as unsafe fn(_, _, _, _, _) -> f64,
                    ),
                    (Kernel::Avx512, kinetic_gravity_avx512),
                ] {
                    if kernel.is_available() {
                        // SAFETY: the CPU has the kernel's instructions (checked).
                        let got = unsafe { f(&mass, gravity, &x, &x_prev, dt) };
                        assert_eq!(got.to_bits(), want.to_bits(), "{kernel:?}, n = {n}");
                    }
                }
            }
        }
    }
}
