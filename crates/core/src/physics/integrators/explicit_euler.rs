//! Explicit (forward) Euler.
//!
//! ```text
//! x_{n+1} = x_n + dt v_n
//! v_{n+1} = v_n + dt a(x_n, v_n)
//! ```
//! where
//! - `x`: positions (m), `v`: velocities (m/s)
//! - `a(x, v)`: accelerations from all forces (m/s²), [`crate::physics::accelerations`]
//! - `dt`: the time step (s), `n`: the step index
//!
//! Both updates use only the old state. Global error O(dt): first order.
//!
//! **Stability on the harmonic oscillator** `x'' = -ω² x`: the amplification factor is
//! `1 + i dt ω`, of modulus `√(1 + dt² ω²) > 1`, so the energy grows by `1 + dt² ω²` every step
//! for any `dt` — explicit Euler is unstable undamped. With damping it is stable only while
//! `dt λ` stays inside the unit circle around -1.
//!
//! **Fast path.** The textbook loop (`textbook`, first below) is the method. On a lattice,
//! [`Method::step`](super::Method::step) hands the same arithmetic, stage by stage, to the
//! stencil's fused passes through the one seam (`integrators::fused` and `fused_pass`, which call
//! [`Stencil::write`](crate::physics::stencil::Stencil::write)): `step_fused`, last in this
//! file, does the same operations in the same order, bit for bit (tested).
//!
//! Reference: E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*,
//! 2nd ed., Springer 1993, §I.7 and §II.1; GAMES101 assignment 8 (2020), §1.2.

use crate::physics::forces::{Model, accelerations};
use crate::physics::integrators::declaration::{Declaration, OscillatorLimit, Scratch, StabilityFunction, one_evaluation};
use crate::physics::integrators::{explicit_step, Workspace, one_pass_step, power_if};
use crate::physics::particles::State;
use crate::physics::stencil::{Base, Stencil, Update};

/// The method as the formula writes it: one force evaluation, then the two lines.
pub(super) fn textbook(model: &Model, state: &mut State, dt: f64, work: &mut Workspace) -> u64 {
    // D_{n+1} = D_n + dt P(x_n, v_n), when accounting.
    let p = power_if(work.account, model, &state.x, &state.v, &mut work.power_f);
    work.dissipated.add_power(dt, p);
    let a = &mut work.a;
    accelerations(model, &state.x, &state.v, a);
    for ((x, v), a) in state.x.iter_mut().zip(state.v.iter_mut()).zip(a.iter()) {
        // Position first, with the OLD velocity: x_{n+1} = x_n + dt v_n.
        *x += dt * *v;
        // Then v_{n+1} = v_n + dt a_n.
        *v += dt * *a;
    }
    state.history_valid = false;
    1
}

/// The same step on a lattice in one stencil pass: `x' = x + dt v`, `v' = v + dt a` per
/// particle (an Euler stage from the pass's own input), into fresh buffers.
pub(super) fn step_fused(
    stencil: &Stencil,
    model: &Model,
    state: &mut State,
    dt: f64,
    work: &mut Workspace,
) -> u64 {
    let update = Update::Euler {
        h: dt,
        base: Base::Input,
    };
    one_pass_step(stencil, model, state, dt, work, update)
}

/// The method's row of the registry (`integrators.rs`).
pub(super) const DECLARATION: Declaration = Declaration {
    name: "explicit-euler",
    label: "EE",
    key: 'e',
    colour: 9,
    order: 1,
    evaluations: one_evaluation,
    oscillator: OscillatorLimit::None,
    stability: |_| StabilityFunction::OneStep(|z| (1.0 + z.0, z.1)),
    params: &[],
    scratch: Scratch::NONE,
    fused: true,
    energy_guard: false,
    step: |model, state, dt, _, work| {
        explicit_step(model, state, dt, work, textbook, step_fused)
    },
    many: None,
};
