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
//! starts, with the estimate; on a terminal a progress bar appears for anything that takes
//! more than a second ([`Progress`]), and Ctrl-C stops the run cleanly ([`interrupt`]).

use std::fmt;
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::{DMat3, DVec3};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::physics::constraints::Rod;
use crate::physics::{Method, MethodParams, Spring};
use crate::scene::Scene;

mod search;
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

/// Bytes per particle of implicit Euler's lattice solver (`physics::integrators::implicit_lattice`,
/// when it steps): 32 `f64` arrays (inverse diagonal blocks, mass, free flags, x, v, the
/// right-hand side and the five CG vectors, three components each) and three `DVec3` buffers
/// (forces, the warm start's Δv, the solve's result).
pub const IMPLICIT_PARTICLE_BYTES: f64 = (32 * 8 + 3 * size_of::<DVec3>()) as f64;

/// Bytes per spring of implicit Euler's lattice solver: its block (six `f64`) and
/// `dt² K (v_b - v_a)` (three `f64`) per spring slot.
pub const IMPLICIT_SPRING_BYTES: f64 = (9 * 8) as f64;

/// Bytes per spring of Verlet's rods (its projection list, [`Rod`]).
pub const ROD_BYTES: f64 = size_of::<Rod>() as f64;

/// Bytes per pixel while rendering: the frame being drawn and the frames queued for the encoder
/// (4 × RGBA each), the RGB copy, and the GIF encoder's RGBA copy and palette indices.
pub const PIXEL_BYTES: f64 = (4 * (2 + crate::render::export::QUEUE) + 3 + 4 + 1) as f64;

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

// ---------------------------------------------------------------------------------------------
// Numbers for messages.

/// A user's number echoed back: its shortest exact form (`0.25`, `1000`) between 10⁻⁴ and 10⁶,
/// else scientific (`1e300`, `1e-320`, `1e9`: never 301 digits).
#[must_use]
pub fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// An estimate: whole numbers below 10⁷ exactly, else three significant digits (`1.84e19`).
#[must_use]
pub fn approx(x: f64) -> String {
    if x.is_infinite() {
        return format!("{}more than 1e308", if x < 0.0 { "-" } else { "" });
    }
    if x.is_nan() {
        return "NaN".to_string();
    }
    if x.abs() < 1e7 && x.fract() == 0.0 {
        return format!("{x}");
    }
    if x.abs() < 1e7 && x.abs() >= 1e-3 {
        return format!("{}", (x * 1000.0).round() / 1000.0);
    }
    let s = format!("{x:.2e}");
    match s.split_once('e') {
        Some((mantissa, exponent)) => {
            let m = mantissa.trim_end_matches('0').trim_end_matches('.');
            format!("{m}e{exponent}")
        }
        None => s,
    }
}

