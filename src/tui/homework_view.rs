//! Your code in the lesson (`springlab lesson N --homework DIR`, `H` attaches or detaches): the
//! student's crate, built and watched by [`crate::grade::live`], steps a copy of the step's body
//! beside springlab's reference; both are drawn over the scene pane ("yours", "reference"), with
//! a strip at the bottom of the pane: the build status, where the two parted or why the
//! student's side stopped, the grader's hint, and two plots over time (the largest particle
//! distance on a log scale, the energy of each).
//!
//! The comparison runs on its own worker thread and the student's code in its own process: the
//! drawing thread only reads frames. The worker may step as far as the lesson's simulation has
//! (`Live::advance_to` with the run's step count), never further.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::thread;

use glam::DVec3;
use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::canvas::{Canvas, Line as CanvasLine};
use ratatui::widgets::{Axis, Chart, Clear, Dataset, GraphType, Paragraph, Widget, Wrap};

use super::lesson_run::LessonRun;
use super::pane::dot_view;
use super::{App, Screen, Theme};
use crate::grade::live::{
    self, BuildOptions, Built, Frame, Integrator, LazyBuilder, Live, LiveOptions, Reload, Setup,
    Watcher,
};
use crate::physics::Method;

/// Colour of the student's body.
const YOURS: Color = Color::Magenta;
/// Colour of the reference body.
const REFERENCE: Color = Color::Cyan;
/// Samples kept for the plots (older ones are thinned by half).
const SAMPLES: usize = 512;

/// What the comparison was started for: the run's generation and step, the bodies' methods,
/// dt and the build.
type Key = (u64, usize, Vec<Method>, u64, u64);

/// The attached crate and its comparison.
pub struct HomeworkView {
    dir: PathBuf,
    watcher: Option<Watcher>,
    built: Option<Built>,
    /// Counts builds: a new one restarts the comparison.
    builds: u64,
    live: Option<Live>,
    key: Option<Key>,
    /// The run's step count last seen (a smaller one is a reset).
    seen_steps: u64,
    /// The comparison has not caught up with the run yet.
    behind: bool,
    /// Steps the comparison's last frame is behind the lesson's simulation.
    lag: u64,
    /// Build status: "building…", "reloaded", or the compiler's first error.
    status: String,
    /// Why there is no comparison on this step.
    idle: Option<String>,
    hint: Arc<Mutex<Option<String>>>,
    hint_for: Option<(u64, Integrator)>,
    last: Option<Frame>,
    /// (time s, largest distance m, your energy J, reference energy J).
    samples: Vec<(f64, f64, f64, f64)>,
}

impl std::fmt::Debug for HomeworkView {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HomeworkView")
            .field("dir", &self.dir)
            .field("status", &self.status)
            .finish_non_exhaustive()
    }
}

impl HomeworkView {
    /// Starts building and watching the crate in `dir` (in the background: the builder too,
    /// made once per app by the first build thread that needs it, `builder`).
    ///
    /// # Errors
    /// The folder cannot be watched.
    pub fn attach(
        dir: &Path,
        builder: LazyBuilder,
        options: BuildOptions,
    ) -> Result<HomeworkView, String> {
        let watcher = Watcher::start_lazy(dir, builder, options)?;
        Ok(HomeworkView {
            dir: dir.to_path_buf(),
            watcher: Some(watcher),
            built: None,
            builds: 0,
            live: None,
            key: None,
            seen_steps: 0,
            behind: false,
            lag: 0,
            status: "building…".to_string(),
            idle: None,
            hint: Arc::new(Mutex::new(None)),
            hint_for: None,
            last: None,
            samples: Vec::new(),
        })
    }

    /// True while something arrives without input (a build, the hint, frames).
    #[must_use]
    pub fn busy(&self) -> bool {
        self.status == "building…"
            || (self.hint_for.is_some() && self.hint.lock().is_ok_and(|h| h.is_none()))
            || self.behind
    }

    /// True while a comparison runs beside the lesson: the lesson's simulation then steps
    /// alone (`physics::pool::alone`), leaving the other core to the comparison's threads and
    /// the student's program (a pool worker woken for each of the lesson's passes spun on it).
    #[must_use]
    pub fn comparing(&self) -> bool {
        self.live.is_some()
    }

    /// The status line's text.
    #[must_use]
    pub fn status_line(&self) -> String {
        let name = self
            .dir
            .canonicalize()
            .ok()
            .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
            .unwrap_or_else(|| self.dir.display().to_string());
        match (&self.idle, &self.live) {
            (Some(why), _) => format!("homework {name}: {} · {why}", self.status),
            (None, Some(live)) => format!(
                "homework {name} · your {}(): {}",
                live.setup().integrator.name(),
                self.status
            ),
            (None, None) => format!("homework {name}: {}", self.status),
        }
    }

