//! Detecting a run that has blown up.
//!
//! A step diverges when any position or velocity is not finite (NaN or ±∞) or when a particle's
//! speed squared exceeds `10^6` m²/s² (1000 m/s), the threshold of the NYCU course's
//! "System Unstable!" check. Divergence is a result, reported with the step and time; it is not
//! a crash.

use serde::Serialize;

use super::particles::State;

/// `|v|²` above this (m²/s²) counts as divergence.
pub const MAX_SPEED_SQUARED: f64 = 1.0e6;

/// Why a run stopped.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Divergence {
    /// The step (1-based count of steps taken) that produced the bad state.
    pub step: u64,
    /// Simulated time after that step (s).
    pub time: f64,
    /// Largest particle speed after that step (m/s); may be NaN or infinite.
    pub max_speed: f64,
    /// Human-readable cause.
    pub reason: String,
}

/// Largest speed (m/s) in `state`, or NaN if any velocity or position is not finite.
#[must_use]
pub fn max_speed(state: &State) -> f64 {
    let mut max_sq = 0.0f64;
    for (x, v) in state.x.iter().zip(&state.v) {
        let sq = v.length_squared();
        if !sq.is_finite() || !x.is_finite() {
            return f64::NAN;
        }
        max_sq = max_sq.max(sq);
    }
    max_sq.sqrt()
}

/// Checks `state` after `step` steps at `time`; `None` while it is healthy.
#[must_use]
pub fn check(state: &State, step: u64, time: f64) -> Option<Divergence> {
    let speed = max_speed(state);
    if speed.is_nan() {
        return Some(Divergence {
            step,
            time,
            max_speed: speed,
            reason: "a position or velocity is NaN or infinite".to_string(),
        });
    }
    if speed * speed > MAX_SPEED_SQUARED {
        return Some(Divergence {
            step,
            time,
            max_speed: speed,
            reason: format!("a particle's speed {speed:.4e} m/s exceeds 1000 m/s (|v|² > 10^6)"),
        });
    }
    None
}
