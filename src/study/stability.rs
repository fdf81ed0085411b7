//! The largest stable time step of each method: `springlab study stability`.
//!
//! # What "stable" means here
//!
//! Two tests, both stated in the output:
//!
//! 1. **Linear stability** ([`super::linear`]): a small perturbation of the scene's initial
//!    positions at rest, stepped by the method's own code (central finite differences of
//!    [`crate::physics::Method::step`], power iteration), must not grow: the windowed growth of
//!    its energy over `N = max(⌈T/dt⌉, 4 000)` steps stays below `10⁻⁶`, that is the spectral
//!    radius of the step map `ρ ≤ 1 + 10⁻¹⁰` or so. Gravity (a constant force) is left out of
//!    the linearisation and rigid motions are Jordan blocks that never grow exponentially: free
//!    fall is never instability. Contacts are excluded from the linearisation.
//! 2. **Confirmation**: the whole scene (contacts, spheres, large motions) runs at the largest
//!    linearly stable `dt` for `min(⌈50 T/dt⌉, 10 000)` steps (at least 100), and must not
//!    diverge (NaN, `|v| > 1000` m/s, a failed implicit solve) nor let its energy `E` rise: it
//!    fails when `E - E_0` passes `10⁴ S`, or ends the run above `10 S` and 1.5 times its
//!    largest value in the run's second quarter (still growing), or stays above `10 S` through
//!    the whole last quarter (pumped up: Verlet with one projection pass on the rope at
//!    `dt·ω = 52` keeps 1000 times its energy). `S = Σ m |g| ℓ + E_kinetic,0 + E_elastic,0` is the scene's
//!    energy scale (J; `ℓ`: the diagonal of a body's bounding box, m). A level alone would not
//!    do: near its limit semi-implicit Euler's energy swings far from `E_0` without growing
//!    (between `E_0/(1 + dt ω/2)` and `E_0/(1 - dt ω/2)` on the oscillator, up to 700-fold at
//!    `dt·ω = 1.997`, and back every period), while an unstable run's energy keeps rising or
//!    stays up. (The energy residual `E + D - E_0` of the accounting is not
//!    used here: a cube resting on a plane under explicit Euler gains a little energy every step
//!    that the contact response takes away again, so its residual grows steadily while nothing
//!    is unstable.) A failed confirmation lowers `dt` by 5 % (three times, then
//!    halves it) until one passes, then bisects to 0.5 %. The result must also pass at 95 % of itself (nonlinear resonances come
//!    and go with `dt`); if not, the search goes on below.
//!
//! The reported `max_stable_dt` is the confirmed one; the linear limit, the damped theory
//! ([`super::theory`]) and every probe and confirmation run are in the report beside it.
//!
//! # Why both
//!
//! The linear test is exact for the linearised system and matches the damped theory (within
//! 0.1 % on the course scenes), but a nonlinear motion can break a method below that limit. On
//! the undamped `rope` swinging from horizontal, semi-implicit Euler is linearly stable up to
//! `dt·ω_max = 2`, yet at 1.9 its energy grows from 59 J to 2·10⁵ J within 100 s: the stiff mode
//! is pumped by the swing (the nonlinear resonances of leapfrog-type methods; Schlick, Mandziuk,
//! Skeel & Srinivas 1998). Verlet with one projection pass is linearly stable at every `dt`
//! (projection removes the stiff modes), yet at `dt·ω_max = 100` (6 s steps) one pass cannot
//! pull a rope that fell 350 m in a step back together. The confirmation run finds these.
//!
//! # Linear, scene, and the stiffest state
//!
//! The report keeps the two limits apart: the **linear** limit is what the damped theory
//! ([`super::theory`]) predicts and is compared with it; the **scene** limit (`max_stable_dt`,
//! the confirmed one) is the dt to use. On the course scenes with impacts the scene limit is a
//! few per cent lower (RK4: `cube-plane` -5.1 %, `jelly-bowl` -8.1 %, `cloth-spheres` -5.3 %;
//! docs/stability.md), and that is not the contact code: an impact squeezes the body, and the
//! stiffest mode of the squeezed body is stiffer than at rest (the springs' directions change;
//! `ω_max` of `jelly-bowl` rises from 183.6 rad/s at rest to 194.4 rad/s in the impact on the
//! hole's edge, which lowers the overdamped mode's limit by about `(194.4/183.6)² ≈ 1.12`,
//! since `μ = (k_d/k) ω²`). Measured on
//! `jelly-bowl` with RK4 at dt = 2.75e-3 s (the theory at rest allows 2.85e-3): the run
//! diverges in the impact with the contact force left out of the stages, with the positional
//! projection left out, and with both; and the step map linearised at the squeezed state of a
//! run at 2.5e-3 s (contacts excluded, as in the linear test) grows perturbations at
//! 77 s⁻¹ at every dt up to 2.65e-3 s (a physical, dt-independent rate: the squeezed lattice is
//! not an equilibrium) and faster beyond it (104 s⁻¹ at 2.75e-3, 147 s⁻¹ at 2.84e-3), while at
//! rest every one of those dt decays (`examples/squeezed_linearisation.rs` reproduces these).
//!
//! So the study also runs the scene once with its own methods and `dt` over the horizon,
//! samples `ω_max` of every body every [`STIFFEST_SAMPLE_INTERVAL`] seconds (power iteration
//! warm-started from the previous sample, [`super::modes::omega_max_unbounded`]) and reports the
//! **stiffest state** and each method's damped theory linearised there (`stiffest_theory`).
//! The state is held only for an instant, so a run survives a little above that theory: on
//! scenes with impacts the scene limit lies between the theory at the stiffest state and the
//! theory at rest. Below both, the motion pumps a stiff mode (a nonlinear resonance, the
//! rope's semi-implicit Euler below).
//!
//! # The search
//!
//! For each method, with `z = dt·ω_max` (the methods are independent and run on separate
//! threads, [`crate::physics::pool::independent`], the longest first; their probes are reported
//! when each ends; once a core is free, a helper computes the confirmation and usable-dt
//! searches' likely next runs ahead, [`super::ahead`], which changes no run and no result):
//! 1. probe `z = 100`: linearly stable there → linearly **unconditional**;
//! 2. when the damped theory gives a limit `z_t`, bracket it: probe `z_t (1 - 10⁻³)`; stable →
//!    probe `10⁻³` higher (at most three times) until one fails: that bracket is the result
//!    (the theory and the measurement agree within 0.1 % on the course scenes, so this costs
//!    two or three probes instead of about ten);
//! 3. otherwise probe the damped theory's limit (or the oscillator's, or `z = 1`); stable → raise `z` by
//!    5 % (then double) until a probe fails; unstable → lower it by 5 % (then divide by 4) until
//!    one passes, down to `z = 0.01`: failing there too → **none**;
//! 4. bisect `[z_stable, z_unstable]` at the geometric mean until within `10⁻³` relatively;
//! 5. confirm (above);
//! 6. the damped theory at the static equilibrium the body hangs at
//!    ([`super::theory::equilibrium`]): a method it finds unstable at every dt (explicit Euler
//!    on the damped rope's undamped pendulum modes) is classed **none**;
//! 7. with [`StabilityOptions::usable`], the **usable dt** below the scene limit
//!    ([`usable`]: the energy residual within 1 % of `|E_0|` over the scene's duration).
//!
//! References: T. Schlick, M. Mandziuk, R. D. Skeel, K. Srinivas, "Nonlinear Resonance Artifacts
//! in Molecular Dynamics Simulations", J. Comput. Phys. 140 (1998); E. Hairer, G. Wanner,
//! *Solving Ordinary Differential Equations II*, 2nd ed., Springer 1996, §IV.2.

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use serde::Serialize;

