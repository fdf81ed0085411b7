//! The estimates of each command: work and memory of scenes, a run, the convergence and
//! stability studies, frames drawn.

use super::{
    BASE_BYTES, Estimate, OVERHEAD, PARTICLE_BYTES, PIXEL_BYTES, SPRING_BYTES,
    WORKSPACE_PARTICLE_BYTES, WORKSPACE_SPRING_BYTES, approx, short,
};
use crate::physics::{Method, MethodParams};
use crate::scene::Scene;

/// Force evaluations (or their equivalent in work) of one step of `method` (its declaration).
#[must_use]
pub fn evaluations_per_step(method: Method, params: &MethodParams) -> f64 {
    (method.declaration().evaluations)(params)
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
/// `ω² ≤` the largest [`spring_gershgorin`](crate::study::modes::spring_gershgorin) of its bodies.
#[must_use]
pub fn omega_bound(scene: &Scene) -> f64 {
    scene
        .bodies
        .iter()
        .map(|b| crate::study::modes::spring_gershgorin(&b.model))
        .fold(0.0, f64::max)
        .sqrt()
}

/// The theoretical stability limit `dt·ω` of `method` on the undamped oscillator, where there
/// is one (the study starts its search there, see `study::stability`).
fn theory_limit(method: Method) -> Option<f64> {
    match method.declaration().oscillator {
        crate::physics::OscillatorLimit::Below(limit) => Some(limit),
        _ => None,
    }
}

/// The fewest steps of a stability probe (the study's divergence criterion; its growth
/// criterion, for conservative scenes like the oscillator, takes at least 10 000).
pub const STABILITY_MIN_STEPS: f64 = 100.0;

/// The estimate of a stability study over `horizon` seconds: per method one probe at
/// `dt·ω = 100` and about 13 near the theoretical limit (or `dt·ω = 1`), each
/// `max(⌈T/dt⌉, min_steps)` steps, with `ω` the Gershgorin bound of [`omega_bound`]; and the
/// run of the scene at its own dt that finds its stiffest state (`⌈T/dt⌉` steps, a sample of
/// `ω_max` every 5 ms counted as 50 power iterations over the springs).
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
    let own_steps = (horizon / scene.dt).ceil();
    let interval = crate::study::stability::STIFFEST_SAMPLE_INTERVAL;
    let samples = own_steps.min((horizon / interval).ceil()) + 1.0;
    work += own_steps * updates_per_step(scene, None)
        + samples * 50.0 * (scene.particle_count() + scene.spring_count()) as f64;
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
