//! The boxes of a broad phase: for every `len` consecutive points, the smallest axis-aligned box
//! that holds them, the box that growing one point by point gives (`collide/prepared.rs`,
//! `Aabb::of`; tested there), eight points at a time with AVX-512:
//!
//! ```text
//! lo_c = min_i x_i,c      hi_c = max_i x_i,c      over the box's points i, axis c
//! an axis with a NaN coordinate: lo_c = -∞, hi_c = +∞
//! ```
//! Eight points `x0 y0 z0 x1 … z7` are three registers of eight values, and value `j` of them
//! is axis `j mod 3`: three running minima and maxima (`vminpd`, `vmaxpd`, which pass over a
//! NaN) and three NaN masks, one per register, see one axis per lane; at the end of a box the
//! 24 lanes are folded into the three axes in registers, lane `j` with lane `j + 12`, then
//! `j + 6`, then `j + 3` (the zero's sign may differ from the point-by-point box, which no
//! distance sees). Longer boxes spread that fold over more points. (The fold went through
//! memory and a scalar chain per axis before: 15 µs for the boxes of 16 384 points, now 4.5–6.5
//! µs, measured on the Zen 5 machine of `fast/stencil/team.rs`.)

use glam::DVec3;

#[cfg(target_arch = "x86_64")]
use super::lanes::Avx512;
use super::lanes::{LANES, Lanes, Plain, first_lanes, load_chunk};

/// Pushes `make(lo, hi)` onto `out` for the box (m) of points `len k .. len (k + 1)` of
/// `points`, `k = 0, 1, …` (the last box may hold fewer); `len` a multiple of eight.
///
/// # Panics
/// If `len` is not a positive multiple of eight.
pub(crate) fn boxes<T>(
    points: &[DVec3],
    len: usize,
    out: &mut Vec<T>,
    make: impl Fn(DVec3, DVec3) -> T,
) {
    assert!(len > 0 && len.is_multiple_of(8), "boxes of whole groups");
    out.clear();
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU supports AVX-512F (checked above).
        unsafe { boxes_avx512(points, len, out, make) };
        return;
    }
    for chunk in points.chunks(len) {
        let (lo, hi) = scalar_box(chunk, DVec3::INFINITY, DVec3::NEG_INFINITY);
        out.push(make(lo, hi));
    }
}

