//! Classic fourth-order Runge–Kutta (RK4).
//!
//! For the state `y = (x, v)` with derivative `y' = (v, a(x, v))`:
//!
//! ```text
//! k1x = v_n                     k1v = a(x_n,              v_n)
//! k2x = v_n + dt/2 k1v          k2v = a(x_n + dt/2 k1x,   v_n + dt/2 k1v)
//! k3x = v_n + dt/2 k2v          k3v = a(x_n + dt/2 k2x,   v_n + dt/2 k2v)
//! k4x = v_n + dt   k3v          k4v = a(x_n + dt   k3x,   v_n + dt   k3v)
//! x_{n+1} = x_n + dt/6 (k1x + 2 k2x + 2 k3x + k4x)
//! v_{n+1} = v_n + dt/6 (k1v + 2 k2v + 2 k3v + k4v)
//! ```
//! where
//! - `x`: positions (m), `v`: velocities (m/s)
//! - `a(x, v)`: accelerations from all forces (m/s²), [`crate::physics::accelerations`]
//! - `dt`: the time step (s), `n`: the step index
//! - `k1x..k4x`: slopes of the positions (m/s), `k1v..k4v`: slopes of the velocities (m/s²)
//!
//! Four force evaluations, global error O(dt⁴): fourth order. Note that `k1x` appears in the
//! position update: dropping it (a mistake in one course's code) makes the method first order.
//!
//! **Stability on the harmonic oscillator**: amplification
//! `R(z) = 1 + z + z²/2 + z³/6 + z⁴/24`, `z = i dt ω`; `|R| ≤ 1` while **dt·ω ≤ 2√2 ≈ 2.828**.
//! Inside that range it loses a little energy each step (`|R|² = 1 - (dt ω)⁶/72 + (dt ω)⁸/576`).
//!
//! **Fast path.** The textbook loop (`textbook`, first below) is the method. On a lattice,
//! [`Method::step`](super::Method::step) hands the same arithmetic, stage by stage, to the
//! stencil's fused passes through the one seam (`integrators::fused` and `fused_pass`, which call
//! [`Stencil::write`](crate::physics::stencil::Stencil::write)): `step_fused`, last in this
//! file, does the same operations in the same order, bit for bit (tested). Many steps in one
//! call (`steps`, after it) run those passes on one team of threads, with the same numbers
//! (tested).
//!
//! Reference: W. Kutta, "Beitrag zur näherungsweisen Integration totaler
//! Differentialgleichungen", Z. Math. Phys. 46 (1901); E. Hairer, S. P. Nørsett, G. Wanner,
//! *Solving Ordinary Differential Equations I*, 2nd ed., Springer 1993, §II.1, Table 1.2.

use crate::physics::energy::{Dissipated, Power};
use crate::physics::forces::{Model, accelerations};
use crate::physics::integrators::declaration::{Declaration, OscillatorLimit, Scratch, StabilityFunction, polynomial};
use crate::physics::integrators::{explicit_step, Workspace, after, fused_pass, power_if, team};
use crate::physics::particles::State;
use crate::physics::stencil::{Base, Output, PartFn, Pass, Stencil, TeamPower, TeamUpdate, Update};

/// The method as the formula writes it: four force evaluations, the stage loops between them.
pub(super) fn textbook(model: &Model, state: &mut State, dt: f64, work: &mut Workspace) -> u64 {
    let n = state.x.len();
    let half = 0.5 * dt;
    let Workspace {
        x_stage,
        v_stage,
        k,
        kx,
        account,
        dissipated,
        power_f,
        ..
    } = work;
    let account = *account;
    let [k1v, k2v, k3v, k4v] = k;
    let [k1x, k2x, k3x, k4x] = kx;
    let (x, v) = (&state.x, &state.v);

    // Stage 1: the slope at the start.
    k1x[..n].copy_from_slice(v);
    accelerations(model, x, v, k1v);
    // The dissipated power at each stage, weighted like the slopes: D' = P(x, v).
    let mut power = Power::default().plus(1.0, power_if(account, model, x, v, power_f));
    // Stage 2: the slope at a half step along stage 1.
    for i in 0..n {
        x_stage[i] = x[i] + half * k1x[i];
        v_stage[i] = v[i] + half * k1v[i];
        k2x[i] = v_stage[i];
    }
    accelerations(model, x_stage, v_stage, k2v);
    power = power.plus(2.0, power_if(account, model, x_stage, v_stage, power_f));
    // Stage 3: the slope at a half step along stage 2.
    for i in 0..n {
        x_stage[i] = x[i] + half * k2x[i];
        v_stage[i] = v[i] + half * k2v[i];
        k3x[i] = v_stage[i];
    }
    accelerations(model, x_stage, v_stage, k3v);
    power = power.plus(2.0, power_if(account, model, x_stage, v_stage, power_f));
    // Stage 4: the slope at a full step along stage 3.
    for i in 0..n {
        x_stage[i] = x[i] + dt * k3x[i];
        v_stage[i] = v[i] + dt * k3v[i];
        k4x[i] = v_stage[i];
    }
    accelerations(model, x_stage, v_stage, k4v);
    power = power.plus(1.0, power_if(account, model, x_stage, v_stage, power_f));
    // Weighted mean of the four slopes (Simpson's rule weights 1, 2, 2, 1).
    let sixth = dt / 6.0;
    dissipated.add_power(sixth, power);
    for i in 0..n {
        state.x[i] += sixth * (k1x[i] + 2.0 * k2x[i] + 2.0 * k3x[i] + k4x[i]);
        state.v[i] += sixth * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
    }
    state.history_valid = false;
    4
}

