//! The lesson walkthrough in the terminal: a menu of lessons, and for each step its text, the
//! live scene, plots and a status line.
//!
//! The structure follows ratatui's demo2: an [`App`] owns the state and has
//! [`run`](App::run) (the event loop), [`handle_event`](App::handle_event) and
//! `impl Widget for &App` (drawing). Everything the loop does is reachable without a terminal:
//! tests call [`App::handle_key`], [`App::handle_mouse`] and [`App::tick`] with explicit wall
//! times and draw into ratatui's `TestBackend`.
//!
//! # Time
//!
//! Simulated time is decoupled from drawing. Each frame the loop measures the wall
//! time since the previous frame and calls [`App::tick`]; the lesson adds that time (times the
//! speed factor) to an accumulator and takes as many steps of the fixed `dt` as fit, at most the
//! cap on steps per frame (`[` / `]`). When the cap (or the frame's time budget) is hit, the
//! backlog is dropped: the simulation runs slower than real time and the status line shows a
//! real-time factor below 1, instead of falling ever further behind. Frames are drawn at most
//! 60 times a second; while nothing animates the loop blocks on input and uses no CPU.

mod app_loop;
mod app_view;
pub mod chart_feed;
pub mod export;
pub mod graphics;
pub mod halfblocks;
pub mod help;
mod homework_view;
pub mod lesson_run;
pub mod lesson_view;
pub mod markdown;
pub mod menu;
pub mod observed_view;
pub mod pane;
pub mod plots;
pub mod progress;
mod query;
pub mod raster;
pub mod sim_view;
pub mod status;
mod terminal;
pub mod theme;

use std::cell::{Cell, RefCell};
use std::time::{Duration, Instant};

use ratatui::crossterm::event::{Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers, MouseEvent};
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};

use crate::lesson::{Lesson, LessonError};
use app_view::raster_stamp;
pub use graphics::{Graphics, Protocol, ViewMode};
pub use halfblocks::ColourDepth;
pub use lesson_run::LessonRun;
pub use progress::Progress;
use raster::{Encoder, Job, PaneRenderer};
pub use terminal::{RunOptions, init_terminal, restore_terminal, run};
pub use theme::Background;

/// The smallest terminal the app draws into (columns, rows).
pub const MIN_SIZE: (u16, u16) = (80, 24);

/// Frames are drawn at most this often while something animates.
const FRAME: Duration = Duration::from_micros(16_667);

/// The raster view sends a new image, and redraws the screen, at most this often while the
/// simulation runs (30 a second); paused, every change is sent at once.
const RASTER_FRAME: Duration = Duration::from_micros(33_333);

/// Wall time a frame may spend stepping before the rest of its steps are dropped.
const STEP_BUDGET: Duration = Duration::from_millis(20);

/// Colours from the 16-colour palette made for the terminal's background ([`theme`]), or none
/// at all (`NO_COLOR`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Theme {
    /// False when the `NO_COLOR` environment variable is set and not empty.
    pub color: bool,
    /// The background the colours are chosen for.
    pub background: Background,
}

impl Theme {
    /// No colours (as with `NO_COLOR`).
    pub const PLAIN: Theme = Theme {
        color: false,
        background: Background::Dark,
    };

    /// Colours for a dark background.
    pub const DARK: Theme = Theme {
        color: true,
        background: Background::Dark,
    };

    /// Colours for a light background.
    pub const LIGHT: Theme = Theme {
        color: true,
        background: Background::Light,
    };

    /// Colours unless `NO_COLOR` is set to a non-empty value (<https://no-color.org>), for a
    /// dark background (see [`Theme::on`]).
    #[must_use]
    pub fn from_env() -> Theme {
        let no_color = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
        Theme {
            color: !no_color,
            background: Background::Dark,
        }
    }

    /// The same theme for `background`.
    #[must_use]
    pub fn on(self, background: Background) -> Theme {
        Theme { background, ..self }
    }

    /// `c` as drawn on the background, or the terminal's default colour when colours are off.
    #[must_use]
    pub fn color(self, c: Color) -> Color {
        if self.color {
            theme::for_background(c, self.background)
        } else {
            Color::Reset
        }
    }

    /// A style with foreground `c` (plain when colours are off).
    #[must_use]
    pub fn fg(self, c: Color) -> Style {
        if self.color {
            Style::new().fg(self.color(c))
        } else {
            Style::new()
        }
    }

