//! How much model a scene needs: `springlab study resolution`.
//!
//! The same body is divided into more and more particles, with and without its shear and bend
//! springs, and the scene's observable ([`super::observe`]) is measured at each level, with the
//! cost of each run. The study prints where dividing further stops changing the answer by more
//! than a tolerance.
//!
//! # Refining the same body
//!
//! The course scenes give each particle a mass and each spring a stiffness; dividing a cube into
//! more particles with the same values would make a heavier, relatively softer cube. A level
//! here keeps the body: its size, total mass and material, with the particle spacing `h`
//! (m) changed:
//!
//! ```text
//! body     resolution  spacing          particle mass      stiffness k, damper k_d     drag c
//! cube     n per edge  h = L/(n - 1)    m ∝ 1/n³           k, k_d ∝ h     (volume)     —
//! cloth    n per side  h = 4/(n - 1)    m ∝ 1/n²           k, k_d const.  (membrane)   c ∝ 1/n²
//! rope     nodes N     h = ℓ/(N - 1)    m ∝ 1/N            k, k_d ∝ 1/h   (line)       c ∝ 1/N
//! ```
//! A spring between particles `h` apart stands for a piece of material of cross-section `A`
//! and length `h`, so `k = E A / h`: in a volume `A ∝ h²` (`k ∝ h`), in a membrane `A ∝ h`
//! (`k` constant), along a line `A` is fixed (`k ∝ 1/h`); dampers scale the same way, and
//! masses and drag share the total among the particles. The scene's own resolution is the level
//! whose values are the scene's. Every mode keeps its frequency and damping as `h → 0`; the
//! stiffest one grows like `1/h` (and its damping rate like `1/h²`), so finer levels need
//! smaller steps. The rope's pinned nodes are carried to the node at the same place along it.
//!
//! # Spring kinds
//!
//! At every level the body is also run without its bend springs and without its shear springs
//! (`bend_stiffness = bend_damping = 0`, …; such springs are then not built). The difference
//! from the run with every kind at the same level says whether the scene needs that kind at
//! that accuracy. Ropes have one kind.
//!
//! # Time step and method
//!
//! Every level runs the same method (default RK4) at the scene's `dt`, or at half the method's
//! damped-theory limit ([`super::theory`]) on that level where that is smaller, so the time
//! step's own error stays below the model's; the study checks it by running the scene's own
//! level again at `dt/2` and printing the change.
//!
//! # Where the answer stops changing
//!
//! With levels `n_1 < n_2 < … < n_L`, the change at level `i` is the difference of its
//! observation from the next finer level's, `Δ_i = d(O(n_i), O(n_{i+1}))` ([`Difference`]:
//! the largest difference of a component, in m for positions and lengths, s for times). Small
//! successive differences do not bound the distance to the limit when they shrink slowly, so
//! the study also extrapolates the limit `O_∞` with its uncertainty from the three finest levels
//! ([`limit`]: Richardson, with the observed order) and says from which level the answer is
//! within `X` of it: **it stops changing** from the first level `n_i` with `|O(n_j) - O_∞| + u
//! ≤ X` for every `j ≥ i`. The successive-difference rule (`Δ_j ≤ X` for all `j ≥ i`) is printed
//! beside it. Each level's answer is also checked to have **settled** in time ([`limit`]: it
//! moved at most `X/10` over the run's last fifth); when it has not, the limit is the limit at
//! `T`, not at rest, and the study says so.
//!
//! The spring kinds are compared at the levels up to the scene's own (the question is whether
//! the scene's model needs them); the finer levels, the costliest, run with every kind.

use serde::Serialize;

use super::StudyError;
use super::modes::omega_max;
use super::observe::{self, Difference, Measurement, Observable, Observation, Unit};
use crate::physics::Method;
use crate::physics::pool::JobEvent;
use crate::scene::{self, Scene};

pub mod limit;
mod refinement;
pub use limit::{ComponentLimit, Settling};
pub use refinement::{Dimension, Kinds, Refinement};

/// The damped-theory limit of a method on a whole scene.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "stability", rename_all = "kebab-case")]
pub enum TheoryDt {
    /// Stable up to `dt` (s): the smallest over the bodies.
    Conditional {
        /// The limit (s).
        dt: f64,
    },
    /// Stable at every step.
    Unconditional,
    /// Unstable at every step.
    None,
    /// The theory does not cover the method (projection, XPBD).
    NotCovered,
}

