//! Implicit (backward) Euler, one Newton step, solved by conjugate gradients.
//!
//! Backward Euler evaluates the force at the END of the step:
//!
//! ```text
//! v_{n+1} = v_n + dt M⁻¹ f(x_{n+1}, v_{n+1})
//! x_{n+1} = x_n + dt v_{n+1}
//! ```
//! Linearising `f` about `(x_n, v_n)` (one Newton step) with `Δv = v_{n+1} - v_n` and
//! `Δx = dt (v_n + Δv)` gives one linear system (Baraff & Witkin 1998, eq. 6):
//!
//! ```text
//! (M - dt ∂f/∂v - dt² ∂f/∂x) Δv = dt (f_n + dt ∂f/∂x v_n)
//! ```
//! where `M` is the diagonal mass matrix (kg), `f_n = f(x_n, v_n)` (N), and per spring with
//! `n = (x_b - x_a)/L`:
//!
//! ```text
//! ∂f_a/∂x_b = K_s = k [ n nᵀ + max(0, 1 - L0/L) (I - n nᵀ) ]      (N/m)
//! ∂f_a/∂v_b = D_s = k_d n nᵀ                                       (N·s/m)
//! ∂f_a/∂x_a = -K_s,   ∂f_a/∂v_a = -D_s,   and the mirror for b
//! ∂f_i/∂v_i = -c I    (viscous drag)
//! ```
//! The transverse term `1 - L0/L` is negative for a compressed spring and would make the matrix
//! indefinite; it is clamped at zero (Choi & Ko 2002, §4), which keeps the system symmetric
//! positive definite so conjugate gradients converge. The damper's dependence on position is
//! dropped, as in Baraff & Witkin. The solve is matrix-free: `A p` is assembled spring by spring
//! from 3×3 blocks, preconditioned by the inverse 3×3 diagonal blocks (block Jacobi). Pinned
//! particles are filtered out: their rows and columns are held at `Δv = 0` (Baraff & Witkin §5.3).
//!
//! One force evaluation per step (plus the Jacobian, at about the cost of another). Global error
//! O(dt): first order. **Stability**: amplification `1 / (1 - z)` with `|·| < 1` for every
//! `Re z < 0` and on the undamped oscillator (`z = i dt ω`): unconditionally stable, and it
//! removes energy, the more the larger `dt·ω`.
//!
//! **Contacts inside the solve.** A particle that the solve would carry into a collider is not
//! projected back afterwards: moving it out while its neighbours stay put would compress its
//! springs and *add* their elastic energy (measured on `jelly-bowl` at dt = 0.04 s: +24 kJ at the
//! first impact). Instead its velocity along the surface normal `N` is prescribed so that the
//! step ends on the surface, and the solve is repeated with that constraint (Baraff & Witkin §5.3,
//! the "filter" `S = I - N Nᵀ` on the constrained particles' rows):
//!
//! ```text
//! x̃      = x_n + dt (v_n + Δv)               where the unconstrained solve would end
//! φ̃, N   = signed distance and normal at x̃   (φ̃ < 0: inside)
//! Δv·N    = (v_n + Δv)·N - φ̃/dt - v_n·N       prescribed: x_{n+1} lands on the surface
//! (S A S) y = S (b - A z),   Δv = z + y       z: the prescribed parts, y ⊥ N
//! ```
//! where `φ̃` is in m. The contact set is found by an active-set loop of up to
//! [`MAX_CONTACT_PASSES`] solves: a solve adds the particles it still carries inside, and
//! releases the constrained ones whose constraint impulse `J_i = (A Δv - b)_i·N_i` is negative
//! (a contact pushes, it never pulls: `J ≥ 0`), then solves again from its own `Δv`. The
//! springs then feel the contact within the same implicit step, the constraint only slows the
//! approach (it removes kinetic energy), and the collision response after the step
//! ([`crate::physics::collide::resolve`]) finds the particle on the surface: it bounces it with
//! the restitution and moves nothing, so no spring is squeezed by a projection. With the warm
//! start (below) the first solve starts from the last step's contact set, re-aimed at where the
//! warm start carries each particle, so a resting contact costs one solve, not two (a missed
//! contact is caught by the check after the last pass).
//!
//! **Contacts with spheres** (the cloth scenes' dynamic and kinematic spheres) are constraints
//! the same way, against the sphere where it ends the step
//! ([`crate::physics::collide::advance_spheres`]: `c_{n+1} = c_n + dt (V_n + dt g)`, or
//! `c_n + dt V_n` for a kinematic one), with `φ̃ = |x̃ - c_{n+1}| - r` and
//! `N = (x̃ - c_{n+1}) / |x̃ - c_{n+1}|`. The constraint's impulse
//! `J_i = (A Δv - b)_i·N_i` (N·s) pushes the particle; its reaction `-J_i N_i` goes to a
//! dynamic sphere, `V ← V - Σ_i J_i N_i / M` (momentum kept; kinetic energy change counted as
//! dissipated by the contacts). Measured on `cloth-spheres` at dt = 0.005 s, the projection
//! after the step that this replaces added 200–2 000 J of elastic energy per step while the
//! spheres pressed into the cloth, so `Simulation`'s energy guard re-took 277 of 600 steps as
//! halves; with the spheres inside the solve the energy rises on none of them.
//!
//! **How exact the solve is.** CG stops at the relative residual `|r| ≤ tol·|b|`, by default
//! `tol = 10⁻³` (`cg_tolerance`). The step is one Newton step of a first-order method, whose own
//! error is far larger: on `cloth-spheres` at dt = 5 ms over 1 s, stopping at 10⁻³ instead of
//! 10⁻¹⁰ moves no particle or sphere by more than 0.14 mm, while the method's own error (against
//! dt/4, a lower bound) is 35 mm, 250 times more (at 10⁻² it would be 2.1 mm, a sixteenth;
//! `tests/integrators.rs` checks that the default stays under a tenth). A tighter tolerance buys
//! digits of a linearisation that is not the true step anyway.
//!
//! **Warm start.** With [`Workspace::warm_start`] (on in `Simulation`) a solve starts from a
//! guess instead of zero: the last step's `Δv` extrapolated linearly over the two last steps
//! (`2 Δv_{n-1} - Δv_{n-2}` at an unchanged dt), and the last step's contact set re-aimed at
//! where that guess carries each particle. When the only things to touch are spheres, the
//! particles the guess carries inside a sphere are constrained from the first solve too, so a
//! contact that begins this step does not cost a second solve (on `cloth-spheres` at dt = 5 ms,
//! 8.07 CG iterations per step instead of 8.69). With a terrain the guess's contacts are left
//! to the solves: on `jelly-bowl` at dt = 0.1 s, where the guess lands far from where the step
//! ends, they picked faces that added energy the guard did not take back (`tests/integrators.rs`).
//! A cloth resting on the spheres takes one solve of about 8 iterations per step (the first
//! version: two solves, 74 iterations in all).
//!
//! **Reported solve.** [`SolveStats`] holds the conjugate-gradient iterations (over all passes)
//! and the final relative residual of the last step; a solve that stops above its tolerance, or
//! whose right-hand side or residual is not finite (an overflowing stiffness), is not
//! `converged`, and a simulation reports that as a divergence.
//!
//! Reference: D. Baraff, A. Witkin, "Large Steps in Cloth Simulation", SIGGRAPH 1998, §3, §5;
//! K.-J. Choi, H.-S. Ko, "Stable but Responsive Cloth", SIGGRAPH 2002, §4; J. R. Shewchuk,
//! "An Introduction to the Conjugate Gradient Method Without the Agonizing Pain", 1994, §B3.

