//! `LANES` f64 computed together: the small SIMD vocabulary of the fast paths (the stencil's
//! passes, implicit Euler's lattice system), in three implementations: a plain array, two AVX2
//! registers and one AVX-512 register.
//!
//! The AVX2 and AVX-512 types call their instructions without checking the CPU: values of them
//! are only created inside functions compiled with the matching `target_feature`, which the
//! callers run only where the feature was detected ([`super::stencil::Kernel`]).

use glam::DVec3;

/// Values computed together: one AVX-512 register of f64 (two AVX2 registers).
pub(crate) const LANES: usize = 8;

/// `LANES` values of `values` from index `i`.
#[inline(always)]
pub(crate) fn lanes(values: &[f64], i: usize) -> &[f64; LANES] {
    values[i..i + LANES]
        .try_into()
        .expect("a slice of LANES values")
}

/// `LANES` f64 computed together, and the few operations the streaming loop needs on them.
/// Three implementations: [`Plain`] (an array; the compiler vectorises what it can) and, on
/// x86-64, [`Avx2`] (two AVX2 registers) and [`Avx512`] (one AVX-512 register).
pub(crate) trait Lanes: Copy {
    /// All lanes zero.
    fn zero() -> Self;
    /// `LANES` values.
    fn load(values: &[f64; LANES]) -> Self;
    /// Writes the lanes to `out`.
    fn store(self, out: &mut [f64; LANES]);
    /// Lane-wise `self + other`.
    fn add(self, other: Self) -> Self;
    /// Lane-wise `self - other`.
    fn sub(self, other: Self) -> Self;
    /// Lane-wise `self · other`.
    fn mul(self, other: Self) -> Self;
    /// `value` in every lane.
    fn splat(value: f64) -> Self;
    /// The same lanes with lanes `0..k` set to zero.
    fn clear_below(self, k: usize) -> Self;
    /// Lane-wise square root (correctly rounded, IEEE 754).
    fn sqrt(self) -> Self;
    /// Lane-wise `self / other` (correctly rounded).
    fn div(self, other: Self) -> Self;
    /// `self` in the lanes where `condition > 0`, zero elsewhere (also where it is NaN).
    fn where_positive(self, condition: Self) -> Self;
    // The defaults are inlined into each caller: compiled on their own (without the caller's
    // instruction set) they would call the vector type's intrinsics out of line, one call per
    // operation (measured: Verlet's chain projection 2.5x slower than the C++ reference on AVX2).
    /// `self` in the lanes whose bit is set in `mask` (bit `l` is lane `l`), zero elsewhere.
    #[inline(always)]
    fn select(self, mask: u8) -> Self {
        let mut values = [0.0; LANES];
        self.store(&mut values);
        for (l, value) in values.iter_mut().enumerate() {
            if mask & (1 << l) == 0 {
                *value = 0.0;
            }
        }
        Self::load(&values)
    }
    /// `self` in the lanes whose bit is set in `mask`, `other` elsewhere (bits unchanged).
    #[inline(always)]
    fn blend(self, other: Self, mask: u8) -> Self {
        let (mut a, mut b) = ([0.0; LANES], [0.0; LANES]);
        self.store(&mut a);
        other.store(&mut b);
        for l in 0..LANES {
            if mask & (1 << l) == 0 {
                a[l] = b[l];
            }
        }
        Self::load(&a)
    }
    /// Bit `l` set where lane `l` of `self` is less than that of `other` (false for NaN).
    #[inline(always)]
    fn less_than(self, other: Self) -> u8 {
        let (mut a, mut b) = ([0.0; LANES], [0.0; LANES]);
        self.store(&mut a);
        other.store(&mut b);
        (0..LANES).fold(0, |m, l| m | (u8::from(a[l] < b[l]) << l))
    }
    /// Bit `l` set where lane `l` is NaN.
    #[inline(always)]
    fn nan_lanes(self) -> u8 {
        let mut a = [0.0; LANES];
        self.store(&mut a);
        (0..LANES).fold(0, |m, l| m | (u8::from(a[l].is_nan()) << l))
    }
    /// Eight vectors `[x, y, z]` as lanes (structure of arrays).
    #[inline(always)]
    fn load_vectors(vectors: &[DVec3; LANES]) -> [Self; 3] {
        to_lanes(vectors)
    }
    /// Whether [`Lanes::funnel`] is one instruction on registers (then the stencil's pass 2
    /// reads its force rings with aligned loads and funnels them; else with unaligned loads).
    const FUNNEL: bool = false;
    /// Lanes `r..LANES` of `self` followed by lanes `0..r` of `next` (`r < LANES`): the
    /// `LANES` values from index `r` of the two chunks one after the other.
    #[inline(always)]
    fn funnel(self, next: Self, r: usize) -> Self {
        let mut both = [0.0; 2 * LANES];
        let (a, b) = both.split_at_mut(LANES);
        self.store(a.try_into().expect("a chunk"));
        next.store(b.try_into().expect("a chunk"));
        Self::load(lanes(&both, r))
    }
    /// Lanes `[x, y, z]` into eight vectors.
    #[inline(always)]
    fn store_vectors(lanes: [Self; 3], vectors: &mut [DVec3; LANES]) {
        from_lanes(lanes, vectors);
    }
}