/// The damped theory's limit of `method` on `scene` ([`super::theory::limit`] on each body's
/// spectrum, linearised at its initial state; the smallest over the bodies). Costs a power
/// iteration per body, no simulation.
#[must_use]
pub fn theory_dt(scene: &Scene, method: Method) -> TheoryDt {
    theory_dts(scene, &[method])[0]
}

/// [`theory_dt`] of each of `methods`, in order, from one spectrum per body (the spectrum
/// does not depend on the method: one power iteration instead of one per method).
#[must_use]
pub fn theory_dts(scene: &Scene, methods: &[Method]) -> Vec<TheoryDt> {
    let mut results = vec![TheoryDt::Unconditional; methods.len()];
    for b in &scene.bodies {
        let omega = omega_max(&b.model, &b.state).omega;
        if !(omega > 0.0 && omega.is_finite()) {
            continue;
        }
        let spectrum = super::theory::spectrum(&b.model, &b.state, omega);
        for (result, &method) in results.iter_mut().zip(methods) {
            let limit = super::theory::limit(method, &b.params, &spectrum);
            *result = match (*result, limit.stability, limit.dt) {
                (TheoryDt::None, _, _) | (_, "none", _) => TheoryDt::None,
                (TheoryDt::NotCovered, _, _) | (_, "not covered", _) => TheoryDt::NotCovered,
                (TheoryDt::Conditional { dt: a }, "conditional", Some(b)) => {
                    TheoryDt::Conditional { dt: a.min(b) }
                }
                (_, "conditional", Some(b)) => TheoryDt::Conditional { dt: b },
                (r, _, _) => r,
            };
        }
    }
    results
}

/// Options of [`resolution`].
#[derive(Clone, Debug, PartialEq)]
pub struct ResolutionOptions {
    /// Resolutions (`n` or `nodes`), any order; `None`: [`Refinement::default_levels`].
    pub levels: Option<Vec<i64>>,
    /// The method of every run.
    pub method: Method,
    /// When the observable is taken (s); `None`: [`default_time`].
    pub time: Option<f64>,
    /// The tolerance `X` (m for positions and lengths, s for times).
    pub tolerance: f64,
    /// Also run each level without bend and without shear springs.
    pub kinds: bool,
}

impl Default for ResolutionOptions {
    fn default() -> ResolutionOptions {
        ResolutionOptions {
            levels: None,
            method: Method::Rk4,
            time: None,
            tolerance: DEFAULT_TOLERANCE,
            kinds: true,
        }
    }
}

/// The default tolerance `X` (m, or s for times).
pub const DEFAULT_TOLERANCE: f64 = 0.01;

/// The instant the observable is taken at by default (s): the built-in scene's
/// [`observe_at`](crate::scene::SceneDef::observe_at), 1 s for a scene file.
#[must_use]
pub fn default_time(scene: &str) -> f64 {
    scene::builtin(scene).map_or(1.0, |def| def.observe_at)
}

/// The largest step a level runs at: the scene's `dt`, or half the method's damped-theory limit
/// when that is smaller (module docs).
///
/// # Errors
/// A method with no stable step on the scene.
pub fn level_dt(scene: &Scene, method: Method) -> Result<f64, StudyError> {
    Ok(match theory_dt(scene, method) {
        TheoryDt::Conditional { dt } => scene.dt.min(0.5 * dt),
        TheoryDt::None => {
            return Err(StudyError::Scene(scene::SceneError::Invalid(format!(
                "{method} has no stable time step on scene `{}` (damped theory): choose another \
                 --method",
                scene.name
            ))));
        }
        TheoryDt::Unconditional | TheoryDt::NotCovered => scene.dt,
    })
}

/// One run of the study.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LevelRun {
    /// The resolution (`n` or `nodes`).
    pub n: i64,
    /// Which spring kinds.
    pub kinds: Kinds,
    /// Particles.
    pub particles: usize,
    /// Springs.
    pub springs: usize,
    /// Springs × steps: the cost the course tables use.
    pub springs_steps: f64,
    /// The run.
    pub run: Measurement,
    /// All kinds: the difference from the next finer level (`null` at the finest).
    pub change_next: Option<Difference>,
    /// All kinds: the difference from the finest level.
    pub change_finest: Option<Difference>,
    /// All kinds: `|O - O_∞| + u` in m and s (`[metres, seconds]`), when every component has a
    /// limit.
    pub from_limit: Option<[f64; 2]>,
    /// Whether the answer had settled at `T` ([`limit`]); `null` for a diverged run.
    pub settling: Option<Settling>,
    /// Without a kind: the difference from the run with every kind at the same level.
    pub change_kinds: Option<Difference>,
}

