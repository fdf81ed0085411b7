//! The cheapest model, method and time step for an accuracy: `springlab advise`.
//!
//! # The question
//!
//! Given a scene, its observable ([`super::observe`]: the jelly's centroid and compression, the
//! cloth's sag and contact time, a rope's end point) at a time `T`, and a tolerance `X` (m for
//! positions and lengths, s for times), find the configuration — resolution and spring kinds
//! ([`super::resolution`]), method, time step — of least cost whose observable is within `X`
//! of the true answer and whose time step has a stability margin of at least 1.5.
//!
//! # The reference
//!
//! The finest resolution considered, with every spring kind, run by RK4 at `dt_0`, `dt_0/2`,
//! `dt_0/4`, … (`dt_0` = RK4's damped-theory limit / 1.5) until two successive runs differ by
//! at most `X/4` at every one of the 20 sample instants (at most [`REFERENCE_HALVINGS`]
//! halvings). The last run is the reference; the last difference `e_ref` estimates its own
//! error (it bounds it when the runs converge monotonically at order ≥ 1). The runs of this
//! chain are also RK4's candidates at that resolution.
//!
//! # The search
//!
//! ```text
//! for each resolution, coarse to fine; each kinds variant (all, no bend, no shear);
//!   each method, cheapest step first:
//!     dt_max = limit / 1.5          limit: the damped theory's (conditional methods), the
//!                                   confirmed stability study's where the theory does not
//!                                   cover the method; implicit Euler: T / 20
//!     for dt = dt_max, dt_max/2, … (at most MAX_HALVINGS halvings):
//!         bound = the cheapest accepted so far, or the reference run's cost
//!         skip if its cost ≥ bound
//!         run; err = max_k d(O(t_k), O_ref(t_k))   over the 20 instants t_k = k T/20
//!         accept if err + e_ref ≤ X (per unit)
//!         reject the resolution and kinds if err - 2 d(O, O_previous dt) > X
//!                                   (the time step's error cannot explain the rest: the model
//!                                    itself is too coarse)
//!         stop if the error falls by r = err_previous/err ≥ 1.2 per halving and the
//!         h = log(err/X)/log r halvings it still needs would cost ≥ bound: cost · 2^h ≥ bound
//! ```
//! The error is taken over the whole run, not only at `T`: an observable that crosses the
//! reference's at `T` by chance (a jelly that tumbles a little late and catches up) is not
//! within `X`. The last two rules prune the search for the cheapest, never the correctness of
//! what is accepted: an accepted configuration is always measured. Cost is counted in particle
//! and spring updates ([`super::observe::cost`]), repeatable on any machine; wall time is
//! printed beside it. The whole search stops when its work reaches [`SEARCH_CAP`] times the
//! reference run's.
//!
//! # The verification
//!
//! Re-running the accepted configuration would only repeat a deterministic run. The check is
//! made with runs the search did not make: the cheapest accepted configuration holds when
//! 1. **its time step is converged**: the same model and method at `dt/2` (energy accounting on,
//!    as `springlab run` runs it) is also within `X` of the reference (with `e_ref`) at every
//!    one of the 20 sample instants, so the acceptance is not a chance agreement of one `dt`
//!    with the reference; the change from `dt` to `dt/2` (the configuration's own time-step
//!    error, to first order) is printed; and
//! 2. the whole scene, contacts included, runs stably at 1.5 × its `dt` up to `T`
//!    ([`super::stability::confirm_steps`]: no divergence, no energy that keeps rising): the
//!    margin holds for the scene, not only for the linear theory, which is linearised at the
//!    initial state and does not see an impact stiffen the body.
//!
//! What this does not verify: the model's own error is measured against the reference, which is
//! RK4 on the finest model; the reference's error `e_ref` is estimated from its own chain.
//!
//! If it does not hold, the next cheapest accepted configuration is verified (at most
//! [`MAX_VERIFICATIONS`]).

use std::time::Instant;

use serde::Serialize;

use super::StudyError;
use super::observe::{self, Difference, Measurement, Observable};
use super::resolution::{Kinds, Refinement, TheoryDt, theory_dts};
use super::stability::{self, Confirmation};
use crate::budget::{self, Limits};
use crate::physics::Method;
use crate::scene::{self, Scene};

mod outlook;
mod search;
pub use search::advise;