use super::StudyError;
use super::ahead;
use super::linear::{self, Linearisation};
use super::modes::omega_max;
use super::theory::equilibrium::spectrum_at_equilibrium;
use super::theory::{self, TheoryLimit};
use crate::physics::pool::JobEvent;
use crate::physics::{Method, OscillatorLimit, energy};
use crate::scene::{self, Scene};

mod confirm;
mod report;
mod stiffest;
pub mod usable;

use confirm::{below, confirm_step_count, confirm_unless};
pub use confirm::{confirm_run, confirm_steps};
pub use report::{
    Confirmation, MethodLimit, Probe, StabilityOptions, StabilityReport, StiffestState,
};
pub use stiffest::stiffest;
use stiffest::stiffest_state;

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
/// Linear probes: the fewest power steps.
pub const GROWTH_MIN_STEPS: u64 = 4_000;
/// Confirmation: the run lasts this many horizons ...
pub const CONFIRM_HORIZONS: f64 = 50.0;
/// ... but at most this many steps ...
pub const CONFIRM_MAX_STEPS: u64 = 10_000;
/// ... and at least this many.
pub const CONFIRM_MIN_STEPS: u64 = 100;
/// Confirmation: a residual above this many energy scales `S` counts only while it grows ...
pub const CONFIRM_ENERGY_SCALES: f64 = 10.0;
/// ... by this factor from the second quarter of the run to the last;
pub const CONFIRM_GROWTH: f64 = 1.5;
/// ... and above this many it fails at once.
pub const CONFIRM_EXPLOSION_SCALES: f64 = 1e4;
/// The oscillator's initial stretch set by the study (m).
pub const OSCILLATOR_AMPLITUDE: &str = "amplitude=1e-6";
/// Confirmation: on scenes of 2 000 springs or more the energy is checked every this many
/// steps (and after the last); every step on smaller ones.
pub const CONFIRM_ENERGY_EVERY: u64 = 10;
/// Confirmation: a limit must also pass at this fraction of itself ...
pub const CONFIRM_MARGIN: f64 = 0.95;
/// ... searched again at most this many times.
pub const CONFIRM_ROUNDS: u32 = 4;
/// Confirmation bisection stops within this relative width.
pub const CONFIRM_TOLERANCE: f64 = 0.005;
/// The stiffest state: the run of the scene is sampled every this many seconds (at least
/// every step).
pub const STIFFEST_SAMPLE_INTERVAL: f64 = 0.005;
/// No probe may take more steps than this (see [`StudyError::TooManySteps`]).
pub const MAX_STEPS: f64 = 1e9;

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
/// conditional (see [`super::theory`] for the damped, scene-specific theory).
#[must_use]
pub fn theory(method: Method) -> (Stability, Option<f64>) {
    match method.declaration().oscillator {
        OscillatorLimit::None => (Stability::None, None),
        OscillatorLimit::Below(limit) => (Stability::Conditional, Some(limit)),
        OscillatorLimit::Unconditional => (Stability::Unconditional, None),
    }
}

