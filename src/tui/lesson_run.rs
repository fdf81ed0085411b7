//! One open lesson at one step, the model of the lesson screen: the step's simulation stepped
//! against wall time, its initial states, the camera, the goal and prediction, the plots'
//! records and the progress through the lesson.
//!
//! The views read it ([`super::lesson_view`], [`super::sim_view`], [`super::status`]); the keys
//! and the mouse change it (`controls.rs`); `goals.rs` judges the goal and the prediction after
//! each step.

mod background;
mod camera;
mod clock;
mod controls;
mod deferred;
mod goals;
mod memo;
mod observed;
mod reveal;
mod usable;

pub use background::lower_priority;
pub use observed::Observed;
pub use usable::UsableDt;

use clock::Rates;

use super::pane::{DOTS, SpringFilter};
use super::plots::{self, History, Oscillator, Studies};
use crate::lesson::{GoalProgress, Lesson, Step};
use crate::physics::{Method, SpringKind, State};
use crate::render::Camera;
use crate::simulation::Simulation;

/// Default cap on the steps taken in one frame.
pub const DEFAULT_MAX_STEPS_PER_FRAME: u64 = 4096;

/// Range of the cap on steps per frame (`[` halves it, `]` doubles it).
pub const STEPS_PER_FRAME_RANGE: (u64, u64) = (1, 1 << 20);

/// Range of the time step the `+` / `-` keys reach (s).
pub const DT_RANGE: (f64, f64) = (1e-7, 1.0);

/// Range of the speed factor (simulated seconds per wall second).
pub const SPEED_RANGE: (f64, f64) = (1.0 / 64.0, 64.0);

/// Factor of one press of `k` / `K` and `d` / `D`.
pub const COEFFICIENT_FACTOR: f64 = 1.5;

/// `D` on an undamped spring starts at this fraction of its critical damping `2√(k m)`.
pub const FIRST_DAMPING: f64 = 0.01;

/// `A` on a scene without drag starts it at this rate `c/m` (1/s, `m` the mean particle mass);
/// then ×2 per press (`a`: ÷2, to zero below the first value).
pub const FIRST_DRAG_RATE: f64 = 0.25;

/// `G` on Verlet without damping starts γ here; then ×10 per press up to [`MAX_VERLET_GAMMA`]
/// (`g`: ÷10, to zero below the first value).
pub const FIRST_VERLET_GAMMA: f64 = 5e-5;

/// The largest γ `G` reaches (per step; 1 would stop every motion at once).
pub const MAX_VERLET_GAMMA: f64 = 0.5;

/// Largest number of projection passes `J` reaches (×2 per press; `j`: ÷2).
pub const MAX_PASSES: u32 = 1024;

/// Columns one press of `h` / `l` scrolls the step's code blocks and tables.
pub const HSCROLL_STEP: u16 = 8;

/// Fraction of the visible height one press of Shift + arrow moves the view.
pub const PAN_STEP: f64 = 0.1;

/// Following keeps every body within this fraction of the view's half-width and half-height:
/// more than the `1/1.08` that the step's first framing leaves the framed region, so a step
/// never starts with the camera moving.
pub const FOLLOW_ZONE: f64 = 0.95;

/// Following moves the eye back at most this many times the step's initial distance.
pub const FOLLOW_MAX_ZOOM_OUT: f64 = 10.0;

/// Once following has had to move the view for bodies free of pins (a cube sliding down a
/// slope), the camera tracks them: its target approaches their centroid, led by their mean
/// velocity, at this rate (1/s of simulated time), so a body keeps to the middle of the pane
/// at its first size instead of riding along the pane's edge. Pinned bodies (a rope, a hung
/// cloth) swing about their pins: the view never tracks them, it only widens.
pub const TRACK_RATE: f64 = 4.0;

/// Aspect ratio (width / height, in pixels) of the scene pane before the app reports it: the
/// pane of a 120 × 40 terminal.
pub const DEFAULT_ASPECT: f64 = 1.75;

