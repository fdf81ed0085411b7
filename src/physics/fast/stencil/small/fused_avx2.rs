//! One pass per step on AVX2 registers (the exact kernel, at most `FUSED_GROUPS` offset
//! groups): the same numbers as `small_body` with the AVX2 kernel, its two passes merged
//! chunk by chunk (see the parent module's docs, "One pass per step"):
//!
//! ```text
//! each step, each chunk c (particles 8c..8c+8), in order:
//!     f_δ[c] = springs(chunk c, particles 8c+δ..)        (second ends: chunks after c, old
//!                                                         values, loaded from the arrays)
//!     plus   = (0 + f_δ₁[c]) + f_δ₂[c] + …
//!     minus  = 0 + (forces ending in chunk c, δ₁) + …    (δ < 8: lanes 8-δ.. of f_δ[c-1],
//!                                                         f_δ[c] by lane shifts in registers;
//!                                                         δ ≥ 8: from the group's array)
//!     F = plus - minus;  f = (m g - c v) + F;  a = f · (1/m);  v' = v + dt a;  x' = x + dt v'
//!     store x', v' into chunk c
//! ```
//! The arrays are those of `small_body` (structure of arrays, one per component), and every
//! operation and sum is `small_body`'s in the same order, so the results are the same bits
//! (tested). A force that ends `δ < 8` particles later is never stored and loaded back a
//! moment later (a load that straddles two pending stores waits until they reach the cache):
//! it is shifted out of the two chunks of forces still in registers, two instructions per
//! four lanes (`VPERM2F128`, `VSHUFPD`; Intel Intrinsics Guide,
//! <https://www.intel.com/content/www/us/en/docs/intrinsics-guide/>).

use super::*;
use std::arch::x86_64::{__m256d, _mm256_permute2f128_pd, _mm256_shuffle_pd};

/// Elements `m..m + 4` of the eight values `x ++ y` (`m` in `0..4`).
///
/// # Safety
/// The CPU must support AVX.
#[inline(always)]
unsafe fn shifted(x: __m256d, y: __m256d, m: usize) -> __m256d {
    // SAFETY: AVX, guaranteed by the caller. Written without a closure: a closure would not
    // be inlined, and the intrinsics inside it would become calls.
    unsafe {
        match m {
            0 => x,
            // [x1, x2, x3, y0]: x1, x3 from x, x2, y0 from [x2, x3, y0, y1].
            1 => _mm256_shuffle_pd::<0b0101>(x, _mm256_permute2f128_pd::<0x21>(x, y)),
            // [x2, x3, y0, y1]
            2 => _mm256_permute2f128_pd::<0x21>(x, y),
            // [x3, y0, y1, y2]
            _ => _mm256_shuffle_pd::<0b0101>(_mm256_permute2f128_pd::<0x21>(x, y), y),
        }
    }
}

/// Lanes `m..m + 8` of the sixteen values `low ++ high` (`m` in `1..8`): lane `l` of the
/// result is lane `m + l` of the pair.
///
/// # Safety
/// The CPU must support AVX.
#[inline(always)]
unsafe fn tail(low: Avx2, high: Avx2, m: usize) -> Avx2 {
    let quarters = [low.0[0], low.0[1], high.0[0], high.0[1]];
    let (q, r) = (m / 4, m % 4);
    // SAFETY: AVX (the caller); q ≤ 1, so q + 2 ≤ 3.
    unsafe {
        Avx2([
            shifted(quarters[q], quarters[q + 1], r),
            shifted(quarters[q + 1], quarters[q + 2], r),
        ])
    }
}

/// `steps` semi-implicit Euler steps of the arrays of `s` (loaded by [`SmallScratch::load`]),
/// one pass over the chunks per step, for a lattice of exactly `G` groups.
///
/// # Safety
/// The CPU must support AVX2, `st.groups.len() == G`, and `s` must have been loaded for `st`.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn fused_avx2<const G: usize>(
    st: &Stencil,
    s: &mut SmallScratch,
    d: &Dynamics,
    dt: f64,
    steps: u64,
) {
    debug_assert_eq!(st.groups.len(), G);
    let n = st.particles;
    let groups: [&Group; G] = std::array::from_fn(|g| &st.groups[g]);
    let SmallScratch {
        x: xs,
        v: vs,
        forces,
        ..
    } = s;
    let dt_lanes = Avx2::splat(dt);
    for _ in 0..steps {
        // The forces of the previous chunk, for the groups with δ < 8.
        let mut previous = [[Avx2::zero(); 3]; G];
        for q in (0..n).step_by(LANES) {
            let count = (n - q).min(LANES);
            let w = Window {
                x: [&xs[0], &xs[1], &xs[2]],
                v: [&vs[0], &vs[1], &vs[2]],
            };
            let first = w.first_ends::<Avx2>(q);
            // Group by group: pass 1 (the springs that start here, summed into `plus` as
            // `small_body` sums them: only the groups the chunk has, a prefix of the list) and
            // pass 2's `minus` (the springs that end here, every group, in the same order).
            let mut plus = [Avx2::zero(); 3];
            let mut minus = [Avx2::zero(); 3];
            for (g, group) in groups.iter().enumerate() {
                let f = if q < group.starts {
                    let (f, _) = springs_exact::<Avx2>(group, &first, &w, q, q);
                    for (total, part) in plus.iter_mut().zip(f) {
                        *total = total.add(part);
                    }
                    f
                } else {
                    [Avx2::zero(); 3]
                };
                if group.delta < LANES {
                    for c in 0..3 {
                        // SAFETY: AVX2 is enabled here; 1 ≤ 8 - δ ≤ 7.
                        let ending = unsafe { tail(previous[g][c], f[c], LANES - group.delta) };
                        minus[c] = minus[c].add(ending);
                    }
                    previous[g] = f;
                } else {
                    // Written a chunk or more ago; stored after the load (δ + q ≥ q + 8).
                    for c in 0..3 {
                        minus[c] = minus[c].add(Avx2::load(lanes(&forces[g][c], q)));
                    }
                    if q < group.starts {
                        for (part, values) in f.into_iter().zip(forces[g].iter_mut()) {
                            part.store(chunk_mut(values, group.delta + q));
                        }
                    }
                }
            }
            let sum = [
                plus[0].sub(minus[0]),
                plus[1].sub(minus[1]),
                plus[2].sub(minus[2]),
            ];
            let x = [first[0], first[1], first[2]];
            let v = [first[3], first[4], first[5]];
            let m = load_padded::<Avx2>(d.mass, q, count);
            let f = weight_drag_springs(m, d.gravity, d.drag, v, sum);
            let w = load_padded::<Avx2>(d.inv_mass, q, count);
            let a = [f[0].mul(w), f[1].mul(w), f[2].mul(w)];
            let (x_new, v_new) = semi_implicit_euler(x, v, a, dt_lanes);
            // Past the last particle the arrays stay zero, as `small_body`'s.
            let keep = first_lanes(count);
            for (new, values) in x_new.into_iter().zip(xs.iter_mut()) {
                new.select(keep).store(chunk_mut(values, q));
            }
            for (new, values) in v_new.into_iter().zip(vs.iter_mut()) {
                new.select(keep).store(chunk_mut(values, q));
            }
        }
    }
}