/// The definition of "stable", in words, for horizon `horizon` (s) and energy scale `scale`.
#[must_use]
pub fn definition(horizon: f64, scale: f64) -> String {
    format!(
        "(1) linear: a perturbation of the initial positions at rest, stepped by the method's own \
         code (central finite differences; gravity and contacts excluded, rigid motions \
         removed), does not grow: \
         its energy averaged with a sin⁴ window over the second half of max(⌈T/dt⌉, \
         {GROWTH_MIN_STEPS}) steps, T = {horizon} s, exceeds the first half's by at most \
         {:e}, i.e. spectral radius ρ ≤ 1 + ~1e-10 (free fall and rigid motion never count); \
         (2) confirmed: the whole scene, contacts included, runs min(⌈{CONFIRM_HORIZONS} T/dt⌉, \
         {CONFIRM_MAX_STEPS}) steps (at least {CONFIRM_MIN_STEPS}) without divergence (NaN, \
         |v| > 1000 m/s, a failed implicit solve), with an energy rise E - E0 that never \
         exceeds {CONFIRM_EXPLOSION_SCALES} S and does not end above {CONFIRM_ENERGY_SCALES} S = \
         {:.4e} J while still growing ({CONFIRM_GROWTH}× from the run's second quarter to its \
         last) or stay above it through the last quarter",
        linear::TOLERANCE,
        CONFIRM_ENERGY_SCALES * scale
    )
}

/// The `--set` assignments the study applies before the user's: `amplitude=1e-6` for the
/// built-in oscillator, so that the linearisation about its initial state is the linear
/// oscillator (a spring stretched by 0.1 m has a transverse stiffness, and the motion of the
/// state it is linearised about would enter the Jacobian); none for other scenes.
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

