//! Convergence order and work-precision: how the error of each method shrinks with `dt`, and
//! what each accuracy costs.
//!
//! # Theory
//!
//! A method of order `p` has a global error at a fixed time `T` that shrinks like `dt^p`:
//!
//! ```text
//! e(dt) = |x_dt(T) - x(T)|_max ≈ C dt^p
//! log e = log C + p log dt                      a straight line of slope p in log-log axes
//! p     ≈ least-squares slope of (log dt_i, log e_i)
//! ```
//! where `x_dt(T)` are the positions (m) computed with step `dt` (s), `x(T)` the reference and the
//! norm is the largest distance over the particles (m).
//!
//! **The reference.** Where the scene has an exact solution it is used:
//! - the `oscillator`, damped or not: `x_1(t) = L0 + u(t)` along x, `u` the damped harmonic
//!   motion from rest (see [`damped_oscillator`]);
//! - free fall (no springs, no colliders, no drag): `x(t) = x_0 + v_0 t + ½ g t²`.
//!
//! Otherwise the reference is RK4 at `dt_ref = dt_min / 16`, whose own error is estimated by
//! Richardson extrapolation from a second run at `2 dt_ref`:
//!
//! ```text
//! e_ref ≈ |x_{dt_ref}(T) - x_{2 dt_ref}(T)| / (2⁴ - 1)
//! ```
//! Points whose error is below `10 e_ref` measure the reference, not the method: they are
//! reported but left out of the fit, as are diverged runs.
//!
//! **Work-precision** plots the same errors against the cost of reaching them: force evaluations
//! (repeatable, machine-independent) and wall time (median of repeats, this machine). For a wanted
//! accuracy the cheapest method is the lowest curve at that error.
//!
//! **Same equations for every method.** Position Verlet's constraint projection and its `(1 - γ)`
//! damping change the equations being solved (a rope of rods instead of springs), so the study
//! runs Verlet with `iterations = 0`, `verlet_damping = 0` and `verlet_damping_rate = 0`, and says
//! so.
//!
//! **Verlet with and without dampers.** Position Verlet is second order only while the forces do
//! not depend on the velocity: a damper or drag sees Verlet's velocity `(x_n - x_{n-1})/dt`,
//! which is `v(t_n - dt/2)` to second order, half a step late, an `O(dt)` error in the force and
//! so a first-order method. The study therefore adds a row for Verlet on the same scene with the
//! dampers switched the other way ([`verlet_companion`]): on the undamped oscillator with
//! `damping = 2` N·s/m (damping ratio 0.1), on a damped scene with `damping = 0` (and `drag = 0`).
//! Verlet's own damping rate (`verlet_damping_rate`) is applied with the centred velocity and
//! keeps it second order; GAMES101's per-step factor `γ` does not.
//!
//! **Verlet's own damping** (when a user sets it back on with `--set`) is a force the other
//! methods do not feel, so Verlet gets a reference of its own in which every method would feel
//! it. The rate `r` (1/s) is the drag `-m r v` on each particle of mass `m`:
//!
//! ```text
//! c' = c + m r                  the drag of the reference (N·s/m), one m for every free particle
//! m u'' = -k u - (k_d + c') u'  the oscillator's reference, exactly (along the spring, the
//!                               damper and the drag are one force)
//! ```
//! where `c` is the scene's drag (N·s/m), `k`, `k_d` the spring's stiffness (N/m) and damper
//! (N·s/m); other scenes get the RK4 reference with `c'`. With it Verlet measures order 2 on
//! the oscillator (`tests/study_convergence.rs`). The factor `γ` per step has no such reference:
//! its rate `γ/dt` grows without bound as `dt` shrinks (at a fixed `γ`, each halving of `dt`
//! doubles the drag), so the runs converge to no solution; the row is reported with the errors
//! against the undamped reference, no order, and the reason.
//!
//! Reference: E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*,
//! 2nd ed., Springer 1993, §II.4 (order and error estimation, Richardson extrapolation) and
//! §II.10 (work-precision diagrams).

use std::time::Instant;

use glam::DVec3;
use serde::Serialize;

use super::StudyError;
use crate::physics::Method;
use crate::scene::{self, Scene};
use crate::simulation::Simulation;

/// Scene parameters every convergence study applies first (see the module docs).
pub const SAME_EQUATIONS: [&str; 3] = ["iterations=0", "verlet_damping=0", "verlet_damping_rate=0"];

