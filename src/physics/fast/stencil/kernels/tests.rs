//! The AVX2 + FMA kernel against the exact one, spring by spring.

use super::*;
use crate::random::XorShift64Star;

/// One chunk: eight springs, the first ends at window index 0, the second ends at 8.
struct Chunk {
    group: Group,
    x: [Vec<f64>; 3],
    v: [Vec<f64>; 3],
}

impl Chunk {
    /// Springs `d` (m) with relative velocities `dv` (m/s), rest lengths `rest` (m), the first
    /// ends at `origin`; `present`: the lanes that hold a spring.
    fn new(
        origin: [f64; 3],
        d: [[f64; 3]; 8],
        dv: [[f64; 3]; 8],
        rest: [f64; 8],
        present: u8,
    ) -> Chunk {
        let component = |c: usize, second: &[[f64; 3]; 8]| {
            let mut values = vec![0.0; 2 * LANES];
            for l in 0..LANES {
                values[l] = origin[c];
                values[LANES + l] = origin[c] + second[l][c];
            }
            values
        };
        let velocity = |c: usize| {
            let mut values = vec![0.0; 2 * LANES];
            for l in 0..LANES {
                values[l] = 0.25;
                values[LANES + l] = 0.25 + dv[l][c];
            }
            values
        };
        Chunk {
            group: Group {
                delta: LANES,
                stiffness: 750.0,
                damping: 0.35,
                starts: LANES,
                rest_length: rest.to_vec(),
                present: vec![present],
                ring: 64,
                ring_offset: 0,
            },
            x: [component(0, &d), component(1, &d), component(2, &d)],
            v: [velocity(0), velocity(1), velocity(2)],
        }
    }

    /// `(forces, power)` of the exact kernel and of the AVX2 + FMA kernel, lane by lane.
    fn both(&self) -> [([[f64; LANES]; 3], [f64; LANES]); 2] {
        #[target_feature(enable = "avx2,fma")]
        fn run(c: &Chunk) -> [([[f64; LANES]; 3], [f64; LANES]); 2] {
            let w = Window {
                x: [&c.x[0], &c.x[1], &c.x[2]],
                v: [&c.v[0], &c.v[1], &c.v[2]],
            };
            let first = w.first_ends::<Avx2>(0);
            let out = |(f, p): (Forces<Avx2>, Avx2)| {
                let mut values = ([[0.0; LANES]; 3], [0.0; LANES]);
                for (lanes, out) in f.into_iter().zip(&mut values.0) {
                    lanes.store(out);
                }
                p.store(&mut values.1);
                values
            };
            let exact = springs_exact::<Avx2>(&c.group, &first, &w, 0, 0);
            // SAFETY: AVX2 and FMA (this function's features, checked by the caller); the
            // window holds both chunks and the group one chunk.
            let fast = unsafe { springs_avx2_fma(&c.group, &first, &w, 0, 0) };
            [out(exact), out(fast)]
        }
        // SAFETY: only called where the kernel is available (see the tests).
        unsafe { run(self) }
    }
}

fn available() -> bool {
    Kernel::Avx2Fma.is_available()
}

/// The unit roundoff of f64, 2⁻⁵³.
const U: f64 = f64::EPSILON / 2.0;

/// The bound on `|f_fast - f_exact|` per component, in units of `U · (k (L + L0) + k_d |Δv|)`.
///
/// Derivation: `y₀` has relative error at most 1.5·2⁻¹² (plus 2⁻²⁴ from rounding `a` to single
/// precision), so `|e| < 7.4e-4`; the series cut after `e⁵` leaves `(231/1024) |e|⁶ < 4e-20`,
/// far below `U`. What is left is rounding: `a` (two fused operations, against three rounded
/// ones in the exact kernel: 2 + 3 U relative), `e` (`a y₀` rounded, then one fused
/// operation: `|Δe| ≤ 2 U`, of which `y` keeps half), the series and `y` (2 U), so `y` is
/// within 4 U of `1/√a` and `L = a y` within 7 U of the exact `√a`; against the exact kernel's
/// own 3 U (`sqrt` and `1/L` each correctly rounded, `n = d/L`) the tension
/// `k (L - L0) + k_d (Δv·d)/L` differs by at most about `10 U (k L + k_d |Δv|)` and the force
/// `tension · n` by that plus `4 U |tension|` (each `≤ k (L + L0) + k_d |Δv|`): 14 U, rounded up
/// to 16.
const BOUND: f64 = 16.0;

