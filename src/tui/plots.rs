//! The plots beside the scene: energy over time, the oscillator beside its exact solution, the
//! largest speed and the oscillator's error, drawn as braille charts.
//!
//! Samples are taken on a grid of simulated time (never wall time), so the same run gives the
//! same plot whatever the frame rate.

use std::collections::VecDeque;

use glam::DVec3;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Widget};

use super::Theme;
use crate::lesson::Plot;
use crate::physics::Method;
use crate::physics::diverge;
use crate::scene::Scene;
use crate::simulation::Simulation;
use crate::study::convergence::{self, ConvergenceOptions, ConvergenceReport};
use crate::study::stability::{self, StabilityOptions};
use crate::study::{Stability, StabilityReport};

/// The harmonic oscillator of the `oscillator` scene and its exact motion along the spring.
///
/// ```text
/// m u'' = -k u - k_d u'                 u = x - L0, the stretch along the spring (m)
/// γ = k_d / (2 m),  ω0 = √(k/m)
/// γ < ω0:  u = e^{-γ τ} (u0 cos ω_d τ + (v0 + γ u0)/ω_d sin ω_d τ),   ω_d = √(ω0² - γ²)
/// γ = ω0:  u = e^{-γ τ} (u0 + (v0 + γ u0) τ)
/// γ > ω0:  u = (u0 r2 - v0) e^{r1 τ}/(r2 - r1) + (v0 - u0 r1) e^{r2 τ}/(r2 - r1),   r1,2 = -γ ± √(γ² - ω0²)
/// ```
/// where `τ = t - t0` (s) is the time since the reference state `(u0, v0)` at `t0`, `k` the
/// stiffness (N/m), `k_d` the damping (N·s/m), `m` the free particle's mass (kg). Undamped and
/// from rest at `t0 = 0` this is `x(t) = L0 + A cos(√(k/m) t)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oscillator {
    /// Rest length `L0` (m).
    pub rest_length: f64,
    /// Mass of the free particle `m` (kg).
    pub mass: f64,
    /// Stiffness `k` (N/m).
    pub stiffness: f64,
    /// Damping `k_d` (N·s/m).
    pub damping: f64,
    /// Unit direction of the spring at the start, from particle 0 to particle 1.
    pub axis: DVec3,
    /// Time of the reference state `t0` (s).
    pub t0: f64,
    /// Stretch `u0 = x - L0` at `t0` (m); at `t0 = 0` this is the amplitude `A`.
    pub u0: f64,
    /// Velocity along the spring at `t0` (m/s).
    pub v0: f64,
}

impl Oscillator {
    /// The oscillator of `scene` read from its first state: one body, two particles, particle 0
    /// pinned, one spring between them, no gravity, drag or colliders. `None` for any other
    /// scene.
    #[must_use]
    pub fn detect(scene: &Scene) -> Option<Oscillator> {
        let [body] = scene.bodies.as_slice() else {
            return None;
        };
        let (model, state) = (&body.model, &body.state);
        let [spring] = model.springs.as_slice() else {
            return None;
        };
        let simple = model.particle_count() == 2
            && model.is_pinned(0)
            && !model.is_pinned(1)
            && model.gravity == DVec3::ZERO
            && model.drag == 0.0
            && model.colliders.is_empty()
            && state.spheres.is_empty()
            && ((spring.a, spring.b) == (0, 1) || (spring.a, spring.b) == (1, 0));
        let d = state.x[1] - state.x[0];
        let axis = d.normalize_or_zero();
        if !simple || axis == DVec3::ZERO {
            return None;
        }
        Some(Oscillator {
            rest_length: spring.rest_length,
            mass: model.mass[1],
            stiffness: spring.stiffness,
            damping: spring.damping,
            axis,
            t0: 0.0,
            u0: d.length() - spring.rest_length,
            v0: (state.v[1] - state.v[0]).dot(axis),
        })
    }

    /// The same oscillator restarted from the simulation's present state and coefficients (after
    /// the student changed the stiffness or damping mid-run).
    #[must_use]
    pub fn restarted(&self, sim: &Simulation) -> Oscillator {
        let Some(body) = sim.scene.bodies.first() else {
            return *self;
        };
        let Some(spring) = body.model.springs.first() else {
            return *self;
        };
        Oscillator {
            stiffness: spring.stiffness,
            damping: spring.damping,
            t0: sim.time(),
            u0: self.position(sim) - self.rest_length,
            v0: (body.state.v[1] - body.state.v[0]).dot(self.axis),
            ..*self
        }
    }