/// The stability margin every recommended `dt` keeps: `limit / dt ≥ MARGIN`.
pub const MARGIN: f64 = 1.5;
/// Halvings of `dt` per (resolution, kinds, method).
pub const MAX_HALVINGS: u32 = 8;
/// Halvings of the reference's `dt`.
pub const REFERENCE_HALVINGS: u32 = 5;
/// The reference chain stops when successive runs differ by at most this fraction of `X`.
pub const REFERENCE_FRACTION: f64 = 0.25;
/// The search's work is capped at this many times the reference run's cost.
pub const SEARCH_CAP: f64 = 3.0;
/// The error must fall by at least this factor per halving for its trend to prune a method.
pub const PROJECTION_RATIO: f64 = 1.2;
/// At most this many configurations are verified.
pub const MAX_VERIFICATIONS: usize = 3;

/// Options of `springlab advise`.
#[derive(Clone, Debug, PartialEq)]
pub struct AdviseOptions {
    /// The tolerance `X` (m for positions and lengths, s for times).
    pub tolerance: f64,
    /// When the observable is taken (s); `None`: [`super::resolution::default_time`].
    pub time: Option<f64>,
    /// Methods to consider, in any order.
    pub methods: Vec<Method>,
    /// Resolutions to consider; `None`: the scene's own and three coarser ones.
    pub levels: Option<Vec<i64>>,
    /// Also consider dropping the bend and the shear springs.
    pub kinds: bool,
}

/// The methods considered by default: all but XPBD, whose margin needs the confirmed stability
/// study (slow on large scenes); `--methods` can add it.
pub const DEFAULT_METHODS: [Method; 7] = [
    Method::SemiImplicitEuler,
    Method::ExplicitEuler,
    Method::Verlet,
    Method::Midpoint,
    Method::PredictorCorrector,
    Method::Rk4,
    Method::ImplicitEuler,
];

impl Default for AdviseOptions {
    fn default() -> AdviseOptions {
        AdviseOptions {
            tolerance: super::resolution::DEFAULT_TOLERANCE,
            time: None,
            methods: DEFAULT_METHODS.to_vec(),
            levels: None,
            kinds: true,
        }
    }
}

/// One model the search considers: a resolution and spring kinds.
#[derive(Clone, Debug)]
pub struct Model {
    /// The resolution (`n` or `nodes`), `None` for a scene that cannot be refined.
    pub n: Option<i64>,
    /// The spring kinds.
    pub kinds: Kinds,
    /// The scene.
    pub scene: Scene,
    /// The `--set` assignments that make it (the user's first).
    pub sets: Vec<String>,
}

/// What [`plan`] prepares: the models, coarse to fine, the reference's index and `T`.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Scene name or path.
    pub scene: String,
    /// The user's assignments.
    pub sets: Vec<String>,
    /// The resolution parameter, when the scene can be refined.
    pub key: Option<&'static str>,
    /// How a level keeps the body, in words.
    pub refinement: Option<String>,
    /// The models in search order.
    pub models: Vec<Model>,
    /// Index of the reference model in `models` (the finest, every kind).
    pub reference: usize,
    /// When the observable is taken (s).
    pub time: f64,
    /// The options.
    pub options: AdviseOptions,
    /// The steps of the reference chain's first run.
    pub reference_steps: u64,
    /// The damped theory's limit of each considered method and of RK4 on the reference model
    /// (one spectrum, computed once for the plan and the search).
    pub reference_theory: Vec<(Method, TheoryDt)>,
}

