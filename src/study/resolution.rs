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
//! the largest difference of a component, in m for positions and lengths, s for times). The
//! answer has stopped changing from the first level `n_i` with `Δ_j ≤ X` for every `j ≥ i`;
//! if the finest change is still above `X`, the answer has not converged over the levels run.
//! The difference from the finest level, `d(O(n_i), O(n_L))`, is printed beside it.

use serde::Serialize;

use super::StudyError;
use super::modes::omega_max;
use super::observe::{self, Difference, Measurement, Observable, Observation, Unit};
use crate::physics::Method;
use crate::scene::lattice::KindCoefficients;
use crate::scene::{self, Params, Scene, SceneDef, Value};

/// How a built-in scene's body is divided (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Dimension {
    /// A cube: `n` particles per edge, springs `k ∝ h`.
    Volume,
    /// A cloth: `n` per side, springs unchanged.
    Membrane,
    /// A rope: `nodes`, springs `k ∝ 1/h`.
    Line,
}

impl Dimension {
    /// The rule in words, for the output.
    #[must_use]
    pub fn rule(self) -> &'static str {
        match self {
            Dimension::Volume => {
                "the same cube at every n: edge, total mass and material kept (particle mass ∝ \
                 1/n³; stiffness and dampers ∝ h = L/(n - 1), a spring standing for material of \
                 cross-section h²)"
            }
            Dimension::Membrane => {
                "the same cloth at every n: size, total mass and material kept (particle mass and \
                 drag ∝ 1/n²; stiffness and dampers unchanged, a spring standing for a strip of \
                 width h)"
            }
            Dimension::Line => {
                "the same rope at every node count N: length, total mass and material kept \
                 (node mass and drag ∝ 1/N; stiffness and dampers ∝ 1/h = (N - 1)/ℓ); pinned \
                 nodes kept at their place along the rope"
            }
        }
    }

    /// The resolution parameter: `n` or `nodes`.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            Dimension::Volume | Dimension::Membrane => "n",
            Dimension::Line => "nodes",
        }
    }

    /// The smallest resolution that makes the body.
    #[must_use]
    pub fn min(self) -> i64 {
        match self {
            Dimension::Volume => 3,
            Dimension::Membrane => 3,
            Dimension::Line => 2,
        }
    }
}

/// Which spring kinds a run has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kinds {
    /// Every kind of the scene.
    All,
    /// Without the bend springs.
    NoBend,
    /// Without the shear springs.
    NoShear,
}

impl Kinds {
    /// `all`, `no bend`, `no shear`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Kinds::All => "all",
            Kinds::NoBend => "no bend",
            Kinds::NoShear => "no shear",
        }
    }

    /// The parameter values that remove the kind.
    fn values(self) -> Vec<(&'static str, Value)> {
        let zero = |stiffness, damping| {
            vec![
                (stiffness, Value::Number(0.0)),
                (damping, Value::Number(0.0)),
            ]
        };
        match self {
            Kinds::All => Vec::new(),
            Kinds::NoBend => zero("bend_stiffness", "bend_damping"),
            Kinds::NoShear => zero("shear_stiffness", "shear_damping"),
        }
    }
}

/// A built-in scene that can be refined, with the values of its parameters that the levels
/// scale (after the user's `--set`).
#[derive(Clone, Debug)]
pub struct Refinement {
    /// The built-in scene.
    pub scene: String,
    /// How its body is divided.
    pub dimension: Dimension,
    /// Its own resolution (`n` or `nodes`).
    pub base: i64,
    /// The user's assignments, applied first at every level.
    pub sets: Vec<String>,
    params: Params,
}

/// The scene is not a refinable built-in.
fn not_refinable(name: &str) -> StudyError {
    StudyError::Scene(scene::SceneError::Invalid(format!(
        "scene `{name}` cannot be refined: the resolution study and advise's resolutions need a \
         built-in scene with a resolution parameter (`n`: cube-plane, cube-tilted, cube-sphere, \
         cube-bowl, jelly-bowl, cloth-spheres, cloth-sphere; `nodes`: rope, ropes)"
    )))
}

impl Refinement {
    /// The refinement of the built-in `name` with the user's `sets`, or `None` when `name` is
    /// not a built-in with a resolution parameter.
    ///
    /// # Errors
    /// A bad assignment in `sets`.
    pub fn of(name: &str, sets: &[String]) -> Result<Option<Refinement>, StudyError> {
        let Some(def) = scene::builtin(name) else {
            return Ok(None);
        };
        let specs = (def.params)();
        let has = |key: &str| specs.iter().any(|p| p.name == key);
        let dimension = if has("nodes") {
            Dimension::Line
        } else if has("n") && has("edge") {
            Dimension::Volume
        } else if has("n") && has("drag") {
            Dimension::Membrane
        } else {
            return Ok(None);
        };
        let params = params_of(def, sets)?;
        Ok(Some(Refinement {
            scene: name.to_string(),
            dimension,
            base: params.integer(dimension.key()),
            sets: sets.to_vec(),
            params,
        }))
    }

