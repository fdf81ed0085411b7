//! The stiffest state along a run (module docs of `stability`, "Linear, scene, and the stiffest
//! state").

use glam::DVec3;

use super::{STIFFEST_SAMPLE_INTERVAL, StiffestState};
use crate::physics::State;
use crate::scene::Scene;
use crate::simulation::Simulation;
use crate::study::modes::{omega_max, omega_max_unbounded};
use crate::study::theory::{self, Spectrum};

/// The stiffest state of `scene` along a run of `horizon` seconds (s) with its own methods
/// and `dt` (module docs), for library callers: [`StiffestState`] with `ω_max` of the stiffest
/// body at the start as the reference of its `ratio`. `None` when no body has stiffness.
#[must_use]
pub fn stiffest(scene: &Scene, horizon: f64) -> Option<StiffestState> {
    let (body, omega) = scene
        .bodies
        .iter()
        .map(|b| omega_max(&b.model, &b.state).omega)
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .filter(|(_, w)| *w > 0.0 && w.is_finite())?;
    Some(stiffest_state(scene, horizon, (body, omega)).0)
}

/// The stiffest state of `scene` along a run of `horizon` seconds (module docs): the report,
/// the index of its body and the damped theory's spectrum there. `omega` (rad/s) is `ω_max` of
/// body `stiffest` at the start, the answer when no sample is stiffer.
pub(super) fn stiffest_state(
    scene: &Scene,
    horizon: f64,
    (stiffest, omega): (usize, f64),
) -> (StiffestState, usize, Spectrum) {
    let mut sim = Simulation::new(scene.clone());
    sim.set_accounting(false);
    let dt = scene.dt;
    let every = ((STIFFEST_SAMPLE_INTERVAL / dt).round() as u64).max(1);
    let steps = (horizon / dt).ceil() as u64;
    let mut warm: Vec<Vec<DVec3>> = vec![Vec::new(); scene.bodies.len()];
    // (ω_max, body, time, state) of the stiffest sample so far; the start counts.
    let mut best: Option<(f64, usize, f64, State)> = None;
    let mut samples = 0;
    let mut stopped = None;
    for k in 0..=steps {
        if k > 0
            && let Some(d) = sim.step()
        {
            stopped = Some(format!("diverged at t = {:.4e} s: {}", d.time, d.reason));
            break;
        }
        if k % every != 0 && k != steps {
            continue;
        }
        for (i, b) in sim.scene.bodies.iter().enumerate() {
            // The samples' ω_max alone: the Gershgorin bound is not reported here.
            let w = omega_max_unbounded(&b.model, &b.state, &mut warm[i]).omega;
            samples += 1;
            if w.is_finite() && best.as_ref().is_none_or(|(top, ..)| w > *top) {
                best = Some((w, i, sim.time(), b.state.clone()));
            }
        }
    }
    let (w, body, time, state) = match best {
        Some((w, body, time, state)) if w > omega => (w, body, time, state),
        // Never stiffer than at the start (or nothing finite): the start is the stiffest.
        _ => (omega, stiffest, 0.0, scene.bodies[stiffest].state.clone()),
    };
    let b = &scene.bodies[body];
    let spectrum = theory::spectrum(&b.model, &state, w);
    let report = StiffestState {
        method: b.method,
        dt,
        samples,
        time,
        omega_max: w,
        ratio: w / omega,
        theory_spectrum: spectrum.how.clone(),
        stopped,
    };
    (report, body, spectrum)
}
