//! The spring kernels of the stencil, one per instruction set (see the parent module's docs,
//! "One reciprocal square root" and "Three kernels"): the exact one (`sqrt`, then `1/L`) in
//! plain Rust and on AVX2 registers, and the AVX-512F one with the reciprocal square root
//! estimate and one fourth-order refinement. Each instantiates the streaming loop of [`super::passes`];
//! the AVX-512 one reads the second ends from one pointer and the window's component stride
//! ([`springs_avx512_strided`]), which leaves the loop the registers the six component pointers
//! took.

use super::passes::*;
#[allow(clippy::wildcard_imports)]
use super::*;

/// The springs of one chunk with correctly rounded operations only: `sqrt`, then `1/L`, in the
/// order of [`Spring::force_on_a`](super::springs::Spring::force_on_a) (the result does not
/// depend on the lane type: [`Plain`] and [`Avx2`] give the same bits); and the dampers' power
/// `k_d ((v_b - v_a)·n)²` (W).
#[inline(always)]
pub(super) fn springs_exact<V: Lanes>(
    g: &Group,
    first: &[V; 6],
    w: &Window,
    i: usize,
    p: usize,
) -> (Forces<V>, V) {
    let j = i + g.delta;
    // d = x_b - x_a, L = |d|
    let dx = V::load(lanes(w.x[0], j)).sub(first[0]);
    let dy = V::load(lanes(w.x[1], j)).sub(first[1]);
    let dz = V::load(lanes(w.x[2], j)).sub(first[2]);
    let length = dx.mul(dx).add(dy.mul(dy)).add(dz.mul(dz)).sqrt();
    // n = d / L; a zero-length spring has no direction and no force.
    let inv = V::splat(1.0).div(length).where_positive(length);
    let (nx, ny, nz) = (dx.mul(inv), dy.mul(inv), dz.mul(inv));
    // Hooke k (L - L0) plus the damper k_d (v_b - v_a)·n, zero where there is no spring.
    let dvx = V::load(lanes(w.v[0], j)).sub(first[3]);
    let dvy = V::load(lanes(w.v[1], j)).sub(first[4]);
    let dvz = V::load(lanes(w.v[2], j)).sub(first[5]);
    let rel = dvx.mul(nx).add(dvy.mul(ny)).add(dvz.mul(nz));
    let rest = V::load(lanes(&g.rest_length, p));
    let hooke = V::splat(g.stiffness).mul(length.sub(rest));
    let damper = V::splat(g.damping).mul(rel);
    let present = g.present[p / LANES];
    let tension = hooke.add(damper).select(present);
    let power = damper.mul(rel).select(present);
    ([tension.mul(nx), tension.mul(ny), tension.mul(nz)], power)
}

/// The streaming loop in plain Rust with the exact springs.
#[allow(clippy::too_many_arguments)]
pub(super) fn range_portable<const POWER: bool>(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    part: &mut Part,
    output: &Output,
) {
    range_body::<Plain, POWER>(
        st,
        s,
        x,
        v,
        q0,
        q1,
        part,
        output,
        // A closure, not the function item: the item would be called through a shim that is
        // not inlined.
        #[inline(always)]
        #[allow(clippy::redundant_closure)]
        |g, first, w, i, p| springs_exact::<Plain>(g, first, w, i, p),
    );
}

/// The streaming loop on AVX2 registers with the exact springs (the same operations as the
/// portable loop, no fused multiply-add: bit-identical results).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
pub(super) fn range_avx2<const POWER: bool>(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    part: &mut Part,
    output: &Output,
) {
    range_body::<Avx2, POWER>(
        st,
        s,
        x,
        v,
        q0,
        q1,
        part,
        output,
        // A closure, not the function item: only a closure is inlined (and with it the AVX2
        // instructions, which cannot be inlined into a function without AVX2).
        #[inline(always)]
        #[allow(clippy::redundant_closure)]
        |g, first, w, i, p| springs_exact::<Avx2>(g, first, w, i, p),
    );
}

/// The streaming loop with the AVX-512 springs.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
pub(super) fn range_avx512<const POWER: bool>(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    part: &mut Part,
    output: &Output,
) {
    range_body::<Avx512, POWER>(
        st,
        s,
        x,
        v,
        q0,
        q1,
        part,
        output,
        #[inline(always)]
        |g, first, w, i, p| {
            // SAFETY: this function only runs on a CPU with AVX-512F (see `Stencil::range`), and
            // `range_body` calls with chunks inside the window and the group's arrays, its six
            // components one after the other at a fixed stride (`Scratch::xv`).
            unsafe { springs_avx512_strided(g, first, w, i, p) }
        },
    );
}

