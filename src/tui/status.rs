//! The two status lines under a lesson: the method and its numbers, then the run's progress.
//!
//! ```text
//!  rk4 · dt 0.010 s · dt·ω 0.100 · k 100 N/m · k_d 0 N·s/m
//!  ‖ paused · t = 0.00 s · step 0 · 0/4096 steps/frame · ×— real time · — steps/s · — fps
//! ```
//! The first line ends with the scene pane's view (`view: raster (sixel, 30 images/s) (v)`,
//! `view: halfblocks (v)`, `view: braille (v)`).
//! `ω` is the stiffest mode ω_max (power iteration, as the stability study); beside it the
//! present method's largest stable dt on this scene by the damped theory
//! ([`crate::study::theory`]: dampers and drag included, the bodies' initial state), yellow
//! above 80 % of it and red with ✗ beyond; "unstable at every dt" (explicit Euler or midpoint
//! with nothing damping), "stable at any dt", or "limit: no theory" (projection, XPBD). Then
//! the drag c, Verlet's γ and projection passes when they apply. Times are simulated times;
//! the real-time factor, steps per second and frames per second are measured (a dash until
//! measured).

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};

use super::Theme;
use super::lesson_run::LessonRun;
use super::plots::number;
use super::sim_view::time_text;

/// Draws the status lines of `run` into the two rows of `area`.
pub fn render(
    run: &LessonRun,
    fps: Option<f64>,
    view: &str,
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    let sim = run.sim();
    let dt = sim.dt();
    let sep = || Span::styled(" · ", theme.dim());
    let mut first = vec![
        Span::raw(" "),
        Span::styled(
            sim.scene.method_label(),
            theme.fg(Color::Cyan).add_modifier(Modifier::BOLD),
        ),
        sep(),
        Span::raw(format!("dt {} s", number(dt))),
    ];
    // dt against the method's limit on this scene: the damped theory (dampers and drag
    // included) of the bodies at their initial state.
    if let Some((limit, omega)) = run.limit() {
        use super::lesson_run::Limit;
        first.push(sep());
        first.push(Span::raw(format!("dt·ω {}", number(dt * omega))));
        let (text, style) = match limit {
            Limit::Below(max) => {
                let ratio = dt / max;
                let style = if ratio >= 1.0 {
                    theme.fg(Color::LightRed).add_modifier(Modifier::BOLD)
                } else if ratio > 0.8 {
                    theme.fg(Color::Yellow)
                } else {
                    Style::default()
                };
                let mark = if ratio >= 1.0 { "✗ over " } else { "" };
                (format!("{mark}limit {} s", number(*max)), style)
            }
            Limit::Never => (
                "unstable at every dt".to_string(),
                theme.fg(Color::LightRed).add_modifier(Modifier::BOLD),
            ),
            Limit::Always => ("stable at any dt".to_string(), Style::default()),
            Limit::NotCovered => ("limit: no theory".to_string(), theme.dim()),
        };
        first.push(sep());
        first.push(Span::styled(text, style));
    }
    if let Some(c) = run.uniform_drag().filter(|c| *c > 0.0) {
        first.push(sep());
        first.push(Span::raw(format!("c {} N·s/m", number(c))));
    }
    if let Some(g) = run.verlet_gamma().filter(|g| *g > 0.0) {
        first.push(sep());
        first.push(Span::raw(format!("γ {}", number(g))));
    }
    if let Some(p) = run.verlet_passes() {
        first.push(sep());
        first.push(Span::raw(format!(
            "{p} pass{}",
            if p == 1 { "" } else { "es" }
        )));
    }
    if let Some(k) = run.uniform_stiffness() {
        first.push(sep());
        first.push(Span::raw(format!("k {} N/m", number(k))));
    }
    if let Some(c) = run.uniform_damping() {
        first.push(sep());
        first.push(Span::raw(format!("k_d {} N·s/m", number(c))));
    }
    if run.speed() != 1.0 {
        first.push(sep());
        first.push(Span::styled(
            format!("speed ×{}", number(run.speed())),
            theme.fg(Color::Yellow),
        ));
    }

    let dash = |v: Option<f64>| v.map_or_else(|| "—".to_string(), number);
    let second = if let Some(d) = &sim.diverged {
        vec![
            Span::styled(
                format!(
                    " ✗ unstable at step {}, t = {} s",
                    d.step,
                    time_text(d.time, dt)
                ),
                theme.fg(Color::LightRed).add_modifier(Modifier::BOLD),
            ),
            Span::styled(
                format!(": max |v| = {} m/s; r to start over", number(d.max_speed)),
                theme.fg(Color::LightRed),
            ),
        ]
    } else {
        let (mark, style) = if run.is_running() {
            ("▶ running", theme.fg(Color::LightGreen))
        } else {
            ("‖ paused", theme.fg(Color::Yellow))
        };
        vec![
            Span::raw(" "),
            Span::styled(mark, style.add_modifier(Modifier::BOLD)),
            sep(),
            Span::raw(format!("t = {} s", time_text(sim.time(), dt))),
            sep(),
            Span::raw(format!("step {}", sim.steps)),
            sep(),
            Span::raw(format!(
                "{}/{} steps/frame",
                run.last_frame_steps(),
                run.max_steps_per_frame()
            )),
            sep(),
            Span::raw(format!("×{} real time", dash(run.real_time_factor()))),
            sep(),
            Span::raw(format!("{} steps/s", dash(run.steps_per_second()))),
            sep(),
            Span::raw(format!(
                "{} fps",
                fps.map_or_else(|| "—".to_string(), |f| format!("{f:.0}"))
            )),
        ]
    };
    buf.set_line(area.x, area.y, &Line::from(first), area.width);
    // The view, right-aligned on the first line (over its end when the line is too long).
    let label = format!(" view: {view} (v) ");
    let width = label.chars().count() as u16;
    if area.width > width {
        buf.set_string(
            area.x + area.width - width,
            area.y,
            label,
            theme.fg(Color::Cyan),
        );
    }
    if area.height > 1 {
        buf.set_line(area.x, area.y + 1, &Line::from(second), area.width);
    }
}
