//! Implicit (backward) Euler, one Newton step, solved by conjugate gradients.
//!
//! Backward Euler evaluates the force at the END of the step:
//!
//! ```text
//! v_{n+1} = v_n + dt M⁻¹ f(x_{n+1}, v_{n+1})
//! x_{n+1} = x_n + dt v_{n+1}
//! ```
//! Linearising `f` about `(x_n, v_n)` (one Newton step) with `Δv = v_{n+1} - v_n` and
//! `Δx = dt (v_n + Δv)` gives one linear system (Baraff & Witkin 1998, eq. 6):
//!
//! ```text
//! (M - dt ∂f/∂v - dt² ∂f/∂x) Δv = dt (f_n + dt ∂f/∂x v_n)
//! ```
//! where `M` is the diagonal mass matrix (kg), `f_n = f(x_n, v_n)` (N), and per spring with
//! `n = (x_b - x_a)/L`:
//!
//! ```text
//! ∂f_a/∂x_b = K_s = k [ n nᵀ + max(0, 1 - L0/L) (I - n nᵀ) ]      (N/m)
//! ∂f_a/∂v_b = D_s = k_d n nᵀ                                       (N·s/m)
//! ∂f_a/∂x_a = -K_s,   ∂f_a/∂v_a = -D_s,   and the mirror for b
//! ∂f_i/∂v_i = -c I    (viscous drag)
//! ```
//! The transverse term `1 - L0/L` is negative for a compressed spring and would make the matrix
//! indefinite; it is clamped at zero (Choi & Ko 2002, §4), which keeps the system symmetric
//! positive definite so conjugate gradients converge. The damper's dependence on position is
//! dropped, as in Baraff & Witkin. The solve is matrix-free: `A p` is assembled spring by spring
//! from 3×3 blocks, preconditioned by the inverse 3×3 diagonal blocks (block Jacobi). Pinned
//! particles are filtered out: their rows and columns are held at `Δv = 0` (Baraff & Witkin §5.3).
//!
//! One force evaluation per step (plus the Jacobian, at about the cost of another). Global error
//! O(dt): first order. **Stability**: amplification `1 / (1 - z)` with `|·| < 1` for every
//! `Re z < 0` and on the undamped oscillator (`z = i dt ω`): unconditionally stable, and it
//! removes energy, the more the larger `dt·ω`.
//!
//! Reference: D. Baraff, A. Witkin, "Large Steps in Cloth Simulation", SIGGRAPH 1998, §3, §5;
//! K.-J. Choi, H.-S. Ko, "Stable but Responsive Cloth", SIGGRAPH 2002, §4; J. R. Shewchuk,
//! "An Introduction to the Conjugate Gradient Method Without the Agonizing Pain", 1994, §B3.

use glam::{DMat3, DVec3};
use serde::Serialize;

use crate::physics::forces::{Model, forces};
use crate::physics::integrators::{MethodParams, Workspace};
use crate::physics::particles::State;

/// How the last linear solve went.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SolveStats {
    /// Conjugate-gradient iterations taken.
    pub iterations: u32,
    /// Final relative residual `|r| / |b|`.
    pub relative_residual: f64,
}