/// [`Lanes`] as a plain array.
#[derive(Clone, Copy)]
pub(crate) struct Plain([f64; LANES]);

impl Lanes for Plain {
    #[inline(always)]
    fn zero() -> Plain {
        Plain([0.0; LANES])
    }
    #[inline(always)]
    fn load(values: &[f64; LANES]) -> Plain {
        Plain(*values)
    }
    #[inline(always)]
    fn store(self, out: &mut [f64; LANES]) {
        *out = self.0;
    }
    #[inline(always)]
    fn add(self, other: Plain) -> Plain {
        Plain(std::array::from_fn(|l| self.0[l] + other.0[l]))
    }
    #[inline(always)]
    fn sub(self, other: Plain) -> Plain {
        Plain(std::array::from_fn(|l| self.0[l] - other.0[l]))
    }
    #[inline(always)]
    fn mul(self, other: Plain) -> Plain {
        Plain(std::array::from_fn(|l| self.0[l] * other.0[l]))
    }
    #[inline(always)]
    fn splat(value: f64) -> Plain {
        Plain([value; LANES])
    }
    #[inline(always)]
    fn clear_below(self, k: usize) -> Plain {
        Plain(std::array::from_fn(|l| if l < k { 0.0 } else { self.0[l] }))
    }
    #[inline(always)]
    fn sqrt(self) -> Plain {
        Plain(self.0.map(f64::sqrt))
    }
    #[inline(always)]
    fn div(self, other: Plain) -> Plain {
        Plain(std::array::from_fn(|l| self.0[l] / other.0[l]))
    }
    #[inline(always)]
    fn where_positive(self, condition: Plain) -> Plain {
        Plain(std::array::from_fn(|l| {
            if condition.0[l] > 0.0 { self.0[l] } else { 0.0 }
        }))
    }
    #[inline(always)]
    fn select(self, mask: u8) -> Plain {
        Plain(std::array::from_fn(|l| {
            if mask & (1 << l) != 0 { self.0[l] } else { 0.0 }
        }))
    }
}

/// The mask of the first `count` lanes (all of them from `LANES` on): the lanes of a chunk that
/// hold values when `count` are left.
#[inline(always)]
pub(crate) fn first_lanes(count: usize) -> u8 {
    if count >= LANES {
        u8::MAX
    } else {
        (1u8 << count) - 1
    }
}

/// `values[q..q + count]` as lanes, zero past `count`.
#[inline(always)]
pub(crate) fn load_padded<V: Lanes>(values: &[f64], q: usize, count: usize) -> V {
    if count == LANES {
        V::load(lanes(values, q))
    } else {
        // The last chunk of a range that does not end on a multiple of LANES.
        let mut chunk = [0.0; LANES];
        chunk[..count].copy_from_slice(&values[q..q + count]);
        V::load(&chunk)
    }
}