use glam::{DMat3, DVec3};
use serde::Serialize;

use crate::physics::collide::Contact;
use crate::physics::energy::Power;
use crate::physics::energy::{Energy, energy, energy_with_elastic};
use crate::physics::forces::{Model, forces};
use crate::physics::integrators::{
    MethodParams, PowerScratch, Workspace, fused, power_if, stencil_power,
};
use crate::physics::particles::State;
use crate::physics::stencil::{Kernel, Stencil};

pub(crate) use super::implicit_constraint::Constraint;
use super::implicit_lattice::{Forces, inside_spheres, usable};

/// At most this many solves per step: the first without contact constraints, each further one
/// with the particles the previous solve carried into a collider.
pub const MAX_CONTACT_PASSES: u32 = 4;

/// How the last linear solve went.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SolveStats {
    /// Conjugate-gradient iterations taken, over all contact passes of the step.
    pub iterations: u32,
    /// Final relative residual `|r| / |b|` (NaN when the system was not finite).
    pub relative_residual: f64,
    /// True when the residual reached the tolerance (or the right-hand side was zero).
    pub converged: bool,
    /// Solves taken (1 + contact passes).
    pub passes: u32,
    /// Particles whose normal velocity the contacts prescribed.
    pub constrained: u32,
}

impl SolveStats {
    /// Adds one solve of `iterations` that ended at relative residual `residual`.
    fn record(&mut self, iterations: u32, residual: f64, converged: bool) {
        self.iterations += iterations;
        self.relative_residual = residual;
        self.converged = converged;
        self.passes += 1;
    }
}

