//! The damped theory where the scene lives: linearised at the static equilibrium the body hangs
//! at (gravity and tension included), not only at its initial state.
//!
//! # Why
//!
//! A rope that starts horizontal at rest length has no transverse stiffness: linearised there,
//! its pendulum motions have `ω = 0` and drop out of the spectrum. Hanging under gravity its
//! springs are stretched, and the tension gives every spring a transverse stiffness: the
//! pendulum modes have `ω > 0`, and the along-spring dampers do not damp them (a damper acts on
//! `n nᵀ v`, and a pendulum mode moves across `n`). A method whose stability region misses the
//! imaginary axis near 0 (explicit Euler: `|1 + iθ|² = 1 + θ²`; midpoint:
//! `|1 + iθ - θ²/2|² = 1 + θ⁴/4`) is then unstable at every dt, however strong the dampers.
//!
//! # The equilibrium
//!
//! The free particles' positions minimise the potential energy
//!
//! ```text
//! V(x) = Σ_s ½ k_s (|x_b - x_a| - L0_s)² - Σ_i m_i g·x_i          (J)
//! f(x) = -∇V(x)                                                    (N), zero at equilibrium
//! (K(x) + λ M) Δ = f(x),   x ← x + Δ   when V falls (λ ← λ/4), else λ ← 4 λ
//! ```
//! where `K(x)` is the tangent stiffness of [`crate::study::modes`] (geometric term of a
//! stretched spring included, a compressed spring's clamped at zero), `M` the masses (kg) and
//! `λ` (1/s²) the Levenberg–Marquardt shift that makes the step a descent step where `K` is
//! singular (the straight rope at rest length). It stops when `|f_i| ≤ 10⁻⁹ m_i |g|` on every
//! free particle. Only bodies with a pinned particle hang (a free body falls until a contact
//! holds it, and contacts are outside the linearisation), and only up to the dense limit.
//!
//! # The damped modes there
//!
//! `K` at the equilibrium gives the modes `φ_i` of `M^(-1/2) K M^(-1/2)` (Jacobi with
//! eigenvectors), and each mode gets its own damping from the damping matrix
//! `C = Σ_s k_d,s n nᵀ (assembled like K) + c I`:
//!
//! ```text
//! ω_i² = φ_iᵀ M^(-1/2) K M^(-1/2) φ_i,     μ_i = φ_iᵀ M^(-1/2) C M^(-1/2) φ_i     (1/s², 1/s)
//! ```
//! the diagonal of the modal damping matrix. It is exact when `ΦᵀCΦ` is diagonal (classical
//! damping, Caughey & O'Kelly): a straight hanging chain is of that kind (its transverse modes
//! see no damper, `μ = 0`; its longitudinal modes see `μ = (k_d/k) ω²`).
//!
//! References: J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006,
//! §10.3 (Levenberg–Marquardt); T. K. Caughey, M. E. J. O'Kelly, "Classical normal modes in
//! damped linear dynamic systems", J. Appl. Mech. 32 (1965); G. H. Golub, C. F. Van Loan,
//! *Matrix Computations*, 4th ed., 2013, §8.5 (Jacobi); A. P. French, *Vibrations and Waves*,
//! Norton 1971, ch. 5 (the hanging chain's and the pendulum's frequencies).

use glam::{DMat3, DVec3};
use serde::Serialize;

use super::{DENSE_MAX, Mode, Spectrum};
use crate::physics::{Model, State, energy, forces};
use crate::study::modes::stiffness_blocks;

/// At most this many Levenberg–Marquardt iterations.
pub const MAX_ITERATIONS: u32 = 200;
/// The equilibrium is reached when every free particle's net force is at most this fraction of
/// its weight.
pub const FORCE_TOLERANCE: f64 = 1e-9;

/// The static equilibrium of a body (module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Equilibrium {
    /// Iterations taken.
    pub iterations: u32,
    /// The largest net force on a free particle at the end over its weight (dimensionless).
    pub force_ratio: f64,
    /// How far the equilibrium is from the initial state: the largest displacement (m).
    pub displacement: f64,
    /// `ω_max` there (rad/s): the largest eigenvalue's root.
    pub omega_max: f64,
    /// The smallest nonzero `ω` there (rad/s): the slowest mode (a pendulum's).
    pub omega_min: f64,
    /// The smallest damping rate `μ` over the modes (1/s).
    pub mu_min: f64,
}

/// Why no equilibrium spectrum was computed.
pub type NoEquilibrium = &'static str;

