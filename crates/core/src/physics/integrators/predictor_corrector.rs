//! Predictor–corrector: what the NYCU Computer Animation course called "implicit Euler".
//!
//! ```text
//! x̃       = x_n + dt v_n                 predict with explicit Euler
//! ṽ       = v_n + dt a(x_n, v_n)
//! x_{n+1} = x_n + dt ṽ                   step from the OLD state
//! v_{n+1} = v_n + dt a(x̃, ṽ)             with the slope at the prediction
//! ```
//! where
//! - `x`: positions (m), `v`: velocities (m/s)
//! - `a(x, v)`: accelerations from all forces (m/s²), [`crate::physics::accelerations`]
//! - `dt`: the time step (s), `n`: the step index
//! - `x̃` (m), `ṽ` (m/s): the explicit-Euler prediction of the end state
//!
//! It looks like backward Euler (`v_{n+1} = v_n + dt a(x_{n+1}, v_{n+1})`) with the unknown end
//! state replaced by a guess, but no equation is solved: it is an explicit method. Two force
//! evaluations; global error O(dt): first order (`R(z) = 1 + z + z²` matches `e^z` only to `z`).
//!
//! **Stability**: on `y' = λ y` the amplification is `R(z) = 1 + z + z²`, `z = dt λ`.
//! - On a pure decay (real `z < 0`, a stiff damper) it is stable only for `-1 ≤ z ≤ 0`: HALF of
//!   explicit Euler's range `[-2, 0]`. This is why the course's "implicit" method failed first on
//!   the cloth (dt 0.0006 against explicit Euler's 0.001, `docs/course.md` §4).
//! - On the undamped oscillator (`z = i dt ω`) `|R|² = 1 - (dt ω)² + (dt ω)⁴`: stable, and losing
//!   energy, while **dt·ω ≤ 1**; growing beyond (measured by the tests).
//!
//! A real implicit Euler is [`super::implicit_euler`].
//!
//! **Fast path.** The textbook loop (`textbook`, first below) is the method. On a lattice,
//! [`Method::step`](super::Method::step) hands the same arithmetic, stage by stage, to the
//! stencil's fused passes through the one seam (`integrators::fused` and `fused_pass`, which call
//! [`Stencil::write`](crate::physics::stencil::Stencil::write)): `step_fused`, last in this
//! file, does the same operations in the same order, bit for bit (tested).
//!
//! Reference: E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*,
//! 2nd ed., Springer 1993, §III.1 (predictor–corrector methods); NYCU Computer Animation HW1
//! (2021–2024), `integrator.cpp`.

use crate::physics::forces::{Model, accelerations};
use crate::physics::integrators::declaration::{Declaration, OscillatorLimit, Scratch, StabilityFunction, polynomial, two_evaluations};
use crate::physics::integrators::{explicit_step, Workspace, power_if, stage_then_step};
use crate::physics::particles::State;
use crate::physics::stencil::Stencil;

/// The method as the formula writes it: predictor, then corrector.
pub(super) fn textbook(model: &Model, state: &mut State, dt: f64, work: &mut Workspace) -> u64 {
    let Workspace {
        a,
        x_stage,
        v_stage,
        account,
        dissipated,
        power_f,
        ..
    } = work;
    accelerations(model, &state.x, &state.v, a);
    // Predictor: one explicit Euler step.
    for i in 0..state.x.len() {
        x_stage[i] = state.x[i] + dt * state.v[i];
        v_stage[i] = state.v[i] + dt * a[i];
    }
    // D_{n+1} = D_n + dt P(x̃, ṽ), when accounting (the corrector's stage).
    dissipated.add_power(dt, power_if(*account, model, x_stage, v_stage, power_f));
    // Corrector: the slope at the predicted state, applied from the old state.
    accelerations(model, x_stage, v_stage, a);
    for i in 0..state.x.len() {
        state.x[i] += dt * v_stage[i];
        state.v[i] += dt * a[i];
    }
    state.history_valid = false;
    2
}

/// The same step on a lattice in two stencil passes: the first writes the predicted state
/// `(x + dt v, v + dt a)`, the second applies the corrector's slope from the old state in
/// place (the loops above, per particle, so the same numbers), with the dissipated power at
/// the predicted state.
pub(super) fn step_fused(
    stencil: &Stencil,
    model: &Model,
    state: &mut State,
    dt: f64,
    work: &mut Workspace,
) -> u64 {
    stage_then_step(stencil, model, state, dt, dt, work)
}

/// The method's row of the registry (`integrators.rs`).
pub(super) const DECLARATION: Declaration = Declaration {
    name: "predictor-corrector",
    label: "PC",
    key: 'p',
    colour: 5,
    order: 1,
    evaluations: two_evaluations,
    oscillator: OscillatorLimit::Below(1.0),
    stability: |_| StabilityFunction::OneStep(|z| polynomial(&[1.0, 1.0, 1.0], z)),
    params: &[],
    scratch: Scratch::NONE,
    fused: true,
    energy_guard: false,
    step: |model, state, dt, _, work| {
        explicit_step(model, state, dt, work, textbook, step_fused)
    },
    many: None,
};
