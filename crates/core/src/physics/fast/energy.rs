//! The kinetic and gravitational terms of Verlet's mechanical energy
//! (`integrators/verlet.rs`, its energy accounting), a block of particles at a time with the
//! CPU's widest vectors.
//!
//! ```text
//! t_i = ½ m_i |(x_i - x_prev,i) / dt|² - m_i g·x_i
//! E   = ((0 + t_0) + t_1) + … + t_{n-1}
//! ```
//! where `m_i` (kg) is particle `i`'s mass, `x_i`, `x_prev,i` (m) its position now and one
//! step earlier, `dt` (s) the step, `g` (m/s²) gravity, `t_i` and `E` (J). The terms do not
//! depend on each other: they are computed for a block of particles first (three divisions
//! each, most of the work, which the compiler then does four or eight at a time with AVX2 or
//! AVX-512), then added in particle order as the textbook loop adds them. The operations are
//! the loop's (no fused multiply-add: Rust does not contract), so the sum is the same bits
//! (tested).
//!
//! Verlet's accounting takes `E` before and after its projection (`x` moved, `x_prev` not):
//! [`kinetic_gravity_terms`] keeps the terms before it, and [`kinetic_gravity_pair`] adds them
//! up beside the terms after it, two independent sums in one loop (each in particle order, so
//! the same bits), where two sums one after the other would wait twice for one chain of `n`
//! dependent additions. Inside [`Method::steps`](crate::physics::Method::steps) a [`Batch`]
//! keeps the terms of up to [`BATCH`] steps and adds them up together: the same chains, each
//! in particle order, but those of eight steps advance side by side instead of one step's
//! chains waiting on one addition after the other.
//!
//! Verlet's elastic term of rods is a sum of `+0` while every coordinate is bounded
//! (`integrators/verlet.rs`): [`all_below`] tests `|c| < limit` for every coordinate as a
//! count of those outside (no early exit), which the compiler does eight at a time.

use glam::DVec3;

use super::stencil::Kernel;

/// Particles per block of terms.
const BLOCK: usize = 64;

/// The terms `t_i` of the module docs into `terms` (resized to `x.len()`), as
/// the textbook loop computes them (module docs).
///
/// # Panics
/// If `mass` or `x_prev` is shorter than `x`.
pub(crate) fn kinetic_gravity_terms(
    mass: &[f64],
    gravity: DVec3,
    x: &[DVec3],
    x_prev: &[DVec3],
    dt: f64,
    terms: &mut Vec<f64>,
) {
    terms.resize(x.len(), 0.0);
    terms_into(mass, gravity, x, x_prev, dt, terms);
}

/// `(E_before, E)`: the sum of `before` (terms of [`kinetic_gravity_terms`]) and `E` of the
/// module docs at `x`, each in particle order, in one loop (module docs): bit for bit the sum
/// of `before` and of the terms at `x`, each added in particle order from `+0`.
///
/// # Panics
/// If `mass`, `x_prev` or `before` is shorter than `x`.
pub(crate) fn kinetic_gravity_pair(
    mass: &[f64],
    gravity: DVec3,
    x: &[DVec3],
    x_prev: &[DVec3],
    dt: f64,
    before: &[f64],
) -> (f64, f64) {
    let (mass, x_prev, before) = (&mass[..x.len()], &x_prev[..x.len()], &before[..x.len()]);
    pair_on(Kernel::best(), mass, gravity, x, x_prev, dt, before)
}

/// Steps whose sums [`Batch`] adds up together.
pub(crate) const BATCH: usize = 8;

