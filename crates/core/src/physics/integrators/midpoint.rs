//! Explicit midpoint method (RK2).
//!
//! ```text
//! x_mid   = x_n + dt/2 v_n
//! v_mid   = v_n + dt/2 a(x_n, v_n)
//! x_{n+1} = x_n + dt v_mid
//! v_{n+1} = v_n + dt a(x_mid, v_mid)
//! ```
//! where
//! - `x`: positions (m), `v`: velocities (m/s)
//! - `a(x, v)`: accelerations from all forces (m/s²), [`crate::physics::accelerations`]
//! - `dt`: the time step (s), `n`: the step index; `x_mid`, `v_mid`: the state at `t_n + dt/2`
//!
//! A half Euler step finds the state at the middle of the interval; its slope is then used for
//! the whole step. Two force evaluations, global error O(dt²): second order.
//!
//! **Stability on the harmonic oscillator**: amplification `1 + z + z²/2` with `z = i dt ω`, of
//! modulus `√(1 + (dt ω)⁴/4) > 1`: unstable at every dt undamped, though far more slowly than
//! explicit Euler.
//!
//! **Fast path.** The textbook loop (`textbook`, first below) is the method. On a lattice,
//! [`Method::step`](super::Method::step) hands the same arithmetic, stage by stage, to the
//! stencil's fused passes through the one seam (`integrators::fused` and `fused_pass`, which call
//! [`Stencil::write`](crate::physics::stencil::Stencil::write)): `step_fused`, last in this
//! file, does the same operations in the same order, bit for bit (tested).
//!
//! Reference: E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*,
//! 2nd ed., Springer 1993, §II.1 (eq. 1.7); NYCU Computer Animation HW1 (2021–2023).

use crate::physics::forces::{Model, accelerations};
use crate::physics::integrators::declaration::{Declaration, OscillatorLimit, Scratch, StabilityFunction, polynomial, two_evaluations};
use crate::physics::integrators::{explicit_step, Workspace, power_if, stage_then_step};
use crate::physics::particles::State;
use crate::physics::stencil::Stencil;

/// The method as the formula writes it: two force evaluations and two loops.
pub(super) fn textbook(model: &Model, state: &mut State, dt: f64, work: &mut Workspace) -> u64 {
    let half = 0.5 * dt;
    let Workspace {
        a,
        x_stage,
        v_stage,
        account,
        dissipated,
        power_f,
        ..
    } = work;
    // First slope at the start: a(x_n, v_n).
    accelerations(model, &state.x, &state.v, a);
    // Half an Euler step to the midpoint.
    for i in 0..state.x.len() {
        x_stage[i] = state.x[i] + half * state.v[i];
        v_stage[i] = state.v[i] + half * a[i];
    }
    // D_{n+1} = D_n + dt P(x_mid, v_mid), when accounting.
    dissipated.add_power(dt, power_if(*account, model, x_stage, v_stage, power_f));
    // Second slope at the midpoint: a(x_mid, v_mid).
    accelerations(model, x_stage, v_stage, a);
    // The full step with the midpoint slopes.
    for i in 0..state.x.len() {
        state.x[i] += dt * v_stage[i];
        state.v[i] += dt * a[i];
    }
    state.history_valid = false;
    2
}

/// The same step on a lattice in two stencil passes: the first writes the midpoint
/// `(x + dt/2 v, v + dt/2 a)`, the second advances the state in place from it (the loops above,
/// per particle, so the same numbers), with the dissipated power at the midpoint.
pub(super) fn step_fused(
    stencil: &Stencil,
    model: &Model,
    state: &mut State,
    dt: f64,
    work: &mut Workspace,
) -> u64 {
    stage_then_step(stencil, model, state, dt, 0.5 * dt, work)
}

/// The method's row of the registry (`integrators.rs`).
pub(super) const DECLARATION: Declaration = Declaration {
    name: "midpoint",
    label: "mid",
    key: 'm',
    colour: 3,
    order: 2,
    evaluations: two_evaluations,
    oscillator: OscillatorLimit::None,
    stability: |_| StabilityFunction::OneStep(|z| polynomial(&[1.0, 1.0, 0.5], z)),
    params: &[],
    scratch: Scratch::NONE,
    fused: true,
    energy_guard: false,
    step: |model, state, dt, _, work| {
        explicit_step(model, state, dt, work, textbook, step_fused)
    },
    many: None,
};
