//! The projection of a chain's rods, eight at a time: the fast path of
//! [`project_distances`](super::project_distances) for a rope.
//!
//! # Theory
//!
//! On a chain `0 - 1 - 2 - … - m` the greedy colouring of [`prepare_rods`](super::prepare_rods)
//! is red-black: colour 0 holds the rods `(2k, 2k + 1)`, colour 1 the rods `(2k + 1, 2k + 2)`.
//! The rods of one colour share no particle, so projecting them one after the other or all at
//! once gives the same numbers. Kept as two arrays per component, the even particles
//! `E[k] = x[2k]` and the odd ones `O[k] = x[2k + 1]`, a colour is a pass over contiguous arrays:
//!
//! ```text
//! colour 0, rod k:  a = E[k],  b = O[k]
//! colour 1, rod k:  a = O[k],  b = E[k + 1]
//! for each rod:     d = b - a,   L = sqrt(d.x·d.x + d.y·d.y + d.z·d.z)
//!                   corr = d (L - L0) / L
//!                   a += s_a corr,   b -= s_b corr
//! ```
//! where `x` are positions (m), `L0` the rest length (m) and `s_a = w_a/(w_a + w_b)`,
//! `s_b = w_b/(w_a + w_b)` the shares of the correction (dimensionless, `w` the inverse masses
//! in 1/kg), exactly the textbook loop's operations. Eight rods (one AVX-512 register of f64,
//! [`LANES`]) are computed together: one vector square root and one vector division per eight
//! rods instead of eight of each, and no rod waits for the one before it.
//!
//! **Same numbers.** Only additions, subtractions, multiplications, a square root and a
//! division, each correctly rounded (IEEE 754), in the textbook's order and without fused
//! multiply-adds: every kernel (plain Rust, AVX2, AVX-512) gives the textbook's bits (tested).
//! A chunk with a rod of zero length (the textbook skips it) or a NaN is projected rod by rod
//! with the textbook's code; lanes past the last rod of a colour are computed, then replaced
//! by the old values (a blend, which keeps every bit).
//!
//! Reference: T. Jakobsen, "Advanced Character Physics", GDC 2001 (the projection);
//! GAMES101 assignment 8 (2020), §1.3 (the rope).

use glam::DVec3;

use crate::physics::constraints::Rod;
#[cfg(target_arch = "x86_64")]
use crate::physics::lanes::{Avx2, Avx512};
use crate::physics::lanes::{LANES, Lanes, Plain, first_lanes, lanes};
use crate::physics::stencil::Kernel;

/// The chain in structure-of-arrays form (reused, so steps do not allocate): twelve arrays of
/// one length, a multiple of [`LANES`], one after the other in one buffer whose first array
/// starts a 64-byte cache line, so that every chunk of eight at an even index `k` (a multiple
/// of eight) is one line, one aligned load or store (an unaligned one spans two lines).
/// Alignment changes no value.
///
/// The arrays, in order: `x`, `y`, `z` of the even particles `2k` (m), of the odd particles
/// `2k + 1` (m), then per colour the rest length `L0` (m), `s_a`, `s_b` of rod `k`.
#[derive(Clone, Debug, Default)]
pub struct ChainScratch {
    values: Vec<f64>,
    /// Where the first array starts in `values` (its first 64-byte boundary).
    start: usize,
    /// The length of each array.
    len: usize,
}

/// Arrays of [`ChainScratch`]: `x`, `y`, `z` of the even and the odd particles, then
/// `L0`, `s_a`, `s_b` of colour 0 and of colour 1.
const ARRAYS: usize = 12;

/// The number of rods of colour 0 and colour 1 when `rods` is a whole chain `0 - 1 - … - m` in
/// red-black order (see the module docs), else `None`.
fn chain_colours(rods: &[Rod]) -> Option<(usize, usize)> {
    let m = rods.len();
    let (c0, c1) = (m.div_ceil(2), m / 2);
    let red = rods[..c0]
        .iter()
        .enumerate()
        .all(|(k, r)| r.a as usize == 2 * k && r.b as usize == 2 * k + 1);
    let black = rods[c0..]
        .iter()
        .enumerate()
        .all(|(k, r)| r.a as usize == 2 * k + 1 && r.b as usize == 2 * k + 2);
    (m > 0 && red && black).then_some((c0, c1))
}