    /// Greyed-out text: dark grey, or dim without colours.
    #[must_use]
    pub fn dim(self) -> Style {
        if self.color {
            Style::new().fg(self.color(Color::DarkGray))
        } else {
            Style::new().add_modifier(Modifier::DIM)
        }
    }
}

/// Which screen is shown.
#[derive(Debug)]
pub enum Screen {
    /// The list of lessons.
    Menu,
    /// One lesson, at one of its steps, with its live simulation.
    Lesson(Box<LessonRun>),
}

/// The application: the lessons, the screen, and the overlay.
#[derive(Debug)]
pub struct App {
    lessons: Vec<Result<Lesson, LessonError>>,
    screen: Screen,
    /// The highlighted menu entry.
    selected: usize,
    help: bool,
    /// The help overlay's scroll, and what its last drawing showed.
    help_scroll: Cell<help::Scroll>,
    quit: bool,
    /// A one-line message for the menu (for example why a lesson cannot open).
    menu_message: Option<String>,
    theme: Theme,
    /// Frames drawn per second, measured by [`App::run`] (none in tests).
    fps: Option<f64>,
    /// Where the scene canvas was last drawn (for the mouse).
    canvas_area: Cell<Rect>,
    /// How the scene pane draws the scene.
    view: ViewMode,
    /// The terminal's graphics protocol and cell size.
    graphics: Graphics,
    /// Colours of the half-block view.
    colour: ColourDepth,
    /// The terminal's size (columns, rows), for the pane's aspect ratio.
    size: (u16, u16),
    /// The rasteriser of the half-block view.
    pane: RefCell<PaneRenderer>,
    /// The encoder thread of the raster view (when a protocol was detected).
    encoder: Option<Encoder>,
    /// What the last raster job showed: (lesson run version, pane size).
    submitted: Option<(u64, Rect)>,
    /// The whole screen must be cleared before the next draw (images left behind).
    clear: bool,
    /// When the last raster job was sent.
    last_raster: Option<Instant>,
    /// When the raster view last sent the plots as a picture.
    charts: chart_feed::ChartFeed,
    /// Counts the lessons opened: a raster frame of an earlier one is never shown.
    opened: u64,
    /// In the event loop: lessons compute off the drawing thread (see `LessonRun::set_deferred`).
    deferred: bool,
    /// Raster images shown per second (measured by [`App::run`]).
    raster_fps: Option<f64>,
    /// What the student has done (in memory unless given a file).
    progress: Progress,
    /// The `--lessons` directory the lessons came from (`None`: the built-in ones).
    lessons_dir: Option<std::path::PathBuf>,
    /// The attached homework crate (`--homework DIR`, `H`).
    homework: Option<homework_view::HomeworkView>,
    /// The `--homework` folder.
    homework_dir: Option<std::path::PathBuf>,
    /// Where the attached crate is built.
    homework_options: crate::grade::live::BuildOptions,
    /// The builder of every attach (made on the first build thread: `H` starts no process).
    homework_builder: crate::grade::live::LazyBuilder,
}

impl App {
    /// An app showing the menu of `lessons` (each loaded, or the error that stopped it).
    #[must_use]
    pub fn new(lessons: Vec<Result<Lesson, LessonError>>, theme: Theme) -> App {
        App {
            lessons,
            screen: Screen::Menu,
            selected: 0,
            help: false,
            help_scroll: Cell::new(help::Scroll::default()),
            quit: false,
            menu_message: None,
            theme,
            fps: None,
            canvas_area: Cell::new(Rect::default()),
            view: ViewMode::HalfBlocks,
            graphics: Graphics::NONE,
            colour: if theme.color {
                ColourDepth::TrueColour
            } else {
                ColourDepth::None
            },
            size: (120, 40),
            pane: RefCell::new(PaneRenderer::default()),
            encoder: None,
            submitted: None,
            clear: false,
            last_raster: None,
            charts: chart_feed::ChartFeed::default(),
            raster_fps: None,
            opened: 0,
            deferred: false,
            progress: Progress::in_memory(),
            lessons_dir: None,
            homework: None,
            homework_dir: None,
            homework_options: crate::grade::live::BuildOptions::default(),
            homework_builder: crate::grade::live::LazyBuilder::default(),
        }
    }

