//! Lessons: plain Markdown files with TOML front matter, one per lesson, in `lessons/`.
//!
//! An instructor edits them without recompiling; the built-in ones are also embedded in the
//! binary so `springlab` runs from anywhere (`--lessons DIR` loads others).
//!
//! # Format
//!
//! ```text
//! +++
//! number = 1
//! slug = "rope"
//! title = "Building a rope"
//! summary = "Masses, springs, and a pinned end."
//! +++
//!
//! +++ step
//! title = "Three masses, two springs"
//! scene = "rope"                    # a built-in scene, or a scene file relative to the lesson
//! params = { nodes = 3 }            # scene parameters, as with --set
//! method = "semi-implicit-euler"    # optional: the method to start with (default: the scene's)
//! dt = 0.01                         # optional: the time step (s)
//! plots = ["energy", "speed"]       # optional: energy | exact | speed | error | stretch
//!                                   # | convergence | stability | work-precision
//! try = [
//!     "Watch the middle node.",                                  # text only
//!     { text = "Stiffen the springs and run.", keys = "K K space" },   # text and its keys
//! ]
//! goal = { kind = "settle", time = 2.0, speed = 0.05, text = "Make it settle within 2 s." }
//! predict = { question = "Which method keeps it bounded?", keys = "+ + +", expect = "survive",
//!             time = 30.0, answer = 2, options = [
//!                 { text = "explicit Euler", keys = "m e + + + space" },
//!                 { text = "semi-implicit Euler", keys = "m s + + + space" } ] }
//! hide = { title = "Which method stays bounded?", try = [2], from = "Why", goal = true,
//!          plots = ["stability"] }   # optional: kept back until the prediction is answered
//! speed = 0.5                       # optional: simulated seconds per wall second (1/64 to 64),
//!                                   # or "machine" (see Budget)
//! +++
//! The text of the step, in Markdown. Formulas go in code blocks:
//!
//!     f = -k (|b - a| - L0) (b - a)/|b - a|
//! ```
//!
//! The keys of a "try" item ([`keys`]) are shown beside its text; the tests play them.
//!
//! A goal is one of
//! - `settle`: every particle (of body `body`, 1-based, when given) slower than `speed` (m/s,
//!   default 0.05) from a moment before `time` (s) on, for at least half a second;
//! - `diverge`: the run blows up (NaN or |v| > 1000 m/s) before `time` (s);
//! - `survive`: the run reaches `time` (s) without diverging.
//!
//! A goal is reached by the keys of one "try" item: `try = N` (1-based) names it, else the last
//! item with keys. A step with a goal must have such an item (the tests play it and check that
//! the goal is met, and, when the keys do more than start the run, that idling does not meet it).
//!
//! A prediction (`predict`) asks a multiple-choice question before the run. Each option is a
//! claim about a run: its keys (else the prediction's `keys`) played from the step's start, and
//! the outcome `expect` (`survive`, `diverge` or `settle`, with `time`, `speed` and `body` as for
//! a goal; per option or for all). `answer` (1-based) is the option whose claim a run confirms;
//! the tests play every option and check that exactly that one holds. The app asks before the
//! first run, records the answer, and shows who was right when a run is decided.
//!
//! `hide` keeps back what would give a prediction's answer away until the student has answered:
//! a neutral `title` shown instead of the step's, try items (1-based), the text from the line
//! that starts with the words `from` on, the goal's text and plots, and (`limit = true`) the
//! status line's dt·ω, limit and "stable below". A "try" item whose keys
//! start with `R` starts from the step as it opened (the app's `R` restores it); the others
//! continue from what is on the screen.
//!
//! Numbers in the text can be computed when the step opens: `{{omega_max}}`,
//! `{{limit_dt:rk4}}`, `{{order:verlet@oscillator damping=2}}` (see [`numbers`]).
//!
//! Every error names the file and the line (and the column where TOML gives one), in one line
//! that quotes at most a short excerpt of a value. A file may start with a UTF-8 byte order mark
//! and use CRLF line ends. Each front-matter block is bounded before it is parsed, as scene
//! files are ([`crate::scene::file::bounds`]).
//!
//! # Budget
//!
//! A step runs in the terminal in real time, so its scene must be small enough for that: its
//! particle and spring updates per simulated second (at its method and dt, see
//! [`crate::budget::updates_per_step`]) at most [`REAL_TIME_UPDATES`], and a run of its longest
//! goal or prediction (at least [`HORIZON`] seconds) within the limits of `springlab run`; and
//! when its text has placeholders computed from ω_max, their power iteration's worst case at
//! most [`PLACEHOLDER_UPDATES`]. The scenes of `{{…@SCENE}}` placeholders obey the same limits. A step over them is refused with
//! the error shown in the menu, like a malformed lesson. A step at a `speed` below 1 is held to
//! its rate times that speed. A step with `speed = "machine"` knowingly runs below real time
//! (lesson 8's full jelly at advise's dt): it opens in real time and runs as fast as the
//! machine steps it, the status line's "× real time" saying how fast; only the run's limits
//! hold for it.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::Deserialize;