    /// Reads the watcher, (re)starts the comparison for the run's step, lets it advance to the
    /// run's step count and keeps its frames.
    pub fn sync(&mut self, run: &mut LessonRun) {
        while let Some(report) = self.watcher.as_ref().and_then(Watcher::try_next) {
            self.status = report.status();
            if let Reload::Reloaded(built) = report {
                self.built = Some(*built);
                self.builds += 1;
            }
        }
        let sim = run.sim();
        let key: Key = (
            run.generation(),
            run.step_index(),
            sim.scene.bodies.iter().map(|b| b.method).collect(),
            sim.dt().to_bits(),
            self.builds,
        );
        let reset = sim.steps < self.seen_steps;
        self.seen_steps = sim.steps;
        if self.built.is_some() && (self.key.as_ref() != Some(&key) || reset) {
            self.restart(run);
            self.key = Some(key);
        }
        let sim = run.sim();
        if let Some(live) = &self.live {
            live.advance_to(sim.steps);
            for frame in live.drain() {
                self.keep(&frame);
                self.last = Some(frame);
            }
            self.behind = self
                .last
                .as_ref()
                .map_or(sim.steps > 0, |f| f.step < sim.steps);
            self.lag = self
                .last
                .as_ref()
                .map_or(0, |f| sim.steps.saturating_sub(f.step));
        } else {
            self.behind = false;
        }
    }

    fn restart(&mut self, run: &mut LessonRun) {
        self.live = None;
        run.set_handover(None);
        self.last = None;
        self.samples.clear();
        let Some(built) = &self.built else { return };
        let sim = run.sim();
        let mut scene = match run.step().build_scene() {
            Ok(s) => s,
            Err(e) => {
                self.idle = Some(e.to_string());
                return;
            }
        };
        for (b, now) in scene.bodies.iter_mut().zip(&sim.scene.bodies) {
            b.method = now.method;
            b.params = now.params;
        }
        scene.dt = sim.dt();
        match Setup::from_scene(built.assignment, run.lesson().number, &scene, 0.0) {
            Ok(setup) => {
                self.idle = None;
                let integrator = setup.integrator;
                if self.hint_for != Some((self.builds, integrator)) {
                    self.hint_for = Some((self.builds, integrator));
                    let slot = Arc::new(Mutex::new(None));
                    self.hint = Arc::clone(&slot);
                    let built = built.clone();
                    let _ = thread::Builder::new()
                        .name("homework-hint".to_string())
                        .spawn(move || {
                            super::lesson_run::lower_priority();
                            let hint = live::grader_hint(&built, integrator);
                            if let Ok(mut s) = slot.lock() {
                                *s = Some(hint);
                            }
                        });
                }
                let live = Live::start(built.homework.clone(), setup, LiveOptions::default());
                // The lesson's own steps of the body, so that the reference need not take
                // them again (`grade::live`'s hand-over).
                run.set_handover(live.handover());
                self.live = Some(live);
            }
            Err(why) => self.idle = Some(why),
        }
    }

    fn keep(&mut self, f: &Frame) {
        if self.samples.len() >= SAMPLES {
            let mut i = 0usize;
            self.samples.retain(|_| {
                i += 1;
                i.is_multiple_of(2)
            });
        }
        self.samples.push((
            f.time,
            f.distance,
            f.energy_yours.unwrap_or(f64::NAN),
            f.energy_reference,
        ));
    }

    /// The lines of the strip: status, parting or failure, hint.
    fn lines(&self) -> Vec<Line<'static>> {
        let mut lines = vec![Line::from(self.status_line())];
        match &self.last {
            Some(f) => {
                let verdict = if let Some(why) = &f.failure {
                    why.clone()
                } else if let Some(p) = &f.parting {
                    format!("yours {}", p.describe())
                } else {
                    // Frames come every 16 steps: a larger lag means the comparison is
                    // slower than the lesson.
                    let lag = if self.lag > LiveOptions::default().frame_every {
                        format!(", {} steps behind the lesson", self.lag)
                    } else {
                        String::new()
                    };
                    format!(
                        "no parting so far (t = {:.2} s, largest distance {:.1e} m{lag})",
                        f.time, f.distance
                    )
                };
                lines.push(Line::from(verdict));
            }
            None if self.idle.is_none() && self.built.is_some() => {
                lines.push(Line::from("press space to run both"));
            }
            None => {}
        }
        if let Ok(h) = self.hint.lock()
            && let Some(h) = h.as_ref()
            && self.idle.is_none()
        {
            lines.push(Line::from(h.clone()));
        } else if self.hint_for.is_some() && self.idle.is_none() {
            lines.push(Line::from("asking the grader for a hint…"));
        }
        lines
    }
}

