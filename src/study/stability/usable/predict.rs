//! The study's usable-dt search: predict from a fit of the residual, then check once.
//!
//! # Why not a bisection
//!
//! A run that passes the criterion cannot stop early: it must cover the whole horizon `H`, and
//! at a usable dt that is many steps (explicit Euler on the 1000-particle jelly: about 10⁵). A
//! bisection passes several times; this search passes once when its prediction holds.
//!
//! # The rule
//!
//! At small `dt` the residual of a method of order `p` falls like a power of `dt`:
//!
//! ```text
//! R(dt) = max_{t_n ≤ H} |E_n + D_n - E_0| ≈ C dt^q                           (J)
//! q     = min(q_fit, p),   q_fit = ln(R(dt_a) / R(dt_b)) / ln(dt_a / dt_b)
//! dt_u  = dt_b (a f |E_0| / R(dt_b))^(1/q)
//! ```
//! where
//! - `dt_a`: the scene limit (the confirmed stable dt), `dt_b = dt_a / 2` (s)
//! - `R(dt_a)`, `R(dt_b)`: measured by two **fit runs** over the whole horizon (they stop early
//!   only when they diverge or `|r|` passes [`FIT_CAP`] `|E_0|`, J)
//! - `p`: the method's declared order; `q_fit` above it is the steeper rise of the error near the
//!   stability limit, not the trend at small `dt` (so it is not used); below it, contacts and
//!   impacts (not smooth) lower the order (RK4 on the jelly: `q ≈ 3`)
//! - `a`: [`USABLE_AIM`], the share of the allowed residual `f |E_0|` aimed at, room for the
//!   fit's error (`f` = [`super::USABLE_FRACTION`])
//!
//! Then **one check run** at [`super::USABLE_MARGIN`] `dt_u` (stopped as soon as `|r|` passes
//! `f |E_0|`): when it passes, `dt_u` is reported; when it fails, `dt_u` is lowered by
//! [`super::USABLE_GRID`] = √2 and checked again (at most [`CHECK_ROUNDS`] times). A fit run
//! that already passes at the scene limit makes the scene limit the candidate. A prediction
//! more than [`MAX_FACTOR_DOWN`] below the scene limit is not checked: no usable dt (as the
//! lesson app's grid, which stops 1024 times below it). Implicit Euler and XPBD on the jelly,
//! whose own damping takes out about the whole energy at any dt probed, end there.
//!
//! Where the residual has a floor that does not fall with dt (an impact whose error is about
//! the allowed residual at every dt near the prediction) the checks step down by √2 until one
//! passes; a failing check stops where it fails, usually in the impact.
//!
//! So what the table guarantees: a run at 95 % of the printed usable dt, over the scene's
//! duration, kept `|E + D - E_0| ≤ f |E_0|` (that run is in the report); the printed dt
//! itself is the fit's prediction for a residual of `a f |E_0|`. `failed_above` is the smallest
//! dt whose run failed (a bracket from above).

use std::sync::atomic::AtomicBool;

use super::{UsableRun, usable_run_unless};
use crate::physics::Method;
use crate::scene::Scene;

/// The fit aims at this share of the allowed residual.
pub const USABLE_AIM: f64 = 0.8;
/// A fit run stops when `|r|` passes this many `|E_0|`; a fit run stopped early (or diverged)
/// gives no point of the fit, and the next halving is run.
pub const FIT_CAP: f64 = 10.0;
/// At most this many fit runs (the scene limit, then halvings) to find two finite residuals.
pub const FIT_RUNS: u32 = 4;
/// At most this many check runs.
pub const CHECK_ROUNDS: u32 = 6;
/// The fitted order is used down to this value.
pub const MIN_ORDER: f64 = 0.5;
/// No prediction lies more than this factor below the scene limit.
pub const MAX_FACTOR_DOWN: f64 = 1024.0;

/// A run of the search: `check` (stops at the allowed residual) or a fit run (stops at
/// [`FIT_CAP`]); the key of a run computed ahead.
pub type Key = (u64, bool);

/// What the search found.
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    /// The usable dt (s), if any.
    pub dt: Option<f64>,
    /// The order `q` of the prediction.
    pub order: Option<f64>,
    /// The smallest dt whose run failed (s).
    pub failed_above: Option<f64>,
}

/// One run of `scene` (module docs): a check when `check`, else a fit run.
#[must_use]
pub fn run_key(
    scene: &Scene,
    method: Method,
    (bits, check): Key,
    allowed: f64,
    e0: f64,
    cancel: &AtomicBool,
) -> Option<UsableRun> {
    let dt = f64::from_bits(bits);
    let stop = if check {
        allowed
    } else {
        FIT_CAP * e0.abs().max(allowed)
    };
    let mut r = usable_run_unless(scene, method, dt, scene.duration, allowed, stop, cancel)?;
    r.role = if check { "check" } else { "fit" };
    Some(r)
}