/// Verlet's energies before and after the projection of up to [`BATCH`] steps of one
/// [`Method::steps`](crate::physics::Method::steps) call, added up together: each step's two
/// sums are the same chains in particle order (the same bits), but the chains of eight steps
/// advance side by side, where one step's two chains alone wait on one addition after the
/// other.
#[derive(Clone, Debug, Default)]
pub(crate) struct Batch {
    /// Set by `Method::steps` around its steps: Verlet's steps leave their projection's share
    /// of the dissipated energy to [`Batch::finish`].
    pub(crate) on: bool,
    /// Particles of a row.
    n: usize,
    /// Rows filled.
    pending: usize,
    /// Row `s` (`n` terms): step `s`'s terms `t_i` before the projection.
    before: Vec<f64>,
    /// Row `s`: step `s`'s terms after the projection.
    after: Vec<f64>,
    /// Per row: the elastic energy before and after the projection (J).
    elastic: [(f64, f64); BATCH],
}

impl Batch {
    /// True when [`BATCH`] steps wait for [`Batch::finish`].
    pub(crate) fn full(&self) -> bool {
        self.pending == BATCH
    }

    /// The terms of the next step before its projection (module docs).
    pub(crate) fn before(
        &mut self,
        mass: &[f64],
        gravity: DVec3,
        x: &[DVec3],
        x_prev: &[DVec3],
        dt: f64,
    ) {
        if self.n != x.len() {
            self.n = x.len();
            self.before = vec![0.0; BATCH * self.n];
            self.after = vec![0.0; BATCH * self.n];
        }
        let row = &mut self.before[self.pending * self.n..][..self.n];
        terms_into(mass, gravity, x, x_prev, dt, row);
    }

    /// The terms of the step after its projection, and its elastic energies before and after
    /// (J): the step waits for [`Batch::finish`].
    pub(crate) fn after(
        &mut self,
        mass: &[f64],
        gravity: DVec3,
        x: &[DVec3],
        x_prev: &[DVec3],
        dt: f64,
        elastic: (f64, f64),
    ) {
        let row = &mut self.after[self.pending * self.n..][..self.n];
        terms_into(mass, gravity, x, x_prev, dt, row);
        self.elastic[self.pending] = elastic;
        self.pending += 1;
    }

    /// Adds each waiting step's projection share, `(E_before + U_before) - (E + U)`, to the
    /// `method` part of its entry in `steps` (the last entries, one per waiting step, in step
    /// order) and sums the entry again, as Verlet's step adds it itself outside a batch.
    pub(crate) fn finish(&mut self, steps: &mut [crate::physics::energy::Dissipated]) {
        let pending = std::mem::take(&mut self.pending);
        if pending == 0 {
            return;
        }
        let first = steps.len() - pending;
        let (mut e_before, mut e) = ([0.0; BATCH], [0.0; BATCH]);
        let n = self.n;
        for i in 0..n {
            for s in 0..BATCH {
                e_before[s] += self.before[s * n + i];
                e[s] += self.after[s * n + i];
            }
        }
        for (s, d) in steps[first..].iter_mut().enumerate() {
            let (elastic_before, elastic_after) = self.elastic[s];
            let before = e_before[s] + elastic_before;
            let after = e[s] + elastic_after;
            d.method += before - after;
            *d = d.summed();
        }
    }
}

/// [`kinetic_gravity_terms`] into a row of the right length.
fn terms_into(
    mass: &[f64],
    gravity: DVec3,
    x: &[DVec3],
    x_prev: &[DVec3],
    dt: f64,
    row: &mut [f64],
) {
    let (mass, x_prev) = (&mass[..x.len()], &x_prev[..x.len()]);
    terms_on(Kernel::best(), mass, gravity, x, x_prev, dt, row);
}

/// True when every coordinate of `x` is below `limit` in magnitude (false where one is NaN):
/// `|c| < limit` for each, the same answer as testing them one by one, here all of them (no early
/// exit) eight at a time with the CPU's widest vectors.
pub(crate) fn all_below(x: &[DVec3], limit: f64) -> bool {
    // SAFETY: `DVec3` is three `f64` (`#[repr(C)]`, no padding), so `x` is `3 x.len()` of them.
    let flat = unsafe { std::slice::from_raw_parts(x.as_ptr().cast::<f64>(), 3 * x.len()) };
    below_on(Kernel::best(), flat, limit)
}

