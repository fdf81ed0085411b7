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
//!     x     += Δ N   for a particle inside a collider (below)
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
//! **Contacts in the substeps** (Macklin et al. 2019, §3: collisions are constraints of every
//! substep). A particle that the substep carries inside a collider is a contact constraint of
//! zero compliance against an obstacle of infinite mass: it is moved back along the normal, but
//! never so far that it ends the substep moving out of the surface:
//!
//! ```text
//! φ, N  = signed distance and normal at x          (φ < 0: inside)
//! Δ     = min(-φ, max(0, (x_prev - x)·N))          the lift (m)
//! x    += Δ N
//! W     = (m Δ / h) (x - x_prev)·N / h  ≤ 0        the work of the impulse m Δ N / h (J)
//! ```
//! where `m` is the particle's mass (kg). A particle resting on the surface is held there with
//! `v·N = 0` (the impulse does no work), one arriving loses its normal speed (`W < 0`), and one
//! that started the substep inside is lifted only to its starting depth: the rest of the way out
//! is the collision response after the step, whose climb is paid from kinetic energy
//! (`crate::physics::collide`), as with implicit Euler's landing cap. The bounce (restitution)
//! and the impact friction are that response's too. Without contacts in the substeps, gravity
//! pulls a resting particle `g h²` into the surface every substep and the response puts it back:
//! on `cube-plane` at the course step the ledger's `contacts` term fell by 11 kJ between
//! t = 1.5 s and 2.5 s, to −6.0 kJ.
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

use glam::DVec3;

use crate::physics::collide::Contact;
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
    // The pass's rows (`fast/xpbd.rs`): two ends and six numbers per spring.
    scratch: Scratch {
        particle: 0.0,
        spring: crate::physics::fast::xpbd::ROW_BYTES as f64,
    },
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
        xpbd: rows,
        textbook,
        account,
        dissipated,
        power_f,
        ..
    } = work;
    // The seam: the textbook pass below, or the same pass laid out once with each spring's
    // constants, eight springs at a time (`fast/xpbd.rs`, the same numbers bit for bit).
    let wide = !*textbook && rows.prepare(model, h);
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
        if wide {
            rows.start_substep();
            for _ in 0..params.iterations.max(1) {
                rows.solve(&model.inv_mass, &mut state.x, x_start);
            }
        } else {
            lambda.fill(0.0);
            for _ in 0..params.iterations.max(1) {
                xpbd_solve(model, &mut state.x, x_start, lambda, h);
            }
        }
        let work = contacts(model, &mut state.x, x_start, h);
        if *account {
            dissipated.contacts -= work;
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

/// The contact constraints of a substep of `h` seconds (module docs): every free particle
/// inside a collider at `x` is lifted along the normal by `Δ = min(-φ, max(0, (x_start - x)·N))`
/// (m). Returns the work the contact impulses do (J, ≤ 0).
fn contacts(model: &Model, x: &mut [DVec3], x_start: &[DVec3], h: f64) -> f64 {
    if model.colliders.is_empty() {
        return 0.0;
    }
    let mut work = 0.0;
    for (i, (x, &start)) in x.iter_mut().zip(x_start).enumerate() {
        if model.inv_mass[i] == 0.0 {
            continue;
        }
        for collider in &model.colliders {
            if !collider.may_touch(*x, 0.0) {
                continue;
            }
            let Some(Contact { phi, normal }) = collider.contact(*x) else {
                continue;
            };
            if phi >= 0.0 {
                continue;
            }
            let lift = (-phi).min((start - *x).dot(normal).max(0.0));
            if lift <= 0.0 {
                continue;
            }
            *x += lift * normal;
            // W = J·v_end with J = m Δ N / h and v_end = (x - x_start) / h.
            work += model.mass[i] * lift * (*x - start).dot(normal) / (h * h);
        }
    }
    work
}
