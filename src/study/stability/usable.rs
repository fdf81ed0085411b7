//! The usable time step (issue 26): stable is not the same as right. Near its stability limit a
//! method can stay bounded while it creates about the whole scene's energy in high-frequency
//! ringing that the dampers then absorb; a student who takes the scene limit as "the dt to use"
//! gets a motion that is not to be trusted. The usable dt is the largest step whose energy error
//! stays a small fraction of the scene's energy.
//!
//! # The criterion
//!
//! With the energy accounting of [`crate::simulation`] (dampers, drag, contacts and what the
//! collision response removes, each measured with the method's own stages), the method's own
//! energy error after `n` steps is the residual
//!
//! ```text
//! r_n = E_n + D_n - E_0                                           (J)
//! usable at dt  ⇔  max_{t_n ≤ H} |r_n| ≤ f |E_0|   and the run does not diverge
//! ```
//! where
//! - `E_n`: the total energy (kinetic + gravitational + elastic) after step `n` (J)
//! - `D_n`: the energy taken out by dampers, drag and contacts up to step `n` (J)
//! - `E_0`: the energy at the start (J); when it is zero, the energy scale `S` of the
//!   confirmation (`super::energy_scale`) stands in for `|E_0|`
//! - `H`: the scene's own duration (s), the run a student makes
//! - `f`: [`USABLE_FRACTION`] = 1 %
//!
//! The residual is checked every step on scenes under 2 000 springs, every
//! [`super::CONFIRM_ENERGY_EVERY`] steps on larger ones (and after the last); a run that can no
//! longer pass stops.
//!
//! # Two searches
//!
//! A run that passes cannot stop early: it covers the whole horizon, and at a usable dt that is
//! many steps. So the number of passing runs is the cost.
//!
//! - **The study** (`springlab study stability`, [`usable`]) fits the residual's power law in
//!   `dt` to two runs at the scene limit and half of it, predicts the usable dt from it and
//!   checks the prediction with one run at 95 % of it ([`predict`]): one passing run when the
//!   prediction holds.
//! - **The lesson app's status line** ([`search`], bounded by its own budget) searches without
//!   a model: `|r|` is not monotone in `dt` (a resonance can spoil one step and spare a larger
//!   one), so a bisection on the criterion alone could stop anywhere. The rule:
//!   1. start at the scene limit (the confirmed stable dt; for a method stable at every dt
//!      probed, the largest dt probed) and go down a geometric grid of ratio √2
//!      ([`USABLE_GRID`]) until a run passes, at most [`USABLE_MAX_STEPS_DOWN`] grid points
//!      (a factor 2¹⁰ = 1024): none passing → no usable dt;
//!   2. bisect (geometric mean) between that point and the failing grid point above it until
//!      they are within [`USABLE_TOLERANCE`] = 5 % of each other;
//!   3. verify at [`USABLE_MARGIN`] = 0.95 of the result: when that run fails, start again at
//!      step 1 from below it (at most [`USABLE_ROUNDS`] times, then no usable dt).
//!
//!   So the reported dt and 95 % of it both passed.
//!
//! Both report every run they made.
//!
//! References: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! Springer 2006, §I.1 and §IX (energy error of non-symplectic and symplectic methods);
//! T. Schlick, M. Mandziuk, R. D. Skeel, K. Srinivas, J. Comput. Phys. 140 (1998) (nonlinear
//! resonances: why the error is not monotone in dt).

use serde::Serialize;

use std::sync::atomic::{AtomicBool, Ordering};

use super::CONFIRM_ENERGY_EVERY;
use crate::physics::Method;
use crate::scene::Scene;
use crate::simulation::Simulation;
use crate::study::ahead::with_helpers_when;

pub mod predict;

/// The fraction `f` of `|E_0|` the residual may reach.
pub const USABLE_FRACTION: f64 = 0.01;
/// The ratio between the grid points of the downward search.
pub const USABLE_GRID: f64 = std::f64::consts::SQRT_2;
/// At most this many grid points below the start.
pub const USABLE_MAX_STEPS_DOWN: u32 = 20;
/// The bisection stops within this relative width.
pub const USABLE_TOLERANCE: f64 = 0.05;
/// The result must also pass at this fraction of itself.
pub const USABLE_MARGIN: f64 = 0.95;
/// Searched again at most this many times when the margin fails.
pub const USABLE_ROUNDS: u32 = 3;

