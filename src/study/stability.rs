//! The largest stable time step of each method: `springlab study stability`.
//!
//! # Theory
//!
//! On the undamped harmonic oscillator `x'' = -ω² x` every one-step method multiplies the state
//! by the same amplification per step, a function of `z = dt·ω` alone; the method is stable
//! while its modulus stays ≤ 1 (Hairer & Wanner, *Solving Ordinary Differential Equations II*,
//! 2nd ed., Springer 1996, §IV.2). For the Runge–Kutta type methods it is a scalar `R(i z)`:
//!
//! ```text
//! explicit Euler        |R|² = 1 + z²                    grows at every dt        none
//! midpoint (RK2)        |R|² = 1 + z⁴/4                  grows at every dt        none
//! RK4                   |R|² = 1 - z⁶/72 + z⁸/576        ≤ 1 while z ≤ 2√2        2.828
//! predictor–corrector   |R|² = 1 - z² + z⁴               ≤ 1 while z ≤ 1          1
//! implicit Euler        |R|² = 1 / (1 + z²)              < 1 at every dt          unconditional
//! ```
//! Semi-implicit Euler and position Verlet share the recurrence
//! `x_{n+1} - (2 - z²) x_n + x_{n-1} = 0`, whose roots have modulus 1 while `z < 2` (at `z = 2`
//! a double root -1: linear growth). XPBD is unconditionally stable and dissipative. See
//! [`crate::physics::integrators`] for the derivations.
//!
//! A mass-spring system has many modes; linearised, each mode `i` is an oscillator of angular
//! frequency `ω_i`, and the stiffest one fails first:
//!
//! ```text
//! dt_max = z_limit / ω_max
//! ```
//! where `z_limit` is the dimensionless limit above, `ω_max` (rad/s) comes from
//! [`super::modes::omega_max`] and `dt_max` is in seconds. Damping, drag, gravity, contact and
//! large motions move the real limit away from this; the study measures it.
//!
//! # What "stable" means here
//!
//! A *probe* runs the scene with one method at one `dt` for
//! `N = max(⌈T/dt⌉, N_min)` steps, `T` being the horizon (s, default 2). Two criteria:
//!
//! **Growth** ([`Criterion::Growth`]), for a conservative scene — no gravity, no spring damping,
//! no drag, no colliders, no dynamic spheres (the oscillator). Its energy
//! `E = E_kinetic + E_elastic ≥ 0` is constant along the exact motion, so any sustained rise
//! is the method's instability. With `N_min = 10 000`, `N` rounded up to an even `2W` and
//! `E_n` the energy after `n` steps:
//!
//! ```text
//! w_j      = sin⁴(π (j + ½) / W),                  j = 0 .. W-1
//! Ē_early  = Σ_j w_j E_{1+j}   / Σ_j w_j            first half of the run
//! Ē_late   = Σ_j w_j E_{W+1+j} / Σ_j w_j            second half
//! stable  ⇔  no divergence  and  Ē_late ≤ (1 + 10⁻⁶) Ē_early
//! ```
//! where the energies are in J and the window `w` is dimensionless. For a Runge–Kutta type
//! method on the oscillator, `y = v + iω (x - L0)` obeys `y' = iω y` and `y_{n+1} = R(i z) y_n`,
//! so `E_n = ½ m |y_n|² = |R|^{2n} E_0`, so `Ē_late / Ē_early = |R|^{2W}` exactly, whatever the
//! window: the test sees a growth of `10⁻⁶` over `W ≥ 5000` steps, which is how midpoint's
//! `|R|² - 1 = z⁴/4 = 2.5·10⁻⁹` per step at `z = 0.01` is still caught. Semi-implicit Euler and
//! Verlet do not conserve `E` but a nearby quadratic form, so their `E_n` oscillates without
//! growing (`E_n = a + Re(b e^{2iθn})`, `θ` the discrete rotation per step); the smooth window
//! cancels that oscillation up to a leakage of order `|b| (W |sin θ|)^-5`, far below `10⁻⁶`
//! except within about `10⁻⁴` of `z = 2`. A run whose energy rises beyond `10⁶ E_0` stops as
//! unstable; one that decays below `10⁻³⁰ E_0` stops as stable. The oscillator's motion along
//! its spring is exactly linear as long as the particle stays clear of the pin; the study starts
//! it `10⁻⁶` m from rest length, so that even a growth by `10³` in amplitude keeps it there (see
//! [`scene_sets`]).
//!
//! **Divergence** ([`Criterion::Divergence`]), for every other scene (gravity, damping,
//! collisions: the rope, the cubes, the cloths): with `N_min = 100`,
//! stable ⇔ the run never diverges (NaN, or `|v|² > 10⁶` m²/s², [`crate::physics::diverge`]).
//! `N_min` keeps a huge `dt` from passing after one or two steps. A mode that the motion never
//! excites grows only from round-off, so an unstable `dt` may pass a short horizon.
//!
//! # The search
//!
//! For each method, with `z = dt·ω_max`:
//! 1. probe `z = 100`: stable there → **unconditional**;
//! 2. probe the theoretical limit (or `z = 1` when there is none); stable → double `z` until a
//!    probe fails; unstable → divide by 4 until one passes, down to `z = 0.01`: failing there
//!    too → **none**;
//! 3. bisect `[z_stable, z_unstable]` at the geometric mean (bisection in `log dt`) until the two
//!    are within `10⁻³` relatively (at most 20 probes): **conditional**, `max_stable_dt` being the
//!    largest stable probe.
//!
//! Stability is not always monotone in `dt`: a nonlinear scene or a collision can be stable at
//! one `dt`, unstable at a smaller one and stable again at a smaller one still, and a mode can
//! be excited at one `dt` and missed at another. The bisection finds *a* boundary between a
//! stable and an unstable probe, and every probe is listed with the result.
//!
//! Cost: a probe takes `max(⌈T/dt⌉, N_min)` steps, fewer when it diverges early; stable probes at
//! small `dt` dominate. The study is sequential and deterministic.