    /// Keeps the student's progress in `progress` (a file, or memory only).
    #[must_use]
    pub fn with_progress(mut self, progress: Progress) -> App {
        // Said once: a progress file kept aside or not a file (`Progress::load`).
        if let Some(n) = progress.notice() {
            self.menu_message = Some(n.to_string());
        }
        self.progress = progress;
        self
    }

    /// Names the `--lessons` directory the lessons came from (the menu's commands use it).
    #[must_use]
    pub fn with_lessons_dir(mut self, dir: Option<std::path::PathBuf>) -> App {
        self.lessons_dir = dir;
        self
    }

    /// The `--lessons` directory, if the lessons came from one.
    #[must_use]
    pub fn lessons_dir(&self) -> Option<&std::path::Path> {
        self.lessons_dir.as_deref()
    }

    /// The student's progress.
    #[must_use]
    pub fn progress(&self) -> &Progress {
        &self.progress
    }

    /// Steps done and steps of entry `index` of the menu (see [`Progress::done`]).
    #[must_use]
    pub fn lesson_done(&self, index: usize) -> Option<(usize, usize)> {
        let steps = self.lesson_steps_done(index)?;
        Some((steps.iter().filter(|d| **d).count(), steps.len()))
    }

    /// Per step of lesson `index`: done (opened, its goal met, its prediction answered), from
    /// the kept progress; `None` for a lesson that did not load.
    #[must_use]
    pub fn lesson_steps_done(&self, index: usize) -> Option<Vec<bool>> {
        let l = self.lessons.get(index)?.as_ref().ok()?;
        let goals: Vec<bool> = l.steps.iter().map(|s| s.goal.is_some()).collect();
        let predictions: Vec<bool> = l.steps.iter().map(|s| s.predict.is_some()).collect();
        let key = Progress::key(&l.source, &l.slug);
        Some(self.progress.steps_done(&key, &goals, &predictions))
    }

    /// Saves what the open lesson's run changed (met goals, visits, predictions).
    fn sync_progress(&mut self) {
        let Screen::Lesson(run) = &mut self.screen else {
            return;
        };
        if !run.take_progress_changed() {
            return;
        }
        let key = Progress::key(&run.lesson().source, &run.lesson().slug);
        let record = progress::LessonProgress {
            visited: run.visited_steps().to_vec(),
            met: run.met_goals().to_vec(),
            answers: run.answers().to_vec(),
        };
        if let Some(e) = self.progress.update(&key, record) {
            run.set_message(e);
        }
    }

    /// Sets how the terminal shows the scene: the view, the graphics protocol (the raster view
    /// needs one; without it the half-block view is used) and the half-block colours.
    #[must_use]
    pub fn with_display(mut self, view: ViewMode, graphics: Graphics, colour: ColourDepth) -> App {
        self.colour = colour;
        self.encoder = graphics.protocol.and_then(|_| Encoder::new());
        // Without an encoder thread there is no raster view.
        self.graphics = if self.encoder.is_some() {
            graphics
        } else {
            Graphics {
                protocol: None,
                ..graphics
            }
        };
        self.view = if view == ViewMode::Raster && self.graphics.protocol.is_none() {
            ViewMode::HalfBlocks
        } else {
            view
        };
        self
    }

    /// The scene pane's view.
    #[must_use]
    pub fn view(&self) -> ViewMode {
        self.view
    }

    /// The view's name in the status line: `raster (sixel)`, `halfblocks`, `braille`.
    #[must_use]
    pub fn view_label(&self) -> String {
        match (self.view, self.graphics.protocol) {
            (ViewMode::Raster, Some(p)) => match self.raster_fps {
                Some(f) if self.is_animating() => format!("raster ({}, {f:.0} images/s)", p.name()),
                _ => format!("raster ({})", p.name()),
            },
            (v, _) => v.name().to_string(),
        }
    }

    /// Tells the app the terminal's size (columns, rows): the scene pane's aspect ratio follows.
    pub fn resize(&mut self, width: u16, height: u16) {
        self.size = (width, height);
        self.report_aspect();
    }

