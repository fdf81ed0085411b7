//! One open lesson: its live simulation (stepping, controls, goal) and the lesson screen.
//!
//! The screen shows the step's title, its text on the left with the "try" list and the goal
//! below it, the scene and the step's plots on the right, and two status lines at the bottom.

use std::time::Instant;

use glam::DVec3;
use ratatui::buffer::Buffer;
use ratatui::crossterm::event::{KeyCode, KeyModifiers, MouseButton, MouseEvent, MouseEventKind};
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};

use super::plots::{self, History, Oscillator, Studies};
use super::sim_view::{self, ORBIT_STEP_DEGREES, Painter};
use super::{Theme, export, markdown, status};
use crate::lesson::{GoalKind, GoalProgress, Lesson, Step};
use crate::physics::particles::pin_particle;
use crate::physics::{Method, SpringKind, State, diverge};
use crate::render::camera::ZOOM_STEP;
use crate::render::{Camera, Projection};
use crate::scene::lattice;
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

/// Aspect ratio (width / height, in pixels) of the scene pane before the app reports it: the
/// pane of a 120 × 40 terminal.
pub const DEFAULT_ASPECT: f64 = 1.75;

/// Which spring kinds are drawn (`t` cycles through them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SpringFilter {
    /// Every spring.
    All,
    /// Structural springs only.
    Struct,
    /// Shear springs only.
    Shear,
    /// Bend springs only.
    Bend,
    /// No springs, particles only.
    None,
}

impl SpringFilter {
    /// The next filter in the cycle all → struct → shear → bend → none → all.
    #[must_use]
    pub fn next(self) -> SpringFilter {
        match self {
            SpringFilter::All => SpringFilter::Struct,
            SpringFilter::Struct => SpringFilter::Shear,
            SpringFilter::Shear => SpringFilter::Bend,
            SpringFilter::Bend => SpringFilter::None,
            SpringFilter::None => SpringFilter::All,
        }
    }

    /// Whether springs of `kind` are drawn.
    #[must_use]
    pub fn shows(self, kind: SpringKind) -> bool {
        match self {
            SpringFilter::All => true,
            SpringFilter::Struct => kind == SpringKind::Struct,
            SpringFilter::Shear => kind == SpringKind::Shear,
            SpringFilter::Bend => kind == SpringKind::Bend,
            SpringFilter::None => false,
        }
    }

    /// Its name in the status line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            SpringFilter::All => "all",
            SpringFilter::Struct => "struct",
            SpringFilter::Shear => "shear",
            SpringFilter::Bend => "bend",
            SpringFilter::None => "none",
        }
    }
}

/// A particle held by the mouse: pinned while held, its inverse mass restored on release.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Drag {
    body: usize,
    index: usize,
    inv_mass: f64,
    /// Depth of the particle in view coordinates (m): it moves in the view plane.
    depth: f64,
}

/// Rolling measurements of the run against wall time (from the wall times passed to
/// [`LessonRun::tick`], so deterministic in tests).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Rates {
    wall: f64,
    simulated: f64,
    steps: u64,
    /// Simulated seconds per wall second over the last half second.
    real_time_factor: Option<f64>,
    /// Steps per wall second over the last half second.
    steps_per_second: Option<f64>,
}

impl Rates {
    fn add(&mut self, wall: f64, simulated: f64, steps: u64) {
        self.wall += wall;
        self.simulated += simulated;
        self.steps += steps;
        if self.wall >= 0.5 {
            self.real_time_factor = Some(self.simulated / self.wall);
            self.steps_per_second = Some(self.steps as f64 / self.wall);
            self.wall = 0.0;
            self.simulated = 0.0;
            self.steps = 0;
        }
    }
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

/// The key that picks each method in the chooser (beside the numbers 1–8).
#[must_use]
pub fn method_key(method: Method) -> char {
    match method {
        Method::ExplicitEuler => 'e',
        Method::SemiImplicitEuler => 's',
        Method::Midpoint => 'm',
        Method::Rk4 => 'r',
        Method::ImplicitEuler => 'i',
        Method::PredictorCorrector => 'p',
        Method::Verlet => 'v',
        Method::Xpbd => 'x',
    }
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
    shown: [bool; 8],
    /// Per body: the linearised spectrum at the step's initial state (for the status line).
    spectra: Vec<Option<crate::study::theory::Spectrum>>,
    /// The stability limit of the present methods, dampers and drag included.
    limit: Option<(Limit, f64)>,
}

impl LessonRun {
    /// Opens `lesson` at step `step` (0-based), paused at `t = 0`.
    ///
    /// # Errors
    /// The step does not exist or its scene does not build (the message says which).
    pub fn new(lesson: Lesson, step: usize) -> Result<LessonRun, String> {
        let sim = build(&lesson, step)?;
        let mut run = LessonRun {
            initial: Vec::new(),
            camera: Camera::default(),
            home: Camera::default(),
            follow: true,
            aspect: DEFAULT_ASPECT,
            generation: 0,
            pan_drag: None,
            version: 0,
            grid: sim_view::DOTS,
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
            hscroll: 0,
            text: String::new(),
            chooser: None,
            met: Vec::new(),
            visited: Vec::new(),
            answers: Vec::new(),
            revealed: None,
            progress_changed: false,
            shown: [true; 8],
            spectra: Vec::new(),
            limit: None,
        };
        let n = run.lesson.steps.len();
        run.met = vec![false; n];
        run.visited = vec![false; n];
        run.answers = vec![None; n];
        run.start_step();
        Ok(run)
    }

    /// Restores what the student did before (met goals, visited steps, predictions), for
    /// example from the progress file; lengths that do not match the lesson are cut or padded.
    pub fn restore(&mut self, met: &[bool], visited: &[bool], answers: &[Option<usize>]) {
        let n = self.lesson.steps.len();
        for i in 0..n {
            self.met[i] |= met.get(i).copied().unwrap_or(false);
            self.visited[i] |= visited.get(i).copied().unwrap_or(false);
            if self.answers[i].is_none() {
                self.answers[i] = answers.get(i).copied().flatten().filter(|&a| {
                    self.lesson.steps[i]
                        .predict
                        .as_ref()
                        .is_some_and(|p| a < p.options.len())
                });
            }
        }
    }

    /// Per step: its goal was met.
    #[must_use]
    pub fn met_goals(&self) -> &[bool] {
        &self.met
    }

    /// Per step: the student opened it.
    #[must_use]
    pub fn visited_steps(&self) -> &[bool] {
        &self.visited
    }

    /// Per step: the option predicted (0-based).
    #[must_use]
    pub fn answers(&self) -> &[Option<usize>] {
        &self.answers
    }

