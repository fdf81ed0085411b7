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
        let [spring] = model.springs() else {
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
        let Some(spring) = body.model.springs().first() else {
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
#[derive(Clone, Debug, PartialEq)]
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
    /// Per body: total energy (J), kinetic energy (J), largest speed (m/s), largest spring
    /// stretch `max |L/L0 - 1|`.
    pub bodies: Vec<[f64; 4]>,
}

impl Sample {
    /// The quantities of a sample as one vector (for the min / max of a bin): the nine scalars,
    /// then four per body.
    fn values(&self) -> Vec<f64> {
        let mut v = vec![
            self.kinetic,
            self.gravity,
            self.elastic,
            self.total,
            self.total_dissipated,
            self.residual,
            self.max_speed,
            self.error,
        ];
        for b in &self.bodies {
            v.extend_from_slice(b);
        }
        v
    }
}

/// Index of a per-body quantity in [`Sample::values`]: body `b`, quantity `q` (0 total, 1
/// kinetic, 2 max speed, 3 stretch).
fn body_index(b: usize, q: usize) -> usize {
    8 + 4 * b + q
}

/// A stretch of the run: the smallest and largest value of every quantity in it, and its last
/// sample. Long runs merge neighbouring bins, so the plots draw a min / max envelope, never a
/// thinned-out line that misses the peaks.
#[derive(Clone, Debug, PartialEq)]
pub struct Bin {
    /// Simulated time of the first sample (s).
    pub t0: f64,
    /// Simulated time of the last sample (s).
    pub t1: f64,
    /// Per quantity ([`Sample::values`] order): smallest finite value (NaN if none).
    pub lo: Vec<f64>,
    /// Per quantity: largest finite value (NaN if none).
    pub hi: Vec<f64>,
    /// Samples merged into it.
    pub count: u32,
}

impl Bin {
    fn new(s: &Sample) -> Bin {
        let v = s.values();
        Bin {
            t0: s.t,
            t1: s.t,
            lo: v.clone(),
            hi: v,
            count: 1,
        }
    }

    fn merge(&mut self, other: &Bin) {
        self.t1 = other.t1;
        self.count += other.count;
        let pick = |a: f64, b: f64, min: bool| match (a.is_finite(), b.is_finite()) {
            (true, true) => {
                if min {
                    a.min(b)
                } else {
                    a.max(b)
                }
            }
            (true, false) => a,
            _ => b,
        };
        for (i, v) in self.lo.iter_mut().enumerate() {
            *v = pick(*v, other.lo.get(i).copied().unwrap_or(f64::NAN), true);
        }
        for (i, v) in self.hi.iter_mut().enumerate() {
            *v = pick(*v, other.hi.get(i).copied().unwrap_or(f64::NAN), false);
        }
    }
}

/// Most bins kept of the whole run; beyond, neighbours merge in pairs, so the plots always span
/// the whole run with every peak kept.
const CAPACITY: usize = 1024;

/// Simulated time between samples (s) when the step is shorter.
const SAMPLE_INTERVAL: f64 = 0.01;

/// The sampled history of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct History {
    /// Bins of the whole run, in time order.
    pub bins: Vec<Bin>,
    /// Labels of the bodies (for per-body curves).
    pub labels: Vec<String>,
    /// Simulated time between samples (s).
    pub interval: f64,
    /// Samples per bin: doubles whenever the bins merge.
    per_bin: u32,
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
            bins: Vec::new(),
            labels: Vec::new(),
            interval: dt.max(SAMPLE_INTERVAL),
            per_bin: 1,
            next: 0.0,
            recent: VecDeque::new(),
            recent_interval: period / 40.0,
            recent_span: 3.0 * period,
            recent_next: 0.0,
        }
    }

    /// The last sample time (s).
    #[must_use]
    pub fn last_time(&self) -> Option<f64> {
        self.bins.last().map(|b| b.t1)
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
        self.set_labels(sim);
        let sample = sample(sim, oscillator, t);
        self.push(&sample);
        while self.next <= t + 1e-12 {
            self.next += self.interval;
        }
    }

    /// Records the state a diverged step produced: its time and the speed the divergence check
    /// measured (the last point of the speed plot), and whatever energies are still finite.
    pub fn record_divergence(&mut self, sim: &Simulation, oscillator: Option<&Oscillator>) {
        let Some(d) = &sim.diverged else { return };
        self.set_labels(sim);
        let mut s = sample(sim, oscillator, d.time);
        s.max_speed = d.max_speed;
        self.push(&s);
    }

    fn set_labels(&mut self, sim: &Simulation) {
        if self.labels.len() != sim.scene.bodies.len() {
            self.labels = sim.scene.bodies.iter().map(|b| b.label.clone()).collect();
        }
    }

    fn push(&mut self, sample: &Sample) {
        let bin = Bin::new(sample);
        match self.bins.last_mut() {
            Some(last) if last.count < self.per_bin => last.merge(&bin),
            _ => self.bins.push(bin),
        }
        if self.bins.len() >= CAPACITY {
            let old = std::mem::take(&mut self.bins);
            for pair in old.chunks(2) {
                let mut b = pair[0].clone();
                if let Some(second) = pair.get(1) {
                    b.merge(second);
                }
                self.bins.push(b);
            }
            self.per_bin *= 2;
        }
    }
}