    /// Tells the open lesson the pixel grid of the view shown (the font cell for raster, braille
    /// dots otherwise) and the pane's aspect ratio in it.
    fn report_aspect(&mut self) {
        let (w, h) = self.size;
        let grid = if self.view == ViewMode::Raster {
            (
                u32::from(self.graphics.cell.0),
                u32::from(self.graphics.cell.1),
            )
        } else {
            pane::DOTS
        };
        if let Screen::Lesson(run) = &mut self.screen {
            run.set_grid(grid);
            let inner = lesson_view::scene_inner(run, Rect::new(0, 0, w, h));
            if inner.width > 0 && inner.height > 0 {
                let aspect = (f64::from(inner.width) * f64::from(grid.0))
                    / (f64::from(inner.height) * f64::from(grid.1));
                run.set_aspect(aspect);
            }
        }
    }

    /// The raster encoder, when the terminal has a graphics protocol.
    #[must_use]
    pub fn encoder(&self) -> Option<&Encoder> {
        self.encoder.as_ref()
    }

    /// Takes a finished raster frame from the encoder, if one is ready; true when one was.
    pub fn poll_raster(&mut self) -> bool {
        self.encoder.as_mut().is_some_and(Encoder::poll)
    }

    /// Sends the open lesson's current frame to the raster encoder when the raster view shows
    /// something new and the encoder is free; true when a job was sent.
    pub fn submit_raster(&mut self) -> bool {
        let Some(encoder) = &mut self.encoder else {
            return false;
        };
        let Screen::Lesson(run) = &self.screen else {
            return false;
        };
        if self.view != ViewMode::Raster
            || self.help
            || encoder.busy()
            || run.sim().diverged.is_some()
        {
            return false;
        }
        let screen = Rect::new(0, 0, self.size.0, self.size.1);
        let inner = lesson_view::scene_inner(run, screen);
        let key = (run.version(), inner);
        let now = Instant::now();
        if inner.width < 4
            || inner.height < 2
            || (run.is_running() && self.last_raster.is_some_and(|t| now - t < RASTER_FRAME))
        {
            return false;
        }
        let picture = self
            .charts
            .due(run, screen, self.theme, self.graphics.cell, now);
        if self.submitted == Some(key) && picture.is_none() {
            return false;
        }
        self.last_raster = Some(now);
        self.submitted = Some(key);
        encoder.submit(Job {
            scene: run.sim().scene.clone(),
            generation: run.generation(),
            camera: *run.camera(),
            filter: run.spring_filter(),
            cells: ratatui::layout::Size::new(inner.width, inner.height),
            graphics: self.graphics,
            stamp: raster_stamp(self.opened, run.version()),
            full: !run.is_running(),
            picture,
        });
        true
    }

    /// The lessons, as loaded.
    pub fn lessons(&self) -> &[Result<Lesson, LessonError>] {
        &self.lessons
    }

    /// The screen shown.
    #[must_use]
    pub fn screen(&self) -> &Screen {
        &self.screen
    }

    /// The open lesson's live state, if a lesson is open.
    #[must_use]
    pub fn lesson(&self) -> Option<&LessonRun> {
        match &self.screen {
            Screen::Lesson(run) => Some(run),
            Screen::Menu => None,
        }
    }

    /// The open lesson's live state, mutably.
    pub fn lesson_mut(&mut self) -> Option<&mut LessonRun> {
        match &mut self.screen {
            Screen::Lesson(run) => Some(run),
            Screen::Menu => None,
        }
    }

    /// The highlighted menu entry (an index into [`App::lessons`]).
    #[must_use]
    pub fn selected(&self) -> usize {
        self.selected
    }

    /// The menu's message line, if any.
    #[must_use]
    pub fn menu_message(&self) -> Option<&str> {
        self.menu_message.as_deref()
    }

    /// True when the help overlay is shown.
    #[must_use]
    pub fn help_shown(&self) -> bool {
        self.help
    }

    /// True once the user asked to quit.
    #[must_use]
    pub fn should_quit(&self) -> bool {
        self.quit
    }

    /// The index into [`App::lessons`] of lesson `which` (see [`find_lesson`]).
    #[must_use]
    pub fn find_lesson(&self, which: &str) -> Option<usize> {
        find_lesson(&self.lessons, which)
    }