/// Bytes in the largest unit that keeps a leading digit: `3.4 GB`, `512 kB`.
#[must_use]
pub fn bytes(b: f64) -> String {
    const UNITS: [&str; 5] = ["bytes", "kB", "MB", "GB", "TB"];
    let mut value = b;
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < UNITS.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{value:.0} {}", UNITS[0])
    } else if value >= 1000.0 {
        format!("{} {}", approx(value), UNITS[unit])
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// A duration in seconds as `40 s`, `12 min`, `3.2 h`, `1.2e280 years`.
#[must_use]
pub fn duration(seconds: f64) -> String {
    if !seconds.is_finite() {
        return "forever".to_string();
    }
    if seconds < 120.0 {
        format!("{} s", seconds.ceil().max(1.0))
    } else if seconds < 7200.0 {
        format!("{} min", (seconds / 60.0).round())
    } else if seconds < 3.0 * 86400.0 {
        format!("{:.1} h", seconds / 3600.0)
    } else if seconds < 3.0 * 31_557_600.0 {
        format!("{:.0} days", seconds / 86400.0)
    } else {
        format!("{} years", approx(seconds / 31_557_600.0))
    }
}

// ---------------------------------------------------------------------------------------------
// Work and memory of scenes.

/// Force evaluations (or their equivalent in work) of one step of `method` (module docs).
#[must_use]
pub fn evaluations_per_step(method: Method, params: &MethodParams) -> f64 {
    match method {
        Method::ExplicitEuler | Method::SemiImplicitEuler => 1.0,
        Method::Midpoint | Method::PredictorCorrector => 2.0,
        Method::Rk4 => 4.0,
        // One evaluation, the Jacobian blocks, and typically 10–20 CG iterations (measured:
        // 12–17 times a semi-implicit step on the rope, the cloth and the jelly).
        Method::ImplicitEuler => 20.0,
        Method::Verlet => 1.0 + f64::from(params.iterations),
        Method::Xpbd => f64::from(params.substeps.max(1)) * (1.0 + f64::from(params.iterations)),
    }
}

/// Updates of one step of `scene`, every body with its own method, or with `method` when given.
#[must_use]
pub fn updates_per_step(scene: &Scene, method: Option<Method>) -> f64 {
    scene
        .bodies
        .iter()
        .map(|b| {
            let m = method.unwrap_or(b.method);
            evaluations_per_step(m, &b.params)
                * (b.model.particle_count() as f64 + b.model.springs().len() as f64 + OVERHEAD)
        })
        .sum()
}

/// Bytes of `particles` particles and `springs` springs in memory while being stepped by the
/// `methods` one after another, with `copies` copies of the model and state (module docs).
#[must_use]
pub fn body_bytes(particles: f64, springs: f64, methods: &[Method], copies: f64) -> f64 {
    let verlet = methods.contains(&Method::Verlet);
    let implicit = methods.contains(&Method::ImplicitEuler);
    copies * (particles * PARTICLE_BYTES + springs * SPRING_BYTES)
        + particles * WORKSPACE_PARTICLE_BYTES
        + springs * (WORKSPACE_SPRING_BYTES + if verlet { ROD_BYTES } else { 0.0 })
        + if implicit {
            particles * IMPLICIT_PARTICLE_BYTES + springs * IMPLICIT_SPRING_BYTES
        } else {
            0.0
        }
}

/// Bytes of `scene` while being stepped, each body by its own method or by each of `methods`
/// in turn, with `copies` copies of the models and states, plus [`BASE_BYTES`].
#[must_use]
pub fn scene_bytes(scene: &Scene, methods: Option<&[Method]>, copies: f64) -> f64 {
    BASE_BYTES
        + scene
            .bodies
            .iter()
            .map(|b| {
                let own = [b.method];
                body_bytes(
                    b.model.particle_count() as f64,
                    b.model.springs().len() as f64,
                    methods.unwrap_or(&own),
                    copies,
                )
            })
            .sum::<f64>()
}

/// Particles and springs the built-in scene `name` builds from `params`, before it is built (so
/// that a scene over the memory budget is refused without being allocated); `None` for a scene
/// this table does not know. Exact when every spring kind is active (tested against the
/// builders in `tests/budget_memory.rs`), an upper bound otherwise:
///
/// ```text
/// rope        N = nodes                  S = nodes - 1             (ropes: twice)
/// cube        N = bodies · n³            S = bodies · (3n²(n-1) + 6n(n-1)² + 4(n-1)³ + 3n²(n-2))
/// cloth       N = n²                     S = 2n(n-1) + 2(n-1)² + 2n(n-2)
/// ```
/// where the cube's springs are struct (edges), shear (face and body diagonals) and bend (two
/// apart along an axis), and the cloth's the same in two dimensions.
#[must_use]
pub fn builtin_size(name: &str, params: &crate::scene::Params) -> Option<(f64, f64)> {
    let integer = |key: &str| {
        params
            .iter()
            .find(|(k, _)| *k == key)
            .and_then(|(_, v)| match v {
                crate::scene::Value::Integer(i) => Some(*i as f64),
                _ => None,
            })
    };
    match name {
        "oscillator" => Some((2.0, 1.0)),
        "rope" => integer("nodes").map(|n| (n, n - 1.0)),
        "ropes" => integer("nodes").map(|n| (2.0 * n, 2.0 * (n - 1.0))),
        "cube-plane" | "cube-tilted" | "cube-sphere" | "cube-bowl" | "jelly-bowl" => {
            let (bodies, n) = (integer("bodies")?, integer("n")?);
            let m = n - 1.0;
            let springs =
                3.0 * n * n * m + 6.0 * n * m * m + 4.0 * m * m * m + 3.0 * n * n * (n - 2.0);
            Some((bodies * n * n * n, bodies * springs))
        }
        "cloth-spheres" | "cloth-sphere" => {
            let n = integer("n")?;
            Some((
                n * n,
                2.0 * n * (n - 1.0) + 2.0 * (n - 1.0) * (n - 1.0) + 2.0 * n * (n - 2.0),
            ))
        }
        _ => None,
    }
}

/// The estimate of one run of `scene` for `steps` steps at `dt` (s) (`springlab run`).
#[must_use]
pub fn run(what: impl Into<String>, scene: &Scene, dt: f64, steps: f64) -> Estimate {
    let particles = scene.particle_count() as f64;
    Estimate {
        what: what.into(),
        steps,
        steps_detail: format!("{} s at dt = {} s", approx(steps * dt), short(dt)),
        runs: 1.0,
        particles,
        springs: scene.spring_count() as f64,
        work: steps * updates_per_step(scene, None),
        // The report's positions and velocities (2 × [f64; 3] per particle).
        memory: scene_bytes(scene, None, 1.0) + 48.0 * particles,
        ..Estimate::default()
    }
}

/// Steps of a run of `time` seconds at `dt` as the studies count them: `round(T/dt)`, at least 1.
#[must_use]
pub fn steps_for(time: f64, dt: f64) -> f64 {
    (time / dt).round().max(1.0)
}

/// The estimate of a convergence or work-precision study: every method at `levels` time steps
/// `dt, dt/2, …` for `time` seconds, `repeats` times each, and the RK4 reference at
/// `dt_min/16` and `dt_min/8` (counted even where an exact solution makes it unnecessary).
#[must_use]
pub fn convergence(
    what: impl Into<String>,
    scene: &Scene,
    methods: &[Method],
    time: f64,
    dt: f64,
    levels: u32,
    repeats: u32,
) -> Estimate {
    let dt_min = dt / 2f64.powi(levels.saturating_sub(1).min(2000) as i32);
    let reference = steps_for(time, dt_min / 16.0);
    let mut work =
        (reference + steps_for(time, dt_min / 8.0)) * updates_per_step(scene, Some(Method::Rk4));
    let mut runs = 2.0;
    for &m in methods {
        let per_step = updates_per_step(scene, Some(m));
        for level in 0..levels.min(2000) {
            let dt_level = dt / 2f64.powi(level as i32);
            work += f64::from(repeats.max(1)) * steps_for(time, dt_level) * per_step;
            runs += f64::from(repeats.max(1));
        }
    }
    let particles = scene.particle_count() as f64;
    Estimate {
        what: what.into(),
        steps: reference,
        steps_detail: format!(
            "the RK4 reference: {} s at dt = {} s, 1/16 of the smallest of {levels} time steps \
             from {} s",
            short(time),
            approx(dt_min / 16.0),
            short(dt)
        ),
        runs: if levels > 2000 { f64::INFINITY } else { runs },
        particles,
        springs: scene.spring_count() as f64,
        work: if levels > 2000 { f64::INFINITY } else { work },
        // The scene, its copy being run, and a few position lists.
        memory: scene_bytes(scene, Some(methods), 2.0) + 4.0 * 24.0 * particles,
        ..Estimate::default()
    }
}

/// An upper bound on the fastest angular frequency of `scene` (rad/s), by Gershgorin's theorem:
/// `ω² ≤ max_i (1/m_i) Σ_{springs at i} k (1 + [other end free])` over free particles `i`.
#[must_use]
pub fn omega_bound(scene: &Scene) -> f64 {
    let mut omega2: f64 = 0.0;
    for b in &scene.bodies {
        let model = &b.model;
        let mut sum = vec![0.0; model.particle_count()];
        for s in model.springs() {
            let (a, bb) = (s.a as usize, s.b as usize);
            let free = |i: usize| if model.inv_mass[i] > 0.0 { 1.0 } else { 0.0 };
            sum[a] += s.stiffness * (1.0 + free(bb));
            sum[bb] += s.stiffness * (1.0 + free(a));
        }
        for (i, k) in sum.iter().enumerate() {
            omega2 = omega2.max(model.inv_mass[i] * k);
        }
    }
    omega2.sqrt()
}

/// The theoretical stability limit `dt·ω` of `method` on the undamped oscillator, where there
/// is one (the study starts its search there, see `study::stability`).
fn theory_limit(method: Method) -> Option<f64> {
    match method {
        Method::SemiImplicitEuler | Method::Verlet => Some(2.0),
        Method::Rk4 => Some(8f64.sqrt()),
        Method::PredictorCorrector => Some(1.0),
        _ => None,
    }
}

/// The fewest steps of a stability probe (the study's divergence criterion; its growth
/// criterion, for conservative scenes like the oscillator, takes at least 10 000).
pub const STABILITY_MIN_STEPS: f64 = 100.0;

/// The estimate of a stability study over `horizon` seconds: per method one probe at
/// `dt·ω = 100` and about 13 near the theoretical limit (or `dt·ω = 1`), each
/// `max(⌈T/dt⌉, min_steps)` steps, with `ω` the Gershgorin bound of [`omega_bound`].
#[must_use]
pub fn stability(
    what: impl Into<String>,
    scene: &Scene,
    methods: &[Method],
    horizon: f64,
    min_steps: f64,
) -> Estimate {
    let omega = omega_bound(scene);
    let probe = |z: f64| (horizon * omega / z).ceil().max(min_steps);
    let mut work = 0.0;
    let mut runs = 0.0;
    for &m in methods {
        let z = theory_limit(m).unwrap_or(1.0);
        work += (probe(100.0) + 13.0 * probe(z)) * updates_per_step(scene, Some(m));
        runs += 14.0;
    }
    let floor = 0.01;
    Estimate {
        what: what.into(),
        steps: probe(floor),
        steps_detail: format!(
            "the smallest probe: {} s at dt·ω = {floor}, ω ≤ {} rad/s",
            short(horizon),
            approx(omega)
        ),
        runs,
        particles: scene.particle_count() as f64,
        springs: scene.spring_count() as f64,
        work,
        memory: scene_bytes(scene, Some(methods), 2.0),
        ..Estimate::default()
    }
}

/// Adds the drawing of `frames` frames of `width × height` pixels to `estimate`.
pub fn add_frames(estimate: &mut Estimate, frames: f64, width: u32, height: u32, detail: &str) {
    let pixels = f64::from(width) * f64::from(height);
    estimate.frame_pixels = pixels;
    estimate.total_pixels = frames * pixels;
    estimate.frames = frames;
    estimate.pixels_detail = detail.to_string();
    estimate.memory += pixels * PIXEL_BYTES;
    // Drawing costs about as much per pixel as an update (a fill, an encode).
    estimate.work += frames * pixels;
}

// ---------------------------------------------------------------------------------------------
// Ctrl-C.

/// Ctrl-C: a flag that the long loops check, so that they stop between steps and remove what
/// they had not finished writing.
pub mod interrupt {
    use super::{AtomicBool, Ordering};

    static INTERRUPTED: AtomicBool = AtomicBool::new(false);

    /// The run was stopped by Ctrl-C.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
    #[error("interrupted (Ctrl-C); unfinished outputs were removed")]
    pub struct Interrupted;

    /// What Ctrl-C does.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Mode {
        /// Set the flag; the command's loop stops at its next check and removes its unfinished
        /// outputs (`run`, `render`). A second Ctrl-C exits at once.
        Flag,
        /// Exit at once with status 130, saying so: for commands that write nothing before
        /// they finish (`study`, `bench`), whose runs cannot be stopped half-way.
        Exit,
    }

    /// Installs the handler (once; later calls do nothing).
    pub fn install(mode: Mode) {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            // Fails only when another handler is installed: then Ctrl-C keeps its default.
            let _ = ctrlc::set_handler(move || {
                if mode == Mode::Exit || INTERRUPTED.swap(true, Ordering::SeqCst) {
                    use std::io::{IsTerminal, Write};
                    let mut err = std::io::stderr();
                    // On a terminal, leave the line of the progress bar first.
                    let newline = if err.is_terminal() { "\n" } else { "" };
                    let _ = writeln!(err, "{newline}springlab: {Interrupted}");
                    std::process::exit(130);
                }
            });
        });
    }

    /// True once Ctrl-C was pressed.
    #[must_use]
    pub fn requested() -> bool {
        INTERRUPTED.load(Ordering::Relaxed)
    }

    /// `Err(Interrupted)` once Ctrl-C was pressed.
    ///
    /// # Errors
    /// [`Interrupted`] after Ctrl-C.
    pub fn check() -> Result<(), Interrupted> {
        if requested() {
            Err(Interrupted)
        } else {
            Ok(())
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Progress.

/// A progress bar on standard error that appears only on a terminal and only once the work has
/// taken a second; piped or redirected output stays free of it.
pub struct Progress {
    bar: ProgressBar,
    start: Instant,
    enabled: bool,
    shown: bool,
}

impl Progress {
    /// A bar of `len` units labelled `label`. On a terminal it appears after a second even
    /// when no unit is done by then (a study's first run can be long), and then redraws twice
    /// a second.
    #[must_use]
    pub fn new(len: u64, label: &str) -> Progress {
        let bar = ProgressBar::hidden();
        bar.set_length(len);
        if let Ok(style) =
            ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} elapsed {elapsed} eta {eta}")
        {
            bar.set_style(style);
        }
        bar.set_message(label.to_string());
        let enabled = std::io::stderr().is_terminal();
        if enabled {
            let later = bar.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_secs(1));
                if !later.is_finished() {
                    later.set_draw_target(ProgressDrawTarget::stderr());
                    later.enable_steady_tick(Duration::from_millis(500));
                }
            });
        }
        Progress {
            bar,
            start: Instant::now(),
            enabled,
            shown: false,
        }
    }

    fn reveal(&mut self) {
        if self.enabled && !self.shown && self.start.elapsed() >= Duration::from_secs(1) {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
        }
    }

    /// Sets the position.
    pub fn set(&mut self, position: u64) {
        self.bar.set_position(position);
        self.reveal();
    }

    /// Advances by `n`.
    pub fn inc(&mut self, n: u64) {
        self.bar.inc(n);
        self.reveal();
    }

    /// Changes the label.
    pub fn label(&mut self, label: String) {
        self.bar.set_message(label);
        self.reveal();
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if !self.bar.is_finished() {
            self.bar.finish_and_clear();
        }
    }
}