impl Default for SolveStats {
    fn default() -> SolveStats {
        SolveStats {
            iterations: 0,
            relative_residual: 0.0,
            converged: true,
            passes: 0,
            constrained: 0,
        }
    }
}

impl SolveStats {
    /// Why the solve failed, in words; `None` when it converged.
    #[must_use]
    pub fn failure(&self, tolerance: f64) -> Option<String> {
        if self.converged {
            return None;
        }
        Some(if self.relative_residual.is_finite() {
            format!(
                "implicit Euler: the linear solve did not converge ({} conjugate-gradient \
                 iterations, relative residual {:.3e} > tolerance {tolerance:.1e})",
                self.iterations, self.relative_residual
            )
        } else {
            "implicit Euler: the linear solve overflowed (a force, the matrix or the residual \
             is not finite)"
                .to_string()
        })
    }
}

/// The method as the formulas above write it: the spring list, 3×3 blocks, textbook CG.
fn textbook(
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    let dt2 = dt * dt;
    let warm = warm_start(work, dt);
    let Workspace {
        a: rhs,
        blocks,
        diag_inv,
        cg,
        last_solve,
        constraints,
        inside,
        account,
        dissipated,
        power_f,
        last_dv,
        last_dt,
        before_dv,
        before_dt,
        ..
    } = work;

    // b = dt f_n  (then + dt² ∂f/∂x v_n below).
    forces(model, &state.x, &state.v, rhs);
    for b in rhs.iter_mut() {
        *b *= dt;
    }
    // Diagonal blocks start with M + dt c I (mass and drag).
    for (d, &m) in diag_inv.iter_mut().zip(&model.mass) {
        *d = DMat3::from_diagonal(DVec3::splat(m + dt * model.drag));
    }
    // Per spring: B_s = dt D_s + dt² K_s, the off-diagonal coupling of A; and b += dt² K_s v.
    for (s, block) in model.springs.iter().zip(blocks.iter_mut()) {
        let (ia, ib) = (s.a as usize, s.b as usize);
        let d = state.x[ib] - state.x[ia];
        let length = d.length();
        if length == 0.0 {
            *block = DMat3::ZERO;
            continue;
        }
        let dir = d / length;
        let nn = outer(dir, dir);
        // K_s = k [ n nᵀ + max(0, 1 - L0/L)(I - n nᵀ) ]
        let transverse = (1.0 - s.rest_length / length).max(0.0);
        let k_s = s.stiffness * (nn + transverse * (DMat3::IDENTITY - nn));
        // D_s = k_d n nᵀ
        let d_s = s.damping * nn;
        *block = dt * d_s + dt2 * k_s;
        // dt² ∂f/∂x v_n: row a gets K_s (v_b - v_a), row b the opposite.
        let kv = dt2 * (k_s * (state.v[ib] - state.v[ia]));
        rhs[ia] += kv;
        rhs[ib] -= kv;
        diag_inv[ia] += *block;
        diag_inv[ib] += *block;
    }
    for d in diag_inv.iter_mut() {
        *d = d.inverse();
    }

    let system = System {
        model,
        dt,
        blocks,
        diag_inv,
        rhs,
    };
    let contacts = has_contacts(model, state);
    if warm && contacts {
        start_contacts(model, state, dt, &cg[0], constraints, inside);
    } else {
        constraints.clear();
    }
    let mut stats = SolveStats::default();
    loop {
        // Later passes start from the previous pass's Δv (it changed only near contacts).
        let (iterations, residual, converged) = system.solve(
            constraints,
            (params.cg_tolerance, params.cg_max_iterations),
            cg,
            warm || stats.passes > 0,
        );
        stats.record(iterations, residual, converged);
        if !converged || !contacts || stats.passes >= MAX_CONTACT_PASSES {
            break;
        }
        // Release the constraints that pull; prescribe the particles this solve carries into
        // a collider.
        let [dv, _, _, ap] = &mut *cg;
        let released = !constraints.is_empty() && {
            system.apply(dv, ap);
            release_pulling(constraints, |i| ap[i] - system.rhs[i])
        };
        if !(add_contacts(model, state, dt, dv, constraints, inside) || released) {
            break;
        }
    }
    stats.constrained = constraints.len() as u32;
    *last_solve = stats;
    if !constraints.is_empty() && (*account || constraints.iter().any(|c| c.sphere.is_some())) {
        // The constraint impulses J = (A Δv - b)·N (N·s) do the work J (v_{n+1}·N) on the
        // particles; minus that is what the contacts inside the solve removed (J).
        let [dv, _, _, ap] = &mut *cg;
        system.apply(dv, ap);
        let removed = contact_impulses(state, constraints, dv, |i| ap[i] - system.rhs[i]);
        if *account {
            dissipated.contacts += removed;
        }
    }

    let dv = &cg[0];
    remember((last_dv, last_dt), (before_dv, before_dt), dv, dt);
    advance(model, state, dt, dv);
    // D_{n+1} = D_n + dt P(x_{n+1}, v_{n+1}): backward Euler on D' = P too, when accounting.
    dissipated.add_power(dt, power_if(*account, model, &state.x, &state.v, power_f));
    1
}