/// The result of [`resolution`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ResolutionReport {
    /// Scene name.
    pub scene: String,
    /// The user's assignments.
    pub sets: Vec<String>,
    /// The resolution parameter (`n` or `nodes`).
    pub key: &'static str,
    /// The scene's own resolution.
    pub base: i64,
    /// How a level keeps the body, in words.
    pub refinement: String,
    /// The method of every run.
    pub method: Method,
    /// When the observable is taken (s).
    pub time: f64,
    /// The observable's components, in words.
    pub observable: String,
    /// Component names and units.
    pub components: Vec<(String, Unit)>,
    /// The tolerance `X` (m for positions and lengths, s for times).
    pub tolerance: f64,
    /// How the time step is chosen, in words.
    pub time_step: String,
    /// The definition of "stops changing", in words.
    pub definition: String,
    /// Every run, coarse to fine, each level's variants after its all-kinds run.
    pub runs: Vec<LevelRun>,
    /// The successive-difference rule: the first level from which every change to the next
    /// level is within the tolerance; `null` when the finest change is still above it.
    pub converged_from: Option<i64>,
    /// The Richardson limit of each component from the three finest levels ([`limit`]); `null`
    /// where it cannot be extrapolated.
    pub limits: Vec<Option<ComponentLimit>>,
    /// The limit's rule, in words.
    pub limit_rule: String,
    /// Where the answer stops changing: the first level from which every level is within X of
    /// the limit (`|O - O_∞| + u ≤ X`); `null` when the finest is not.
    pub within_limit_from: Option<i64>,
    /// The settling rule, in words.
    pub settling_rule: String,
    /// True when every all-kinds level had settled at `T`.
    pub settled: bool,
    /// The change of the scene's own level when its time step is halved (the time step's own
    /// error), when the scene's level is among the levels.
    pub time_step_check: Option<Difference>,
}

/// The definition printed with the study.
#[must_use]
pub fn definition(tolerance: f64) -> String {
    format!(
        "the answer stops changing at the first level n_i from which every level is within X = \
         {tolerance} of the extrapolated limit (|O(n_j) - O_∞| + u ≤ X for all j ≥ i); beside it \
         the successive-difference rule (Δ_j = d(O(n_j), O(n_(j+1))) ≤ X for all j ≥ i; d is the \
         largest difference of a component, m for positions and lengths, s for times)"
    )
}

/// Validates the options and returns the refinement, the levels (sorted, deduplicated) and
/// the observable's time.
///
/// # Errors
/// A scene that cannot be refined, bad levels, time or tolerance.
pub fn plan(
    name: &str,
    sets: &[String],
    options: &ResolutionOptions,
) -> Result<(Refinement, Vec<i64>, f64), StudyError> {
    let refinement = Refinement::require(name, sets)?;
    let time = options.time.unwrap_or_else(|| default_time(name));
    if !(time > 0.0 && time.is_finite()) {
        return Err(StudyError::Time(time));
    }
    if !(options.tolerance > 0.0 && options.tolerance.is_finite()) {
        return Err(StudyError::Tolerance(options.tolerance));
    }
    let mut levels = match &options.levels {
        Some(l) => l.clone(),
        None => refinement.default_levels(3, 1),
    };
    levels.sort_unstable();
    levels.dedup();
    let min = refinement.dimension.min();
    if let Some(&bad) = levels.iter().find(|&&n| n < min) {
        return Err(StudyError::Resolutions(format!(
            "{} = {bad}: expected whole numbers ≥ {min}",
            refinement.dimension.key()
        )));
    }
    if levels.len() < 2 {
        return Err(StudyError::Resolutions(format!(
            "expected at least two resolutions to compare, got {}",
            levels.len()
        )));
    }
    Ok((refinement, levels, time))
}

