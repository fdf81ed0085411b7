//! Implicit Euler's contacts inside the solve (Baraff & Witkin §5.3): a particle the solve would
//! carry into a collider or a sphere gets its velocity along the surface normal `N` prescribed,
//! so that the step ends on the surface, and the solve is repeated with that constraint (the
//! filter `S = I - N Nᵀ` on its rows); projecting it out after the step would squeeze its
//! springs and add energy. The contact set is an active set of at most [`MAX_CONTACT_PASSES`]
//! solves: add the particles a solve still carries inside, release those whose constraint
//! impulse `J_i = (A Δv - b)_i·N_i` (N·s) pulls (`J < 0`). A dynamic sphere gets the reaction
//! `-J_i N_i`.
//!
//! ```text
//! x̃      = x_n + dt (v_n + Δv)               where the unconstrained solve would end
//! φ̃, N   = signed distance and normal at x̃   (φ̃ < 0: inside)
//! u       = min((v_n + Δv)·N - φ̃/dt, V·N)     prescribed normal velocity v_{n+1}·N
//! Δv·N    = u - v_n·N                         x_{n+1} lands on the surface, or stays inside
//! (S A S) y = S (b - A z),   Δv = z + y       z: the prescribed parts, y ⊥ N
//! W       = J (v_{n+1} - V)·N ≤ 0              the work of the contact impulse J ≥ 0
//! ```
//! where `φ̃` is in m (against a sphere where it ends the step), `V` (m/s) the obstacle's velocity
//! at the end of the step (zero for a collider, a sphere's after gravity), `J` (N·s) the
//! constraint impulse and `W` (J) its work on the particle and the obstacle. The cap `V·N` is
//! Baraff & Witkin's inelastic contact (§5.3: the constrained particle moves with the
//! obstacle along `N`): landing on the surface may need a normal velocity faster than the
//! obstacle's (a particle that starts the step inside, a curved or moving surface that
//! overtakes it), and then `W > 0`, energy pushed in: before the cap −16.8 kJ over 2.5 s on
//! `jelly-bowl` at dt = 0.04 s. A capped particle ends the step inside by at most
//! `dt (u_land - V·N)`; the collision response after the step lifts it out and pays the climb
//! from kinetic energy (`collide`'s energy budget, Su, Sheth & Fedkiw 2013), so neither part
//! adds energy.

use glam::DVec3;

use super::Constraint;
use super::solve::{SolveStats, System};
use crate::physics::fast::implicit_constraint::SphereRows;
use crate::physics::collide::Contact;
use crate::physics::forces::Model;
use crate::physics::integrators::MethodParams;
use crate::physics::particles::State;
use crate::physics::stencil::{Kernel, Stencil};

use crate::physics::fast::implicit_lattice::inside_spheres;

/// At most this many solves per step that add contacts: the first without contact constraints,
/// each further one with the particles the previous solve carried into a collider (then up to
/// [`RELEASE_PASSES`] that only release).
pub const MAX_CONTACT_PASSES: u32 = 4;

/// After [`MAX_CONTACT_PASSES`], at most this many more solves that only release the
/// constraints that pull (`J < 0`): a pulling constraint kept to the end of the step does the
/// positive work `J (v_{n+1}·N)` with `J < 0` and `v_{n+1}·N < 0` — energy in (measured on
/// `jelly-bowl` at dt = 0.04 s with the landing cap: 3.2 kJ over 2.5 s).
pub(super) const RELEASE_PASSES: u32 = 2;

/// The scratch of the contact passes: the CG vectors (`Δv` ends in `cg[0]`), the contact set
/// and a list of particles.
pub(super) struct Scratch<'a> {
    pub(super) cg: &'a mut [Vec<DVec3>; 4],
    pub(super) constraints: &'a mut Vec<Constraint>,
    pub(super) inside: &'a mut Vec<usize>,
    pub(super) spheres: &'a mut SphereRows,
}

/// Each sphere's mass (kg) when it is dynamic, `None` when kinematic.
pub(super) fn dynamic(state: &State) -> impl ExactSizeIterator<Item = Option<f64>> + '_ {
    state.spheres.iter().map(|s| (!s.kinematic).then_some(s.mass))
}

