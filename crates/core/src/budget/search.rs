//! Estimates of the commands that search over many runs: `study resolution` and `advise`
//! (see the studies `resolution` and `advise`).

use super::{BASE_BYTES, Estimate, Stepped, approx, scene_bytes, short, updates_per_step};
use crate::physics::Method;

/// The estimate of a command that makes the runs `(scene, method, steps)` one after another
/// (`study resolution`): steps of the longest, the sum of their work, the memory of the largest
/// scene with a copy being run.
#[must_use]
pub fn runs<S: Stepped>(what: impl Into<String>, runs: &[(&S, Method, f64)]) -> Estimate {
    let longest = runs
        .iter()
        .max_by(|a, b| a.2.total_cmp(&b.2))
        .map(|r| (r.0, r.2));
    let largest = |f: fn(&S) -> f64| runs.iter().map(|r| f(r.0)).fold(0.0, f64::max);
    Estimate {
        what: what.into(),
        steps: longest.map_or(0.0, |l| l.1),
        steps_detail: longest.map_or_else(String::new, |(scene, steps)| {
            format!(
                "the longest run: {} steps of {} particles",
                approx(steps),
                scene.particles()
            )
        }),
        runs: runs.len() as f64,
        particles: largest(S::particles),
        springs: largest(S::springs),
        work: runs
            .iter()
            .map(|(scene, m, steps)| steps * updates_per_step(*scene, Some(*m)))
            .sum(),
        memory: runs
            .iter()
            .map(|(scene, m, _)| scene_bytes(*scene, Some(&[*m]), 2.0))
            .fold(0.0, f64::max),
        ..Estimate::default()
    }
}

/// The estimate of `springlab advise` (see `study::advise`): an upper bound.
///
/// ```text
/// chain   = (2^(R+1) - 1) s_0 u_ref                    the reference: RK4, s_0 steps halved R times
/// search  = cap · 2^R s_0 u_ref                          the search stops at its cap
/// verify  = V · 2^R s_0 u_ref · (1 + 1/1.5)               a run and a confirmation at 1.5 dt
/// steps   = 2^R s_0 · u_ref / u_min                      a candidate cheaper than the reference
/// ```
/// where `u_ref` are the updates of an RK4 step of the reference model and `u_min` those of a
/// one-evaluation step of the smallest model.
#[must_use]
#[allow(clippy::too_many_arguments)]
pub fn advise<S: Stepped>(
    what: impl Into<String>,
    reference: &S,
    models: &[&S],
    time: f64,
    first_steps: f64,
    halvings: u32,
    cap: f64,
    verifications: f64,
    margin: f64,
    search_runs: f64,
) -> Estimate {
    let last = first_steps * 2f64.powi(halvings.min(60) as i32);
    let per_step = updates_per_step(reference, Some(Method::Rk4));
    let reference_run = last * per_step;
    let confirm = 1.0 / margin;
    let work = (2.0 * last - first_steps) * per_step
        + cap * reference_run
        + verifications * reference_run * (1.0 + confirm);
    let cheapest = models
        .iter()
        .map(|m| updates_per_step(*m, Some(Method::SemiImplicitEuler)))
        .fold(f64::INFINITY, f64::min);
    let steps = last * (per_step / cheapest).max(1.0);
    let largest = |f: fn(&S) -> f64| models.iter().map(|m| f(m)).fold(0.0, f64::max);
    Estimate {
        what: what.into(),
        steps,
        steps_detail: format!(
            "at most: the reference's {} s with RK4 at dt = {} s taken as one-evaluation steps \
             of the smallest model",
            short(time),
            approx(time / last)
        ),
        // At most: the chain, every model × method halved `MAX_HALVINGS` times, the checks.
        runs: f64::from(halvings + 1) + search_runs + verifications * 2.0,
        particles: largest(S::particles),
        springs: largest(S::springs),
        work,
        // Every model is built before the search (one model and state each) and one is run at
        // a time; the reference's snapshots are small.
        memory: BASE_BYTES
            + models
                .iter()
                .map(|m| scene_bytes(*m, None, 1.0) - BASE_BYTES)
                .sum::<f64>()
            + scene_bytes(reference, Some(&Method::ALL), 1.0)
            - BASE_BYTES,
        ..Estimate::default()
    }
}