/// A particle held by the mouse: pinned while held, its inverse mass restored on release.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Drag {
    body: usize,
    index: usize,
    inv_mass: f64,
    /// Depth of the particle in view coordinates (m): it moves in the view plane.
    depth: f64,
}

/// The four corners of an `n × n` cloth body (keys 1–4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Cloth {
    body: usize,
    n: usize,
}

/// The method chooser (`m`): a list of the methods, one of them highlighted, and which bodies a
/// choice applies to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chooser {
    /// The highlighted entry of [`Method::ALL`].
    pub selected: usize,
    /// The body a choice applies to (`None`: every body); Tab cycles it.
    pub target: Option<usize>,
}

/// The key that picks each method in the chooser (beside its number), from its declaration.
#[must_use]
pub fn method_key(method: Method) -> char {
    method.declaration().key
}

/// What the status line says about the method's stability limit at the present scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Limit {
    /// Stable below this dt (s), by the damped theory of the scene (dampers and drag included).
    Below(f64),
    /// No dt is stable (explicit Euler or midpoint without damping).
    Never,
    /// Stable at any dt.
    Always,
    /// The theory does not cover the method (projection, XPBD).
    NotCovered,
}

/// An open lesson at one step, with its simulation running or paused.
#[derive(Clone, Debug)]
pub struct LessonRun {
    lesson: Lesson,
    step: usize,
    sim: Simulation,
    /// The body states at `t = 0`, restored by `r`.
    initial: Vec<State>,
    running: bool,
    /// Simulated time owed to the simulation (s), paid in whole steps.
    accumulator: f64,
    /// Simulated seconds per wall second.
    speed: f64,
    max_steps_per_frame: u64,
    last_frame_steps: u64,
    rates: Rates,
    /// The camera the pane shows (every view, and `e`).
    camera: Camera,
    /// The step's initial camera, restored by `r`, `c` and on entering a step.
    home: Camera,
    /// The camera keeps the bodies in view.
    follow: bool,
    /// The camera tracks the followed bodies (see [`TRACK_RATE`]).
    tracking: bool,
    /// Width / height of the scene pane in pixels.
    aspect: f64,
    /// Changes whenever the scene's structure (bodies, springs) may have changed.
    generation: u64,
    /// The last cell of a drag that pans the view (the left button on empty space).
    pan_drag: Option<(u16, u16)>,
    /// Changes whenever what the pane shows may have changed (a key, the mouse, a step).
    version: u64,
    /// Pixels of a cell in the view shown (dots for braille and half-blocks, the font cell for
    /// raster): the mouse maps cells to the scene through it.
    grid: (u32, u32),
    filter: SpringFilter,
    history: History,
    oscillator: Option<Oscillator>,
    /// Study results for the step's study plots.
    studies: Studies,
    cloth: Option<Cloth>,
    /// The goal's verdict once decided: met or failed.
    goal: Option<bool>,
    /// What the goal remembers between frames.
    goal_progress: GoalProgress,
    message: Option<String>,
    drag: Option<Drag>,
    text_scroll: u16,
    /// Rows of the step's text the last frame showed: PgUp / PgDn move by that page.
    text_rows: std::cell::Cell<u16>,
    /// Which of the step's plots shows where only one fits (Tab turns to the next).
    plot_turn: usize,
    /// Columns the code blocks and tables of the text are scrolled to the left.
    hscroll: u16,
    /// The step's text with its numbers filled in (computed when the step opens).
    text: String,
    /// The method chooser, when open.
    chooser: Option<Chooser>,
    /// Per step: its goal was met (in this visit or an earlier one, see [`LessonRun::restore`]).
    met: Vec<bool>,
    /// Per step: the student opened it.
    visited: Vec<bool>,
    /// Per step: the option the student predicted (0-based).
    answers: Vec<Option<usize>>,
    /// The prediction's result is shown: a run after the answer was decided.
    revealed: Option<String>,
    /// Something that the progress file keeps changed (met goals, visits, answers).
    progress_changed: bool,
    /// Which methods the study charts show (by index into [`Method::ALL`]).
    shown: [bool; Method::COUNT],
    /// Per body: the linearised spectrum at the step's initial state (for the status line).
    spectra: std::sync::Arc<background::Bodies>,
    /// The limit's worker (in the event loop).
    limits: background::Limits,
    /// The stability limit of the present methods, dampers and drag included.
    limit: Option<(Limit, f64)>,
    /// The usable dt below it (`usable.rs`).
    usable: usable::State,
    /// The spectra recomputed off the drawing thread after a change of the coefficients.
    background: background::Spectra,
    /// The limit waits to be recomputed (once for a burst of keys: see
    /// [`LessonRun::poll_background`]).
    limit_stale: bool,
    /// In the event loop: a new step's numbers, studies and spectra and the exports are
    /// computed off the drawing thread (`deferred.rs`); otherwise at once.
    deferred: bool,
    /// A new step's text numbers and study charts (when deferred).
    step_work: deferred::StepWorker,
    /// The `e` exports (when deferred).
    exports: deferred::Exports,
    /// A key changed what the spectra depend on since the last request.
    spectra_wanted: bool,
    /// The observable's readings (steps with the `observable` plot).
    observed: Observed,
    /// The speed was set by the step's front matter.
    speed_from_step: bool,
    /// Where each step's body goes to the attached homework's reference (`goals.rs`).
    handover: Option<crate::grade::live::Handover>,
}