use std::f64::consts::PI;

use glam::DVec3;
use serde::Serialize;

use super::StudyError;
use super::modes::omega_max;
use crate::physics::Method;
use crate::scene::{self, Scene};
use crate::simulation::Simulation;

/// Default horizon `T` (s).
pub const DEFAULT_HORIZON: f64 = 2.0;
/// Smallest `dt·ω_max` probed: a method unstable there is reported as having no stable dt.
pub const DT_OMEGA_FLOOR: f64 = 0.01;
/// Largest `dt·ω_max` probed: a method stable there is reported as unconditionally stable.
pub const DT_OMEGA_CEILING: f64 = 100.0;
/// The bisection stops when `z_unstable / z_stable ≤ 1 + BISECTION_TOLERANCE`.
pub const BISECTION_TOLERANCE: f64 = 1e-3;
/// At most this many bisection probes per method.
pub const MAX_BISECTIONS: u32 = 20;
/// Growth criterion: the fewest steps of a probe.
pub const GROWTH_MIN_STEPS: u64 = 10_000;
/// Growth criterion: `Ē_late / Ē_early` above `1 +` this is growth.
pub const GROWTH_TOLERANCE: f64 = 1e-6;
/// Growth criterion: an energy above this multiple of the initial one stops the run (unstable).
pub const GROWTH_STOP: f64 = 1e6;
/// Growth criterion: an energy below this multiple of the initial one stops the run (stable).
pub const DECAY_STOP: f64 = 1e-30;
/// Divergence criterion: the fewest steps of a probe.
pub const DIVERGENCE_MIN_STEPS: u64 = 100;
/// No probe may take more steps than this (see [`StudyError::TooManySteps`]).
pub const MAX_STEPS: f64 = 1e9;
/// The oscillator's initial stretch set by the study (m): small, so that a growth by 10³ in
/// amplitude still leaves the particle far from the pin and the motion linear.
pub const OSCILLATOR_AMPLITUDE: &str = "amplitude=1e-6";

/// What "stable" means for a probe (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Criterion {
    /// No divergence and no growth of the energy (conservative scenes).
    Growth,
    /// No divergence (scenes with gravity, damping, drag or contact).
    Divergence,
}

impl Criterion {
    /// [`Criterion::Growth`] when every body of `scene` is conservative and free — no gravity,
    /// no spring damping, no drag, no colliders, no dynamic spheres — else
    /// [`Criterion::Divergence`].
    #[must_use]
    pub fn for_scene(scene: &Scene) -> Criterion {
        let conservative = scene.bodies.iter().all(|b| {
            b.model.gravity == DVec3::ZERO
                && b.model.drag == 0.0
                && b.model.springs.iter().all(|s| s.damping == 0.0)
                && b.model.colliders.is_empty()
                && b.state.spheres.is_empty()
        });
        if conservative {
            Criterion::Growth
        } else {
            Criterion::Divergence
        }
    }

    /// The fewest steps of a probe under this criterion.
    #[must_use]
    pub fn min_steps(self) -> u64 {
        match self {
            Criterion::Growth => GROWTH_MIN_STEPS,
            Criterion::Divergence => DIVERGENCE_MIN_STEPS,
        }
    }