    /// [`Refinement::of`] that fails for a scene that cannot be refined.
    ///
    /// # Errors
    /// As [`Refinement::of`], and a scene without a resolution parameter.
    pub fn require(name: &str, sets: &[String]) -> Result<Refinement, StudyError> {
        Refinement::of(name, sets)?.ok_or_else(|| not_refinable(name))
    }

    /// True when the scene has the springs that `kinds` removes (so the variant differs).
    #[must_use]
    pub fn has_kind(&self, kinds: Kinds) -> bool {
        // The coefficients as the lattice scenes build them (an override of -1: the common
        // value); a rope has one kind.
        let active = |kind: fn(&KindCoefficients) -> (f64, f64)| {
            let (stiffness, damping) = kind(&scene::course::coefficients(&self.params));
            stiffness > 0.0 || damping > 0.0
        };
        match (self.dimension, kinds) {
            (_, Kinds::All) => true,
            (Dimension::Line, _) => false,
            (_, Kinds::NoBend) => active(|c| c.bend),
            (_, Kinds::NoShear) => active(|c| c.shear),
        }
    }

    /// The default levels: a geometric sequence of spacings about the scene's own, from
    /// coarse to fine (`coarser` levels below it and `finer` above, ratio about √2; a cloth
    /// keeps an even number of cells per side, so its centre is a particle).
    #[must_use]
    pub fn default_levels(&self, coarser: i32, finer: i32) -> Vec<i64> {
        let cells = (self.base - 1) as f64;
        let even = self.dimension == Dimension::Membrane && (self.base - 1) % 2 == 0;
        let mut levels: Vec<i64> = (-coarser..=finer)
            .map(|k| {
                let c = cells * 2f64.sqrt().powi(k);
                let c = if even {
                    2.0 * (c / 2.0).round()
                } else {
                    c.round()
                };
                c as i64 + 1
            })
            .filter(|&n| n >= self.dimension.min())
            .collect();
        levels.push(self.base);
        levels.sort_unstable();
        levels.dedup();
        levels
    }

    /// The parameter values of level `n` with `kinds` on top of the user's (module docs): the
    /// scaled values (none at the scene's own resolution), then those that remove a kind.
    fn values_for(&self, n: i64, kinds: Kinds) -> Vec<(&'static str, Value)> {
        let mut values = if n == self.base {
            Vec::new()
        } else {
            self.scaled(n)
        };
        values.extend(kinds.values());
        values
    }

    /// The `--set` assignments of level `n` with `kinds`, to show and repeat a level: the
    /// user's, then [`Refinement::params`]'s values as text (the levels are built from the
    /// values, not from this text).
    #[must_use]
    pub fn sets_for(&self, n: i64, kinds: Kinds) -> Vec<String> {
        let mut sets = self.sets.clone();
        for (key, value) in self.values_for(n, kinds) {
            sets.push(match value {
                Value::Indices(list) => {
                    let items: Vec<String> = list.iter().map(i64::to_string).collect();
                    format!("{key}=[{}]", items.join(","))
                }
                other => format!("{key}={other}"),
            });
        }
        sets
    }

    /// The parameters of level `n` with `kinds`: the scene's with the user's assignments, then
    /// the level's values (module docs).
    ///
    /// # Errors
    /// A level outside a parameter's range.
    pub fn params(&self, n: i64, kinds: Kinds) -> Result<Params, StudyError> {
        let mut params = self.params.clone();
        for (key, value) in self.values_for(n, kinds) {
            params.set(key, value).map_err(scene::SceneError::from)?;
        }
        Ok(params)
    }

