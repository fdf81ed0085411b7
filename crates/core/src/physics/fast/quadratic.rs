//! The stability study's sum over springs (`springlab::study::linear`: the elastic energy of a
//! perturbation, once per power step of every linear probe), a block of springs at a time with
//! the CPU's widest vectors.
//!
//! ```text
//! d_s = u_b - u_a                                       (spring s from particle a to b)
//! t_s = ½ d_s·(K_s d_s)
//! E   = ((e + t_0) + t_1) + … + t_{m-1}
//! K_s d = (K_s e_x) d_x + (K_s e_y) d_y + (K_s e_z) d_z  (glam's column order)
//! ```
//! where `K_s` (N/m) is the spring's symmetric 3×3 stiffness block, given by its six numbers
//! `(xx, xy, xz, yy, yz, zz)` in six arrays, `u` (m, or any vector per particle) the
//! perturbation, `t_s` and `E` (J, or J per s² for a scaled `u`). The terms of one spring do
//! not depend on another's: a block's differences are gathered first, the terms computed for
//! the whole block (the compiler does them four or eight at a time with AVX2 or AVX-512), then
//! added in spring order as the textbook loop adds them, while the next block's differences
//! are gathered (the additions are one chain, one after the other; the gathering fills the
//! time between them). The operations are the loop's, in glam's order (`DMat3 * DVec3` column by column,
//! `dot` as `x + y + z`), without fused multiply-add (Rust does not contract): the same bits
//! (tested).
//!
//! Beside it, the power iterations' normalisation `v ← v / s` of every vector ([`divide`]),
//! several divisions at a time (the same bits: a division is correctly rounded in every lane).

use glam::DVec3;

use super::stencil::Kernel;

/// Springs per block of terms.
const BLOCK: usize = 64;

/// A spring's six numbers of `K_s` from the six arrays.
pub type SymBlocks<'a> = [&'a [f64]; 6];

