//! Semi-implicit (symplectic) Euler.
//!
//! ```text
//! v_{n+1} = v_n + dt a(x_n, v_n)
//! x_{n+1} = x_n + dt v_{n+1}
//! ```
//! where
//! - `x`: positions (m), `v`: velocities (m/s)
//! - `a(x, v)`: accelerations from all forces (m/s²), [`crate::physics::accelerations`]
//! - `dt`: the time step (s), `n`: the step index
//!
//! The only difference from explicit Euler is the order of the two lines: position is advanced
//! with the NEW velocity. Global error O(dt): first order. The map is symplectic, so on a
//! conservative system the energy oscillates around its true value instead of drifting.
//!
//! **Stability on the harmonic oscillator** `x'' = -ω² x`: the step matrix
//! `[[1 - dt²ω², dt], [-dt ω², 1]]` has determinant 1 and trace `2 - dt²ω²`; its eigenvalues stay
//! on the unit circle while `|trace| < 2`, that is while **dt·ω < 2**; at dt·ω = 2 they meet at
//! -1 as a double root and the amplitude grows linearly; beyond, one grows exponentially.
//!
//! **Fast path.** The textbook loop (`textbook`, first below) is the method. On a lattice,
//! [`Method::step`](super::Method::step) hands the same arithmetic, stage by stage, to the
//! stencil's fused passes through the one seam (`integrators::fused` and `fused_pass`, which call
//! [`Stencil::write`](crate::physics::stencil::Stencil::write)): `step_fused`, last in this
//! file, does the same operations in the same order, bit for bit (tested). On a small lattice
//! (a rope) many steps can also be taken in one call (`steps`, after it): the stencil then
//! keeps the particles in its own layout between the steps, with the same numbers (tested).
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, §I.1.2 and §VI.3; GAMES101 assignment 8 (2020), §1.2.

use crate::physics::forces::{Model, accelerations};
use crate::physics::integrators::declaration::{Declaration, OscillatorLimit, Scratch, StabilityFunction, one_evaluation};
use crate::physics::energy::{Dissipated, Power};
use crate::physics::integrators::{explicit_step, Workspace, after, fused, one_pass_step, power_if, team};
use crate::physics::particles::State;
use crate::physics::stencil::{PartFn, Pass, Stencil, TeamPower, TeamUpdate, Update};

/// The method as the formula writes it: one force evaluation, then the two lines.
pub(super) fn textbook(model: &Model, state: &mut State, dt: f64, work: &mut Workspace) -> u64 {
    // D_{n+1} = D_n + dt P(x_n, v_n), when accounting.
    let p = power_if(work.account, model, &state.x, &state.v, &mut work.power_f);
    work.dissipated.add_power(dt, p);
    let a = &mut work.a;
    accelerations(model, &state.x, &state.v, a);
    for ((x, v), a) in state.x.iter_mut().zip(state.v.iter_mut()).zip(a.iter()) {
        // Velocity first: v_{n+1} = v_n + dt a_n.
        *v += dt * *a;
        // Then position with the NEW velocity: x_{n+1} = x_n + dt v_{n+1}.
        *x += dt * *v;
    }
    state.history_valid = false;
    1
}

/// The same step on a lattice, fused into the stencil's pass (`physics::stencil`): every thread
/// computes the accelerations of its particles and advances them with the two lines above (so
/// the same numbers), the dissipated power and the projection in the same pass, into fresh
/// buffers, because the other threads still read the old positions and velocities.
pub(super) fn step_fused(
    stencil: &Stencil,
    model: &Model,
    state: &mut State,
    dt: f64,
    work: &mut Workspace,
) -> u64 {
    one_pass_step(
        stencil,
        model,
        state,
        dt,
        work,
        Update::SemiImplicitEuler { dt },
    )
}