/// The box of `points` grown from `[lo, hi]` point by point (NaN: that axis infinite).
fn scalar_box(points: &[DVec3], mut lo: DVec3, mut hi: DVec3) -> (DVec3, DVec3) {
    let mut nan = glam::BVec3::FALSE;
    for &p in points {
        lo = lo.min(p);
        hi = hi.max(p);
        nan |= p.is_nan_mask();
    }
    (
        DVec3::select(nan, DVec3::NEG_INFINITY, lo),
        DVec3::select(nan, DVec3::INFINITY, hi),
    )
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn boxes_avx512<T>(
    points: &[DVec3],
    len: usize,
    out: &mut Vec<T>,
    make: impl Fn(DVec3, DVec3) -> T,
) {
    use std::arch::x86_64::{
        _CMP_UNORD_Q, _mm512_cmp_pd_mask, _mm512_loadu_pd, _mm512_max_pd, _mm512_min_pd,
        _mm512_set1_pd,
    };
    // Bits of the lanes of register r that hold axis c: AXIS[r][c].
    const fn axis_bits(r: usize, c: usize) -> u8 {
        let mut bits = 0u8;
        let mut l = 0;
        while l < 8 {
            if (8 * r + l) % 3 == c {
                bits |= 1 << l;
            }
            l += 1;
        }
        bits
    }
    const AXIS: [[u8; 3]; 3] = {
        let mut a = [[0u8; 3]; 3];
        let mut r = 0;
        while r < 3 {
            let mut c = 0;
            while c < 3 {
                a[r][c] = axis_bits(r, c);
                c += 1;
            }
            r += 1;
        }
        a
    };
    for chunk in points.chunks(len) {
        let whole = chunk.len() / 8 * 8;
        let mut lo = [_mm512_set1_pd(f64::INFINITY); 3];
        let mut hi = [_mm512_set1_pd(f64::NEG_INFINITY); 3];
        let mut nan = [0u8; 3];
        for group in chunk[..whole].chunks_exact(8) {
            let p = group.as_ptr().cast::<f64>();
            for r in 0..3 {
                // SAFETY: `DVec3` is `repr(C)` with three f64, so a group of eight is 24
                // contiguous f64: three unaligned 512-bit loads inside it.
                let v = unsafe { _mm512_loadu_pd(p.add(8 * r)) };
                lo[r] = _mm512_min_pd(v, lo[r]);
                hi[r] = _mm512_max_pd(v, hi[r]);
                nan[r] |= _mm512_cmp_pd_mask::<_CMP_UNORD_Q>(v, v);
            }
        }
        // Axis c is lanes c, c + 3, … c + 21 (never NaN: the minima and maxima passed over
        // every NaN), folded in registers.
        let (l, h) = (
            fold::<true>(lo[0], lo[1], lo[2]),
            fold::<false>(hi[0], hi[1], hi[2]),
        );
        let (box_lo, box_hi) = ([l[0], l[1], l[2]], [h[0], h[1], h[2]]);
        let mut nan_axis = glam::BVec3::FALSE;
        for c in 0..3 {
            nan_axis.set(
                c,
                (nan[0] & AXIS[0][c]) | (nan[1] & AXIS[1][c]) | (nan[2] & AXIS[2][c]) != 0,
            );
        }
        // The last points, fewer than eight, one by one.
        let (lo, hi) = scalar_box(&chunk[whole..], DVec3::from(box_lo), DVec3::from(box_hi));
        out.push(make(
            DVec3::select(nan_axis, DVec3::NEG_INFINITY, lo),
            DVec3::select(nan_axis, DVec3::INFINITY, hi),
        ));
    }
}

/// The 24 lanes `a ++ b ++ c` (lane `j` holds axis `j mod 3`, as [`boxes_avx512`] keeps
/// them) folded into the three axes, by minima (`MIN`) or maxima: lane `j` with lane `j + 12`,
/// then `j + 6`, then `j + 3` (lanes of one axis each time), the axes in lanes 0, 1, 2 of the
/// result. No lane is NaN, so the order of the fold changes no value (a zero's sign aside).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx512f")]
fn fold<const MIN: bool>(
    a: std::arch::x86_64::__m512d,
    b: std::arch::x86_64::__m512d,
    c: std::arch::x86_64::__m512d,
) -> [f64; 4] {
    use std::arch::x86_64::{
        __m512d, _mm256_storeu_pd, _mm512_castpd512_pd256, _mm512_max_pd, _mm512_min_pd,
        _mm512_permutex2var_pd, _mm512_permutexvar_pd, _mm512_set_epi64, _mm512_shuffle_f64x2,
    };
    let op = |x: __m512d, y: __m512d| {
        if MIN {
            _mm512_min_pd(x, y)
        } else {
            _mm512_max_pd(x, y)
        }
    };
    // Lanes j 0..8 with j 12..20 (b's upper half, c's lower half); j 8..12 (b's lower half)
    // with j 20..24 (c's upper half).
    let low = op(a, _mm512_shuffle_f64x2::<0b01_00_11_10>(b, c));
    let high = op(b, _mm512_shuffle_f64x2::<0b11_10_11_10>(c, c));
    // j 0..6 with j 6..12: `low`'s lanes 6, 7 and `high`'s 0..4.
    let six = op(
        low,
        _mm512_permutex2var_pd(low, _mm512_set_epi64(0, 0, 11, 10, 9, 8, 7, 6), high),
    );
    // j 0..3 with j 3..6.
    let three = op(
        six,
        _mm512_permutexvar_pd(_mm512_set_epi64(0, 0, 0, 0, 0, 5, 4, 3), six),
    );
    let mut out = [0.0; 4];
    // SAFETY: four f64 into an array of four.
    unsafe { _mm256_storeu_pd(out.as_mut_ptr(), _mm512_castpd512_pd256(three)) };
    out
}

/// Sets bit `i mod 64` of `bits[i / 64]` for every point `i` of `x` whose height over a plane
/// is below a bound or NaN, `(x_i - point)·normal < phi_max` (m), the test of
/// `Broad::plane_may_touch` (the same operations, so the same answers: tested in
/// `collide/prepared.rs`), eight points at a time; and returns whether every point is calm
/// (every coordinate inside (-1e50, 1e50) m, `collide::calm`).
///
/// # Panics
/// If `bits` holds fewer than `x.len()` bits.
pub(crate) fn plane_bits(
    x: &[DVec3],
    point: DVec3,
    normal: DVec3,
    phi_max: f64,
    bits: &mut [u64],
) -> bool {
    assert!(bits.len() * 64 >= x.len(), "a bit for every point");
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU supports AVX-512F (checked above).
        return unsafe { plane_bits_avx512(x, point, normal, phi_max, bits) };
    }
    plane_bits_lanes::<Plain>(x, point, normal, phi_max, bits)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn plane_bits_avx512(
    x: &[DVec3],
    point: DVec3,
    normal: DVec3,
    phi_max: f64,
    bits: &mut [u64],
) -> bool {
    plane_bits_lanes::<Avx512>(x, point, normal, phi_max, bits)
}

/// [`plane_bits`] with lanes `V`.
#[inline(always)]
fn plane_bits_lanes<V: Lanes>(
    x: &[DVec3],
    point: DVec3,
    normal: DVec3,
    phi_max: f64,
    bits: &mut [u64],
) -> bool {
    let (bound, low, high) = (V::splat(phi_max), V::splat(-CALM), V::splat(CALM));
    let mut calm = u8::MAX;
    for (k, chunk) in x.chunks(LANES).enumerate() {
        let count = chunk.len();
        let p = load_chunk::<V>(chunk, count);
        // (x - point)·normal, as `DVec3::dot` adds it: (x n_x + y n_y) + z n_z.
        let phi = (p[0].sub(V::splat(point.x)).mul(V::splat(normal.x)))
            .add(p[1].sub(V::splat(point.y)).mul(V::splat(normal.y)))
            .add(p[2].sub(V::splat(point.z)).mul(V::splat(normal.z)));
        let lanes = first_lanes(count);
        let near = (phi.less_than(bound) | phi.nan_lanes()) & lanes;
        bits[k / 8] |= u64::from(near) << (8 * (k % 8));
        for c in p {
            calm &= (low.less_than(c) & c.less_than(high)) | !lanes;
        }
    }
    calm == u8::MAX
}

/// Sets bit `i mod 64` of `bits[i / 64]` for every point `i` at `x` moving at `v` that some
/// plane `(point, normal)` of `planes` answers, the first tests of the collision response
/// (`collide::response::responds`: the same operations, so the same answers, tested in
/// `collide/prepared.rs`), eight points at a time:
///
/// ```text
/// φ   = (x_i - point)·normal           (m)
/// v_N = v_i·normal                     (m/s)
/// answered  ⟺  not φ ≥ ε  and  not (φ ≥ 0 and v_N ≥ 0)
/// ```
/// where `ε` is the contact band (m) and a comparison with a NaN is false; and returns
/// whether every position is calm (every coordinate inside (-1e50, 1e50) m, `collide::calm`).
///
/// # Panics
/// If `bits` holds fewer than `x.len()` bits, or `v` is shorter than `x`.
pub(crate) fn plane_answer_bits(
    x: &[DVec3],
    v: &[DVec3],
    planes: &[(DVec3, DVec3)],
    epsilon: f64,
    bits: &mut [u64],
) -> bool {
    assert!(bits.len() * 64 >= x.len(), "a bit for every point");
    let v = &v[..x.len()];
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU supports AVX-512F (checked above).
        return unsafe { plane_answer_bits_avx512(x, v, planes, epsilon, bits) };
    }
    plane_answer_bits_lanes::<Plain>(x, v, planes, epsilon, bits)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn plane_answer_bits_avx512(
    x: &[DVec3],
    v: &[DVec3],
    planes: &[(DVec3, DVec3)],
    epsilon: f64,
    bits: &mut [u64],
) -> bool {
    plane_answer_bits_lanes::<Avx512>(x, v, planes, epsilon, bits)
}

/// [`plane_answer_bits`] with lanes `V`.
#[inline(always)]
fn plane_answer_bits_lanes<V: Lanes>(
    x: &[DVec3],
    v: &[DVec3],
    planes: &[(DVec3, DVec3)],
    epsilon: f64,
    bits: &mut [u64],
) -> bool {
    let (low, high) = (V::splat(-CALM), V::splat(CALM));
    let (band, zero) = (V::splat(epsilon), V::zero());
    // `a ≥ b` as a mask: neither NaN and not `a < b`. A function, not a closure: a closure
    // does not take the caller's target features, and its operations would become calls.
    #[inline(always)]
    fn at_least<V: Lanes>(a: V, b: V) -> u8 {
        !a.less_than(b) & !a.nan_lanes() & !b.nan_lanes()
    }
    let mut calm = u8::MAX;
    for (k, (xc, vc)) in x.chunks(LANES).zip(v.chunks(LANES)).enumerate() {
        let count = xc.len();
        let lanes = first_lanes(count);
        let p = load_chunk::<V>(xc, count);
        // The velocities only for a chunk with a point in some plane's band (most have none).
        let mut u = [V::zero(); 3];
        let mut loaded = false;
        let mut answered = 0u8;
        for &(point, normal) in planes {
            // As `DVec3::dot` adds: (a_x n_x + a_y n_y) + a_z n_z.
            let phi = (p[0].sub(V::splat(point.x)).mul(V::splat(normal.x)))
                .add(p[1].sub(V::splat(point.y)).mul(V::splat(normal.y)))
                .add(p[2].sub(V::splat(point.z)).mul(V::splat(normal.z)));
            let within = !at_least(phi, band) & lanes;
            if within == 0 {
                continue;
            }
            if !loaded {
                u = load_chunk::<V>(vc, count);
                loaded = true;
            }
            let v_n = (u[0].mul(V::splat(normal.x)))
                .add(u[1].mul(V::splat(normal.y)))
                .add(u[2].mul(V::splat(normal.z)));
            answered |= within & !(at_least(phi, zero) & at_least(v_n, zero));
        }
        bits[k / 8] |= u64::from(answered) << (8 * (k % 8));
        for c in p {
            calm &= (low.less_than(c) & c.less_than(high)) | !lanes;
        }
    }
    calm == u8::MAX
}

/// The size of a calm coordinate (m): below it in magnitude (`collide::calm`).
const CALM: f64 = 1e50;