/// The springs of one chunk with AVX-512F: `1/L` from the reciprocal square root estimate and
/// one fourth-order refinement (see the module docs), fused multiply-adds.
///
/// Not itself a `target_feature` function, so that the compiler inlines it (a function with
/// more target features than its caller is never inlined); it is only called from
/// `range_avx512`, which has them.
///
/// # Safety
/// The CPU must support AVX-512F, and the window and `g`'s arrays must hold the chunk (see
/// `range_body`): `i + g.delta + LANES` at most the window's length, `p + LANES` at most
/// the length of `g.rest_length` and `g.present`. These are not checked in release builds.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) unsafe fn springs_avx512(
    g: &Group,
    first: &[Avx512; 6],
    w: &Window,
    i: usize,
    p: usize,
) -> (Forces<Avx512>, Avx512) {
    use std::arch::x86_64::_mm512_loadu_pd;
    let j = i + g.delta;
    debug_assert!(j + LANES <= w.x[0].len() && p + LANES <= g.rest_length.len());
    // SAFETY (the intrinsics): the caller guarantees AVX-512F, and that LANES = 8 values exist
    // from every index loaded below (window: `j = i + δ`; group arrays: `p`), which is what one
    // unaligned 512-bit load reads.
    unsafe {
        let load = |values: &[f64], at: usize| _mm512_loadu_pd(values.as_ptr().add(at));
        let second = [
            load(w.x[0], j),
            load(w.x[1], j),
            load(w.x[2], j),
            load(w.v[0], j),
            load(w.v[1], j),
            load(w.v[2], j),
        ];
        springs_avx512_of(g, first, &second, p)
    }
}

/// The springs of `g` starting at `p` from their first and second ends (`[x, y, z, v_x, v_y,
/// v_z]`, m and m/s): the group's constants loaded, then [`spring_lanes_avx512`].
///
/// # Safety
/// The CPU must support AVX-512F, and `p + LANES` must be at most the length of
/// `g.rest_length` (`LANES` times that of `g.present`). Not checked in release builds.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn springs_avx512_of(
    g: &Group,
    first: &[Avx512; 6],
    second: &[std::arch::x86_64::__m512d; 6],
    p: usize,
) -> (Forces<Avx512>, Avx512) {
    use std::arch::x86_64::{_mm512_loadu_pd, _mm512_set1_pd};
    debug_assert!(p + LANES <= g.rest_length.len());
    // Written out, not with `map`: its closure would not be inlined, and neither would the
    // AVX-512 operations inside it.
    let first = [
        first[0].0, first[1].0, first[2].0, first[3].0, first[4].0, first[5].0,
    ];
    // SAFETY: the caller guarantees AVX-512F and the group's arrays from `p`
    // (`p + LANES <= rest_length.len() = LANES present.len()`).
    unsafe {
        let ([fx, fy, fz], power) = spring_lanes_avx512(
            &first,
            second,
            _mm512_set1_pd(g.stiffness),
            _mm512_set1_pd(g.damping),
            _mm512_loadu_pd(g.rest_length.as_ptr().add(p)),
            *g.present.get_unchecked(p / LANES),
        );
        ([Avx512(fx), Avx512(fy), Avx512(fz)], Avx512(power))
    }
}

/// [`springs_avx512`] on a window whose six components lie one after the other at a fixed
/// stride `S` (the streaming loop's, `Scratch::xv`): the second ends are read from one pointer
/// and `S` instead of six pointers, which leaves the loop registers for the rest (the same
/// loads, so the same forces).
///
/// # Safety
/// As [`springs_avx512`]; also `w.x[1]`, `w.x[2]`, `w.v[0]`, `w.v[1]`, `w.v[2]` must start
/// `S`, `2 S`, … `5 S` values after `w.x[0]`, inside one allocation.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) unsafe fn springs_avx512_strided(
    g: &Group,
    first: &[Avx512; 6],
    w: &Window,
    i: usize,
    p: usize,
) -> (Forces<Avx512>, Avx512) {
    use std::arch::x86_64::_mm512_loadu_pd;
    let j = i + g.delta;
    debug_assert!(j + LANES <= w.x[0].len() && p + LANES <= g.rest_length.len());
    // SAFETY (the intrinsics and the pointers): the caller guarantees AVX-512F, the layout
    // (component `c` at `c S` values from `w.x[0]`), and that LANES values exist from `j` in
    // every component and from `p` in the group's arrays.
    unsafe {
        let base = w.x[0].as_ptr();
        let stride = w.x[1].as_ptr().offset_from(base) as usize;
        debug_assert!((0..3).all(|c| w.x[c].as_ptr() == base.add(c * stride)
            && w.v[c].as_ptr() == base.add((3 + c) * stride)));
        let at = base.add(j);
        let second = [
            _mm512_loadu_pd(at),
            _mm512_loadu_pd(at.add(stride)),
            _mm512_loadu_pd(at.add(2 * stride)),
            _mm512_loadu_pd(at.add(3 * stride)),
            _mm512_loadu_pd(at.add(4 * stride)),
            _mm512_loadu_pd(at.add(5 * stride)),
        ];
        springs_avx512_of(g, first, &second, p)
    }
}