/// Options of [`convergence`].
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergenceOptions {
    /// Methods, in order.
    pub methods: Vec<Method>,
    /// The time at which errors are measured (s); `None`: 1 s.
    pub time: Option<f64>,
    /// The largest dt (s); `None`: the scene's default dt, or 0.005 s for the oscillator.
    pub dt: Option<f64>,
    /// Number of dt values: dt, dt/2, …, dt/2^(levels-1).
    pub levels: u32,
    /// Timed repeats per point (wall time is their median).
    pub repeats: u32,
}

impl Default for ConvergenceOptions {
    fn default() -> ConvergenceOptions {
        ConvergenceOptions {
            methods: Method::ALL.to_vec(),
            time: None,
            dt: None,
            levels: 4,
            repeats: 1,
        }
    }
}

/// One run of one method at one dt.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Point {
    /// Time step (s).
    pub dt: f64,
    /// Largest position error at the study time (m); `null` in JSON when the run diverged.
    pub error: Option<f64>,
    /// Force evaluations the run took.
    pub force_evals: u64,
    /// Wall time of the run (s), median of the repeats.
    pub wall_seconds: f64,
    /// Whether the point entered the order fit.
    pub fitted: bool,
}

/// The points of one method and its fitted order.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodConvergence {
    /// The method.
    pub method: Method,
    /// Least-squares slope of log error against log dt over the fitted points; `null` when fewer
    /// than two points could be fitted.
    pub order: Option<f64>,
    /// One point per dt, largest dt first.
    pub points: Vec<Point>,
    /// The method's own reference when it is not the report's (module docs, "Verlet's own
    /// damping"): Verlet with `verlet_damping_rate`, or why there is none (`verlet_damping`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference: Option<String>,
}

/// The result of [`convergence`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConvergenceReport {
    /// Scene name.
    pub scene: String,
    /// Parameters applied before the user's.
    pub sets: Vec<String>,
    /// The time the errors are measured at (s).
    pub time: f64,
    /// `exact` or `rk4 dt=…`.
    pub reference: String,
    /// Estimated error of the reference itself (m); 0 for an exact solution.
    pub reference_error: f64,
    /// One entry per method.
    pub methods: Vec<MethodConvergence>,
    /// Verlet on the same scene with the dampers switched the other way (module docs), when
    /// Verlet is studied and the scene has a `damping` parameter.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verlet_companion: Option<Companion>,
}

/// Verlet's convergence on the scene with the dampers switched.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Companion {
    /// The parameters applied on top of the study's.
    pub sets: Vec<String>,
    /// True when the companion has dampers (the study's scene has none).
    pub damped: bool,
    /// `exact` or `rk4 dt=…`.
    pub reference: String,
    /// Verlet's points and fitted order.
    pub verlet: MethodConvergence,
}

/// The parameters that switch a built-in scene's dampers the other way for the Verlet row
/// (module docs): `None` for scene files and scenes without a `damping` parameter. Returns the
/// assignments and whether the result is damped.
#[must_use]
pub fn verlet_companion(name: &str, sets: &[String]) -> Option<(Vec<String>, bool)> {
    let def = scene::builtin(name)?;
    let specs = (def.params)();
    let has = |key: &str| specs.iter().any(|p| p.name == key);
    if !has("damping") {
        return None;
    }
    let mut params = def.default_params();
    for s in sets {
        params.set_text(s).ok()?;
    }
    let damped = params.number("damping") > 0.0 || (has("drag") && params.number("drag") > 0.0);
    let mut extra = Vec::new();
    if damped {
        extra.push("damping=0".to_string());
        if has("drag") {
            extra.push("drag=0".to_string());
        }
    } else {
        // Damping ratio 0.1 for the first spring: k_d = 0.2 √(k m).
        let k = params.number("stiffness");
        let m = params.number("mass");
        let kd = 0.2 * (k * m).sqrt();
        extra.push(format!("damping={kd}"));
    }
    Some((extra, !damped))
}

