//! XPBD's constraint pass ([`crate::physics::constraints::xpbd_solve`], the textbook form) laid
//! out once and run eight springs at a time.
//!
//! **Constants once.** Every substep of a step has the same length `h`, so each spring's
//! compliance term `α̃ = 1/(k h²)` and damping term `γ = k_d/(k h)` (two divisions) are the same
//! in all its `substeps × iterations` passes, and in every later step with the same `h` and the
//! same springs. [`XpbdRows::prepare`] computes them with the textbook's operations and lays the
//! springs out as arrays in the order the textbook pass visits them (colour by colour), those
//! without stiffness left out as it leaves them out; the layout is kept while the model's
//! springs (their revision, which every change renews) and `h` stay the same. The particles'
//! inverse masses are read in the pass, not kept: a model's masses are public and may change
//! between steps (pinning).
//!
//! **Eight at a time.** No two springs of a colour share a particle, so the textbook's result
//! does not depend on the order within a colour: on a CPU with AVX-512 the pass takes eight
//! springs of a colour at once, each end's `x, y, z` read whole and turned into lanes, and
//! computes each lane with the textbook's operations in its order (no fused multiply-add).
//!
//! Elsewhere (no AVX-512) the textbook pass runs. The positions and multipliers are the
//! textbook's bit for bit (`tests/physics.rs` compares the two on the lattices; the test below
//! on a model that is not one, with pinned ends, dampers, zero stiffness and a spring of zero
//! length). On the jelly cube (1 000 particles, 12 876 springs, 10 substeps) the pass takes
//! about half the textbook's time (docs/performance.md).

use glam::DVec3;

use crate::physics::forces::{Model, SpringsRevision};
#[cfg(target_arch = "x86_64")]
use crate::physics::stencil::Kernel;

/// Bytes per spring of [`XpbdRows`]: two ends (`i64`) and four numbers (`f64`: rest length,
/// `α̃`, `γ`, `λ`).
pub(crate) const ROW_BYTES: usize = 2 * size_of::<i64>() + 4 * size_of::<f64>();

/// The springs of one step's passes, in the textbook pass's order, as arrays (one entry per
/// row): their ends, rest lengths (m), `α̃ = 1/(k h²)` (1/kg), `γ = k_d/(k h)`
/// (dimensionless) and multipliers `λ` (N·s²); `colours[c]..colours[c + 1]` are the rows of
/// colour `c`.
#[derive(Clone, Debug, Default)]
pub(crate) struct XpbdRows {
    a: Vec<i64>,
    b: Vec<i64>,
    rest: Vec<f64>,
    alpha_tilde: Vec<f64>,
    gamma: Vec<f64>,
    lambda: Vec<f64>,
    colours: Vec<usize>,
    /// One more than the largest end of a row: the particles a pass needs.
    needs: usize,
    /// What the rows were laid out for: the model's springs and `h` (its bits).
    key: (SpringsRevision, u64),
}

impl XpbdRows {
    /// Lays out the springs of `model` for substeps of `h` seconds (module docs), unless they
    /// are laid out for the same springs and `h` already. False, with nothing done, where the
    /// pass cannot take eight springs at a time (no AVX-512, or that kernel turned off with
    /// `SPRINGLAB_KERNEL`, or a colouring whose last colour holds springs that share
    /// particles): the caller takes the textbook pass.
    pub(crate) fn prepare(&mut self, model: &Model, h: f64) -> bool {
        if !wide() || !model.colours_disjoint() {
            return false;
        }
        let revision = model.springs_revision();
        if revision.same(self.key.0) && h.to_bits() == self.key.1 {
            return true;
        }
        self.key = (revision, h.to_bits());
        self.a.clear();
        self.b.clear();
        self.rest.clear();
        self.alpha_tilde.clear();
        self.gamma.clear();
        self.colours.clear();
        self.colours.push(0);
        for colour in model.spring_colours() {
            for &si in colour {
                let s = &model.springs[si as usize];
                if s.stiffness <= 0.0 {
                    // Zero stiffness is infinite compliance: no force (the textbook skips it).
                    continue;
                }
                self.a.push(i64::from(s.a));
                self.b.push(i64::from(s.b));
                self.rest.push(s.rest_length);
                // α̃ = 1/(k h²), γ = k_d/(k h): the textbook pass's operations.
                self.alpha_tilde.push(1.0 / (s.stiffness * h * h));
                self.gamma.push(s.damping / (s.stiffness * h));
            }
            self.colours.push(self.a.len());
        }
        self.lambda.clear();
        self.lambda.resize(self.a.len(), 0.0);
        self.needs = (self.a.iter().chain(&self.b))
            .map(|&i| i as usize + 1)
            .max()
            .unwrap_or(0);
        true
    }