/// Solves `system` with the contacts inside the solve (module docs): from the warm start's
/// contact set when `warm`, at most [`MAX_CONTACT_PASSES`] solves, releasing the constraints that
/// pull and prescribing the particles a solve carries into a collider. Returns how the solve
/// went and, when there were constraints and `account` or a sphere to push, the energy the
/// contacts removed (J; the spheres get the reactions).
pub(super) fn solve(
    system: &System,
    state: &mut State,
    params: &MethodParams,
    warm: bool,
    account: bool,
    scratch: Scratch,
) -> (SolveStats, Option<f64>) {
    let (model, dt) = (system.model, system.dt);
    let Scratch {
        cg,
        constraints,
        inside,
        spheres,
    } = scratch;
    let contacts = has_contacts(model, state);
    spheres.begin_step(dynamic(state), model.gravity, dt, warm);
    if warm && contacts {
        start_contacts(model, state, dt, &cg[0], constraints, inside, spheres);
    } else {
        constraints.clear();
    }
    let mut stats = SolveStats::default();
    loop {
        spheres.prepare(dynamic(state), constraints, |i| system.diag_inv[i]);
        // Later passes start from the previous pass's Δv (it changed only near contacts).
        let (iterations, residual, converged) = system.solve(
            constraints,
            (params.cg_tolerance, params.cg_max_iterations),
            cg,
            warm || stats.passes > 0,
            spheres,
        );
        stats.record(iterations, residual, converged);
        if !converged || !contacts {
            break;
        }
        // Release the constraints that pull; prescribe the particles this solve carries into
        // a collider (after the last pass: only release, module docs).
        let [dv, _, _, ap] = &mut *cg;
        let released = !constraints.is_empty() && {
            system.apply(dv, ap);
            release_pulling(constraints, |i| ap[i] - system.rhs[i])
        };
        if stats.passes >= MAX_CONTACT_PASSES {
            if released && stats.passes < MAX_CONTACT_PASSES + RELEASE_PASSES {
                continue;
            }
            break;
        }
        if !(add_contacts(model, state, dt, dv, constraints, inside, spheres) || released) {
            break;
        }
    }
    stats.constrained = constraints.len() as u32;
    spheres.remember(dt);
    let mut removed = None;
    if !constraints.is_empty() && (account || constraints.iter().any(|c| c.sphere.is_some())) {
        // The constraint impulses J = (A Δv - b)·N (N·s) do the work J (v_{n+1}·N) on the
        // particles; minus that is what the contacts inside the solve removed (J).
        let [dv, _, _, ap] = &mut *cg;
        system.apply(dv, ap);
        removed = Some(contact_impulses(
            state,
            constraints,
            dv,
            dt * model.gravity,
            |i| ap[i] - system.rhs[i],
        ));
    }
    (stats, removed)
}