/// The exact positions at time `t`, when the scene has a closed-form solution.
fn exact_solution(scene: &Scene, t: f64) -> Option<Vec<DVec3>> {
    let [body] = scene.bodies.as_slice() else {
        return None;
    };
    let (model, state) = (&body.model, &body.state);
    if !model.colliders.is_empty() || !state.spheres.is_empty() {
        return None;
    }
    if model.springs().is_empty() {
        if model.drag != 0.0 {
            return None;
        }
        // Free fall: x(t) = x0 + v0 t + ½ g t² for free particles; pinned ones stay.
        return Some(
            state
                .x
                .iter()
                .zip(&state.v)
                .zip(&model.inv_mass)
                .map(|((&x, &v), &w)| {
                    if w == 0.0 {
                        x
                    } else {
                        x + v * t + 0.5 * model.gravity * t * t
                    }
                })
                .collect(),
        );
    }
    // The oscillator: one spring from a pinned particle at the origin to a free one on the x axis,
    // no gravity: x_1(t) = L0 + u(t), the damped motion with the damper and the drag together
    // (along the axis, with the other end at rest, the damper k_d and the drag c are one force
    // -(k_d + c) u').
    let [s] = model.springs() else {
        return None;
    };
    let along_x = state
        .x
        .iter()
        .chain(&state.v)
        .all(|p| p.y == 0.0 && p.z == 0.0);
    let pinned_origin = model.inv_mass[0] == 0.0 && state.x[0] == DVec3::ZERO;
    if model.particle_count() != 2 || model.gravity != DVec3::ZERO || !along_x || !pinned_origin {
        return None;
    }
    if state.v[1] != DVec3::ZERO || state.x[1].x <= 0.0 {
        return None;
    }
    let u = damped_oscillator(
        s.stiffness,
        s.damping + model.drag,
        model.mass[1],
        state.x[1].x - s.rest_length,
        0.0,
        t,
    );
    Some(vec![DVec3::ZERO, DVec3::new(s.rest_length + u, 0.0, 0.0)])
}

/// The stretch `u(τ)` (m) of the damped harmonic oscillator, exactly: the one formula of the
/// convergence study's reference and of the lesson app's "exact vs simulated" plot.
///
/// ```text
/// m u'' = -k u - k_d u'                 u = x - L0, the stretch along the spring (m)
/// γ = k_d / (2 m),  ω0 = √(k/m)
/// γ < ω0:  u = e^{-γ τ} (u0 cos ω_d τ + (v0 + γ u0)/ω_d sin ω_d τ),   ω_d = √(ω0² - γ²)
/// γ = ω0:  u = e^{-γ τ} (u0 + (v0 + γ u0) τ)
/// γ > ω0:  u = (u0 r2 - v0) e^{r1 τ}/(r2 - r1) + (v0 - u0 r1) e^{r2 τ}/(r2 - r1),   r1,2 = -γ ± √(γ² - ω0²)
/// ```
/// where `τ` (s) is the time since the state `(u0, v0)` (m, m/s), `k` the `stiffness` (N/m),
/// `k_d` the `damping` (N·s/m) and `m` the `mass` (kg). Undamped and from rest this is
/// `u = u0 cos(ω0 τ)`; with `k = 0` the mass coasts, `u = u0 + v0 τ`.
#[must_use]
pub fn damped_oscillator(
    stiffness: f64,
    damping: f64,
    mass: f64,
    u0: f64,
    v0: f64,
    tau: f64,
) -> f64 {
    let omega0 = (stiffness / mass).sqrt();
    let gamma = damping / (2.0 * mass);
    if gamma == 0.0 {
        if omega0 == 0.0 {
            u0 + v0 * tau
        } else {
            u0 * (omega0 * tau).cos() + v0 / omega0 * (omega0 * tau).sin()
        }
    } else if (gamma - omega0).abs() <= 1e-12 * omega0.max(gamma) {
        (-gamma * tau).exp() * (u0 + (v0 + gamma * u0) * tau)
    } else if gamma < omega0 {
        let omega_d = (omega0 * omega0 - gamma * gamma).sqrt();
        (-gamma * tau).exp()
            * (u0 * (omega_d * tau).cos() + (v0 + gamma * u0) / omega_d * (omega_d * tau).sin())
    } else {
        let root = (gamma * gamma - omega0 * omega0).sqrt();
        let (r1, r2) = (-gamma + root, -gamma - root);
        ((u0 * r2 - v0) * (r1 * tau).exp() + (v0 - u0 * r1) * (r2 * tau).exp()) / (r2 - r1)
    }
}