    /// Angular frequency `ω0 = √(k/m)` (rad/s).
    #[must_use]
    pub fn omega(&self) -> f64 {
        (self.stiffness / self.mass).sqrt()
    }

    /// The simulated position along the spring axis, `(x_1 - x_0)·axis` (m).
    #[must_use]
    pub fn position(&self, sim: &Simulation) -> f64 {
        sim.scene
            .bodies
            .first()
            .map_or(f64::NAN, |b| (b.state.x[1] - b.state.x[0]).dot(self.axis))
    }

    /// The exact position `L0 + u(t)` (m) at time `t` (s); see the type's documentation.
    #[must_use]
    pub fn exact(&self, t: f64) -> f64 {
        let tau = t - self.t0;
        let (u0, v0) = (self.u0, self.v0);
        let omega0 = self.omega();
        let gamma = self.damping / (2.0 * self.mass);
        let u = if gamma == 0.0 {
            if omega0 == 0.0 {
                u0 + v0 * tau
            } else {
                u0 * (omega0 * tau).cos() + v0 / omega0 * (omega0 * tau).sin()
            }
        } else if (gamma - omega0).abs() <= 1e-12 * omega0.max(gamma) {
            (-gamma * tau).exp() * (u0 + (v0 + gamma * u0) * tau)
        } else if gamma < omega0 {
            let omega_d = (omega0 * omega0 - gamma * gamma).sqrt();
            (-gamma * tau).exp()
                * (u0 * (omega_d * tau).cos() + (v0 + gamma * u0) / omega_d * (omega_d * tau).sin())
        } else {
            let root = (gamma * gamma - omega0 * omega0).sqrt();
            let (r1, r2) = (-gamma + root, -gamma - root);
            ((u0 * r2 - v0) * (r1 * tau).exp() + (v0 - u0 * r1) * (r2 * tau).exp()) / (r2 - r1)
        };
        self.rest_length + u
    }
}

/// One sample of the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Simulated time (s).
    pub t: f64,
    /// Kinetic energy (J).
    pub kinetic: f64,
    /// Gravitational energy (J).
    pub gravity: f64,
    /// Elastic energy (J).
    pub elastic: f64,
    /// Total energy (J).
    pub total: f64,
    /// Total plus the energy dissipated since the start (J); NaN without accounting.
    pub total_dissipated: f64,
    /// The method's energy error `E + D - E_0` (J); NaN without accounting.
    pub residual: f64,
    /// Largest particle speed (m/s).
    pub max_speed: f64,
    /// `|x_sim - x_exact|` for the oscillator (m); NaN otherwise.
    pub error: f64,
}

/// Most samples kept of the whole run; beyond, every other one is dropped and the interval
/// doubles, so the plots always span the whole run.
const CAPACITY: usize = 1024;

/// The sampled history of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct History {
    /// Samples of the whole run, `interval` apart.
    pub samples: Vec<Sample>,
    /// Simulated time between samples (s).
    pub interval: f64,
    next: f64,
    /// Recent `(t, x_sim)` of the oscillator, finely sampled, for the exact-solution plot.
    pub recent: VecDeque<(f64, f64)>,
    recent_interval: f64,
    recent_span: f64,
    recent_next: f64,
}

impl History {
    /// An empty history for a run with time step `dt` (s); `oscillator` sets the fine sampling
    /// of the exact plot (40 samples per period, three periods kept).
    #[must_use]
    pub fn new(dt: f64, oscillator: Option<&Oscillator>) -> History {
        let period = oscillator
            .map(|o| std::f64::consts::TAU / o.omega())
            .filter(|p| p.is_finite() && *p > 0.0)
            .unwrap_or(1.0);
        History {
            samples: Vec::new(),
            interval: dt.max(0.01),
            next: 0.0,
            recent: VecDeque::new(),
            recent_interval: period / 40.0,
            recent_span: 3.0 * period,
            recent_next: 0.0,
        }
    }