impl App {
    /// Attaches the homework crate in `dir` (`--homework DIR`), built in the grader's
    /// default cache.
    #[must_use]
    pub fn with_homework(self, dir: Option<PathBuf>) -> App {
        self.with_homework_options(dir, BuildOptions::default())
    }

    /// [`App::with_homework`] with the build cache and call limit of `options`.
    #[must_use]
    pub fn with_homework_options(mut self, dir: Option<PathBuf>, options: BuildOptions) -> App {
        self.homework_dir = dir.clone();
        self.homework_options = options;
        self.homework_builder = LazyBuilder::default();
        if let Some(dir) = dir {
            match HomeworkView::attach(
                &dir,
                self.homework_builder.clone(),
                self.homework_options.clone(),
            ) {
                Ok(view) => self.homework = Some(view),
                Err(e) => self.menu_message = Some(e),
            }
        }
        self
    }

    /// `H`: detaches the crate, or attaches it again (`--homework DIR`, else the current
    /// folder).
    pub(super) fn toggle_homework(&mut self) {
        let message = if self.homework.take().is_some() {
            "homework detached (H attaches it again)".to_string()
        } else {
            let dir = self
                .homework_dir
                .clone()
                .unwrap_or_else(|| PathBuf::from("."));
            match HomeworkView::attach(
                &dir,
                self.homework_builder.clone(),
                self.homework_options.clone(),
            ) {
                Ok(view) => {
                    self.homework = Some(view);
                    format!("homework {}: building…", dir.display())
                }
                Err(e) => e,
            }
        };
        if let Screen::Lesson(run) = &mut self.screen {
            run.set_message(message);
        }
    }

    /// Lets the attached crate's comparison follow the open lesson.
    pub(super) fn sync_homework(&mut self) {
        if let (Some(view), Screen::Lesson(run)) = (&mut self.homework, &mut self.screen) {
            view.sync(run);
        }
    }

    /// True while the attached crate has something on its way.
    pub(super) fn homework_busy(&self) -> bool {
        self.homework.as_ref().is_some_and(HomeworkView::busy)
    }
}

/// Draws the attached crate's bodies over the scene pane `inner` and its strip at the bottom.
pub fn render(app: &App, run: &LessonRun, theme: Theme, inner: Rect, buf: &mut Buffer) {
    let Some(view) = &app.homework else { return };
    if inner.width < 20 || inner.height < 8 {
        return;
    }
    let strip_height = (inner.height * 2 / 5).clamp(6, 12);
    let [scene, strip] =
        Layout::vertical([Constraint::Fill(1), Constraint::Length(strip_height)]).areas(inner);
    if let (Some(f), Some(live)) = (&view.last, &view.live) {
        let springs: Vec<(usize, usize)> = live
            .setup()
            .model
            .springs()
            .iter()
            .map(|s| (s.a as usize, s.b as usize))
            .collect();
        bodies(run, theme, inner, scene, &springs, f, buf);
        let legend = Line::from(vec![
            Span::styled("── yours ", theme.fg(YOURS)),
            Span::styled("── reference", theme.fg(REFERENCE)),
        ]);
        let w = legend.width() as u16;
        if scene.width > w {
            buf.set_line(scene.x + scene.width - w, scene.y, &legend, w);
        }
    }
    Clear.render(strip, buf);
    let text = view.lines();
    // Wrapped: a compiler error or a hint is longer than the pane is wide.
    let width = usize::from(strip.width.max(1));
    let rows: usize = text.iter().map(|l| l.width().max(1).div_ceil(width)).sum();
    let text_rows = u16::try_from(rows).unwrap_or(u16::MAX).min(strip.height);
    let [words, plots] =
        Layout::vertical([Constraint::Length(text_rows), Constraint::Fill(1)]).areas(strip);
    Paragraph::new(text)
        .wrap(Wrap { trim: false })
        .render(words, buf);
    if plots.height >= 3 && view.samples.len() > 1 {
        let [left, right] =
            Layout::horizontal([Constraint::Percentage(50), Constraint::Fill(1)]).areas(plots);
        distance_plot(&view.samples, theme, left, buf);
        energy_plot(&view.samples, theme, right, buf);
    }
}