on_lanes!(below_on(kernel), plain below, (flat: &[f64], limit: f64) -> bool);

/// The count of values not below `limit` in magnitude is zero (a count, not a search, so the
/// compiler tests many values per instruction).
#[inline(always)]
fn below(flat: &[f64], limit: f64) -> bool {
    // Not below: at or above the limit, or NaN (which is below nothing).
    let outside = |c: &f64| usize::from(c.abs() >= limit || c.is_nan());
    flat.iter().map(outside).sum::<usize>() == 0
}

on_lanes!(
    terms_on(kernel),
    plain all_terms,
    (m: &[f64], g: DVec3, x: &[DVec3], xp: &[DVec3], dt: f64, t: &mut [f64]) -> ()
);

on_lanes!(
    pair_on(kernel),
    plain pair,
    (m: &[f64], g: DVec3, x: &[DVec3], xp: &[DVec3], dt: f64, b: &[f64]) -> (f64, f64)
);

/// One particle's term `t_i` (module docs).
#[inline(always)]
fn term(m: f64, gravity: DVec3, x: DVec3, x_prev: DVec3, dt: f64) -> f64 {
    let v = (x - x_prev) / dt;
    0.5 * m * v.length_squared() - m * gravity.dot(x)
}

/// Every term into `terms`.
#[inline(always)]
fn all_terms(
    mass: &[f64],
    gravity: DVec3,
    x: &[DVec3],
    x_prev: &[DVec3],
    dt: f64,
    terms: &mut [f64],
) {
    for (((t, &m), &x), &x_prev) in terms.iter_mut().zip(mass).zip(x).zip(x_prev) {
        *t = term(m, gravity, x, x_prev, dt);
    }
}

/// The terms at `x` a block at a time, then their sum beside the sum of `before`.
#[inline(always)]
fn pair(
    mass: &[f64],
    gravity: DVec3,
    x: &[DVec3],
    x_prev: &[DVec3],
    dt: f64,
    before: &[f64],
) -> (f64, f64) {
    let (mut e_before, mut e) = (0.0, 0.0);
    let mut terms = [0.0; BLOCK];
    for (((m, x), x_prev), before) in mass
        .chunks(BLOCK)
        .zip(x.chunks(BLOCK))
        .zip(x_prev.chunks(BLOCK))
        .zip(before.chunks(BLOCK))
    {
        let terms = &mut terms[..x.len()];
        all_terms(m, gravity, x, x_prev, dt, terms);
        for (t, b) in terms.iter().zip(before) {
            e_before += b;
            e += t;
        }
    }
    (e_before, e)
}