    /// `λ = 0`: the start of a substep.
    pub(crate) fn start_substep(&mut self) {
        self.lambda.fill(0.0);
    }

    /// One pass over the springs as compliant constraints, as the textbook pass, eight springs
    /// of a colour at a time: positions `x` (m) moved, `x_prev` (m) those at the start of the
    /// substep, `inv_mass` (1/kg) the model's.
    ///
    /// # Panics
    /// If the rows are not laid out ([`XpbdRows::prepare`] returned false) or a spring's end is
    /// out of range of `x`, `x_prev` or `inv_mass`.
    pub(crate) fn solve(&mut self, inv_mass: &[f64], x: &mut [DVec3], x_prev: &[DVec3]) {
        let n = x.len().min(x_prev.len()).min(inv_mass.len());
        assert!(self.needs <= n, "a spring's end out of range");
        assert!(
            wide() && !self.colours.is_empty(),
            "laid out for eight at a time"
        );
        #[cfg(target_arch = "x86_64")]
        // SAFETY: AVX-512F and VL are there (`wide`), every end is in range (asserted above),
        // and the rows of a colour share no particle (`prepare` laid them out only then).
        unsafe {
            self.solve_avx512(inv_mass, x, x_prev);
        }
    }

    /// [`XpbdRows::solve`] eight rows of a colour at a time: each end's position and its
    /// position at the start of the substep read whole (one 256-bit load of `x, y, z`) and
    /// turned into lanes, the textbook's operations lane by lane (no fused multiply-add, so
    /// each lane rounds as the scalar code does), the moved ends written back the same way; a
    /// lane whose spring the textbook skips (both ends pinned, zero length) writes nothing.
    ///
    /// # Safety
    /// The CPU must support AVX-512F and AVX-512VL; every row's ends must be below the lengths
    /// of `x`, `x_prev` and `inv_mass`; the rows of a colour must share no particle.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl")]
    unsafe fn solve_avx512(&mut self, inv_mass: &[f64], x: &mut [DVec3], x_prev: &[DVec3]) {
        use std::arch::x86_64::{
            __m512d, _CMP_NEQ_UQ, _mm256_mask_storeu_pd, _mm256_maskz_loadu_pd, _mm512_add_pd,
            _mm512_castpd_si512, _mm512_castpd256_pd512, _mm512_castpd512_pd256,
            _mm512_castsi512_pd, _mm512_cmp_pd_mask, _mm512_div_pd, _mm512_extractf64x4_pd,
            _mm512_insertf64x4, _mm512_loadu_epi64, _mm512_mask_i64gather_pd, _mm512_mask_loadu_pd,
            _mm512_mask_storeu_pd, _mm512_mul_pd, _mm512_permutex2var_pd, _mm512_set1_epi64,
            _mm512_set1_pd, _mm512_setr_epi64, _mm512_setzero_pd, _mm512_sqrt_pd, _mm512_sub_pd,
            _mm512_xor_si512,
        };
        const _: () = assert!(
            std::mem::size_of::<DVec3>() == 24,
            "x, y, z one after another"
        );
        // SAFETY (the block): AVX-512F and VL (the caller); every load and store of a
        // position reads or writes the three components of `x[i]` or `x_prev[i]` (masked to
        // three of four lanes) for an end `i` below their lengths (the caller); the gathers
        // read `inv_mass` at an end; the masked loads and stores of the rows stay within them.
        unsafe {
            let zero = _mm512_setzero_pd();
            let one = _mm512_set1_pd(1.0);
            let sign = _mm512_set1_epi64(i64::MIN);
            // Lanes of four particles' [x y z 0] pairs: x, y of four, then z of four.
            let xy = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
            let zz = _mm512_setr_epi64(2, 6, 10, 14, 2, 6, 10, 14);
            let low = _mm512_setr_epi64(0, 1, 2, 3, 8, 9, 10, 11);
            let high = _mm512_setr_epi64(4, 5, 6, 7, 12, 13, 14, 15);
            // Back: x, y of two particles interleaved, then [x y z z] of each.
            let pairs_low = _mm512_setr_epi64(0, 8, 1, 9, 2, 10, 3, 11);
            let pairs_high = _mm512_setr_epi64(4, 12, 5, 13, 6, 14, 7, 15);
            let put = [
                _mm512_setr_epi64(0, 1, 8, 8, 2, 3, 9, 9),
                _mm512_setr_epi64(4, 5, 10, 10, 6, 7, 11, 11),
                _mm512_setr_epi64(0, 1, 12, 12, 2, 3, 13, 13),
                _mm512_setr_epi64(4, 5, 14, 14, 6, 7, 15, 15),
            ];
            // The positions of particles idx[0..8] (those of lanes in `m`) as x, y, z lanes.
            let read = |base: *const DVec3, idx: &[i64; 8], m: u8| -> [__m512d; 3] {
                let one_particle = |k: usize| {
                    let keep = if m >> k & 1 == 1 { 0b0111 } else { 0 };
                    _mm256_maskz_loadu_pd(keep, base.add(idx[k] as usize).cast::<f64>())
                };
                let two = |k: usize| {
                    _mm512_insertf64x4::<1>(
                        _mm512_castpd256_pd512(one_particle(k)),
                        one_particle(k + 1),
                    )
                };
                let (q01, q23, q45, q67) = (two(0), two(2), two(4), two(6));
                let a = _mm512_permutex2var_pd(q01, xy, q23);
                let b = _mm512_permutex2var_pd(q45, xy, q67);
                let c = _mm512_permutex2var_pd(q01, zz, q23);
                let d = _mm512_permutex2var_pd(q45, zz, q67);
                [
                    _mm512_permutex2var_pd(a, low, b),
                    _mm512_permutex2var_pd(a, high, b),
                    _mm512_permutex2var_pd(c, low, d),
                ]
            };
            // Writes x, y, z lanes back to the particles idx[0..8] of the lanes in `m`.
            let write = |base: *mut DVec3, idx: &[i64; 8], m: u8, p: [__m512d; 3]| {
                let t = [
                    _mm512_permutex2var_pd(p[0], pairs_low, p[1]),
                    _mm512_permutex2var_pd(p[0], pairs_high, p[1]),
                ];
                for (j, put) in put.iter().enumerate() {
                    let q = _mm512_permutex2var_pd(t[j / 2], *put, p[2]);
                    let halves = [_mm512_castpd512_pd256(q), _mm512_extractf64x4_pd::<1>(q)];
                    for (h, half) in halves.into_iter().enumerate() {
                        let k = 2 * j + h;
                        let keep = if m >> k & 1 == 1 { 0b0111 } else { 0 };
                        _mm256_mask_storeu_pd(base.add(idx[k] as usize).cast::<f64>(), keep, half);
                    }
                }
            };
            let (xs, ps) = (x.as_mut_ptr(), x_prev.as_ptr());
            let ws = inv_mass.as_ptr();
            for c in 0..self.colours.len() - 1 {
                let (first, end) = (self.colours[c], self.colours[c + 1]);
                for r in (first..end).step_by(8) {
                    let m: u8 = if end - r >= 8 {
                        0xff
                    } else {
                        (1u8 << (end - r)) - 1
                    };
                    let load = |v: &[f64]| _mm512_mask_loadu_pd(zero, m, v.as_ptr().add(r));
                    let mut ia = [0i64; 8];
                    let mut ib = [0i64; 8];
                    let count = (end - r).min(8);
                    ia[..count].copy_from_slice(&self.a[r..r + count]);
                    ib[..count].copy_from_slice(&self.b[r..r + count]);
                    let w_a =
                        _mm512_mask_i64gather_pd::<8>(zero, m, _mm512_loadu_epi64(ia.as_ptr()), ws);
                    let w_b =
                        _mm512_mask_i64gather_pd::<8>(zero, m, _mm512_loadu_epi64(ib.as_ptr()), ws);
                    let w = _mm512_add_pd(w_a, w_b);
                    let mut active = _mm512_cmp_pd_mask::<_CMP_NEQ_UQ>(w, zero) & m;
                    let xa = read(xs, &ia, m);
                    let xb = read(xs, &ib, m);
                    // d = x_b - x_a, L = |d| = √((d_x² + d_y²) + d_z²) (glam's order)
                    let d: [_; 3] = std::array::from_fn(|k| _mm512_sub_pd(xb[k], xa[k]));
                    let dd = _mm512_add_pd(
                        _mm512_add_pd(_mm512_mul_pd(d[0], d[0]), _mm512_mul_pd(d[1], d[1])),
                        _mm512_mul_pd(d[2], d[2]),
                    );
                    let length = _mm512_sqrt_pd(dd);
                    active &= _mm512_cmp_pd_mask::<_CMP_NEQ_UQ>(length, zero);
                    let n: [_; 3] = std::array::from_fn(|k| _mm512_div_pd(d[k], length));
                    let cc = _mm512_sub_pd(length, load(&self.rest));
                    let pa = read(ps, &ia, m);
                    let pb = read(ps, &ib, m);
                    // (x_b - x_prev,b) - (x_a - x_prev,a), then its dot with n
                    let u: [_; 3] = std::array::from_fn(|k| {
                        _mm512_sub_pd(_mm512_sub_pd(xb[k], pb[k]), _mm512_sub_pd(xa[k], pa[k]))
                    });
                    let c_dot = _mm512_add_pd(
                        _mm512_add_pd(_mm512_mul_pd(n[0], u[0]), _mm512_mul_pd(n[1], u[1])),
                        _mm512_mul_pd(n[2], u[2]),
                    );
                    let alpha_tilde = load(&self.alpha_tilde);
                    let gamma = load(&self.gamma);
                    let lambda = load(&self.lambda);
                    // ((-c) - α̃ λ) - γ ċ over (1 + γ)(w_a + w_b) + α̃
                    let minus_c =
                        _mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(cc), sign));
                    let numerator = _mm512_sub_pd(
                        _mm512_sub_pd(minus_c, _mm512_mul_pd(alpha_tilde, lambda)),
                        _mm512_mul_pd(gamma, c_dot),
                    );
                    let denominator =
                        _mm512_add_pd(_mm512_mul_pd(_mm512_add_pd(one, gamma), w), alpha_tilde);
                    let delta = _mm512_div_pd(numerator, denominator);
                    _mm512_mask_storeu_pd(
                        self.lambda.as_mut_ptr().add(r),
                        active,
                        _mm512_add_pd(lambda, delta),
                    );
                    // x_a -= (w_a Δλ) n, x_b += (w_b Δλ) n
                    let (t_a, t_b) = (_mm512_mul_pd(w_a, delta), _mm512_mul_pd(w_b, delta));
                    let new_a =
                        std::array::from_fn(|k| _mm512_sub_pd(xa[k], _mm512_mul_pd(t_a, n[k])));
                    let new_b =
                        std::array::from_fn(|k| _mm512_add_pd(xb[k], _mm512_mul_pd(t_b, n[k])));
                    write(xs, &ia, active, new_a);
                    write(xs, &ib, active, new_b);
                }
            }
        }
    }
}