/// The energy scale `S` of `scene` (J): `Σ m |g| ℓ + E_kinetic + E_elastic` at the start, `ℓ`
/// the diagonal of each body's bounding box (module docs).
#[must_use]
pub fn energy_scale(scene: &Scene) -> f64 {
    let mut scale = 0.0;
    for b in &scene.bodies {
        let (lo, hi) = b.state.x.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), x| (lo.min(*x), hi.max(*x)),
        );
        let extent = if b.state.x.is_empty() {
            0.0
        } else {
            (hi - lo).length()
        };
        let g = b.model.gravity.length();
        let free_mass: f64 = (0..b.model.particle_count())
            .filter(|&i| !b.model.is_pinned(i))
            .map(|i| b.model.mass[i])
            .sum();
        let spheres: f64 = b
            .state
            .spheres
            .iter()
            .filter(|s| !s.kinematic)
            .map(|s| s.mass)
            .sum();
        let e = energy(&b.model, &b.state);
        scale += (free_mass + spheres) * g * extent + e.kinetic + e.elastic;
    }
    scale
}

/// The largest stable `dt` of one method on a scene, for library callers: the study of
/// [`stability`] for that method alone, with the default horizon and confirmation.
/// `Ok(None)` when the method is stable at every `dt` probed (unconditional).
///
/// # Errors
/// As [`stability`]; a method with no stable `dt` gives `Ok(Some(0.0))`.
pub fn max_stable_dt(scene: &Scene, method: Method) -> Result<Option<f64>, StudyError> {
    let options = StabilityOptions {
        methods: vec![method],
        ..StabilityOptions::default()
    };
    let report = stability(scene, &options, &mut |_, _| {})?;
    let m = &report.methods[0];
    Ok(match m.stability {
        Stability::Unconditional => None,
        Stability::None => Some(0.0),
        Stability::Conditional => m.max_stable_dt,
    })
}

/// Measures the largest stable `dt` of each method of `options` on `scene` (see the module
/// documentation). Calls `progress` after every linear probe.
///
/// # Errors
/// A horizon that is not positive and finite, no method, a scene without stiffness, or a
/// horizon so long that a probe would exceed [`MAX_STEPS`].
pub fn stability(
    scene: &Scene,
    options: &StabilityOptions,
    progress: &mut dyn FnMut(Method, &Probe),
) -> Result<StabilityReport, StudyError> {
    stability_with(scene, options, progress, &mut |_, _| {})
}

/// Counts a job out of [`Context::busy`] when it ends.
struct Leave<'a>(&'a AtomicUsize);

impl Drop for Leave<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

/// One job of [`stability_with`]: a method's search, or the stiffest state.
enum Job {
    Method(Box<MethodLimit>),
    Stiffest((StiffestState, usize, theory::Spectrum)),
}