/// `E` of the module docs alone: the second sum of [`kinetic_gravity_pair`] (the tests'
/// one-sum form).
#[cfg(test)]
pub(crate) fn kinetic_gravity(
    mass: &[f64],
    gravity: DVec3,
    x: &[DVec3],
    x_prev: &[DVec3],
    dt: f64,
) -> f64 {
    kinetic_gravity_pair(mass, gravity, x, x_prev, dt, &vec![0.0; x.len()]).1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The loop of the module docs, one particle after the other.
    fn textbook(mass: &[f64], gravity: DVec3, x: &[DVec3], x_prev: &[DVec3], dt: f64) -> f64 {
        let mut e = 0.0;
        for i in 0..x.len() {
            let v = (x[i] - x_prev[i]) / dt;
            e += 0.5 * mass[i] * v.length_squared() - mass[i] * gravity.dot(x[i]);
        }
        e
    }

    /// `all_below` answers as the coordinates tested one by one: at, just below and above the
    /// limit, NaN and infinities, in every position of every size up to three vectors.
    #[test]
    fn all_below_is_every_coordinate_tested_one_by_one() {
        let limit = 1e150;
        let one_by_one = |x: &[DVec3]| {
            x.iter()
                .all(|p| p.x.abs() < limit && p.y.abs() < limit && p.z.abs() < limit)
        };
        let odd = [
            limit,
            -limit,
            f64::from_bits(limit.to_bits() - 1),
            -f64::from_bits(limit.to_bits() - 1),
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -0.0,
        ];
        for n in 0..25 {
            let clean: Vec<DVec3> = (0..n)
                .map(|i| DVec3::new(i as f64, -(i as f64) * 1e140, 0.5))
                .collect();
            let mut cases = vec![clean.clone()];
            for i in 0..n {
                for axis in 0..3 {
                    for &c in &odd {
                        let mut x = clean.clone();
                        x[i][axis] = c;
                        cases.push(x);
                    }
                }
            }
            for x in &cases {
                let want = one_by_one(x);
                assert_eq!(all_below(x, limit), want, "{x:?}");
                let flat: Vec<f64> = x.iter().flat_map(|p| p.to_array()).collect();
                assert_eq!(below(&flat, limit), want);
                #[cfg(target_arch = "x86_64")]
                for kernel in [Kernel::Avx2, Kernel::Avx512] {
                    if kernel.is_available() {
                        assert_eq!(below_on(kernel, &flat, limit), want, "{kernel:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn the_terms_and_the_pair_sum_the_textbook_loop_bit_for_bit() {
        let mut rng = crate::random::XorShift64Star::new(7);
        let mut next = || rng.unit() - 0.5;
        let gravity = DVec3::new(0.1, -9.81, 0.3);
        // Sizes below, at and above a vector and a block, not multiples of either.
        for n in [0, 1, 3, 8, 13, 64, 65, 150] {
            let x: Vec<DVec3> = (0..n).map(|_| DVec3::new(next(), next(), next())).collect();
            let x_prev: Vec<DVec3> = (x.iter())
                .map(|p| *p + 1e-3 * DVec3::new(next(), next(), next()))
                .collect();
            let mass: Vec<f64> = (0..n).map(|_| 0.5 + next()).collect();
            for dt in [1e-3, 1.0 / 60.0, 0.7] {
                let want = textbook(&mass, gravity, &x, &x_prev, dt);
                assert_eq!(
                    kinetic_gravity(&mass, gravity, &x, &x_prev, dt).to_bits(),
                    want.to_bits(),
                    "n = {n}, dt = {dt}"
                );
                // The pair: the terms at one position set, summed beside the sum at another.
                let moved: Vec<DVec3> = x.iter().map(|p| *p * 0.75 + DVec3::splat(1e-3)).collect();
                let mut before = Vec::new();
                kinetic_gravity_terms(&mass, gravity, &moved, &x_prev, dt, &mut before);
                let (e_moved, e) = kinetic_gravity_pair(&mass, gravity, &x, &x_prev, dt, &before);
                let want_moved = textbook(&mass, gravity, &moved, &x_prev, dt);
                assert_eq!(e_moved.to_bits(), want_moved.to_bits(), "pair, n = {n}");
                assert_eq!(e.to_bits(), want.to_bits(), "pair, n = {n}");
                // Every kernel's instance, not only the CPU's best.
                #[cfg(target_arch = "x86_64")]
                for kernel in [Kernel::Avx2, Kernel::Avx512] {
                    if kernel.is_available() {
                        let mut before = vec![0.0; n];
                        terms_on(kernel, &mass, gravity, &moved, &x_prev, dt, &mut before);
                        let (got_moved, got) =
                            pair_on(kernel, &mass, gravity, &x, &x_prev, dt, &before);
                        assert_eq!(got_moved.to_bits(), want_moved.to_bits(), "{kernel:?}");
                        assert_eq!(got.to_bits(), want.to_bits(), "{kernel:?}, n = {n}");
                    }
                }
            }
        }
    }
}
