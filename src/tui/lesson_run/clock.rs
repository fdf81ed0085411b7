//! The run's clock: simulated time paid in whole steps of dt against the wall time the app
//! passes in, capped per frame, and the rates measured from it.

use std::time::Instant;

use super::{LessonRun, STEPS_PER_FRAME_RANGE};

/// Rolling measurements of the run against wall time (from the wall times passed to
/// [`LessonRun::tick`], so deterministic in tests).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Rates {
    wall: f64,
    simulated: f64,
    steps: u64,
    /// Simulated seconds per wall second over the last half second, where the time that waits
    /// in the accumulator for the next whole step (less than one step) counts as kept: the
    /// factor is the speed exactly while no time is dropped, and below it by the time dropped.
    real_time_factor: Option<f64>,
    /// Steps per wall second over the last half second.
    steps_per_second: Option<f64>,
}

impl Rates {
    pub(super) fn add(&mut self, wall: f64, simulated: f64, steps: u64) {
        self.wall += wall;
        self.simulated += simulated;
        self.steps += steps;
        if self.wall >= 0.5 {
            self.real_time_factor = Some(self.simulated / self.wall);
            self.steps_per_second = Some(self.steps as f64 / self.wall);
            self.wall = 0.0;
            self.simulated = 0.0;
            self.steps = 0;
        }
    }
}

impl LessonRun {
    /// The cap on steps per frame.
    #[must_use]
    pub fn max_steps_per_frame(&self) -> u64 {
        self.max_steps_per_frame
    }

    /// Sets the cap on steps per frame (clamped to [`STEPS_PER_FRAME_RANGE`]).
    pub fn set_max_steps_per_frame(&mut self, n: u64) {
        self.max_steps_per_frame = n.clamp(STEPS_PER_FRAME_RANGE.0, STEPS_PER_FRAME_RANGE.1);
    }

    /// Steps taken in the last frame.
    #[must_use]
    pub fn last_frame_steps(&self) -> u64 {
        self.last_frame_steps
    }

    /// Simulated time owed to the simulation (s).
    #[must_use]
    pub fn accumulator(&self) -> f64 {
        self.accumulator
    }

    /// Simulated seconds per wall second.
    #[must_use]
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Measured simulated seconds per wall second, once half a second of wall time ran.
    #[must_use]
    pub fn real_time_factor(&self) -> Option<f64> {
        self.rates.real_time_factor
    }

    /// Measured steps per wall second, once half a second of wall time ran.
    #[must_use]
    pub fn steps_per_second(&self) -> Option<f64> {
        self.rates.steps_per_second
    }

    /// Advances the simulation by `wall_dt` seconds of wall time; see [`LessonRun::tick_until`].
    pub fn tick(&mut self, wall_dt: f64) {
        self.tick_until(wall_dt, None);
    }

    /// Adds `wall_dt` (s) times the speed factor to the accumulator and takes as many steps of
    /// `dt` as fit, at most the cap on steps per frame, stopping early at `deadline` or at
    /// divergence. When it stops early the rest of the accumulator is dropped: the run falls
    /// behind real time rather than ever further behind. Does nothing while paused.
    pub fn tick_until(&mut self, wall_dt: f64, deadline: Option<Instant>) {
        if !self.running || self.sim.diverged.is_some() {
            self.running = false;
            self.accumulator = 0.0;
            return;
        }
        let wall_dt = if wall_dt.is_finite() && wall_dt > 0.0 {
            wall_dt
        } else {
            0.0
        };
        let owed_before = self.accumulator;
        self.accumulator += wall_dt * self.speed;
        let dt = self.sim.dt();
        // Whole steps that fit, with a billionth of a step of slack against rounding
        // (0.1 s at dt = 0.01 s is 10 steps, not 9.999...).
        let fit = (self.accumulator / dt + 1e-9).floor();
        let mut wanted = if fit >= self.max_steps_per_frame as f64 {
            self.max_steps_per_frame
        } else {
            fit as u64
        };
        let mut behind = fit > self.max_steps_per_frame as f64;
        let mut taken = 0;
        while taken < wanted {
            if self.step_once() {
                taken += 1;
                behind = true;
                break;
            }
            taken += 1;
            if let Some(deadline) = deadline
                && taken % 16 == 0
                && Instant::now() >= deadline
            {
                behind = true;
                wanted = taken;
            }
        }
        self.accumulator = if behind {
            0.0
        } else {
            (self.accumulator - taken as f64 * dt).max(0.0)
        };
        self.last_frame_steps = taken;
        self.version += 1;
        // Kept: the steps taken and what the accumulator still owes (dropped time is not).
        let kept = taken as f64 * dt + (self.accumulator - owed_before);
        self.rates.add(wall_dt, kept, taken);
        if self.follow {
            self.follow_bodies_after(taken as f64 * dt);
        }
    }
}