/// Adds or updates a constraint for every free particle that `x_n + dt (v_n + Δv)` puts inside
/// a collider (module docs): a constrained particle that still ends inside (a curved surface, or
/// another face of the terrain) gets the new normal and target. Returns whether anything
/// changed; keeps `constraints` sorted by particle. `inside` is scratch.
pub(super) fn add_contacts(
    model: &Model,
    state: &State,
    dt: f64,
    dv: &[DVec3],
    constraints: &mut Vec<Constraint>,
    inside: &mut Vec<usize>,
    spheres: &SphereRows,
) -> bool {
    // Deeper than this (m) counts as inside: rounding of a landing exactly on the surface is not.
    const DEPTH: f64 = 1e-12;
    let ends = sphere_ends(state, dt, spheres);
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
        let obstacle = obstacle_velocity(state, sphere, spheres);
        let (target, capped) = landing(v, contact, obstacle, dt);
        let constraint = Constraint {
            i,
            normal: contact.normal,
            dv_n: prescribed(state, i, contact.normal, target, sphere, spheres),
            sphere,
        };
        match constraints.binary_search_by_key(&i, |c| c.i) {
            // Held at the obstacle's normal velocity already: it ends inside on purpose (the
            // response after the step lifts it out), not a reason for another solve.
            Ok(_) if capped => continue,
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
pub(super) fn start_contacts(
    model: &Model,
    state: &State,
    dt: f64,
    dv: &[DVec3],
    constraints: &mut Vec<Constraint>,
    inside: &mut Vec<usize>,
    spheres: &SphereRows,
) {
    carry_over(model, state, dt, dv, constraints, spheres);
    if model.colliders.is_empty() {
        add_contacts(model, state, dt, dv, constraints, inside, spheres);
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
    spheres: &SphereRows,
) {
    let ends = sphere_ends(state, dt, spheres);
    constraints.retain_mut(|c| {
        let v = state.v[c.i] + dv[c.i];
        let x = state.x[c.i] + dt * v;
        let Some((contact, sphere)) = nearest_contact(model, &ends, x, false) else {
            return false;
        };
        let obstacle = obstacle_velocity(state, sphere, spheres);
        let (target, _) = landing(v, contact, obstacle, dt);
        *c = Constraint {
            i: c.i,
            normal: contact.normal,
            dv_n: prescribed(state, c.i, contact.normal, target, sphere, spheres),
            sphere,
        };
        true
    });
}

/// Removes the constraints whose impulse `J_i = (A Δv - b)_i·N_i` (N·s; `impulse(i)` is
/// `(A Δv - b)_i`) is negative: a contact pushes, it never pulls a particle onto a surface it
/// would leave (the contact's complementarity condition, `J ≥ 0`). Returns whether any went.
pub(super) fn release_pulling(
    constraints: &mut Vec<Constraint>,
    impulse: impl Fn(usize) -> DVec3,
) -> bool {
    let before = constraints.len();
    constraints.retain(|c| impulse(c.i).dot(c.normal) >= 0.0);
    constraints.len() != before
}

/// The prescribed normal velocity (m/s) of a particle whose unconstrained step ends at
/// `v` (m/s) with `contact` there (module docs): the velocity that lands it on the surface,
/// `v·N - φ̃/dt`, but never faster away from the surface than the obstacle's own normal
/// velocity `V·N` (`obstacle`, m/s: zero for a collider). A target above `V·N` would have the
/// contact impulse `J ≥ 0` do positive work `J (v_{n+1} - V)·N` and push energy in (a particle
/// that starts the step inside, or that a curved or moving surface overtakes); the rest of the
/// way out is the collision response's projection after the step, paid from kinetic energy.
/// Returns the target and whether the cap set it.
fn landing(v: DVec3, contact: Contact, obstacle: DVec3, dt: f64) -> (f64, bool) {
    let land = v.dot(contact.normal) - contact.phi / dt;
    let cap = obstacle.dot(contact.normal);
    if land > cap { (cap, true) } else { (land, false) }
}

/// The velocity (m/s) of the obstacle a contact is with at the end of the step, for the cap of
/// [`landing`]: zero for a collider, a kinematic sphere's own, a dynamic sphere's `V + ΔV`
/// with the solve's current estimate of its change (`spheres`; `g dt` before it is in the
/// solve).
fn obstacle_velocity(state: &State, sphere: Option<usize>, spheres: &SphereRows) -> DVec3 {
    sphere.map_or(DVec3::ZERO, |k| state.spheres[k].velocity + spheres.dv[k])
}

/// The constraint's `dv_n` (m/s) for the prescribed normal velocity `target` (m/s) of particle
/// `i` along `normal`: `target - v_n·N`, less the part `ΔV·N` that a dynamic sphere's row
/// adds in the solve (`SphereRows::target`), so that the particle keeps the relative normal
/// velocity `target - (V + ΔV)·N` to the sphere whatever the solve makes of `ΔV`.
fn prescribed(
    state: &State,
    i: usize,
    normal: DVec3,
    target: f64,
    sphere: Option<usize>,
    spheres: &SphereRows,
) -> f64 {
    let tied = sphere.map_or(0.0, |k| spheres.dv[k].dot(normal));
    target - state.v[i].dot(normal) - tied
}

/// Where each sphere ends this step, `c + dt (V + ΔV)` (as `collide::advance_spheres` moves
/// it, with the solve's current estimate `ΔV` of its velocity change: `g dt` before any
/// reaction, zero for a kinematic sphere), and its radius (m).
fn sphere_ends(state: &State, dt: f64, spheres: &SphereRows) -> Vec<(DVec3, f64)> {
    state
        .spheres
        .iter()
        .zip(&spheres.dv)
        .map(|(s, dv)| (s.center + dt * (s.velocity + *dv), s.radius))
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
pub(super) fn has_contacts(model: &Model, state: &State) -> bool {
    !model.colliders.is_empty() || !state.spheres.is_empty()
}

/// The constraint impulses of a solve and what they did (module docs, "Contacts with
/// spheres"): `impulse(i)` is `(A Δv - b)_i` (N·s) of the constrained particle `i`; its part
/// along the normal, `J_i = (A Δv - b)_i·N_i`, acts on the particle, and `-J_i N_i` on the
/// dynamic sphere it touches (a kinematic one takes nothing), so momentum is kept exactly:
///
/// ```text
/// P_s  = Σ_{i on s} J_i N_i,    V_s' = V_s - P_s / M_s
/// removed = -Σ_i J_i (v_n + Δv)_i·N_i  +  Σ_s P_s·(V_s' + g dt)
/// ```
/// where `V_s` (m/s) and `M_s` (kg) are the sphere's velocity and mass and `g dt` (`fall`, m/s)
/// the velocity its weight adds after the solve (`collide::advance_spheres`), so that
/// `V_s' + g dt` is its velocity at the end of the step. Each impulse's work is judged at the
/// end-of-step velocity of the body it acts on, as backward Euler moves every body with it
/// (`J v_{n+1}` is the force `J/dt` times the step's displacement `dt v_{n+1}`): a sphere at rest
/// on the cloth, `P = M g dt`, does no work. With the particle tied to the sphere in the solve
/// (`(v_n + Δv)·N = (V' + g dt)·N + u`, `SphereRows`), `removed = -Σ_i J_i u_i ≥ 0`. Returns
/// `removed` (J): the energy the contacts inside the solve took out.
pub(super) fn contact_impulses(
    state: &mut State,
    constraints: &[Constraint],
    dv: &[DVec3],
    fall: DVec3,
    impulse: impl Fn(usize) -> DVec3,
) -> f64 {
    let before: Vec<DVec3> = state.spheres.iter().map(|s| s.velocity).collect();
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
    for (s, v) in state.spheres.iter().zip(before) {
        if !s.kinematic {
            removed += s.mass * (v - s.velocity).dot(s.velocity + fall);
        }
    }
    removed
}