/// The first `count` (at most `LANES`) vectors of `vectors` as lanes `[x, y, z]`, zero past
/// `count`.
#[inline(always)]
pub(crate) fn load_chunk<V: Lanes>(vectors: &[DVec3], count: usize) -> [V; 3] {
    if count == LANES {
        V::load_vectors(vectors[..LANES].try_into().expect("a chunk"))
    } else {
        to_lanes(&vectors[..count])
    }
}

/// Writes lanes `[x, y, z]` into the first `count` (at most `LANES`) vectors of `vectors`.
#[inline(always)]
pub(crate) fn store_chunk<V: Lanes>(lanes: [V; 3], vectors: &mut [DVec3], count: usize) {
    if count == LANES {
        V::store_vectors(lanes, (&mut vectors[..LANES]).try_into().expect("a chunk"));
    } else {
        from_lanes(lanes, &mut vectors[..count]);
    }
}

/// The components of up to `LANES` vectors as lanes `[x, y, z]` (zero past the end).
#[inline(always)]
pub(crate) fn to_lanes<V: Lanes>(vectors: &[DVec3]) -> [V; 3] {
    let mut soa = [[0.0; LANES]; 3];
    for (l, p) in vectors.iter().enumerate().take(LANES) {
        soa[0][l] = p.x;
        soa[1][l] = p.y;
        soa[2][l] = p.z;
    }
    [V::load(&soa[0]), V::load(&soa[1]), V::load(&soa[2])]
}

/// Writes lanes `[x, y, z]` into up to `LANES` vectors.
#[inline(always)]
pub(crate) fn from_lanes<V: Lanes>(lanes: [V; 3], vectors: &mut [DVec3]) {
    let mut soa = [[0.0; LANES]; 3];
    lanes[0].store(&mut soa[0]);
    lanes[1].store(&mut soa[1]);
    lanes[2].store(&mut soa[2]);
    for (l, p) in vectors.iter_mut().enumerate().take(LANES) {
        *p = DVec3::new(soa[0][l], soa[1][l], soa[2][l]);
    }
}

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::__m512d;

/// [`Lanes`] as one AVX-512 register.
///
/// Its methods call AVX-512F instructions without checking the CPU: an `Avx512` value is only
/// ever created inside `range_avx512` or the chain projection's `passes_avx512`
/// (`target_feature(enable = "avx512f")` functions, which run only where AVX-512F was detected) or by the methods of a value that already exists, so
/// their code only runs where AVX-512F was detected.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(crate) struct Avx512(pub(crate) __m512d);