impl LessonRun {
    /// Opens `lesson` at step `step` (0-based), paused at `t = 0`.
    ///
    /// # Errors
    /// The step does not exist or its scene does not build (the message says which).
    pub fn new(lesson: Lesson, step: usize) -> Result<LessonRun, String> {
        LessonRun::with_deferred(lesson, step, false)
    }

    /// As [`LessonRun::new`]; with `deferred` (the event loop) what a step computes beside its
    /// scene (text numbers, study charts, spectra) and the exports are computed off the drawing
    /// thread, and [`LessonRun::poll_background`] takes them when ready.
    ///
    /// # Errors
    /// As [`LessonRun::new`].
    pub fn with_deferred(lesson: Lesson, step: usize, deferred: bool) -> Result<LessonRun, String> {
        let sim = build(&lesson, step)?;
        let mut run = LessonRun {
            initial: Vec::new(),
            camera: Camera::default(),
            home: Camera::default(),
            follow: true,
            tracking: false,
            aspect: DEFAULT_ASPECT,
            generation: 0,
            pan_drag: None,
            version: 0,
            grid: DOTS,
            history: History::new(sim.dt(), None),
            sim,
            lesson,
            step,
            running: false,
            accumulator: 0.0,
            speed: 1.0,
            max_steps_per_frame: DEFAULT_MAX_STEPS_PER_FRAME,
            last_frame_steps: 0,
            rates: Rates::default(),
            filter: SpringFilter::All,
            oscillator: None,
            studies: Studies::default(),
            cloth: None,
            goal: None,
            goal_progress: GoalProgress::default(),
            message: None,
            drag: None,
            text_scroll: 0,
            text_rows: std::cell::Cell::new(5),
            plot_turn: 0,
            hscroll: 0,
            text: String::new(),
            chooser: None,
            met: Vec::new(),
            visited: Vec::new(),
            answers: Vec::new(),
            revealed: None,
            progress_changed: false,
            shown: [true; Method::COUNT],
            spectra: std::sync::Arc::new(Vec::new()),
            limits: background::Limits::default(),
            limit: None,
            usable: usable::State::default(),
            background: background::Spectra::default(),
            limit_stale: false,
            deferred,
            step_work: deferred::StepWorker::default(),
            exports: deferred::Exports::default(),
            spectra_wanted: false,
            observed: Observed::default(),
            speed_from_step: false,
            handover: None,
        };
        let n = run.lesson.steps.len();
        run.met = vec![false; n];
        run.visited = vec![false; n];
        run.answers = vec![None; n];
        run.start_step();
        Ok(run)
    }