/// One run the study will make.
#[derive(Clone, Debug)]
pub struct PlannedRun {
    /// The resolution.
    pub n: i64,
    /// The spring kinds.
    pub kinds: Kinds,
    /// The scene of that level and kinds.
    pub scene: Scene,
    /// Its time step (s): the all-kinds level's, for every variant.
    pub dt: f64,
    /// Its steps (`time / dt`).
    pub steps: u64,
}

/// The runs the study will make, built within `limits`.
///
/// # Errors
/// As [`Refinement::scene`] and [`level_dt`].
pub fn runs(
    refinement: &Refinement,
    levels: &[i64],
    options: &ResolutionOptions,
    time: f64,
    limits: &crate::budget::Limits,
) -> Result<Vec<PlannedRun>, StudyError> {
    let mut out = Vec::new();
    for &n in levels {
        let variants: &[Kinds] = if options.kinds {
            &[Kinds::All, Kinds::NoBend, Kinds::NoShear]
        } else {
            &[Kinds::All]
        };
        let all = refinement.scene(n, Kinds::All, limits)?;
        let dt_max = level_dt(&all, options.method)?.min(time);
        let steps = observe::steps_for(time, dt_max);
        let dt = time / steps as f64;
        for &kinds in variants {
            // Kinds are compared up to the scene's own level (module docs).
            if !refinement.has_kind(kinds) || (kinds != Kinds::All && n > refinement.base) {
                continue;
            }
            let scene = if kinds == Kinds::All {
                all.clone()
            } else {
                refinement.scene(n, kinds, limits)?
            };
            out.push(PlannedRun {
                n,
                kinds,
                scene,
                dt,
                steps,
            });
        }
    }
    Ok(out)
}

/// The work of a planned run (spring updates), to start the costliest first.
fn weight_of(p: &PlannedRun) -> f64 {
    p.scene.spring_count() as f64 * p.steps as f64
}

