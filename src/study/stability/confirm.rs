//! The confirmation run of the stability study (module docs of `stability`, "Confirmation"):
//! the whole scene at a `dt`, judged by its energy.

use glam::DVec3;

use super::{
    CONFIRM_ENERGY_EVERY, CONFIRM_ENERGY_SCALES, CONFIRM_EXPLOSION_SCALES, CONFIRM_GROWTH,
    CONFIRM_HORIZONS, CONFIRM_MAX_STEPS, CONFIRM_MIN_STEPS, Confirmation,
};
use crate::physics::Method;
use crate::scene::Scene;
use crate::simulation::Simulation;
use crate::study::modes::omega_max;

/// One confirmation run (module docs): `scene` with `method` at `dt` (s) for
/// `min(⌈50 horizon/dt⌉, 20 000)` steps (at least 100), judged against the energy scale `scale`
/// (J, [`energy_scale`]). Library callers can use it to check a `dt` of their own.
#[must_use]
pub fn confirm_run(
    scene: &Scene,
    method: Method,
    dt: f64,
    horizon: f64,
    scale: f64,
) -> Confirmation {
    confirm_steps(scene, method, dt, confirm_step_count(dt, horizon), scale)
}

/// `min(⌈50 horizon/dt⌉, 20 000)` steps, at least 100.
pub(super) fn confirm_step_count(dt: f64, horizon: f64) -> u64 {
    ((CONFIRM_HORIZONS * horizon / dt).ceil() as u64).clamp(CONFIRM_MIN_STEPS, CONFIRM_MAX_STEPS)
}

/// [`confirm_run`] for a given number of steps; `dt_omega` uses the stiffest body's `ω_max`
/// ([`omega_max`]).
#[must_use]
pub fn confirm_steps(
    scene: &Scene,
    method: Method,
    dt: f64,
    steps: u64,
    scale: f64,
) -> Confirmation {
    let omega = scene
        .bodies
        .iter()
        .map(|b| omega_max(&b.model, &b.state).omega)
        .filter(|w| w.is_finite())
        .fold(0.0, f64::max);
    confirm_with_omega(scene, method, dt, steps, scale, omega)
}

/// [`confirm_steps`] with `ω_max` (rad/s) already known.
pub(super) fn confirm_with_omega(
    scene: &Scene,
    method: Method,
    dt: f64,
    steps: u64,
    scale: f64,
    omega: f64,
) -> Confirmation {
    {
        let mut scene = scene.clone();
        scene.set_method(method);
        let driven = scene.bodies.iter().any(|b| {
            b.state
                .spheres
                .iter()
                .any(|s| s.kinematic && s.velocity != DVec3::ZERO)
        });
        let mut sim = Simulation::new(scene);
        sim.set_dt(dt);
        sim.set_accounting(false);
        let e0 = sim.energy().total;
        let level = (!driven && scale > 0.0).then_some(CONFIRM_ENERGY_SCALES * scale);
        // Every step on small scenes (a sampled oscillating energy would alias), every 10 on
        // large ones, where the energy is a noticeable share of a step's cost.
        let every = if sim.scene.spring_count() < 2_000 {
            1
        } else {
            CONFIRM_ENERGY_EVERY
        };
        let explosion = CONFIRM_EXPLOSION_SCALES * scale;
        // The largest and the smallest rise E - E_0 of each quarter of the run.
        let mut quarters = [f64::NEG_INFINITY; 4];
        let mut lowest = [f64::INFINITY; 4];
        let mut reason = None;
        // The steps between two looks at the energy go to `Simulation::advance` (the fused
        // multi-step path where the scene allows it; the same bits as one step at a time).
        let mut taken = 0;
        while taken < steps {
            let k = match level {
                Some(_) => next_check(taken, every, steps),
                None => steps - 1,
            };
            sim.advance(k + 1 - taken);
            taken = k + 1;
            if let Some(d) = &sim.diverged {
                reason = Some(format!("diverged at t = {:.4e} s: {}", d.time, d.reason));
                break;
            }
            if level.is_some() {
                let r = sim.energy().total - e0;
                let q = (4 * k / steps) as usize;
                quarters[q] = quarters[q].max(r);
                lowest[q] = lowest[q].min(r);
                if r.is_nan() || r > explosion {
                    reason = Some(format!(
                        "energy rose {r:.4e} J above its start, more than {explosion:.4e} J \
                         (10⁴ S), at t = {:.4e} s",
                        sim.time()
                    ));
                    break;
                }
            }
        }
        let residual_max = quarters.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if reason.is_none()
            && let Some(level) = level
        {
            if quarters[3] > level && quarters[3] > CONFIRM_GROWTH * quarters[1] {
                reason = Some(format!(
                    "energy still rising: {:.4e} J above its start in the last quarter of the \
                     run, {:.4e} J in the second, above {level:.4e} J (10 S)",
                    quarters[3], quarters[1]
                ));
            } else if lowest[3] > level {
                reason = Some(format!(
                    "energy pumped up: never below {:.4e} J above its start in the last quarter \
                     of the run, more than {level:.4e} J (10 S)",
                    lowest[3]
                ));
            }
        }
        let allowed = level;
        Confirmation {
            dt,
            dt_omega: dt * omega,
            steps: sim.steps,
            passed: reason.is_none(),
            reason,
            rise_max: allowed.map(|_| residual_max),
            rise_allowed: allowed,
        }
    }
}

/// The first step index `k ≥ taken` (0-based) after which a run of `steps` steps that looks
/// every `every` steps looks: `k` a multiple of `every`, or the last step.
pub(super) fn next_check(taken: u64, every: u64, steps: u64) -> u64 {
    taken.next_multiple_of(every).min(steps - 1)
}