/// Projects `rods` like [`project_distances`](super::project_distances), with the same
/// result bit for bit, when they form a chain (see the module docs), with `kernel`'s
/// instructions (the best available when `kernel` is not); returns false, and does nothing,
/// otherwise.
pub fn project_chain(
    rods: &[Rod],
    x: &mut [DVec3],
    iterations: u32,
    scratch: &mut ChainScratch,
    kernel: Kernel,
) -> bool {
    let Some((c0, c1)) = chain_colours(rods) else {
        return false;
    };
    let n = rods.len() + 1;
    if x.len() < n || iterations == 0 {
        return iterations == 0 && x.len() >= n;
    }
    scratch.load(&x[..n], rods, c0);
    let kernel = if kernel.is_available() {
        kernel
    } else {
        Kernel::best()
    };
    match kernel {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the kernel is available on this CPU (checked above).
        Kernel::Avx512 => unsafe { passes_avx512(scratch, c0, c1, iterations) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above.
        Kernel::Avx2 => unsafe { passes_avx2(scratch, c0, c1, iterations) },
        _ => passes::<Plain>(scratch, c0, c1, iterations),
    }
    scratch.store(&mut x[..n]);
    true
}

impl ChainScratch {
    /// The twelve arrays (see [`ChainScratch`]).
    #[inline]
    fn arrays(&mut self) -> [&mut [f64]; ARRAYS] {
        let len = self.len;
        let mut arrays = self.values[self.start..self.start + ARRAYS * len].chunks_exact_mut(len);
        std::array::from_fn(|_| arrays.next().expect("twelve arrays"))
    }

    /// Copies the `n` particles of the chain and its rods' coefficients in.
    fn load(&mut self, x: &[DVec3], rods: &[Rod], c0: usize) {
        let n = x.len();
        // One chunk of padding past the longest array: colour 1 reads E[k + 1].
        let len = n.div_ceil(2).next_multiple_of(LANES) + LANES;
        // The padding is never stored into; what it holds only reaches lanes that are not
        // stored either.
        if len != self.len {
            self.values = vec![0.0; ARRAYS * len + LANES];
            self.start = self.values.as_ptr().align_offset(64).min(LANES);
            self.len = len;
        }
        let [ex, ey, ez, ox, oy, oz, arrays @ ..] = self.arrays();
        let (mut even, mut odd) = ([ex, ey, ez], [ox, oy, oz]);
        for (i, p) in x.iter().enumerate() {
            let (side, k) = if i % 2 == 0 {
                (&mut even, i / 2)
            } else {
                (&mut odd, i / 2)
            };
            side[0][k] = p.x;
            side[1][k] = p.y;
            side[2][k] = p.z;
        }
        let [r0, a0, b0, r1, a1, b1] = arrays;
        let coefficients = [[r0, a0, b0], [r1, a1, b1]];
        for (list, [rest, share_a, share_b]) in
            [&rods[..c0], &rods[c0..]].into_iter().zip(coefficients)
        {
            for (k, r) in list.iter().enumerate() {
                rest[k] = r.rest_length;
                share_a[k] = r.share_a;
                share_b[k] = r.share_b;
            }
        }
    }

    /// Copies the projected positions back.
    fn store(&mut self, x: &mut [DVec3]) {
        let [ex, ey, ez, ox, oy, oz, ..] = self.arrays();
        let (even, odd) = ([ex, ey, ez], [ox, oy, oz]);
        for (i, p) in x.iter_mut().enumerate() {
            let side = if i % 2 == 0 { &even } else { &odd };
            let k = i / 2;
            *p = DVec3::new(side[0][k], side[1][k], side[2][k]);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn passes_avx512(s: &mut ChainScratch, c0: usize, c1: usize, iterations: u32) {
    passes::<Avx512>(s, c0, c1, iterations);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn passes_avx2(s: &mut ChainScratch, c0: usize, c1: usize, iterations: u32) {
    passes::<Avx2>(s, c0, c1, iterations);
}

/// `iterations` times colour 0 then colour 1 (`c0`, `c1` rods).
#[inline(always)]
fn passes<V: Lanes>(s: &mut ChainScratch, c0: usize, c1: usize, iterations: u32) {
    let [ex, ey, ez, ox, oy, oz, r0, a0, b0, r1, a1, b1] = s.arrays();
    let (mut even, mut odd) = ([ex, ey, ez], [ox, oy, oz]);
    let rods = [[&*r0, &*a0, &*b0], [&*r1, &*a1, &*b1]];
    for _ in 0..iterations {
        colour::<V>(&mut even, 0, &mut odd, &rods[0], c0);
        colour::<V>(&mut odd, 1, &mut even, &rods[1], c1);
    }
}

/// The `count` rods `k` joining `a[k]` and `b[k + b_shift]`, eight at a time.
#[inline(always)]
fn colour<V: Lanes>(
    a: &mut [&mut [f64]; 3],
    b_shift: usize,
    b: &mut [&mut [f64]; 3],
    coefficients: &[&[f64]; 3],
    count: usize,
) {
    let [ax, ay, az] = a;
    let [bx, by, bz] = b;
    let [rest, share_a, share_b] = coefficients;
    for k in (0..count).step_by(LANES) {
        let valid = (count - k).min(LANES);
        let j = k + b_shift;
        let (xa, ya, za) = (load::<V>(ax, k), load::<V>(ay, k), load::<V>(az, k));
        let (xb, yb, zb) = (load::<V>(bx, j), load::<V>(by, j), load::<V>(bz, j));
        // d = x_b - x_a, L = |d|
        let (dx, dy, dz) = (xb.sub(xa), yb.sub(ya), zb.sub(za));
        let length = dx.mul(dx).add(dy.mul(dy)).add(dz.mul(dz)).sqrt();
        let wanted = first_lanes(valid);
        if V::zero().less_than(length) & wanted != wanted {
            // A rod of zero length (skipped) or NaN: the textbook's code, rod by rod.
            for r in k..k + valid {
                let j = r + b_shift;
                let d = DVec3::new(bx[j] - ax[r], by[j] - ay[r], bz[j] - az[r]);
                let length = d.length();
                if length == 0.0 {
                    continue;
                }
                let corr = d * ((length - rest[r]) / length);
                let (pa, pb) = (share_a[r] * corr, share_b[r] * corr);
                (ax[r], ay[r], az[r]) = (ax[r] + pa.x, ay[r] + pa.y, az[r] + pa.z);
                (bx[j], by[j], bz[j]) = (bx[j] - pb.x, by[j] - pb.y, bz[j] - pb.z);
            }
            continue;
        }
        // corr = d (L - L0) / L
        let scale = length.sub(load::<V>(rest, k)).div(length);
        let (cx, cy, cz) = (dx.mul(scale), dy.mul(scale), dz.mul(scale));
        // x_a += s_a corr;  x_b -= s_b corr
        let (sa, sb) = (load::<V>(share_a, k), load::<V>(share_b, k));
        // Past the colour's last rod the old values are stored back.
        store(xa.add(sa.mul(cx)).blend(xa, wanted), ax, k);
        store(ya.add(sa.mul(cy)).blend(ya, wanted), ay, k);
        store(za.add(sa.mul(cz)).blend(za, wanted), az, k);
        store(xb.sub(sb.mul(cx)).blend(xb, wanted), bx, j);
        store(yb.sub(sb.mul(cy)).blend(yb, wanted), by, j);
        store(zb.sub(sb.mul(cz)).blend(zb, wanted), bz, j);
    }
}

#[inline(always)]
fn load<V: Lanes>(values: &[f64], at: usize) -> V {
    V::load(lanes(values, at))
}

/// `value` into `values[at..at + LANES]`.
#[inline(always)]
fn store<V: Lanes>(value: V, values: &mut [f64], at: usize) {
    value.store((&mut values[at..at + LANES]).try_into().expect("a chunk"));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::constraints::project_distances;
    use crate::random::XorShift64Star;

    /// A deterministic sequence in [-0.5, 0.5) (the crate's generator).
    struct Rng(XorShift64Star);
    impl Rng {
        fn new(seed: u64) -> Rng {
            Rng(XorShift64Star::new(seed))
        }
        fn next(&mut self) -> f64 {
            self.0.unit() - 0.5
        }
    }

    /// A chain of `n` particles with a stretched, bent shape and the red-black rods of
    /// `prepare_rods` (particle 0 pinned when `pinned`, unequal masses otherwise).
    fn chain(n: usize, pinned: bool, rng: &mut Rng) -> (Vec<Rod>, Vec<DVec3>) {
        let x: Vec<DVec3> = (0..n)
            .map(|i| {
                DVec3::new(
                    i as f64 * 0.1 + 0.03 * rng.next(),
                    rng.next(),
                    0.1 * rng.next(),
                )
            })
            .collect();
        let w: Vec<f64> = (0..n)
            .map(|i| {
                if pinned && i == 0 {
                    0.0
                } else {
                    1.0 + rng.next()
                }
            })
            .collect();
        let mut rod = |a: usize| Rod {
            a: a as u32,
            b: a as u32 + 1,
            rest_length: 0.1 + 0.01 * rng.next(),
            share_a: w[a] / (w[a] + w[a + 1]),
            share_b: w[a + 1] / (w[a] + w[a + 1]),
        };
        let mut rods = Vec::new();
        for a in (0..n - 1).step_by(2).chain((1..n - 1).step_by(2)) {
            rods.push(rod(a));
        }
        (rods, x)
    }

    fn bits(x: &[DVec3]) -> Vec<[u64; 3]> {
        x.iter()
            .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect()
    }

    #[test]
    fn every_kernel_projects_a_chain_bit_for_bit_as_the_textbook_loop() {
        let mut rng = Rng::new(7);
        let mut scratch = ChainScratch::default();
        for n in (2..40).chain([63, 64, 65, 200]) {
            for pinned in [false, true] {
                let (rods, x) = chain(n, pinned, &mut rng);
                let mut textbook = x.clone();
                project_distances(&rods, &mut textbook, 20);
                for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
                    let mut fast = x.clone();
                    assert!(project_chain(&rods, &mut fast, 20, &mut scratch, kernel));
                    assert_eq!(bits(&fast), bits(&textbook), "n = {n}, {kernel:?}");
                }
                // It did something: the rods' total length error shrank (Gauss–Seidel).
                let error = |x: &[DVec3]| -> f64 {
                    rods.iter()
                        .map(|r| {
                            ((x[r.b as usize] - x[r.a as usize]).length() - r.rest_length).abs()
                        })
                        .sum()
                };
                assert!(error(&textbook) < 0.5 * error(&x), "n = {n}");
            }
        }
    }

    #[test]
    fn rods_of_zero_length_and_negative_zeros_are_left_as_the_textbook_leaves_them() {
        let mut rng = Rng::new(11);
        let mut scratch = ChainScratch::default();
        let (rods, mut x) = chain(21, true, &mut rng);
        // Particles 4 and 5 coincide (a rod of zero length, skipped on the first pass); every
        // z is -0.0, which an added +0.0 would turn into +0.0.
        x[5] = x[4];
        for p in &mut x {
            p.z = -0.0;
        }
        for iterations in [1, 3] {
            let mut textbook = x.clone();
            project_distances(&rods, &mut textbook, iterations);
            for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
                let mut fast = x.clone();
                assert!(project_chain(
                    &rods,
                    &mut fast,
                    iterations,
                    &mut scratch,
                    kernel
                ));
                assert_eq!(bits(&fast), bits(&textbook), "{kernel:?}, {iterations}");
            }
        }
    }

    #[test]
    fn rods_that_are_not_a_whole_chain_are_left_to_the_textbook_loop() {
        let mut rng = Rng::new(3);
        let mut scratch = ChainScratch::default();
        let (mut rods, x) = chain(10, false, &mut rng);
        let mut y = x.clone();
        // Not red-black (sequential order).
        rods.sort_by_key(|r| r.a);
        assert!(!project_chain(
            &rods,
            &mut y,
            5,
            &mut scratch,
            Kernel::best()
        ));
        // A rod left out (two pinned ends).
        let (mut rods, _) = chain(10, false, &mut rng);
        rods.remove(0);
        assert!(!project_chain(
            &rods,
            &mut y,
            5,
            &mut scratch,
            Kernel::best()
        ));
        // No rods.
        assert!(!project_chain(&[], &mut y, 5, &mut scratch, Kernel::best()));
        assert_eq!(bits(&y), bits(&x));
    }
}