/// The arithmetic of [`springs_avx512`] on ends already in registers: the forces of eight
/// springs and their dampers' power (W). `first`, `second`: `[x, y, z, v_x, v_y, v_z]` of the
/// first and second ends (m, m/s); `stiffness` `k` (N/m), `damping` `k_d` (N·s/m) and `rest`
/// `L0` (m) per lane; `present`: the lanes that hold a spring. Also used by the small lattices'
/// fused pass (`small.rs`), which keeps both ends in registers, so both give the same bits.
///
/// # Safety
/// The CPU must support AVX-512F.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) unsafe fn spring_lanes_avx512(
    first: &[std::arch::x86_64::__m512d; 6],
    second: &[std::arch::x86_64::__m512d; 6],
    stiffness: std::arch::x86_64::__m512d,
    damping: std::arch::x86_64::__m512d,
    rest: std::arch::x86_64::__m512d,
    present: u8,
) -> ([std::arch::x86_64::__m512d; 3], std::arch::x86_64::__m512d) {
    use std::arch::x86_64::{
        _CMP_GT_OQ, _mm512_cmp_pd_mask, _mm512_fmadd_pd, _mm512_fmsub_pd, _mm512_fnmadd_pd,
        _mm512_maskz_mul_pd, _mm512_maskz_rsqrt14_pd, _mm512_mul_pd, _mm512_set1_pd,
        _mm512_setzero_pd, _mm512_sub_pd,
    };
    // SAFETY (the intrinsics): the caller guarantees AVX-512F; nothing is loaded or stored.
    unsafe {
        // d = x_b - x_a
        let dx = _mm512_sub_pd(second[0], first[0]);
        let dy = _mm512_sub_pd(second[1], first[1]);
        let dz = _mm512_sub_pd(second[2], first[2]);
        // a = d·d = L²
        let a = _mm512_fmadd_pd(dz, dz, _mm512_fmadd_pd(dy, dy, _mm512_mul_pd(dx, dx)));
        // k_d (v_b - v_a)·d, computed while the square root is refined: (v_b - v_a)·n is
        // this times 1/L.
        let dvx = _mm512_sub_pd(second[3], first[3]);
        let dvy = _mm512_sub_pd(second[4], first[4]);
        let dvz = _mm512_sub_pd(second[5], first[5]);
        let dv_d = _mm512_fmadd_pd(dvz, dz, _mm512_fmadd_pd(dvy, dy, _mm512_mul_pd(dvx, dx)));
        let damper = _mm512_mul_pd(damping, dv_d);
        // y₀ ≈ 1/√a to 2⁻¹⁴, and 0 where a = 0 (a zero-length spring has no direction, no force).
        let nonzero = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(a, _mm512_setzero_pd());
        let y0 = _mm512_maskz_rsqrt14_pd(nonzero, a);
        // e = 1 - a y₀², then y = y₀ (1 + ½e + ⅜e² + 5⁄16 e³) (the series of y₀ (1 - e)^(-½),
        // Horner form): six operations where two Newton steps take eight.
        let e = _mm512_fnmadd_pd(_mm512_mul_pd(a, y0), y0, _mm512_set1_pd(1.0));
        let series = _mm512_fmadd_pd(_mm512_set1_pd(5.0 / 16.0), e, _mm512_set1_pd(3.0 / 8.0));
        let series = _mm512_fmadd_pd(series, e, _mm512_set1_pd(0.5));
        let y = _mm512_fmadd_pd(y0, _mm512_mul_pd(series, e), y0);
        // L = a / √a = a y; tension = k (L - L0) + k_d (v_b - v_a)·d / L
        let stretch = _mm512_fmsub_pd(a, y, rest);
        let damper_n = _mm512_mul_pd(damper, y);
        let tension = _mm512_fmadd_pd(stiffness, stretch, damper_n);
        // f = tension n = (tension / L) d, zero where there is no spring.
        let scale = _mm512_maskz_mul_pd(present, tension, y);
        // The damper's power k_d ((v_b - v_a)·n)² = (k_d (v_b - v_a)·n) ((v_b - v_a)·d / L);
        // unused (and not computed) unless the caller asks for the power.
        let power = _mm512_maskz_mul_pd(present, damper_n, _mm512_mul_pd(dv_d, y));
        (
            [
                _mm512_mul_pd(dx, scale),
                _mm512_mul_pd(dy, scale),
                _mm512_mul_pd(dz, scale),
            ],
            power,
        )
    }
}