    /// The definition of "stable", in words, for horizon `horizon` (s).
    #[must_use]
    pub fn definition(self, horizon: f64) -> String {
        match self {
            Criterion::Growth => format!(
                "no divergence (NaN, or |v|² > 10⁶ m²/s²) and no growth: over \
                 N = max(⌈T/dt⌉, {GROWTH_MIN_STEPS}) steps, T = {horizon} s, the energy \
                 (kinetic + elastic) averaged with a sin⁴ window over the second half of the \
                 run exceeds its average over the first half by at most {GROWTH_TOLERANCE:e} \
                 (relative)"
            ),
            Criterion::Divergence => format!(
                "no divergence over N = max(⌈T/dt⌉, {DIVERGENCE_MIN_STEPS}) steps, T = {horizon} \
                 s: every position and velocity finite and |v|² ≤ 10⁶ m²/s² (1000 m/s) after \
                 every step"
            ),
        }
    }
}

/// The stability class of a method on a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Stability {
    /// Stable up to a limit `dt`.
    Conditional,
    /// Unstable at every `dt` probed, down to `dt·ω_max =` [`DT_OMEGA_FLOOR`].
    None,
    /// Stable at `dt·ω_max =` [`DT_OMEGA_CEILING`].
    Unconditional,
}

impl Stability {
    /// The lower-case name used in the output.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Stability::Conditional => "conditional",
            Stability::None => "none",
            Stability::Unconditional => "unconditional",
        }
    }
}

/// The stability of `method` on the undamped harmonic oscillator, and its limit `dt·ω` when
/// conditional (see the module documentation). The predictor–corrector's 1 follows from
/// `|R|² = 1 - z² + z⁴` and is confirmed by measurement (`tests/integrators.rs`).
#[must_use]
pub fn theory(method: Method) -> (Stability, Option<f64>) {
    match method {
        Method::ExplicitEuler | Method::Midpoint => (Stability::None, None),
        Method::SemiImplicitEuler | Method::Verlet => (Stability::Conditional, Some(2.0)),
        Method::Rk4 => (Stability::Conditional, Some(2.0 * std::f64::consts::SQRT_2)),
        Method::PredictorCorrector => (Stability::Conditional, Some(1.0)),
        Method::ImplicitEuler | Method::Xpbd => (Stability::Unconditional, None),
    }
}

/// One run of the scene at one time step.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Probe {
    /// Time step (s).
    pub dt: f64,
    /// `dt·ω_max` (dimensionless).
    pub dt_omega: f64,
    /// Steps taken (fewer than planned when the run stopped early).
    pub steps: u64,
    /// The verdict.
    pub stable: bool,
    /// Growth criterion: `Ē_late / Ē_early` when the run went to the end, else null.
    pub growth: Option<f64>,
    /// Simulated time at which the run diverged (s), or null.
    pub diverged_time: Option<f64>,
}

/// The result for one method.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodLimit {
    /// The method.
    pub method: Method,
    /// Measured stability class.
    pub stability: Stability,
    /// Largest stable time step found (s); null when none or unconditional.
    pub max_stable_dt: Option<f64>,
    /// `max_stable_dt · ω_max` (dimensionless); null when none or unconditional.
    pub limit_dt_omega: Option<f64>,
    /// The limit `dt·ω` on the undamped oscillator; null when none or unconditional.
    pub theory_dt_omega: Option<f64>,
    /// The stability class on the undamped oscillator.
    pub theory: Stability,
    /// Every probe, in the order taken.
    pub probes: Vec<Probe>,
}

/// What `springlab study stability --json` prints (DESIGN.md, more fields welcome).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StabilityReport {
    /// Scene name.
    pub scene: String,
    /// The `--set` assignments the scene was built with, the study's own first.
    pub sets: Vec<String>,
    /// `ω_max` of the stiffest body at the initial state (rad/s).
    pub omega_max: f64,
    /// How `omega_max` was computed.
    pub omega_method: &'static str,
    /// Gershgorin upper bound on `ω_max` (rad/s).
    pub omega_gershgorin: f64,
    /// Power iterations taken for `omega_max`.
    pub omega_iterations: u32,
    /// Horizon `T` (s).
    pub horizon: f64,
    /// The criterion used.
    pub criterion: Criterion,
    /// What "stable" means, in words.
    pub definition: String,
    /// The range of `dt·ω_max` probed, `[floor, ceiling]`.
    pub dt_omega_range: [f64; 2],
    /// One entry per method, in the order asked for.
    pub methods: Vec<MethodLimit>,
}

