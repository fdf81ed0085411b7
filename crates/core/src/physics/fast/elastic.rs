//! The elastic term of the mechanical energy (`physics/energy.rs`: the studies' confirmation and
//! usable-dt runs look at the energy every few steps, `run` and the lessons at every sample), a
//! block of springs at a time with the CPU's widest vectors.
//!
//! ```text
//! d_s = x_b - x_a                                       (spring s from particle a to b)
//! t_s = ½ k_s (|d_s| - L_s)²
//! E   = ((-0 + t_0) + t_1) + … + t_{m-1}
//! ```
//! where `x` (m) are the positions, `k_s` (N/m) the spring's stiffness, `L_s` (m) its rest
//! length, `t_s` and `E` (J); `-0` is the start of Rust's `Iterator::sum` of floats. The terms
//! do not depend on each other: a block's differences, stiffnesses and rest lengths are gathered
//! first, the terms computed for the whole block (the compiler does them, square roots
//! included, four or eight at a time with AVX2 or AVX-512), then added in spring order as the
//! textbook sum adds them, while the next block is gathered (the additions are one chain; the
//! gathering fills the time between them; `x_a` is loaded once for the run of springs that
//! start at `a`, as a lattice lists them). The operations are `Spring::energy`'s (glam's
//! `length` as `√(x² + y² + z²)`, a correctly rounded square root in every lane, no fused
//! multiply-add: Rust does not contract), so the sum is the same bits (tested).

use glam::DVec3;

use super::stencil::Kernel;
use crate::physics::springs::Spring;

/// Springs per block of terms.
const BLOCK: usize = 64;

/// `E` of the module docs: `Σ_s ½ k_s (|x_b - x_a| - L_s)²` in spring order (J), the same bits
/// as `springs.iter().map(|s| s.energy(x)).sum()`.
///
/// # Panics
/// If a spring's end is not an index of `x`.
#[must_use]
pub(crate) fn elastic(springs: &[Spring], x: &[DVec3]) -> f64 {
    elastic_on(Kernel::best(), springs, x)
}

on_lanes!(elastic_on(kernel), plain blocks, (springs: &[Spring], x: &[DVec3]) -> f64);

/// A block's gathered numbers, one array each: the differences' components, the stiffnesses and
/// the rest lengths.
struct Gathered {
    d: [[f64; BLOCK]; 3],
    k: [f64; BLOCK],
    rest: [f64; BLOCK],
}

/// Gathers spring `j` of a block.
#[inline(always)]
fn gather(g: &mut Gathered, j: usize, s: &Spring, x: &[DVec3]) {
    let d = x[s.b as usize] - x[s.a as usize];
    g.d[0][j] = d.x;
    g.d[1][j] = d.y;
    g.d[2][j] = d.z;
    g.k[j] = s.stiffness;
    g.rest[j] = s.rest_length;
}

/// The terms `t_s` of the first `m` springs gathered in `g`. A function, not a closure: a
/// closure does not take its caller's target features.
#[inline(always)]
fn terms_of(g: &Gathered, m: usize, terms: &mut [f64; BLOCK]) {
    let [dx, dy, dz] = &g.d;
    for j in 0..m {
        let length = (dx[j] * dx[j] + dy[j] * dy[j] + dz[j] * dz[j]).sqrt();
        let stretch = length - g.rest[j];
        terms[j] = 0.5 * g.k[j] * stretch * stretch;
    }
}

/// The blocks' terms, then their sum (module docs): while the sum runs through a block's
/// terms, the same loop gathers the next block.
#[inline(always)]
fn blocks(springs: &[Spring], x: &[DVec3]) -> f64 {
    let mut e: f64 = std::iter::empty::<f64>().sum();
    let mut g = Gathered {
        d: [[0.0; BLOCK]; 3],
        k: [0.0; BLOCK],
        rest: [0.0; BLOCK],
    };
    let mut terms = [0.0; BLOCK];
    let mut chunks = springs.chunks(BLOCK);
    let Some(first) = chunks.next() else {
        return e;
    };
    for (j, s) in first.iter().enumerate() {
        gather(&mut g, j, s, x);
    }
    terms_of(&g, first.len(), &mut terms);
    // Every block but the last is full.
    let mut ready = first.len();
    // x_a is kept while consecutive springs start at it (a lattice's springs of one particle
    // come one after another).
    let (mut held, mut x_a) = (u32::MAX, DVec3::ZERO);
    for chunk in chunks {
        for (j, s) in chunk.iter().enumerate() {
            if s.a != held {
                held = s.a;
                x_a = x[s.a as usize];
            }
            let d = x[s.b as usize] - x_a;
            g.d[0][j] = d.x;
            g.d[1][j] = d.y;
            g.d[2][j] = d.z;
            g.k[j] = s.stiffness;
            g.rest[j] = s.rest_length;
            e += terms[j];
        }
        for t in &terms[chunk.len()..ready] {
            e += t;
        }
        terms_of(&g, chunk.len(), &mut terms);
        ready = chunk.len();
    }
    for t in &terms[..ready] {
        e += t;
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::springs::SpringKind;

    #[test]
    fn blocks_sum_the_textbook_loop_bit_for_bit() {
        let mut rng = crate::random::XorShift64Star::new(11);
        let mut next = || rng.unit() - 0.5;
        let n = 41;
        let x: Vec<DVec3> = (0..n).map(|_| DVec3::new(next(), next(), next())).collect();
        // Counts below, at and above a vector and a block, not multiples of either; a spring
        // of zero length (both ends one particle) and one of zero stiffness among them.
        // Runs of springs from one particle (as a lattice lists them) and springs from scattered
        // ones.
        for (count, run) in [(0, 1), (1, 1), (7, 1), (64, 1), (65, 3), (129, 1), (300, 3)] {
            let springs: Vec<Spring> = (0..count)
                .map(|s| Spring {
                    a: ((s / run * 7 + 3) % n) as u32,
                    b: if s == 5 { 3 } else { ((s * 13 + 5) % n) as u32 },
                    rest_length: 0.3 + next(),
                    stiffness: if s == 2 { 0.0 } else { 1e3 * (1.0 + next()) },
                    damping: 0.0,
                    kind: SpringKind::Struct,
                })
                .collect();
            let want: f64 = springs.iter().map(|s| s.energy(&x)).sum();
            assert_eq!(blocks(&springs, &x).to_bits(), want.to_bits(), "{count}");
            assert_eq!(elastic(&springs, &x).to_bits(), want.to_bits(), "{count}");
            #[cfg(target_arch = "x86_64")]
            for kernel in [Kernel::Avx2, Kernel::Avx512] {
                if kernel.is_available() {
                    let got = elastic_on(kernel, &springs, &x);
                    assert_eq!(got.to_bits(), want.to_bits(), "{kernel:?}, {count}");
                }
            }
        }
    }
}