pub mod keys;
pub mod numbers;
mod parse;

pub use parse::parse;
use parse::reject_duplicates;

pub use keys::{Key, Keys, Stroke};

use crate::budget::{self, Limits};
use crate::physics::Method;
use crate::scene::{self, Scene, SceneError};

/// The most particle and spring updates per simulated second a lesson step's scene may need
/// (module docs): half the rate [`budget::RATE`] the budget assumes of one thread, so that
/// stepping in real time leaves half of each frame to drawing. The largest built-in step (the
/// cloth over a sphere, 625 particles and 3 502 springs at dt = 1e-4 s) needs 4.1e7.
pub const REAL_TIME_UPDATES: f64 = 0.5 * budget::RATE;

/// The shortest simulated time (s) a step's run is budgeted for (a student lets it run).
pub const HORIZON: f64 = 60.0;

/// Checks a lesson step's `scene` stepped at `dt` (s) for `horizon` seconds against the budget
/// (module docs); `what` names it in the message.
///
/// # Errors
/// The message of the first limit exceeded.
pub fn check_budget(scene: &Scene, dt: f64, horizon: f64, what: &str) -> Result<(), String> {
    check_budget_at(scene, dt, horizon, 1.0, what)
}

/// As [`check_budget`] for a step that opens at `speed` simulated seconds per wall second
/// (front matter `speed`, below 1 for a configuration slower than real time): the updates per
/// wall second, the rate times `speed`, are what must fit.
///
/// # Errors
/// As [`check_budget`].
pub fn check_budget_at(
    scene: &Scene,
    dt: f64,
    horizon: f64,
    speed: f64,
    what: &str,
) -> Result<(), String> {
    let horizon = horizon.max(HORIZON);
    let steps = budget::steps_for(horizon, dt);
    budget::run(what.to_string(), scene, dt, steps)
        .check(&Limits::DEFAULT)
        .map_err(|e| e.to_string())?;
    let rate = budget::updates_per_step(scene, None) / dt * speed;
    if rate > REAL_TIME_UPDATES {
        return Err(format!(
            "{what} needs about {} particle and spring updates per simulated second ({} \
             particles, {} springs at dt = {} s); a lesson runs in real time and may need at \
             most {}: use fewer nodes or a larger dt",
            budget::approx(rate),
            scene.particle_count(),
            scene.spring_count(),
            budget::short(dt),
            budget::approx(REAL_TIME_UPDATES)
        ));
    }
    Ok(())
}

/// The most particle and spring updates the placeholders that need ω_max (`{{omega_max}}`,
/// `{{limit_dt:…}}`, …) may cost when a step opens, at the power iteration's worst case
/// ([`crate::study::modes::MAX_ITERATIONS`] passes): ten seconds at [`budget::RATE`] (it
/// usually converges in far fewer). The jelly of lesson 5 is priced 2.8e8.
pub const PLACEHOLDER_UPDATES: f64 = 10.0 * budget::RATE;

/// Checks the worst-case cost of ω_max on `scene` against [`PLACEHOLDER_UPDATES`]; `what`
/// names it in the message.
///
/// # Errors
/// The message when it is over.
pub fn check_omega_cost(scene: &Scene, what: &str) -> Result<(), String> {
    let cost = f64::from(crate::study::modes::MAX_ITERATIONS)
        * (scene.particle_count() as f64 + scene.spring_count() as f64);
    if cost > PLACEHOLDER_UPDATES {
        return Err(format!(
            "{what}: its ω_max placeholders may need about {} particle and spring updates when \
             the step opens (power iteration, {} particles, {} springs); at most {}: use a \
             smaller scene",
            budget::approx(cost),
            scene.particle_count(),
            scene.spring_count(),
            budget::approx(PLACEHOLDER_UPDATES)
        ));
    }
    Ok(())
}