/// [`stability`], also calling `event(method, …)` as each method's search starts and as it
/// ends (on the calling thread, while the others run: a terminal's progress).
///
/// # Errors
/// As [`stability`].
pub fn stability_with(
    scene: &Scene,
    options: &StabilityOptions,
    progress: &mut dyn FnMut(Method, &Probe),
    event: &mut dyn FnMut(Method, JobEvent),
) -> Result<StabilityReport, StudyError> {
    let horizon = options.horizon;
    if !(horizon > 0.0 && horizon.is_finite()) {
        return Err(StudyError::Horizon(horizon));
    }
    if options.methods.is_empty() {
        return Err(StudyError::NoMethods);
    }
    // The stiffest body sets ω_max.
    let estimates: Vec<_> = scene
        .bodies
        .iter()
        .map(|b| omega_max(&b.model, &b.state))
        .collect();
    let Some((stiffest, estimate)) = estimates
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.omega.total_cmp(&b.1.omega))
        .filter(|(_, e)| e.omega > 0.0 && e.omega.is_finite())
    else {
        return Err(StudyError::NoStiffness(scene.name.clone()));
    };
    let omega = estimate.omega;
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
    let body = &scene.bodies[stiffest];
    let spectrum = theory::spectrum(&body.model, &body.state, omega);
    let scale = energy_scale(scene);
    let context = Context {
        scene,
        omega,
        horizon,
        scale,
        confirm: options.confirm,
        usable: options.usable,
        linear: scene
            .bodies
            .iter()
            .zip(&estimates)
            .map(|(b, e)| Linearisation::new(&b.model, &b.state, e.omega.max(omega * 1e-9)))
            .collect(),
        busy: AtomicUsize::new(0),
        threads: crate::physics::pool::Pool::global().threads(),
    };
    let hanging = spectrum_at_equilibrium(&body.model, &body.state);
    // The methods are independent: one job each, spread over the cores (the results do not
    // depend on the thread that computes them); the probes are reported after each job. The
    // stiffest state (one run of the scene, a power iteration every 5 ms, a chain of warm
    // starts that cannot be split) is one more job beside them, started first: only the
    // report needs it.
    let count = options.methods.len();
    // Each job steps its simulations on its own thread alone (`pool::independent`).
    let job = |i: usize| {
        context.busy.fetch_add(1, Ordering::SeqCst);
        let _done = Leave(&context.busy);
        let Some(&m) = options.methods.get(i) else {
            return Job::Stiffest(stiffest_state(scene, horizon, (stiffest, omega)));
        };
        let damped = theory::limit(m, &body.params, &spectrum);
        let at_equilibrium = hanging
            .as_ref()
            .ok()
            .map(|(spectrum, _)| theory::limit(m, &body.params, spectrum));
        let mut limit = context.search(m, damped, at_equilibrium.as_ref());
        limit.equilibrium_theory = at_equilibrium;
        Job::Method(Box::new(limit))
    };
    let threads = context.threads;
    // Longest first, so that no long search starts last (the order changes no result): the
    // work of a step, times, with the usable dt searched, its steps: the energy error of an
    // order-p method grows as dt^p, so a usable dt for a 1 % error lies about 100^(1/p) below
    // the stable one (measured on jelly-bowl: explicit Euler's search takes ten times the steps
    // of semi-implicit Euler's). The stiffest state, one chain, starts first.
    let weight = |i: usize| match options.methods.get(i) {
        Some(m) => {
            let d = m.declaration();
            let usable = options.usable && !matches!(d.oscillator, OscillatorLimit::Unconditional);
            let steps = if usable {
                100f64.powf(1.0 / f64::from(d.order.max(1)))
            } else {
                1.0
            };
            (d.evaluations)(&body.params) * steps
        }
        None => f64::INFINITY,
    };
    let mut jobs = crate::physics::pool::independent(count + 1, threads, weight, job, |i, e| {
        if let Some(&m) = options.methods.get(i) {
            event(m, e);
        }
    });
    let Some(Job::Stiffest((stiffest_state, stiffest_body, stiffest_spectrum))) = jobs.pop() else {
        unreachable!("the last job is the stiffest state")
    };
    let methods: Vec<MethodLimit> = jobs
        .into_iter()
        .filter_map(|j| match j {
            Job::Method(limit) => Some(*limit),
            Job::Stiffest(_) => None,
        })
        .map(|mut limit| {
            let at_stiffest = theory::limit(
                limit.method,
                &scene.bodies[stiffest_body].params,
                &stiffest_spectrum,
            );
            limit.stiffest_theory_dt = at_stiffest.dt;
            limit.stiffest_theory = at_stiffest;
            limit
        })
        .collect();
    for m in &methods {
        for p in &m.probes {
            progress(m.method, p);
        }
    }
    Ok(StabilityReport {
        scene: scene.name.clone(),
        sets: Vec::new(),
        omega_max: omega,
        omega_method: estimate.method,
        omega_gershgorin: estimate.gershgorin_omega,
        omega_iterations: estimate.iterations,
        horizon,
        criterion: "linear growth, confirmed by a run",
        definition: definition(horizon, scale),
        energy_scale: scale,
        theory_spectrum: spectrum.how,
        stiffest_state,
        equilibrium: hanging.as_ref().ok().map(|(_, e)| e.clone()),
        equilibrium_spectrum: match &hanging {
            Ok((spectrum, _)) => spectrum.how.clone(),
            Err(why) => format!("not computed: {why}"),
        },
        dt_omega_range: [DT_OMEGA_FLOOR, DT_OMEGA_CEILING],
        methods,
    })
}

