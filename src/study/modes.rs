//! The stiffest mode of a mass-spring system: `ω_max`, the angular frequency that sets the
//! stability limit of every explicit method.
//!
//! # Theory
//!
//! Linearised about a state `x`, the undamped motion of small displacements `δx` obeys
//! `M δx'' = -K δx`, where `K = -∂f/∂x` is assembled from one 3×3 block per spring, exactly as the
//! implicit Euler step builds it ([`crate::physics::integrators`], implicit Euler):
//!
//! ```text
//! n       = (x_b - x_a) / L,   L = |x_b - x_a|
//! K_s     = k [ n nᵀ + max(0, 1 - L0/L) (I - n nᵀ) ]        (N/m)
//! K_aa   += K_s,   K_bb += K_s,   K_ab = K_ba = -K_s
//! ω_i²    = λ_i(M⁻¹K)                                        (rad²/s²)
//! ω_max   = √λ_max(M⁻¹K)                                     (rad/s)
//! ```
//! where
//! - `k`: spring stiffness (N/m), `L0`: rest length (m), `L`: current length (m)
//! - `M`: the diagonal mass matrix (kg); pinned particles (`1/m = 0`) are removed with their rows
//!   and columns, since their `δx` is held at zero
//! - `λ_i`: the eigenvalues (1/s²), `ω_i`: the angular frequencies of the normal modes (rad/s)
//!
//! The transverse term is clamped at zero for a compressed spring (Choi & Ko 2002, §4), so every
//! `K_s` is symmetric positive semidefinite, and so is `K`. A spring of zero length has no
//! direction and contributes nothing. Damping, drag and contact are left out: `ω_max` is the
//! frequency of the undamped springs, the `ω` of the stability limits `dt·ω`.
//!
//! **Power iteration.** `M⁻¹K` is not symmetric, but it is similar to the symmetric positive
//! semidefinite `A = M^(-1/2) K M^(-1/2)` (`A = M^(1/2) (M⁻¹K) M^(-1/2)`), which has the same
//! eigenvalues. Starting from a fixed pseudo-random vector `q_0`:
//!
//! ```text
//! y_k     = A q_k
//! λ_k     = q_kᵀ y_k                    Rayleigh quotient, |q_k| = 1
//! r_k     = |y_k - λ_k q_k| / λ_k       relative residual
//! q_{k+1} = y_k / |y_k|
//! ```
//! For a symmetric positive semidefinite `A` the Rayleigh quotients never decrease and converge
//! to `λ_max` like `(λ_2/λ_max)^(2k)` (Golub & Van Loan, §7.3.1, §8.2.1): they are lower bounds.
//! The iteration stops when `r_k ≤ 10⁻¹⁰` (the vector has converged), when one iteration raises
//! `λ_k` by less than `10⁻⁸ λ_k` (the quotient has: with the nearly degenerate top of a lattice's
//! spectrum the vector converges far more slowly than the value), or after [`MAX_ITERATIONS`].
//! On the W1 jelly that is about 2000 iterations, `λ` within `10⁻⁴` of its limit.
//!
//! **Gershgorin bound.** Every eigenvalue of `M⁻¹K` lies in a disc centred on a diagonal entry
//! with radius the sum of the absolute values of the rest of its row (Golub & Van Loan, §7.2.1):
//!
//! ```text
//! λ_max ≤ max_i Σ_j |(M⁻¹K)_ij|
//! ```
//! an upper bound that costs one pass over the springs. So `λ_power ≤ λ_max ≤ λ_Gershgorin`.
//! [`spring_gershgorin`] is the same bound with each spring taken as a scalar spring (no
//! geometry, no state): the budget estimates and the lesson app's status line use it.
//!
//! Checks: for the oscillator (one spring, one free mass) `ω_max = √(k/m) = 10` rad/s exactly;
//! for a chain of `N` free masses hanging from a pinned end, at rest,
//! `ω_max² = 4 (k/m) sin²((2N - 1) π / (4N + 2))` (a fixed–free chain); for the W1 jelly at rest
//! `λ_max = 3.37·10⁴` 1/s², `ω_max = 184` rad/s (`docs/workloads.md`).
//!
//! References: G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., Johns Hopkins 2013,
//! §7.2.1 (Gershgorin), §7.3.1 (the power method), §8.2.1 (the symmetric power method);
//! D. Baraff, A. Witkin, "Large Steps in Cloth Simulation", SIGGRAPH 1998, §5 (the spring
//! Jacobians); K.-J. Choi, H.-S. Ko, "Stable but Responsive Cloth", SIGGRAPH 2002, §4.