/// The sample of `sim` at time `t`.
fn sample(sim: &Simulation, oscillator: Option<&Oscillator>, t: f64) -> Sample {
    let e = sim.energy();
    let mut bodies = Vec::new();
    let mut max_speed = 0.0f64;
    for body in &sim.scene.bodies {
        let be = crate::physics::energy::energy(&body.model, &body.state);
        let speed = diverge::max_speed(&body.state);
        max_speed = if speed.is_nan() || max_speed.is_nan() {
            f64::NAN
        } else {
            max_speed.max(speed)
        };
        let stretch = body
            .model
            .springs()
            .iter()
            .filter(|s| s.rest_length > 0.0)
            .map(|s| {
                let l = (body.state.x[s.a as usize] - body.state.x[s.b as usize]).length();
                (l / s.rest_length - 1.0).abs()
            })
            .fold(0.0f64, f64::max);
        bodies.push([be.total, be.kinetic, speed, stretch]);
    }
    let error = oscillator.map_or(f64::NAN, |o| (o.position(sim) - o.exact(t)).abs());
    Sample {
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
        bodies,
    }
}

/// Draws the charts for `plots` side by side in `area`; `shown` picks the methods of the study
/// charts (by index into [`Method::ALL`]).
#[allow(clippy::too_many_arguments)]
pub fn render(
    plots: &[Plot],
    history: &History,
    oscillator: Option<&Oscillator>,
    studies: &Studies,
    shown: [bool; 8],
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
        let view = View {
            history,
            oscillator,
            studies,
            shown,
            now,
            theme,
        };
        render_one(*plot, &view, rect, buf);
    }
}

/// What every chart may draw from.
struct View<'a> {
    history: &'a History,
    oscillator: Option<&'a Oscillator>,
    studies: &'a Studies,
    shown: [bool; 8],
    now: f64,
    theme: Theme,
}

/// One series of a chart: name, colour, points.
struct Series {
    name: String,
    short: String,
    color: Color,
    points: Vec<(f64, f64)>,
    /// Drawn dim as a guide (slope lines), left out of the legend.
    guide: bool,
}

impl Series {
    fn new(name: &str, short: &str, color: Color, points: Vec<(f64, f64)>) -> Series {
        Series {
            name: name.to_string(),
            short: short.to_string(),
            color,
            points,
            guide: false,
        }
    }
}

/// The points of one curve: (x, y).
type Points = Vec<(f64, f64)>;