    /// Opens entry `index` of the menu at its first step.
    ///
    /// # Errors
    /// The lesson failed to load (its message names the file and line), its first scene does
    /// not build, or there is no such entry.
    pub fn open_lesson(&mut self, index: usize) -> Result<(), String> {
        let lesson = match self.lessons.get(index) {
            Some(Ok(lesson)) => lesson.clone(),
            Some(Err(e)) => return Err(format!("this lesson cannot be opened: {e}")),
            None => return Err(format!("there is no lesson {}", index + 1)),
        };
        self.selected = index;
        let key = Progress::key(&lesson.source, &lesson.slug);
        let mut run = LessonRun::with_deferred(lesson, 0, self.deferred)?;
        if let Some(r) = self.progress.lesson(&key) {
            run.restore(&r.met, &r.visited, &r.answers);
        }
        self.screen = Screen::Lesson(Box::new(run));
        self.sync_progress();
        self.menu_message = None;
        self.clear = true;
        // A new run counts its versions from 0 again: forget the last lesson's frame.
        self.submitted = None;
        self.charts.reset();
        self.opened += 1;
        if let Some(encoder) = &mut self.encoder {
            encoder.clear();
        }
        self.report_aspect();
        Ok(())
    }

    /// True while the simulation runs (or something else needs frames without input).
    #[must_use]
    pub fn is_animating(&self) -> bool {
        !self.help && self.lesson().is_some_and(LessonRun::is_running) || self.homework_busy()
    }

    /// Advances the open lesson's simulation by `wall_dt` seconds of wall time (see the module
    /// documentation). Does nothing in the menu, under the help overlay or while paused.
    pub fn tick(&mut self, wall_dt: f64) {
        self.tick_until(wall_dt, None);
    }

    /// As [`App::tick`], but stops stepping at `deadline` (the frame's time budget).
    pub fn tick_until(&mut self, wall_dt: f64, deadline: Option<Instant>) {
        let help = self.help;
        // Beside a homework comparison the lesson steps on this thread alone: the comparison
        // and the student's program need the other core (`homework_view.rs`).
        let alone = self
            .homework
            .as_ref()
            .is_some_and(homework_view::HomeworkView::comparing);
        if let Screen::Lesson(run) = &mut self.screen {
            if help {
                run.tick_until(0.0, None);
            } else if alone {
                crate::physics::pool::alone(|| run.tick_until(wall_dt, deadline));
            } else {
                run.tick_until(wall_dt, deadline);
            }
        }
        self.sync_homework();
        self.sync_progress();
    }

    /// Handles one terminal event; returns true when the screen needs redrawing.
    pub fn handle_event(&mut self, event: &Event) -> bool {
        match event {
            Event::Key(key) => {
                self.key(*key);
                true
            }
            Event::Mouse(mouse) => self.handle_mouse(*mouse),
            Event::Resize(w, h) => {
                self.resize(*w, *h);
                self.clear = true;
                true
            }
            _ => false,
        }
    }

    /// Handles a key press (releases and repeats of other kinds are ignored) and waits for
    /// what it recomputes in the background, so that the state read next is up to date (the
    /// event loop does not wait: see [`App::handle_event`]).
    pub fn handle_key(&mut self, key: KeyEvent) {
        self.key(key);
        if let Some(run) = self.lesson_mut() {
            run.settle();
        }
    }

    /// Whether the lesson's background work has news; true when the screen must be redrawn.
    fn poll_background(&mut self) -> bool {
        self.lesson_mut().is_some_and(LessonRun::poll_background)
    }

    /// True while the lesson waits for background work.
    fn background_pending(&self) -> bool {
        self.lesson().is_some_and(LessonRun::busy)
    }

