//! Velocity Verlet: the form of Verlet's method most students meet first.
//!
//! ```text
//! a_n     = a(x_n, v_n)
//! x_{n+1} = x_n + dt v_n + ½ dt² a_n
//! v*      = v_n + dt a_n                        (predicted velocity, for the dampers only)
//! a_{n+1} = a(x_{n+1}, v*)
//! v_{n+1} = v_n + ½ dt (a_n + a_{n+1})
//! ```
//! where
//! - `x`: positions (m), `v`: velocities (m/s)
//! - `a(x, v)`: accelerations from all forces (m/s²), [`crate::physics::accelerations`]
//! - `v*`: the velocity the forces at the new positions see (m/s)
//! - `dt`: the time step (s), `n`: the step index
//!
//! Without velocity-dependent forces (no dampers, no drag) `v*` plays no part and this is
//! exactly position Verlet (`verlet.rs`) written with the velocity as a state variable: the same
//! positions, no start-up rule, and a velocity at the same instant as the position. Global error
//! O(dt²): **second order**; symplectic and time-reversible, so on a conservative system the
//! energy oscillates around its true value instead of drifting. With dampers the force at the
//! new positions needs the new velocity, which the step has not computed yet; the predicted
//! `v*` differs from it by O(dt²), which costs O(dt³) per step in `v_{n+1}`, so the method stays
//! second order (position Verlet, whose dampers see a velocity half a step late, becomes first
//! order). Two force evaluations per step (the second could serve the next step when nothing
//! changes the state in between; this file keeps the textbook form). On a lattice each
//! evaluation and the dissipated power at the same state come from one stencil pass
//! (`integrators::accelerations_and_power`, the same bits as the two calls).
//!
//! **Stability on the harmonic oscillator** `x'' = -ω² x`: the step matrix has trace
//! `2 - dt²ω²` and determinant 1, the same recurrence as position Verlet and semi-implicit
//! Euler, stable while **dt·ω < 2**. With a damper the matrix is taken from the step itself
//! ([`DECLARATION`]'s stability function).
//!
//! **Energy accounting**: the trapezoidal rule on the dissipated power,
//! `dt/2 (P(x_n, v_n) + P(x_{n+1}, v*))`, second order like the step.
//!
//! Reference: W. C. Swope, H. C. Andersen, P. H. Berens, K. R. Wilson, "A computer simulation
//! method for the calculation of equilibrium constants…", J. Chem. Phys. 76 (1982), 637;
//! E. Hairer, C. Lubich, G. Wanner, "Geometric numerical integration illustrated by the
//! Störmer–Verlet method", Acta Numerica 12 (2003), §1.3.

use crate::physics::forces::Model;
use crate::physics::integrators::declaration::{
    Declaration, OscillatorLimit, Scratch, StabilityFunction, two_evaluations,
};
use crate::physics::integrators::{MethodParams, Workspace, accelerations_and_power};
use crate::physics::particles::State;

/// The method's row of the registry (`integrators.rs`).
pub(super) const DECLARATION: Declaration = Declaration {
    name: "velocity-verlet",
    label: "VV",
    key: 'V',
    colour: 10,
    order: 2,
    evaluations: two_evaluations,
    oscillator: OscillatorLimit::Below(2.0),
    stability: |_| StabilityFunction::TwoStep(recurrence),
    params: &[],
    scratch: Scratch::NONE,
    fused: false,
    energy_guard: false,
    step,
    many: None,
};

/// The method as the formula writes it.
fn step(model: &Model, state: &mut State, dt: f64, _: &MethodParams, work: &mut Workspace) -> u64 {
    let half = 0.5 * dt;
    let Workspace {
        a,
        k,
        v_stage,
        account,
        textbook,
        dissipated,
        power_f,
        ..
    } = work;
    let (account, textbook) = (*account, *textbook);
    // a_n = a(x_n, v_n); D += dt/2 P(x_n, v_n), when accounting (on a lattice from one pass,
    // `accelerations_and_power`).
    let (x, v) = (&state.x, &state.v);
    let p = accelerations_and_power(model, x, v, a, account, textbook, power_f);
    dissipated.add_power(half, p);
    for i in 0..state.x.len() {
        // x_{n+1} = x_n + dt v_n + ½ dt² a_n; v* = v_n + dt a_n.
        state.x[i] += dt * state.v[i] + half * dt * a[i];
        v_stage[i] = state.v[i] + dt * a[i];
    }
    // a_{n+1} = a(x_{n+1}, v*); D += dt/2 P(x_{n+1}, v*), when accounting.
    let a_new = &mut k[0];
    let p = accelerations_and_power(model, &state.x, v_stage, a_new, account, textbook, power_f);
    dissipated.add_power(half, p);
    for i in 0..state.v.len() {
        // v_{n+1} = v_n + ½ dt (a_n + a_{n+1}).
        state.v[i] += half * (a[i] + a_new[i]);
    }
    state.history_valid = false;
    2
}

/// The step on one mode `x'' = -ω² x - μ x'` is linear in `(x, v)`: its matrix `M` from the
/// formulas above applied to `(1, 0)` and `(0, 1)`; returns `(trace M, det M)`, the
/// coefficients of its characteristic polynomial `r² - t r + d` (`dt` in s, `ω²` in rad²/s²,
/// `μ` in 1/s).
fn recurrence(_: &MethodParams, dt: f64, w2: f64, mu: f64) -> (f64, f64) {
    let map = |x: f64, v: f64| {
        let a = -w2 * x - mu * v;
        let x1 = x + dt * v + 0.5 * dt * dt * a;
        let v_star = v + dt * a;
        let a1 = -w2 * x1 - mu * v_star;
        (x1, v + 0.5 * dt * (a + a1))
    };
    let (m00, m10) = map(1.0, 0.0);
    let (m01, m11) = map(0.0, 1.0);
    (m00 + m11, m00 * m11 - m01 * m10)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Undamped, the recurrence is leapfrog's: trace `2 - (dt ω)²`, determinant 1.
    #[test]
    fn undamped_recurrence_is_leapfrogs() {
        for z in [0.1, 1.0, 1.9, 2.5] {
            let (t, d) = recurrence(&MethodParams::default(), z, 1.0, 0.0);
            assert!((t - (2.0 - z * z)).abs() < 1e-12, "trace at dt·ω = {z}");
            assert!((d - 1.0).abs() < 1e-12, "determinant at dt·ω = {z}");
        }
    }
}