/// Runs the study on the planned `runs` (see [`runs`]) over the cores; calls
/// `progress(i, n, kinds, …)` as run `i` starts and as it ends (`i = planned.len()`: the
/// time-step check).
#[must_use]
pub fn resolution(
    refinement: &Refinement,
    options: &ResolutionOptions,
    time: f64,
    planned: &[PlannedRun],
    progress: &mut dyn FnMut(usize, i64, Kinds, JobEvent),
) -> ResolutionReport {
    // The runs are independent, and so is the time-step check (the base level at dt / 2, the
    // last job): all of them spread over the cores, the costliest first; each result is the
    // same whichever thread computes it.
    let base = planned
        .iter()
        .position(|p| p.n == refinement.base && p.kinds == Kinds::All);
    // Each run steps on its own thread alone (`pool::independent`): the finest level, about
    // half of the work, starts first on one core while the others follow one another on the
    // rest.
    let job = |i: usize| match planned.get(i) {
        Some(p) => observe::measure(&p.scene, options.method, p.dt, p.steps),
        None => {
            let p = &planned[base.unwrap_or_default()];
            observe::measure(&p.scene, options.method, p.dt / 2.0, p.steps * 2)
        }
    };
    let weight = |i: usize| match planned.get(i) {
        Some(p) => weight_of(p),
        None => 2.0 * base.map_or(0.0, |b| weight_of(&planned[b])),
    };
    let jobs = planned.len() + usize::from(base.is_some());
    let threads = crate::physics::pool::Pool::global().threads();
    let mut measured = crate::physics::pool::independent(jobs, threads, weight, job, |i, e| {
        match planned.get(i) {
            Some(p) => progress(i, p.n, p.kinds, e),
            None => progress(planned.len(), refinement.base, Kinds::All, e),
        }
    });
    let half = base.and_then(|_| measured.pop());
    let mut runs: Vec<LevelRun> = Vec::with_capacity(planned.len());
    for (p, run) in planned.iter().zip(measured) {
        runs.push(LevelRun {
            n: p.n,
            kinds: p.kinds,
            particles: p.scene.particle_count(),
            springs: p.scene.spring_count(),
            springs_steps: p.scene.spring_count() as f64 * run.steps as f64,
            run,
            change_next: None,
            change_finest: None,
            from_limit: None,
            settling: None,
            change_kinds: None,
        });
    }
    // Differences: along the all-kinds series, and of each variant from its level's all-kinds.
    let all: Vec<usize> = (0..runs.len())
        .filter(|&i| runs[i].kinds == Kinds::All)
        .collect();
    let observations: Vec<Option<Observation>> =
        runs.iter().map(|r| r.run.observation.clone()).collect();
    let diff = |a: &Option<Observation>, b: &Option<Observation>, count: usize| match (a, b) {
        (Some(a), Some(b)) => a.difference(b, time),
        _ => Difference::infinite(count),
    };
    let count = planned
        .first()
        .map_or(0, |p| Observable::of(&p.scene).names().len());
    let finest = all.last().copied();
    for (k, &i) in all.iter().enumerate() {
        let next = all
            .get(k + 1)
            .map(|&j| diff(&observations[i], &observations[j], count));
        let to_finest = finest.map(|f| diff(&observations[i], &observations[f], count));
        runs[i].change_next = next;
        runs[i].change_finest = to_finest;
    }
    for i in 0..runs.len() {
        if runs[i].kinds != Kinds::All
            && let Some(&j) = all.iter().find(|&&j| runs[j].n == runs[i].n)
        {
            runs[i].change_kinds = Some(diff(&observations[i], &observations[j], count));
        }
    }
    // Converged from the first level after which every successive change is within X.
    let changes: Vec<(i64, bool)> = all
        .iter()
        .filter_map(|&i| {
            runs[i]
                .change_next
                .as_ref()
                .map(|d| (runs[i].n, d.within(options.tolerance)))
        })
        .collect();
    let converged_from = changes
        .iter()
        .rposition(|&(_, ok)| !ok)
        .map_or(changes.first().map(|c| c.0), |last_bad| {
            all.get(last_bad + 1).map(|&i| runs[i].n)
        })
        .filter(|_| changes.last().is_some_and(|c| c.1));
    // The limit through the three finest levels that did not diverge, each level's distance
    // from it, and where every level is within X of it (module docs).
    let series: Vec<(i64, f64, &Observation)> = all
        .iter()
        .filter_map(|&i| {
            let o = runs[i].run.observation.as_ref()?;
            Some((runs[i].n, 1.0 / (runs[i].n - 1).max(1) as f64, o))
        })
        .collect();
    let limits = limit::limits(&series);
    let mut within: Vec<(i64, bool)> = Vec::new();
    for &i in &all {
        let run = &mut runs[i];
        run.settling = limit::settling(&run.run.snapshots, time, options.tolerance);
        run.from_limit = run
            .run
            .observation
            .as_ref()
            .map(|o| limit::distance(o, &limits))
            .filter(|d| d.0.is_finite() && d.1.is_finite())
            .map(|(m, s)| [m, s]);
        let ok = run
            .from_limit
            .is_some_and(|[m, s]| m <= options.tolerance && s <= options.tolerance);
        within.push((run.n, ok));
    }
    let within_limit_from = match within.iter().rposition(|&(_, ok)| !ok) {
        None => within.first().map(|w| w.0),
        Some(last_bad) => within.get(last_bad + 1).map(|w| w.0),
    };
    let settled = all
        .iter()
        .all(|&i| runs[i].settling.as_ref().is_some_and(|s| s.settled));
    // The time step's own error at the scene's level.
    let time_step_check = base.zip(half).map(|(i, half)| {
        let reference = runs[i].run.observation.clone();
        diff(&half.observation, &reference, count)
    });
    let first = planned.first().map(|p| Observable::of(&p.scene));
    ResolutionReport {
        scene: refinement.scene.clone(),
        sets: refinement.sets.clone(),
        key: refinement.dimension.key(),
        base: refinement.base,
        refinement: refinement.dimension.rule().to_string(),
        method: options.method,
        time,
        observable: first
            .as_ref()
            .map_or_else(String::new, |o| o.definition(time)),
        components: first.map(|o| o.names()).unwrap_or_default(),
        tolerance: options.tolerance,
        time_step: format!(
            "{} at the scene's dt, or half its damped-theory limit on the level where that is \
             smaller; every run ends at exactly {time} s",
            options.method
        ),
        definition: definition(options.tolerance),
        runs,
        converged_from,
        limits,
        limit_rule: limit::limit_rule(options.tolerance),
        within_limit_from,
        settling_rule: limit::settling_rule(options.tolerance),
        settled,
        time_step_check,
    }
}