/// One run of the usable-dt search.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UsableRun {
    /// Time step (s).
    pub dt: f64,
    /// Steps taken (fewer than planned when it failed early).
    pub steps: u64,
    /// The verdict.
    pub passed: bool,
    /// The largest `|E + D - E_0|` seen (J).
    pub residual_max: f64,
    /// Why it failed, or null.
    pub reason: Option<String>,
    /// Whether it ran to the horizon (a run stopped early gives a lower bound of the residual).
    pub complete: bool,
    /// `fit` (runs on past the allowed residual, for the fit of [`predict`]), `check` (stops
    /// there), or `grid` (the lesson app's search, [`search`]).
    pub role: &'static str,
}

/// The usable dt of one method, from the study's search ([`predict`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Usable {
    /// The dt the fit predicts for a residual of `aim · fraction · |E_0|`, checked: a run at
    /// 95 % of it stayed within `fraction` of `|E_0|` over `horizon` (s); null when none was
    /// found.
    pub dt: Option<f64>,
    /// The order `q` of the prediction (`min` of the fitted and the declared order).
    pub order: Option<f64>,
    /// The share of the allowed residual the prediction aims at ([`predict::USABLE_AIM`]).
    pub aim: f64,
    /// The smallest dt whose run failed (s): the usable dt lies below it.
    pub failed_above: Option<f64>,
    /// The horizon `H` of every run (s): the scene's duration.
    pub horizon: f64,
    /// The fraction `f`.
    pub fraction: f64,
    /// The allowed `|E + D - E_0|` (J): `f |E_0|` (or `f S` when `E_0 = 0`).
    pub allowed: f64,
    /// Every run, in the order taken.
    pub runs: Vec<UsableRun>,
}

/// The residual allowed on `scene`: `f |E_0|`, or `f S` when `E_0` is zero (J).
#[must_use]
pub fn allowed_residual(scene: &Scene, scale: f64) -> f64 {
    let e0 = Simulation::new(scene.clone()).energy_initial().abs();
    USABLE_FRACTION * if e0 > 0.0 { e0 } else { scale }
}

/// One run of `scene` with `method` at `dt` (s) over `horizon` (s), stopped at the first
/// `|residual| > allowed` (J) or divergence.
#[must_use]
pub fn usable_run(scene: &Scene, method: Method, dt: f64, horizon: f64, allowed: f64) -> UsableRun {
    let never = AtomicBool::new(false);
    usable_run_unless(scene, method, dt, horizon, allowed, allowed, &never)
        .unwrap_or_else(|| unreachable!("not cancelled"))
}

/// One run as [`usable_run`] that stops at the first `|residual| > stop` (J, at least
/// `allowed`) or divergence, given up (`None`) soon after `cancel` becomes true: a run computed
/// ahead that the search no longer wants ([`crate::study::ahead`]). It passes when it did not
/// diverge and its residual stayed within `allowed`.
#[must_use]
pub fn usable_run_unless(
    scene: &Scene,
    method: Method,
    dt: f64,
    horizon: f64,
    allowed: f64,
    stop: f64,
    cancel: &AtomicBool,
) -> Option<UsableRun> {
    let mut scene = scene.clone();
    scene.set_method(method);
    let mut sim = Simulation::new(scene);
    sim.set_dt(dt);
    sim.set_accounting(true);
    let steps = ((horizon / dt).round() as u64).max(1);
    let every = if sim.scene.spring_count() < 2_000 {
        1
    } else {
        CONFIRM_ENERGY_EVERY
    };
    let mut residual_max = 0.0f64;
    let mut reason = None;
    let mut stopped = false;
    // The steps between two looks at the residual go to `Simulation::advance` (the fused
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
        let k = super::confirm::next_check(taken, every, steps);
        sim.advance(k + 1 - taken);
        taken = k + 1;
        if let Some(d) = &sim.diverged {
            reason = Some(format!("diverged at t = {:.4e} s: {}", d.time, d.reason));
            stopped = true;
            break;
        }
        let r = sim.energy_residual();
        if r.is_nan() {
            reason = Some(format!(
                "E + D - E0 is not a number at t = {:.4e} s",
                sim.time()
            ));
            residual_max = f64::NAN;
            stopped = true;
            break;
        }
        if r.abs() > allowed && reason.is_none() {
            reason = Some(format!(
                "|E + D - E0| = {:.4e} J > {allowed:.4e} J at t = {:.4e} s",
                r.abs(),
                sim.time()
            ));
        }
        residual_max = residual_max.max(r.abs());
        if r.abs() > stop {
            stopped = true;
            break;
        }
    }
    Some(UsableRun {
        dt,
        steps: sim.steps,
        passed: reason.is_none(),
        residual_max,
        reason,
        complete: !stopped,
        role: "grid",
    })
}