/// Validates the options and builds every model within `limits`.
///
/// # Errors
/// Bad tolerance, time, levels or methods; a scene that does not load.
pub fn plan(
    name: &str,
    sets: &[String],
    options: &AdviseOptions,
    limits: &Limits,
) -> Result<Plan, StudyError> {
    if !(options.tolerance > 0.0 && options.tolerance.is_finite()) {
        return Err(StudyError::Tolerance(options.tolerance));
    }
    if options.methods.is_empty() {
        return Err(StudyError::NoMethods);
    }
    let time = options
        .time
        .unwrap_or_else(|| super::resolution::default_time(name));
    if !(time > 0.0 && time.is_finite()) {
        return Err(StudyError::Time(time));
    }
    let refinement = Refinement::of(name, sets)?;
    let mut models = Vec::new();
    let (key, rule) = match &refinement {
        Some(r) => {
            let mut levels = match &options.levels {
                Some(l) => l.clone(),
                None => match r.dimension {
                    super::resolution::Dimension::Line => r.default_levels(2, 0),
                    _ => r.default_levels(3, 0),
                },
            };
            levels.sort_unstable();
            levels.dedup();
            let min = r.dimension.min();
            if let Some(&bad) = levels.iter().find(|&&n| n < min) {
                return Err(StudyError::Resolutions(format!(
                    "{} = {bad}: expected whole numbers ≥ {min}",
                    r.dimension.key()
                )));
            }
            if levels.is_empty() {
                return Err(StudyError::Resolutions(
                    "expected at least one resolution".into(),
                ));
            }
            for &n in &levels {
                let variants: &[Kinds] = if options.kinds {
                    &[Kinds::All, Kinds::NoBend, Kinds::NoShear]
                } else {
                    &[Kinds::All]
                };
                for &kinds in variants {
                    if !r.has_kind(kinds) {
                        continue;
                    }
                    models.push(Model {
                        n: Some(n),
                        kinds,
                        scene: r.scene(n, kinds, limits)?,
                        sets: r.sets_for(n, kinds),
                    });
                }
            }
            (
                Some(r.dimension.key()),
                Some(r.dimension.rule().to_string()),
            )
        }
        None => {
            if options.levels.is_some() {
                return Err(StudyError::Resolutions(format!(
                    "scene `{name}` cannot be refined (only built-in scenes with `n` or `nodes`)"
                )));
            }
            models.push(Model {
                n: None,
                kinds: Kinds::All,
                scene: scene::load_with(name, sets, limits)?,
                sets: sets.to_vec(),
            });
            (None, None)
        }
    };
    // The reference: the finest resolution with every kind (the last `All`).
    let reference = models
        .iter()
        .rposition(|m| m.kinds == Kinds::All)
        .unwrap_or(0);
    let mut theory_methods = search::search_order(&options.methods);
    if !theory_methods.contains(&Method::Rk4) {
        theory_methods.push(Method::Rk4);
    }
    let reference_theory: Vec<(Method, TheoryDt)> = theory_methods
        .iter()
        .copied()
        .zip(theory_dts(&models[reference].scene, &theory_methods))
        .collect();
    let rk4_theory = reference_theory
        .iter()
        .find(|(m, _)| *m == Method::Rk4)
        .map_or(TheoryDt::None, |&(_, t)| t);
    let reference_steps = match rk4_theory {
        TheoryDt::Conditional { dt } => observe::steps_for(time, (dt / MARGIN).min(time)),
        TheoryDt::None => {
            return Err(StudyError::Scene(scene::SceneError::Invalid(format!(
                "RK4, the reference method, has no stable time step on `{name}`"
            ))));
        }
        _ => observe::steps_for(time, models[reference].scene.dt.min(time)),
    };
    Ok(Plan {
        scene: name.to_string(),
        sets: sets.to_vec(),
        key,
        refinement: rule,
        models,
        reference,
        time,
        options: options.clone(),
        reference_steps,
        reference_theory,
    })
}

/// The budget estimate of a plan ([`budget::advise`]): an upper bound — the reference chain's
/// [`REFERENCE_HALVINGS`] halvings, the search's cap, and the verifications.
#[must_use]
pub fn estimate(what: impl Into<String>, plan: &Plan) -> budget::Estimate {
    let scenes: Vec<&Scene> = plan.models.iter().map(|m| &m.scene).collect();
    budget::advise(
        what,
        &plan.models[plan.reference].scene,
        &scenes,
        plan.time,
        plan.reference_steps as f64,
        REFERENCE_HALVINGS,
        SEARCH_CAP,
        MAX_VERIFICATIONS as f64,
        MARGIN,
        (plan.models.len() * plan.options.methods.len()) as f64 * f64::from(MAX_HALVINGS + 1),
    )
}

/// Why a candidate was or was not accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Within the tolerance with the margin: a candidate.
    Meets,
    /// Measured, but its error is above the tolerance.
    TooInaccurate,
    /// The run diverged.
    Diverged,
    /// Not run: it would cost as much as an accepted candidate or the reference.
    Costlier,
    /// Measured, above the tolerance, and the halvings its error trend still needs would cost
    /// as much as an accepted candidate or the reference.
    ProjectedCostlier,
    /// The model's own error exceeds the tolerance: no method or step can fix it.
    ModelTooCoarse,
    /// The method has no stable step on this model.
    NoStableDt,
    /// Not run: the search reached its cap.
    OverCap,
}

impl Verdict {
    /// The word in the table.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Meets => "meets",
            Verdict::TooInaccurate => "error > X",
            Verdict::Diverged => "diverged",
            Verdict::Costlier => "skipped: costs more than the best so far or the reference",
            Verdict::ProjectedCostlier => "error > X; reaching X would cost more",
            Verdict::ModelTooCoarse => "model too coarse",
            Verdict::NoStableDt => "no stable dt (theory)",
            Verdict::OverCap => "skipped: search cap",
        }
    }
}

/// How a margin was established.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MarginKind {
    /// Damped theory limit / dt.
    Theory,
    /// Confirmed stability study limit / dt.
    Confirmed,
    /// Unconditionally stable by the theory (implicit Euler).
    Unconditional,
}