#[test]
fn the_avx2_fma_kernel_gives_the_exact_forces_within_its_bound() {
    if !available() {
        return;
    }
    let mut rng = XorShift64Star::new(0xf3a2_0000_0000_0029);
    let mut worst: f64 = 0.0;
    for trial in 0..4000 {
        // Lengths from 1e-12 m to 1e12 m (L² from 1e-24 to 1e24, all normal singles), in
        // every direction, rest lengths around them.
        let scale = 10f64.powf(-12.0 + 24.0 * rng.unit());
        let mut unit = || rng.symmetric();
        let d: [[f64; 3]; 8] =
            std::array::from_fn(|_| [scale * unit(), scale * unit(), scale * unit()]);
        let dv: [[f64; 3]; 8] = std::array::from_fn(|_| [unit(), unit(), unit()]);
        let rest: [f64; 8] = std::array::from_fn(|_| scale * (1.0 + unit()));
        let origin = [unit(), unit(), unit()].map(|c| c * scale);
        let present = if trial % 3 == 0 { 0b1011_0111 } else { u8::MAX };
        let chunk = Chunk::new(origin, d, dv, rest, present);
        let [(exact, exact_power), (fast, fast_power)] = chunk.both();
        let g = &chunk.group;
        for l in 0..LANES {
            // d and Δv as the kernels see them (the window's differences).
            let dl: [f64; 3] = std::array::from_fn(|c| chunk.x[c][LANES + l] - chunk.x[c][l]);
            let dvl: [f64; 3] = std::array::from_fn(|c| chunk.v[c][LANES + l] - chunk.v[c][l]);
            let length = dl.iter().map(|c| c * c).sum::<f64>().sqrt();
            let speed = dvl.iter().map(|c| c * c).sum::<f64>().sqrt();
            let size = g.stiffness * (length + rest[l]) + g.damping * speed;
            for c in 0..3 {
                let error = (fast[c][l] - exact[c][l]).abs() / (U * size);
                worst = worst.max(error);
                assert!(
                    error <= BOUND,
                    "trial {trial} lane {l}: {} vs {} ({error:.1} U)",
                    fast[c][l],
                    exact[c][l]
                );
            }
            // The power k_d ((Δv·d)/L)² ≤ k_d |Δv|², relative to it the same bound.
            let power_error =
                (fast_power[l] - exact_power[l]).abs() / (U * g.damping * speed * speed);
            assert!(
                power_error <= BOUND,
                "trial {trial} lane {l}: power {power_error:.1} U"
            );
            if present & (1 << l) == 0 {
                assert!(fast[0][l] == 0.0 && fast_power[l] == 0.0, "absent lane {l}");
            }
        }
    }
    // Not loose by orders of magnitude: the measured worst case is within a factor 16.
    assert!(worst > BOUND / 16.0, "worst {worst:.2} U");
}

#[test]
fn lanes_outside_the_single_precision_range_get_the_exact_kernels_bits() {
    if !available() {
        return;
    }
    let (nan, inf) = (f64::NAN, f64::INFINITY);
    // Per lane: zero length, below the smallest normal single (L² = 1e-40), above the largest
    // (L² = 1e40), NaN, ∞, two ordinary springs and one just inside the range.
    let d = [
        [0.0, 0.0, 0.0],
        [1e-20, 0.0, 0.0],
        [0.0, 1e20, 0.0],
        [nan, 1.0, 0.0],
        [inf, 0.0, 0.0],
        [0.3, -0.4, 0.1],
        [1.0, 2.0, 2.0],
        [0.0, 0.0, 1.1e-19],
    ];
    let dv = std::array::from_fn(|l| [0.1 * l as f64, -0.2, 0.05]);
    let rest = [0.5, 1e-20, 1e20, 1.0, 1.0, 0.5, 3.0, 1e-19];
    for present in [u8::MAX, 0b0101_0101] {
        let chunk = Chunk::new([0.0; 3], d, dv, rest, present);
        let [(exact, exact_power), (fast, fast_power)] = chunk.both();
        for l in [0, 1, 2, 3, 4] {
            for c in 0..3 {
                assert!(
                    fast[c][l].to_bits() == exact[c][l].to_bits(),
                    "lane {l} component {c}: {} vs {}",
                    fast[c][l],
                    exact[c][l]
                );
            }
            assert!(
                fast_power[l].to_bits() == exact_power[l].to_bits(),
                "lane {l} power"
            );
        }
        // What those lanes get: no force from a zero-length spring, NaN where the run diverges.
        assert!(fast.iter().all(|c| c[0] == 0.0));
        if present & (1 << 3) != 0 {
            assert!(fast[0][3].is_nan());
        }
        // The ordinary lanes of the same chunk keep the fast kernel's accuracy.
        for l in [5, 6, 7] {
            for c in 0..3 {
                let tolerance = 1e-14 * (1.0 + exact[c][l].abs()) * 750.0;
                assert!((fast[c][l] - exact[c][l]).abs() <= tolerance, "lane {l}");
            }
        }
    }
}
