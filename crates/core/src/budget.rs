//! Budgets: what an input asks of the machine, estimated before any of it is done.
//!
//! Every `run`, `study`, `render` and `bench` first turns its inputs into an [`Estimate`] —
//! the steps of its longest run, particles, springs, memory, work and pixels — and refuses
//! when one of them is over its [`Limits`], naming the estimate, the limit and the override:
//!
//! ```text
//! springlab: run rope would take 1e300 steps (1 s at dt = 1e-300 s); at most 1e9 steps per run (use --force to run anyway)
//! ```
//!
//! # The estimates
//!
//! ```text
//! steps   = round(T / dt)                                    one run of T seconds at dt
//! work    = Σ_runs steps · Σ_bodies e(method) · (N + S + C)   "updates"
//! memory  = Σ_bodies  c · (N b_N + S b_S)  +  N w_N + S w_S(method)  +  pixels · b_px
//! seconds ≈ work / RATE
//! ```
//! where `N` is the number of particles and `S` of springs of a body, `e(method)` the force
//! evaluations a step of the method takes ([`evaluations_per_step`]: 1 for the Euler methods and
//! Verlet without projection, 2 for midpoint and the predictor–corrector, 4 for RK4, 20 for
//! implicit Euler's Newton step with its conjugate gradients, `1 + iterations` for Verlet,
//! `substeps · (1 + iterations)` for XPBD), `C` = [`OVERHEAD`] a fixed cost per evaluation, `c`
//! the copies of the model and state the command keeps (2 for the studies, which clone the scene
//! for every run), `b_N`, `b_S` the bytes of the model and the state per particle and per
//! spring, `w_N`, `w_S` those of the integrators' scratch buffers ([`Workspace`](crate::physics::Workspace)), and `b_px`
//! the bytes per pixel of a frame being drawn, queued and encoded. The byte counts are the sizes
//! of the real data structures (see [`PARTICLE_BYTES`], [`SPRING_BYTES`],
//! [`WORKSPACE_PARTICLE_BYTES`], [`WORKSPACE_SPRING_BYTES`]); `tests/budget_memory.rs` compares
//! them with the allocations measured while a scene is loaded and stepped by every method.
//! One update is one particle or spring visited by one force evaluation: about 5–10 ns on the
//! 2-core machine the README's timings come from, so [`RATE`] = 10⁸ updates/s is on the slow
//! side.
//!
//! # The limits ([`Limits::DEFAULT`])
//!
//! | quantity | limit | why |
//! |---|---|---|
//! | steps of one run | 10⁹ | 10⁹ steps of the 3-node rope take about a minute |
//! | work | 3.6·10¹¹ updates | about an hour at [`RATE`] |
//! | memory | 2 GiB | the largest built-in scene (`cube-plane` with 10 cubes of 40³) needs about 1.3 GB |
//! | pixels per frame | 3840 × 2160 | 4K; GIF quantisation of one 8192² frame takes about 30 s |
//! | pixels of a render | 10¹⁰ | about ten minutes of drawing and encoding |
//! | scene or lesson file | 16 MiB | checked before parsing; a 16 MiB scene file needs about 0.9 GB to parse |
//!
//! Every built-in scene, scene file in `scenes/`, lesson step and README example is far inside
//! them (`tests/budget.rs`). `--force` lifts them all ([`Limits::NONE`]); what cannot be
//! represented (image sides above 8192 pixels, particle indices above 2³²) stays refused.
//!
//! Work estimated at more than [`NOTICE_SECONDS`] is announced on standard error before it
//! starts, with the estimate (the command line adds a progress bar and Ctrl-C handling).
//!
//! The budget is a leaf: it reads scenes through [`Stepped`] (particles, springs, method per
//! body), which the scene module implements, and takes what the studies and the renderer know
//! (a frequency bound, bytes per pixel) as arguments. Its number formats are [`crate::format`]'s.

use glam::{DMat3, DVec3};