pub(super) fn step(
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    let n = state.x.len();
    let dt2 = dt * dt;
    let Workspace {
        a: rhs,
        blocks,
        diag_inv,
        cg,
        last_solve,
        ..
    } = work;
    let [dv, r, p, ap] = cg;

    // b = dt f_n  (then + dt² ∂f/∂x v_n below).
    forces(model, &state.x, &state.v, rhs);
    for b in rhs.iter_mut() {
        *b *= dt;
    }
    // Diagonal blocks start with M + dt c I (mass and drag).
    for (d, &m) in diag_inv.iter_mut().zip(&model.mass) {
        *d = DMat3::from_diagonal(DVec3::splat(m + dt * model.drag));
    }
    // Per spring: B_s = dt D_s + dt² K_s, the off-diagonal coupling of A; and b += dt² K_s v.
    for (s, block) in model.springs.iter().zip(blocks.iter_mut()) {
        let (ia, ib) = (s.a as usize, s.b as usize);
        let d = state.x[ib] - state.x[ia];
        let length = d.length();
        if length == 0.0 {
            *block = DMat3::ZERO;
            continue;
        }
        let dir = d / length;
        let nn = outer(dir, dir);
        // K_s = k [ n nᵀ + max(0, 1 - L0/L)(I - n nᵀ) ]
        let transverse = (1.0 - s.rest_length / length).max(0.0);
        let k_s = s.stiffness * (nn + transverse * (DMat3::IDENTITY - nn));
        // D_s = k_d n nᵀ
        let d_s = s.damping * nn;
        *block = dt * d_s + dt2 * k_s;
        // dt² ∂f/∂x v_n: row a gets K_s (v_b - v_a), row b the opposite.
        let kv = dt2 * (k_s * (state.v[ib] - state.v[ia]));
        rhs[ia] += kv;
        rhs[ib] -= kv;
        diag_inv[ia] += *block;
        diag_inv[ib] += *block;
    }
    for d in diag_inv.iter_mut() {
        *d = d.inverse();
    }

    // Preconditioned conjugate gradients on A Δv = b, pinned rows filtered (Shewchuk §B3).
    let free = |i: usize| model.inv_mass[i] != 0.0;
    let apply = |p: &[DVec3], out: &mut [DVec3]| {
        for i in 0..n {
            out[i] = (model.mass[i] + dt * model.drag) * p[i];
        }
        for (s, block) in model.springs.iter().zip(blocks.iter()) {
            let (ia, ib) = (s.a as usize, s.b as usize);
            let y = *block * (p[ia] - p[ib]);
            out[ia] += y;
            out[ib] -= y;
        }
        for (i, o) in out.iter_mut().enumerate() {
            if !free(i) {
                *o = DVec3::ZERO;
            }
        }
    };
    dv.fill(DVec3::ZERO);
    let mut b_norm2 = 0.0;
    for i in 0..n {
        r[i] = if free(i) { rhs[i] } else { DVec3::ZERO };
        b_norm2 += r[i].length_squared();
    }
    let tol2 = params.cg_tolerance * params.cg_tolerance * b_norm2;
    // z = P⁻¹ r, stored in p as the first search direction.
    let mut rz = 0.0;
    for i in 0..n {
        p[i] = diag_inv[i] * r[i];
        rz += r[i].dot(p[i]);
    }
    let mut r_norm2 = b_norm2;
    let mut iterations = 0;
    while r_norm2 > tol2 && iterations < params.cg_max_iterations {
        apply(p, ap);
        let p_ap: f64 = p.iter().zip(ap.iter()).map(|(p, q)| p.dot(*q)).sum();
        if p_ap <= 0.0 {
            break;
        }
        let alpha = rz / p_ap;
        r_norm2 = 0.0;
        let mut rz_new = 0.0;
        for i in 0..n {
            dv[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
            r_norm2 += r[i].length_squared();
            rz_new += r[i].dot(diag_inv[i] * r[i]);
        }
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = diag_inv[i] * r[i] + beta * p[i];
        }
        iterations += 1;
    }
    *last_solve = SolveStats {
        iterations,
        relative_residual: if b_norm2 > 0.0 {
            (r_norm2 / b_norm2).sqrt()
        } else {
            0.0
        },
    };

    for i in 0..n {
        if free(i) {
            // v_{n+1} = v_n + Δv;  x_{n+1} = x_n + dt v_{n+1}
            state.v[i] += dv[i];
            state.x[i] += dt * state.v[i];
        }
    }
    state.history_valid = false;
    1
}

/// The outer product `u vᵀ`.
fn outer(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}
