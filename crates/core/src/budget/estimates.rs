//! The estimates of each command: work and memory of scenes, a run, the convergence and
//! stability studies, frames drawn.
//!
//! The estimates read a scene through [`Stepped`] (its bodies' sizes, methods and time step),
//! which the scene module implements: the budget knows numbers, not scenes.

use super::{
    BASE_BYTES, Estimate, OVERHEAD, PARTICLE_BYTES, SPRING_BYTES, WORKSPACE_PARTICLE_BYTES,
    WORKSPACE_SPRING_BYTES, approx, short,
};
use crate::physics::{Method, MethodParams, OscillatorLimit};

/// One body as the estimates see it: its size and how it is stepped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodySize {
    /// Particles.
    pub particles: f64,
    /// Springs.
    pub springs: f64,
    /// The method that steps it.
    pub method: Method,
    /// The method's settings.
    pub params: MethodParams,
}

/// What is stepped: the bodies of a scene and its own time step.
pub trait Stepped {
    /// Every body's size, method and settings.
    fn bodies(&self) -> Vec<BodySize>;
    /// The scene's own time step (s).
    fn dt(&self) -> f64;
    /// Particles over all bodies.
    fn particles(&self) -> f64 {
        self.bodies().iter().map(|b| b.particles).sum()
    }
    /// Springs over all bodies.
    fn springs(&self) -> f64 {
        self.bodies().iter().map(|b| b.springs).sum()
    }
}

/// Force evaluations (or their equivalent in work) of one step of `method` (its declaration).
#[must_use]
pub fn evaluations_per_step(method: Method, params: &MethodParams) -> f64 {
    (method.declaration().evaluations)(params)
}

/// Updates of one step of `scene`, every body with its own method, or with `method` when given.
#[must_use]
pub fn updates_per_step(scene: &(impl Stepped + ?Sized), method: Option<Method>) -> f64 {
    scene
        .bodies()
        .iter()
        .map(|b| {
            let m = method.unwrap_or(b.method);
            evaluations_per_step(m, &b.params) * (b.particles + b.springs + OVERHEAD)
        })
        .sum()
}

/// Bytes of `particles` particles and `springs` springs in memory while being stepped by the
/// `methods` one after another, with `copies` copies of the model and state (module docs).
#[must_use]
pub fn body_bytes(particles: f64, springs: f64, methods: &[Method], copies: f64) -> f64 {
    // Each method's own scratch once, however often it appears in `methods`.
    let own: f64 = Method::ALL
        .iter()
        .filter(|m| methods.contains(m))
        .map(|m| {
            let s = m.declaration().scratch;
            particles * s.particle + springs * s.spring
        })
        .sum();
    copies * (particles * PARTICLE_BYTES + springs * SPRING_BYTES)
        + particles * WORKSPACE_PARTICLE_BYTES
        + springs * WORKSPACE_SPRING_BYTES
        + own
}

/// Bytes of `scene` while being stepped, each body by its own method or by each of `methods`
/// in turn, with `copies` copies of the models and states, plus [`BASE_BYTES`].
#[must_use]
pub fn scene_bytes(
    scene: &(impl Stepped + ?Sized),
    methods: Option<&[Method]>,
    copies: f64,
) -> f64 {
    BASE_BYTES
        + scene
            .bodies()
            .iter()
            .map(|b| {
                let own = [b.method];
                body_bytes(b.particles, b.springs, methods.unwrap_or(&own), copies)
            })
            .sum::<f64>()
}

/// The estimate of one run of `scene` for `steps` steps at `dt` (s) (`springlab run`).
#[must_use]
pub fn run(
    what: impl Into<String>,
    scene: &(impl Stepped + ?Sized),
    dt: f64,
    steps: f64,
) -> Estimate {
    let particles = scene.particles();
    Estimate {
        what: what.into(),
        steps,
        steps_detail: format!("{} s at dt = {} s", approx(steps * dt), short(dt)),
        runs: 1.0,
        particles,
        springs: scene.springs(),
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
    scene: &(impl Stepped + ?Sized),
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
    let particles = scene.particles();
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
        springs: scene.springs(),
        work: if levels > 2000 { f64::INFINITY } else { work },
        // The scene, its copy being run, and a few position lists.
        memory: scene_bytes(scene, Some(methods), 2.0) + 4.0 * 24.0 * particles,
        ..Estimate::default()
    }
}

/// The theoretical stability limit `dt·ω` of `method` on the undamped oscillator, where there
/// is one (the study starts its search there, see `study::stability`).
fn theory_limit(method: Method) -> Option<f64> {
    match method.declaration().oscillator {
        OscillatorLimit::Below(limit) => Some(limit),
        _ => None,
    }
}

/// The fewest steps of a stability probe (the study's divergence criterion; its growth
/// criterion, for conservative scenes like the oscillator, takes at least 10 000).
pub const STABILITY_MIN_STEPS: f64 = 100.0;

/// The estimate of a stability study over `horizon` seconds: per method one probe at
/// `dt·ω = 100` and about 13 near the theoretical limit (or `dt·ω = 1`), each
/// `max(⌈T/dt⌉, min_steps)` steps, with `ω` = `omega` (rad/s) an upper bound on the scene's
/// fastest angular frequency (the study's Gershgorin bound); and the run of the scene at its own
/// dt that finds its stiffest state (`⌈T/dt⌉` steps, a sample of `ω_max` every
/// `sample_interval` seconds counted as 50 power iterations over the springs).
#[must_use]
pub fn stability(
    what: impl Into<String>,
    scene: &(impl Stepped + ?Sized),
    methods: &[Method],
    horizon: f64,
    min_steps: f64,
    omega: f64,
    sample_interval: f64,
) -> Estimate {
    let probe = |z: f64| (horizon * omega / z).ceil().max(min_steps);
    let mut work = 0.0;
    let mut runs = 0.0;
    for &m in methods {
        let z = theory_limit(m).unwrap_or(1.0);
        work += (probe(100.0) + 13.0 * probe(z)) * updates_per_step(scene, Some(m));
        runs += 14.0;
    }
    let own_steps = (horizon / scene.dt()).ceil();
    let samples = own_steps.min((horizon / sample_interval).ceil()) + 1.0;
    let (particles, springs) = (scene.particles(), scene.springs());
    work += own_steps * updates_per_step(scene, None) + samples * 50.0 * (particles + springs);
    runs += 1.0;
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
        particles,
        springs,
        work,
        memory: scene_bytes(scene, Some(methods), 2.0),
        ..Estimate::default()
    }
}

/// Adds the drawing of `frames` frames of `width × height` pixels to `estimate`, each pixel
/// taking `pixel_bytes` bytes while it is drawn, queued and encoded.
pub fn add_frames(
    estimate: &mut Estimate,
    frames: f64,
    (width, height): (u32, u32),
    pixel_bytes: f64,
    detail: &str,
) {
    let pixels = f64::from(width) * f64::from(height);
    estimate.frame_pixels = pixels;
    estimate.total_pixels = frames * pixels;
    estimate.frames = frames;
    estimate.pixels_detail = detail.to_string();
    estimate.memory += pixels * pixel_bytes;
    // Drawing costs about as much per pixel as an update (a fill, an encode).
    estimate.work += frames * pixels;
}