use crate::physics::Spring;

mod estimates;
mod search;

pub use crate::format::{approx, bytes, duration, short};
pub use estimates::{
    BodySize, STABILITY_MIN_STEPS, Stepped, add_frames, body_bytes, convergence,
    evaluations_per_step, run, scene_bytes, stability, steps_for, updates_per_step,
};
pub use search::{advise, runs};

/// Updates per second assumed when an estimate is turned into a time.
pub const RATE: f64 = 1e8;

/// Fixed cost of one force evaluation, in updates (the loop set-up, gravity, the divergence
/// check): what makes a 2-particle oscillator cost more than 3 updates a step.
pub const OVERHEAD: f64 = 8.0;

/// Estimated work above this many seconds at [`RATE`] is announced before it starts.
pub const NOTICE_SECONDS: f64 = 10.0;

/// Bytes per particle of the model and the state: positions, velocities and Verlet's previous
/// positions (3 × `DVec3`), mass and inverse mass (2 × `f64`), the stencil's scratch copy of
/// positions and velocities (6 × `f64`) and its share of the chunk table (1 byte).
pub const PARTICLE_BYTES: f64 = (3 * size_of::<DVec3>() + 2 * 8 + 6 * 8 + 1) as f64;

/// Bytes per spring of the model: the [`Spring`], its slot in the projection order (`u32`), and
/// its slot in the stencil form (rest length and presence flag, 2 × `f64`).
pub const SPRING_BYTES: f64 = (size_of::<Spring>() + 4 + 2 * 8) as f64;

/// Bytes per particle of the integrators' scratch buffers ([`Workspace`](crate::physics::Workspace)): 15 `DVec3` buffers
/// (acceleration, stage position and velocity, RK4's four slopes of each, four CG vectors) and
/// the implicit solver's diagonal blocks (`DMat3`). Every method sizes all of them.
pub const WORKSPACE_PARTICLE_BYTES: f64 = (15 * size_of::<DVec3>() + size_of::<DMat3>()) as f64;

/// Bytes per spring of the [`Workspace`](crate::physics::Workspace): the implicit solver's Jacobian blocks (`DMat3`) and
/// XPBD's multipliers (`f64`).
pub const WORKSPACE_SPRING_BYTES: f64 = (size_of::<DMat3>() + 8) as f64;

/// Bytes per byte of a scene file while it is parsed and built (the TOML reader's values with
/// their spans: measured 53 on a 16 MiB file of `[[particles]]`, 0.9 GB at the peak).
pub const PARSE_BYTES: f64 = 56.0;

/// Bytes of everything that does not grow with the input (the binary, the font, buffers).
pub const BASE_BYTES: f64 = 16.0 * 1024.0 * 1024.0;

/// The limits of [`Estimate::check`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Steps of one run.
    pub steps: f64,
    /// Updates over the whole command (see the module docs).
    pub work: f64,
    /// Bytes.
    pub memory: f64,
    /// Pixels of one frame.
    pub frame_pixels: f64,
    /// Pixels over all frames.
    pub total_pixels: f64,
    /// Bytes of a scene or lesson file.
    pub file_bytes: u64,
}

impl Limits {
    /// The limits of the module docs.
    pub const DEFAULT: Limits = Limits {
        steps: 1e9,
        work: 3.6e11,
        memory: 2.0 * 1024.0 * 1024.0 * 1024.0,
        frame_pixels: 3840.0 * 2160.0,
        total_pixels: 1e10,
        file_bytes: 16 * 1024 * 1024,
    };

    /// No limits (`--force`).
    pub const NONE: Limits = Limits {
        steps: f64::INFINITY,
        work: f64::INFINITY,
        memory: f64::INFINITY,
        frame_pixels: f64::INFINITY,
        total_pixels: f64::INFINITY,
        file_bytes: u64::MAX,
    };