/// The step's update from the solved velocity change, on free particles:
/// `v_{n+1} = v_n + Δv`, `x_{n+1} = x_n + dt v_{n+1}`.
fn advance(model: &Model, state: &mut State, dt: f64, dv: &[DVec3]) {
    for i in 0..state.x.len() {
        if model.inv_mass[i] != 0.0 {
            state.v[i] += dv[i];
            state.x[i] += dt * state.v[i];
        }
    }
    state.history_valid = false;
}

pub(super) fn step(
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    match fused(model, work).filter(|s| usable(s)) {
        Some(stencil) => step_lattice(stencil, model, state, dt, params, work),
        None => textbook(model, state, dt, params, work),
    }
}

/// The energy of `state` (J) as [`crate::physics::energy`] sums it, with the springs' elastic
/// term summed on the lattice where there is one (eight springs at a time; equal to rounding).
/// `Simulation`'s energy guard compares two of these around every step.
pub fn guard_energy(model: &Model, state: &State, work: &mut Workspace) -> Energy {
    match fused(model, work) {
        Some(stencil) => {
            let elastic = work.lattice.elastic_energy(stencil, &state.x);
            energy_with_elastic(model, state, elastic)
        }
        None => energy(model, state),
    }
}

/// [`guard_energy`] of `start`, the state a step started from: with the elastic term that the
/// step's assembly summed at that state when it left one in `work.start_elastic` (taken), else
/// summed here.
pub fn guard_start_energy(model: &Model, start: &State, work: &mut Workspace) -> Energy {
    match work.start_elastic.take() {
        Some(elastic) => energy_with_elastic(model, start, elastic),
        None => guard_energy(model, start, work),
    }
}

/// With `work.warm_start` and a last step: the start of the solve in `cg[0]`. The velocity
/// change of a step is about `dt a`, and `a` changes smoothly between steps, so the guess is the
/// last step's `Δv` scaled by the ratio of the steps, extrapolated linearly over the two last
/// steps when they had this step's `dt`:
///
/// ```text
/// Δv_guess = 2 Δv_{n-1} - Δv_{n-2}      (dt_{n-1} = dt_{n-2} = dt)
/// Δv_guess = (dt / dt_{n-1}) Δv_{n-1}   (otherwise)
/// ```
/// where the `Δv` are in m/s. Only the start changes: the solve goes on to its tolerance.
fn warm_start(work: &mut Workspace, dt: f64) -> bool {
    let n = work.cg[0].len();
    if !(work.warm_start && work.last_dv.len() == n && work.last_dt > 0.0) {
        return false;
    }
    if work.last_dt == dt && work.before_dt == dt && work.before_dv.len() == n {
        for ((start, last), before) in work.cg[0]
            .iter_mut()
            .zip(&work.last_dv)
            .zip(&work.before_dv)
        {
            *start = 2.0 * *last - *before;
        }
        return true;
    }
    let scale = dt / work.last_dt;
    for (start, last) in work.cg[0].iter_mut().zip(&work.last_dv) {
        *start = scale * *last;
    }
    true
}