use glam::{DMat3, DVec3};
use serde::Serialize;

use crate::physics::fast::quadratic;
use crate::physics::{Model, Spring, State};
use crate::random::XorShift64Star;

/// Iteration limit of the power iteration.
pub const MAX_ITERATIONS: u32 = 20_000;

/// Stop when the relative residual `|A q - λ q| / λ` falls below this.
pub const RESIDUAL_TOLERANCE: f64 = 1e-10;

/// Stop when one iteration changes the Rayleigh quotient by less than this, relatively.
pub const STALL_TOLERANCE: f64 = 1e-8;

/// The estimate of the stiffest mode (see the module documentation).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OmegaEstimate {
    /// `ω_max = √λ_max(M⁻¹K)` from the power iteration (rad/s).
    pub omega: f64,
    /// How `omega` was computed: `"power iteration"`.
    pub method: &'static str,
    /// The Rayleigh quotient `λ_max(M⁻¹K)` (1/s²): a lower bound.
    pub lambda: f64,
    /// Power iterations taken.
    pub iterations: u32,
    /// Final relative residual `|A q - λ q| / λ` (dimensionless).
    pub residual: f64,
    /// The Gershgorin upper bound on `λ_max(M⁻¹K)` (1/s²).
    pub gershgorin_lambda: f64,
    /// `√gershgorin_lambda` (rad/s): an upper bound on `ω_max`.
    pub gershgorin_omega: f64,
}

/// The angular frequency `ω_max` (rad/s) of the stiffest mode of `model` linearised at `state`,
/// by power iteration on `M^(-1/2) K M^(-1/2)`, with the Gershgorin upper bound beside it.
///
/// Deterministic: the start vector is a fixed pseudo-random sequence. A model without free
/// particles or without stiffness gives `omega = 0`.
///
/// # Panics
/// If `state` has fewer particles than `model`.
#[must_use]
pub fn omega_max(model: &Model, state: &State) -> OmegaEstimate {
    omega_max_from(model, state, &mut Vec::new())
}

/// [`omega_max`] started from `warm` (the vector a previous call left there) when it has one
/// entry per particle and is not zero, else from the fixed start vector; leaves the final
/// vector in `warm`. Along a motion sampled finely the stiffest mode changes little between
/// samples, so a warm start needs a few iterations instead of thousands. The result is still
/// the Rayleigh quotient of the last vector: a lower bound on `λ_max`.
///
/// # Panics
/// If `state` has fewer particles than `model`.
pub fn omega_max_from(model: &Model, state: &State, warm: &mut Vec<DVec3>) -> OmegaEstimate {
    estimate(model, state, warm, true)
}

/// [`omega_max_from`] without the Gershgorin bound (its fields NaN): the same power iteration
/// and the same `ω_max`, for a caller that samples `ω_max` along a run and never reads the bound
/// (the stability study's stiffest state: the bound is a pass over the springs per sample).
///
/// # Panics
/// If `state` has fewer particles than `model`.
pub fn omega_max_unbounded(model: &Model, state: &State, warm: &mut Vec<DVec3>) -> OmegaEstimate {
    estimate(model, state, warm, false)
}