/// Both bodies' springs, projected as the scene pane projects (braille dots of `inner`), drawn
/// only inside `clip`.
fn bodies(
    run: &LessonRun,
    theme: Theme,
    inner: Rect,
    clip: Rect,
    springs: &[(usize, usize)],
    f: &Frame,
    buf: &mut Buffer,
) {
    let view = dot_view(run.camera(), inner);
    let (w, h) = (view.width, view.height);
    let line = |ctx: &mut ratatui::widgets::canvas::Context, a: DVec3, b: DVec3, c: Color| {
        let (ca, cb) = (view.to_camera(a), view.to_camera(b));
        if let Some((ca, cb)) = view.clip_segment(ca, cb)
            && let (Some(p), Some(q)) = (view.project_camera(ca), view.project_camera(cb))
        {
            ctx.draw(&CanvasLine::new(
                f64::from(p.x),
                h - f64::from(p.y),
                f64::from(q.x),
                h - f64::from(q.y),
                c,
            ));
        }
    };
    let mut scratch = Buffer::empty(inner);
    Canvas::default()
        .marker(Marker::Braille)
        .x_bounds([0.0, w])
        .y_bounds([0.0, h])
        .paint(|ctx| {
            let draw = |ctx: &mut ratatui::widgets::canvas::Context, x: &[DVec3], c: Color| {
                for &(a, b) in springs {
                    if a < x.len() && b < x.len() {
                        line(ctx, x[a], x[b], c);
                    }
                }
            };
            draw(ctx, &f.reference, theme.color(REFERENCE));
            ctx.layer();
            if let Some(y) = &f.yours {
                draw(ctx, y, theme.color(YOURS));
            }
        })
        .render(inner, &mut scratch);
    for y in clip.y..clip.y + clip.height {
        for x in clip.x..clip.x + clip.width {
            let cell = &scratch[(x, y)];
            let symbol = cell.symbol();
            if symbol != " " && symbol != "\u{2800}" {
                buf[(x, y)].set_symbol(symbol).set_fg(cell.fg);
            }
        }
    }
}

fn bounds(values: impl Iterator<Item = f64>) -> [f64; 2] {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return [0.0, 1.0];
    }
    let pad = ((hi - lo) * 0.05).max(1e-9 * hi.abs().max(1.0));
    [lo - pad, hi + pad]
}

fn time_axis(samples: &[(f64, f64, f64, f64)]) -> Axis<'static> {
    let t = samples.last().map_or(1.0, |s| s.0).max(1e-9);
    Axis::default()
        .bounds([samples.first().map_or(0.0, |s| s.0), t])
        .labels(vec![Span::raw(""), Span::raw(format!("{t:.1} s"))])
}

/// log10 of the largest particle distance over time.
fn distance_plot(samples: &[(f64, f64, f64, f64)], theme: Theme, area: Rect, buf: &mut Buffer) {
    let points: Vec<(f64, f64)> = samples
        .iter()
        .map(|s| (s.0, s.1.max(1e-18).log10()))
        .collect();
    let y = bounds(points.iter().map(|p| p.1));
    let data = [Dataset::default()
        .name("log10 distance (m)")
        .marker(Marker::Braille)
        .graph_type(GraphType::Line)
        .style(theme.fg(YOURS))
        .data(&points)];
    Chart::new(data.to_vec())
        .x_axis(time_axis(samples))
        .y_axis(Axis::default().bounds(y).labels(vec![
            Span::raw(format!("{:.0}", y[0])),
            Span::raw(format!("{:.0}", y[1])),
        ]))
        .style(Style::default())
        .render(area, buf);
}

/// The energy of each body over time.
fn energy_plot(samples: &[(f64, f64, f64, f64)], theme: Theme, area: Rect, buf: &mut Buffer) {
    let yours: Vec<(f64, f64)> = samples
        .iter()
        .filter(|s| s.2.is_finite())
        .map(|s| (s.0, s.2))
        .collect();
    let reference: Vec<(f64, f64)> = samples.iter().map(|s| (s.0, s.3)).collect();
    let y = bounds(yours.iter().chain(&reference).map(|p| p.1));
    let data = vec![
        Dataset::default()
            .name("E reference (J)")
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(theme.fg(REFERENCE))
            .data(&reference),
        Dataset::default()
            .name("E yours (J)")
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(theme.fg(YOURS))
            .data(&yours),
    ];
    Chart::new(data)
        .x_axis(time_axis(samples))
        .y_axis(Axis::default().bounds(y).labels(vec![
            Span::raw(format!("{:.3}", y[0])),
            Span::raw(format!("{:.3}", y[1])),
        ]))
        .render(area, buf);
}