/// Keeps this step's `Δv` and `dt` (and the last step's) for the next warm start.
fn remember(
    work_last: (&mut Vec<DVec3>, &mut f64),
    work_before: (&mut Vec<DVec3>, &mut f64),
    dv: &[DVec3],
    dt: f64,
) {
    std::mem::swap(work_last.0, work_before.0);
    *work_before.1 = *work_last.1;
    work_last.0.clear();
    work_last.0.extend_from_slice(dv);
    *work_last.1 = dt;
}

/// The same step on a lattice (`implicit_lattice`): the same system, its blocks stored by
/// offset group and its products computed eight springs at a time.
fn step_lattice(
    stencil: &Stencil,
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    let warm = warm_start(work, dt);
    let Workspace {
        a: f,
        cg,
        last_solve,
        constraints,
        inside,
        account,
        dissipated,
        power_f,
        last_dv,
        last_dt,
        before_dv,
        before_dt,
        lattice,
        start_elastic,
        ..
    } = work;
    // f_n: with colliders from `forces` (the contact forces need the total), else summed by the
    // assembly itself.
    let given = if model.colliders.is_empty() {
        Forces::Springs {
            gravity: model.gravity,
        }
    } else {
        forces(model, &state.x, &state.v, f);
        Forces::Given(f)
    };
    lattice.assemble(
        stencil,
        &model.mass,
        &model.inv_mass,
        model.drag,
        dt,
        &state.x,
        &state.v,
        given,
    );
    *start_elastic = Some(lattice.start_elastic());
    let contacts = has_contacts(model, state);
    let dv = &mut cg[0];
    if warm && contacts {
        start_contacts(model, state, dt, dv, constraints, inside);
    } else {
        constraints.clear();
    }
    let mut stats = SolveStats::default();
    loop {
        let start = (warm && stats.passes == 0).then_some(&dv[..]);
        let (iterations, residual, converged) = lattice.solve(
            constraints,
            params.cg_tolerance,
            params.cg_max_iterations,
            stats.passes > 0,
            start,
        );
        lattice.copy_dv(dv);
        stats.record(iterations, residual, converged);
        if !converged || !contacts || stats.passes >= MAX_CONTACT_PASSES {
            break;
        }
        let released = release_pulling(constraints, |i| lattice.row_residual(i));
        if !(add_contacts(model, state, dt, dv, constraints, inside) || released) {
            break;
        }
    }
    stats.constrained = constraints.len() as u32;
    *last_solve = stats;
    if !constraints.is_empty() && (*account || constraints.iter().any(|c| c.sphere.is_some())) {
        // The constraint impulses (A Δv - b)·N and the spheres' reactions, as in the textbook
        // step.
        let impulse = |i| lattice.row_residual(i);
        let removed = contact_impulses(state, constraints, dv, impulse);
        if *account {
            dissipated.contacts += removed;
        }
    }
    remember((last_dv, last_dt), (before_dv, before_dt), dv, dt);
    // D_{n+1} = D_n + dt P(x_{n+1}, v_{n+1}), when accounting: the dampers' and the drag's power
    // from the update's pass, the colliders' contact forces (a pass of their own) where there
    // are colliders.
    let lattice_power = *account && model.colliders.is_empty();
    let dampers_and_drag = lattice.advance(
        stencil,
        dt,
        model.drag,
        lattice_power,
        &mut state.x,
        &mut state.v,
    );
    state.history_valid = false;
    let power = if lattice_power {
        Power {
            dampers_and_drag,
            contact: 0.0,
        }
    } else {
        power_one_part(*account, stencil, model, &state.x, &state.v, power_f)
    };
    dissipated.add_power(dt, power);
    1
}

/// [`power_if`]'s stencil pass in one part, on this thread. The lattice step's other passes
/// run on one core; one pool job per step for this pass alone cost more than it saved on a
/// loaded machine (waiting for a pre-empted worker: 0.13 s against 0.08 s for 3 s of
/// `cloth-spheres`). The sums are the same for any split (`Stencil::write_in_parts`).
fn power_one_part(
    account: bool,
    stencil: &Stencil,
    model: &Model,
    x: &[DVec3],
    v: &[DVec3],
    scratch: &mut PowerScratch,
) -> Power {
    if !account {
        return Power::default();
    }
    stencil_power(stencil, model, x, v, scratch, 1)
}