/// The static equilibrium of `model` from `state` (module docs): the positions, and how it was
/// reached.
///
/// # Errors
/// No pinned particle (nothing to hang from), more free coordinates than [`DENSE_MAX`], no
/// gravity, or no convergence.
pub fn equilibrium(model: &Model, state: &State) -> Result<(Vec<DVec3>, u32, f64), NoEquilibrium> {
    let n = model.particle_count();
    let free: Vec<usize> = (0..n).filter(|&i| !model.is_pinned(i)).collect();
    if free.len() == n {
        return Err(
            "no pinned particle: the body hangs from nothing (a free body is held by \
                    contacts, which the linearisation leaves out)",
        );
    }
    if 3 * free.len() > DENSE_MAX {
        return Err("more free coordinates than the dense limit");
    }
    let g = model.gravity.length();
    if g == 0.0 {
        return Err("no gravity: the initial state is the equilibrium");
    }
    let mut model = model.clone();
    model.colliders.clear();
    let mut s = state.clone();
    s.spheres.clear();
    s.v.fill(DVec3::ZERO);
    let zero = vec![DVec3::ZERO; n];
    let potential = |s: &State| {
        let e = energy(&model, s);
        e.elastic + e.gravity
    };
    let net = |x: &[DVec3], f: &mut Vec<DVec3>| {
        f.resize(n, DVec3::ZERO);
        forces(&model, x, &zero, f);
    };
    let worst = |f: &[DVec3]| {
        free.iter()
            .map(|&i| f[i].length() / (model.mass[i] * g))
            .fold(0.0, f64::max)
    };
    let m = 3 * free.len();
    let mut f = Vec::new();
    net(&s.x, &mut f);
    let mut v = potential(&s);
    // λ starts at the largest K/M ratio's scale: a short gradient step.
    let mut lambda = free.iter().map(|&i| model.inv_mass[i]).fold(0.0, f64::max)
        * model
            .springs()
            .iter()
            .map(|sp| sp.stiffness)
            .fold(0.0, f64::max)
            .max(1e-12);
    for iteration in 0..MAX_ITERATIONS {
        let ratio = worst(&f);
        if ratio <= FORCE_TOLERANCE {
            return Ok((s.x, iteration, ratio));
        }
        let blocks = stiffness_blocks(&model, &s.x);
        let mut accepted = false;
        for _ in 0..60 {
            let mut a = assemble(&model, &blocks, &free, |_, _| None);
            for (k, &i) in free.iter().enumerate() {
                for r in 0..3 {
                    a[(3 * k + r) * m + 3 * k + r] += lambda * model.mass[i];
                }
            }
            let mut b: Vec<f64> = free
                .iter()
                .flat_map(|&i| [f[i].x, f[i].y, f[i].z])
                .collect();
            if !solve(&mut a, &mut b, m) {
                lambda *= 4.0;
                continue;
            }
            let mut trial = s.clone();
            for (k, &i) in free.iter().enumerate() {
                trial.x[i] += DVec3::new(b[3 * k], b[3 * k + 1], b[3 * k + 2]);
            }
            let vt = potential(&trial);
            if vt.is_finite() && vt <= v {
                s = trial;
                v = vt;
                lambda /= 4.0;
                accepted = true;
                break;
            }
            lambda *= 4.0;
        }
        if !accepted {
            // No descent step left: at a minimum to rounding, or stuck.
            net(&s.x, &mut f);
            let ratio = worst(&f);
            return if ratio <= 1e-6 {
                Ok((s.x, iteration, ratio))
            } else {
                Err("the equilibrium search did not converge")
            };
        }
        net(&s.x, &mut f);
    }
    Err("the equilibrium search did not converge")
}

/// The dense `K` over the free coordinates (row-major `3F × 3F`), each spring's block from
/// `blocks` (or from `other(spring index, block)` when it returns one).
fn assemble(
    model: &Model,
    blocks: &[DMat3],
    free: &[usize],
    other: impl Fn(usize, &DMat3) -> Option<DMat3>,
) -> Vec<f64> {
    let m = 3 * free.len();
    let mut index = vec![usize::MAX; model.particle_count()];
    for (k, &i) in free.iter().enumerate() {
        index[i] = k;
    }
    let mut a = vec![0.0; m * m];
    for (j, (s, k)) in model.springs().iter().zip(blocks).enumerate() {
        let k = other(j, k).unwrap_or(*k);
        super::add_spring_block(&mut a, m, index[s.a as usize], index[s.b as usize], &k);
    }
    a
}