/// The lessons shipped with springlab, embedded at compile time: `(file name, text)`.
pub const BUILTIN: &[(&str, &str)] = &[
    ("01-rope.md", include_str!("../lessons/01-rope.md")),
    ("02-hooke.md", include_str!("../lessons/02-hooke.md")),
    ("03-euler.md", include_str!("../lessons/03-euler.md")),
    ("04-verlet.md", include_str!("../lessons/04-verlet.md")),
    ("05-jelly.md", include_str!("../lessons/05-jelly.md")),
    ("06-cloth.md", include_str!("../lessons/06-cloth.md")),
    (
        "07-speed-accuracy.md",
        include_str!("../lessons/07-speed-accuracy.md"),
    ),
    ("08-model.md", include_str!("../lessons/08-model.md")),
];

/// A plot the lesson screen can show beside the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Plot {
    /// Kinetic, gravitational, elastic and total energy over time.
    Energy,
    /// The oscillator's simulated position beside its exact solution.
    Exact,
    /// The largest particle speed over time.
    Speed,
    /// The oscillator's error against its exact solution.
    Error,
    /// Error against dt per method, log-log (`study convergence` of the step's scene).
    Convergence,
    /// The largest stable dt per method beside the theory (`study stability`).
    Stability,
    /// Error against force evaluations per method, log-log (`study work-precision`).
    #[serde(rename = "work-precision")]
    WorkPrecision,
    /// The largest stretch of a spring, `max |L/L0 - 1|`, per body over time.
    Stretch,
    /// The scene's observable (`study::observe`: a cloth's sag, a jelly's centroid height and
    /// largest compression) over time, beside the recorded resolution study's value.
    Observable,
    /// The recorded resolution study of the step's scene: the observable against the
    /// resolution, with every spring kind and without bend or shear springs.
    Resolution,
}

impl Plot {
    /// True for the plots of a study (convergence, stability, work-precision), whose methods
    /// the number keys show and hide.
    #[must_use]
    pub fn is_study(self) -> bool {
        matches!(
            self,
            Plot::Convergence | Plot::Stability | Plot::WorkPrecision
        )
    }
}

/// What the student is asked to achieve in a step.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Goal {
    /// `settle`, `diverge` or `survive`.
    pub kind: GoalKind,
    /// Deadline or duration (s).
    pub time: f64,
    /// For `settle`: the speed below which a particle counts as at rest (m/s).
    #[serde(default = "default_settle_speed")]
    pub speed: f64,
    /// For `settle`: only this body (1-based) must come to rest; `None`: every body.
    #[serde(default)]
    pub body: Option<usize>,
    /// The "try" item (1-based) whose keys reach the goal; `None`: the last item with keys.
    #[serde(default, rename = "try")]
    pub try_item: Option<usize>,
    /// What to tell the student.
    pub text: String,
}

fn default_settle_speed() -> f64 {
    0.05
}

/// The kinds of goal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GoalKind {
    /// Every particle slower than `speed` before `time`.
    Settle,
    /// The run diverges before `time`.
    Diverge,
    /// The run reaches `time` without diverging.
    Survive,
}

/// How long the speed must stay below the threshold for `settle` to count (s): a single slow
/// instant is only a turning point.
pub const SETTLE_HOLD: f64 = 0.5;

/// What a goal remembers between checks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GoalProgress {
    /// Since when every particle has been slower than the settle speed (s).
    calm_since: Option<f64>,
}

impl Goal {
    /// Whether a run at simulated time `time` (s) with largest speed `max_speed` (m/s), diverged
    /// or not, has met the goal: `Some(true)` met, `Some(false)` failed for good, `None` not yet.
    /// Call it as the run advances with the same `progress` (a fresh one for a fresh run).
    ///
    /// `settle` is met when the speed stays below `speed` for [`SETTLE_HOLD`] seconds from a
    /// moment before the deadline.
    pub fn check(
        &self,
        progress: &mut GoalProgress,
        time: f64,
        max_speed: f64,
        diverged: bool,
    ) -> Option<bool> {
        match self.kind {
            GoalKind::Settle if diverged => Some(false),
            GoalKind::Settle => {
                if max_speed < self.speed && time > 0.0 {
                    let since = *progress.calm_since.get_or_insert(time);
                    if time - since >= SETTLE_HOLD {
                        return Some(since <= self.time);
                    }
                } else {
                    progress.calm_since = None;
                }
                (time > self.time + SETTLE_HOLD).then_some(false)
            }
            GoalKind::Diverge if diverged => Some(time <= self.time),
            GoalKind::Diverge if time > self.time => Some(false),
            GoalKind::Survive if diverged => Some(false),
            GoalKind::Survive if time >= self.time => Some(true),
            _ => None,
        }
    }
}