/// The same step on a lattice in four stencil passes, each ending with the next stage's loop
/// for its own particles (the loops above, so the same numbers):
///
/// ```text
/// pass 1 at (x_n, v_n):  k1v;  x_2 = x_n + dt/2 v_n,  v_2 = v_n + dt/2 k1v
/// pass 2 at (x_2, v_2):  k2v;  x_3 = x_n + dt/2 v_2,  v_3 = v_n + dt/2 k2v
/// pass 3 at (x_3, v_3):  k3v;  x_4 = x_n + dt v_3,    v_4 = v_n + dt k3v
/// pass 4 at (x_4, v_4):  k4v;  the weighted sums, in place
/// ```
/// with `k1x = v_n`, `k2x = v_2`, `k3x = v_3`, `k4x = v_4`: the slopes of positions are the
/// stages' velocities, so they need no buffers of their own. Each pass also integrates the
/// dissipated power of its stage when accounting.
pub(super) fn step_fused(
    stencil: &Stencil,
    model: &Model,
    state: &mut State,
    dt: f64,
    work: &mut Workspace,
) -> u64 {
    let half = 0.5 * dt;
    let Workspace {
        x_stage,
        k,
        kx,
        account,
        dissipated,
        power_f,
        projection,
        projected,
        ..
    } = work;
    let account = *account;
    let [k1v, k2v, k3v, _] = k;
    // x_2 and x_4 share a buffer: pass 3 reads x_3.
    let [x3, v2, v3, v4] = kx;
    let dynamics = model.dynamics(true);
    // Every stage starts from (x_n, v_n): the first from its own input (the same numbers, read
    // where the pass has them already), the others from the state.
    let stage = |h: f64, base| Output::Step {
        dynamics,
        update: Update::Euler { h, base },
        after: None,
    };
    let p1 = fused_pass(
        stencil,
        &state.x,
        &state.v,
        [x_stage, v2, k1v],
        stage(half, Base::Input),
        account,
        power_f,
    );
    let p2 = fused_pass(
        stencil,
        x_stage,
        v2,
        [x3, v3, k2v],
        stage(half, Base::Slices(&state.x, &state.v)),
        account,
        power_f,
    );
    let p3 = fused_pass(
        stencil,
        x3,
        v3,
        [x_stage, v4, k3v],
        stage(dt, Base::Slices(&state.x, &state.v)),
        account,
        power_f,
    );
    let sixth = dt / 6.0;
    let last = Output::Step {
        dynamics,
        update: Update::Rk4 {
            sixth,
            a: [k1v, k2v, k3v],
            v: [v2, v3],
        },
        after: after(projection),
    };
    let outs = [&mut state.x[..], &mut state.v[..], &mut []];
    let p4 = fused_pass(stencil, x_stage, v4, outs, last, account, power_f);
    // D_{n+1} = D_n + dt/6 (P1 + 2 P2 + 2 P3 + P4), when accounting.
    let power = Power::default()
        .plus(1.0, p1)
        .plus(2.0, p2)
        .plus(2.0, p3)
        .plus(1.0, p4);
    dissipated.add_power(sixth, power);
    *projected = true;
    state.history_valid = false;
    4
}