/// What every probe of one study shares.
struct Context<'a> {
    scene: &'a Scene,
    omega: f64,
    horizon: f64,
    scale: f64,
    confirm: bool,
    usable: bool,
    linear: Vec<Linearisation>,
    /// The study's jobs running now, and the cores they may use.
    busy: AtomicUsize,
    threads: usize,
}

impl Context<'_> {
    /// The search of the module documentation for one method.
    fn search(
        &self,
        method: Method,
        damped: TheoryLimit,
        at_equilibrium: Option<&TheoryLimit>,
    ) -> MethodLimit {
        let (theory_class, theory_dt_omega) = theory(method);
        let mut probes = Vec::new();
        let mut stable_at = |z: f64| {
            let p = self.probe(method, z / self.omega);
            let stable = p.stable;
            probes.push(p);
            stable
        };
        let (linear_stability, linear_z) = self.linear_search(&mut stable_at, &damped, method);
        let mut result = MethodLimit {
            method,
            stability: linear_stability,
            max_stable_dt: None,
            limit_dt_omega: None,
            linear_stability,
            linear_max_dt: linear_z.map(|z| z / self.omega),
            linear_dt_omega: linear_z,
            theory_dt: damped.dt,
            stiffest_theory_dt: damped.dt,
            stiffest_theory: damped.clone(),
            damped_theory: damped,
            theory_dt_omega,
            theory: theory_class,
            probes,
            confirmations: Vec::new(),
            equilibrium_theory: None,
            classed_by_equilibrium: false,
            usable: None,
        };
        let candidate = match linear_stability {
            Stability::None => return result,
            Stability::Conditional => linear_z.unwrap_or(DT_OMEGA_FLOOR),
            Stability::Unconditional => DT_OMEGA_CEILING,
        };
        if self.confirm {
            let (stability, z) =
                self.confirm_search(method, candidate, linear_stability, &mut result);
            result.stability = stability;
            result.limit_dt_omega = z;
            result.max_stable_dt = z.map(|z| z / self.omega);
        } else {
            result.max_stable_dt = linear_z.map(|z| z / self.omega);
            result.limit_dt_omega = linear_z;
        }
        // Linearised where the scene hangs, a method can be unstable at every dt (pendulum
        // modes that no along-spring damper damps): that class wins over the one at rest.
        if at_equilibrium.is_some_and(|t| t.stability == "none")
            && result.stability != Stability::None
        {
            result.stability = Stability::None;
            result.max_stable_dt = None;
            result.limit_dt_omega = None;
            result.classed_by_equilibrium = true;
        }
        if self.usable {
            let start = match result.stability {
                Stability::None => None,
                Stability::Conditional => result.max_stable_dt,
                Stability::Unconditional => Some(DT_OMEGA_CEILING / self.omega),
            };
            // A helper computes this search's likely next runs while a core is free (the
            // other methods' searches have ended): the same runs and result.
            let helpers = usize::from(self.threads > 1);
            let idle = || self.busy.load(Ordering::SeqCst) < self.threads;
            result.usable = start
                .map(|dt| usable::usable_ahead(self.scene, method, dt, self.scale, helpers, &idle));
        }
        result
    }

    /// Steps 1–3 of the search: the linear class and limit `z`.
    fn linear_search(
        &self,
        stable_at: &mut dyn FnMut(f64) -> bool,
        damped: &TheoryLimit,
        method: Method,
    ) -> (Stability, Option<f64>) {
        if stable_at(DT_OMEGA_CEILING) {
            return (Stability::Unconditional, None);
        }
        let start = damped
            .dt_omega
            .or(theory(method).1)
            .unwrap_or(1.0)
            .clamp(DT_OMEGA_FLOOR, DT_OMEGA_CEILING);
        // The damped theory agrees with the measurement within 0.1 % on the course scenes:
        // bracket its limit first, one bisection tolerance below it, then up by the tolerance
        // (at most three times); the general search below when that does not settle it.
        if damped.dt_omega.is_some() {
            let mut stable = start * (1.0 - BISECTION_TOLERANCE);
            if stable_at(stable) {
                for _ in 0..3 {
                    let z = stable * (1.0 + BISECTION_TOLERANCE);
                    if !stable_at(z) {
                        return (Stability::Conditional, Some(stable));
                    }
                    stable = z;
                }
            }
        }
        let mut unstable = DT_OMEGA_CEILING;
        let mut stable;
        if stable_at(start) {
            stable = start;
            let mut factor = 1.05;
            let mut tries = 0;
            while stable * factor < unstable {
                let z = stable * factor;
                if stable_at(z) {
                    stable = z;
                    tries += 1;
                    if tries >= 2 {
                        factor = 2.0;
                    }
                } else {
                    unstable = z;
                    break;
                }
            }
        } else {
            unstable = start;
            let mut factor = 1.05;
            let mut tries = 0;
            loop {
                if unstable <= DT_OMEGA_FLOOR {
                    return (Stability::None, None);
                }
                let z = (unstable / factor).max(DT_OMEGA_FLOOR);
                if stable_at(z) {
                    stable = z;
                    break;
                }
                unstable = z;
                tries += 1;
                if tries >= 2 {
                    factor = 4.0;
                }
            }
        }
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
        (Stability::Conditional, Some(stable))
    }

    /// Step 4: confirm `z`, else lower it until a run passes and bisect to 0.5 %; then check that a
    /// run at 95 % of the result passes too (nonlinear resonances are not monotone in `dt`),
    /// and search below it when it does not.
    fn confirm_search(
        &self,
        method: Method,
        candidate: f64,
        linear: Stability,
        result: &mut MethodLimit,
    ) -> (Stability, Option<f64>) {
        // A helper confirms the likely next dt ahead while a core is free (the other
        // methods' searches have ended): the same runs and result.
        let compute = |bits: &u64, cancel: &ahead::Cancel| {
            let dt = f64::from_bits(*bits) / self.omega;
            let steps = confirm_step_count(dt, self.horizon);
            confirm_unless(
                self.scene, method, dt, steps, self.scale, self.omega, cancel,
            )
        };
        let helpers = usize::from(self.threads > 1);
        let idle = || self.busy.load(Ordering::SeqCst) < self.threads;
        let searched = ahead::with_helpers_when(helpers, &compute, &idle, |ahead| {
            let mut run = |z: f64, next: &[f64]| {
                ahead.hint(next.iter().map(|z| z.to_bits()).collect());
                let c = ahead.get(&z.to_bits());
                let passed = c.passed;
                result.confirmations.push(c);
                passed
            };
            let mut failed = candidate;
            let first = CONFIRM_MARGIN * candidate;
            let mut passed = if run(candidate, &[first]) {
                candidate
            } else {
                below(&mut run, &mut failed)?
            };
            for _ in 0..CONFIRM_ROUNDS {
                let check = CONFIRM_MARGIN * passed;
                if run(check, &[check * 0.95]) {
                    break;
                }
                failed = check;
                passed = below(&mut run, &mut failed)?;
            }
            Some(passed)
        });
        let Some(passed) = searched else {
            return (Stability::None, None);
        };
        if passed == candidate && linear == Stability::Unconditional {
            return (Stability::Unconditional, None);
        }
        (Stability::Conditional, Some(passed))
    }

    /// One linear probe of `method` at `dt` (s): the worst body.
    fn probe(&self, method: Method, dt: f64) -> Probe {
        let planned = ((self.horizon / dt).ceil() as u64).max(GROWTH_MIN_STEPS);
        let mut worst: Option<linear::Growth> = None;
        for (lin, body) in self.linear.iter().zip(&self.scene.bodies) {
            let g = lin.growth(method, &body.params, dt, planned);
            if worst
                .is_none_or(|w| (w.stable && !g.stable) || (w.stable == g.stable && g.rho > w.rho))
            {
                worst = Some(g);
            }
        }
        let g = worst.unwrap_or(linear::Growth {
            steps: 0,
            stable: true,
            rho: 1.0,
            ratio: None,
            stopped: "decayed",
        });
        Probe {
            dt,
            dt_omega: dt * self.omega,
            steps: g.steps,
            stable: g.stable,
            growth: g.ratio,
            rho: g.rho,
            stopped: g.stopped,
        }
    }
}
