//! Semi-implicit (symplectic) Euler.
//!
//! ```text
//! v_{n+1} = v_n + dt a(x_n, v_n)
//! x_{n+1} = x_n + dt v_{n+1}
//! ```
//! where `x` is position (m), `v` velocity (m/s), `a` acceleration (m/s²) and `dt` the step (s).
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
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, §I.1.2 and §VI.3; GAMES101 assignment 8 (2020), §1.2.

use crate::physics::forces::{Model, accelerations};
use crate::physics::integrators::{Workspace, power_if};
use crate::physics::particles::State;
use crate::physics::stencil::Output;

pub(super) fn step(model: &Model, state: &mut State, dt: f64, work: &mut Workspace) -> u64 {
    // D_{n+1} = D_n + dt P(x_n, v_n), when accounting.
    let p = power_if(work.account, model, &state.x, &state.v, &mut work.power_f);
    work.dissipated.add_power(dt, p);
    if let Some(stencil) = model.stencil()
        && model.colliders.is_empty()
    {
        // A lattice: every thread computes the accelerations of its particles and advances
        // them in the same pass, with the operations below (so the same numbers), into fresh
        // buffers, because the other threads still read the old positions and velocities.
        let output = Output::SemiImplicitEuler {
            mass: &model.mass,
            gravity: model.gravity,
            drag: model.drag,
            inv_mass: &model.inv_mass,
            dt,
        };
        let (v_new, x_new) = (&mut work.v_stage, &mut work.x_stage);
        stencil.write(&state.x, &state.v, v_new, x_new, output);
        std::mem::swap(&mut state.v, v_new);
        std::mem::swap(&mut state.x, x_new);
        state.history_valid = false;
        return 1;
    }
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
