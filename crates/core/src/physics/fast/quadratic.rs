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
//! time between them; `u_a` is loaded once for the run of springs that start at `a`, as a
//! lattice lists them). The operations are the loop's, in glam's order (`DMat3 * DVec3` column by column,
//! `dot` as `x + y + z`), without fused multiply-add (Rust does not contract): the same bits
//! (tested).
//!
//! Beside it, the rest of a linear probe's power step, eight particles at a time on the CPU's
//! widest [`Lanes`] (each lane's operations are the textbook loop's, in glam's order, so the
//! same bits; tested), where `u` is `δx` or `δv` (per particle), `e` a rigid mode, `m` the
//! masses (kg) and `s`, `dt` (s) scalars:
//!
//! ```text
//! x = x_0 + s δx,  v = v_0 + s δv,  x_prev = x - dt v     (offset: the perturbed states)
//! u = (u_+ - u_-) · (1 / 2s)                              (central_difference)
//! c = ((-0 + m_0 u_0·e_0) + m_1 u_1·e_1) + …              (components: the terms eight at
//! u ← u - c e                                               a time, the sum in order; remove)
//! K = ((e + ½ m_0 |δv_0|²) + …)  over free particles       (kinetic, in order)
//! v ← v / s                                               (divide: the normalisations)
//! ```
//! One particle at a time in the baseline build they were about half of a probe's bookkeeping
//! beside [`spring_energy`] (`examples/study_phases.rs`).

use glam::DVec3;

#[cfg(test)]
use super::lanes::Plain;
use super::lanes::{LANES, Lanes, load_chunk, load_padded, store_chunk};
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
    energy_on(Kernel::best(), e, ends, k, u)
}

on_lanes!(
    energy_on(kernel),
    plain energy_blocks,
    (e: f64, ends: &[[u32; 2]], k: SymBlocks, u: &[DVec3]) -> f64
);

/// `v ← v / by` for every vector of `values`, component by component (as glam's `DVec3 / f64`):
/// the power iterations' normalisations (`springlab::study::linear`, `springlab::study::modes`).
/// The divisions do not depend on each other, so the compiler does them eight or four at a time
/// with AVX-512 or AVX2 (a division is correctly rounded in every lane: the same bits, tested);
/// one at a time they were about a fifth of a linear probe's bookkeeping.
pub fn divide(values: &mut [DVec3], by: f64) {
    divide_on(Kernel::best(), values, by);
}

on_lanes!(divide_on(kernel), plain divide_each, (values: &mut [DVec3], by: f64) -> ());

on_lanes!(
    pub central_difference,
    difference_body,
    (plus: &[DVec3], minus: &[DVec3], inv: f64, out: &mut [DVec3]) -> ()
);
on_lanes!(
    pub offset,
    offset_body,
    (
        base: (&[DVec3], &[DVec3]),
        s: f64,
        delta: (&[DVec3], &[DVec3]),
        dt: f64,
        out: (&mut [DVec3], &mut [DVec3], &mut [DVec3])
    ) -> ()
);
on_lanes!(
    pub components,
    components_body,
    (mass: &[f64], along: &[DVec3], x: &[DVec3], v: &[DVec3]) -> (f64, f64)
);
on_lanes!(
    pub remove,
    remove_body,
    (mode: &[DVec3], c: (f64, f64), x: &mut [DVec3], v: &mut [DVec3]) -> ()
);
on_lanes!(
    pub kinetic,
    kinetic_body,
    (e: f64, half_mass: &[f64], free: &[bool], v: &[DVec3]) -> f64
);