/// Verlet's own reference (module docs, "Verlet's own damping"), when the scene gives Verlet a
/// damping of its own: a description, and the reference positions at `t_end` with their
/// estimated error (m), or `None` for the positions when no dt-independent reference exists
/// (`verlet_damping` γ per step, or a rate on a scene whose free masses differ).
#[allow(clippy::type_complexity)]
fn verlet_own_reference(
    scene: &Scene,
    t_end: f64,
    dt_min: f64,
    steps_for: &dyn Fn(f64) -> u64,
) -> Option<(String, Option<(Vec<DVec3>, f64)>)> {
    let [body] = scene.bodies.as_slice() else {
        return None;
    };
    let (gamma, rate) = (body.params.verlet_damping, body.params.verlet_damping_rate);
    if gamma != 0.0 {
        return Some((
            format!(
                "none: verlet_damping γ = {gamma} per step is a drag of rate γ/dt, which grows \
                 without bound as dt shrinks, so Verlet converges to no solution (not fitted); \
                 use verlet_damping_rate"
            ),
            None,
        ));
    }
    if rate == 0.0 {
        return None;
    }
    // The rate r is the drag -m r v on every free particle: the model's drag c = m r when the
    // free masses are one m.
    let model = &body.model;
    let mut free = model
        .mass
        .iter()
        .zip(&model.inv_mass)
        .filter(|&(_, &w)| w != 0.0)
        .map(|(&m, _)| m);
    let m = free.next()?;
    if free.any(|other| other != m) {
        return Some((
            format!(
                "none: verlet_damping_rate {rate} 1/s is a drag m r that differs between \
                 particles of different mass (not fitted)"
            ),
            None,
        ));
    }
    let mut twin = scene.clone();
    let drag = twin.bodies[0].model.drag + m * rate;
    twin.bodies[0].model.drag = drag;
    let with = format!("verlet_damping_rate {rate} 1/s as drag {drag} N·s/m");
    if let Some(x) = exact_solution(&twin, t_end) {
        return Some((format!("exact, {with}"), Some((x, 0.0))));
    }
    let dt_ref = dt_min / 16.0;
    let (fine, _, d1, _) = run(&twin, Method::Rk4, dt_ref, steps_for(dt_ref));
    let (coarse, _, d2, _) = run(&twin, Method::Rk4, 2.0 * dt_ref, steps_for(2.0 * dt_ref));
    let estimate = if d1 || d2 {
        f64::INFINITY
    } else {
        max_distance(&fine, &coarse) / 15.0
    };
    Some((format!("rk4 dt={dt_ref:e}, {with}"), Some((fine, estimate))))
}

/// Positions after running `scene` with `method` at `dt` for `steps` steps, the force evaluations,
/// and whether it diverged.
fn run(scene: &Scene, method: Method, dt: f64, steps: u64) -> (Vec<DVec3>, u64, bool, f64) {
    let mut scene = scene.clone();
    scene.set_method(method);
    let mut sim = Simulation::new(scene);
    sim.set_dt(dt);
    // Timing measures the method, not the energy accounting.
    sim.set_accounting(false);
    let start = Instant::now();
    sim.advance(steps);
    let wall = start.elapsed().as_secs_f64();
    (
        sim.positions().collect(),
        sim.force_evals,
        sim.diverged.is_some(),
        wall,
    )
}

fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max)
}

/// Least-squares slope of `log y` against `log x`.
#[must_use]
pub fn fitted_slope(points: &[(f64, f64)]) -> Option<f64> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Loads `name_or_path` for a convergence study: [`SAME_EQUATIONS`] first, then `user_sets`.
///
/// # Errors
/// As [`scene::load`].
pub fn load_scene(
    name_or_path: &str,
    user_sets: &[String],
) -> Result<(Scene, Vec<String>), StudyError> {
    let mut sets: Vec<String> = SAME_EQUATIONS.iter().map(|s| (*s).to_string()).collect();
    sets.extend(user_sets.iter().cloned());
    let scene = scene::load(name_or_path, &sets)?;
    Ok((scene, sets))
}