/// A cancelled run stops within this many steps.
const CANCEL_EVERY: u64 = 64;

/// The next run of the bisection after `[passed, failed]`: its midpoint, or the check at 95 %
/// once they are within the tolerance (the same operations as [`search`], so the same bits).
fn after(passed: f64, failed: f64) -> f64 {
    if failed > passed * (1.0 + USABLE_TOLERANCE) {
        (passed * failed).sqrt()
    } else {
        USABLE_MARGIN * passed
    }
}

/// The search of the module docs from `start` (s) down, with `run(dt, next)` the verdict of
/// one run; `next` lists the runs that may follow it (whichever its verdict), for a caller that
/// computes them ahead. Returns the usable dt, if any.
pub fn search(start: f64, run: &mut dyn FnMut(f64, &[f64]) -> bool) -> Option<f64> {
    let mut top = start;
    // A failing dt above the grid's first point, when known.
    let mut failed: Option<f64> = None;
    for _ in 0..USABLE_ROUNDS {
        let (mut passed, above) = down(top, failed, run)?;
        if let Some(mut f) = above {
            while f > passed * (1.0 + USABLE_TOLERANCE) {
                let m = (passed * f).sqrt();
                if run(m, &[after(m, f), after(passed, m)]) {
                    passed = m;
                } else {
                    f = m;
                }
            }
        }
        let check = USABLE_MARGIN * passed;
        if run(check, &[check / USABLE_GRID]) {
            return Some(passed);
        }
        failed = Some(check);
        top = check / USABLE_GRID;
    }
    None
}

/// Step 1: the first passing point of the grid `top, top/√2, …`; with the failing point above
/// it (`failed` when the first point passes).
fn down(
    top: f64,
    failed: Option<f64>,
    run: &mut dyn FnMut(f64, &[f64]) -> bool,
) -> Option<(f64, Option<f64>)> {
    let mut above = failed;
    let mut dt = top;
    for _ in 0..=USABLE_MAX_STEPS_DOWN {
        // Most grid points fail (and stop early): the next two are the likely next runs.
        let next = dt / USABLE_GRID;
        let passes = run(dt, &[next, next / USABLE_GRID]);
        if passes {
            return Some((dt, above));
        }
        above = Some(dt);
        dt = next;
    }
    None
}

/// The usable dt of `method` on `scene` by the study's search ([`predict`]), from `start` (s,
/// the scene limit) down.
#[must_use]
pub fn usable(scene: &Scene, method: Method, start: f64, scale: f64) -> Usable {
    usable_ahead(scene, method, start, scale, 0, &|| false)
}

/// [`usable`] with `helpers` threads computing its likely next runs ahead while `idle()` says
/// a core is free ([`crate::study::ahead`]): the same runs, verdicts and result.
#[must_use]
pub fn usable_ahead(
    scene: &Scene,
    method: Method,
    start: f64,
    scale: f64,
    helpers: usize,
    idle: &(dyn Fn() -> bool + Sync),
) -> Usable {
    let horizon = scene.duration;
    let allowed = allowed_residual(scene, scale);
    let e0 = allowed / USABLE_FRACTION;
    let mut runs = Vec::new();
    let compute = |key: &predict::Key, cancel: &AtomicBool| {
        predict::run_key(scene, method, *key, allowed, e0, cancel)
    };
    let found = with_helpers_when(helpers, &compute, idle, |ahead| {
        predict::predict_and_check(
            start,
            method.declaration().order,
            allowed,
            &mut |key, next| {
                ahead.hint(next.to_vec());
                let r = ahead.get(&key);
                runs.push(r.clone());
                r
            },
        )
    });
    Usable {
        dt: found.dt,
        order: found.order,
        aim: predict::USABLE_AIM,
        failed_above: found.failed_above,
        horizon,
        fraction: USABLE_FRACTION,
        allowed,
        runs,
    }
}
