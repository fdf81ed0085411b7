//! Position Verlet (Störmer–Verlet) with damping and distance-constraint projection.
//!
//! ```text
//! x_{n+1} = x_n + (1 - γ) (x_n - x_{n-1}) + a(x_n, v_n) dt²
//! then, `iterations` times, project every spring back to its rest length
//! v_{n+1} = (x_{n+1} - x_n) / dt
//! ```
//! where `x` is position (m), `a` acceleration (m/s²), `dt` the step (s) and `γ` the
//! dimensionless damping factor (GAMES101 uses 0.00005).
//!
//! The velocity is not a state variable: the last displacement `x_n - x_{n-1}` plays its part.
//! Global error O(dt²): **second order** (the GAMES101 sheet's "fourth order" is the local error
//! of the position in one step; errors accumulate over 1/dt steps). The velocity reported is the
//! backward difference, a first-order estimate of `v(t_{n+1})`.
//!
//! **Start-up.** The first step needs `x_{-1}`. Taking `x_{-1} = x_0` would be a velocity error
//! of O(dt) and make the method first order; instead, when the state holds no history,
//! `x_{-1} = x_0 - dt v_0 + ½ dt² a_0` (Taylor, error O(dt³)).
//!
//! **Stability on the harmonic oscillator** (γ = 0, no projection): the same recurrence as
//! semi-implicit Euler, `x_{n+1} - (2 - dt²ω²) x_n + x_{n-1} = 0`, stable while **dt·ω ≤ 2**.
//!
//! **Projection** ([`project_distances`]) with `iterations > 0` turns every spring into a rigid
//! rod (an infinitely stiff spring, GAMES101 §1.3): each end moves half the error, a pinned end
//! none. The spring forces still enter `a`, but after projection they are nearly zero.
//!
//! Reference: L. Verlet, "Computer 'Experiments' on Classical Fluids", Phys. Rev. 159 (1967);
//! E. Hairer, C. Lubich, G. Wanner, "Geometric numerical integration illustrated by the
//! Störmer–Verlet method", Acta Numerica 12 (2003), §1; T. Jakobsen, "Advanced Character
//! Physics", GDC 2001; GAMES101 assignment 8 (2020), §1.3–1.4.

use crate::physics::constraints::{prepare_rods, project_distances};
use crate::physics::forces::{Model, accelerations};
use crate::physics::integrators::{MethodParams, Workspace};
use crate::physics::particles::State;

pub(super) fn step(
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    let a = &mut work.a;
    accelerations(model, &state.x, &state.v, a);
    let dt2 = dt * dt;
    if !state.history_valid {
        // x_{-1} = x_0 - dt v_0 + ½ dt² a_0 (backward Taylor step, error O(dt³)).
        for i in 0..state.x.len() {
            state.x_prev[i] = state.x[i] - dt * state.v[i] + 0.5 * dt2 * a[i];
        }
    }
    let keep = 1.0 - params.verlet_damping;
    for i in 0..state.x.len() {
        let x_n = state.x[i];
        // x_{n+1} = x_n + (1 - γ)(x_n - x_{n-1}) + a_n dt²
        state.x[i] = x_n + keep * (x_n - state.x_prev[i]) + dt2 * a[i];
        state.x_prev[i] = x_n;
    }
    if params.iterations > 0 {
        prepare_rods(model, &mut work.rods);
        project_distances(&work.rods, &mut state.x, params.iterations);
    }
    let inv_dt = 1.0 / dt;
    for i in 0..state.x.len() {
        // v_{n+1} = (x_{n+1} - x_n) / dt
        state.v[i] = (state.x[i] - state.x_prev[i]) * inv_dt;
    }
    state.history_valid = true;
    1
}
