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
//! The cheapest accepted configuration is run again as `springlab run` runs it (energy
//! accounting on), and it holds when
//! 1. its observable is within `X` of the reference's (with `e_ref`) at every one of the 20
//!    sample instants, `T` included; and
//! 2. the whole scene, contacts included, runs stably at 1.5 × its `dt` up to `T`
//!    ([`super::stability::confirm_steps`]: no divergence, no energy that keeps rising): the
//!    margin holds for the scene, not only for the linear theory, which is linearised at the
//!    initial state and does not see an impact stiffen the body.
//!
//! If it does not hold, the next cheapest accepted configuration is verified (at most
//! [`MAX_VERIFICATIONS`]).

use std::time::Instant;

use serde::Serialize;

use super::StudyError;
use super::observe::{self, Difference, Measurement, Observable};
use super::resolution::{Kinds, Refinement, TheoryDt, theory_dt};
use super::stability::{self, Confirmation};
use crate::budget::{self, Limits};
use crate::physics::Method;
use crate::scene::{self, Scene};

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
                    let sets = r.sets_for(n, kinds);
                    models.push(Model {
                        n: Some(n),
                        kinds,
                        scene: scene::load_with(name, &sets, limits)?,
                        sets,
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
    let reference_steps = match theory_dt(&models[reference].scene, Method::Rk4) {
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

/// One verification.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Verification {
    /// Index of the verified candidate.
    pub candidate: usize,
    /// Its largest difference from the reference over the 20 sample instants.
    pub error: Difference,
    /// Its difference from the reference at `T`.
    pub error_at_t: Difference,
    /// Whether `error + e_ref ≤ X` (per unit).
    pub accurate: bool,
    /// The confirmation run at 1.5 × dt.
    pub stability: Confirmation,
    /// Both.
    pub holds: bool,
    /// The energy error of the run (J): `E + dissipated - E0` with the energy accounting on.
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

/// Methods by cost per step, cheapest first (ties in teaching order).
fn search_order(methods: &[Method]) -> Vec<Method> {
    let mut m = methods.to_vec();
    let cost =
        |m: &Method| budget::evaluations_per_step(*m, &crate::physics::MethodParams::default());
    m.sort_by(|a, b| cost(a).total_cmp(&cost(b)));
    m
}

/// The margin limit of `method` on `scene`: `(limit dt, kind)`; `None` for no stable dt.
fn margin_limit(
    scene: &Scene,
    method: Method,
) -> Result<Option<(Option<f64>, MarginKind)>, StudyError> {
    Ok(match theory_dt(scene, method) {
        TheoryDt::Conditional { dt } => Some((Some(dt), MarginKind::Theory)),
        TheoryDt::Unconditional => Some((None, MarginKind::Unconditional)),
        TheoryDt::None => None,
        TheoryDt::NotCovered => match stability::max_stable_dt(scene, method)? {
            None => Some((None, MarginKind::Confirmed)),
            Some(dt) if dt > 0.0 => Some((Some(dt), MarginKind::Confirmed)),
            Some(_) => None,
        },
    })
}

/// Accepted when `err + e_ref ≤ X` in each unit.
fn accepted(error: &Difference, reference: &Difference, tolerance: f64) -> bool {
    error.metres + reference.metres <= tolerance && error.seconds + reference.seconds <= tolerance
}

/// The command line that runs a candidate.
fn command(plan: &Plan, c: &Candidate) -> String {
    let model = &plan.models[c.model];
    let mut line = format!(
        "springlab run {} --method {} --dt {:e} --time {}",
        plan.scene,
        c.method,
        c.dt,
        budget::short(plan.time)
    );
    for s in &model.sets {
        line.push_str(&format!(" --set {s}"));
    }
    line
}

/// Runs the plan (module docs). `progress` is called before every run.
///
/// # Errors
/// A confirmed stability study that fails (for methods the theory does not cover).
pub fn advise(plan: &Plan, progress: &mut dyn FnMut(&Stage)) -> Result<AdviseReport, StudyError> {
    let start = Instant::now();
    let time = plan.time;
    let x = plan.options.tolerance;
    let reference_model = &plan.models[plan.reference];

    // 1. The reference chain.
    let mut chain_runs: Vec<Measurement> = Vec::new();
    let mut chain: Vec<(f64, Option<Difference>)> = Vec::new();
    let mut converged = false;
    for k in 0..=REFERENCE_HALVINGS {
        let steps = plan.reference_steps << k;
        let dt = time / steps as f64;
        progress(&Stage::Reference(dt));
        let run = observe::measure(&reference_model.scene, Method::Rk4, dt, steps);
        let change = chain_runs
            .last()
            .map(|prev| observe::history_difference(&run.snapshots, &prev.snapshots, time));
        let done = change
            .as_ref()
            .is_some_and(|d| d.within(REFERENCE_FRACTION * x));
        chain.push((dt, change));
        chain_runs.push(run);
        if done {
            converged = true;
            break;
        }
    }
    let reference_run = chain_runs.last().cloned().unwrap_or_else(|| {
        observe::measure(&reference_model.scene, Method::Rk4, time, observe::SAMPLES)
    });
    let count = Observable::of(&reference_model.scene).names().len();
    let e_ref = chain
        .last()
        .and_then(|c| c.1.clone())
        .unwrap_or_else(|| Difference::infinite(count));
    let reference_obs = reference_run.observation.clone();
    let reference = Reference {
        n: reference_model.n,
        method: Method::Rk4,
        dt: reference_run.dt,
        steps: reference_run.steps,
        cost: reference_run.cost,
        chain,
        error: e_ref.clone(),
        converged,
        observation: reference_obs.clone(),
    };
    let cap = SEARCH_CAP * reference_run.cost;

    // 2. The search.
    let mut candidates: Vec<Candidate> = Vec::new();
    let mut best = f64::INFINITY;
    let mut work = 0.0;
    let mut left_out = Vec::new();
    if !plan.options.methods.contains(&Method::Xpbd) {
        left_out.push((
            Method::Xpbd,
            "not considered unless asked (--methods): no stability theory, and its confirmed \
             limit needs the whole stability study"
                .to_string(),
        ));
    }
    let Some(reference_obs) = reference_obs else {
        return Ok(report(
            plan,
            reference,
            candidates,
            None,
            Vec::new(),
            work,
            cap,
            left_out,
            start,
        ));
    };
    for (index, model) in plan.models.iter().enumerate() {
        let is_reference = index == plan.reference;
        let mut too_coarse = false;
        for method in search_order(&plan.options.methods) {
            let base = Candidate {
                model: index,
                n: model.n,
                kinds: model.kinds,
                particles: model.scene.particle_count(),
                springs: model.scene.spring_count(),
                method,
                dt: 0.0,
                steps: 0,
                margin: None,
                margin_kind: MarginKind::Theory,
                cost: 0.0,
                wall_seconds: None,
                error: None,
                error_at_t: None,
                verdict: Verdict::NoStableDt,
                diverged: None,
            };
            if too_coarse {
                // The model was judged with a cheaper method: nothing to run.
                continue;
            }
            let Some((limit, margin_kind)) = margin_limit(&model.scene, method)? else {
                candidates.push(base);
                continue;
            };
            let dt_max = match limit {
                Some(limit) => (limit / MARGIN).min(time),
                None => time / observe::SAMPLES as f64,
            };
            let first_steps = observe::steps_for(time, dt_max);
            let mut previous: Option<Measurement> = None;
            for k in 0..=MAX_HALVINGS {
                let steps = first_steps << k;
                let dt = time / steps as f64;
                let mut c = Candidate {
                    dt,
                    steps,
                    margin: limit.map(|l| l / dt),
                    margin_kind,
                    ..base.clone()
                };
                // RK4 at the reference model: the reference chain's runs.
                let reused = (is_reference && method == Method::Rk4)
                    .then(|| chain_runs.iter().find(|r| r.steps == steps).cloned())
                    .flatten();
                let predicted = match (&reused, &previous) {
                    (Some(r), _) => r.cost,
                    (None, Some(p)) => 2.0 * p.cost,
                    (None, None) => {
                        steps as f64 * budget::updates_per_step(&model.scene, Some(method))
                    }
                };
                if predicted >= best.min(reference_run.cost) && reused.is_none() {
                    c.cost = predicted;
                    c.verdict = Verdict::Costlier;
                    candidates.push(c);
                    break;
                }
                if reused.is_none() && work + predicted > cap {
                    c.cost = predicted;
                    c.verdict = Verdict::OverCap;
                    candidates.push(c);
                    break;
                }
                let run = match reused {
                    Some(r) => r,
                    None => {
                        progress(&Stage::Candidate {
                            n: model.n,
                            kinds: model.kinds,
                            method,
                            dt,
                        });
                        let r = observe::measure(&model.scene, method, dt, steps);
                        work += r.cost;
                        r
                    }
                };
                c.cost = run.cost;
                c.wall_seconds = Some(run.wall_seconds);
                let Some(obs) = &run.observation else {
                    c.verdict = Verdict::Diverged;
                    c.diverged = run.diverged.clone();
                    candidates.push(c);
                    previous = Some(run);
                    continue;
                };
                // The error over the run: the observable at each of the 20 sample instants.
                let error =
                    observe::history_difference(&run.snapshots, &reference_run.snapshots, time);
                let meets = accepted(&error, &e_ref, x);
                let coarse = !is_reference
                    && previous
                        .as_ref()
                        .filter(|p| p.observation.is_some())
                        .is_some_and(|p| {
                            let step =
                                observe::history_difference(&run.snapshots, &p.snapshots, time);
                            error.metres - 2.0 * step.metres > x
                                || error.seconds - 2.0 * step.seconds > x
                        });
                c.error_at_t = Some(obs.difference(&reference_obs, time));
                c.error = Some(error);
                c.verdict = if meets {
                    Verdict::Meets
                } else if coarse {
                    Verdict::ModelTooCoarse
                } else {
                    Verdict::TooInaccurate
                };
                candidates.push(c);
                if meets {
                    best = best.min(run.cost);
                    break;
                }
                if coarse {
                    too_coarse = true;
                    break;
                }
                // The error's trend: halvings still needed, and what they would cost.
                let bound = best.min(reference_run.cost);
                let trend = previous
                    .as_ref()
                    .filter(|p| p.observation.is_some())
                    .map(|p| {
                        observe::history_difference(&p.snapshots, &reference_run.snapshots, time)
                            .worst()
                    })
                    .zip(
                        candidates
                            .last()
                            .and_then(|c| c.error.as_ref())
                            .map(Difference::worst),
                    );
                if let Some((before, now)) = trend
                    && now > 0.0
                    && before / now >= PROJECTION_RATIO
                {
                    let halvings = ((now / x).ln() / (before / now).ln()).max(0.0);
                    if run.cost * 2f64.powf(halvings) >= bound
                        && let Some(last) = candidates.last_mut()
                    {
                        last.verdict = Verdict::ProjectedCostlier;
                        break;
                    }
                }
                previous = Some(run);
            }
        }
    }

    // 3. Verification, cheapest accepted first.
    let mut accepted_order: Vec<usize> = (0..candidates.len())
        .filter(|&i| candidates[i].verdict == Verdict::Meets)
        .collect();
    accepted_order.sort_by(|&a, &b| {
        candidates[a]
            .cost
            .total_cmp(&candidates[b].cost)
            .then(candidates[a].particles.cmp(&candidates[b].particles))
    });
    let mut verifications = Vec::new();
    let mut recommended = None;
    for &i in accepted_order.iter().take(MAX_VERIFICATIONS) {
        let c = &candidates[i];
        let model = &plan.models[c.model];
        progress(&Stage::Verify(c.method, c.dt));
        let run = observe::measure_accounted(&model.scene, c.method, c.dt, c.steps);
        let energy_residual = run.energy_residual.unwrap_or(f64::NAN);
        let error = observe::history_difference(&run.snapshots, &reference_run.snapshots, time);
        let error_at_t = run.difference(&reference_obs, time);
        let accurate = accepted(&error, &e_ref, x);
        let horizon = time;
        let confirm_dt = MARGIN * c.dt;
        let confirm_count =
            ((horizon / confirm_dt).ceil() as u64).max(stability::CONFIRM_MIN_STEPS);
        let confirmation = stability::confirm_steps(
            &model.scene,
            c.method,
            confirm_dt,
            confirm_count,
            stability::energy_scale(&model.scene),
        );
        let holds = accurate && confirmation.passed;
        verifications.push(Verification {
            candidate: i,
            error,
            error_at_t,
            accurate,
            stability: confirmation,
            holds,
            energy_residual,
            command: command(plan, c),
        });
        if holds {
            recommended = Some(i);
            break;
        }
    }
    Ok(report(
        plan,
        reference,
        candidates,
        recommended,
        verifications,
        work,
        cap,
        left_out,
        start,
    ))
}

#[allow(clippy::too_many_arguments)]
fn report(
    plan: &Plan,
    reference: Reference,
    candidates: Vec<Candidate>,
    recommended: Option<usize>,
    verifications: Vec<Verification>,
    search_work: f64,
    search_cap: f64,
    left_out: Vec<(Method, String)>,
    start: Instant,
) -> AdviseReport {
    AdviseReport {
        scene: plan.scene.clone(),
        sets: plan.sets.clone(),
        time: plan.time,
        tolerance: plan.options.tolerance,
        tolerance_unit: TOLERANCE_UNIT,
        observable: Observable::of(&plan.models[plan.reference].scene).definition(plan.time),
        refinement: plan.refinement.clone(),
        key: plan.key,
        margin_rule: format!(
            "dt ≤ limit / {MARGIN}: limit = the damped theory's (linearised at the initial state, \
             study::theory) on that resolution and kinds; the confirmed stability study's for a \
             method the theory does not cover; implicit Euler is unconditional (first dt = T/{})",
            observe::SAMPLES
        ),
        cost_unit: "particle and spring updates: (force evaluations + CG iterations) × \
                    (particles + springs + 8), as the budget counts them",
        reference,
        candidates,
        recommended,
        verifications,
        search_work,
        search_cap,
        left_out,
        wall_seconds: start.elapsed().as_secs_f64(),
    }
}