/// Adds or updates a constraint for every free particle that `x_n + dt (v_n + Δv)` puts inside
/// a collider (module docs): a constrained particle that still ends inside (a curved surface, or
/// another face of the terrain) gets the new normal and target. Returns whether anything
/// changed; keeps `constraints` sorted by particle. `inside` is scratch.
fn add_contacts(
    model: &Model,
    state: &State,
    dt: f64,
    dv: &[DVec3],
    constraints: &mut Vec<Constraint>,
    inside: &mut Vec<usize>,
) -> bool {
    // Deeper than this (m) counts as inside: rounding of a landing exactly on the surface is not.
    const DEPTH: f64 = 1e-12;
    let ends = sphere_ends(model, state, dt);
    // Without colliders, only the particles that the test of `nearest_contact` finds inside a
    // sphere, taken eight at a time first.
    let candidates: &mut dyn Iterator<Item = usize> = if model.colliders.is_empty() {
        let kernel = model.stencil().map_or_else(Kernel::best, Stencil::kernel);
        inside_spheres(kernel, &state.x, &state.v, dv, dt, &ends, inside);
        &mut inside.iter().copied()
    } else {
        &mut (0..state.x.len())
    };
    let mut changed = false;
    for i in candidates {
        if model.inv_mass[i] == 0.0 {
            continue;
        }
        let v = state.v[i] + dv[i];
        let x = state.x[i] + dt * v;
        let Some((contact, sphere)) =
            nearest_contact(model, &ends, x, true).filter(|(c, _)| c.phi < -DEPTH)
        else {
            continue;
        };
        // (v_n + Δv)·N - φ̃/dt is the normal velocity that ends on the surface.
        let target = v.dot(contact.normal) - contact.phi / dt;
        let constraint = Constraint {
            i,
            normal: contact.normal,
            dv_n: target - state.v[i].dot(contact.normal),
            sphere,
        };
        match constraints.binary_search_by_key(&i, |c| c.i) {
            Ok(k) => constraints[k] = constraint,
            Err(k) => constraints.insert(k, constraint),
        }
        changed = true;
    }
    changed
}

/// The contact set the first solve starts from, with the warm start `dv` (module docs, "Warm
/// start"): the last step's contacts re-aimed ([`carry_over`]) and, when the only things to touch
/// are spheres, the particles `dv` carries inside one ([`add_contacts`]; `inside` is scratch).
fn start_contacts(
    model: &Model,
    state: &State,
    dt: f64,
    dv: &[DVec3],
    constraints: &mut Vec<Constraint>,
    inside: &mut Vec<usize>,
) {
    carry_over(model, state, dt, dv, constraints);
    if model.colliders.is_empty() {
        add_contacts(model, state, dt, dv, constraints, inside);
    }
}

/// The last step's constraints as the first guess of this step's (with the warm start): each
/// constrained particle gets the contact nearest to where the warm start `dv` carries it
/// (collider or sphere, inside or not) and the normal velocity that lands it there. A guess that
/// pulls is released after the first solve ([`release_pulling`]); one that is missing is found
/// by [`add_contacts`].
fn carry_over(
    model: &Model,
    state: &State,
    dt: f64,
    dv: &[DVec3],
    constraints: &mut Vec<Constraint>,
) {
    let ends = sphere_ends(model, state, dt);
    constraints.retain_mut(|c| {
        let v = state.v[c.i] + dv[c.i];
        let x = state.x[c.i] + dt * v;
        let Some((contact, sphere)) = nearest_contact(model, &ends, x, false) else {
            return false;
        };
        *c = Constraint {
            i: c.i,
            normal: contact.normal,
            dv_n: v.dot(contact.normal) - contact.phi / dt - state.v[c.i].dot(contact.normal),
            sphere,
        };
        true
    });
}

/// Removes the constraints whose impulse `J_i = (A Δv - b)_i·N_i` (N·s; `impulse(i)` is
/// `(A Δv - b)_i`) is negative: a contact pushes, it never pulls a particle onto a surface it
/// would leave (the contact's complementarity condition, `J ≥ 0`). Returns whether any went.
fn release_pulling(constraints: &mut Vec<Constraint>, impulse: impl Fn(usize) -> DVec3) -> bool {
    let before = constraints.len();
    constraints.retain(|c| impulse(c.i).dot(c.normal) >= 0.0);
    constraints.len() != before
}