    /// True once since the last call when met goals, visits or answers changed.
    pub fn take_progress_changed(&mut self) -> bool {
        std::mem::take(&mut self.progress_changed)
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
        self.initial = self.sim.states().cloned().collect();
        self.generation += 1;
        self.home = Camera::for_scene(&self.sim.scene, self.aspect, Projection::default());
        self.camera = self.home;
        self.follow = true;
        self.pan_drag = None;
        self.oscillator = Oscillator::detect(&self.sim.scene);
        let step = &self.lesson.steps[self.step];
        self.studies = Studies::compute(&step.plots, &step.scene, &step.params);
        self.text = crate::lesson::numbers::fill(
            &step.text,
            &step.scene,
            &step.params,
            Some(self.scene_at_start()),
        );
        self.cloth = find_cloth(&self.sim);
        self.running = false;
        self.drag = None;
        self.text_scroll = 0;
        self.hscroll = 0;
        self.chooser = None;
        self.revealed = None;
        if let Some(v) = self.visited.get_mut(self.step)
            && !*v
        {
            *v = true;
            self.progress_changed = true;
        }
        self.refresh_spectra();
        self.restart_records();
    }

    /// The step's text with its computed numbers.
    #[must_use]
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Recomputes every body's spectrum (after a change of stiffness, damping, drag or pins)
    /// and the limit.
    fn refresh_spectra(&mut self) {
        use crate::study::{omega_max, theory};
        self.spectra = self
            .sim
            .scene
            .bodies
            .iter()
            .zip(&self.initial)
            .map(|(b, initial)| {
                let omega = omega_max(&b.model, initial).omega;
                (omega > 0.0 && omega.is_finite())
                    .then(|| theory::spectrum(&b.model, initial, omega))
            })
            .collect();
        self.refresh_limit();
    }