impl fmt::Debug for Progress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Progress")
            .field("enabled", &self.enabled)
            .field("shown", &self.shown)
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_echoed_briefly() {
        assert_eq!(short(1e300), "1e300");
        assert_eq!(short(1e-320), "1e-320");
        assert_eq!(short(-1e300), "-1e300");
        assert_eq!(short(0.015625), "0.015625");
        assert_eq!(short(10.0), "10");
        assert_eq!(short(1e9), "1e9");
        assert_eq!(short(f64::NAN), "NaN");
        assert_eq!(approx(18_446_744_073_709_551_615.0), "1.84e19");
        assert_eq!(approx(1e300), "1e300");
        assert_eq!(approx(4_999_995.0), "4999995");
        assert_eq!(approx(0.999_999_999_999_999_9), "1");
        assert_eq!(approx(f64::INFINITY), "more than 1e308");
        assert_eq!(bytes(3.7e9), "3.7 GB");
        assert_eq!(bytes(2.0 * 1024.0 * 1024.0 * 1024.0), "2.1 GB");
        assert_eq!(bytes(512.0), "512 bytes");
        assert_eq!(duration(30.2), "31 s");
        assert_eq!(duration(3600.0), "60 min");
        assert_eq!(duration(f64::INFINITY), "forever");
    }

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