    /// Records the simulation's state when its time has reached the next sample time.
    pub fn record(&mut self, sim: &Simulation, oscillator: Option<&Oscillator>) {
        let t = sim.time();
        if let Some(o) = oscillator
            && t >= self.recent_next - 1e-12
        {
            self.recent.push_back((t, o.position(sim)));
            while self
                .recent
                .front()
                .is_some_and(|&(t0, _)| t - t0 > self.recent_span)
            {
                self.recent.pop_front();
            }
            self.recent_next = t + self.recent_interval;
        }
        if t < self.next - 1e-12 {
            return;
        }
        let e = sim.energy();
        let max_speed = sim.states().map(diverge::max_speed).fold(0.0f64, |a, b| {
            if b.is_nan() || a.is_nan() {
                f64::NAN
            } else {
                a.max(b)
            }
        });
        let error = oscillator.map_or(f64::NAN, |o| (o.position(sim) - o.exact(t)).abs());
        self.samples.push(Sample {
            t,
            kinetic: e.kinetic,
            gravity: e.gravity,
            elastic: e.elastic,
            total: e.total,
            total_dissipated: if sim.accounting() {
                e.total + sim.dissipated().total
            } else {
                f64::NAN
            },
            residual: sim.energy_residual(),
            max_speed,
            error,
        });
        while self.next <= t + 1e-12 {
            self.next += self.interval;
        }
        if self.samples.len() >= CAPACITY {
            let kept: Vec<Sample> = self.samples.iter().copied().step_by(2).collect();
            self.samples = kept;
            self.interval *= 2.0;
            self.next = self.samples.last().map_or(0.0, |s| s.t) + self.interval;
        }
    }
}

/// Draws the charts for `plots` side by side in `area`.
#[allow(clippy::too_many_arguments)]
pub fn render(
    plots: &[Plot],
    history: &History,
    oscillator: Option<&Oscillator>,
    studies: &Studies,
    now: f64,
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    if plots.is_empty() || area.width == 0 {
        return;
    }
    let count = plots.len() as u16;
    let width = area.width / count;
    for (i, plot) in plots.iter().enumerate() {
        let i = i as u16;
        let w = if i + 1 == count {
            area.width - width * i
        } else {
            width
        };
        let rect = Rect::new(area.x + width * i, area.y, w, area.height);
        render_one(*plot, history, oscillator, studies, now, theme, rect, buf);
    }
}

/// One series of a chart: name, colour, points.
struct Series {
    name: &'static str,
    short: &'static str,
    color: Color,
    points: Vec<(f64, f64)>,
}