/// Solves `a x = b` in place (`x` in `b`) by Gaussian elimination with partial pivoting;
/// false when `a` is singular to rounding.
fn solve(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))
            .unwrap_or(col);
        if a[pivot * n + col].abs() <= 1e-14 * scale {
            return false;
        }
        if pivot != col {
            for k in 0..n {
                a.swap(col * n + k, pivot * n + k);
            }
            b.swap(col, pivot);
        }
        for row in col + 1..n {
            let factor = a[row * n + col] / a[col * n + col];
            if factor != 0.0 {
                for k in col..n {
                    a[row * n + k] -= factor * a[col * n + k];
                }
                b[row] -= factor * b[col];
            }
        }
    }
    for row in (0..n).rev() {
        let mut sum = b[row];
        for k in row + 1..n {
            sum -= a[row * n + k] * b[k];
        }
        b[row] = sum / a[row * n + row];
    }
    true
}

/// The damped spectrum of `model` at its static equilibrium from `state` (module docs), with
/// the equilibrium's report.
///
/// # Errors
/// As [`equilibrium`].
pub fn spectrum_at_equilibrium(
    model: &Model,
    state: &State,
) -> Result<(Spectrum, Equilibrium), NoEquilibrium> {
    let (x, iterations, force_ratio) = equilibrium(model, state)?;
    let n = model.particle_count();
    let free: Vec<usize> = (0..n).filter(|&i| !model.is_pinned(i)).collect();
    let m = 3 * free.len();
    let blocks = stiffness_blocks(model, &x);
    let scaled = |mut a: Vec<f64>| {
        for (p, &i) in free.iter().enumerate() {
            for (q, &j) in free.iter().enumerate() {
                let s = (model.inv_mass[i] * model.inv_mass[j]).sqrt();
                for r in 0..3 {
                    for c in 0..3 {
                        a[(3 * p + r) * m + 3 * q + c] *= s;
                    }
                }
            }
        }
        a
    };
    let mut k = scaled(assemble(model, &blocks, &free, |_, _| None));
    // C: k_d n nᵀ per spring, plus the drag c on the diagonal.
    let springs = model.springs();
    let mut c = scaled(assemble(model, &blocks, &free, |j, _| {
        let s = &springs[j];
        let d = x[s.b as usize] - x[s.a as usize];
        let len = d.length();
        Some(if len > 0.0 {
            let u = d / len;
            DMat3::from_cols(u * u.x, u * u.y, u * u.z) * s.damping
        } else {
            DMat3::ZERO
        })
    }));
    for (p, &i) in free.iter().enumerate() {
        for r in 0..3 {
            c[(3 * p + r) * m + 3 * p + r] += model.drag * model.inv_mass[i];
        }
    }
    let (values, vectors) = jacobi_eigen(&mut k, m);
    let top = values.iter().copied().fold(0.0f64, f64::max);
    let mut modes = Vec::new();
    for (w2, phi) in values.iter().zip(&vectors) {
        if *w2 <= 1e-12 * top {
            continue;
        }
        let mu: f64 = (0..m)
            .map(|r| phi[r] * (0..m).map(|q| c[r * m + q] * phi[q]).sum::<f64>())
            .sum();
        modes.push(Mode {
            omega: w2.sqrt(),
            mu: mu.max(0.0),
        });
    }
    let omega_max = top.max(0.0).sqrt();
    let report = Equilibrium {
        iterations,
        force_ratio,
        displacement: free
            .iter()
            .map(|&i| (x[i] - state.x[i]).length())
            .fold(0.0, f64::max),
        omega_max,
        omega_min: modes.iter().map(|m| m.omega).fold(f64::INFINITY, f64::min),
        mu_min: modes.iter().map(|m| m.mu).fold(f64::INFINITY, f64::min),
    };
    let how = format!(
        "linearised at the static equilibrium under gravity (Levenberg–Marquardt, {iterations} \
         iterations, largest net force {force_ratio:.1e} of a weight; largest displacement \
         {:.4e} m): all {} modes of M⁻¹K there by a dense eigen-solve (Jacobi), tension's \
         transverse stiffness included, each mode damped by its diagonal entry of the modal \
         damping ΦᵀCΦ",
        report.displacement,
        modes.len()
    );
    Ok((
        Spectrum {
            modes,
            omega_max,
            dense: true,
            rayleigh: None,
            how,
        },
        report,
    ))
}

/// Eigenvalues (ascending) and unit eigenvectors of the symmetric `n × n` matrix `a` (row-major,
/// destroyed) by cyclic Jacobi rotations with the rotations accumulated (Golub & Van Loan
/// §8.5.3).
fn jacobi_eigen(a: &mut [f64], n: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut v = vec![0.0; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    super::jacobi_rotate(a, n, Some(&mut v));
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| a[i * n + i].total_cmp(&a[j * n + j]));
    let values = order.iter().map(|&i| a[i * n + i]).collect();
    let vectors = order
        .iter()
        .map(|&i| (0..n).map(|k| v[k * n + i]).collect())
        .collect();
    (values, vectors)
}