/// True where the pass can take eight springs at a time: AVX-512F and VL, and that kernel not
/// turned off ([`Kernel::best`]).
fn wide() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        Kernel::best() == Kernel::Avx512
            && std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512vl")
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::constraints::xpbd_solve;
    use crate::physics::springs::{Spring, SpringKind};
    use crate::random::XorShift64Star;

    /// The textbook pass and this one, from the same state, `passes` passes in `substeps`
    /// substeps: the same positions bit for bit.
    #[test]
    fn the_pass_is_the_textbook_pass_bit_for_bit() {
        let mut random = XorShift64Star::new(0x5eed_0000_0000_0029);
        let n = 40;
        let mut x: Vec<DVec3> = (0..n)
            .map(|_| DVec3::new(random.symmetric(), random.symmetric(), random.symmetric()))
            .collect();
        // Particle 7 on top of particle 3: a spring of zero length.
        x[7] = x[3];
        let spring = |a: u32, b: u32, stiffness: f64, damping: f64, rest_length: f64| Spring {
            a,
            b,
            rest_length,
            stiffness,
            damping,
            kind: SpringKind::Struct,
        };
        let mut springs = Vec::new();
        for k in 0..160u32 {
            let a = (k * 7 + 3) % n as u32;
            let b = (k * 13 + 5) % n as u32;
            if a == b {
                continue;
            }
            let stiffness = match k % 9 {
                0 => 0.0,
                _ => 10.0 + 1000.0 * random.symmetric().abs(),
            };
            let damping = if k % 4 == 0 {
                0.0
            } else {
                random.symmetric().abs()
            };
            springs.push(spring(
                a,
                b,
                stiffness,
                damping,
                0.5 * random.symmetric().abs(),
            ));
        }
        springs.push(spring(3, 7, 50.0, 0.1, 0.2));
        let mass: Vec<f64> = (0..n).map(|i| 0.5 + (i % 5) as f64).collect();
        let pinned: Vec<bool> = (0..n).map(|i| i % 11 == 0).collect();
        // Two pinned ends: a spring the pass leaves out.
        springs.push(spring(0, 11, 80.0, 0.0, 1.0));
        let model = Model::new(mass, &pinned, springs, DVec3::new(0.0, -9.81, 0.0), 0.0);
        let x_prev: Vec<DVec3> = (x.iter())
            .map(|p| *p + 1e-3 * DVec3::new(random.symmetric(), random.symmetric(), 0.0))
            .collect();
        for (substeps, passes) in [(1, 1), (3, 2), (2, 5)] {
            let h = 1e-3 / f64::from(substeps);
            let (mut textbook, mut fast) = (x.clone(), x.clone());
            let mut lambda = vec![0.0; model.springs().len()];
            let mut rows = XpbdRows::default();
            if !rows.prepare(&model, h) {
                eprintln!("no AVX-512 here: the textbook pass runs instead, nothing to compare");
                return;
            }
            for _ in 0..substeps {
                lambda.fill(0.0);
                rows.start_substep();
                for _ in 0..passes {
                    xpbd_solve(&model, &mut textbook, &x_prev, &mut lambda, h);
                    rows.solve(&model.inv_mass, &mut fast, &x_prev);
                }
            }
            let bits = |x: &[DVec3]| -> Vec<[u64; 3]> {
                x.iter().map(|p| p.to_array().map(f64::to_bits)).collect()
            };
            let label = format!("{substeps} substeps, {passes} passes");
            assert_eq!(bits(&fast), bits(&textbook), "{label}");
            assert_ne!(
                bits(&fast),
                bits(&x),
                "{label}: the pass moved the particles"
            );
        }
    }

    /// The layout follows the springs: a change of their coefficients between two steps (a
    /// lesson's slider) is in the next step's pass, as in the textbook's; an unchanged model
    /// and `h` keep it.
    #[test]
    fn a_change_of_the_springs_renews_the_layout() {
        let springs: Vec<Spring> = (0..5u32)
            .map(|i| Spring {
                a: i,
                b: i + 1,
                rest_length: 0.5,
                stiffness: 100.0,
                damping: 0.5,
                kind: SpringKind::Struct,
            })
            .collect();
        let mut model = Model::new(
            vec![1.0; 6],
            &[true, false, false, false, false, false],
            springs,
            DVec3::ZERO,
            0.0,
        );
        let x: Vec<DVec3> = (0..6)
            .map(|i| DVec3::new(0.6 * f64::from(i), 0.0, 0.0))
            .collect();
        let h = 1e-3;
        let mut rows = XpbdRows::default();
        for change in [None, Some(2.0), None, Some(0.5)] {
            if let Some(factor) = change {
                model.scale_stiffness(factor);
            }
            let (mut textbook, mut fast) = (x.clone(), x.clone());
            let mut lambda = vec![0.0; 5];
            xpbd_solve(&model, &mut textbook, &x, &mut lambda, h);
            if !rows.prepare(&model, h) {
                return;
            }
            rows.start_substep();
            rows.solve(&model.inv_mass, &mut fast, &x);
            assert_eq!(fast, textbook, "after {change:?}");
        }
    }

    /// A particle with more springs than the colouring has colours (a star of 70): its last
    /// colour holds springs that share the centre, so the rows are not laid out and the step
    /// takes the textbook pass.
    #[test]
    fn a_colouring_that_runs_out_of_colours_is_left_to_the_textbook() {
        let springs: Vec<Spring> = (1..=70u32)
            .map(|b| Spring {
                a: 0,
                b,
                rest_length: 1.0,
                stiffness: 10.0,
                damping: 0.0,
                kind: SpringKind::Struct,
            })
            .collect();
        let model = Model::new(vec![1.0; 71], &[false; 71], springs, DVec3::ZERO, 0.0);
        assert!(!model.colours_disjoint());
        assert!(!XpbdRows::default().prepare(&model, 1e-3));
    }
}
