//! The confirmation run of the stability study (module docs of `stability`, "Confirmation"):
//! the whole scene at a `dt`, judged by its energy.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::DVec3;

use super::{
    CONFIRM_ENERGY_EVERY, CONFIRM_ENERGY_SCALES, CONFIRM_EXPLOSION_SCALES, CONFIRM_GROWTH,
    CONFIRM_HORIZONS, CONFIRM_MARGIN, CONFIRM_MAX_STEPS, CONFIRM_MIN_STEPS, CONFIRM_TOLERANCE,
    Confirmation, DT_OMEGA_FLOOR,
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
    let never = AtomicBool::new(false);
    confirm_unless(scene, method, dt, steps, scale, omega, &never)
        .unwrap_or_else(|| unreachable!("not cancelled"))
}

/// [`confirm_with_omega`], given up (`None`) soon after `cancel` becomes true: a run computed
/// ahead that the search no longer wants ([`crate::study::ahead`]).
pub(super) fn confirm_unless(
    scene: &Scene,
    method: Method,
    dt: f64,
    steps: u64,
    scale: f64,
    omega: f64,
    cancel: &AtomicBool,
) -> Option<Confirmation> {
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
        let mut looked = 0;
        while taken < steps {
            if taken >= looked + CANCEL_EVERY {
                looked = taken;
                if cancel.load(Ordering::Relaxed) {
                    return None;
                }
            }
            let k = match level {
                Some(_) if taken >= looked + CANCEL_EVERY => taken,
                Some(_) => next_check(taken, every, steps),
                None => (taken + CANCEL_EVERY).min(steps) - 1,
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
        Some(Confirmation {
            dt,
            dt_omega: dt * omega,
            steps: sim.steps,
            passed: reason.is_none(),
            reason,
            rise_max: allowed.map(|_| residual_max),
            rise_allowed: allowed,
        })
    }
}

/// A cancelled run stops within this many steps.
const CANCEL_EVERY: u64 = 64;

/// The first step index `k ≥ taken` (0-based) after which a run of `steps` steps that looks
/// every `every` steps looks: `k` a multiple of `every`, or the last step.
pub(super) fn next_check(taken: u64, every: u64, steps: u64) -> u64 {
    taken.next_multiple_of(every).min(steps - 1)
}

/// The next run once a bisection step leaves `[passed, failed]`: its midpoint, or, within
/// [`CONFIRM_TOLERANCE`], the check at [`CONFIRM_MARGIN`] of `passed` (the same operations as
/// [`below`] and the search, so the same bits: a run computed ahead is the one asked for).
fn after(passed: f64, failed: f64) -> f64 {
    if failed > passed * (1.0 + CONFIRM_TOLERANCE) {
        (passed * failed).sqrt()
    } else {
        CONFIRM_MARGIN * passed
    }
}

/// Below a failed `z`: lower it by 5 % three times, then halve, until a run passes (none below
/// the floor); then bisect to [`CONFIRM_TOLERANCE`]. `failed` ends as the smallest failing `z`.
/// `run(z, next)` confirms `z`; `next` lists the runs that may follow it, either verdict.
pub(super) fn below(run: &mut dyn FnMut(f64, &[f64]) -> bool, failed: &mut f64) -> Option<f64> {
    let mut tries = 0;
    let mut passed = loop {
        // 5 % steps first (contacts and large motions usually cost a few per cent), then halve.
        tries += 1;
        let z = if tries <= 3 {
            *failed * 0.95
        } else {
            *failed / 2.0
        };
        if z < DT_OMEGA_FLOOR {
            return None;
        }
        let lower = if tries < 3 { z * 0.95 } else { z / 2.0 };
        if run(z, &[lower, after(z, *failed)]) {
            break z;
        }
        *failed = z;
    };
    while *failed > passed * (1.0 + CONFIRM_TOLERANCE) {
        let z = (passed * *failed).sqrt();
        if run(z, &[after(z, *failed), after(passed, z)]) {
            passed = z;
        } else {
            *failed = z;
        }
    }
    Some(passed)
}