/// Where each sphere ends this step (`collide::advance_spheres`: gravity, then the move), and
/// its radius (m).
fn sphere_ends(model: &Model, state: &State, dt: f64) -> Vec<(DVec3, f64)> {
    state
        .spheres
        .iter()
        .map(|s| {
            let velocity = if s.kinematic {
                s.velocity
            } else {
                s.velocity + dt * model.gravity
            };
            (s.center + dt * velocity, s.radius)
        })
        .collect()
}

/// The contact with the smallest signed distance at `x` over the colliders and the spheres'
/// end positions `ends` (the sphere's index with it), if any; with `inside`, the spheres that
/// `x` is outside of are skipped (a test of the squared distance, no square root).
fn nearest_contact(
    model: &Model,
    ends: &[(DVec3, f64)],
    x: DVec3,
    inside: bool,
) -> Option<(Contact, Option<usize>)> {
    // The first of the smallest, colliders before spheres.
    let mut nearest: Option<(Contact, Option<usize>)> = None;
    let mut consider = |contact: Contact, sphere: Option<usize>| {
        if nearest.is_none_or(|(n, _)| contact.phi.total_cmp(&n.phi).is_lt()) {
            nearest = Some((contact, sphere));
        }
    };
    for c in &model.colliders {
        if let Some(contact) = c.contact(x) {
            consider(contact, None);
        }
    }
    for (k, &(center, radius)) in ends.iter().enumerate() {
        let d = x - center;
        let distance2 = d.length_squared();
        if (inside && distance2 >= radius * radius) || distance2 == 0.0 {
            continue;
        }
        let distance = distance2.sqrt();
        consider(
            Contact {
                phi: distance - radius,
                normal: d / distance,
            },
            Some(k),
        );
    }
    nearest
}

/// True when the step may need contact constraints: colliders or spheres.
fn has_contacts(model: &Model, state: &State) -> bool {
    !model.colliders.is_empty() || !state.spheres.is_empty()
}

/// The constraint impulses of a solve and what they did (module docs, "Contacts with
/// spheres"): `impulse(i)` is `(A Δv - b)_i` (N·s) of the constrained particle `i`; its part
/// along the normal, `J_i = (A Δv - b)_i·N_i`, acts on the particle, and `-J_i N_i` on the
/// dynamic sphere it touches (a kinematic one takes nothing):
///
/// ```text
/// V_s ← V_s - Σ_{i on s} J_i N_i / M_s
/// removed = -Σ_i J_i (v_n + Δv)_i·N_i  -  Σ_s ½ M_s (|V_s'|² - |V_s|²)
/// ```
/// where `V_s` (m/s) and `M_s` (kg) are the sphere's velocity and mass. Returns `removed` (J):
/// the energy the contacts inside the solve took out (the work of the impulses on the
/// particles and the spheres' change of kinetic energy, negated).
fn contact_impulses(
    state: &mut State,
    constraints: &[Constraint],
    dv: &[DVec3],
    impulse: impl Fn(usize) -> DVec3,
) -> f64 {
    let before: f64 = state.spheres.iter().map(sphere_kinetic).sum();
    let mut removed = 0.0;
    for c in constraints {
        let j = impulse(c.i).dot(c.normal);
        removed -= j * (state.v[c.i] + dv[c.i]).dot(c.normal);
        if let Some(s) = c.sphere.map(|k| &mut state.spheres[k])
            && !s.kinematic
        {
            s.velocity -= (j / s.mass) * c.normal;
        }
    }
    let after: f64 = state.spheres.iter().map(sphere_kinetic).sum();
    removed - (after - before)
}

/// A dynamic sphere's kinetic energy (J); a kinematic one's is not counted.
fn sphere_kinetic(s: &crate::physics::collide::DynamicSphere) -> f64 {
    if s.kinematic {
        0.0
    } else {
        0.5 * s.mass * s.velocity.length_squared()
    }
}

/// The assembled system `A Δv = b` of one step.
struct System<'a> {
    model: &'a Model,
    dt: f64,
    blocks: &'a [DMat3],
    diag_inv: &'a [DMat3],
    rhs: &'a [DVec3],
}

