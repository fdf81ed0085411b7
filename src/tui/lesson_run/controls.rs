//! The controller of the lesson screen: what each key and mouse action does to the run.

use glam::DVec3;
use ratatui::crossterm::event::{KeyCode, KeyModifiers, MouseButton, MouseEvent, MouseEventKind};
use ratatui::layout::Rect;

use crate::tui::plots::{self, Oscillator};
use crate::tui::status::precise;

use crate::physics::Method;
use crate::physics::particles::pin_particle;
use crate::render::camera::ZOOM_STEP;
use crate::scene::lattice;
use crate::simulation::Simulation;

use super::{
    COEFFICIENT_FACTOR, Chooser, DT_RANGE, Drag, FIRST_DAMPING, FIRST_DRAG_RATE,
    FIRST_VERLET_GAMMA, HSCROLL_STEP, LessonRun, MAX_PASSES, MAX_VERLET_GAMMA, PAN_STEP, Rates,
    SPEED_RANGE, build, method_key, uniform,
};
use crate::tui::pane::{self, SpringFilter, contains};

/// Degrees the arrow keys turn the camera.
pub const ORBIT_STEP_DEGREES: f64 = 15.0;

impl LessonRun {
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
            KeyCode::Char('R') => self.restore_step(),
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
            KeyCode::Char('x') => self.message = Some(self.history.toggle_full_exact()),
            KeyCode::Char('n') => self.go_to_step(self.step + 1),
            KeyCode::Char('p') => match self.step.checked_sub(1) {
                Some(s) => self.go_to_step(s),
                None => self.message = Some("this is the first step".into()),
            },
            KeyCode::Tab => {
                let plots = self.shown_plots();
                if plots.len() > 1 {
                    self.plot_turn = (self.plot_turn + 1) % plots.len();
                    self.message = Some(format!(
                        "plot {} of {} where one fits at a time (Tab: the next)",
                        self.plot_turn + 1,
                        plots.len()
                    ));
                }
            }
            KeyCode::PageDown => {
                self.text_scroll = self.text_scroll.saturating_add(self.text_page()).min(999);
            }
            KeyCode::PageUp => self.text_scroll = self.text_scroll.saturating_sub(self.text_page()),
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

    /// `R`: the step as it opened: its own scene, parameters, method, dt, pins, springs shown,
    /// methods shown in the study charts and first view, paused at `t = 0`. The speed factor,
    /// the steps-per-frame cap and the prediction's answer stay.
    pub fn restore_step(&mut self) {
        self.release();
        match build(&self.lesson, self.step) {
            Ok(sim) => {
                self.sim = sim;
                self.filter = SpringFilter::All;
                self.restart_scene();
                self.revealed = None;
                self.message =
                    Some("the step as it opened: its parameters, methods and view".into());
            }
            Err(e) => self.message = Some(e),
        }
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
            KeyCode::Char(d) if d.is_ascii_digit() && d != '0' => {
                Method::ALL.get(d as usize - '1' as usize).copied()
            }
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
        self.limit_stale = true;
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
            body.model.drag = ladder(c, up, first, 2.0, f64::INFINITY);
        }
        self.sim.rebase_energy();
        self.refresh_spectra();
        let drags: Vec<f64> = self.sim.scene.bodies.iter().map(|b| b.model.drag).collect();
        self.message = Some(match uniform(drags.iter().copied()) {
            Some(0.0) => "no air drag".into(),
            Some(c) => format!(
                "air drag c = {} N·s/m on every particle (f = -c v)",
                precise(c)
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
                .filter(|b| b.method.reads("verlet_damping"))
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
            .filter(|b| b.method.reads("iterations"))
            // XPBD runs at least one solver pass.
            .map(|b| {
                if b.method == Method::Xpbd {
                    b.params.iterations.max(1)
                } else {
                    b.params.iterations
                }
            });
        let first = it.next()?;
        it.all(|p| p == first).then_some(first)
    }

    /// `G` / `g`: Verlet's damping factor γ per step of every body, ×10 / ÷10.
    fn scale_gamma(&mut self, up: bool) {
        for body in &mut self.sim.scene.bodies {
            let g = body.params.verlet_damping;
            body.params.verlet_damping = ladder(g, up, FIRST_VERLET_GAMMA, 10.0, MAX_VERLET_GAMMA);
        }
        self.sim.rebase_energy();
        self.limit_stale = true;
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
            .any(|b| b.method.reads("verlet_damping"));
        self.message = Some(format!(
            "Verlet damping γ = {} per step: a decay rate γ/dt = {} 1/s at this dt{}",
            precise(g),
            precise(g / dt),
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
        self.limit_stale = true;
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
        self.message = Some(format!("dt = {} s", precise(dt)));
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
            Some(k) => format!("stiffness k = {} N/m", precise(k)),
            None => format!("stiffness ×{} of every spring", precise(factor)),
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
            Some(c) => format!("damping k_d = {} N·s/m", precise(c)),
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
        let job = super::deferred::Export {
            sim: self.sim.clone(),
            generation: self.generation,
            camera: self.camera,
            filter: self.filter,
            aspect: self.aspect,
            path,
        };
        if !self.deferred {
            self.message = Some(job.write());
            return;
        }
        let name = job.path.display().to_string();
        self.message = Some(match self.exports.send(job) {
            Ok(()) => format!("writing {name}…"),
            Err(job) => job.write(),
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
                let Some((body, index, depth)) = pane::pick(
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
                let p = pane::cell_to_world(
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
}

/// One press of a coefficient key (`A`/`a`, `G`/`g`) on the value `c`: up from zero starts at
/// `first`, else ×`factor` (at most `max`); down ÷`factor`, and to zero once below `first` (with a
/// relative slack of 10⁻⁹ for round-off).
fn ladder(c: f64, up: bool, first: f64, factor: f64, max: f64) -> f64 {
    if up {
        if c <= 0.0 {
            first
        } else {
            (c * factor).min(max)
        }
    } else if c / factor < first * (1.0 - 1e-9) {
        0.0
    } else {
        c / factor
    }
}

/// The step text's scrolling (PgUp / PgDn above) and the plot shown where one fits (Tab).
impl LessonRun {
    /// Which of the shown plots the screen shows where only one fits at a time.
    #[must_use]
    pub fn plot_turn(&self) -> usize {
        self.plot_turn
    }

    /// Records how many rows of the step's text the screen shows (the drawing calls it), so a
    /// page of PgUp / PgDn is what the student sees, less one row kept for context.
    pub fn set_text_rows(&self, rows: u16) {
        self.text_rows.set(rows);
    }

    /// Rows one PgUp / PgDn moves the text: the rows shown less one, at least one.
    pub(crate) fn text_page(&self) -> u16 {
        self.text_rows.get().saturating_sub(1).max(1)
    }

    /// Lines the step's text is scrolled down.
    #[must_use]
    pub fn text_scroll(&self) -> u16 {
        self.text_scroll
    }
}
