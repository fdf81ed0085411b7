//! Implicit (backward) Euler: Baraff & Witkin's one linearised Newton step.
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
//! (M - dt ∂f/∂v - dt² ∂f/∂x) Δv = dt (f₀ + dt ∂f/∂x v₀)
//!
//! ∂f_a/∂x_b = K_s = k [ n nᵀ + max(0, 1 - L0/L) (I - n nᵀ) ]      per spring s = (a, b)
//! ∂f_a/∂v_b = D_s = k_d n nᵀ
//! ∂f_a/∂x_a = -K_s,   ∂f_a/∂v_a = -D_s,   and the mirror for b
//! ∂f_i/∂v_i = -c I                                                  viscous drag
//! ```
//! where
//! - `M` is the diagonal mass matrix (kg), `dt` the time step (s),
//! - `f₀ = f(x_n, v_n)` the forces at the start of the step (N), `v₀ = v_n` (m/s),
//! - `Δv` the velocity change of the step (m/s),
//! - `∂f/∂x` the stiffness matrix (N/m), assembled from the spring blocks `K_s`,
//! - `∂f/∂v` the damping matrix (N·s/m), from the damper blocks `D_s` and the drag `c` (N·s/m),
//! - `n = (x_b - x_a)/L` the spring's direction, `L` its length and `L0` its rest length (m),
//!   `k` its stiffness (N/m) and `k_d` its damping (N·s/m).
//!
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
//! The step below reads as the formula: [`assemble`] the system, solve it, [`advance`]. What a
//! real scene adds sits behind the solve, each part in a file of its own and skippable on a
//! first reading (why each is built as it is, with its measurements: `docs/implicit-euler.md`):
//!
//! - `crates/core/src/physics/integrators/implicit_euler/solve.rs`: the conjugate-gradient solve itself
//!   (`System`) and how it went ([`SolveStats`]; CG stops at `|r| ≤ tol·|b|`, `tol = 10⁻³` by
//!   default, `cg_tolerance`);
//! - `crates/core/src/physics/integrators/implicit_euler/contacts.rs`: contacts inside the solve (Baraff &
//!   Witkin §5.3), an active set of at most [`MAX_CONTACT_PASSES`] solves;
//! - `crates/core/src/physics/integrators/implicit_euler/warm.rs`: the warm start (the solve starts from the
//!   last steps' `Δv` extrapolated);
//! - `crates/core/src/physics/integrators/implicit_euler/lattice.rs`: the lattice path, reaching the fast
//!   engine (`crate::physics::fast::implicit_lattice`): the same system with each spring block
//!   stored as four numbers, two passes per CG iteration.
//!
//! Reference: D. Baraff, A. Witkin, "Large Steps in Cloth Simulation", SIGGRAPH 1998, §3, §5;
//! K.-J. Choi, H.-S. Ko, "Stable but Responsive Cloth", SIGGRAPH 2002, §4; J. R. Shewchuk,
//! "An Introduction to the Conjugate Gradient Method Without the Agonizing Pain", 1994, §B3.

use glam::{DMat3, DVec3};

use crate::physics::forces::{Model, forces};
use crate::physics::integrators::declaration::{
    Declaration, OscillatorLimit, Scratch, StabilityFunction,
};
use crate::physics::integrators::{MethodParams, Workspace, fused, power_if};
use crate::physics::particles::State;

mod contacts;
mod lattice;
mod solve;
mod warm;

pub(crate) use crate::physics::fast::implicit_constraint::Constraint;
pub use contacts::MAX_CONTACT_PASSES;
pub use lattice::{guard_energy, guard_start_energy};
pub use solve::SolveStats;
use solve::System;