/// Measures each method's error at the study time for dt, dt/2, … and fits its order.
/// Calls `progress(method, level)` after each run.
///
/// # Errors
/// A time or dt that is not positive and finite, fewer than 2 levels, no method.
pub fn convergence(
    scene: &Scene,
    options: &ConvergenceOptions,
    progress: &mut dyn FnMut(Method, u32),
) -> Result<ConvergenceReport, StudyError> {
    let time = options.time.unwrap_or(1.0);
    if !(time > 0.0 && time.is_finite()) {
        return Err(StudyError::Time(time));
    }
    let exact_scene = exact_solution(scene, time).is_some();
    let dt0 = options
        .dt
        .unwrap_or(if exact_scene && scene.name == "oscillator" {
            0.005
        } else {
            scene.dt
        });
    if !(dt0 > 0.0 && dt0.is_finite()) {
        return Err(StudyError::TimeStep(dt0));
    }
    if options.levels < 2 {
        return Err(StudyError::Levels(options.levels));
    }
    if options.methods.is_empty() {
        return Err(StudyError::NoMethods);
    }
    let dts: Vec<f64> = (0..options.levels)
        .map(|i| dt0 / f64::from(1u32 << i.min(30)))
        .collect();
    let steps_for = |dt: f64| (time / dt).round().max(1.0) as u64;
    let dt_min = dts[dts.len() - 1];
    // Every run ends at exactly steps·dt; the reference is taken at the same instant.
    let t_end = steps_for(dt0) as f64 * dt0;
    let (reference_x, reference, reference_error) = match exact_solution(scene, t_end) {
        Some(x) => (x, "exact".to_string(), 0.0),
        None => {
            let dt_ref = dt_min / 16.0;
            let (fine, _, d1, _) = run(scene, Method::Rk4, dt_ref, steps_for(dt_ref));
            let (coarse, _, d2, _) = run(scene, Method::Rk4, 2.0 * dt_ref, steps_for(2.0 * dt_ref));
            let estimate = if d1 || d2 {
                f64::INFINITY
            } else {
                max_distance(&fine, &coarse) / 15.0
            };
            (fine, format!("rk4 dt={dt_ref:e}"), estimate)
        }
    };
    // Verlet's own damping is a force only Verlet feels: its reference has it too.
    let verlet_reference = options
        .methods
        .contains(&Method::Verlet)
        .then(|| verlet_own_reference(scene, t_end, dt_min, &steps_for))
        .flatten();
    let mut methods = Vec::new();
    for &method in &options.methods {
        let own = verlet_reference
            .as_ref()
            .filter(|_| method == Method::Verlet);
        let (reference_x, reference_error) = match own {
            Some((_, Some((x, e)))) => (x, *e),
            _ => (&reference_x, reference_error),
        };
        let mut points = Vec::new();
        for (level, &dt) in dts.iter().enumerate() {
            let steps = steps_for(dt);
            let mut walls = Vec::new();
            let mut last = None;
            for _ in 0..options.repeats.max(1) {
                let (x, evals, diverged, wall) = run(scene, method, dt, steps);
                walls.push(wall);
                last = Some((x, evals, diverged));
            }
            walls.sort_by(f64::total_cmp);
            let Some((x, force_evals, diverged)) = last else {
                continue;
            };
            let error = (!diverged)
                .then(|| max_distance(&x, reference_x))
                .filter(|e| e.is_finite());
            let fitted = error.is_some_and(|e| e > 10.0 * reference_error && e > 0.0)
                && own.is_none_or(|o| o.1.is_some());
            points.push(Point {
                dt,
                error,
                force_evals,
                wall_seconds: walls[walls.len() / 2],
                fitted,
            });
            progress(method, level as u32);
        }
        let fit: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.fitted)
            .filter_map(|p| p.error.map(|e| (p.dt, e)))
            .collect();
        let order = if own.is_some_and(|o| o.1.is_none()) {
            None
        } else {
            fitted_slope(&fit)
        };
        methods.push(MethodConvergence {
            method,
            order,
            points,
            reference: own.map(|o| o.0.clone()),
        });
    }
    Ok(ConvergenceReport {
        scene: scene.name.clone(),
        sets: Vec::new(),
        time: t_end,
        reference,
        reference_error,
        methods,
        verlet_companion: None,
    })
}

/// [`convergence`] of `name_or_path` with `user_sets`, plus the Verlet row with the dampers
/// switched (module docs) when Verlet is among the methods and the scene allows it.
///
/// # Errors
/// As [`load_scene`] and [`convergence`].
pub fn convergence_with_companion(
    name_or_path: &str,
    user_sets: &[String],
    options: &ConvergenceOptions,
    limits: &crate::budget::Limits,
    progress: &mut dyn FnMut(Method, u32),
) -> Result<ConvergenceReport, StudyError> {
    let mut sets: Vec<String> = SAME_EQUATIONS.iter().map(|s| (*s).to_string()).collect();
    sets.extend(user_sets.iter().cloned());
    let scene = scene::load_with(name_or_path, &sets, limits)?;
    let mut report = convergence(&scene, options, progress)?;
    report.sets = sets.clone();
    if options.methods.contains(&Method::Verlet)
        && let Some((extra, damped)) = verlet_companion(name_or_path, &sets)
    {
        let mut all = sets;
        all.extend(extra.iter().cloned());
        let companion = scene::load_with(name_or_path, &all, limits)?;
        let only = ConvergenceOptions {
            methods: vec![Method::Verlet],
            ..options.clone()
        };
        let r = convergence(&companion, &only, progress)?;
        if let Some(verlet) = r.methods.into_iter().next() {
            report.verlet_companion = Some(Companion {
                sets: extra,
                damped,
                reference: r.reference,
                verlet,
            });
        }
    }
    Ok(report)
}
