//! The study's report: one linear probe, one confirmation run, one method's result, the
//! stiffest state, the whole report, and the options (what `study stability --json` prints).

use serde::Serialize;

use super::usable::Usable;
use super::{DEFAULT_HORIZON, Stability};
use crate::physics::Method;
use crate::study::theory::TheoryLimit;
use crate::study::theory::equilibrium::Equilibrium;

/// One linear probe: the perturbation growth at one time step.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Probe {
    /// Time step (s).
    pub dt: f64,
    /// `dt·ω_max` (dimensionless).
    pub dt_omega: f64,
    /// Power steps taken (fewer than planned when the growth or decay was decisive).
    pub steps: u64,
    /// The verdict.
    pub stable: bool,
    /// `Ē_late / Ē_early` when the probe went to the end, else null.
    pub growth: Option<f64>,
    /// The estimated spectral radius of the step map (per step).
    pub rho: f64,
    /// Why the probe stopped: `window`, `grew`, `decayed`, `not finite`.
    pub stopped: &'static str,
}

/// One confirmation run of the whole scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Confirmation {
    /// Time step (s).
    pub dt: f64,
    /// `dt·ω_max`.
    pub dt_omega: f64,
    /// Steps taken.
    pub steps: u64,
    /// The verdict.
    pub passed: bool,
    /// Why it failed, or null.
    pub reason: Option<String>,
    /// The largest rise of the energy above its start, `E - E_0` (J); null when the energy is
    /// not checked (a driven sphere does work).
    pub rise_max: Option<f64>,
    /// The rise that counts when it keeps growing, `10 S` (J); null when not checked.
    pub rise_allowed: Option<f64>,
}

/// The result for one method.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodLimit {
    /// The method.
    pub method: Method,
    /// Stability class after confirmation.
    pub stability: Stability,
    /// Largest stable time step, confirmed (s); null when none or unconditional.
    pub max_stable_dt: Option<f64>,
    /// `max_stable_dt · ω_max`; null when none or unconditional.
    pub limit_dt_omega: Option<f64>,
    /// Stability class by the linear criterion alone.
    pub linear_stability: Stability,
    /// Largest linearly stable time step (s); null when none or unconditional.
    pub linear_max_dt: Option<f64>,
    /// `linear_max_dt · ω_max`.
    pub linear_dt_omega: Option<f64>,
    /// The damped theory's limit (s); null unless conditional.
    pub theory_dt: Option<f64>,
    /// The damped theory for this scene: class, limit, binding mode and how it was obtained.
    pub damped_theory: TheoryLimit,
    /// The damped theory linearised at the scene's stiffest state ([`StiffestState`]) (s);
    /// null unless conditional there.
    pub stiffest_theory_dt: Option<f64>,
    /// That theory in full: class, limit, binding mode, how it was obtained.
    pub stiffest_theory: TheoryLimit,
    /// The limit `dt·ω` on the undamped oscillator; null when none or unconditional.
    pub theory_dt_omega: Option<f64>,
    /// The stability class on the undamped oscillator.
    pub theory: Stability,
    /// Every linear probe, in the order taken.
    pub probes: Vec<Probe>,
    /// Every confirmation run, in the order taken.
    pub confirmations: Vec<Confirmation>,
    /// The damped theory linearised at the static equilibrium the scene hangs at (gravity and
    /// tension included, [`crate::study::theory::equilibrium`]); null when the body does not
    /// hang (no pinned particle) or is above the dense limit.
    pub equilibrium_theory: Option<TheoryLimit>,
    /// True when the stability class is `none` because the theory at the equilibrium says so
    /// (the class at rest, and any scene limit measured there, are overruled).
    pub classed_by_equilibrium: bool,
    /// The usable dt ([`super::usable`]): the largest dt whose energy residual stays within 1 %
    /// of `|E_0|` over the scene's duration; null when not searched (`usable` off, or no
    /// stable dt).
    pub usable: Option<Usable>,
}

/// The stiffest state of the scene along a run (module docs, "Linear, scene, and the stiffest
/// state"): the scene with its own methods and `dt` over the horizon, `ω_max` of every body
/// sampled every [`STIFFEST_SAMPLE_INTERVAL`](super::STIFFEST_SAMPLE_INTERVAL) seconds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StiffestState {
    /// The method of the body whose state it is (the scene's own).
    pub method: Method,
    /// The run's time step (s): the scene's own.
    pub dt: f64,
    /// Samples taken (each body at each sampled step).
    pub samples: u64,
    /// When `ω_max` was largest (s).
    pub time: f64,
    /// The largest `ω_max` of the run (rad/s), the power iteration's lower bound.
    pub omega_max: f64,
    /// `omega_max / ω_max` at the start.
    pub ratio: f64,
    /// How the damped theory at that state was obtained.
    pub theory_spectrum: String,
    /// Why the run ended before the horizon (a divergence of the scene's own method), or null.
    pub stopped: Option<String>,
}

/// What `springlab study stability --json` prints.
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
    /// The criterion, by name.
    pub criterion: &'static str,
    /// What "stable" means, in words.
    pub definition: String,
    /// The energy scale `S` of the confirmation (J).
    pub energy_scale: f64,
    /// How the damped theory's spectrum was obtained.
    pub theory_spectrum: String,
    /// Where along a run of the whole scene the stiffest mode is stiffest (module docs).
    pub stiffest_state: StiffestState,
    /// The static equilibrium the stiffest body hangs at, when it hangs (module docs of
    /// [`crate::study::theory::equilibrium`]).
    pub equilibrium: Option<Equilibrium>,
    /// How the damped theory at the equilibrium was obtained, or why it was not.
    pub equilibrium_spectrum: String,
    /// The range of `dt·ω_max` probed, `[floor, ceiling]`.
    pub dt_omega_range: [f64; 2],
    /// One entry per method, in the order asked for.
    pub methods: Vec<MethodLimit>,
}

/// Options of [`stability`](super::stability()).
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityOptions {
    /// The methods to study, in order.
    pub methods: Vec<Method>,
    /// Horizon `T` (s), > 0.
    pub horizon: f64,
    /// Run the confirmation (default true); without it the linear limit is reported.
    pub confirm: bool,
    /// Search the usable dt below the scene limit ([`super::usable`]; default false: it runs
    /// the whole scene over its duration several times per method; the command turns it on).
    pub usable: bool,
}

impl Default for StabilityOptions {
    /// Every method, a 2 s horizon, with confirmation.
    fn default() -> StabilityOptions {
        StabilityOptions {
            methods: Method::ALL.to_vec(),
            horizon: DEFAULT_HORIZON,
            confirm: true,
            usable: false,
        }
    }
}