/// The curve of quantity `q` ([`Sample::values`] order) over the run, drawn into a chart
/// `columns` braille dots wide: one point per bin while the bins fit, else per column its
/// largest and its smallest value as two lines (a min / max envelope). Returns (upper, lower);
/// lower is empty when every column holds a single value.
fn envelope(history: &History, q: usize, t_end: f64, columns: usize) -> (Points, Points) {
    let finite = |b: &Bin| {
        let (lo, hi) = (
            b.lo.get(q).copied().unwrap_or(f64::NAN),
            b.hi.get(q).copied().unwrap_or(f64::NAN),
        );
        (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
    };
    let columns = columns.max(2);
    let single = history.bins.iter().all(|b| b.count == 1) && history.bins.len() <= columns;
    if single {
        let pts = history
            .bins
            .iter()
            .filter_map(|b| finite(b).map(|(_, hi)| (b.t1, hi)))
            .collect();
        return (pts, Vec::new());
    }
    let span = t_end.max(1e-12);
    let mut cols: Vec<Option<(f64, f64, f64)>> = vec![None; columns];
    for b in &history.bins {
        let Some((lo, hi)) = finite(b) else { continue };
        let t = 0.5 * (b.t0 + b.t1);
        let c = ((t / span) * columns as f64)
            .floor()
            .clamp(0.0, columns as f64 - 1.0) as usize;
        cols[c] = Some(match cols[c] {
            None => (t, lo, hi),
            Some((t0, l, h)) => (t0, l.min(lo), h.max(hi)),
        });
    }
    let mut upper = Vec::new();
    let mut lower = Vec::new();
    for (i, c) in cols.iter().enumerate() {
        if let Some((_, lo, hi)) = c {
            let t = (i as f64 + 0.5) / columns as f64 * span;
            upper.push((t, *hi));
            lower.push((t, *lo));
        }
    }
    // The last sample (a divergence, for example) is drawn where it happened.
    if let Some(b) = history.bins.last()
        && let Some((lo, hi)) = finite(b)
    {
        upper.push((b.t1, hi));
        lower.push((b.t1, lo));
    }
    (upper, lower)
}

fn render_one(plot: Plot, v: &View, area: Rect, buf: &mut Buffer) {
    let theme = v.theme;
    let history = v.history;
    let now = v.now;
    let x_range = [0.0, now.max(1.0)];
    // Braille dots across the plotting area (borders and a y label of ~7 cells left out).
    let columns = usize::from(area.width.saturating_sub(9)) * 2;
    let bodies = history.labels.len();
    // (name, short, colour, quantity index)
    let mut curves: Vec<(String, String, Color, usize)> = Vec::new();
    let (title, nonneg) = match plot {
        Plot::Stability => {
            render_stability(v.studies.stability.as_ref(), v.shown, theme, area, buf);
            return;
        }
        Plot::Convergence | Plot::WorkPrecision => {
            render_study(plot, v, area, buf);
            return;
        }
        Plot::Exact => {
            render_exact(v, area, buf);
            return;
        }
        Plot::Energy if bodies > 1 => {
            let colours = [Color::Green, Color::Yellow, Color::Cyan, Color::Magenta];
            for (b, label) in history.labels.iter().enumerate() {
                let c = colours[b % colours.len()];
                curves.push((
                    format!("total {label}"),
                    format!("E{}", b + 1),
                    c,
                    body_index(b, 0),
                ));
            }
            for (b, label) in history.labels.iter().enumerate() {
                let c = colours[b % colours.len()];
                curves.push((
                    format!("kin {label}"),
                    format!("K{}", b + 1),
                    dimmer(c),
                    body_index(b, 1),
                ));
            }
            ("E (J):", false)
        }
        Plot::Energy => {
            for (name, short, color, q) in [
                ("kinetic", "kin", Color::Yellow, 0),
                ("gravity", "grav", Color::Blue, 1),
                ("elastic", "el", Color::Green, 2),
                ("total", "tot", Color::White, 3),
                // The dissipated energy stacked on the total (flat at E0 for an exact
                // integrator) and the method's own energy error.
                ("total + dissipated", "+D", Color::LightBlue, 4),
                ("residual E + D - E0", "res", Color::LightRed, 5),
            ] {
                curves.push((name.into(), short.into(), color, q));
            }
            ("E (J):", false)
        }
        Plot::Speed if bodies > 1 => {
            let colours = [Color::Green, Color::Yellow, Color::Cyan, Color::Magenta];
            for (b, label) in history.labels.iter().enumerate() {
                curves.push((
                    label.clone(),
                    format!("{}", b + 1),
                    colours[b % 4],
                    body_index(b, 2),
                ));
            }
            ("max |v| (m/s):", true)
        }
        Plot::Speed => {
            curves.push(("max |v|".into(), "|v|".into(), Color::Cyan, 6));
            ("max |v| (m/s)", true)
        }
        Plot::Stretch => {
            let colours = [Color::Green, Color::Yellow, Color::Cyan, Color::Magenta];
            for (b, label) in history.labels.iter().enumerate() {
                curves.push((
                    label.clone(),
                    format!("{}", b + 1),
                    colours[b % 4],
                    body_index(b, 3),
                ));
            }
            ("max |L/L0 - 1|:", true)
        }
        Plot::Error => {
            curves.push(("error".into(), "err".into(), Color::LightRed, 7));
            ("|x - x_exact| (m)", true)
        }
    };
    let mut series = Vec::new();
    for (name, short, color, q) in curves {
        let (upper, lower) = envelope(history, q, x_range[1], columns);
        let mut s = Series::new(&name, &short, color, upper);
        let envelope = !lower.is_empty();
        if envelope {
            s.name = format!("{name} (min/max)");
        }
        series.push(s);
        if envelope {
            let mut l = Series::new(&name, &short, color, lower);
            l.guide = true;
            series.push(l);
        }
    }
    let legend_titles = series.iter().filter(|s| !s.guide).count() > 1;
    draw_chart(
        title,
        &series,
        x_range,
        " s",
        nonneg,
        legend_titles,
        theme,
        area,
        buf,
    );
}

fn dimmer(c: Color) -> Color {
    match c {
        Color::Green => Color::LightGreen,
        Color::Yellow => Color::LightYellow,
        Color::Cyan => Color::LightCyan,
        Color::Magenta => Color::LightMagenta,
        other => other,
    }
}

/// A linear chart of `series` with the legend in the title.
#[allow(clippy::too_many_arguments)]
fn draw_chart(
    title: &str,
    series: &[Series],
    x_range: [f64; 2],
    x_unit: &str,
    nonneg: bool,
    legend: bool,
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
            (lo.min(y), hi.max(y))
        });
    let (mut lo, mut hi) = padded(lo, hi);
    if nonneg {
        // A quantity that is never negative: its axis starts at 0.
        lo = 0.0;
        if hi <= 0.0 {
            hi = 1.0;
        }
    }
    let datasets: Vec<Dataset> = series
        .iter()
        .map(|s| {
            Dataset::default()
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
    let named: Vec<&Series> = series.iter().filter(|s| !s.guide).collect();
    let full: usize = named.iter().map(|s| s.name.chars().count() + 1).sum();
    let room = usize::from(area.width.saturating_sub(2));
    if legend {
        for s in &named {
            let name = if title.chars().count() + 1 + full <= room {
                &s.name
            } else {
                &s.short
            };
            spans.push(Span::styled(format!("{name} "), theme.fg(s.color)));
        }
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

fn render_exact(v: &View, area: Rect, buf: &mut Buffer) {
    let theme = v.theme;
    let Some(o) = v.oscillator else {
        not_available(
            "x(t) vs exact",
            "no exact solution: not a one-spring oscillator",
            theme,
            area,
            buf,
        );
        return;
    };
    let history = v.history;
    let span = history.recent_span;
    let start = (v.now - span).max(0.0);
    let end = start + span;
    let simulated: Vec<(f64, f64)> = history
        .recent
        .iter()
        .copied()
        .filter(|(_, x)| x.is_finite())
        .collect();
    // The exact curve over the whole window, ahead of the simulation too, at 4 points per
    // braille column of the widest chart (200 columns).
    let exact: Vec<(f64, f64)> = (0..=800)
        .map(|i| start + span * f64::from(i) / 800.0)
        .map(|t| (t, o.exact(t)))
        .collect();
    let series = vec![
        Series::new("exact", "exact", Color::Yellow, exact),
        Series::new("simulated", "sim", Color::Cyan, simulated),
    ];
    draw_chart(
        "x (m):",
        &series,
        [start, end],
        " s",
        false,
        true,
        theme,
        area,
        buf,
    );
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

/// One log-log series per shown method: log10 error against log10 dt (or log10 force
/// evaluations), named with its key (1–8) and fitted order.
fn study_series(report: &ConvergenceReport, work: bool, shown: [bool; 8]) -> Vec<Series> {
    report
        .methods
        .iter()
        .filter(|m| {
            Method::ALL
                .iter()
                .position(|&x| x == m.method)
                .is_some_and(|i| shown[i])
        })
        .map(|m| {
            let (color, short) = method_style(m.method);
            let key = Method::ALL.iter().position(|&x| x == m.method).unwrap_or(0) + 1;
            let points = m
                .points
                .iter()
                .filter_map(|p| {
                    let x = if work { p.force_evals as f64 } else { p.dt };
                    p.error.filter(|e| *e > 0.0).map(|e| (x.log10(), e.log10()))
                })
                .collect();
            let order = m
                .order
                .map_or_else(|| "—".to_string(), |o| format!("{o:.2}"));
            Series::new(
                &format!("{key} {short} {order}"),
                &format!("{key}{short} {order}"),
                color,
                points,
            )
        })
        .collect()
}

/// `1e-3` for -3: the label of a decade.
fn decade(p: i32) -> String {
    match p {
        0 => "1".into(),
        1 => "10".into(),
        _ => format!("1e{p}"),
    }
}

/// The convergence or work-precision chart: log-log with decade labels, slope guides 1, 2 and
/// 4 through the top corner, the shown methods with their fitted orders in the legend.
fn render_study(plot: Plot, v: &View, area: Rect, buf: &mut Buffer) {
    let theme = v.theme;
    let work = plot == Plot::WorkPrecision;
    let report = if work {
        v.studies.work_precision.as_ref()
    } else {
        v.studies.convergence.as_ref()
    };
    let Some(report) = report else {
        let what = if work {
            "work-precision"
        } else {
            "convergence"
        };
        not_available(
            "study",
            &format!("this scene is too large to study live: run `springlab study {what} <scene>`"),
            theme,
            area,
            buf,
        );
        return;
    };
    let mut series = study_series(report, work, v.shown);
    let pts = || series.iter().flat_map(|s| s.points.iter().copied());
    let (x0, x1, y0, y1) = pts().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), (x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
    );
    let (x0, x1, y0, y1) = if x0.is_finite() {
        (
            x0.floor(),
            x1.ceil().max(x0.floor() + 1.0),
            y0.floor(),
            y1.ceil().max(y0.floor() + 1.0),
        )
    } else {
        (-3.0, 0.0, -6.0, 0.0)
    };
    // Labels every k decades, k so that they fit (ratatui spreads labels evenly over the
    // bounds, so the bounds become multiples of k).
    let step = |lo: f64, hi: f64, room: f64| -> (f64, f64, i32) {
        let mut k = 1.0;
        while (hi - lo) / k + 1.0 > room.max(2.0) {
            k += 1.0;
        }
        ((lo / k).floor() * k, (hi / k).ceil() * k, k as i32)
    };
    let (y0, y1, ky) = step(y0, y1, f64::from(area.height.saturating_sub(4)) / 2.0 + 1.0);
    let (x0, x1, kx) = step(x0, x1, f64::from(area.width.saturating_sub(10)) / 7.0);
    // Slope guides through the corner where the curves start: the largest dt (convergence,
    // error falls to the left) or the fewest evaluations (work, error falls to the right).
    for p in [1.0, 2.0, 4.0] {
        let (ax, ay) = if work { (x0, y1) } else { (x1, y1) };
        let sign = if work { -1.0 } else { 1.0 };
        let far = if work { x1 } else { x0 };
        // Where the line leaves the box at the bottom.
        let bottom_x = ax + sign * (y0 - ay) / p;
        let end_x = if work {
            far.min(bottom_x)
        } else {
            far.max(bottom_x)
        };
        let end_y = ay + sign * p * (end_x - ax);
        let mut g = Series::new(
            &format!("slope {p}"),
            "",
            Color::DarkGray,
            vec![(ax, ay), (end_x, end_y)],
        );
        g.guide = true;
        series.push(g);
    }
    let x_labels: Vec<Span> = (x0 as i32..=x1 as i32)
        .step_by(kx as usize)
        .map(|p| Span::raw(decade(p)))
        .collect();
    let y_labels: Vec<Span> = (y0 as i32..=y1 as i32)
        .step_by(ky as usize)
        .map(|p| Span::raw(decade(p)))
        .collect();
    let datasets: Vec<Dataset> = series
        .iter()
        .map(|s| {
            let d = Dataset::default()
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(if s.guide {
                    theme.dim()
                } else {
                    theme.fg(s.color)
                })
                .data(&s.points);
            // The legend (in the corner the curves leave empty) names the methods with their
            // fitted orders; guides have no name.
            if s.guide { d } else { d.name(s.short.clone()) }
        })
        .collect();
    let title = if work {
        "log-log: error (m) vs force evals"
    } else {
        "log-log: error (m) vs dt (s)"
    };
    let mut spans = vec![Span::raw(title)];
    if series.iter().all(|s| s.guide) {
        spans.push(Span::styled(" (none shown: 1–8)", theme.dim()));
    } else {
        spans.push(Span::styled(" · grey: slopes 1 2 4", theme.dim()));
    }
    let corner = if work {
        ratatui::widgets::LegendPosition::TopRight
    } else {
        ratatui::widgets::LegendPosition::TopLeft
    };
    Chart::new(datasets)
        .block(Block::bordered().title(Line::from(spans)))
        .x_axis(
            Axis::default()
                .bounds([x0, x1])
                .labels(x_labels)
                .style(theme.dim()),
        )
        .y_axis(
            Axis::default()
                .bounds([y0, y1])
                .labels(y_labels)
                .style(theme.dim()),
        )
        .legend_position(Some(corner))
        .hidden_legend_constraints((
            ratatui::layout::Constraint::Percentage(100),
            ratatui::layout::Constraint::Percentage(100),
        ))
        .render(area, buf);
}

/// The stability table: measured limit beside the theory, one line per shown method.
fn render_stability(
    report: Option<&StabilityReport>,
    shown: [bool; 8],
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
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
    let block =
        Block::bordered().title(format!("stable dt·ω (ω_max {} rad/s)", number(r.omega_max)));
    let inner = block.inner(area);
    block.render(area, buf);
    // Name column as wide as the pane allows (names shortened with … when narrow).
    let w = if inner.width >= 30 { 8 } else { 6 };
    let name_width = usize::from(inner.width)
        .saturating_sub(4 + 2 * w)
        .clamp(5, 20);
    let (measured_head, theory_head) = if w == 8 {
        ("measured", "theory")
    } else {
        ("meas.", "theory")
    };
    let mut lines = vec![Line::styled(
        format!(
            "  {:<name_width$} {measured_head:>w$} {theory_head:>w$}",
            "method"
        ),
        theme.dim(),
    )];
    for m in &r.methods {
        let Some(key) = Method::ALL.iter().position(|&x| x == m.method) else {
            continue;
        };
        if !shown[key] {
            continue;
        }
        let (color, _) = method_style(m.method);
        let measured = match (m.stability, m.limit_dt_omega) {
            (_, Some(z)) => format!("{z:.3}"),
            (Stability::Unconditional, None) => "any".to_string(),
            (_, None) => "none".to_string(),
        };
        // The damped theory of the scene (on the undamped oscillator: |R| ≤ 1).
        let theory = m.damped_theory.dt_omega.map_or_else(
            || match m.damped_theory.stability {
                "unconditional" => "any".to_string(),
                "not covered" => "—".to_string(),
                other => other.to_string(),
            },
            |z| format!("{z:.3}"),
        );
        let mut name = m.method.name().to_string();
        if name.chars().count() > name_width {
            name = name.chars().take(name_width - 1).collect::<String>() + "…";
        }
        lines.push(Line::from(vec![
            Span::styled(format!("{} {name:<name_width$} ", key + 1), theme.fg(color)),
            Span::raw(format!("{measured:>w$} {theory:>w$}")),
        ]));
    }
    ratatui::widgets::Paragraph::new(lines).render(inner, buf);
}