/// `out_i = (plus_i - minus_i) · inv` (glam's order: the difference, then the product).
#[inline(always)]
fn difference_body<V: Lanes>(plus: &[DVec3], minus: &[DVec3], inv: f64, out: &mut [DVec3]) {
    let n = out.len();
    let (plus, minus) = (&plus[..n], &minus[..n]);
    let inv = V::splat(inv);
    for q in (0..n).step_by(LANES) {
        let count = (n - q).min(LANES);
        let (p, m) = (
            load_chunk::<V>(&plus[q..], count),
            load_chunk::<V>(&minus[q..], count),
        );
        let d = [
            p[0].sub(m[0]).mul(inv),
            p[1].sub(m[1]).mul(inv),
            p[2].sub(m[2]).mul(inv),
        ];
        store_chunk(d, &mut out[q..], count);
    }
}

/// A perturbed state: `x = x_0 + s δx`, `v = v_0 + s δv` and Verlet's history
/// `x_prev = x - dt v`, into `out = (x, v, x_prev)` (glam's order).
#[inline(always)]
fn offset_body<V: Lanes>(
    (base_x, base_v): (&[DVec3], &[DVec3]),
    s: f64,
    (dx, dv): (&[DVec3], &[DVec3]),
    dt: f64,
    (x, v, x_prev): (&mut [DVec3], &mut [DVec3], &mut [DVec3]),
) {
    let n = x.len();
    let (base_x, base_v, dx, dv) = (&base_x[..n], &base_v[..n], &dx[..n], &dv[..n]);
    let (v, x_prev) = (&mut v[..n], &mut x_prev[..n]);
    let (s, dt) = (V::splat(s), V::splat(dt));
    for q in (0..n).step_by(LANES) {
        let count = (n - q).min(LANES);
        let (bx, bv) = (
            load_chunk::<V>(&base_x[q..], count),
            load_chunk::<V>(&base_v[q..], count),
        );
        let (ex, ev) = (
            load_chunk::<V>(&dx[q..], count),
            load_chunk::<V>(&dv[q..], count),
        );
        let xq = [
            bx[0].add(s.mul(ex[0])),
            bx[1].add(s.mul(ex[1])),
            bx[2].add(s.mul(ex[2])),
        ];
        let vq = [
            bv[0].add(s.mul(ev[0])),
            bv[1].add(s.mul(ev[1])),
            bv[2].add(s.mul(ev[2])),
        ];
        let back = [
            xq[0].sub(dt.mul(vq[0])),
            xq[1].sub(dt.mul(vq[1])),
            xq[2].sub(dt.mul(vq[2])),
        ];
        store_chunk(xq, &mut x[q..], count);
        store_chunk(vq, &mut v[q..], count);
        store_chunk(back, &mut x_prev[q..], count);
    }
}

/// `(Σ_i m_i x_i·e_i, Σ_i m_i v_i·e_i)`, each added in particle order from `-0` (as
/// `Iterator::sum`): the terms eight at a time, then the two chains of additions.
#[inline(always)]
fn components_body<V: Lanes>(
    mass: &[f64],
    along: &[DVec3],
    x: &[DVec3],
    v: &[DVec3],
) -> (f64, f64) {
    let n = x.len();
    let (mass, along, v) = (&mass[..n], &along[..n], &v[..n]);
    let (mut cx, mut cv) = (-0.0, -0.0);
    let (mut tx, mut tv) = ([0.0; LANES], [0.0; LANES]);
    for q in (0..n).step_by(LANES) {
        let count = (n - q).min(LANES);
        let e = load_chunk::<V>(&along[q..], count);
        let (xq, vq) = (
            load_chunk::<V>(&x[q..], count),
            load_chunk::<V>(&v[q..], count),
        );
        let m = load_padded::<V>(mass, q, count);
        // Written out, not with a closure: a closure does not take its caller's target
        // features.
        let x_e = xq[0].mul(e[0]).add(xq[1].mul(e[1])).add(xq[2].mul(e[2]));
        let v_e = vq[0].mul(e[0]).add(vq[1].mul(e[1])).add(vq[2].mul(e[2]));
        m.mul(x_e).store(&mut tx);
        m.mul(v_e).store(&mut tv);
        for (a, b) in tx[..count].iter().zip(&tv[..count]) {
            cx += a;
            cv += b;
        }
    }
    (cx, cv)
}