/// `n` steps in one call on a lattice large enough for several threads, the same numbers bit
/// for bit as `n` calls of `step`: the four passes of `step_fused` for each step, all run by
/// one team of threads ([`Stencil::team_with_power`]) instead of one pool job per pass. With
/// energy accounting each pass also writes the dissipated power of its stage, and
/// `work.step_dissipated` receives `dt/6 (P1 + 2 P2 + 2 P3 + P4)` per step, as `step` adds it.
/// `None`, having done nothing, where that does not apply: no lattice, the textbook loop asked
/// for, or one thread.
pub(super) fn steps(
    model: &Model,
    state: &mut State,
    dt: f64,
    work: &mut Workspace,
    n: u64,
) -> Option<u64> {
    let (stencil, parts) = team(model, work)?;
    let (half, sixth) = (0.5 * dt, dt / 6.0);
    let dynamics = model.dynamics(true);
    let account = work.account;
    let after = after(&work.projection);
    // The buffers of `step_fused`, by index: the state (0, 1), x_2 and x_4 (2), x_3 (3),
    // v_2, v_3, v_4 (4, 5, 6), k1v, k2v, k3v (7, 8, 9). With accounting, pass j of step s
    // writes its power into slot 4 s + j.
    // The first stage's base is its own input, the state (as in `step_fused`).
    let stage = |x, v, outs, h, base| Pass {
        x,
        v,
        outs,
        dynamics,
        update: TeamUpdate::Euler { h, base },
        after: None,
        power: None,
    };
    let passes = [
        stage(0, 1, [Some(2), Some(4), Some(7)], half, None),
        stage(2, 4, [Some(3), Some(5), Some(8)], half, Some([0, 1])),
        stage(3, 5, [Some(2), Some(6), Some(9)], dt, Some([0, 1])),
        Pass {
            x: 2,
            v: 6,
            outs: [Some(0), Some(1), None],
            dynamics,
            update: TeamUpdate::Rk4 {
                sixth,
                a: [7, 8, 9],
                v: [4, 5],
            },
            after,
            power: None,
        },
    ];
    let Workspace {
        x_stage,
        k,
        kx,
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
    let [k1v, k2v, k3v, _] = k;
    let [x3, v2, v3, v4] = kx;
    let mut buffers = [
        &mut state.x[..],
        &mut state.v[..],
        &mut x_stage[..],
        &mut x3[..],
        &mut v2[..],
        &mut v3[..],
        &mut v4[..],
        &mut k1v[..],
        &mut k2v[..],
        &mut k3v[..],
    ];
    let (ring, totals) = if account {
        (stencil.power_ring_len(parts), 4 * n as usize)
    } else {
        (0, 0)
    };
    power_slots.resize(ring, 0.0);
    step_powers.clear();
    step_powers.resize(totals, (0.0, 0.0));
    let power = TeamPower {
        ring: power_slots,
        totals: step_powers,
        contact: !dynamics.colliders.is_empty(),
    };
    stencil.team_with_power(parts, &mut buffers, power, &|crew| {
        for s in 0..n as usize {
            for (j, pass) in passes.iter().enumerate() {
                let mut pass = *pass;
                pass.power = account.then_some(4 * s + j);
                // The last pass writes the state, which the response's summary reads.
                crew.pass_then(&pass, if j == 3 { prepare } else { None });
            }
            if let Some(response) = response {
                // The step's last pass wrote the state (buffers 0 and 1).
                crew.serial(0, 1, &|x, v| (response.0)(model, x, v));
            }
        }
    });
    if account {
        for powers in step_powers.chunks_exact(4) {
            let p = |j: usize| Power {
                dampers_and_drag: powers[j].0,
                contact: powers[j].1,
            };
            // D_{n+1} = D_n + dt/6 (P1 + 2 P2 + 2 P3 + P4), as `step_fused` adds it.
            let power = Power::default()
                .plus(1.0, p(0))
                .plus(2.0, p(1))
                .plus(2.0, p(2))
                .plus(1.0, p(3));
            let mut d = Dissipated::default();
            d.add_power(sixth, power);
            step_dissipated.push(d.summed());
        }
    }
    work.projected = true;
    state.history_valid = false;
    Some(4 * n)
}

/// The method's row of the registry (`integrators.rs`).
pub(super) const DECLARATION: Declaration = Declaration {
    name: "rk4",
    label: "RK4",
    key: 'r',
    colour: 6,
    order: 4,
    evaluations: |_| 4.0,
    oscillator: OscillatorLimit::Below(2.0 * std::f64::consts::SQRT_2),
    stability: |_| StabilityFunction::OneStep(|z| polynomial(&[1.0, 1.0, 1.0 / 2.0, 1.0 / 6.0, 1.0 / 24.0], z)),
    params: &[],
    scratch: Scratch::NONE,
    fused: true,
    energy_guard: false,
    step: |model, state, dt, _, work| {
        explicit_step(model, state, dt, work, textbook, step_fused)
    },
    many: Some(steps),
};