/// `n` steps in one call on a lattice, the same numbers bit for bit as `n` calls of `step`:
/// on a small lattice (at most 256 particles, no colliders, no projection) the stencil keeps
/// the particles in its own layout between the steps
/// ([`Stencil::semi_implicit_euler_steps_with_power`]); on a lattice large enough for several
/// threads they run all `n` steps as one team, alternating between the state and the stage
/// buffers ([`Stencil::team_with_power`]). With energy accounting each step's pass also
/// writes its dissipated power at `(x_n, v_n)`, and `work.step_dissipated` receives
/// `dt P(x_n, v_n)` per step, as `step` adds it. `None`, having done nothing, where neither
/// applies: no lattice, the textbook loop asked for, or one thread.
pub(super) fn steps(
    model: &Model,
    state: &mut State,
    dt: f64,
    work: &mut Workspace,
    n: u64,
) -> Option<u64> {
    let stencil = fused(model, work.textbook)?;
    let dynamics = model.dynamics(true);
    let account = work.account;
    let per_step = |p: Power| {
        // D_{n+1} = D_n + dt P(x_n, v_n), as `step` adds it.
        let mut d = Dissipated::default();
        d.add_power(dt, p);
        d.summed()
    };
    if work.projection.is_none() && work.response.is_none() {
        work.step_powers.clear();
        let powers = account.then_some(&mut work.step_powers);
        if stencil.semi_implicit_euler_steps_with_power(
            &mut state.x,
            &mut state.v,
            &dynamics,
            dt,
            n,
            powers,
        ) {
            let dissipated = work.step_powers.iter().map(|&(dampers_and_drag, contact)| {
                per_step(Power {
                    dampers_and_drag,
                    contact,
                })
            });
            work.step_dissipated.extend(dissipated);
            state.history_valid = false;
            return Some(n);
        }
    }
    let (stencil, parts) = team(model, work)?;
    // Buffers 0, 1: the state; 2, 3: the stage. Step s reads one pair and writes the other;
    // with accounting its power goes to slot s.
    let pass = |s: u64, slot: usize| {
        let (from, to) = if s.is_multiple_of(2) { (0, 2) } else { (2, 0) };
        Pass {
            x: from,
            v: from + 1,
            outs: [Some(to), Some(to + 1), None],
            dynamics,
            update: TeamUpdate::SemiImplicitEuler { dt },
            after: after(&work.projection),
            power: account.then_some(slot),
        }
    };
    let Workspace {
        x_stage,
        v_stage,
        power_slots,
        step_powers,
        step_dissipated,
        response,
        ..
    } = work;
    let response = response.as_ref();
    // The response's summary of each part, made by the thread that wrote it.
    let prepare_part = response.and_then(|r| r.part_summary(model));
    let prepare: Option<PartFn> = prepare_part.as_ref().map(|f| f as PartFn);
    let (ring, totals) = if account {
        (stencil.power_ring_len(parts), n as usize)
    } else {
        (0, 0)
    };
    power_slots.resize(ring, 0.0);
    step_powers.clear();
    step_powers.resize(totals, (0.0, 0.0));
    let mut buffers = [
        &mut state.x[..],
        &mut state.v[..],
        &mut x_stage[..],
        &mut v_stage[..],
    ];
    let power = TeamPower {
        ring: power_slots,
        totals: step_powers,
        contact: !dynamics.colliders.is_empty(),
    };
    stencil.team_with_power(parts, &mut buffers, power, &|crew| {
        for s in 0..n {
            crew.pass_then(&pass(s, s as usize), prepare);
            if let Some(response) = response {
                // Between this step and the next, on the buffers the step wrote.
                let to = if s.is_multiple_of(2) { 2 } else { 0 };
                crew.serial(to, to + 1, &|x, v| (response.0)(model, x, v));
            }
        }
    });
    if account {
        let powers = step_powers.iter().map(|&(dampers_and_drag, contact)| Power {
            dampers_and_drag,
            contact,
        });
        step_dissipated.extend(powers.map(per_step));
    }
    if !n.is_multiple_of(2) {
        std::mem::swap(&mut state.x, x_stage);
        std::mem::swap(&mut state.v, v_stage);
    }
    work.projected = true;
    state.history_valid = false;
    Some(n)
}

/// The method's row of the registry (`integrators.rs`).
pub(super) const DECLARATION: Declaration = Declaration {
    name: "semi-implicit-euler",
    label: "SIE",
    key: 's',
    colour: 2,
    order: 1,
    evaluations: one_evaluation,
    oscillator: OscillatorLimit::Below(2.0),
    stability: |_| StabilityFunction::TwoStep(|_, dt, w2, mu| (2.0 - dt * dt * w2 - dt * mu, 1.0 - dt * mu)),
    params: &[],
    scratch: Scratch::NONE,
    fused: true,
    energy_guard: false,
    step: |model, state, dt, _, work| {
        explicit_step(model, state, dt, work, textbook, step_fused)
    },
    many: Some(steps),
};