/// The search of the module docs from `start` (s, the scene limit) for a method of declared
/// order `order`; `run(key, next)` returns the run of `key` (`next`: the runs likely to follow,
/// for a caller that computes them ahead). `allowed` is `f |E_0|` (J).
pub fn predict_and_check(
    start: f64,
    order: u32,
    allowed: f64,
    run: &mut dyn FnMut(Key, &[Key]) -> UsableRun,
) -> Found {
    let nominal = f64::from(order.max(1));
    let aim = USABLE_AIM * allowed;
    let floor = start / MAX_FACTOR_DOWN;
    let mut failed_above: Option<f64> = None;
    // The fit: the scene limit, then halvings, until two finite residuals (or one passing).
    let mut last: Option<(f64, f64)> = None;
    let mut candidate = None;
    let mut used = None;
    let mut dt = start;
    for _ in 0..FIT_RUNS {
        let r = run((dt.to_bits(), false), &[((dt / 2.0).to_bits(), false)]);
        if r.passed {
            // Passing at the first dt: the scene limit is the candidate; passing later: the
            // fit between it and the failing one above (never above that one).
            let q = last.map_or(nominal, |(d, rr)| {
                fitted(d, rr, dt, r.residual_max, nominal)
            });
            candidate = Some(match last {
                None => dt,
                Some((above, _)) => predicted(dt, r.residual_max, aim, q).min(above),
            });
            used = Some(q);
            break;
        }
        lower(&mut failed_above, dt);
        if r.complete {
            if let Some((d, rr)) = last {
                let q = fitted(d, rr, dt, r.residual_max, nominal);
                candidate = Some(predicted(dt, r.residual_max, aim, q));
                used = Some(q);
                break;
            }
            last = Some((dt, r.residual_max));
        }
        dt /= 2.0;
    }
    let mut candidate = match (candidate, last) {
        (Some(c), _) => c,
        // One finite residual only: the declared order.
        (None, Some((d, rr))) => {
            used = Some(nominal);
            predicted(d, rr, aim, nominal)
        }
        (None, None) => dt,
    };
    if let Some(f) = failed_above {
        candidate = candidate.min(f);
    }
    for _ in 0..CHECK_ROUNDS {
        if candidate < floor {
            break;
        }
        let check = super::USABLE_MARGIN * candidate;
        let next = super::USABLE_MARGIN * (candidate / super::USABLE_GRID);
        let r = run((check.to_bits(), true), &[(next.to_bits(), true)]);
        if r.passed {
            return Found {
                dt: Some(candidate),
                order: used,
                failed_above,
            };
        }
        lower(&mut failed_above, check);
        candidate /= super::USABLE_GRID;
    }
    Found {
        dt: None,
        order: used,
        failed_above,
    }
}

/// `failed` becomes the smaller of itself and `dt`.
fn lower(failed: &mut Option<f64>, dt: f64) {
    *failed = Some(failed.map_or(dt, |f| f.min(dt)));
}

/// The order `q = min(q_fit, p)` from residuals `r_a` at `dt_a` and `r_b` at `dt_b < dt_a`,
/// at least [`MIN_ORDER`].
fn fitted(dt_a: f64, r_a: f64, dt_b: f64, r_b: f64, nominal: f64) -> f64 {
    let q = (r_a / r_b).ln() / (dt_a / dt_b).ln();
    if q.is_finite() {
        q.clamp(MIN_ORDER, nominal)
    } else if r_b <= 0.0 {
        nominal
    } else {
        MIN_ORDER
    }
}

/// `dt (aim / r)^(1/q)`; `dt` itself when `r` is zero.
fn predicted(dt: f64, r: f64, aim: f64, q: f64) -> f64 {
    if r > 0.0 {
        dt * (aim / r).powf(1.0 / q)
    } else {
        dt
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A method whose residual is exactly `C dt^q` (no run): the prediction lands where the
    /// law puts `a f |E_0|`, and one check passes.
    fn law(c: f64, q: f64, allowed: f64) -> impl FnMut(Key, &[Key]) -> UsableRun {
        move |(bits, check), _| {
            let dt = f64::from_bits(bits);
            let r = c * dt.powf(q);
            UsableRun {
                dt,
                steps: 1,
                passed: r <= allowed,
                residual_max: r,
                reason: (r > allowed).then(|| "residual".to_string()),
                complete: true,
                role: if check { "check" } else { "fit" },
            }
        }
    }

    #[test]
    fn a_power_law_is_predicted_and_checked_once() {
        let (c, q, allowed) = (290.0, 1.0, 0.01);
        let mut runs = Vec::new();
        let mut f = law(c, q, allowed);
        let found = predict_and_check(2e-3, 1, allowed, &mut |k, n| {
            let r = f(k, n);
            runs.push(r.clone());
            r
        });
        let expected = (USABLE_AIM * allowed / c).powf(1.0 / q);
        let dt = found.dt.expect("usable");
        assert!(
            (dt / expected - 1.0).abs() < 1e-12,
            "{dt} against {expected}"
        );
        // Two fit runs (2e-3, 1e-3), one check.
        assert_eq!(runs.len(), 3, "{runs:?}");
        assert_eq!(runs.iter().filter(|r| r.passed).count(), 1);
        assert_eq!(found.failed_above, Some(1e-3));
    }

    #[test]
    fn an_order_above_the_declared_one_is_not_trusted() {
        // The residual falls as dt³ but the method declares order 1: the prediction uses 1,
        // which lands lower (more cautious) than the law's own point.
        let (c, allowed) = (1e6, 0.01);
        let mut f = law(c, 3.0, allowed);
        let found = predict_and_check(1e-2, 1, allowed, &mut f);
        assert_eq!(found.order, Some(1.0));
        let at_law = (USABLE_AIM * allowed / c).powf(1.0 / 3.0);
        assert!(found.dt.expect("usable") < at_law);
    }

    #[test]
    fn passing_at_the_scene_limit_reports_it() {
        let mut f = law(1.0, 2.0, 0.01);
        let found = predict_and_check(1e-2, 2, 0.01, &mut f);
        assert_eq!(found.dt, Some(1e-2));
    }
}