    /// [`Limits::NONE`] when `force`, else [`Limits::DEFAULT`].
    #[must_use]
    pub fn forced(force: bool) -> Limits {
        if force { Limits::NONE } else { Limits::DEFAULT }
    }
}

impl Default for Limits {
    fn default() -> Limits {
        Limits::DEFAULT
    }
}

/// What one command is estimated to take.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    /// What is estimated, for messages (`run rope`, `study convergence oscillator`).
    pub what: String,
    /// Steps of the longest single run.
    pub steps: f64,
    /// How those steps come about, for messages (`1 s at dt = 1e-300 s`).
    pub steps_detail: String,
    /// Runs in all (studies run a scene many times).
    pub runs: f64,
    /// Particles of the scene.
    pub particles: f64,
    /// Springs of the scene.
    pub springs: f64,
    /// Updates over all runs.
    pub work: f64,
    /// Bytes at the peak.
    pub memory: f64,
    /// Pixels of one frame (0 when nothing is drawn).
    pub frame_pixels: f64,
    /// Pixels over all frames.
    pub total_pixels: f64,
    /// Frames drawn.
    pub frames: f64,
    /// How the frame size comes about (`--size 8192x8192`).
    pub pixels_detail: String,
}

/// An estimate over its limit.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BudgetError {
    /// Too many steps in one run.
    #[error(
        "{what} would take {} steps{}; at most {} steps per run{FORCE}",
        approx(*steps), paren(detail), approx(*limit)
    )]
    Steps {
        /// The command.
        what: String,
        /// The estimate.
        steps: f64,
        /// How it comes about.
        detail: String,
        /// The limit.
        limit: f64,
    },
    /// Too much memory.
    #[error(
        "{what} would need about {} of memory ({} particles, {} springs); at most {}{FORCE}",
        bytes(*memory), approx(*particles), approx(*springs), bytes(*limit)
    )]
    Memory {
        /// The command.
        what: String,
        /// The estimate (bytes).
        memory: f64,
        /// Particles.
        particles: f64,
        /// Springs.
        springs: f64,
        /// The limit (bytes).
        limit: f64,
    },
    /// Too much work.
    #[error(
        "{what} would take about {} particle and spring updates ({}, about {} at {} \
         updates/s); at most {} (about {}){FORCE}",
        approx(*work), runs_text(*runs), duration(*work / RATE), approx(RATE), approx(*limit),
        duration(*limit / RATE)
    )]
    Work {
        /// The command.
        what: String,
        /// The estimate (updates).
        work: f64,
        /// Runs.
        runs: f64,
        /// The limit (updates).
        limit: f64,
    },
    /// A frame too large.
    #[error(
        "{what}: {detail} is {} pixels per frame; at most {} (3840x2160){FORCE}",
        approx(*pixels), approx(*limit)
    )]
    FramePixels {
        /// The command.
        what: String,
        /// The size as given.
        detail: String,
        /// The estimate.
        pixels: f64,
        /// The limit.
        limit: f64,
    },
    /// Too many pixels over all frames.
    #[error(
        "{what} would draw {} pixels ({} frames of {detail}); at most {}{FORCE}",
        approx(*pixels), approx(*frames), approx(*limit)
    )]
    TotalPixels {
        /// The command.
        what: String,
        /// Frames.
        frames: f64,
        /// The size as given.
        detail: String,
        /// The estimate.
        pixels: f64,
        /// The limit.
        limit: f64,
    },
}

/// `x <= limit`, false for NaN (an estimate that is NaN is refused).
fn within(x: f64, limit: f64) -> bool {
    x.partial_cmp(&limit)
        .is_some_and(|o| o != std::cmp::Ordering::Greater)
}

const FORCE: &str = " (use --force to run anyway)";

fn runs_text(runs: f64) -> String {
    if runs == 1.0 {
        "1 run".to_string()
    } else {
        format!("{} runs", approx(runs))
    }
}