    /// Replaces the step's scene with `scene` (a scene built in code, for tests and tools), paused
    /// at its start; `r` returns to this scene's initial state.
    pub fn set_scene(&mut self, scene: crate::scene::Scene) {
        self.sim = Simulation::new(scene);
        self.filter = SpringFilter::All;
        self.start_step();
    }

    /// Everything that follows from a freshly built scene.
    fn start_step(&mut self) {
        self.restart_scene();
        let step = &self.lesson.steps[self.step];
        if self.deferred {
            self.text = deferred::placeholders_pending(&step.text);
            self.studies = Studies::default();
            let inputs = deferred::StepInputs {
                text: step.text.clone(),
                name: step.scene.clone(),
                params: step.params.clone(),
                plots: step.plots.clone(),
                scene: self.scene_at_start(),
            };
            self.step_work.request(inputs);
        } else {
            let work = deferred::step_work(deferred::StepInputs {
                text: step.text.clone(),
                name: step.scene.clone(),
                params: step.params.clone(),
                plots: step.plots.clone(),
                scene: self.scene_at_start(),
            });
            self.studies = work.studies;
            self.text = work.text;
        }
        self.text_scroll = 0;
        self.hscroll = 0;
        self.plot_turn = 0;
        self.revealed = None;
        if let Some(v) = self.visited.get_mut(self.step)
            && !*v
        {
            *v = true;
            self.progress_changed = true;
        }
    }

    /// What a freshly built scene of this step starts with: its initial states, its first view,
    /// every method shown in the study charts, paused at `t = 0` (shared by a new step and `R`;
    /// the text, the studies and the prediction's answer stay).
    fn restart_scene(&mut self) {
        // The step's own speed (front matter), or back to real time after a step that had one.
        if let Some(speed) = self.lesson.steps[self.step].speed {
            self.speed = speed;
            self.speed_from_step = true;
        } else if std::mem::take(&mut self.speed_from_step) {
            self.speed = 1.0;
        }
        self.initial = self.sim.states().cloned().collect();
        self.generation += 1;
        self.home = self.first_view(self.aspect);
        self.camera = self.home;
        self.follow = true;
        self.tracking = false;
        self.pan_drag = None;
        self.oscillator = Oscillator::detect(&self.sim.scene);
        self.cloth = find_cloth(&self.sim);
        self.running = false;
        self.drag = None;
        self.chooser = None;
        self.shown = [true; Method::COUNT];
        // Outside the event loop a new step waits for its spectra: the status line is right from
        // the first frame. In it, the limit shows "computing…" until they arrive.
        if self.deferred {
            self.spectra = std::sync::Arc::new(Vec::new());
            self.refresh_limit();
            self.refresh_spectra();
        } else {
            self.spectra = std::sync::Arc::new(background::compute(&self.bodies_at_start()));
            self.refresh_limit();
        }
        self.restart_records();
    }

    /// The step's text with its computed numbers.
    #[must_use]
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Asks the background worker for every body's spectrum (after a change of stiffness,
    /// damping, drag or pins); the limit follows when it arrives ([`LessonRun::poll_background`],
    /// [`LessonRun::settle`]).
    /// Once per loop turn however many keys asked (the models are copied for the worker).
    fn refresh_spectra(&mut self) {
        self.spectra_wanted = true;
    }

    /// Sends the request [`LessonRun::refresh_spectra`] marked.
    fn send_spectra_request(&mut self) {
        if std::mem::take(&mut self.spectra_wanted) {
            let bodies = self.bodies_at_start();
            self.background.request(bodies);
        }
    }

    /// Every body's model with its initial state.
    fn bodies_at_start(&self) -> Vec<(crate::physics::Model, State)> {
        self.sim
            .scene
            .bodies
            .iter()
            .zip(&self.initial)
            .map(|(b, initial)| (b.model.clone(), initial.clone()))
            .collect()
    }