#[cfg(target_arch = "x86_64")]
impl Lanes for Avx512 {
    #[inline(always)]
    fn zero() -> Avx512 {
        // SAFETY: see the type's docs (the streaming loop asks for zero only where it also
        // computes springs, i.e. on a CPU with AVX-512F).
        Avx512(unsafe { std::arch::x86_64::_mm512_setzero_pd() })
    }
    #[inline(always)]
    fn load(values: &[f64; LANES]) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs; `values` is 8 f64, one unaligned 512-bit load.
        Avx512(unsafe { std::arch::x86_64::_mm512_loadu_pd(values.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, out: &mut [f64; LANES]) {
        // SAFETY: AVX-512F, see the type's docs; `out` is 8 f64, one unaligned 512-bit store.
        unsafe { std::arch::x86_64::_mm512_storeu_pd(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn add(self, other: Avx512) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_add_pd(self.0, other.0) })
    }
    #[inline(always)]
    fn sub(self, other: Avx512) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_sub_pd(self.0, other.0) })
    }
    #[inline(always)]
    fn mul(self, other: Avx512) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_mul_pd(self.0, other.0) })
    }
    #[inline(always)]
    fn splat(value: f64) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_set1_pd(value) })
    }
    #[inline(always)]
    fn clear_below(self, k: usize) -> Avx512 {
        // Keep lanes k.. : bit l of the mask is lane l.
        let keep = (0xFF_u32 << k.min(LANES)) as u8;
        self.select(keep)
    }
    #[inline(always)]
    fn sqrt(self) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_sqrt_pd(self.0) })
    }
    #[inline(always)]
    fn div(self, other: Avx512) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_div_pd(self.0, other.0) })
    }
    #[inline(always)]
    fn where_positive(self, condition: Avx512) -> Avx512 {
        self.select(Avx512::zero().less_than(condition))
    }
    #[inline(always)]
    fn select(self, mask: u8) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_maskz_mov_pd(mask, self.0) })
    }
    #[inline(always)]
    fn blend(self, other: Avx512, mask: u8) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_mask_blend_pd(mask, other.0, self.0) })
    }
    #[inline(always)]
    fn less_than(self, other: Avx512) -> u8 {
        use std::arch::x86_64::{_CMP_LT_OQ, _mm512_cmp_pd_mask};
        // SAFETY: AVX-512F, see the type's docs.
        unsafe { _mm512_cmp_pd_mask::<_CMP_LT_OQ>(self.0, other.0) }
    }
    #[inline(always)]
    fn nan_lanes(self) -> u8 {
        use std::arch::x86_64::{_CMP_UNORD_Q, _mm512_cmp_pd_mask};
        // SAFETY: AVX-512F, see the type's docs.
        unsafe { _mm512_cmp_pd_mask::<_CMP_UNORD_Q>(self.0, self.0) }
    }
    const FUNNEL: bool = true;
    #[inline(always)]
    fn funnel(self, next: Avx512, r: usize) -> Avx512 {
        use std::arch::x86_64::{
            _mm512_add_epi64, _mm512_permutex2var_pd, _mm512_set1_epi64, _mm512_setr_epi64,
        };
        // Index i < 8: lane i of `self`, i ≥ 8: lane i - 8 of `next`.
        // SAFETY: AVX-512F, see the type's docs.
        unsafe {
            let index = _mm512_add_epi64(
                _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7),
                _mm512_set1_epi64(r as i64),
            );
            Avx512(_mm512_permutex2var_pd(self.0, index, next.0))
        }
    }
    #[inline(always)]
    fn load_vectors(vectors: &[DVec3; LANES]) -> [Avx512; 3] {
        use std::arch::x86_64::{_mm512_loadu_pd, _mm512_permutex2var_pd, _mm512_setr_epi64};
        // The 24 values x0 y0 z0 x1 … z7 are three registers r0, r1, r2; each component is
        // gathered from two of them, then completed from the third (index i < 8: the first
        // operand's lane i, i ≥ 8: the second's lane i - 8).
        // SAFETY: AVX-512F, see the type's docs; `vectors` is 24 contiguous f64 (`DVec3` is
        // `repr(C)` with three f64), three unaligned 512-bit loads.
        unsafe {
            let p = vectors.as_ptr().cast::<f64>();
            let (r0, r1, r2) = (
                _mm512_loadu_pd(p),
                _mm512_loadu_pd(p.add(8)),
                _mm512_loadu_pd(p.add(16)),
            );
            let gather = |a: [i64; 8], b: [i64; 8]| {
                let t = _mm512_permutex2var_pd(
                    r0,
                    _mm512_setr_epi64(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]),
                    r1,
                );
                Avx512(_mm512_permutex2var_pd(
                    t,
                    _mm512_setr_epi64(b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]),
                    r2,
                ))
            };
            [
                gather([0, 3, 6, 9, 12, 15, 0, 0], [0, 1, 2, 3, 4, 5, 10, 13]),
                gather([1, 4, 7, 10, 13, 0, 0, 0], [0, 1, 2, 3, 4, 8, 11, 14]),
                gather([2, 5, 8, 11, 14, 0, 0, 0], [0, 1, 2, 3, 4, 9, 12, 15]),
            ]
        }
    }
    #[inline(always)]
    fn store_vectors(lanes: [Avx512; 3], vectors: &mut [DVec3; LANES]) {
        use std::arch::x86_64::{_mm512_permutex2var_pd, _mm512_setr_epi64, _mm512_storeu_pd};
        let [x, y, z] = lanes.map(|l| l.0);
        // SAFETY: AVX-512F, see the type's docs; `vectors` is 24 contiguous f64, three
        // unaligned 512-bit stores.
        unsafe {
            let index =
                |i: [i64; 8]| _mm512_setr_epi64(i[0], i[1], i[2], i[3], i[4], i[5], i[6], i[7]);
            // r0 = x0 y0 z0 x1 y1 z1 x2 y2
            let t = _mm512_permutex2var_pd(x, index([0, 8, 0, 1, 9, 0, 2, 10]), y);
            let r0 = _mm512_permutex2var_pd(t, index([0, 1, 8, 3, 4, 9, 6, 7]), z);
            // r1 = z2 x3 y3 z3 x4 y4 z4 x5
            let t = _mm512_permutex2var_pd(x, index([0, 3, 11, 0, 4, 12, 0, 5]), y);
            let r1 = _mm512_permutex2var_pd(t, index([10, 1, 2, 11, 4, 5, 12, 7]), z);
            // r2 = y5 z5 x6 y6 z6 x7 y7 z7
            let t = _mm512_permutex2var_pd(y, index([5, 13, 0, 6, 14, 0, 7, 15]), z);
            let r2 = _mm512_permutex2var_pd(t, index([0, 1, 14, 3, 4, 15, 6, 7]), x);
            let p = vectors.as_mut_ptr().cast::<f64>();
            _mm512_storeu_pd(p, r0);
            _mm512_storeu_pd(p.add(8), r1);
            _mm512_storeu_pd(p.add(16), r2);
        }
    }
}