/// One step of a lesson: text, a scene and what to try.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// Step title.
    pub title: String,
    /// The scene name or path, as written.
    pub scene: String,
    /// `key=value` scene parameters.
    pub params: Vec<String>,
    /// The method to start with (`None`: the scene's).
    pub method: Option<Method>,
    /// The time step (s) to start with (`None`: the scene's).
    pub dt: Option<f64>,
    /// Plots to show.
    pub plots: Vec<Plot>,
    /// Things to try, one per line, each with the keys that do it.
    pub try_list: Vec<TryItem>,
    /// An optional goal the app detects.
    pub goal: Option<Goal>,
    /// An optional prediction asked before the run.
    pub predict: Option<Prediction>,
    /// What the step keeps back until its prediction is answered.
    pub hide: Hidden,
    /// The body (1-based) the first view frames and the camera follows (`camera = { body = 2 }`);
    /// `None`: every body.
    pub camera_body: Option<usize>,
    /// The speed the step opens at (simulated seconds per wall second; `None`: 1, or the
    /// student's own after a step that set none; `speed = "machine"` is 1).
    pub speed: Option<f64>,
    /// The Markdown text.
    pub text: String,
    /// Where scene file paths are resolved from.
    base_dir: Option<PathBuf>,
}

impl Step {
    /// Builds the step's scene with its parameters and method.
    ///
    /// # Errors
    /// As [`scene::load`]; lessons are validated when loaded, so this fails only if a scene file
    /// changed since.
    pub fn build_scene(&self) -> Result<Scene, SceneError> {
        let target = match &self.base_dir {
            Some(dir) if self.scene.ends_with(".toml") => {
                dir.join(&self.scene).to_string_lossy().into_owned()
            }
            _ => self.scene.clone(),
        };
        let mut scene = scene::load(&target, &self.params)?;
        if let Some(m) = self.method {
            scene.set_method(m);
        }
        if let Some(dt) = self.dt {
            scene.dt = dt;
        }
        Ok(scene)
    }
}

/// A lesson: a title and its steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Lesson {
    /// Position in the menu.
    pub number: u32,
    /// Short name for `springlab lesson <slug>`.
    pub slug: String,
    /// Title.
    pub title: String,
    /// One line for the menu.
    pub summary: String,
    /// The steps, in order.
    pub steps: Vec<Step>,
    /// The file it came from.
    pub source: String,
    /// Lines of `number = ` and `slug = ` in the header (for duplicate errors).
    header_lines: (usize, usize),
}

/// A lesson file that cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{file}:{line}{}: {message}", column.map(|c| format!(":{c}")).unwrap_or_default())]
pub struct LessonError {
    /// The file.
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, when known.
    pub column: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for Lesson {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}. {} ({}): {}",
            self.number, self.title, self.slug, self.summary
        )
    }
}

/// What a step with a prediction keeps back until the student has answered it (front matter
/// `hide = { title = "…", try = [1, 2], from = "…", goal = true, plots = ["stability"],
/// limit = true }`):
/// whatever would give the answer away.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Hidden {
    /// The title shown until then (the step's own title says the answer).
    pub title: Option<String>,
    /// The try items (0-based) hidden until then.
    pub try_items: Vec<usize>,
    /// The text from the line that starts with these words on is hidden until then.
    pub from: Option<String>,
    /// The goal's text is hidden until then.
    pub goal: bool,
    /// These plots are hidden until then.
    pub plots: Vec<Plot>,
    /// The status line's stability fields (dt·ω, the limit, "stable below") are hidden until
    /// then: compared with the dt the question names, they answer it.
    pub limit: bool,
}