    /// The values that make level `n` from the scene's own (module docs).
    fn scaled(&self, n: i64) -> Vec<(&'static str, Value)> {
        let p = &self.params;
        let base = self.base as f64;
        let level = n as f64;
        let mut sets = Vec::new();
        let mut put = |key: &'static str, value: f64| {
            if value != p.number(key) {
                sets.push((key, Value::Number(value)));
            }
        };
        let spring_keys = [
            "stiffness",
            "damping",
            "struct_stiffness",
            "shear_stiffness",
            "bend_stiffness",
            "struct_damping",
            "shear_damping",
            "bend_damping",
        ];
        let springs = |ratio: f64, put: &mut dyn FnMut(&'static str, f64)| {
            for key in spring_keys {
                // The per-kind overrides: -1 (any negative) means "the common value".
                let v = p.number(key);
                if v >= 0.0 {
                    put(key, v * ratio);
                }
            }
        };
        match self.dimension {
            Dimension::Volume => {
                put("mass", p.number("mass") * (base / level).powi(3));
                springs((base - 1.0) / (level - 1.0), &mut put);
            }
            Dimension::Membrane => {
                put("mass", p.number("mass") * (base / level).powi(2));
                put("drag", p.number("drag") * (base / level).powi(2));
            }
            Dimension::Line => {
                put("mass", p.number("mass") * base / level);
                put("drag", p.number("drag") * base / level);
                for key in ["stiffness", "damping"] {
                    put(key, p.number(key) * (level - 1.0) / (base - 1.0));
                }
            }
        }
        if self.dimension == Dimension::Line
            && let Ok(pinned) = p.indices("pinned", self.base as usize)
        {
            let mut moved: Vec<i64> = pinned
                .iter()
                .map(|&i| ((i as f64) * (level - 1.0) / (base - 1.0)).round() as i64)
                .collect();
            moved.dedup();
            if moved.iter().zip(&pinned).any(|(a, &b)| *a != b as i64)
                || moved.len() != pinned.len()
            {
                sets.push(("pinned", Value::Indices(moved)));
            }
        }
        sets.push((self.dimension.key(), Value::Integer(n)));
        sets
    }

    /// The scene of level `n` with `kinds`, within `limits`.
    ///
    /// # Errors
    /// A level the scene refuses (out of its range, over the memory budget).
    pub fn scene(
        &self,
        n: i64,
        kinds: Kinds,
        limits: &crate::budget::Limits,
    ) -> Result<Scene, StudyError> {
        let def = scene::builtin(&self.scene).ok_or_else(|| not_refinable(&self.scene))?;
        Ok(scene::build_from(def, &self.params(n, kinds)?, limits)?)
    }
}

fn params_of(def: &SceneDef, sets: &[String]) -> Result<Params, StudyError> {
    let mut params = def.default_params();
    for s in sets {
        params.set_text(s).map_err(scene::SceneError::from)?;
    }
    // A resolution that is not an integer cannot be refined (never the case for built-ins).
    for (key, value) in params.iter() {
        if (key == "n" || key == "nodes") && !matches!(value, Value::Integer(_)) {
            return Err(not_refinable(def.name));
        }
    }
    Ok(params)
}

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
    let mut result = TheoryDt::Unconditional;
    for b in &scene.bodies {
        let omega = omega_max(&b.model, &b.state).omega;
        if !(omega > 0.0 && omega.is_finite()) {
            continue;
        }
        let spectrum = super::theory::spectrum(&b.model, &b.state, omega);
        let limit = super::theory::limit(method, &b.params, &spectrum);
        result = match (result, limit.stability, limit.dt) {
            (TheoryDt::None, _, _) | (_, "none", _) => TheoryDt::None,
            (TheoryDt::NotCovered, _, _) | (_, "not covered", _) => TheoryDt::NotCovered,
            (TheoryDt::Conditional { dt: a }, "conditional", Some(b)) => {
                TheoryDt::Conditional { dt: a.min(b) }
            }
            (_, "conditional", Some(b)) => TheoryDt::Conditional { dt: b },
            (r, _, _) => r,
        };
    }
    result
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
    /// The first level from which every change is within the tolerance; `null` when the finest
    /// change is still above it.
    pub converged_from: Option<i64>,
    /// The change of the scene's own level when its time step is halved (the time step's own
    /// error), when the scene's level is among the levels.
    pub time_step_check: Option<Difference>,
}

/// The definition printed with the study.
#[must_use]
pub fn definition(tolerance: f64) -> String {
    format!(
        "the answer stops changing at the first level n_i from which every refinement changes \
         it by at most {tolerance} (successive differences Δ_j = d(O(n_j), O(n_(j+1))) ≤ X for \
         all j ≥ i; d is the largest difference of a component, m for positions and lengths, s \
         for times)"
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
        None => refinement.default_levels(3, 2),
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
            if !refinement.has_kind(kinds) {
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

/// Runs the study on the planned `runs` (see [`runs`]) over the cores; calls `progress(i)` as
/// run `i` starts (`i = planned.len()`: the time-step check).
#[must_use]
pub fn resolution(
    refinement: &Refinement,
    options: &ResolutionOptions,
    time: f64,
    planned: &[PlannedRun],
    progress: &mut dyn FnMut(usize, i64, Kinds),
) -> ResolutionReport {
    // The runs are independent, and so is the time-step check (the base level at dt / 2, the
    // last job): all of them spread over the cores, the costliest first; each result is the
    // same whichever thread computes it.
    let base = planned
        .iter()
        .position(|p| p.n == refinement.base && p.kinds == Kinds::All);
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
    let mut measured =
        crate::physics::pool::independent(jobs, threads, weight, job, |i| match planned.get(i) {
            Some(p) => progress(i, p.n, p.kinds),
            None => progress(planned.len(), refinement.base, Kinds::All),
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
        time_step_check,
    }
}