    /// Takes the spectra the worker finished since the last call and recomputes the limit
    /// when a key changed what it depends on (once per frame however many keys came in: the
    /// theory's limit over every mode of the cloth takes tens of milliseconds); true when the
    /// limit changed.
    pub fn poll_background(&mut self) -> bool {
        self.send_spectra_request();
        if let Some(spectra) = self.background.poll() {
            self.spectra = std::sync::Arc::new(spectra);
            self.limit_stale = true;
        }
        let mut changed = false;
        if let Some(limit) = self.limits.poll() {
            self.limit = limit;
            self.limit_changed();
            self.version += 1;
            changed = true;
        }
        changed |= self.usable.poll();
        if let Some(work) = self.step_work.poll() {
            self.take_step_work(work);
            changed = true;
        }
        if let Some(m) = self.exports.poll() {
            self.message = Some(m);
            changed = true;
        }
        self.refresh_stale_limit() || changed
    }

    /// Whether a new step's work and the exports go off the drawing thread (the event loop).
    pub fn set_deferred(&mut self, on: bool) {
        self.deferred = on;
    }

    fn take_step_work(&mut self, work: deferred::StepWork) {
        self.text = work.text;
        self.studies = work.studies;
        self.version += 1;
    }

    /// Waits for the spectra of the newest change and the limit (the public key API and tests
    /// read an up-to-date limit after every key).
    ///
    /// Spectra asked for since the last request are computed on the calling thread: it waits
    /// for them anyway, and a worker at the lower priority `WORKER_NICE` would wait behind every
    /// other busy thread of a loaded machine while the caller sits idle.
    pub fn settle(&mut self) {
        if let Some(work) = self.step_work.settle() {
            self.take_step_work(work);
        }
        // A request the worker already has (from the event loop) first, so that it cannot
        // replace the newer spectra computed below.
        if let Some(spectra) = self.background.settle() {
            self.spectra = std::sync::Arc::new(spectra);
            self.limit_stale = true;
        }
        if std::mem::take(&mut self.spectra_wanted) {
            self.spectra = std::sync::Arc::new(background::compute(&self.bodies_at_start()));
            self.limit_stale = true;
        }
        self.refresh_stale_limit();
        if let Some(limit) = self.limits.settle() {
            self.limit = limit;
            self.limit_changed();
        }
        self.usable.settle();
    }

    fn refresh_stale_limit(&mut self) -> bool {
        if !std::mem::take(&mut self.limit_stale) {
            return false;
        }
        self.refresh_limit();
        self.version += 1;
        true
    }

    /// True while the spectra of the newest change are being computed.
    #[must_use]
    pub fn computing(&self) -> bool {
        self.spectra_wanted
            || self.limit_stale
            || self.background.pending()
            || self.limits.pending()
            || self.usable.pending()
    }

    /// True while anything is computed off the drawing thread (the limit, a new step's numbers
    /// and studies, an export): the event loop then looks for results between inputs.
    #[must_use]
    pub fn busy(&self) -> bool {
        self.computing() || self.step_work.pending() || self.exports.busy()
    }

    /// The limit of the present methods and method settings over the bodies' spectra: at once,
    /// or in the event loop from the limit's worker (over every mode of the cloth it takes tens
    /// of milliseconds, more on a loaded machine).
    fn refresh_limit(&mut self) {
        let methods: Vec<_> = self
            .sim
            .scene
            .bodies
            .iter()
            .map(|b| (b.method, b.params))
            .collect();
        if self.deferred {
            self.limits
                .request((methods, std::sync::Arc::clone(&self.spectra)));
        } else {
            self.limit = background::limit_of(&methods, &self.spectra);
            self.limit_changed();
        }
    }

    /// The stability limit of the present methods on this scene by the damped theory (dampers
    /// and drag included), and ω_max (rad/s); `None` when no spring holds a free particle.
    #[must_use]
    pub fn limit(&self) -> Option<&(Limit, f64)> {
        self.limit.as_ref()
    }