#[allow(clippy::too_many_arguments)]
fn render_one(
    plot: Plot,
    history: &History,
    oscillator: Option<&Oscillator>,
    studies: &Studies,
    now: f64,
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    let samples = &history.samples;
    let column = |f: fn(&Sample) -> f64| -> Vec<(f64, f64)> {
        samples
            .iter()
            .filter(|s| f(s).is_finite())
            .map(|s| (s.t, f(s)))
            .collect()
    };
    let mut x_unit = " s";
    let (title, series, x_range): (&str, Vec<Series>, [f64; 2]) = match plot {
        Plot::Stability => {
            render_stability(studies.stability.as_ref(), theme, area, buf);
            return;
        }
        Plot::Convergence | Plot::WorkPrecision => {
            let work = plot == Plot::WorkPrecision;
            let report = if work {
                studies.work_precision.as_ref()
            } else {
                studies.convergence.as_ref()
            };
            let Some(report) = report else {
                let what = if work {
                    "work-precision"
                } else {
                    "convergence"
                };
                not_available(
                    "study",
                    &format!(
                        "this scene is too large to study live: run `springlab study {what} <scene>`"
                    ),
                    theme,
                    area,
                    buf,
                );
                return;
            };
            x_unit = "";
            let series = study_series(report, work);
            let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
            let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
            let title = if work {
                "log10 error (m) vs log10 force evals:"
            } else {
                "log10 error (m) vs log10 dt:"
            };
            (title, series, if x0 < x1 { [x0, x1] } else { [0.0, 1.0] })
        }
        Plot::Energy => (
            "E (J):",
            vec![
                Series {
                    name: "kinetic",
                    short: "kin",
                    color: Color::Yellow,
                    points: column(|s| s.kinetic),
                },
                Series {
                    name: "gravity",
                    short: "grav",
                    color: Color::Blue,
                    points: column(|s| s.gravity),
                },
                Series {
                    name: "elastic",
                    short: "el",
                    color: Color::Green,
                    points: column(|s| s.elastic),
                },
                Series {
                    name: "total",
                    short: "tot",
                    color: Color::White,
                    points: column(|s| s.total),
                },
                // The dissipated energy stacked on the total (flat at E0 for an exact
                // integrator) and the method's own energy error.
                Series {
                    name: "total + dissipated",
                    short: "+D",
                    color: Color::LightBlue,
                    points: column(|s| s.total_dissipated),
                },
                Series {
                    name: "residual E + D - E0",
                    short: "res",
                    color: Color::LightRed,
                    points: column(|s| s.residual),
                },
            ],
            [0.0, now.max(1.0)],
        ),
        Plot::Speed => (
            "max |v| (m/s)",
            vec![Series {
                name: "max |v|",
                short: "|v|",
                color: Color::Cyan,
                points: column(|s| s.max_speed),
            }],
            [0.0, now.max(1.0)],
        ),
        Plot::Error => (
            "|x - x_exact| (m)",
            vec![Series {
                name: "error",
                short: "err",
                color: Color::LightRed,
                points: column(|s| s.error),
            }],
            [0.0, now.max(1.0)],
        ),
        Plot::Exact => {
            let Some(o) = oscillator else {
                not_available(
                    "x(t) vs exact",
                    "no exact solution: not a one-spring oscillator",
                    theme,
                    area,
                    buf,
                );
                return;
            };
            let span = history.recent_span;
            let start = (now - span).max(0.0);
            let end = start + span;
            let simulated: Vec<(f64, f64)> = history
                .recent
                .iter()
                .copied()
                .filter(|(_, x)| x.is_finite())
                .collect();
            // The exact curve over the whole window, ahead of the simulation too, at 4 points
            // per braille column of the widest chart (200 columns).
            let exact: Vec<(f64, f64)> = (0..=800)
                .map(|i| start + span * f64::from(i) / 800.0)
                .map(|t| (t, o.exact(t)))
                .collect();
            (
                "x (m):",
                vec![
                    Series {
                        name: "exact",
                        short: "exact",
                        color: Color::Yellow,
                        points: exact,
                    },
                    Series {
                        name: "simulated",
                        short: "sim",
                        color: Color::Cyan,
                        points: simulated,
                    },
                ],
                [start, end],
            )
        }
    };
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
            (lo.min(y), hi.max(y))
        });
    let (lo, hi) = padded(lo, hi);
    let datasets: Vec<Dataset> = series
        .iter()
        .map(|s| {
            Dataset::default()
                .name(s.name)
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(theme.fg(s.color))
                .data(&s.points)
        })
        .collect();
    let label = |v: f64| Span::raw(number(v));
    // The legend is the title: each series' name in its colour (a legend box would hide the
    // curves of these small charts); short names when the full ones do not fit.
    let mut spans = vec![Span::raw(format!("{title} "))];
    let full: usize = series.iter().map(|s| s.name.chars().count() + 1).sum();
    let room = usize::from(area.width.saturating_sub(2));
    for s in series.iter().filter(|_| series.len() > 1) {
        let name = if title.chars().count() + 1 + full <= room {
            s.name
        } else {
            s.short
        };
        spans.push(Span::styled(format!("{name} "), theme.fg(s.color)));
    }
    let chart = Chart::new(datasets)
        .block(Block::bordered().title(Line::from(spans)))
        .x_axis(
            Axis::default()
                .bounds(x_range)
                .labels([
                    label(x_range[0]),
                    Span::raw(format!("{}{x_unit}", number(x_range[1]))),
                ])
                .style(theme.dim()),
        )
        .y_axis(
            Axis::default()
                .bounds([lo, hi])
                .labels([label(lo), label(hi)])
                .style(theme.dim()),
        )
        .legend_position(None);
    chart.render(area, buf);
}

fn not_available(title: &str, text: &str, theme: Theme, area: Rect, buf: &mut Buffer) {
    let block = Block::bordered().title(title);
    let inner = block.inner(area);
    block.render(area, buf);
    ratatui::widgets::Paragraph::new(text)
        .style(theme.dim())
        .wrap(ratatui::widgets::Wrap { trim: true })
        .render(inner, buf);
}

