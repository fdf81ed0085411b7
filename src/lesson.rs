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
//! the error shown in the menu, like a malformed lesson.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::Deserialize;

pub mod keys;
pub mod numbers;

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
    let horizon = horizon.max(HORIZON);
    let steps = budget::steps_for(horizon, dt);
    budget::run(what.to_string(), scene, dt, steps)
        .check(&Limits::DEFAULT)
        .map_err(|e| e.to_string())?;
    let rate = budget::updates_per_step(scene, None) / dt;
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

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HeaderToml {
    number: toml::Spanned<u32>,
    slug: toml::Spanned<String>,
    title: String,
    summary: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StepToml {
    title: String,
    scene: String,
    #[serde(default)]
    params: toml::Table,
    method: Option<toml::Spanned<String>>,
    dt: Option<toml::Spanned<f64>>,
    #[serde(default)]
    plots: Vec<Plot>,
    #[serde(default, rename = "try")]
    try_list: Vec<toml::Spanned<TryToml>>,
    goal: Option<toml::Spanned<Goal>>,
    predict: Option<toml::Spanned<PredictToml>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum TryToml {
    Text(String),
    Keyed { text: String, keys: String },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PredictToml {
    question: String,
    options: Vec<OptionToml>,
    answer: usize,
    keys: Option<String>,
    expect: Option<GoalKind>,
    time: Option<f64>,
    speed: Option<f64>,
    body: Option<usize>,
    #[serde(default)]
    explain: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OptionToml {
    text: String,
    keys: Option<String>,
    expect: Option<GoalKind>,
    time: Option<f64>,
    speed: Option<f64>,
    body: Option<usize>,
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

/// Parses lesson text; `file` names it in errors and `base_dir` resolves scene file paths.
///
/// # Errors
/// A [`LessonError`] naming the file and line: missing or unterminated front matter, TOML errors
/// (with column), unknown keys, a scene or parameter that does not build, an unknown method, a
/// non-positive dt or goal time, a lesson without steps.
pub fn parse(text: &str, file: &str, base_dir: Option<&Path>) -> Result<Lesson, LessonError> {
    let err = |line: usize, column: Option<usize>, message: String| LessonError {
        file: file.to_string(),
        line,
        column,
        message: scene::file::excerpt(&message, scene::file::MAX_MESSAGE),
    };
    // A byte order mark is no content (scene files accept it too).
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lines: Vec<&str> = text.lines().collect();
    // Blocks: (kind "lesson" | "step", first front-matter line index, toml text, body text).
    let mut blocks: Vec<(bool, usize, String, String)> = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let trimmed = lines[i].trim_end();
        let is_step = trimmed == "+++ step";
        if trimmed == "+++" || is_step {
            if !is_step && !blocks.is_empty() {
                return Err(err(
                    i + 1,
                    None,
                    "expected `+++ step` to start a step (the lesson header comes once, first)"
                        .into(),
                ));
            }
            let start = i + 1;
            let end = (start..lines.len())
                .find(|&j| lines[j].trim_end() == "+++")
                .ok_or_else(|| {
                    err(
                        i + 1,
                        None,
                        "front matter opened here is never closed with `+++`".into(),
                    )
                })?;
            let toml_text = lines[start..end].join("\n");
            let body_end = (end + 1..lines.len())
                .find(|&j| matches!(lines[j].trim_end(), "+++ step" | "+++"))
                .unwrap_or(lines.len());
            let body = lines[end + 1..body_end].join("\n").trim().to_string();
            blocks.push((is_step, start, toml_text, body));
            i = body_end;
        } else if blocks.is_empty() && !trimmed.is_empty() {
            return Err(err(
                i + 1,
                None,
                "expected the lesson header: a `+++` line, TOML, and `+++`".into(),
            ));
        } else {
            i += 1;
        }
    }
    // Line and column of a byte offset inside a front-matter block that starts at line index `start`.
    let position = |start: usize, toml_text: &str, offset: usize| {
        let before = &toml_text[..offset.min(toml_text.len())];
        let line = start + 1 + before.matches('\n').count();
        let column = before
            .rfind('\n')
            .map_or(before.len(), |p| before.len() - p - 1)
            + 1;
        (line, column)
    };
    let toml_err = |start: usize, toml_text: &str, e: toml::de::Error| {
        let (line, column) = e
            .span()
            .map_or((start + 1, 1), |s| position(start, toml_text, s.start));
        err(line, Some(column), e.message().trim().to_string())
    };
    // Bounded before the TOML reader builds its tree.
    for (_, start, toml_text, _) in &blocks {
        if let Err(e) = scene::file::bounds::check(toml_text) {
            let (line, column) = position(*start, toml_text, e.offset);
            return Err(err(line, Some(column), e.message));
        }
    }

    let Some((false, hstart, htext, _)) = blocks.first() else {
        return Err(err(
            1,
            None,
            "expected the lesson header: a `+++` line, TOML, and `+++`".into(),
        ));
    };
    let header: HeaderToml = toml::from_str(htext).map_err(|e| toml_err(*hstart, htext, e))?;
    let mut steps = Vec::new();
    for (_, start, toml_text, body) in blocks.iter().skip(1) {
        let st: StepToml = toml::from_str(toml_text).map_err(|e| toml_err(*start, toml_text, e))?;
        let at = |offset: usize| position(*start, toml_text, offset);
        let method = match &st.method {
            Some(m) => Some(m.get_ref().parse::<Method>().map_err(|e| {
                let (l, c) = at(m.span().start);
                err(l, Some(c), e.to_string())
            })?),
            None => None,
        };
        if let Some(dt) = &st.dt
            && !(*dt.get_ref() > 0.0 && dt.get_ref().is_finite())
        {
            let (l, c) = at(dt.span().start);
            return Err(err(
                l,
                Some(c),
                format!("dt = {}: expected a time step in seconds > 0", dt.get_ref()),
            ));
        }
        if let Some(goal) = &st.goal {
            let g = goal.get_ref();
            let valid = g.time > 0.0 && g.time.is_finite() && g.speed > 0.0;
            if !valid {
                let (l, c) = at(goal.span().start);
                return Err(err(
                    l,
                    Some(c),
                    "goal: expected time > 0 (s) and speed > 0 (m/s)".into(),
                ));
            }
        }
        let params: Vec<String> = st
            .params
            .iter()
            .map(|(k, v)| format!("{k}={}", value_text(v)))
            .collect();
        let mut try_list = Vec::new();
        for item in st.try_list {
            let (l, c) = at(item.span().start);
            try_list.push(match item.into_inner() {
                TryToml::Text(text) => TryItem { text, keys: None },
                TryToml::Keyed { text, keys } => {
                    let parsed = Keys::parse(&keys).map_err(|m| err(l, Some(c), m))?;
                    TryItem {
                        text,
                        keys: Some(parsed),
                    }
                }
            });
        }
        let goal_span = st.goal.as_ref().map(|g| at(g.span().start));
        let goal = st.goal.map(toml::Spanned::into_inner);
        if let (Some(g), Some((l, c))) = (&goal, goal_span) {
            let keyed = |i: usize| try_list.get(i).is_some_and(|t| t.keys.is_some());
            match g.try_item {
                Some(n) if n == 0 || !keyed(n - 1) => {
                    return Err(err(
                        l,
                        Some(c),
                        format!(
                            "goal: try = {n}: expected the number (from 1) of a try item with keys"
                        ),
                    ));
                }
                None if !(0..try_list.len()).any(keyed) => {
                    return Err(err(
                        l,
                        Some(c),
                        "goal: expected a try item with `keys` that reaches it (the tests play it)"
                            .into(),
                    ));
                }
                _ => {}
            }
            if g.body.is_some() && g.kind != GoalKind::Settle {
                return Err(err(
                    l,
                    Some(c),
                    "goal: `body` applies to `settle` only".into(),
                ));
            }
        }
        let predict = match st.predict {
            None => None,
            Some(p) => {
                let (l, c) = at(p.span().start);
                Some(prediction(p.into_inner()).map_err(|m| err(l, Some(c), m))?)
            }
        };
        // Placeholders: known names, methods and scenes (computed when the step opens).
        if let Some((offset, message)) = numbers::check(body).into_iter().next() {
            let line = body_line(&lines, *start, offset);
            return Err(err(line, None, message));
        }
        let step = Step {
            title: st.title,
            scene: st.scene,
            params,
            method,
            dt: st.dt.map(|d| *d.get_ref()),
            plots: st.plots,
            try_list,
            goal,
            predict,
            text: body.clone(),
            base_dir: base_dir.map(Path::to_path_buf),
        };
        // Validate now, so a broken lesson shows its error in the menu, not mid-lesson.
        let scene = step
            .build_scene()
            .map_err(|e| err(*start, None, format!("step \"{}\": {e}", step.title)))?;
        check_budget(
            &scene,
            scene.dt,
            step.horizon(),
            &format!("step \"{}\"", step.title),
        )
        .map_err(|m| err(*start, None, m))?;
        if numbers::needs_omega(body) {
            check_omega_cost(&scene, &format!("step \"{}\"", step.title))
                .map_err(|m| err(*start, None, m))?;
        }
        // `{{param:KEY}}`: a parameter of its scene.
        if let Some((offset, message)) = numbers::check_params(body, &step.scene).into_iter().next()
        {
            let line = body_line(&lines, *start, offset);
            return Err(err(line, None, message));
        }
        steps.push(step);
    }
    if steps.is_empty() {
        return Err(err(
            lines.len().max(1),
            None,
            "a lesson needs at least one `+++ step`".into(),
        ));
    }
    let header_lines = (
        position(*hstart, htext, header.number.span().start).0,
        position(*hstart, htext, header.slug.span().start).0,
    );
    Ok(Lesson {
        number: header.number.into_inner(),
        slug: header.slug.into_inner(),
        header_lines,
        title: header.title,
        summary: header.summary,
        steps,
        source: file.to_string(),
    })
}

/// Turns every lesson whose number or slug an earlier one (in number order, then file order)
/// already has into an error at the line of its `number` or `slug`, naming the other file: two
/// lessons with one number would make `springlab lesson 3` ambiguous.
fn reject_duplicates(lessons: &mut [Result<Lesson, LessonError>]) {
    // (number, slug, file:line of its number, file:line of its slug)
    let mut seen: Vec<(u32, String, String, String)> = Vec::new();
    for entry in lessons.iter_mut() {
        let Ok(lesson) = entry else { continue };
        let by_number = seen.iter().find(|(n, ..)| *n == lesson.number);
        let by_slug = seen.iter().find(|(_, s, ..)| *s == lesson.slug);
        let error = match (by_number, by_slug) {
            (Some((n, _, at, _)), _) => Some((
                lesson.header_lines.0,
                format!(
                    "lesson number {n} is already used by {at}; give each lesson its own number"
                ),
            )),
            (None, Some((_, slug, _, at))) => Some((
                lesson.header_lines.1,
                format!(
                    "lesson slug \"{slug}\" is already used by {at}; give each lesson its own slug"
                ),
            )),
            (None, None) => None,
        };
        match error {
            Some((line, message)) => {
                *entry = Err(LessonError {
                    file: lesson.source.clone(),
                    line,
                    column: None,
                    message,
                });
            }
            None => seen.push((
                lesson.number,
                lesson.slug.clone(),
                format!("{}:{}", lesson.source, lesson.header_lines.0),
                format!("{}:{}", lesson.source, lesson.header_lines.1),
            )),
        }
    }
}

/// The 1-based file line of byte `offset` of the body of the block whose front matter starts at
/// line index `start`.
fn body_line(lines: &[&str], start: usize, offset: usize) -> usize {
    // The body starts after the closing `+++`; leading blank lines were trimmed.
    let close = (start..lines.len())
        .find(|&j| lines[j].trim_end() == "+++")
        .unwrap_or(start);
    let first = (close + 1..lines.len())
        .find(|&j| !lines[j].trim().is_empty())
        .unwrap_or(close + 1);
    let mut rest = offset;
    for (j, line) in lines.iter().enumerate().skip(first) {
        if rest <= line.len() {
            return j + 1;
        }
        rest -= line.len() + 1;
    }
    lines.len()
}

/// A prediction from its front matter, each option's claim resolved.
fn prediction(p: PredictToml) -> Result<Prediction, String> {
    if p.options.len() < 2 || p.options.len() > 6 {
        return Err("predict: expected 2 to 6 options".into());
    }
    if p.answer == 0 || p.answer > p.options.len() {
        return Err(format!(
            "predict: answer = {}: expected the number (from 1) of an option, at most {}",
            p.answer,
            p.options.len()
        ));
    }
    let mut options = Vec::new();
    for (i, o) in p.options.into_iter().enumerate() {
        let n = i + 1;
        let keys = o.keys.or_else(|| p.keys.clone()).ok_or_else(|| {
            format!("predict: option {n}: expected `keys` (on the option or the prediction)")
        })?;
        let keys = Keys::parse(&keys).map_err(|m| format!("predict: option {n}: {m}"))?;
        let kind = o.expect.or(p.expect).ok_or_else(|| {
            format!("predict: option {n}: expected `expect` = survive, diverge or settle")
        })?;
        let time = o.time.or(p.time).ok_or_else(|| {
            format!("predict: option {n}: expected `time` (s) of the run that decides it")
        })?;
        let speed = o.speed.or(p.speed).unwrap_or_else(default_settle_speed);
        if !(time > 0.0 && time.is_finite() && speed > 0.0) {
            return Err(format!(
                "predict: option {n}: expected time > 0 (s) and speed > 0 (m/s)"
            ));
        }
        let body = o.body.or(p.body);
        if body.is_some() && kind != GoalKind::Settle {
            return Err(format!(
                "predict: option {n}: `body` applies to `settle` only"
            ));
        }
        options.push(PredictOption {
            claim: Goal {
                kind,
                time,
                speed,
                body,
                try_item: None,
                text: o.text.clone(),
            },
            text: o.text,
            keys,
        });
    }
    Ok(Prediction {
        question: p.question,
        options,
        answer: p.answer - 1,
        explain: p.explain,
    })
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

/// TOML value → the text `--set` accepts (`3`, `0.5`, `[0, 1]`, `[0.0, 2.0, 0.0]`).
fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::Array(items) => {
            let inner: Vec<String> = items.iter().map(value_text).collect();
            format!("[{}]", inner.join(", "))
        }
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
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