/// `E` of the module docs: `e` plus `½ d_s·K_s d_s` of every spring, added in spring order.
///
/// # Panics
/// If an array of `k` is shorter than `ends`, or an end is not an index of `u`.
#[must_use]
pub fn spring_energy(e: f64, ends: &[[u32; 2]], k: SymBlocks, u: &[DVec3]) -> f64 {
    let m = ends.len();
    let k = k.map(|a| &a[..m]);
    match Kernel::best() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Kernel::best` chooses `Avx512` only on a CPU with AVX-512F.
        Kernel::Avx512 => unsafe { energy_avx512(e, ends, k, u) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above, AVX2.
        Kernel::Avx2 => unsafe { energy_avx2(e, ends, k, u) },
        _ => energy_blocks(e, ends, k, u),
    }
}

/// `v ← v / by` for every vector of `values`, component by component (as glam's `DVec3 / f64`):
/// the power iterations' normalisations (`springlab::study::linear`, `springlab::study::modes`).
/// The divisions do not depend on each other, so the compiler does them eight or four at a time
/// with AVX-512 or AVX2 (a division is correctly rounded in every lane: the same bits, tested);
/// one at a time they were about a fifth of a linear probe's bookkeeping.
pub fn divide(values: &mut [DVec3], by: f64) {
    match Kernel::best() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Kernel::best` chooses `Avx512` only on a CPU with AVX-512F.
        Kernel::Avx512 => unsafe { divide_avx512(values, by) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above, AVX2.
        Kernel::Avx2 => unsafe { divide_avx2(values, by) },
        _ => divide_each(values, by),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn divide_avx512(values: &mut [DVec3], by: f64) {
    divide_each(values, by);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn divide_avx2(values: &mut [DVec3], by: f64) {
    divide_each(values, by);
}

#[inline(always)]
fn divide_each(values: &mut [DVec3], by: f64) {
    for v in values {
        *v /= by;
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn energy_avx512(e: f64, ends: &[[u32; 2]], k: SymBlocks, u: &[DVec3]) -> f64 {
    energy_blocks(e, ends, k, u)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn energy_avx2(e: f64, ends: &[[u32; 2]], k: SymBlocks, u: &[DVec3]) -> f64 {
    energy_blocks(e, ends, k, u)
}

/// A block's differences `u_to - u_from`, one array per component: `d_s = u_b - u_a` (`from`
/// the spring's first end), or `u_a - u_b`.
#[inline(always)]
fn gather(ends: &[[u32; 2]], u: &[DVec3], from: usize, d: &mut [[f64; BLOCK]; 3]) {
    for (j, ends) in ends.iter().enumerate() {
        let (from, to) = (ends[from] as usize, ends[1 - from] as usize);
        let v = u[to] - u[from];
        d[0][j] = v.x;
        d[1][j] = v.y;
        d[2][j] = v.z;
    }
}

/// `f_s = K_s d_s` of a block (`k` the block's six arrays), in glam's order.
#[inline(always)]
fn forces(k: [&[f64]; 6], d: &[[f64; BLOCK]; 3], f: &mut [[f64; BLOCK]; 3]) {
    let m = k[0].len();
    let [k0, k1, k2, k3, k4, k5] = k.map(|a| &a[..m]);
    for j in 0..m {
        let (x, y, z) = (d[0][j], d[1][j], d[2][j]);
        f[0][j] = k0[j] * x + k1[j] * y + k2[j] * z;
        f[1][j] = k1[j] * x + k3[j] * y + k4[j] * z;
        f[2][j] = k2[j] * x + k4[j] * y + k5[j] * z;
    }
}

/// The blocks' terms, then their sum (module docs). The sum is a chain of dependent additions,
/// one per spring: while it runs through a block's terms, the same loop gathers the next
/// block's differences, so the two overlap.
#[inline(always)]
fn energy_blocks(mut e: f64, ends: &[[u32; 2]], k: SymBlocks, u: &[DVec3]) -> f64 {
    let mut d = [[0.0; BLOCK]; 3];
    let mut f = [[0.0; BLOCK]; 3];
    let mut terms = [0.0; BLOCK];
    let mut blocks = (0..).step_by(BLOCK).zip(ends.chunks(BLOCK));
    let Some((_, first)) = blocks.next() else {
        return e;
    };
    gather(first, u, 0, &mut d);
    terms_of(k, 0, first.len(), &d, &mut f, &mut terms);
    // Every block but the last is full.
    let mut ready = first.len();
    for (start, ends) in blocks {
        for (j, ends) in ends.iter().enumerate() {
            let v = u[ends[1] as usize] - u[ends[0] as usize];
            d[0][j] = v.x;
            d[1][j] = v.y;
            d[2][j] = v.z;
            e += terms[j];
        }
        for t in &terms[ends.len()..ready] {
            e += t;
        }
        terms_of(k, start, ends.len(), &d, &mut f, &mut terms);
        ready = ends.len();
    }
    for t in &terms[..ready] {
        e += t;
    }
    e
}

/// The terms `t_s` of the `m` springs from `start` (their differences gathered in `d`; `f` is
/// scratch). A function, not a closure: a closure does not take its caller's target features.
#[inline(always)]
fn terms_of(
    k: SymBlocks,
    start: usize,
    m: usize,
    d: &[[f64; BLOCK]; 3],
    f: &mut [[f64; BLOCK]; 3],
    terms: &mut [f64; BLOCK],
) {
    forces(
        [
            &k[0][start..start + m],
            &k[1][start..start + m],
            &k[2][start..start + m],
            &k[3][start..start + m],
            &k[4][start..start + m],
            &k[5][start..start + m],
        ],
        d,
        f,
    );
    for (j, t) in terms[..m].iter_mut().enumerate() {
        *t = 0.5 * (d[0][j] * f[0][j] + d[1][j] * f[1][j] + d[2][j] * f[2][j]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat3;

    /// Random symmetric blocks (as `DMat3`, and as six arrays), ends and vectors.
    fn case(springs: usize, n: usize, seed: u64) -> (Vec<[u32; 2]>, Vec<DMat3>, Vec<DVec3>) {
        let mut rng = crate::random::XorShift64Star::new(seed);
        let mut next = || rng.unit() - 0.5;
        let u: Vec<DVec3> = (0..n).map(|_| DVec3::new(next(), next(), next())).collect();
        let mut ends = Vec::new();
        let mut blocks = Vec::new();
        for s in 0..springs {
            let a = (s * 7 + 3) % n;
            let b = (s * 13 + 5) % n;
            ends.push([a as u32, b as u32]);
            let (xx, xy, xz, yy, yz, zz) = (next(), next(), next(), next(), next(), next());
            blocks.push(DMat3::from_cols(
                DVec3::new(xx, xy, xz),
                DVec3::new(xy, yy, yz),
                DVec3::new(xz, yz, zz),
            ));
        }
        (ends, blocks, u)
    }

    fn six(blocks: &[DMat3]) -> [Vec<f64>; 6] {
        let mut k: [Vec<f64>; 6] = Default::default();
        for m in blocks {
            let entries = [
                m.x_axis.x, m.y_axis.x, m.z_axis.x, m.y_axis.y, m.z_axis.y, m.z_axis.z,
            ];
            for (k, e) in k.iter_mut().zip(entries) {
                k.push(e);
            }
        }
        k
    }

    #[test]
    fn divide_gives_the_textbook_bits() {
        for n in [0, 1, 7, 37, 200] {
            let (_, _, u) = case(0, n.max(1), n as u64 + 3);
            let u = &u[..n];
            for by in [3.0, 0.7, 1e-300, -2.5e7] {
                let want: Vec<[u64; 3]> = u
                    .iter()
                    .map(|v| (*v / by).to_array().map(f64::to_bits))
                    .collect();
                let mut got = u.to_vec();
                divide(&mut got, by);
                let got: Vec<[u64; 3]> =
                    got.iter().map(|v| v.to_array().map(f64::to_bits)).collect();
                assert_eq!(got, want, "{n} vectors / {by}");
                #[cfg(target_arch = "x86_64")]
                for kernel in [Kernel::Avx2, Kernel::Avx512] {
                    if !kernel.is_available() {
                        continue;
                    }
                    let mut got = u.to_vec();
                    // SAFETY: the CPU has the kernel's instructions (checked).
                    unsafe {
                        if kernel == Kernel::Avx2 {
                            divide_avx2(&mut got, by);
                        } else {
                            divide_avx512(&mut got, by);
                        }
                    }
                    let got: Vec<[u64; 3]> =
                        got.iter().map(|v| v.to_array().map(f64::to_bits)).collect();
                    assert_eq!(got, want, "{kernel:?}: {n} vectors / {by}");
                }
            }
        }
    }

    #[test]
    fn blocks_give_the_textbook_loops_bits() {
        // Counts below, at and above a block, not multiples of a vector.
        for springs in [0, 1, 5, 64, 65, 200] {
            let (ends, blocks, u) = case(springs, 37, springs as u64 + 1);
            let k = six(&blocks);
            let k = [&k[0][..], &k[1], &k[2], &k[3], &k[4], &k[5]];
            // The textbook loop with glam's matrix product.
            let mut want_e = 0.25;
            for (&[a, b], m) in ends.iter().zip(&blocks) {
                let d = u[b as usize] - u[a as usize];
                want_e += 0.5 * d.dot(*m * d);
            }
            assert_eq!(
                spring_energy(0.25, &ends, k, &u).to_bits(),
                want_e.to_bits(),
                "{springs} springs"
            );
            #[cfg(target_arch = "x86_64")]
            for kernel in [Kernel::Avx2, Kernel::Avx512] {
                if !kernel.is_available() {
                    continue;
                }
                // SAFETY: the CPU has the kernel's instructions (checked).
                let e = unsafe {
                    if kernel == Kernel::Avx2 {
                        energy_avx2(0.25, &ends, k, &u)
                    } else {
                        energy_avx512(0.25, &ends, k, &u)
                    }
                };
                assert_eq!(e.to_bits(), want_e.to_bits(), "{kernel:?}, {springs}");
            }
        }
    }
}