/// The method's row of the registry (`integrators.rs`).
pub(super) const DECLARATION: Declaration = Declaration {
    name: "implicit-euler",
    label: "IE",
    key: 'i',
    colour: 12,
    order: 1,
    // One evaluation, the Jacobian blocks, and typically 10–20 CG iterations (measured: 12–17
    // times a semi-implicit step on the rope, the cloth and the jelly).
    evaluations: |_| 20.0,
    oscillator: OscillatorLimit::Unconditional,
    // R(z) = 1/(1 - z).
    stability: |_| {
        StabilityFunction::OneStep(|z| {
            let (re, im) = (1.0 - z.0, -z.1);
            let m = re * re + im * im;
            (re / m, -im / m)
        })
    },
    params: &["cg_tolerance"],
    // The lattice solver (`implicit_lattice`, when it steps): per particle 32 `f64` arrays
    // (inverse diagonal blocks, mass, free flags, x, v, the right-hand side and the five CG
    // vectors, three components each) and three `DVec3` buffers (forces, the warm start's Δv,
    // the solve's result); per spring its block (six `f64`) and `dt² K (v_b - v_a)` (three).
    scratch: Scratch {
        particle: (32 * 8 + 3 * size_of::<DVec3>()) as f64,
        spring: (9 * 8) as f64,
    },
    fused: true,
    energy_guard: true,
    step,
    many: None,
};

/// One step: on a lattice the fast engine's solver (`lattice.rs`), else [`newton_step`].
pub(super) fn step(
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    match fused(model, work.textbook).filter(|s| lattice::usable(s)) {
        Some(stencil) => lattice::step(stencil, model, state, dt, params, work),
        None => newton_step(model, state, dt, params, work),
    }
}

/// Baraff & Witkin's one Newton step, as the formulas above write it: assemble `A Δv = b` at
/// `(x_n, v_n)` ([`assemble`]), solve it by conjugate gradients (with the contacts inside the
/// solve and the warm start, behind `contacts::solve`), then `v += Δv`, `x += dt v`
/// ([`advance`]).
fn newton_step(
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    let warm = warm::start(work, dt);
    let Workspace {
        a: rhs,
        blocks,
        diag_inv,
        cg,
        last_solve,
        constraints,
        inside,
        sphere_rows,
        account,
        dissipated,
        power_f,
        last_dv,
        last_dt,
        before_dv,
        before_dt,
        ..
    } = work;

    // A = M - dt ∂f/∂v - dt² ∂f/∂x (its blocks) and b = dt (f₀ + dt ∂f/∂x v₀).
    assemble(model, state, dt, rhs, blocks, diag_inv);
    let system = System {
        model,
        dt,
        blocks,
        diag_inv,
        rhs,
    };
    // A Δv = b, Δv into cg[0].
    let scratch = contacts::Scratch {
        cg,
        constraints,
        inside,
        spheres: sphere_rows,
    };
    let (stats, removed) = contacts::solve(&system, state, params, warm, *account, scratch);
    *last_solve = stats;
    if *account && let Some(removed) = removed {
        dissipated.contacts += removed;
    }

    let dv = &cg[0];
    warm::remember((last_dv, last_dt), (before_dv, before_dt), dv, dt);
    // v_{n+1} = v_n + Δv, x_{n+1} = x_n + dt v_{n+1}.
    advance(model, state, dt, dv);
    // D_{n+1} = D_n + dt P(x_{n+1}, v_{n+1}): backward Euler on D' = P too, when accounting.
    dissipated.add_power(dt, power_if(*account, model, &state.x, &state.v, power_f));
    1
}

/// Baraff & Witkin's linear system (module docs), spring by spring: the right-hand side
/// `b = dt (f_n + dt ∂f/∂x v_n)` (N·s) into `rhs`, each spring's off-diagonal block
/// `B_s = dt D_s + dt² K_s` (kg) into `blocks`, and the inverse diagonal blocks
/// `(M + dt c I + Σ_s B_s)⁻¹` (1/kg, the preconditioner) into `diag_inv`.
fn assemble(
    model: &Model,
    state: &State,
    dt: f64,
    rhs: &mut [DVec3],
    blocks: &mut [DMat3],
    diag_inv: &mut [DMat3],
) {
    let dt2 = dt * dt;
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
}

/// The step's update from the solved velocity change, on free particles:
/// `v_{n+1} = v_n + Δv`, `x_{n+1} = x_n + dt v_{n+1}`.
fn advance(model: &Model, state: &mut State, dt: f64, dv: &[DVec3]) {
    for i in 0..state.x.len() {
        if model.inv_mass[i] != 0.0 {
            state.v[i] += dv[i];
            state.x[i] += dt * state.v[i];
        }
    }
    state.history_valid = false;
}

/// The outer product `u vᵀ`.
fn outer(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}