/// [`Lanes`] as two AVX2 registers of four f64 each.
///
/// Its methods call AVX2 instructions without checking the CPU: an `Avx2` value is only ever
/// created inside `range_avx2` (a `target_feature(enable = "avx2")` function, which runs only
/// where AVX2 was detected) or by the methods of a value that already exists.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(crate) struct Avx2([std::arch::x86_64::__m256d; 2]);

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// The lanes whose bit is set in `mask` (bit `4h + l` is lane `l` of half `h`) as all-ones
    /// lanes of two registers, zero elsewhere.
    #[inline(always)]
    fn masks(mask: u8) -> [std::arch::x86_64::__m256d; 2] {
        use std::arch::x86_64::{
            _mm256_and_si256, _mm256_castsi256_pd, _mm256_cmpeq_epi64, _mm256_set1_epi64x,
            _mm256_setr_epi64x,
        };
        // SAFETY: AVX2, see the type's docs: (mask & bit) == bit gives all-ones lanes there.
        // Written without a closure, which would not be inlined (nor its intrinsics).
        unsafe {
            let bits = _mm256_set1_epi64x(i64::from(mask));
            let low = _mm256_setr_epi64x(1, 2, 4, 8);
            let high = _mm256_setr_epi64x(16, 32, 64, 128);
            [
                _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(bits, low), low)),
                _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(bits, high), high)),
            ]
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl Lanes for Avx2 {
    #[inline(always)]
    fn zero() -> Avx2 {
        // SAFETY: AVX2, see the type's docs.
        let zero = unsafe { std::arch::x86_64::_mm256_setzero_pd() };
        Avx2([zero, zero])
    }
    #[inline(always)]
    fn load(values: &[f64; LANES]) -> Avx2 {
        use std::arch::x86_64::_mm256_loadu_pd;
        // SAFETY: AVX2, see the type's docs; two unaligned 256-bit loads of 4 f64 each, inside
        // the 8 values of `values`.
        unsafe {
            Avx2([
                _mm256_loadu_pd(values.as_ptr()),
                _mm256_loadu_pd(values.as_ptr().add(4)),
            ])
        }
    }
    #[inline(always)]
    fn store(self, out: &mut [f64; LANES]) {
        use std::arch::x86_64::_mm256_storeu_pd;
        // SAFETY: AVX2, see the type's docs; two 256-bit stores inside the 8 values of `out`.
        unsafe {
            _mm256_storeu_pd(out.as_mut_ptr(), self.0[0]);
            _mm256_storeu_pd(out.as_mut_ptr().add(4), self.0[1]);
        }
    }
    #[inline(always)]
    fn add(self, other: Avx2) -> Avx2 {
        use std::arch::x86_64::_mm256_add_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe {
            Avx2([
                _mm256_add_pd(self.0[0], other.0[0]),
                _mm256_add_pd(self.0[1], other.0[1]),
            ])
        }
    }
    #[inline(always)]
    fn sub(self, other: Avx2) -> Avx2 {
        use std::arch::x86_64::_mm256_sub_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe {
            Avx2([
                _mm256_sub_pd(self.0[0], other.0[0]),
                _mm256_sub_pd(self.0[1], other.0[1]),
            ])
        }
    }
    #[inline(always)]
    fn mul(self, other: Avx2) -> Avx2 {
        use std::arch::x86_64::_mm256_mul_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe {
            Avx2([
                _mm256_mul_pd(self.0[0], other.0[0]),
                _mm256_mul_pd(self.0[1], other.0[1]),
            ])
        }
    }
    #[inline(always)]
    fn splat(value: f64) -> Avx2 {
        // SAFETY: AVX2, see the type's docs.
        let v = unsafe { std::arch::x86_64::_mm256_set1_pd(value) };
        Avx2([v, v])
    }
    #[inline(always)]
    fn clear_below(self, k: usize) -> Avx2 {
        // Keep lanes k.. : bit l of the mask is lane l (zeros are +0.0, as the default's).
        let keep = (0xFF_u32 << k.min(LANES)) as u8;
        self.select(keep)
    }
    #[inline(always)]
    fn sqrt(self) -> Avx2 {
        use std::arch::x86_64::_mm256_sqrt_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe { Avx2([_mm256_sqrt_pd(self.0[0]), _mm256_sqrt_pd(self.0[1])]) }
    }
    #[inline(always)]
    fn div(self, other: Avx2) -> Avx2 {
        use std::arch::x86_64::_mm256_div_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe {
            Avx2([
                _mm256_div_pd(self.0[0], other.0[0]),
                _mm256_div_pd(self.0[1], other.0[1]),
            ])
        }
    }
    #[inline(always)]
    fn select(self, mask: u8) -> Avx2 {
        use std::arch::x86_64::_mm256_and_pd;
        let keep = Avx2::masks(mask);
        // SAFETY: AVX2, see the type's docs: `and` keeps the lanes of `keep`.
        unsafe {
            Avx2([
                _mm256_and_pd(self.0[0], keep[0]),
                _mm256_and_pd(self.0[1], keep[1]),
            ])
        }
    }
    #[inline(always)]
    fn blend(self, other: Avx2, mask: u8) -> Avx2 {
        use std::arch::x86_64::_mm256_blendv_pd;
        let take = Avx2::masks(mask);
        // SAFETY: AVX2, see the type's docs. `blendv` takes its second operand where the
        // mask's sign bit is set (all-ones lanes), the first elsewhere: no arithmetic, the
        // same bits as the default's copy lane by lane, without its round trip through memory
        // (eight scalar stores, then a vector load that cannot take them from the store queue).
        unsafe {
            Avx2([
                _mm256_blendv_pd(other.0[0], self.0[0], take[0]),
                _mm256_blendv_pd(other.0[1], self.0[1], take[1]),
            ])
        }
    }
    #[inline(always)]
    fn load_vectors(vectors: &[DVec3; LANES]) -> [Avx2; 3] {
        use std::arch::x86_64::{_mm256_loadu_pd, _mm256_permute2f128_pd, _mm256_shuffle_pd};
        // SAFETY: AVX2, see the type's docs; `vectors` is 24 contiguous f64 (`DVec3` is
        // `repr(C)` with three f64), six unaligned 256-bit loads.
        unsafe {
            let p = vectors.as_ptr().cast::<f64>();
            let mut lanes = [[_mm256_loadu_pd(p); 2]; 3];
            for h in 0..2 {
                // Four vectors: a = x0 y0 z0 x1, b = y1 z1 x2 y2, c = z2 x3 y3 z3.
                let a = _mm256_loadu_pd(p.add(12 * h));
                let b = _mm256_loadu_pd(p.add(12 * h + 4));
                let c = _mm256_loadu_pd(p.add(12 * h + 8));
                // Halves: ab = x0 y0 | x2 y2, ac = z0 x1 | z2 x3, bc = y1 z1 | y3 z3; then
                // one value of each pair (bit i of the shuffle: which of pair i).
                let ab = _mm256_permute2f128_pd::<0x30>(a, b);
                let ac = _mm256_permute2f128_pd::<0x21>(a, c);
                let bc = _mm256_permute2f128_pd::<0x30>(b, c);
                lanes[0][h] = _mm256_shuffle_pd::<0b1010>(ab, ac);
                lanes[1][h] = _mm256_shuffle_pd::<0b0101>(ab, bc);
                lanes[2][h] = _mm256_shuffle_pd::<0b1010>(ac, bc);
            }
            [Avx2(lanes[0]), Avx2(lanes[1]), Avx2(lanes[2])]
        }
    }
    #[inline(always)]
    fn store_vectors(lanes: [Avx2; 3], vectors: &mut [DVec3; LANES]) {
        use std::arch::x86_64::{_mm256_permute2f128_pd, _mm256_shuffle_pd, _mm256_storeu_pd};
        // SAFETY: AVX2, see the type's docs; `vectors` is 24 contiguous f64, six unaligned
        // 256-bit stores.
        unsafe {
            let p = vectors.as_mut_ptr().cast::<f64>();
            for h in 0..2 {
                let (x, y, z) = (lanes[0].0[h], lanes[1].0[h], lanes[2].0[h]);
                // The inverse of `load_vectors`: ab = x0 y0 | x2 y2, ac = z0 x1 | z2 x3,
                // bc = y1 z1 | y3 z3, then a = x0 y0 z0 x1, b = y1 z1 x2 y2, c = z2 x3 y3 z3.
                let ab = _mm256_shuffle_pd::<0b0000>(x, y);
                let ac = _mm256_shuffle_pd::<0b1010>(z, x);
                let bc = _mm256_shuffle_pd::<0b1111>(y, z);
                _mm256_storeu_pd(p.add(12 * h), _mm256_permute2f128_pd::<0x20>(ab, ac));
                _mm256_storeu_pd(p.add(12 * h + 4), _mm256_permute2f128_pd::<0x30>(bc, ab));
                _mm256_storeu_pd(p.add(12 * h + 8), _mm256_permute2f128_pd::<0x31>(ac, bc));
            }
        }
    }
    #[inline(always)]
    fn less_than(self, other: Avx2) -> u8 {
        use std::arch::x86_64::{_CMP_LT_OQ, _mm256_cmp_pd, _mm256_movemask_pd};
        // SAFETY: AVX2, see the type's docs; movemask gives one bit per lane.
        unsafe {
            let lo = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(self.0[0], other.0[0]));
            let hi = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(self.0[1], other.0[1]));
            (lo | (hi << 4)) as u8
        }
    }
    #[inline(always)]
    fn nan_lanes(self) -> u8 {
        use std::arch::x86_64::{_CMP_UNORD_Q, _mm256_cmp_pd, _mm256_movemask_pd};
        // SAFETY: AVX2, see the type's docs; movemask gives one bit per lane.
        unsafe {
            let lo = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_UNORD_Q>(self.0[0], self.0[0]));
            let hi = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_UNORD_Q>(self.0[1], self.0[1]));
            (lo | (hi << 4)) as u8
        }
    }
    #[inline(always)]
    fn where_positive(self, condition: Avx2) -> Avx2 {
        use std::arch::x86_64::{_CMP_GT_OQ, _mm256_and_pd, _mm256_cmp_pd, _mm256_setzero_pd};
        // SAFETY: AVX2, see the type's docs. The comparison gives all-ones lanes where
        // `condition > 0` (false for NaN), and `and` keeps `self` there.
        unsafe {
            let zero = _mm256_setzero_pd();
            let keep = [
                _mm256_cmp_pd::<_CMP_GT_OQ>(condition.0[0], zero),
                _mm256_cmp_pd::<_CMP_GT_OQ>(condition.0[1], zero),
            ];
            Avx2([
                _mm256_and_pd(self.0[0], keep[0]),
                _mm256_and_pd(self.0[1], keep[1]),
            ])
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;

    /// The AVX2 transposes and lane operations move values without changing a bit: the same as
    /// the portable lanes (distinct values, negative zero, NaN payloads, infinities).
    #[test]
    fn the_avx2_transposes_and_masks_move_every_bit_as_the_plain_lanes() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        #[target_feature(enable = "avx2")]
        fn check() {
            let special = [-0.0, f64::from_bits(0x7ff8_0000_0000_1234), f64::INFINITY];
            let vectors: [DVec3; LANES] = std::array::from_fn(|i| {
                let v = |c: usize| {
                    special
                        .get(3 * i + c)
                        .copied()
                        .unwrap_or((10 * i + c) as f64 + 0.5)
                };
                DVec3::new(v(0), v(1), v(2))
            });
            let bits = |lanes: [[f64; LANES]; 3]| lanes.map(|c| c.map(f64::to_bits));
            let out = |l: [Avx2; 3]| {
                let mut a = [[0.0; LANES]; 3];
                for (c, lane) in l.into_iter().enumerate() {
                    lane.store(&mut a[c]);
                }
                a
            };
            let plain = to_lanes::<Plain>(&vectors).map(|l| l.0);
            assert_eq!(bits(out(Avx2::load_vectors(&vectors))), bits(plain));
            let mut back = [DVec3::ZERO; LANES];
            Avx2::store_vectors(Avx2::load_vectors(&vectors), &mut back);
            let flat = |v: &[DVec3; LANES]| v.map(|p| p.to_array().map(f64::to_bits));
            assert_eq!(flat(&back), flat(&vectors));
            let x = Avx2::load(&plain[0]);
            let y = Avx2::load(&plain[1]);
            for mask in [0u8, 1, 0b1010_0101, 0x80, 0xFF] {
                let mut got = [0.0; LANES];
                x.blend(y, mask).store(&mut got);
                let expected: [f64; LANES] = std::array::from_fn(|l| {
                    if mask & (1 << l) != 0 {
                        plain[0][l]
                    } else {
                        plain[1][l]
                    }
                });
                assert_eq!(
                    got.map(f64::to_bits),
                    expected.map(f64::to_bits),
                    "blend {mask:b}"
                );
            }
            for k in 0..=LANES {
                let mut got = [0.0; LANES];
                x.clear_below(k).store(&mut got);
                let expected = Plain(plain[0]).clear_below(k).0;
                assert_eq!(
                    got.map(f64::to_bits),
                    expected.map(f64::to_bits),
                    "clear_below {k}"
                );
            }
        }
        // SAFETY: AVX2 is available (checked above).
        unsafe { check() }
    }

    /// The AVX-512 funnel (one permute) gives the lanes of the plain one (through memory), bit
    /// for bit, for every shift: lanes `r..8` of the first chunk, then `0..r` of the second.
    #[test]
    fn the_avx512_funnel_moves_every_bit_as_the_plain_lanes() {
        let values: [f64; 2 * LANES] = std::array::from_fn(|i| match i {
            3 => -0.0,
            7 => f64::from_bits(0x7ff8_0000_0000_1234),
            8 => f64::NEG_INFINITY,
            _ => i as f64 + 0.25,
        });
        let (low, high) = (lanes(&values, 0), lanes(&values, LANES));
        for r in 0..LANES {
            let plain = Plain(*low).funnel(Plain(*high), r).0;
            assert_eq!(
                plain.map(f64::to_bits),
                lanes(&values, r).map(f64::to_bits),
                "plain funnel {r}"
            );
        }
        if !std::arch::is_x86_feature_detected!("avx512f") {
            return;
        }
        #[target_feature(enable = "avx512f")]
        fn check(low: &[f64; LANES], high: &[f64; LANES], values: &[f64; 2 * LANES]) {
            for r in 0..LANES {
                let mut got = [0.0; LANES];
                Avx512::load(low)
                    .funnel(Avx512::load(high), r)
                    .store(&mut got);
                assert_eq!(
                    got.map(f64::to_bits),
                    lanes(values, r).map(f64::to_bits),
                    "AVX-512 funnel {r}"
                );
            }
        }
        // SAFETY: AVX-512F is available (checked above).
        unsafe { check(low, high, &values) }
    }
}