/// One configuration the search considered.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Candidate {
    /// Index of its model in the plan.
    pub model: usize,
    /// Resolution (`null` for a scene that cannot be refined).
    pub n: Option<i64>,
    /// Spring kinds.
    pub kinds: Kinds,
    /// Particles.
    pub particles: usize,
    /// Springs.
    pub springs: usize,
    /// The method.
    pub method: Method,
    /// Time step (s).
    pub dt: f64,
    /// Steps.
    pub steps: u64,
    /// Stability margin `limit / dt` (`null` when unconditional).
    pub margin: Option<f64>,
    /// How the margin was established.
    pub margin_kind: MarginKind,
    /// Cost in particle and spring updates (measured, or predicted when not run).
    pub cost: f64,
    /// Wall time (s), when run.
    pub wall_seconds: Option<f64>,
    /// Difference from the reference over the run (the largest at the 20 sample instants),
    /// when run and not diverged: what acceptance looks at.
    pub error: Option<Difference>,
    /// Difference from the reference at `T` alone.
    pub error_at_t: Option<Difference>,
    /// The verdict.
    pub verdict: Verdict,
    /// Why the run diverged, when it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diverged: Option<String>,
}

/// The reference and how it was reached.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Reference {
    /// Its model's resolution.
    pub n: Option<i64>,
    /// Method (RK4).
    pub method: Method,
    /// Its time step (s).
    pub dt: f64,
    /// Steps.
    pub steps: u64,
    /// Cost in updates.
    pub cost: f64,
    /// Each halving: `(dt, difference from the previous run over the whole run)`.
    pub chain: Vec<(f64, Option<Difference>)>,
    /// The estimate of its own error: the last difference (m and s).
    pub error: Difference,
    /// True when the chain reached `X/10` before its last halving.
    pub converged: bool,
    /// The observation.
    pub observation: Option<observe::Observation>,
}

/// One verification (module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Verification {
    /// Index of the verified candidate.
    pub candidate: usize,
    /// The time step of the check run (s): half the candidate's.
    pub dt: f64,
    /// The check run's largest difference from the reference over the 20 sample instants.
    pub error: Difference,
    /// The check run's difference from the reference at `T`.
    pub error_at_t: Difference,
    /// The largest difference between the candidate's run and the check run over the 20
    /// instants: the candidate's own time-step error (to first order).
    pub time_step_change: Difference,
    /// Whether the check run's `error + e_ref ≤ X` (per unit).
    pub accurate: bool,
    /// The confirmation run at 1.5 × dt.
    pub stability: Confirmation,
    /// Both.
    pub holds: bool,
    /// The energy error of the check run (J): `E + dissipated - E0` at `T`, with the energy
    /// accounting on.
    pub energy_residual: f64,
    /// The command that runs the configuration.
    pub command: String,
}

/// The result of [`advise`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AdviseReport {
    /// Scene name or path.
    pub scene: String,
    /// The user's assignments.
    pub sets: Vec<String>,
    /// When the observable is taken (s).
    pub time: f64,
    /// `X`.
    pub tolerance: f64,
    /// The unit of `X`, in words.
    pub tolerance_unit: &'static str,
    /// The observable, in words.
    pub observable: String,
    /// How a level keeps the body (refinable scenes).
    pub refinement: Option<String>,
    /// The resolution parameter (`n`, `nodes`), when refinable.
    pub key: Option<&'static str>,
    /// The margin rule, in words.
    pub margin_rule: String,
    /// The cost unit, in words.
    pub cost_unit: &'static str,
    /// The reference.
    pub reference: Reference,
    /// Every configuration considered, in search order.
    pub candidates: Vec<Candidate>,
    /// The recommended candidate (verified), or `null`.
    pub recommended: Option<usize>,
    /// The verifications made, in order.
    pub verifications: Vec<Verification>,
    /// The search's work (updates) and its cap.
    pub search_work: f64,
    /// The cap.
    pub search_cap: f64,
    /// Methods left out, with the reason.
    pub left_out: Vec<(Method, String)>,
    /// Wall time of the whole advice (s).
    pub wall_seconds: f64,
}

/// What X means.
pub const TOLERANCE_UNIT: &str = "metres for positions and lengths, seconds for times";

/// What the progress callback is told.
#[derive(Clone, Debug)]
pub enum Stage {
    /// A reference run at this dt (s).
    Reference(f64),
    /// A candidate run.
    Candidate {
        /// Resolution.
        n: Option<i64>,
        /// Kinds.
        kinds: Kinds,
        /// Method.
        method: Method,
        /// dt (s).
        dt: f64,
    },
    /// A verification of this method at this dt (s).
    Verify(Method, f64),
}