/// `x_i ← x_i - c_x e_i`, `v_i ← v_i - c_v e_i` (glam's order).
#[inline(always)]
fn remove_body<V: Lanes>(mode: &[DVec3], (cx, cv): (f64, f64), x: &mut [DVec3], v: &mut [DVec3]) {
    let n = x.len();
    let (mode, v) = (&mode[..n], &mut v[..n]);
    let (cx, cv) = (V::splat(cx), V::splat(cv));
    for q in (0..n).step_by(LANES) {
        let count = (n - q).min(LANES);
        let e = load_chunk::<V>(&mode[q..], count);
        let (xq, vq) = (
            load_chunk::<V>(&x[q..], count),
            load_chunk::<V>(&v[q..], count),
        );
        let xq = [
            xq[0].sub(cx.mul(e[0])),
            xq[1].sub(cx.mul(e[1])),
            xq[2].sub(cx.mul(e[2])),
        ];
        let vq = [
            vq[0].sub(cv.mul(e[0])),
            vq[1].sub(cv.mul(e[1])),
            vq[2].sub(cv.mul(e[2])),
        ];
        store_chunk(xq, &mut x[q..], count);
        store_chunk(vq, &mut v[q..], count);
    }
}

/// `e + Σ ½ m_i |v_i|²` over the particles with `free[i]`, added in particle order.
#[inline(always)]
fn kinetic_body<V: Lanes>(mut e: f64, half_mass: &[f64], free: &[bool], v: &[DVec3]) -> f64 {
    let n = v.len();
    let (half_mass, free) = (&half_mass[..n], &free[..n]);
    let mut t = [0.0; LANES];
    for q in (0..n).step_by(LANES) {
        let count = (n - q).min(LANES);
        let vq = load_chunk::<V>(&v[q..], count);
        let squared = vq[0].mul(vq[0]).add(vq[1].mul(vq[1])).add(vq[2].mul(vq[2]));
        load_padded::<V>(half_mass, q, count)
            .mul(squared)
            .store(&mut t);
        for (t, free) in t[..count].iter().zip(&free[q..q + count]) {
            if *free {
                e += t;
            }
        }
    }
    e
}