fn paren(detail: &str) -> String {
    if detail.is_empty() {
        String::new()
    } else {
        format!(" ({detail})")
    }
}

impl Estimate {
    /// An empty estimate for `what`.
    #[must_use]
    pub fn new(what: impl Into<String>) -> Estimate {
        Estimate {
            what: what.into(),
            ..Estimate::default()
        }
    }

    /// Estimated wall time (s) at [`RATE`].
    #[must_use]
    pub fn seconds(&self) -> f64 {
        self.work / RATE
    }

    /// Checks every quantity against `limits`: steps, memory, pixels, work, in that order.
    ///
    /// # Errors
    /// The first quantity over its limit.
    pub fn check(&self, limits: &Limits) -> Result<(), BudgetError> {
        if !within(self.steps, limits.steps) {
            return Err(BudgetError::Steps {
                what: self.what.clone(),
                steps: self.steps,
                detail: self.steps_detail.clone(),
                limit: limits.steps,
            });
        }
        if !within(self.memory, limits.memory) {
            return Err(BudgetError::Memory {
                what: self.what.clone(),
                memory: self.memory,
                particles: self.particles,
                springs: self.springs,
                limit: limits.memory,
            });
        }
        if !within(self.frame_pixels, limits.frame_pixels) {
            return Err(BudgetError::FramePixels {
                what: self.what.clone(),
                detail: self.pixels_detail.clone(),
                pixels: self.frame_pixels,
                limit: limits.frame_pixels,
            });
        }
        if !within(self.total_pixels, limits.total_pixels) {
            return Err(BudgetError::TotalPixels {
                what: self.what.clone(),
                frames: self.frames,
                detail: self.pixels_detail.clone(),
                pixels: self.total_pixels,
                limit: limits.total_pixels,
            });
        }
        if !within(self.work, limits.work) {
            return Err(BudgetError::Work {
                what: self.what.clone(),
                work: self.work,
                runs: self.runs,
                limit: limits.work,
            });
        }
        Ok(())
    }

    /// The line announcing a long command, when it is estimated at more than
    /// [`NOTICE_SECONDS`]: `study stability rope: about 2.1e10 updates (…), about 4 min at …`.
    #[must_use]
    pub fn notice(&self) -> Option<String> {
        (self.seconds() > NOTICE_SECONDS).then(|| {
            format!(
                "{}: about {} particle and spring updates ({}, {} particles, {} springs, \
                 about {} of memory): about {} at {} updates/s; Ctrl-C stops it",
                self.what,
                approx(self.work),
                runs_text(self.runs),
                approx(self.particles),
                approx(self.springs),
                bytes(self.memory),
                duration(self.seconds()),
                approx(RATE)
            )
        })
    }

    /// [`Estimate::check`], then [`Estimate::notice`] on standard error.
    ///
    /// # Errors
    /// As [`Estimate::check`].
    pub fn enforce(&self, limits: &Limits) -> Result<(), BudgetError> {
        self.check(limits)?;
        if let Some(line) = self.notice() {
            use std::io::Write;
            // A closed standard error is no reason to stop.
            let _ = writeln!(std::io::stderr(), "springlab: {line}");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_quantity_over_its_limit_is_refused() {
        let mut e = Estimate::new("run x");
        e.steps = 10.0;
        e.work = 100.0;
        assert!(e.check(&Limits::DEFAULT).is_ok());
        e.steps = f64::NAN;
        assert!(matches!(
            e.check(&Limits::DEFAULT),
            Err(BudgetError::Steps { .. })
        ));
        assert!(
            e.check(&Limits::NONE).is_err(),
            "NaN is never within a limit"
        );
        e.steps = 2e9;
        assert!(e.check(&Limits::NONE).is_ok());
        let err = e.check(&Limits::DEFAULT).unwrap_err().to_string();
        assert_eq!(
            err,
            "run x would take 2e9 steps; at most 1e9 steps per run (use --force to run anyway)"
        );
    }
}