impl Hidden {
    /// True when nothing is kept back.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        *self == Hidden::default()
    }

    /// `text` up to the line that starts with [`Hidden::from`] (all of it when there is none or
    /// it is not found).
    #[must_use]
    pub fn text_before<'a>(&self, text: &'a str) -> &'a str {
        let Some(from) = &self.from else { return text };
        let mut offset = 0;
        for line in text.split_inclusive('\n') {
            if line.trim_start().starts_with(from.as_str()) {
                return text[..offset].trim_end();
            }
            offset += line.len();
        }
        text
    }
}

/// One item of a step's "try" list.
#[derive(Clone, Debug, PartialEq)]
pub struct TryItem {
    /// What to do or watch.
    pub text: String,
    /// The keys that do it, when it is done with keys.
    pub keys: Option<Keys>,
}

/// A multiple-choice question asked before the run (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// The question.
    pub question: String,
    /// The options, each a claim about a run.
    pub options: Vec<PredictOption>,
    /// The index (0-based) of the option a run confirms.
    pub answer: usize,
    /// Said after the answer is revealed.
    pub explain: String,
}

/// One option of a [`Prediction`]: its text and the run that decides it.
#[derive(Clone, Debug, PartialEq)]
pub struct PredictOption {
    /// What the student chooses.
    pub text: String,
    /// The keys of the run, from the step's start.
    pub keys: Keys,
    /// The claim: this outcome (kind, time, speed, body) of that run. Its `text` is the option's.
    pub claim: Goal,
}

impl Step {
    /// The longest simulated time (s) its goal or a prediction's option is decided at (0 when
    /// it has neither).
    #[must_use]
    pub fn horizon(&self) -> f64 {
        let goal = self.goal.as_ref().map_or(0.0, |g| g.time + SETTLE_HOLD);
        let predict = self.predict.as_ref().map_or(0.0, |p| {
            p.options
                .iter()
                .fold(0.0f64, |a, o| a.max(o.claim.time + SETTLE_HOLD))
        });
        goal.max(predict)
    }

    /// The keys that reach the step's goal (see the module docs), if it has a goal.
    #[must_use]
    pub fn goal_keys(&self) -> Option<&Keys> {
        let goal = self.goal.as_ref()?;
        match goal.try_item {
            Some(n) => self.try_list.get(n.checked_sub(1)?)?.keys.as_ref(),
            None => self.try_list.iter().rev().find_map(|t| t.keys.as_ref()),
        }
    }

    /// Body `body` (1-based) of the settle check, if any.
    #[must_use]
    pub fn goal_body(&self) -> Option<usize> {
        self.goal.as_ref().and_then(|g| g.body)
    }
}

/// The built-in lessons, each parsed or with its error (shown in the menu, never a crash).
#[must_use]
pub fn builtin() -> Vec<Result<Lesson, LessonError>> {
    let mut lessons: Vec<_> = BUILTIN
        .iter()
        .map(|(file, text)| parse(text, &format!("lessons/{file}"), None))
        .collect();
    sort(&mut lessons);
    lessons
}

/// Every `*.md` file of `dir`, each parsed or with its error, sorted by lesson number.
///
/// # Errors
/// When the directory cannot be read.
pub fn load_dir(dir: &Path) -> std::io::Result<Vec<Result<Lesson, LessonError>>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    files.sort();
    let mut lessons: Vec<_> = files
        .iter()
        .map(|path| {
            let name = path.display().to_string();
            match scene::file::read_bounded(path, Limits::DEFAULT.file_bytes) {
                Ok(text) => parse(&text, &name, path.parent()),
                Err(e) => Err(LessonError {
                    file: name,
                    line: 1,
                    column: None,
                    message: match e {
                        SceneError::Io { source, .. } => format!("cannot read: {source}"),
                        other => other.to_string(),
                    },
                }),
            }
        })
        .collect();
    sort(&mut lessons);
    Ok(lessons)
}

fn sort(lessons: &mut [Result<Lesson, LessonError>]) {
    lessons.sort_by_key(|l| match l {
        Ok(l) => (l.number, String::new()),
        Err(e) => (u32::MAX, e.file.clone()),
    });
    reject_duplicates(lessons);
    // Rejected duplicates go to the end with the other errors.
    lessons.sort_by_key(|l| match l {
        Ok(l) => (l.number, String::new()),
        Err(e) => (u32::MAX, e.file.clone()),
    });
}