    /// A key press, its background work left running.
    fn key(&mut self, key: KeyEvent) {
        if key.kind == KeyEventKind::Release {
            return;
        }
        // Ctrl-C arrives as a key in raw mode: quit from anywhere.
        if key.modifiers.contains(KeyModifiers::CONTROL) {
            if matches!(key.code, KeyCode::Char('c' | 'C')) {
                self.quit = true;
            }
            return;
        }
        if self.help {
            // The arrows and pages scroll an overlay taller than the terminal; any other key
            // closes it (`q` and Esc only close it).
            if let Some(scroll) = self.help_scroll.get().after(key.code) {
                self.help_scroll.set(scroll);
                return;
            }
            self.help = false;
            self.clear = true;
            self.submitted = None;
            self.charts.reset();
            return;
        }
        if key.code == KeyCode::Char('?') && self.lesson().is_none_or(|r| r.chooser().is_none()) {
            self.help = true;
            self.help_scroll.set(help::Scroll::default());
            return;
        }
        let raster = self.graphics.protocol.is_some();
        match &mut self.screen {
            Screen::Menu => self.menu_key(key.code),
            Screen::Lesson(run) => {
                if run.chooser().is_some() {
                    // The method chooser takes every key (its own `v`, `q`, Esc, numbers).
                    run.handle_key_with(key.code, key.modifiers);
                } else if matches!(key.code, KeyCode::Char('q') | KeyCode::Esc) {
                    self.screen = Screen::Menu;
                    self.clear = true;
                } else if key.code == KeyCode::Char('H') {
                    self.toggle_homework();
                } else if key.code == KeyCode::Char('v') {
                    self.view = self.view.next(raster);
                    self.report_aspect();
                    let Screen::Lesson(run) = &mut self.screen else {
                        return;
                    };
                    self.clear = true;
                    self.submitted = None;
                    self.charts.reset();
                    let note = if raster {
                        ""
                    } else {
                        " (no raster view: the terminal answered no graphics protocol)"
                    };
                    run.set_message(format!("view: {}{note}", self.view.name()));
                } else if key.code == KeyCode::Char('n')
                    && run.chooser().is_none()
                    && run.step_index() + 1 == run.lesson().steps.len()
                {
                    // `n` on the last step opens the next lesson that loads.
                    let next =
                        (self.selected + 1..self.lessons.len()).find(|&i| self.lessons[i].is_ok());
                    match next {
                        Some(i) => {
                            if let Err(e) = self.open_lesson(i)
                                && let Some(run) = self.lesson_mut()
                            {
                                run.set_message(e);
                            }
                        }
                        None => {
                            run.set_message("this was the last lesson: q goes back to the menu")
                        }
                    }
                } else {
                    let step = run.step_index();
                    run.handle_key_with(key.code, key.modifiers);
                    if run.step_index() != step {
                        self.clear = true;
                        self.report_aspect();
                    }
                }
            }
        }
        self.sync_progress();
    }

    fn menu_key(&mut self, code: KeyCode) {
        let count = self.lessons.len();
        // Moving through the list keeps a message (a progress file kept aside is worth reading
        // to its end); any other key clears it.
        let moves = matches!(code, KeyCode::Up | KeyCode::Down | KeyCode::Char('j' | 'k'));
        if !moves {
            self.menu_message = None;
        }
        match code {
            KeyCode::Char('q') | KeyCode::Esc => self.quit = true,
            KeyCode::Up | KeyCode::Char('k') => self.selected = self.selected.saturating_sub(1),
            KeyCode::Down | KeyCode::Char('j') if count > 0 => {
                self.selected = (self.selected + 1).min(count - 1);
            }
            KeyCode::Home => self.selected = 0,
            KeyCode::End => self.selected = count.saturating_sub(1),
            KeyCode::Enter | KeyCode::Right | KeyCode::Char('l' | ' ') => {
                if let Err(e) = self.open_lesson(self.selected) {
                    self.menu_message = Some(e);
                }
            }
            KeyCode::Char(c @ '1'..='9') => {
                let digit = c.to_string();
                match self.find_lesson(&digit) {
                    Some(i) => {
                        self.selected = i;
                        if let Err(e) = self.open_lesson(i) {
                            self.menu_message = Some(e);
                        }
                    }
                    None => self.menu_message = Some(format!("there is no lesson {digit}")),
                }
            }
            _ => {}
        }
    }

    /// Handles a mouse event (grabbing and dragging particles); returns true when the screen
    /// needs redrawing.
    pub fn handle_mouse(&mut self, mouse: MouseEvent) -> bool {
        let area = self.canvas_area.get();
        if self.help {
            return false;
        }
        let changed = match &mut self.screen {
            Screen::Lesson(run) => run.handle_mouse(mouse, area),
            Screen::Menu => false,
        };
        self.sync_progress();
        changed
    }

    /// Sets the canvas rectangle the mouse maps to (normally recorded when drawing).
    pub fn set_canvas_area(&self, area: Rect) {
        self.canvas_area.set(area);
    }
}

/// The index in `lessons` of the lesson numbered `which` or with slug `which` (any case).
#[must_use]
pub fn find_lesson(lessons: &[Result<Lesson, LessonError>], which: &str) -> Option<usize> {
    let which = which.trim();
    let number = which.parse::<u32>().ok();
    lessons.iter().position(|l| {
        l.as_ref()
            .is_ok_and(|l| Some(l.number) == number || l.slug.eq_ignore_ascii_case(which))
    })
}