    /// The limit of the present methods and method settings over the bodies' spectra.
    fn refresh_limit(&mut self) {
        use crate::study::theory;
        let mut limit: Option<Limit> = None;
        let mut omega = 0.0f64;
        for (b, spectrum) in self.sim.scene.bodies.iter().zip(&self.spectra) {
            let Some(spectrum) = spectrum else { continue };
            omega = omega.max(spectrum.omega_max);
            let l = theory::limit(b.method, &b.params, spectrum);
            let this = match (l.stability, l.dt) {
                ("conditional", Some(dt)) => Limit::Below(dt),
                ("none", _) => Limit::Never,
                ("unconditional", _) => Limit::Always,
                _ => Limit::NotCovered,
            };
            // The most restrictive body decides.
            let rank = |l: &Limit| match l {
                Limit::Never => 0,
                Limit::Below(_) => 1,
                Limit::NotCovered => 2,
                Limit::Always => 3,
            };
            limit = Some(match limit {
                None => this,
                Some(Limit::Below(a)) if matches!(this, Limit::Below(b) if b < a) => this,
                Some(prev) if rank(&this) < rank(&prev) => this,
                Some(prev) => prev,
            });
        }
        self.limit = limit.map(|l| (l, omega));
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

    /// The cap on steps per frame.
    #[must_use]
    pub fn max_steps_per_frame(&self) -> u64 {
        self.max_steps_per_frame
    }

    /// Sets the cap on steps per frame (clamped to [`STEPS_PER_FRAME_RANGE`]).
    pub fn set_max_steps_per_frame(&mut self, n: u64) {
        self.max_steps_per_frame = n.clamp(STEPS_PER_FRAME_RANGE.0, STEPS_PER_FRAME_RANGE.1);
    }

    /// Steps taken in the last frame.
    #[must_use]
    pub fn last_frame_steps(&self) -> u64 {
        self.last_frame_steps
    }

    /// Simulated time owed to the simulation (s).
    #[must_use]
    pub fn accumulator(&self) -> f64 {
        self.accumulator
    }

    /// Simulated seconds per wall second.
    #[must_use]
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Measured simulated seconds per wall second, once half a second of wall time ran.
    #[must_use]
    pub fn real_time_factor(&self) -> Option<f64> {
        self.rates.real_time_factor
    }

    /// Measured steps per wall second, once half a second of wall time ran.
    #[must_use]
    pub fn steps_per_second(&self) -> Option<f64> {
        self.rates.steps_per_second
    }

    /// The camera.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The step's initial camera (what `r` and `c` return to).
    #[must_use]
    pub fn home_camera(&self) -> &Camera {
        &self.home
    }

    /// True while the camera follows the bodies.
    #[must_use]
    pub fn follows(&self) -> bool {
        self.follow
    }

    /// Width / height of the scene pane in pixels, as last reported.
    #[must_use]
    pub fn aspect(&self) -> f64 {
        self.aspect
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

    /// Tells the run the pixel size of a cell in the view shown (see [`sim_view::grid_view`]).
    pub fn set_grid(&mut self, grid: (u32, u32)) {
        self.grid = (grid.0.max(1), grid.1.max(1));
    }

    /// Shows `message` on the hint line.
    pub fn set_message(&mut self, message: impl Into<String>) {
        self.message = Some(message.into());
    }

    /// Tells the run the scene pane's aspect ratio (width / height in pixels). The step's
    /// initial view is framed for it; a camera the user has not moved follows the new framing.
    pub fn set_aspect(&mut self, aspect: f64) {
        if !(aspect.is_finite() && aspect > 0.0) || (aspect / self.aspect - 1.0).abs() < 1e-3 {
            return;
        }
        self.aspect = aspect;
        self.version += 1;
        let untouched = self.camera == self.home;
        self.home = Camera::for_scene(&self.scene_at_start(), aspect, Projection::default());
        if untouched {
            self.camera = self.home;
        }
    }

    /// The scene with the bodies' initial states.
    fn scene_at_start(&self) -> crate::scene::Scene {
        let mut scene = self.sim.scene.clone();
        for (body, initial) in scene.bodies.iter_mut().zip(&self.initial) {
            body.state = initial.clone();
        }
        scene
    }

    /// Turns following on or off.
    pub fn set_follow(&mut self, on: bool) {
        self.follow = on;
        if on {
            self.follow_bodies();
        }
    }

    /// Moves the camera so that every body is in view (see [`Camera::follow`]).
    fn follow_bodies(&mut self) {
        if self.sim.diverged.is_some() {
            return;
        }
        let mut points: Vec<DVec3> = Vec::new();
        for body in &self.sim.scene.bodies {
            points.extend(body.state.x.iter().copied());
            for s in &body.state.spheres {
                points.extend([-1.0, 1.0].map(|k| s.center + k * s.radius * DVec3::X));
                points.extend([-1.0, 1.0].map(|k| s.center + k * s.radius * DVec3::Y));
                points.extend([-1.0, 1.0].map(|k| s.center + k * s.radius * DVec3::Z));
            }
        }
        let max_distance = self.home.distance * FOLLOW_MAX_ZOOM_OUT;
        let max_height = self.home.visible_height() * FOLLOW_MAX_ZOOM_OUT;
        self.camera
            .follow(&points, self.aspect, FOLLOW_ZONE, max_distance, max_height);
    }

    fn zoom(&mut self, factor: f64) {
        let before = self.camera;
        self.camera.zoom(factor);
        if self.follow {
            self.follow_bodies();
            if factor > 1.0 && self.camera.distance >= before.distance {
                self.message = Some(
                    "following keeps every body in view: f stops following, to zoom closer".into(),
                );
            }
        }
    }

    fn pan(&mut self, right: f64, up: f64) {
        self.camera.pan(right, up);
        if self.follow {
            self.follow_bodies();
        }
    }

    /// Back to the step's initial view.
    pub fn reset_camera(&mut self) {
        self.camera = self.home;
        self.pan_drag = None;
    }

    /// Which springs are drawn.
    #[must_use]
    pub fn spring_filter(&self) -> SpringFilter {
        self.filter
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
    pub fn shown_methods(&self) -> [bool; 8] {
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

    /// An upper bound on the highest angular frequency of the springs (rad/s), by Gershgorin's
    /// theorem on `M⁻¹K`:
    ///
    /// ```text
    /// ω_max² ≤ max_i (1/m_i) Σ_{springs s at i} k_s (1 + [the other end is free])
    /// ```
    /// over free particles `i` (pinned ones have `1/m = 0`). Exact for one spring with a pinned
    /// end (`ω = √(k/m)`); `2√(k/m)` for a long chain, the value of its fastest mode. Damping,
    /// gravity and collisions are left out. `None` when no spring moves a free particle.
    #[must_use]
    pub fn omega_max(&self) -> Option<f64> {
        let mut max = 0.0f64;
        let mut any = false;
        for body in &self.sim.scene.bodies {
            let m = &body.model;
            let mut row = vec![0.0f64; m.particle_count()];
            for s in m.springs() {
                let (a, b) = (s.a as usize, s.b as usize);
                let (free_a, free_b) = (m.inv_mass[a] > 0.0, m.inv_mass[b] > 0.0);
                row[a] += s.stiffness * (1.0 + f64::from(u8::from(free_b)));
                row[b] += s.stiffness * (1.0 + f64::from(u8::from(free_a)));
                any = true;
            }
            for (r, inv) in row.iter().zip(&m.inv_mass) {
                max = max.max(r * inv);
            }
        }
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

    /// Advances the simulation by `wall_dt` seconds of wall time; see [`LessonRun::tick_until`].
    pub fn tick(&mut self, wall_dt: f64) {
        self.tick_until(wall_dt, None);
    }

    /// Adds `wall_dt` (s) times the speed factor to the accumulator and takes as many steps of
    /// `dt` as fit, at most the cap on steps per frame, stopping early at `deadline` or at
    /// divergence. When it stops early the rest of the accumulator is dropped: the run falls
    /// behind real time rather than ever further behind. Does nothing while paused.
    pub fn tick_until(&mut self, wall_dt: f64, deadline: Option<Instant>) {
        if !self.running || self.sim.diverged.is_some() {
            self.running = false;
            self.accumulator = 0.0;
            return;
        }
        let wall_dt = if wall_dt.is_finite() && wall_dt > 0.0 {
            wall_dt
        } else {
            0.0
        };
        self.accumulator += wall_dt * self.speed;
        let dt = self.sim.dt();
        // Whole steps that fit, with a billionth of a step of slack against rounding
        // (0.1 s at dt = 0.01 s is 10 steps, not 9.999...).
        let fit = (self.accumulator / dt + 1e-9).floor();
        let mut wanted = if fit >= self.max_steps_per_frame as f64 {
            self.max_steps_per_frame
        } else {
            fit as u64
        };
        let mut behind = fit > self.max_steps_per_frame as f64;
        let mut taken = 0;
        while taken < wanted {
            if self.step_once() {
                taken += 1;
                behind = true;
                break;
            }
            taken += 1;
            if let Some(deadline) = deadline
                && taken % 16 == 0
                && Instant::now() >= deadline
            {
                behind = true;
                wanted = taken;
            }
        }
        self.accumulator = if behind {
            0.0
        } else {
            (self.accumulator - taken as f64 * dt).max(0.0)
        };
        self.last_frame_steps = taken;
        self.version += 1;
        self.rates.add(wall_dt, taken as f64 * dt, taken);
        if self.follow {
            self.follow_bodies();
        }
    }

    /// One step, then the history, the goal and the divergence check; true when it diverged.
    fn step_once(&mut self) -> bool {
        let diverged = self.sim.step().is_some() || self.sim.diverged.is_some();
        if diverged {
            // The diverging sample is drawn too (the plot ends where the status line says).
            self.history
                .record_divergence(&self.sim, self.oscillator.as_ref());
        } else {
            self.history.record(&self.sim, self.oscillator.as_ref());
        }
        self.check_goal(diverged);
        if diverged {
            self.running = false;
        }
        diverged
    }

    fn check_goal(&mut self, diverged: bool) {
        let time = self
            .sim
            .diverged
            .as_ref()
            .map_or(self.sim.time(), |d| d.time);
        self.check_prediction(diverged, time);
        if self.goal.is_some() {
            return;
        }
        let Some(goal) = &self.lesson.steps[self.step].goal else {
            return;
        };
        let speed = if goal.kind == GoalKind::Settle && !diverged {
            self.body_speed(goal.body)
        } else {
            0.0
        };
        self.goal = goal.check(&mut self.goal_progress, time, speed, diverged);
        if self.goal == Some(true) && !self.met[self.step] {
            self.met[self.step] = true;
            self.progress_changed = true;
        }
    }

    /// The largest particle speed of body `body` (1-based), or of every body (m/s).
    fn body_speed(&self, body: Option<usize>) -> f64 {
        self.sim
            .states()
            .enumerate()
            .filter(|(i, _)| body.is_none_or(|b| b == i + 1))
            .map(|(_, s)| diverge::max_speed(s))
            .fold(0.0f64, f64::max)
    }

    /// After an answer, a run that diverged or passed the longest option's time reveals the
    /// prediction's answer beside what this run did.
    fn check_prediction(&mut self, diverged: bool, time: f64) {
        if self.revealed.is_some() {
            return;
        }
        let Some(chosen) = self.answer() else { return };
        let Some(p) = &self.lesson.steps[self.step].predict else {
            return;
        };
        let horizon = p
            .options
            .iter()
            .map(|o| o.claim.time + crate::lesson::SETTLE_HOLD)
            .fold(0.0, f64::max);
        if !diverged && time < horizon {
            return;
        }
        let per_body = p
            .options
            .iter()
            .all(|o| o.claim.kind == crate::lesson::GoalKind::Settle && o.claim.body.is_some());
        let what = if diverged {
            format!("this run blew up at t = {} s", super::plots::number(time))
        } else if per_body {
            // Options about different bodies of one run: say what each body did in this one.
            let bodies: Vec<String> = p
                .options
                .iter()
                .map(|o| {
                    let v = self.body_speed(o.claim.body);
                    let state = if v < o.claim.speed {
                        "at rest"
                    } else {
                        "still moving"
                    };
                    format!(
                        "{} {state} (max |v| {} m/s)",
                        o.text,
                        super::plots::number(v)
                    )
                })
                .collect();
            format!(
                "at t = {} s in this run: {}",
                super::plots::number(time),
                bodies.join(", ")
            )
        } else {
            format!("this run kept going for {} s", super::plots::number(time))
        };
        let right = &p.options[p.answer];
        let verdict = if chosen == p.answer {
            "✓ you predicted it".to_string()
        } else {
            format!("✗ you predicted {}) {}", chosen + 1, p.options[chosen].text)
        };
        self.revealed = Some(format!(
            "{what}. Answer: {}) {}. {verdict}.",
            p.answer + 1,
            right.text
        ));
    }

    /// Handles a key of the lesson screen (the app handles `q`, Esc, `?`, `v` and Ctrl-C).
    pub fn handle_key(&mut self, code: KeyCode) {
        self.handle_key_with(code, KeyModifiers::NONE);
    }

    /// As [`LessonRun::handle_key`], with the modifier keys held (Shift + arrows pan).
    pub fn handle_key_with(&mut self, code: KeyCode, modifiers: KeyModifiers) {
        self.message = None;
        self.version += 1;
        if self.chooser.is_some() {
            self.chooser_key(code);
            return;
        }
        if let KeyCode::Char(c @ '1'..='9') = code {
            let n = c as usize - '1' as usize;
            if self.awaiting_prediction() {
                self.predict(n);
                return;
            }
            if self.step().plots.iter().any(|p| p.is_study()) {
                self.toggle_shown(n);
                return;
            }
        }
        if modifiers.contains(KeyModifiers::SHIFT) {
            let moved = match code {
                KeyCode::Left => Some((-PAN_STEP, 0.0)),
                KeyCode::Right => Some((PAN_STEP, 0.0)),
                KeyCode::Up => Some((0.0, PAN_STEP)),
                KeyCode::Down => Some((0.0, -PAN_STEP)),
                _ => None,
            };
            if let Some((right, up)) = moved {
                self.pan(right, up);
                return;
            }
        }
        match code {
            KeyCode::Char(' ') => self.toggle_run(),
            KeyCode::Char('s') => self.single_step(),
            KeyCode::Char('r') => self.reset(),
            KeyCode::Char('m') => self.open_chooser(),
            KeyCode::Char('A') => self.scale_drag(true),
            KeyCode::Char('a') => self.scale_drag(false),
            KeyCode::Char('G') => self.scale_gamma(true),
            KeyCode::Char('g') => self.scale_gamma(false),
            KeyCode::Char('J') => self.scale_passes(true),
            KeyCode::Char('j') => self.scale_passes(false),
            KeyCode::Char('l') => self.hscroll = self.hscroll.saturating_add(HSCROLL_STEP).min(400),
            KeyCode::Char('h') => self.hscroll = self.hscroll.saturating_sub(HSCROLL_STEP),
            KeyCode::Char('+' | '=') => self.scale_dt(2.0),
            KeyCode::Char('-' | '_') => self.scale_dt(0.5),
            KeyCode::Char(']') => self.scale_steps_per_frame(true),
            KeyCode::Char('[') => self.scale_steps_per_frame(false),
            KeyCode::Char('>' | '.') => self.scale_speed(2.0),
            KeyCode::Char('<' | ',') => self.scale_speed(0.5),
            KeyCode::Char('K') => self.scale_stiffness(COEFFICIENT_FACTOR),
            KeyCode::Char('k') => self.scale_stiffness(1.0 / COEFFICIENT_FACTOR),
            KeyCode::Char('D') => self.scale_damping(true),
            KeyCode::Char('d') => self.scale_damping(false),
            KeyCode::Left => self.turn(-ORBIT_STEP_DEGREES, 0.0),
            KeyCode::Right => self.turn(ORBIT_STEP_DEGREES, 0.0),
            KeyCode::Up => self.turn(0.0, ORBIT_STEP_DEGREES),
            KeyCode::Down => self.turn(0.0, -ORBIT_STEP_DEGREES),
            KeyCode::Char('i') => self.zoom(ZOOM_STEP),
            KeyCode::Char('o') => self.zoom(1.0 / ZOOM_STEP),
            KeyCode::Char('f') => {
                self.set_follow(!self.follow);
                self.message = Some(if self.follow {
                    "the camera follows the bodies".into()
                } else {
                    "the camera stays where it is".into()
                });
            }
            KeyCode::Char('c') => {
                self.reset_camera();
                self.message = Some("back to the step's first view".into());
            }
            KeyCode::Char(c @ '1'..='4') => self.toggle_corner(c as usize - '1' as usize),
            KeyCode::Char('t') => self.filter = self.filter.next(),
            KeyCode::Char('e') => self.export(),
            KeyCode::Char('n') => self.go_to_step(self.step + 1),
            KeyCode::Char('p') => match self.step.checked_sub(1) {
                Some(s) => self.go_to_step(s),
                None => self.message = Some("this is the first step".into()),
            },
            KeyCode::PageDown => self.text_scroll = self.text_scroll.saturating_add(5).min(999),
            KeyCode::PageUp => self.text_scroll = self.text_scroll.saturating_sub(5),
            _ => {}
        }
    }

    fn turn(&mut self, orbit: f64, elevation: f64) {
        self.camera.turn(orbit, elevation);
        if self.follow {
            self.follow_bodies();
        }
    }

    fn toggle_run(&mut self) {
        if !self.running && self.awaiting_prediction() {
            self.message = Some(self.prediction_prompt());
            return;
        }
        if let Some(d) = &self.sim.diverged {
            self.message = Some(format!(
                "unstable at step {}: press r to start over",
                d.step
            ));
            return;
        }
        self.running = !self.running;
        self.accumulator = 0.0;
        self.rates = Rates::default();
    }

    fn single_step(&mut self) {
        if self.awaiting_prediction() {
            self.message = Some(self.prediction_prompt());
            return;
        }
        self.running = false;
        if self.sim.diverged.is_some() {
            self.message = Some("the run diverged: press r to start over".into());
            return;
        }
        self.step_once();
    }

    /// Restores the state at `t = 0` bit for bit, keeping the chosen method, dt, stiffness,
    /// damping and pins; pauses.
    pub fn reset(&mut self) {
        self.release();
        let mut scene = self.sim.scene.clone();
        for (body, initial) in scene.bodies.iter_mut().zip(&self.initial) {
            body.state = initial.clone();
        }
        let dt = self.sim.dt();
        self.sim = Simulation::new(scene);
        if self.sim.dt() != dt {
            self.sim.set_dt(dt);
        }
        self.running = false;
        self.reset_camera();
        // The exact solution starts again from the initial state.
        self.oscillator = Oscillator::detect(&self.sim.scene);
        self.restart_records();
    }

    fn prediction_prompt(&self) -> String {
        let n = self.step().predict.as_ref().map_or(0, |p| p.options.len());
        format!("predict first: press 1–{n} (the run starts after your answer)")
    }

    /// Records option `n` (0-based) as the student's prediction.
    fn predict(&mut self, n: usize) {
        let Some(p) = &self.lesson.steps[self.step].predict else {
            return;
        };
        let Some(option) = p.options.get(n) else {
            self.message = Some(self.prediction_prompt());
            return;
        };
        self.message = Some(format!(
            "you predicted {}) {}: now run it and see",
            n + 1,
            option.text
        ));
        self.answers[self.step] = Some(n);
        self.progress_changed = true;
    }

    /// Number keys in a step with study charts: show or hide method `n` (0-based).
    fn toggle_shown(&mut self, n: usize) {
        let Some(&method) = Method::ALL.get(n) else {
            return;
        };
        self.shown[n] = !self.shown[n];
        self.message = Some(format!(
            "{method} {}",
            if self.shown[n] { "shown" } else { "hidden" }
        ));
    }

    /// `m`: opens the method chooser on the first body's method.
    fn open_chooser(&mut self) {
        let current = self
            .sim
            .scene
            .bodies
            .first()
            .map_or(Method::SemiImplicitEuler, |b| b.method);
        self.chooser = Some(Chooser {
            selected: Method::ALL.iter().position(|&m| m == current).unwrap_or(0),
            target: None,
        });
    }

    fn chooser_key(&mut self, code: KeyCode) {
        let Some(mut c) = self.chooser else { return };
        let n = Method::ALL.len();
        let pick = match code {
            KeyCode::Esc | KeyCode::Char('q') => {
                self.chooser = None;
                return;
            }
            KeyCode::Up => {
                c.selected = (c.selected + n - 1) % n;
                None
            }
            KeyCode::Down => {
                c.selected = (c.selected + 1) % n;
                None
            }
            KeyCode::Tab => {
                let bodies = self.sim.scene.bodies.len();
                c.target = match c.target {
                    _ if bodies < 2 => None,
                    None => Some(0),
                    Some(b) if b + 1 < bodies => Some(b + 1),
                    Some(_) => None,
                };
                None
            }
            KeyCode::Enter | KeyCode::Char(' ') => Some(Method::ALL[c.selected]),
            KeyCode::Char(d @ '1'..='8') => Some(Method::ALL[d as usize - '1' as usize]),
            KeyCode::Char(k) => Method::ALL.into_iter().find(|&m| method_key(m) == k),
            _ => None,
        };
        self.chooser = Some(c);
        if let Some(method) = pick {
            self.chooser = None;
            self.set_method(method, c.target);
        }
    }

    /// Gives `method` to body `target` (every body when `None`).
    pub fn set_method(&mut self, method: Method, target: Option<usize>) {
        match target {
            None => self.sim.set_method(method),
            Some(b) => {
                let mut methods: Vec<Method> =
                    self.sim.scene.bodies.iter().map(|b| b.method).collect();
                if let Some(m) = methods.get_mut(b) {
                    *m = method;
                }
                for (body, m) in self.sim.scene.bodies.iter_mut().zip(methods) {
                    body.method = m;
                }
                // Verlet's history belongs to the previous method.
                if let Some(body) = self.sim.scene.bodies.get_mut(b) {
                    body.state.history_valid = false;
                }
            }
        }
        self.sim.rebase_energy();
        self.refresh_limit();
        self.message = Some(match target {
            None => format!("method: {method}"),
            Some(b) => format!(
                "method of {}: {method}",
                self.sim
                    .scene
                    .bodies
                    .get(b)
                    .map_or("?", |b| b.label.as_str())
            ),
        });
    }

    /// `A` / `a`: the viscous drag `f = -c v` on every particle, ×2 / ÷2 (module constants).
    fn scale_drag(&mut self, up: bool) {
        for body in &mut self.sim.scene.bodies {
            let count = body.model.mass.len().max(1) as f64;
            let mean = body.model.mass.iter().sum::<f64>() / count;
            let first = FIRST_DRAG_RATE * mean;
            let c = body.model.drag;
            body.model.drag = if up {
                if c <= 0.0 { first } else { c * 2.0 }
            } else if c / 2.0 < first * (1.0 - 1e-9) {
                0.0
            } else {
                c / 2.0
            };
        }
        self.sim.rebase_energy();
        self.refresh_spectra();
        let drags: Vec<f64> = self.sim.scene.bodies.iter().map(|b| b.model.drag).collect();
        self.message = Some(match uniform(drags.iter().copied()) {
            Some(0.0) => "no air drag".into(),
            Some(c) => format!(
                "air drag c = {} N·s/m on every particle (f = -c v)",
                plots::number(c)
            ),
            None => "air drag changed on every body".into(),
        });
    }

    /// The drag coefficient (N·s/m) when every body has the same.
    #[must_use]
    pub fn uniform_drag(&self) -> Option<f64> {
        uniform(self.sim.scene.bodies.iter().map(|b| b.model.drag))
    }

    /// The Verlet bodies' γ, when every Verlet body has the same.
    #[must_use]
    pub fn verlet_gamma(&self) -> Option<f64> {
        uniform(
            self.sim
                .scene
                .bodies
                .iter()
                .filter(|b| b.method == Method::Verlet)
                .map(|b| b.params.verlet_damping),
        )
    }

    /// The Verlet bodies' projection passes, when every Verlet body has the same.
    #[must_use]
    pub fn verlet_passes(&self) -> Option<u32> {
        let mut it = self
            .sim
            .scene
            .bodies
            .iter()
            .filter(|b| matches!(b.method, Method::Verlet | Method::Xpbd))
            .map(|b| b.params.iterations);
        let first = it.next()?;
        it.all(|p| p == first).then_some(first)
    }

    /// `G` / `g`: Verlet's damping factor γ per step of every body, ×10 / ÷10.
    fn scale_gamma(&mut self, up: bool) {
        for body in &mut self.sim.scene.bodies {
            let g = body.params.verlet_damping;
            body.params.verlet_damping = if up {
                if g <= 0.0 {
                    FIRST_VERLET_GAMMA
                } else {
                    (g * 10.0).min(MAX_VERLET_GAMMA)
                }
            } else if g / 10.0 < FIRST_VERLET_GAMMA * (1.0 - 1e-9) {
                0.0
            } else {
                g / 10.0
            };
        }
        self.sim.rebase_energy();
        self.refresh_limit();
        let dt = self.sim.dt();
        let g = self
            .sim
            .scene
            .bodies
            .first()
            .map_or(0.0, |b| b.params.verlet_damping);
        let verlet = self
            .sim
            .scene
            .bodies
            .iter()
            .any(|b| b.method == Method::Verlet);
        self.message = Some(format!(
            "Verlet damping γ = {} per step: a decay rate γ/dt = {} 1/s at this dt{}",
            plots::number(g),
            plots::number(g / dt),
            if verlet {
                ""
            } else {
                " (no body uses Verlet now: m v)"
            }
        ));
    }

    /// `J` / `j`: Verlet's projection passes (XPBD's solver passes) per step, ×2 / ÷2.
    fn scale_passes(&mut self, up: bool) {
        for body in &mut self.sim.scene.bodies {
            let p = body.params.iterations;
            body.params.iterations = if up {
                (p.max(1) * 2)
                    .min(MAX_PASSES)
                    .max(if p == 0 { 1 } else { 0 })
            } else {
                p / 2
            };
            if up && p == 0 {
                body.params.iterations = 1;
            }
            if body.method == Method::Xpbd {
                body.params.iterations = body.params.iterations.max(1);
            }
        }
        self.sim.rebase_energy();
        self.refresh_limit();
        let p = self
            .sim
            .scene
            .bodies
            .first()
            .map_or(0, |b| b.params.iterations);
        self.message = Some(format!(
            "{p} projection pass{} per step (Verlet; XPBD: solver passes per substep)",
            if p == 1 { "" } else { "es" }
        ));
    }

    fn scale_dt(&mut self, factor: f64) {
        let dt = self.sim.dt() * factor;
        if !(DT_RANGE.0..=DT_RANGE.1).contains(&dt) {
            self.message = Some(format!(
                "dt stays between {:e} s and {} s",
                DT_RANGE.0, DT_RANGE.1
            ));
            return;
        }
        self.sim.set_dt(dt);
        self.sim.rebase_energy();
        self.accumulator = 0.0;
        self.message = Some(format!("dt = {} s", plots::number(dt)));
    }

    fn scale_steps_per_frame(&mut self, up: bool) {
        let n = self.max_steps_per_frame;
        self.set_max_steps_per_frame(if up { n.saturating_mul(2) } else { n / 2 });
        self.message = Some(format!(
            "at most {} steps per frame",
            self.max_steps_per_frame
        ));
    }

    fn scale_speed(&mut self, factor: f64) {
        self.speed = (self.speed * factor).clamp(SPEED_RANGE.0, SPEED_RANGE.1);
        self.accumulator = 0.0;
        self.message = Some(format!("speed ×{} real time", plots::number(self.speed)));
    }

    /// Multiplies every spring's stiffness by `factor` (per spring, so kinds keep their ratios).
    fn scale_stiffness(&mut self, factor: f64) {
        if self.springs().next().is_none() {
            self.message = Some("this scene has no springs".into());
            return;
        }
        for body in &mut self.sim.scene.bodies {
            body.model.scale_stiffness(factor);
        }
        self.coefficients_changed();
        self.message = Some(match self.uniform_stiffness() {
            Some(k) => format!("stiffness k = {} N/m", plots::number(k)),
            None => format!("stiffness ×{} of every spring", plots::number(factor)),
        });
    }

    /// `D`: ×1.5, starting an undamped spring at 1 % of its critical damping `2√(k m)` (m the
    /// lighter end's mass); `d`: ÷1.5, down to zero below that.
    fn scale_damping(&mut self, up: bool) {
        if self.springs().next().is_none() {
            self.message = Some("this scene has no springs".into());
            return;
        }
        for body in &mut self.sim.scene.bodies {
            let mass = body.model.mass.clone();
            body.model.update_springs(|s| {
                let m = mass[s.a as usize].min(mass[s.b as usize]);
                let first = FIRST_DAMPING * 2.0 * (s.stiffness * m).sqrt();
                s.damping = if up {
                    if s.damping == 0.0 {
                        first
                    } else {
                        s.damping * COEFFICIENT_FACTOR
                    }
                } else {
                    let d = s.damping / COEFFICIENT_FACTOR;
                    if d < first { 0.0 } else { d }
                };
            });
        }
        self.coefficients_changed();
        self.message = Some(match self.uniform_damping() {
            Some(c) => format!("damping k_d = {} N·s/m", plots::number(c)),
            None => "damping changed on every spring".into(),
        });
    }

    fn coefficients_changed(&mut self) {
        // The exact solution continues from here with the new coefficients.
        if let Some(o) = &mut self.oscillator {
            *o = o.restarted(&self.sim);
        }
        self.sim.rebase_energy();
        self.refresh_spectra();
    }

    /// Keys 1–4: pins or frees corner `corner` of the cloth.
    fn toggle_corner(&mut self, corner: usize) {
        let Some(cloth) = self.cloth else {
            self.message = Some("keys 1–4 pin the corners of a cloth; this scene has none".into());
            return;
        };
        let corners = lattice::corners(cloth.n);
        let Some(&p) = corners.get(corner) else {
            return;
        };
        if self
            .drag
            .is_some_and(|d| d.body == cloth.body && d.index == p)
        {
            return;
        }
        self.generation += 1;
        let body = &mut self.sim.scene.bodies[cloth.body];
        if body.model.is_pinned(p) {
            body.model.unpin(p);
            self.message = Some(format!("corner {} (particle {p}) is free", corner + 1));
        } else {
            pin_particle(&mut body.model, &mut body.state, p);
            self.message = Some(format!("corner {} (particle {p}) is pinned", corner + 1));
        }
        self.sim.rebase_energy();
        self.refresh_spectra();
    }

    fn export(&mut self) {
        let path = std::path::PathBuf::from(format!(
            "springlab-{}-step{}-{:06}.png",
            self.lesson.slug,
            self.step + 1,
            self.sim.steps
        ));
        self.message = Some(match export::export_png(self, &path) {
            Ok(p) => format!("wrote {}", p.display()),
            Err(e) => e,
        });
    }

    /// Opens step `step` (0-based) of the lesson.
    pub fn go_to_step(&mut self, step: usize) {
        if step >= self.lesson.steps.len() {
            self.message = Some("this is the last step: q goes back to the menu".into());
            return;
        }
        match build(&self.lesson, step) {
            Ok(sim) => {
                self.sim = sim;
                self.step = step;
                self.filter = SpringFilter::All;
                self.start_step();
            }
            Err(e) => self.message = Some(e),
        }
    }

    /// Grabs, drags and releases particles with the left button; `canvas` is the canvas's inner
    /// area on screen. Returns true when something changed.
    pub fn handle_mouse(&mut self, mouse: MouseEvent, canvas: Rect) -> bool {
        let changed = self.mouse(mouse, canvas);
        if changed {
            self.version += 1;
        }
        changed
    }

    fn mouse(&mut self, mouse: MouseEvent, canvas: Rect) -> bool {
        match mouse.kind {
            MouseEventKind::ScrollUp | MouseEventKind::ScrollDown
                if contains(canvas, mouse.column, mouse.row) =>
            {
                self.message = None;
                self.zoom(if mouse.kind == MouseEventKind::ScrollUp {
                    ZOOM_STEP
                } else {
                    1.0 / ZOOM_STEP
                });
                true
            }
            MouseEventKind::Down(MouseButton::Left) => {
                self.release();
                self.pan_drag = None;
                if self.sim.diverged.is_some() {
                    return false;
                }
                let Some((body, index, depth)) = sim_view::pick(
                    &self.camera,
                    &self.sim,
                    canvas,
                    self.grid,
                    mouse.column,
                    mouse.row,
                ) else {
                    // Empty space: the drag pans the view.
                    if contains(canvas, mouse.column, mouse.row) {
                        self.pan_drag = Some((mouse.column, mouse.row));
                    }
                    return false;
                };
                self.generation += 1;
                let b = &mut self.sim.scene.bodies[body];
                let inv_mass = b.model.inv_mass[index];
                pin_particle(&mut b.model, &mut b.state, index);
                self.sim.rebase_energy();
                self.drag = Some(Drag {
                    body,
                    index,
                    inv_mass,
                    depth,
                });
                self.message = Some(format!("holding particle {index}"));
                true
            }
            MouseEventKind::Drag(MouseButton::Left) => {
                let Some(drag) = self.drag else {
                    let Some((c0, r0)) = self.pan_drag else {
                        return false;
                    };
                    let (w, h) = (
                        f64::from(canvas.width.max(1)),
                        f64::from(canvas.height.max(1)),
                    );
                    let dx = f64::from(mouse.column) - f64::from(c0);
                    let dy = f64::from(mouse.row) - f64::from(r0);
                    self.pan_drag = Some((mouse.column, mouse.row));
                    self.pan(-dx / w * self.aspect, dy / h);
                    return true;
                };
                let p = sim_view::cell_to_world(
                    &self.camera,
                    canvas,
                    self.grid,
                    mouse.column,
                    mouse.row,
                    drag.depth,
                );
                let state = &mut self.sim.scene.bodies[drag.body].state;
                state.x[drag.index] = p;
                state.x_prev[drag.index] = p;
                state.v[drag.index] = DVec3::ZERO;
                true
            }
            MouseEventKind::Up(MouseButton::Left) => {
                self.pan_drag = None;
                let held = self.drag.is_some();
                self.release();
                held
            }
            _ => false,
        }
    }

    /// Lets go of the held particle: its inverse mass comes back, it starts at rest.
    fn release(&mut self) {
        if let Some(d) = self.drag.take()
            && let Some(body) = self.sim.scene.bodies.get_mut(d.body)
        {
            body.model.inv_mass[d.index] = d.inv_mass;
            body.state.v[d.index] = DVec3::ZERO;
            body.state.x_prev[d.index] = body.state.x[d.index];
            self.message = Some(format!("let go of particle {}", d.index));
            self.sim.rebase_energy();
        }
    }

    fn text_scroll(&self) -> u16 {
        self.text_scroll
    }
}

fn contains(r: Rect, column: u16, row: u16) -> bool {
    column >= r.x && column < r.x + r.width && row >= r.y && row < r.y + r.height
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

/// Draws the lesson screen; returns the scene canvas's inner area (for the mouse).
pub fn render(
    run: &LessonRun,
    fps: Option<f64>,
    view: &str,
    theme: Theme,
    painter: &dyn Painter,
    area: Rect,
    buf: &mut Buffer,
) -> Rect {
    let [header, body, status_area, hints] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Fill(1),
        Constraint::Length(2),
        Constraint::Length(1),
    ])
    .areas(area);
    render_header(run, theme, header, buf);
    let [left, right] =
        Layout::horizontal([Constraint::Percentage(40), Constraint::Fill(1)]).areas(body);
    render_text(run, theme, left, buf);
    let step = run.step();
    let (scene, plot_area) = split_right(step, right);
    let canvas = sim_view::render(run, theme, painter, scene, buf);
    if let Some(plot_area) = plot_area {
        plots::render(
            &step.plots,
            run.history(),
            run.oscillator(),
            &run.studies,
            run.shown_methods(),
            run.sim().time(),
            theme,
            plot_area,
            buf,
        );
    }
    status::render(run, fps, view, theme, status_area, buf);
    render_hints(run, theme, hints, buf);
    canvas
}

/// The scene pane and the plots' area of the right column (no plots: the whole column).
fn split_right(step: &Step, right: Rect) -> (Rect, Option<Rect>) {
    if step.plots.is_empty() {
        return (right, None);
    }
    // Study charts (log-log, several methods) get more of the column than time plots.
    let share = if step.plots.iter().any(|p| p.is_study()) {
        3
    } else {
        2
    };
    let plot_height = (right.height * share / 5)
        .max(8)
        .min(right.height.saturating_sub(6));
    let [scene, plot_area] =
        Layout::vertical([Constraint::Fill(1), Constraint::Length(plot_height)]).areas(right);
    (scene, Some(plot_area))
}

/// The scene pane's inner area (inside its border) when the lesson screen fills `area`.
#[must_use]
pub fn scene_inner(run: &LessonRun, area: Rect) -> Rect {
    let [_, body, _, _] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Fill(1),
        Constraint::Length(2),
        Constraint::Length(1),
    ])
    .areas(area);
    let [_, right] =
        Layout::horizontal([Constraint::Percentage(40), Constraint::Fill(1)]).areas(body);
    let (scene, _) = split_right(run.step(), right);
    ratatui::widgets::Block::bordered().inner(scene)
}

fn render_header(run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) {
    let lesson = run.lesson();
    let step = run.step();
    let bold = Style::new().add_modifier(Modifier::BOLD);
    let line = Line::from(vec![
        Span::styled(
            format!(" Lesson {}: {} ", lesson.number, lesson.title),
            bold.patch(theme.fg(Color::Cyan)),
        ),
        Span::styled("· ", theme.dim()),
        Span::styled(
            format!(
                "step {}/{}: {}",
                run.step_index() + 1,
                lesson.steps.len(),
                step.title
            ),
            bold,
        ),
    ]);
    buf.set_line(area.x, area.y, &line, area.width);
    let right = "? help · q menu ";
    let width = right.chars().count() as u16;
    if area.width > width + line.width() as u16 + 2 {
        buf.set_string(area.x + area.width - width, area.y, right, theme.dim());
    }
}

/// The step text (scrollable with PgUp / PgDn; code sideways with h / l) above the "try"
/// list, the prediction and the goal.
fn render_text(run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) {
    let area = Rect {
        width: area.width.saturating_sub(1),
        ..area
    };
    let width = area.width.saturating_sub(1).max(10);
    let step = run.step();
    let bold_green = Style::new()
        .add_modifier(Modifier::BOLD)
        .patch(theme.fg(Color::Green));
    let key_style = theme.fg(Color::Cyan).add_modifier(Modifier::BOLD);
    // The try list, the prediction and the goal, at most half of the column.
    let mut tail: Vec<Line<'static>> = Vec::new();
    if let Some(p) = &step.predict {
        tail.push(Line::from(vec![
            Span::styled("Predict ", bold_green),
            Span::styled(
                match run.answer() {
                    None => format!("1–{} first", p.options.len()),
                    Some(a) => format!("you chose {}", a + 1),
                },
                theme.fg(Color::Yellow),
            ),
        ]));
        tail.extend(markdown::wrap_text(&p.question, width, theme));
        for (i, o) in p.options.iter().enumerate() {
            let mark = match (run.answer(), run.revealed()) {
                (_, Some(_)) if i == p.answer => "✓",
                (Some(a), _) if a == i => "▸",
                _ => " ",
            };
            let mut lines =
                markdown::wrap_text(&format!("{}) {}", i + 1, o.text), width - 2, theme);
            for (j, l) in lines.iter_mut().enumerate() {
                let mut spans = vec![Span::styled(
                    if j == 0 {
                        format!("{mark} ")
                    } else {
                        "  ".into()
                    },
                    key_style,
                )];
                spans.append(&mut l.spans);
                *l = Line::from(spans);
            }
            tail.extend(lines);
        }
        if let Some(r) = run.revealed() {
            tail.extend(
                markdown::wrap_text(r, width, theme)
                    .into_iter()
                    .map(|l| l.patch_style(theme.fg(Color::LightGreen))),
            );
            if !p.explain.is_empty() {
                tail.extend(markdown::wrap_text(&p.explain, width, theme));
            }
        }
    }
    if !step.try_list.is_empty() {
        tail.push(Line::from(Span::styled("Try", bold_green)));
        for item in &step.try_list {
            let mut lines = markdown::bullet(&item.text, width, theme);
            if let Some(keys) = &item.keys {
                let k = format!("  keys: {keys}");
                let fits = lines
                    .last()
                    .is_some_and(|l| l.width() + k.chars().count() <= usize::from(width));
                if fits {
                    if let Some(l) = lines.last_mut() {
                        l.spans.push(Span::styled(k, key_style));
                    }
                } else {
                    lines.push(Line::from(Span::styled(
                        format!("  keys: {keys}"),
                        key_style,
                    )));
                }
            }
            tail.extend(lines);
        }
    }
    if let Some(goal) = &step.goal {
        let (mark, style) = match run.goal_state() {
            Some(true) => ("✓ met", theme.fg(Color::LightGreen)),
            Some(false) => ("✗ failed: r to retry", theme.fg(Color::LightRed)),
            None => ("… pending", theme.fg(Color::Yellow)),
        };
        tail.push(Line::from(vec![
            Span::styled("Goal ", bold_green),
            Span::styled(mark, style.add_modifier(Modifier::BOLD)),
        ]));
        tail.extend(markdown::wrap_text(&goal.text, width, theme));
    }
    let tail_height = (tail.len() as u16).min(area.height / 2);
    let [text_area, tail_area] = Layout::vertical([
        Constraint::Fill(1),
        Constraint::Length(if tail.is_empty() { 0 } else { tail_height + 1 }),
    ])
    .areas(area);
    let marked = markdown::render_marked(run.text(), width, theme);
    let total = marked.len() as u16;
    // When the text does not fit, its last row holds the scroll hint (never over the text).
    let overflow = total > text_area.height;
    let rows = if overflow {
        text_area.height.saturating_sub(1)
    } else {
        text_area.height
    };
    let max_scroll = total.saturating_sub(rows);
    let scroll = run.text_scroll().min(max_scroll);
    let marker = theme.fg(Color::Yellow).add_modifier(Modifier::BOLD);
    let offset = usize::from(run.hscroll());
    let shown: Vec<Line<'static>> = marked
        .into_iter()
        .skip(usize::from(scroll))
        .take(usize::from(rows))
        .map(|(line, code)| {
            if code {
                markdown::clip(&line, offset, usize::from(text_area.width), marker)
            } else {
                line
            }
        })
        .collect();
    Paragraph::new(shown).render(
        Rect {
            height: rows,
            ..text_area
        },
        buf,
    );
    if overflow && text_area.height > 0 {
        let hint = match (scroll > 0, scroll < max_scroll) {
            (false, _) => " ↓ more: PgDn ",
            (true, true) => " ↑ PgUp · ↓ PgDn ",
            (true, false) => " ↑ PgUp: back ",
        };
        let w = hint.chars().count() as u16;
        buf.set_string(
            text_area.x + text_area.width.saturating_sub(w),
            text_area.y + text_area.height - 1,
            hint,
            theme.fg(Color::Yellow).add_modifier(Modifier::REVERSED),
        );
    }
    if !tail.is_empty() && tail_area.height > 0 {
        let rule = "─".repeat(tail_area.width as usize);
        buf.set_string(tail_area.x, tail_area.y, rule, theme.dim());
        let rest = Rect {
            y: tail_area.y + 1,
            height: tail_area.height - 1,
            ..tail_area
        };
        Paragraph::new(tail).render(rest, buf);
    }
    if let Some(c) = run.chooser() {
        render_chooser(run, c, theme, area, buf);
    }
}

/// The method chooser over the bottom of the text column.
fn render_chooser(run: &LessonRun, c: &Chooser, theme: Theme, area: Rect, buf: &mut Buffer) {
    let bodies = &run.sim().scene.bodies;
    let current = |m: Method| match c.target {
        Some(b) => bodies.get(b).is_some_and(|b| b.method == m),
        None => bodies.iter().all(|b| b.method == m),
    };
    let mut lines: Vec<Line> = Method::ALL
        .iter()
        .enumerate()
        .map(|(i, &m)| {
            let style = if i == c.selected {
                Style::new().add_modifier(Modifier::REVERSED)
            } else {
                Style::new()
            };
            Line::from(vec![
                Span::styled(
                    format!(" {} {} ", i + 1, method_key(m)),
                    theme.fg(Color::Cyan).add_modifier(Modifier::BOLD),
                ),
                Span::styled(
                    format!("{}{}", m.name(), if current(m) { " (now)" } else { "" }),
                    style,
                ),
            ])
        })
        .collect();
    if bodies.len() > 1 {
        let target = c
            .target
            .and_then(|b| bodies.get(b))
            .map_or("every body".to_string(), |b| b.label.clone());
        lines.push(Line::styled(
            format!(" Tab: for {target}"),
            theme.fg(Color::Yellow),
        ));
    }
    lines.push(Line::styled(" key, number or Enter · Esc", theme.dim()));
    let height = (lines.len() as u16 + 2).min(area.height);
    let width = 36.min(area.width);
    let rect = Rect::new(area.x, area.y + area.height - height, width, height);
    ratatui::widgets::Clear.render(rect, buf);
    Paragraph::new(lines)
        .block(
            ratatui::widgets::Block::bordered()
                .title(" method (m) ")
                .border_style(theme.fg(Color::Cyan)),
        )
        .render(rect, buf);
}

fn render_hints(run: &LessonRun, theme: Theme, area: Rect, buf: &mut Buffer) {
    let line = match run.message() {
        Some(m) => Line::from(Span::styled(format!(" {m}"), theme.fg(Color::Yellow))),
        None => {
            // The longest hint that fits, so that "? help · q menu" is never cut off.
            let hints = [
                " space run · s step · r reset · m method · +/- dt · k/K d/D a/A · v view · \
                 n/p step · ? help · q menu",
                " space run · s step · r reset · m method · +/- dt · v view · n/p step · ? help \
                 · q menu",
                " space run · r reset · m method · +/- dt · n/p step · ? help · q menu",
                " space run · ? help · q menu",
            ];
            let fits = hints
                .iter()
                .find(|h| h.chars().count() <= usize::from(area.width))
                .unwrap_or(&hints[hints.len() - 1]);
            Line::from(Span::styled(*fits, theme.dim()))
        }
    };
    buf.set_line(area.x, area.y, &line, area.width);
}