/// Options of [`stability`].
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityOptions {
    /// The methods to study, in order.
    pub methods: Vec<Method>,
    /// Horizon `T` (s), > 0.
    pub horizon: f64,
    /// The criterion; `None` chooses with [`Criterion::for_scene`].
    pub criterion: Option<Criterion>,
}

impl Default for StabilityOptions {
    /// Every method, a 2 s horizon, the criterion chosen by the scene.
    fn default() -> StabilityOptions {
        StabilityOptions {
            methods: Method::ALL.to_vec(),
            horizon: DEFAULT_HORIZON,
            criterion: None,
        }
    }
}

/// The `--set` assignments the study applies before the user's: `amplitude=1e-6` for the
/// built-in oscillator (so that its spring stays linear however much a method lets it grow),
/// none for other scenes.
#[must_use]
pub fn scene_sets(name_or_path: &str, user_sets: &[String]) -> Vec<String> {
    let mut sets = Vec::with_capacity(user_sets.len() + 1);
    if name_or_path == "oscillator" {
        sets.push(OSCILLATOR_AMPLITUDE.to_string());
    }
    sets.extend(user_sets.iter().cloned());
    sets
}

/// Loads a scene for the study: [`scene::load`] with [`scene_sets`] applied; returns the scene
/// and the assignments used.
///
/// # Errors
/// As [`scene::load`].
pub fn load_scene(
    name_or_path: &str,
    user_sets: &[String],
) -> Result<(Scene, Vec<String>), StudyError> {
    let sets = scene_sets(name_or_path, user_sets);
    let scene = scene::load(name_or_path, &sets)?;
    Ok((scene, sets))
}

/// Parses a comma-separated method list (`rk4, verlet`); empty items are skipped and repeats
/// dropped.
///
/// # Errors
/// An unknown name, or no name at all.
pub fn parse_methods(text: &str) -> Result<Vec<Method>, StudyError> {
    let mut methods = Vec::new();
    for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let m: Method = name.parse()?;
        if !methods.contains(&m) {
            methods.push(m);
        }
    }
    if methods.is_empty() {
        return Err(StudyError::NoMethods);
    }
    Ok(methods)
}

/// Measures the largest stable `dt` of each method of `options` on `scene` (see the module
/// documentation). Calls `progress` after every probe.
///
/// # Errors
/// A horizon that is not positive and finite, no method, a scene without stiffness, a
/// conservative scene at rest, or a horizon so long that a probe would exceed [`MAX_STEPS`].
pub fn stability(
    scene: &Scene,
    options: &StabilityOptions,
    progress: &mut dyn FnMut(Method, &Probe),
) -> Result<StabilityReport, StudyError> {
    let horizon = options.horizon;
    if !(horizon > 0.0 && horizon.is_finite()) {
        return Err(StudyError::Horizon(horizon));
    }
    if options.methods.is_empty() {
        return Err(StudyError::NoMethods);
    }
    let criterion = options
        .criterion
        .unwrap_or_else(|| Criterion::for_scene(scene));
    // The stiffest body sets ω_max.
    let estimate = scene
        .bodies
        .iter()
        .map(|b| omega_max(&b.model, &b.state))
        .max_by(|a, b| a.omega.total_cmp(&b.omega));
    let Some(estimate) = estimate.filter(|e| e.omega > 0.0 && e.omega.is_finite()) else {
        return Err(StudyError::NoStiffness(scene.name.clone()));
    };
    let omega = estimate.omega;
    if criterion == Criterion::Growth && Simulation::new(scene.clone()).energy().total <= 0.0 {
        return Err(StudyError::AtRest(scene.name.clone()));
    }
    let dt_floor = DT_OMEGA_FLOOR / omega;
    let steps = (horizon / dt_floor).ceil();
    if steps > MAX_STEPS {
        return Err(StudyError::TooManySteps {
            horizon,
            dt: dt_floor,
            steps,
            max: MAX_STEPS,
        });
    }

    let context = Context {
        scene,
        omega,
        horizon,
        criterion,
    };
    let methods = options
        .methods
        .iter()
        .map(|&m| context.search(m, progress))
        .collect();
    Ok(StabilityReport {
        scene: scene.name.clone(),
        sets: Vec::new(),
        omega_max: omega,
        omega_method: estimate.method,
        omega_gershgorin: estimate.gershgorin_omega,
        omega_iterations: estimate.iterations,
        horizon,
        criterion,
        definition: criterion.definition(horizon),
        dt_omega_range: [DT_OMEGA_FLOOR, DT_OMEGA_CEILING],
        methods,
    })
}