#[inline(always)]
fn divide_each(values: &mut [DVec3], by: f64) {
    for v in values {
        *v /= by;
    }
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
    let (mut held, mut u_a) = (u32::MAX, DVec3::ZERO);
    for (start, ends) in blocks {
        for (j, &[a, b]) in ends.iter().enumerate() {
            // u_a is kept while consecutive springs start at it (a lattice's springs of one
            // particle come one after another).
            if a != held {
                held = a;
                u_a = u[a as usize];
            }
            let v = u[b as usize] - u_a;
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
            // Runs of three springs from one particle (as a lattice lists them) where the count
            // is odd.
            let a = if springs % 2 == 1 {
                (s / 3 * 7 + 3) % n
            } else {
                (s * 7 + 3) % n
            };
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

    fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
        v.iter().map(|v| v.to_array().map(f64::to_bits)).collect()
    }

    /// The power step's passes on the best kernel and on plain arrays against the textbook
    /// loops, bit for bit, for counts below, at and above a chunk of lanes.
    #[test]
    fn power_step_passes_give_the_textbook_bits() {
        for n in [0, 1, 7, 8, 9, 37] {
            let (_, _, a) = case(0, n + 1, 3 * n as u64 + 1);
            let (_, _, b) = case(0, n + 1, 3 * n as u64 + 2);
            let (_, _, e) = case(0, n + 1, 3 * n as u64 + 3);
            let (a, b, e) = (&a[..n], &b[..n], &e[..n]);
            let mass: Vec<f64> = (0..n).map(|i| 0.5 + i as f64).collect();
            let free: Vec<bool> = (0..n).map(|i| i % 4 != 2).collect();
            let (s, dt, c) = (1.5e-7, 2e-3, (0.3, -1.7));

            // offset
            let mut want = (a.to_vec(), b.to_vec(), a.to_vec());
            for i in 0..n {
                want.0[i] = a[i] + s * e[i];
                want.1[i] = b[i] + s * a[i];
                want.2[i] = want.0[i] - dt * want.1[i];
            }
            let mut got = (
                vec![DVec3::ZERO; n],
                vec![DVec3::ZERO; n],
                vec![DVec3::ZERO; n],
            );
            offset((a, b), s, (e, a), dt, (&mut got.0, &mut got.1, &mut got.2));
            assert_eq!(bits(&got.0), bits(&want.0), "offset x, {n}");
            assert_eq!(bits(&got.1), bits(&want.1), "offset v, {n}");
            assert_eq!(bits(&got.2), bits(&want.2), "offset x_prev, {n}");
            let mut plain = (
                vec![DVec3::ZERO; n],
                vec![DVec3::ZERO; n],
                vec![DVec3::ZERO; n],
            );
            offset_body::<Plain>(
                (a, b),
                s,
                (e, a),
                dt,
                (&mut plain.0, &mut plain.1, &mut plain.2),
            );
            assert_eq!(bits(&plain.2), bits(&want.2), "plain offset, {n}");

            // central_difference
            let want: Vec<DVec3> = (0..n).map(|i| (a[i] - b[i]) * (0.5 / s)).collect();
            let mut got = vec![DVec3::ZERO; n];
            central_difference(a, b, 0.5 / s, &mut got);
            assert_eq!(bits(&got), bits(&want), "difference, {n}");
            difference_body::<Plain>(a, b, 0.5 / s, &mut got);
            assert_eq!(bits(&got), bits(&want), "plain difference, {n}");

            // components
            let (mut cx, mut cv) = (-0.0, -0.0);
            for i in 0..n {
                cx += mass[i] * a[i].dot(e[i]);
                cv += mass[i] * b[i].dot(e[i]);
            }
            for got in [
                components(&mass, e, a, b),
                components_body::<Plain>(&mass, e, a, b),
            ] {
                assert_eq!(got.0.to_bits(), cx.to_bits(), "components x, {n}");
                assert_eq!(got.1.to_bits(), cv.to_bits(), "components v, {n}");
            }

            // remove
            let (mut wx, mut wv) = (a.to_vec(), b.to_vec());
            for i in 0..n {
                wx[i] -= c.0 * e[i];
                wv[i] -= c.1 * e[i];
            }
            let (mut gx, mut gv) = (a.to_vec(), b.to_vec());
            remove(e, c, &mut gx, &mut gv);
            assert_eq!(
                (bits(&gx), bits(&gv)),
                (bits(&wx), bits(&wv)),
                "remove, {n}"
            );
            let (mut gx, mut gv) = (a.to_vec(), b.to_vec());
            remove_body::<Plain>(e, c, &mut gx, &mut gv);
            assert_eq!(
                (bits(&gx), bits(&gv)),
                (bits(&wx), bits(&wv)),
                "plain remove, {n}"
            );

            // kinetic
            let half: Vec<f64> = mass.iter().map(|m| 0.5 * m).collect();
            let mut want = 0.0;
            for i in 0..n {
                if free[i] {
                    want += half[i] * b[i].length_squared();
                }
            }
            for got in [
                kinetic(0.0, &half, &free, b),
                kinetic_body::<Plain>(0.0, &half, &free, b),
            ] {
                assert_eq!(got.to_bits(), want.to_bits(), "kinetic, {n}");
            }
        }
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
                    divide_on(kernel, &mut got, by);
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
                let e = energy_on(kernel, 0.25, &ends, k, &u);
                assert_eq!(e.to_bits(), want_e.to_bits(), "{kernel:?}, {springs}");
            }
        }
    }
}