    /// Clears what belongs to one run from `t = 0`: accumulator, history, goal, rates.
    fn restart_records(&mut self) {
        self.accumulator = 0.0;
        self.last_frame_steps = 0;
        self.rates = Rates::default();
        self.goal = None;
        self.goal_progress = GoalProgress::default();
        if let Some(o) = &mut self.oscillator {
            *o = o.restarted(&self.sim);
        }
        self.history = History::new(self.sim.dt(), self.oscillator.as_ref());
        self.history.record(&self.sim, self.oscillator.as_ref());
        let watch = self.lesson.steps[self.step]
            .plots
            .contains(&crate::lesson::Plot::Observable);
        self.observed = Observed::new(&self.sim, watch);
    }

    /// The observable's readings so far (empty unless the step plots it).
    #[must_use]
    pub fn observed(&self) -> &Observed {
        &self.observed
    }

    /// The lesson.
    #[must_use]
    pub fn lesson(&self) -> &Lesson {
        &self.lesson
    }

    /// The current step's index (0-based).
    #[must_use]
    pub fn step_index(&self) -> usize {
        self.step
    }

    /// The current step.
    #[must_use]
    pub fn step(&self) -> &Step {
        &self.lesson.steps[self.step]
    }

    /// The simulation.
    #[must_use]
    pub fn sim(&self) -> &Simulation {
        &self.sim
    }

    /// True while the simulation runs.
    #[must_use]
    pub fn is_running(&self) -> bool {
        self.running
    }

    /// Changes whenever the scene's bodies or springs may have changed (a renderer made for an
    /// older generation must be rebuilt).
    #[must_use]
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Changes whenever what the scene pane shows may have changed.
    #[must_use]
    pub fn version(&self) -> u64 {
        self.version
    }

    /// Tells the run the pixel size of a cell in the view shown (see [`super::pane::grid_view`]).
    pub fn set_grid(&mut self, grid: (u32, u32)) {
        self.grid = (grid.0.max(1), grid.1.max(1));
    }

    /// Shows `message` on the hint line.
    pub fn set_message(&mut self, message: impl Into<String>) {
        self.message = Some(message.into());
    }

    /// Which springs are drawn.
    #[must_use]
    pub fn spring_filter(&self) -> SpringFilter {
        self.filter
    }

    /// Study results for the step's study plots.
    #[must_use]
    pub fn studies(&self) -> &Studies {
        &self.studies
    }

    /// The sampled history of this run.
    #[must_use]
    pub fn history(&self) -> &History {
        &self.history
    }

    /// The oscillator's exact solution, when the scene is the one-spring oscillator.
    #[must_use]
    pub fn oscillator(&self) -> Option<&Oscillator> {
        self.oscillator.as_ref()
    }

    /// The goal's state: `Some(true)` met (in this run or an earlier one: a met goal stays
    /// met), `Some(false)` failed in this run, `None` pending (or no goal).
    #[must_use]
    pub fn goal_state(&self) -> Option<bool> {
        if self.met.get(self.step).copied().unwrap_or(false) {
            Some(true)
        } else {
            self.goal
        }
    }

    /// This run's verdict on the goal alone (`r` clears it), whatever earlier runs did.
    #[must_use]
    pub fn run_verdict(&self) -> Option<bool> {
        self.goal
    }

    /// The method chooser, when open.
    #[must_use]
    pub fn chooser(&self) -> Option<&Chooser> {
        self.chooser.as_ref()
    }

    /// The option predicted at this step (0-based), if any.
    #[must_use]
    pub fn answer(&self) -> Option<usize> {
        self.answers.get(self.step).copied().flatten()
    }

    /// What a decided run showed after the prediction (`None` until then).
    #[must_use]
    pub fn revealed(&self) -> Option<&str> {
        self.revealed.as_deref()
    }