/// What every probe of one study shares.
struct Context<'a> {
    scene: &'a Scene,
    omega: f64,
    horizon: f64,
    criterion: Criterion,
}

impl Context<'_> {
    /// The search of the module documentation for one method.
    fn search(&self, method: Method, progress: &mut dyn FnMut(Method, &Probe)) -> MethodLimit {
        let (theory, theory_dt_omega) = theory(method);
        let mut probes = Vec::new();
        let mut stable_at = |z: f64| {
            let p = self.probe(method, z / self.omega);
            progress(method, &p);
            let stable = p.stable;
            probes.push(p);
            stable
        };
        let result = |stability, z: Option<f64>, probes| {
            let max_stable_dt = z.map(|z| z / self.omega);
            MethodLimit {
                method,
                stability,
                max_stable_dt,
                limit_dt_omega: max_stable_dt.map(|dt| dt * self.omega),
                theory_dt_omega,
                theory,
                probes,
            }
        };

        // 1. Unconditional?
        if stable_at(DT_OMEGA_CEILING) {
            return result(Stability::Unconditional, None, probes);
        }
        // 2. Bracket [stable, unstable], starting from the theoretical limit.
        let mut unstable = DT_OMEGA_CEILING;
        let start = theory_dt_omega
            .unwrap_or(1.0)
            .clamp(DT_OMEGA_FLOOR, DT_OMEGA_CEILING);
        let mut stable;
        if stable_at(start) {
            stable = start;
            while 2.0 * stable < unstable {
                let z = 2.0 * stable;
                if stable_at(z) {
                    stable = z;
                } else {
                    unstable = z;
                    break;
                }
            }
        } else {
            unstable = start;
            loop {
                if unstable <= DT_OMEGA_FLOOR {
                    return result(Stability::None, None, probes);
                }
                let z = (unstable / 4.0).max(DT_OMEGA_FLOOR);
                if stable_at(z) {
                    stable = z;
                    break;
                }
                unstable = z;
            }
        }
        // 3. Bisection in log dt.
        for _ in 0..MAX_BISECTIONS {
            if unstable <= stable * (1.0 + BISECTION_TOLERANCE) {
                break;
            }
            let z = (stable * unstable).sqrt();
            if stable_at(z) {
                stable = z;
            } else {
                unstable = z;
            }
        }
        result(Stability::Conditional, Some(stable), probes)
    }

    /// One run of `method` at `dt` (s).
    fn probe(&self, method: Method, dt: f64) -> Probe {
        let mut scene = self.scene.clone();
        scene.set_method(method);
        let mut sim = Simulation::new(scene);
        sim.set_dt(dt);
        // ⌈T/dt⌉ fits in u64: T·ω/DT_OMEGA_FLOOR ≤ MAX_STEPS was checked.
        let planned = ((self.horizon / dt).ceil() as u64).max(self.criterion.min_steps());
        let mut probe = Probe {
            dt,
            dt_omega: dt * self.omega,
            steps: 0,
            stable: true,
            growth: None,
            diverged_time: None,
        };
        match self.criterion {
            Criterion::Divergence => {
                for _ in 0..planned {
                    if let Some(d) = sim.step() {
                        probe.diverged_time = Some(d.time);
                        probe.stable = false;
                        break;
                    }
                }
            }
            Criterion::Growth => growth_run(&mut sim, planned, &mut probe),
        }
        probe.steps = sim.steps;
        probe
    }
}

/// The growth criterion: `2W ≥ planned` steps and their energies `E_1 .. E_{2W}` (module
/// documentation), with the early stops.
fn growth_run(sim: &mut Simulation, planned: u64, probe: &mut Probe) {
    let w = planned.div_ceil(2).max(1);
    let e0 = sim.energy().total;
    let (mut early, mut late) = (0.0, 0.0);
    for i in 0..2 * w {
        if let Some(d) = sim.step() {
            probe.diverged_time = Some(d.time);
            probe.stable = false;
            return;
        }
        let e = sim.energy().total;
        if e.is_nan() || e > GROWTH_STOP * e0 {
            probe.stable = false;
            return;
        }
        if e <= DECAY_STOP * e0 {
            probe.stable = true;
            return;
        }
        let j = i % w;
        // w_j = sin⁴(π (j + ½) / W)
        let s = (PI * (j as f64 + 0.5) / w as f64).sin();
        let weight = (s * s) * (s * s);
        if i < w {
            early += weight * e;
        } else {
            late += weight * e;
        }
    }
    // The two windows have the same weights, so their sums compare directly.
    let ratio = late / early;
    probe.growth = Some(ratio);
    probe.stable = ratio <= 1.0 + GROWTH_TOLERANCE;
}
