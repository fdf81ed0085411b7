//! Implicit Euler on a lattice: the same step as `newton_step`, reaching the fast engine's
//! solver (`crate::physics::fast::implicit_lattice`: each spring block stored by offset group as
//! four numbers, its products computed eight springs at a time, two passes per CG iteration),
//! with the same contacts and warm start; and the energy the `Simulation`'s energy guard
//! compares, summed on the lattice where there is one.

use glam::DVec3;

use super::contacts::{
    MAX_CONTACT_PASSES, RELEASE_PASSES, add_contacts, contact_impulses, dynamic, has_contacts,
    release_pulling, start_contacts,
};
use super::solve::SolveStats;
use crate::physics::energy::Power;
use crate::physics::energy::{Energy, energy, energy_with_elastic};
use crate::physics::forces::{Model, forces};
use crate::physics::integrators::{MethodParams, PowerScratch, Workspace, fused, stencil_power};
use crate::physics::particles::State;
use crate::physics::stencil::Stencil;

use crate::physics::fast::implicit_lattice::Forces;
pub(super) use crate::physics::fast::implicit_lattice::usable;

/// The energy of `state` (J) as [`crate::physics::energy`] sums it, with the springs' elastic
/// term summed on the lattice where there is one (eight springs at a time; equal to rounding).
/// `Simulation`'s energy guard compares two of these around every step.
pub fn guard_energy(model: &Model, state: &State, work: &mut Workspace) -> Energy {
    match fused(model, work.textbook) {
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

/// The same step on a lattice (`implicit_lattice`): the same system, its blocks stored by
/// offset group and its products computed eight springs at a time.
pub(super) fn step(
    stencil: &Stencil,
    model: &Model,
    state: &mut State,
    dt: f64,
    params: &MethodParams,
    work: &mut Workspace,
) -> u64 {
    let warm = super::warm::start(work, dt);
    let Workspace {
        a: f,
        cg,
        last_solve,
        constraints,
        inside,
        sphere_rows: spheres,
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
    spheres.begin_step(dynamic(state), model.gravity, dt, warm);
    if warm && contacts {
        start_contacts(model, state, dt, dv, constraints, inside, spheres);
    } else {
        constraints.clear();
    }
    let mut stats = SolveStats::default();
    loop {
        spheres.prepare(dynamic(state), constraints, |i| lattice.diag_inv_block(i));
        let start = (warm && stats.passes == 0).then_some(&dv[..]);
        let (iterations, residual, converged) = lattice.solve(
            constraints,
            params.cg_tolerance,
            params.cg_max_iterations,
            stats.passes > 0,
            start,
            spheres,
        );
        lattice.copy_dv(dv);
        stats.record(iterations, residual, converged);
        if !converged || !contacts {
            break;
        }
        let released = release_pulling(constraints, |i| lattice.row_residual(i));
        if stats.passes >= MAX_CONTACT_PASSES {
            // After the last pass only release (`contacts::RELEASE_PASSES`).
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
    *last_solve = stats;
    if !constraints.is_empty() && (*account || constraints.iter().any(|c| c.sphere.is_some())) {
        // The constraint impulses (A Δv - b)·N and the spheres' reactions, as in the textbook
        // step.
        let impulse = |i| lattice.row_residual(i);
        let removed = contact_impulses(state, constraints, dv, dt * model.gravity, impulse);
        if *account {
            dissipated.contacts += removed;
        }
    }
    super::warm::remember((last_dv, last_dt), (before_dv, before_dt), dv, dt);
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