    /// True while the step's prediction waits for an answer (the run waits too).
    #[must_use]
    pub fn awaiting_prediction(&self) -> bool {
        self.step().predict.is_some() && self.answer().is_none()
    }

    /// Which methods the study charts show.
    #[must_use]
    pub fn shown_methods(&self) -> [bool; Method::COUNT] {
        self.shown
    }

    /// Columns the text's code blocks are scrolled to the left.
    #[must_use]
    pub fn hscroll(&self) -> u16 {
        self.hscroll
    }

    /// The last message of a key (for example why it did nothing).
    #[must_use]
    pub fn message(&self) -> Option<&str> {
        self.message.as_deref()
    }

    /// The particle held by the mouse: `(body, index)`.
    #[must_use]
    pub fn dragged(&self) -> Option<(usize, usize)> {
        self.drag.map(|d| (d.body, d.index))
    }

    /// An upper bound on the highest angular frequency of the springs (rad/s): the square root
    /// of the largest [`spring_gershgorin`](crate::study::modes::spring_gershgorin) bound of the
    /// bodies. Exact for one spring with a pinned end (`ω = √(k/m)`); `2√(k/m)` for a long chain,
    /// the value of its fastest mode. Damping, gravity and collisions are left out. `None` when no
    /// spring moves a free particle.
    #[must_use]
    pub fn omega_max(&self) -> Option<f64> {
        let bodies = &self.sim.scene.bodies;
        let any = bodies.iter().any(|b| !b.model.springs().is_empty());
        let max = bodies
            .iter()
            .map(|b| crate::study::modes::spring_gershgorin(&b.model))
            .fold(0.0, f64::max);
        (any && max > 0.0).then(|| max.sqrt())
    }

    /// The stiffness (N/m) when every spring has the same, else `None`.
    #[must_use]
    pub fn uniform_stiffness(&self) -> Option<f64> {
        uniform(self.springs().map(|s| s.stiffness))
    }

    /// The damping (N·s/m) when every spring has the same, else `None`.
    #[must_use]
    pub fn uniform_damping(&self) -> Option<f64> {
        uniform(self.springs().map(|s| s.damping))
    }

    fn springs(&self) -> impl Iterator<Item = &crate::physics::Spring> {
        self.sim.scene.bodies.iter().flat_map(|b| b.model.springs())
    }
}

fn build(lesson: &Lesson, step: usize) -> Result<Simulation, String> {
    let s = lesson
        .steps
        .get(step)
        .ok_or_else(|| format!("lesson {} has no step {}", lesson.number, step + 1))?;
    let scene = s
        .build_scene()
        .map_err(|e| format!("{}: step \"{}\": {e}", lesson.source, s.title))?;
    let mut sim = Simulation::new(scene);
    if let Some(dt) = s.dt
        && dt > 0.0
        && dt.is_finite()
    {
        sim.set_dt(dt);
    }
    Ok(sim)
}

fn uniform(mut values: impl Iterator<Item = f64>) -> Option<f64> {
    let first = values.next()?;
    values.all(|v| v == first).then_some(first)
}

/// The first body that is an `n × n` cloth: `n²` particles whose structural springs join
/// `p` to `p + 1` within a row and `p` to `p + n`, `2n(n-1)` of them.
fn find_cloth(sim: &Simulation) -> Option<Cloth> {
    sim.scene.bodies.iter().enumerate().find_map(|(b, body)| {
        let count = body.model.particle_count();
        let n = (count as f64).sqrt().round() as usize;
        if n < 2 || n * n != count {
            return None;
        }
        let mut structural = 0;
        for s in body.model.springs() {
            if s.kind != SpringKind::Struct {
                continue;
            }
            let (a, c) = (s.a.min(s.b) as usize, s.a.max(s.b) as usize);
            let along_row = c == a + 1 && c % n != 0;
            if !(along_row || c == a + n) {
                return None;
            }
            structural += 1;
        }
        (structural == 2 * n * (n - 1)).then_some(Cloth { body: b, n })
    })
}