/// [`omega_max_from`], with the Gershgorin bound when `bound`.
fn estimate(model: &Model, state: &State, warm: &mut Vec<DVec3>, bound: bool) -> OmegaEstimate {
    let n = model.particle_count();
    let blocks = stiffness_blocks(model, &state.x);
    let free: Vec<bool> = (0..n).map(|i| !model.is_pinned(i)).collect();
    let gershgorin_lambda = if bound {
        gershgorin(model, &blocks, &free)
    } else {
        f64::NAN
    };

    // s_i = 1/√m_i for free particles, 0 for pinned ones: A = S K S with the pinned rows
    // and columns zeroed.
    let scale: Vec<f64> = (0..n)
        .map(|i| {
            if free[i] {
                model.inv_mass[i].sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let mut q = if warm.len() == n && norm(warm) > 0.0 {
        let mut q = std::mem::take(warm);
        for (q, s) in q.iter_mut().zip(&scale) {
            if *s == 0.0 {
                *q = DVec3::ZERO;
            }
        }
        let q_norm = norm(&q);
        if q_norm > 0.0 {
            for q in &mut q {
                *q /= q_norm;
            }
            q
        } else {
            start_vector(&scale)
        }
    } else {
        start_vector(&scale)
    };
    let mut y = vec![DVec3::ZERO; n];
    let mut u = vec![DVec3::ZERO; n];
    let mut lambda = 0.0;
    let mut residual = f64::INFINITY;
    let mut iterations = 0;
    if norm(&q) > 0.0 {
        while iterations < MAX_ITERATIONS {
            apply(model, &blocks, &scale, &q, &mut u, &mut y);
            iterations += 1;
            // λ_k = q_kᵀ A q_k (|q_k| = 1)
            let lambda_new = dot(&q, &y);
            // r_k = |A q_k - λ_k q_k|
            let r: f64 = q
                .iter()
                .zip(&y)
                .map(|(q, y)| (*y - lambda_new * *q).length_squared())
                .sum::<f64>()
                .sqrt();
            let y_norm = norm(&y);
            if lambda_new <= 0.0 || y_norm == 0.0 {
                // q lies in the null space: no stiffness reaches the free particles.
                lambda = 0.0;
                residual = 0.0;
                break;
            }
            let change = (lambda_new - lambda).abs();
            lambda = lambda_new;
            residual = r / lambda;
            // q_{k+1} = A q_k / |A q_k| (the divisions several at a time)
            std::mem::swap(&mut q, &mut y);
            quadratic::divide(&mut q, y_norm);
            if residual <= RESIDUAL_TOLERANCE || change <= STALL_TOLERANCE * lambda {
                break;
            }
        }
    } else {
        residual = 0.0;
    }
    *warm = q;
    OmegaEstimate {
        omega: lambda.max(0.0).sqrt(),
        method: "power iteration",
        lambda,
        iterations,
        residual,
        gershgorin_lambda,
        gershgorin_omega: gershgorin_lambda.sqrt(),
    }
}

/// `K_s = k [n nᵀ + max(0, 1 - L0/L)(I - n nᵀ)]` for every spring (zero for a zero length).
pub(crate) fn stiffness_blocks(model: &Model, x: &[DVec3]) -> Vec<DMat3> {
    model.springs().iter().map(|s| spring_block(s, x)).collect()
}

/// `K_s` of one spring at `x` (formula of the module docs; zero for a zero length).
fn spring_block(s: &Spring, x: &[DVec3]) -> DMat3 {
    let d = x[s.b as usize] - x[s.a as usize];
    let length = d.length();
    if length == 0.0 {
        return DMat3::ZERO;
    }
    let n = d / length;
    let nn = DMat3::from_cols(n * n.x, n * n.y, n * n.z);
    let transverse = (1.0 - s.rest_length / length).max(0.0);
    s.stiffness * (nn + transverse * (DMat3::IDENTITY - nn))
}

/// Every spring's `K_s` in the form the products read it: the two ends and the six numbers of
/// the symmetric block, `(xx, xy, xz, yy, yz, zz)`, in six arrays — 56 bytes a spring instead of
/// the 72 of a 3×3 matrix and the spring itself, and the form [`quadratic`]'s blocks of springs
/// read. `K_s` is symmetric bit for bit (every entry is built from `n_i n_j = n_j n_i`, and sums
/// and scalings keep that), so the product from the six numbers, column by column as glam's
/// `DMat3 * DVec3`, gives the same bits (tested).
#[derive(Clone, Debug, Default)]
pub(crate) struct Blocks {
    /// The spring's ends `(a, b)`.
    pub ends: Vec<[u32; 2]>,
    /// `xx, xy, xz, yy, yz, zz` of every `K_s` (N/m).
    pub k: [Vec<f64>; 6],
}

impl Blocks {
    /// The blocks of `model`'s springs at positions `x`.
    pub(crate) fn new(model: &Model, x: &[DVec3]) -> Blocks {
        let count = model.springs().len();
        let mut blocks = Blocks {
            ends: Vec::with_capacity(count),
            k: std::array::from_fn(|_| Vec::with_capacity(count)),
        };
        for s in model.springs() {
            let m = spring_block(s, x);
            debug_assert!(
                m.x_axis.y.to_bits() == m.y_axis.x.to_bits()
                    && m.x_axis.z.to_bits() == m.z_axis.x.to_bits()
                    && m.y_axis.z.to_bits() == m.z_axis.y.to_bits(),
                "K_s is symmetric"
            );
            blocks.ends.push([s.a, s.b]);
            let entries = [
                m.x_axis.x, m.y_axis.x, m.z_axis.x, m.y_axis.y, m.z_axis.y, m.z_axis.z,
            ];
            for (k, e) in blocks.k.iter_mut().zip(entries) {
                k.push(e);
            }
        }
        blocks
    }

    /// The six arrays, as [`quadratic`] reads them.
    pub(crate) fn six(&self) -> quadratic::SymBlocks<'_> {
        let k = &self.k;
        [&k[0], &k[1], &k[2], &k[3], &k[4], &k[5]]
    }

    /// The six numbers of spring `s`.
    #[inline(always)]
    pub(crate) fn at(&self, s: usize) -> [f64; 6] {
        let k = &self.k;
        [k[0][s], k[1][s], k[2][s], k[3][s], k[4][s], k[5][s]]
    }

    /// `K_s d`, in the order of glam's `DMat3 * DVec3`: `(K e_x) d_x + (K e_y) d_y + (K e_z) d_z`.
    #[inline(always)]
    pub(crate) fn mul(k: &[f64; 6], d: DVec3) -> DVec3 {
        DVec3::new(
            k[0] * d.x + k[1] * d.y + k[2] * d.z,
            k[1] * d.x + k[3] * d.y + k[4] * d.z,
            k[2] * d.x + k[4] * d.y + k[5] * d.z,
        )
    }
}

/// `y = S K S q`, with `S = diag(scale)`; `u` is scratch.
fn apply(
    model: &Model,
    blocks: &[DMat3],
    scale: &[f64],
    q: &[DVec3],
    u: &mut [DVec3],
    y: &mut [DVec3],
) {
    for ((u, q), s) in u.iter_mut().zip(q).zip(scale) {
        *u = *q * *s;
    }
    y.fill(DVec3::ZERO);
    // Row `held` is summed in `sum` while consecutive springs start at the same particle (the
    // lattices list a particle's springs one after another) instead of a store and a load per
    // spring; every row still gets its terms in spring order.
    let mut held = usize::MAX;
    let mut sum = DVec3::ZERO;
    for (s, k_s) in model.springs().iter().zip(blocks) {
        let (a, b) = (s.a as usize, s.b as usize);
        // (K u)_a += K_s (u_a - u_b),  (K u)_b += K_s (u_b - u_a)
        let f = *k_s * (u[a] - u[b]);
        if a != held {
            if let Some(row) = y.get_mut(held) {
                *row = sum;
            }
            held = a;
            sum = y[a];
        }
        sum += f;
        if b == held {
            sum -= f;
        } else {
            y[b] -= f;
        }
    }
    if let Some(row) = y.get_mut(held) {
        *row = sum;
    }
    for (y, s) in y.iter_mut().zip(scale) {
        *y *= *s;
    }
}

/// The Gershgorin bound of `M⁻¹K` with each spring taken as a scalar spring of stiffness `k`
/// (no geometry, no state), in 1/s²: the quick bound of the budget estimates and the lesson
/// app's status line.
///
/// ```text
/// λ_max ≤ max_i (1/m_i) Σ_{springs s at i} k_s (1 + [other end of s free])
/// ```
/// where `m_i` is the mass of particle `i` (kg; pinned particles have `1/m_i = 0`) and `k_s` the
/// stiffness (N/m): row `i` of the scalar `K` holds `Σ k_s` on its diagonal and `k_s` beside it
/// for each free neighbour. For one spring on a pinned end `λ = k/m`; inside a chain `4k/m`.
#[must_use]
pub fn spring_gershgorin(model: &Model) -> f64 {
    let mut sum = vec![0.0; model.particle_count()];
    for s in model.springs() {
        let (a, b) = (s.a as usize, s.b as usize);
        let free = |i: usize| if model.inv_mass[i] > 0.0 { 1.0 } else { 0.0 };
        sum[a] += s.stiffness * (1.0 + free(b));
        sum[b] += s.stiffness * (1.0 + free(a));
    }
    sum.iter()
        .zip(&model.inv_mass)
        .map(|(k, w)| w * k)
        .fold(0.0, f64::max)
}

/// `max_i Σ_j |(M⁻¹K)_ij|` over the rows of free particles, pinned columns left out (1/s²).
fn gershgorin(model: &Model, blocks: &[DMat3], free: &[bool]) -> f64 {
    let n = model.particle_count();
    let mut diagonal = vec![DMat3::ZERO; n];
    let mut off = vec![DVec3::ZERO; n];
    for (s, k_s) in model.springs().iter().zip(blocks) {
        let (a, b) = (s.a as usize, s.b as usize);
        diagonal[a] += *k_s;
        diagonal[b] += *k_s;
        // Row sums of |K_s|: the off-diagonal block -K_s of a free column.
        let abs_rows = abs_row_sums(k_s);
        if free[b] {
            off[a] += abs_rows;
        }
        if free[a] {
            off[b] += abs_rows;
        }
    }
    (0..n)
        .filter(|&i| free[i])
        .map(|i| {
            let rows = abs_row_sums(&diagonal[i]) + off[i];
            model.inv_mass[i] * rows.max_element()
        })
        .fold(0.0, f64::max)
}

/// `(Σ_c |m_rc|)_r`: the absolute row sums of a 3×3 matrix.
fn abs_row_sums(m: &DMat3) -> DVec3 {
    let t = m.transpose();
    DVec3::new(
        t.x_axis.abs().element_sum(),
        t.y_axis.abs().element_sum(),
        t.z_axis.abs().element_sum(),
    )
}

/// A fixed pseudo-random unit vector (xorshift64*), zero on pinned particles.
fn start_vector(scale: &[f64]) -> Vec<DVec3> {
    let mut random = XorShift64Star::new(0x9E37_79B9_7F4A_7C15);
    let mut next = || random.symmetric();
    let mut q: Vec<DVec3> = scale
        .iter()
        .map(|&s| {
            let v = DVec3::new(next(), next(), next());
            if s > 0.0 { v } else { DVec3::ZERO }
        })
        .collect();
    let q_norm = norm(&q);
    if q_norm > 0.0 {
        for q in &mut q {
            *q /= q_norm;
        }
    }
    q
}

fn dot(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a.dot(*b)).sum()
}

fn norm(a: &[DVec3]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene;

    /// The product of the power iteration (a row held in registers while its springs come one
    /// after another) gives the spring loop's bits on a jelly, a cloth and a rope.
    #[test]
    fn the_product_gives_the_spring_loops_bits() {
        let mut random = XorShift64Star::new(5);
        for name in ["jelly-bowl", "cloth-sphere", "rope"] {
            let scene = scene::load(name, &[]).expect("a built-in scene");
            let body = &scene.bodies[0];
            let n = body.model.particle_count();
            let blocks = stiffness_blocks(&body.model, &body.state.x);
            let scale: Vec<f64> = (0..n).map(|i| body.model.inv_mass[i].sqrt()).collect();
            let q: Vec<DVec3> = (0..n)
                .map(|_| DVec3::new(random.symmetric(), random.symmetric(), random.symmetric()))
                .collect();
            let u: Vec<DVec3> = q.iter().zip(&scale).map(|(q, s)| *q * *s).collect();
            let mut want = vec![DVec3::ZERO; n];
            for (s, k_s) in body.model.springs().iter().zip(&blocks) {
                let (a, b) = (s.a as usize, s.b as usize);
                let f = *k_s * (u[a] - u[b]);
                want[a] += f;
                want[b] -= f;
            }
            for (y, s) in want.iter_mut().zip(&scale) {
                *y *= *s;
            }
            let (mut scratch, mut y) = (vec![DVec3::ZERO; n], vec![DVec3::ONE; n]);
            apply(&body.model, &blocks, &scale, &q, &mut scratch, &mut y);
            let bits = |v: &[DVec3]| -> Vec<[u64; 3]> {
                v.iter().map(|v| v.to_array().map(f64::to_bits)).collect()
            };
            assert_eq!(bits(&y), bits(&want), "{name}");
        }
    }

    /// The six numbers of every block of a stretched, sheared jelly and a cloth (compressed and
    /// stretched springs, every direction) give `K_s d` with the bits of glam's `DMat3 * d`, and
    /// the blocks are symmetric bit for bit.
    #[test]
    fn six_numbers_give_the_matrix_product_bits() {
        let mut random = XorShift64Star::new(11);
        for name in ["jelly-bowl", "cloth-sphere"] {
            let scene = scene::load(name, &[]).expect("a built-in scene");
            let body = &scene.bodies[0];
            let x: Vec<DVec3> = (body.state.x.iter())
                .map(|p| {
                    *p + 0.05
                        * DVec3::new(random.symmetric(), random.symmetric(), random.symmetric())
                })
                .collect();
            let matrices = stiffness_blocks(&body.model, &x);
            let blocks = Blocks::new(&body.model, &x);
            assert_eq!(blocks.ends.len(), matrices.len());
            for (s, m) in matrices.iter().enumerate() {
                assert_eq!(m.transpose(), *m, "{name}: spring {s}");
                let d = DVec3::new(random.symmetric(), random.symmetric(), random.symmetric());
                let want = (*m * d).to_array().map(f64::to_bits);
                assert_eq!(
                    Blocks::mul(&blocks.at(s), d).to_array().map(f64::to_bits),
                    want
                );
            }
        }
    }
}