impl System<'_> {
    /// `out = A p`, pinned rows zero.
    fn apply(&self, p: &[DVec3], out: &mut [DVec3]) {
        let model = self.model;
        for (i, o) in out.iter_mut().enumerate() {
            *o = (model.mass[i] + self.dt * model.drag) * p[i];
        }
        for (s, block) in model.springs.iter().zip(self.blocks) {
            let (ia, ib) = (s.a as usize, s.b as usize);
            let y = *block * (p[ia] - p[ib]);
            out[ia] += y;
            out[ib] -= y;
        }
        for (i, o) in out.iter_mut().enumerate() {
            if model.inv_mass[i] == 0.0 {
                *o = DVec3::ZERO;
            }
        }
    }

    /// Preconditioned conjugate gradients on `A Δv = b` with pinned rows filtered and the
    /// constrained particles' normal components prescribed (Shewchuk §B3; Baraff & Witkin §5.3).
    /// Writes `Δv` into `cg[0]`; returns the iterations, the final relative residual and whether
    /// it reached the tolerance.
    fn solve(
        &self,
        constraints: &[Constraint],
        (tolerance, max_iterations): (f64, u32),
        cg: &mut [Vec<DVec3>; 4],
        warm: bool,
    ) -> (u32, f64, bool) {
        let n = self.rhs.len();
        let [dv, r, p, ap] = cg;
        // S: remove the constrained normal components (sorted by particle).
        let filter = |v: &mut [DVec3]| {
            for c in constraints {
                v[c.i] -= v[c.i].dot(c.normal) * c.normal;
            }
        };
        // Δv starts at z: the prescribed normal velocity changes, and elsewhere zero, or a
        // warm start (the previous pass's solution, which changed only near contacts, or the
        // last step's Δv). A warm start whose residual is not below |b| is dropped for zero.
        let mut warm = warm;
        let b_norm2 = loop {
            if !warm {
                dv.fill(DVec3::ZERO);
            }
            for c in constraints {
                let along = dv[c.i].dot(c.normal);
                dv[c.i] += (c.dv_n - along) * c.normal;
            }
            // r = S (b - A z), pinned rows zero.
            self.apply(dv, ap);
            let mut b_norm2 = 0.0;
            for i in 0..n {
                let b = if self.model.inv_mass[i] != 0.0 {
                    self.rhs[i]
                } else {
                    DVec3::ZERO
                };
                b_norm2 += b.length_squared();
                r[i] = if self.model.inv_mass[i] != 0.0 {
                    b - ap[i]
                } else {
                    DVec3::ZERO
                };
            }
            filter(r);
            if warm && r.iter().map(|r| r.length_squared()).sum::<f64>() >= b_norm2 {
                warm = false;
                continue;
            }
            break b_norm2;
        };
        if !b_norm2.is_finite() {
            return (0, f64::NAN, false);
        }
        // Relative to |b|, but never below the smallest normal number: a state so close to rest
        // that |b|² underflows has nothing left to solve for.
        let tol2 = (tolerance * tolerance * b_norm2).max(f64::MIN_POSITIVE);
        // z = S P⁻¹ r, stored in p as the first search direction.
        let mut rz = 0.0;
        for i in 0..n {
            p[i] = self.diag_inv[i] * r[i];
        }
        filter(p);
        for i in 0..n {
            rz += r[i].dot(p[i]);
        }
        let mut r_norm2: f64 = r.iter().map(|r| r.length_squared()).sum();
        let mut iterations = 0;
        while r_norm2 > tol2 && iterations < max_iterations {
            self.apply(p, ap);
            filter(ap);
            let p_ap: f64 = p.iter().zip(ap.iter()).map(|(p, q)| p.dot(*q)).sum();
            if p_ap.is_nan() || p_ap <= 0.0 {
                break;
            }
            let alpha = rz / p_ap;
            r_norm2 = 0.0;
            for i in 0..n {
                dv[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
                r_norm2 += r[i].length_squared();
            }
            // z = S P⁻¹ r
            for i in 0..n {
                ap[i] = self.diag_inv[i] * r[i];
            }
            filter(ap);
            let rz_new: f64 = r.iter().zip(ap.iter()).map(|(r, z)| r.dot(*z)).sum();
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                p[i] = ap[i] + beta * p[i];
            }
            iterations += 1;
        }
        let residual = if b_norm2 > 0.0 {
            (r_norm2 / b_norm2).sqrt()
        } else {
            0.0
        };
        let converged = r_norm2.is_finite() && r_norm2 <= tol2;
        (iterations, residual, converged)
    }
}

/// The outer product `u vᵀ`.
fn outer(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}
