//! Implicit Euler's warm start ([`Workspace::warm_start`], on in `Simulation`): the solve starts
//! from the last steps' `Δv` extrapolated, with the last step's contacts re-aimed, instead of
//! zero. Only the start changes: the solve goes on to its tolerance.

use glam::DVec3;

use crate::physics::integrators::Workspace;

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
pub(super) fn start(work: &mut Workspace, dt: f64) -> bool {
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
pub(super) fn remember(
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