/// A y range with a margin, never empty (a constant series gets ±10 % or ±1).
fn padded(lo: f64, hi: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    if hi - lo <= 1e-12 * lo.abs().max(hi.abs()) {
        let pad = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - pad, hi + pad);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// A number in at most 7 characters: `0`, `12.5`, `-0.0312`, `1.2e4`.
#[must_use]
pub fn number(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if !v.is_finite() {
        format!("{v}")
    } else if !(1e-3..1e4).contains(&a) {
        format!("{v:.1e}")
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

/// Study results shown by the `convergence`, `stability` and `work-precision` plots, computed
/// once when a step opens (only for scenes small enough to study in a fraction of a second).
#[derive(Clone, Debug, Default)]
pub struct Studies {
    /// `study convergence` of the step's scene.
    pub convergence: Option<ConvergenceReport>,
    /// `study work-precision` (cost as force evaluations) of the step's scene.
    pub work_precision: Option<ConvergenceReport>,
    /// `study stability` of the step's scene.
    pub stability: Option<StabilityReport>,
}

/// Scenes with more springs than this are not studied live (a study of the jelly takes a minute).
const LIVE_STUDY_MAX_SPRINGS: usize = 200;

impl Studies {
    /// Runs the studies `plots` asks for on the step's scene `name` with parameters `sets`.
    #[must_use]
    pub fn compute(plots: &[Plot], name: &str, sets: &[String]) -> Studies {
        let mut studies = Studies::default();
        let small = |scene: &Scene| scene.spring_count() <= LIVE_STUDY_MAX_SPRINGS;
        for plot in plots {
            match plot {
                Plot::Convergence | Plot::WorkPrecision => {
                    let Ok((scene, used)) = convergence::load_scene(name, sets) else {
                        continue;
                    };
                    if !small(&scene) {
                        continue;
                    }
                    let work = *plot == Plot::WorkPrecision;
                    let options = ConvergenceOptions {
                        levels: if work { 6 } else { 4 },
                        ..ConvergenceOptions::default()
                    };
                    if let Ok(mut report) =
                        convergence::convergence(&scene, &options, &mut |_, _| {})
                    {
                        report.sets = used;
                        if work {
                            studies.work_precision = Some(report);
                        } else {
                            studies.convergence = Some(report);
                        }
                    }
                }
                Plot::Stability => {
                    let Ok((scene, _)) = stability::load_scene(name, sets) else {
                        continue;
                    };
                    if small(&scene) {
                        studies.stability = stability::stability(
                            &scene,
                            &StabilityOptions::default(),
                            &mut |_, _| {},
                        )
                        .ok();
                    }
                }
                _ => {}
            }
        }
        studies
    }
}

/// Colour and short name of each method in the study charts.
fn method_style(method: Method) -> (Color, &'static str) {
    match method {
        Method::ExplicitEuler => (Color::LightRed, "EE"),
        Method::SemiImplicitEuler => (Color::Green, "SIE"),
        Method::Midpoint => (Color::Yellow, "mid"),
        Method::Rk4 => (Color::Cyan, "RK4"),
        Method::ImplicitEuler => (Color::LightBlue, "IE"),
        Method::PredictorCorrector => (Color::Magenta, "PC"),
        Method::Verlet => (Color::White, "Vlt"),
        Method::Xpbd => (Color::Gray, "XPBD"),
    }
}

/// One log-log series per method: log10 error against log10 dt (or log10 force evaluations).
fn study_series(report: &ConvergenceReport, work: bool) -> Vec<Series> {
    report
        .methods
        .iter()
        .map(|m| {
            let (color, short) = method_style(m.method);
            let points = m
                .points
                .iter()
                .filter_map(|p| {
                    let x = if work { p.force_evals as f64 } else { p.dt };
                    p.error.filter(|e| *e > 0.0).map(|e| (x.log10(), e.log10()))
                })
                .collect();
            Series {
                name: m.method.name(),
                short,
                color,
                points,
            }
        })
        .collect()
}

/// The stability table: measured limit beside the theory, one line per method.
fn render_stability(report: Option<&StabilityReport>, theme: Theme, area: Rect, buf: &mut Buffer) {
    let Some(r) = report else {
        not_available(
            "stability",
            "this scene is too large to study live: run `springlab study stability <scene>`",
            theme,
            area,
            buf,
        );
        return;
    };
    let block = Block::bordered().title(format!(
        "largest stable dt·ω (ω_max = {} rad/s)",
        number(r.omega_max)
    ));
    let inner = block.inner(area);
    block.render(area, buf);
    let mut lines = vec![Line::styled(
        format!("{:<20} {:>10} {:>10}", "method", "measured", "theory"),
        theme.dim(),
    )];
    for m in &r.methods {
        let (color, _) = method_style(m.method);
        let measured = match (m.stability, m.limit_dt_omega) {
            (_, Some(z)) => format!("{z:.3}"),
            (Stability::Unconditional, None) => "any".to_string(),
            (_, None) => "none".to_string(),
        };
        // The damped theory of the scene (on the undamped oscillator: |R| ≤ 1).
        let theory = m.damped_theory.dt_omega.map_or_else(
            || m.damped_theory.stability.to_string(),
            |z| format!("{z:.3}"),
        );
        lines.push(Line::from(vec![
            Span::styled(format!("{:<20} ", m.method.name()), theme.fg(color)),
            Span::raw(format!("{measured:>10} {theory:>10}")),
        ]));
    }
    ratatui::widgets::Paragraph::new(lines).render(inner, buf);
}
