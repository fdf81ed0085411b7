//! XPBD: extended position-based dynamics with substeps.
//!
//! Each step of `dt` is split into `substeps` substeps of `h = dt / substeps`:
//!
//! ```text
//! for each substep:
//!     x_prev = x
//!     v     += h a_ext(x, v)               gravity and drag only
//!     x     += h v                         predict
//!     λ      = 0
//!     repeat `iterations` times: solve every spring as a compliant constraint (α = 1/k, β = k_d)
//!     v      = (x - x_prev) / h
//! ```
//! where
//! - `x`: positions (m), `x_prev`: the positions at the start of the substep (m)
//! - `v`: velocities (m/s)
//! - `a_ext`: the acceleration from the forces other than springs (m/s²)
//! - `h = dt / substeps`: the substep (s)
//! - `λ`: each spring's accumulated Lagrange multiplier (N·s²), see [`xpbd_solve`]
//! - `α = 1/k`: compliance (m/N), `β = k_d`: the spring's damping (N·s/m)
//!
//! The constraint solve is [`xpbd_solve`].
//!
//! Springs are not forces here but constraints with compliance `α = 1/k` (m/N); as `α → 0` a spring
//! becomes a rigid rod, and nothing becomes unstable: the solve is a projection. The error is
//! O(h): first order, with the first-order error showing as extra damping. Many small substeps
//! with one iteration each beat few substeps with many iterations (Macklin et al. 2019).
//!
//! The count returned is one force evaluation per substep (the external forces).
//!
//! Reference: M. Macklin, M. Müller, N. Chentanez, "XPBD: Position-Based Simulation of Compliant
//! Constrained Dynamics", Motion in Games 2016, §3–4; M. Macklin, K. Storey, M. Lu, P. Terdiman,
//! N. Chentanez, S. Jeschke, M. Müller, "Small Steps in Physics Simulation", SCA 2019, §3.

use crate::physics::constraints::xpbd_solve;
use crate::physics::forces::Model;
use crate::physics::integrators::declaration::{
    Declaration, OscillatorLimit, Scratch, StabilityFunction,
};
use crate::physics::integrators::{MethodParams, Workspace, power_if};
use crate::physics::particles::State;

/// The method's row of the registry (`integrators.rs`).
pub(super) const DECLARATION: Declaration = Declaration {
    name: "xpbd",
    label: "XPBD",
    key: 'x',
    colour: 7,
    order: 1,
    evaluations: |p| f64::from(p.substeps.max(1)) * (1.0 + f64::from(p.iterations)),
    oscillator: OscillatorLimit::Unconditional,
    stability: |_| {
        StabilityFunction::NotCovered(
            "XPBD solves springs as compliant constraints: no stability function",
        )
    },
    params: &["iterations", "substeps"],
    scratch: Scratch::NONE,
    fused: false,
    energy_guard: false,
    step,
    many: None,
};

/// One step: `substeps` substeps of the loop in the module docs.
fn step(
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    let substeps = params.substeps.max(1);
    let h = dt / f64::from(substeps);
    let Workspace {
        x_stage: x_start,
        lambda,
        account,
        dissipated,
        power_f,
        ..
    } = work;
    for _ in 0..substeps {
        // Remember where the substep started: x_prev = x.
        x_start.copy_from_slice(&state.x);
        for i in 0..state.x.len() {
            // External forces only: a = (m g - c v) / m, zero for pinned particles.
            let w = model.inv_mass[i];
            let a_ext = w * (model.mass[i] * model.gravity - model.drag * state.v[i]);
            state.v[i] += h * a_ext;
            state.x[i] += h * state.v[i];
        }
        lambda.fill(0.0);
        for _ in 0..params.iterations.max(1) {
            xpbd_solve(model, &mut state.x, x_start, lambda, h);
        }
        let inv_h = 1.0 / h;
        for i in 0..state.x.len() {
            state.v[i] = (state.x[i] - x_start[i]) * inv_h;
        }
        // Dampers and drag at the end of the substep, when accounting.
        dissipated.add_power(h, power_if(*account, model, &state.x, &state.v, power_f));
    }
    state.history_valid = false;
    u64::from(substeps)
}
