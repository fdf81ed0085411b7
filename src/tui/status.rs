//! The two status lines under a lesson: the method and its numbers, then the run's progress.
//!
//! ```text
//!  rk4 · dt 0.01 s · dt·ω 0.100 · limit 0.2828 s · k 100 N/m · k_d 0 N·s/m · view: braille (v)
//!  ‖ paused · t = 0.00 s · step 0 · 0/4096 steps/frame · ×— real time · — steps/s · — fps
//! ```
//! The first line ends with the scene pane's view (`view: raster (sixel, 30 images/s) (v)`,
//! `view: halfblocks (v)`, `view: braille (v)`). A line too long for the terminal drops whole
//! fields, least needed first (k_d, k and passes, drag and γ, dt·ω, the view; the method, dt
//! and its limit last), so no number is ever cut; a field the step points at (`dt·ω`,
//! `stable below`, `` `c` ``, `γ`, `` `k` ``, `k_d` in a try item, or in a line of its text
//! that says "status line") is kept as long as the limit.
//! dt and the limit have four significant digits.
//! `ω` is the stiffest mode ω_max (power iteration, as the stability study); beside it the
//! present method's largest stable dt on this scene by the damped theory
//! ([`crate::study::theory`]: dampers and drag included, the bodies' initial state), yellow
//! above 80 % of it and red with ✗ beyond. Where the usable dt (the energy within 1 % of E₀
//! over the scene's duration: `lesson_run/usable.rs`, searched in the app on small scenes) is
//! lower, the limit shown is that one, `limit … s (usable)`, yellow with "over" beyond it,
//! and `stable below … s` follows as a field of its own, kept before the view (red ✗ beyond
//! that);
//! "unstable at every dt" (explicit Euler or midpoint
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

/// True when the step points at the status field `tag` (`dt·ω`, `stable below`, `` `c` ``,
/// `γ`, `` `k` ``, `k_d`): a try item names it, or a line of its text that says "status line"
/// ("the status line shows `c`").
#[must_use]
pub fn points_at(run: &LessonRun, tag: &str) -> bool {
    run.shown_text()
        .lines()
        .any(|l| l.contains("status line") && l.contains(tag))
        || run.step().try_list.iter().any(|t| t.text.contains(tag))
}

/// One field of a status line: its spans and its priority (0 is kept longest).
type Field = (u8, Vec<Span<'static>>);

/// The fields that fit `width` columns, whole, in their order: the lowest-priority fields are
/// dropped first (never a field cut in the middle of a number), ` · ` between them.
fn fit(fields: Vec<Field>, width: usize, sep: Style) -> Line<'static> {
    line(kept(fields, width), sep)
}

/// The fields of [`fit`] that fit `width` columns.
fn kept(fields: Vec<Field>, width: usize) -> Vec<Field> {
    let len = |f: &Field| f.1.iter().map(Span::width).sum::<usize>();
    let total =
        |fs: &[Field]| fs.iter().map(len).sum::<usize>() + 3 * fs.len().saturating_sub(1) + 1;
    let mut fields = fields;
    while total(&fields) > width && fields.len() > 1 {
        let Some(worst) = fields
            .iter()
            .enumerate()
            .max_by_key(|(i, f)| (f.0, *i))
            .map(|(i, _)| i)
        else {
            break;
        };
        fields.remove(worst);
    }
    fields
}

/// Fields joined by `sep`, after one column of margin.
fn line(fields: Vec<Field>, sep: Style) -> Line<'static> {
    let mut spans = vec![Span::raw(" ")];
    for (i, (_, f)) in fields.into_iter().enumerate() {
        if i > 0 {
            spans.push(Span::styled(" · ", sep));
        }
        spans.extend(f);
    }
    Line::from(spans)
}

/// A time step or a limit with four significant digits, so that two of them compare
/// (`1.917e-3`, `2e-3`, `0.2`): trailing zeros dropped, scientific below 0.01.
#[must_use]
pub fn precise(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if !(1e-2..1e5).contains(&a) {
        let s = format!("{v:.3e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = if m.contains('.') {
            m.trim_end_matches('0').trim_end_matches('.')
        } else {
            m
        };
        return format!("{m}e{e}");
    }
    let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

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
    let raw = |p: u8, s: String| (p, vec![Span::raw(s)]);
    // A field the step points at is kept as long as the limit.
    let priority = |tag: &str, p: u8| if points_at(run, tag) { 1 } else { p };
    let mut first: Vec<Field> = vec![
        (
            0,
            vec![Span::styled(
                sim.scene.method_label(),
                theme.fg(Color::Cyan).add_modifier(Modifier::BOLD),
            )],
        ),
        raw(0, format!("dt {} s", precise(dt))),
    ];
    // dt against the method's limit on this scene: the damped theory (dampers and drag
    // included) of the bodies at their initial state.
    if !run.limit_shown() {
        first.push((
            1,
            vec![Span::styled("limit: after your prediction", theme.dim())],
        ));
    } else if let Some((limit, omega)) = run.limit() {
        use super::lesson_run::{Limit, UsableDt};
        use crate::study::stability::usable::USABLE_TOLERANCE;
        first.push(raw(
            priority("dt·ω", 4),
            format!("dt·ω {}", number(dt * omega)),
        ));
        let usable = match (limit, run.usable_dt()) {
            (Limit::Below(max), Some(UsableDt::Below(u))) if u < *max => Some(u),
            _ => None,
        };
        let mut stable = None;
        let (text, style) = match (limit, usable) {
            (Limit::Below(max), Some(u)) => {
                // Over the usable dt the run is stable but its energy is off by more than
                // 1 %: yellow; over the stable limit too, red as below.
                let (mark, style) = if dt >= *max {
                    (
                        "✗ over ",
                        theme.fg(Color::LightRed).add_modifier(Modifier::BOLD),
                    )
                } else if dt > u * (1.0 + USABLE_TOLERANCE) {
                    // The search brackets the usable dt within its tolerance: a dt inside
                    // that bracket is not judged.
                    ("over ", theme.fg(Color::Yellow))
                } else {
                    ("", Style::default())
                };
                stable = Some(raw(
                    priority("stable below", 2),
                    format!("stable below {} s", precise(*max)),
                ));
                (format!("{mark}limit {} s (usable)", precise(u)), style)
            }
            (Limit::Below(max), None) => {
                let ratio = dt / max;
                let style = if ratio >= 1.0 {
                    theme.fg(Color::LightRed).add_modifier(Modifier::BOLD)
                } else if ratio > 0.8 {
                    theme.fg(Color::Yellow)
                } else {
                    Style::default()
                };
                let mark = if ratio >= 1.0 { "✗ over " } else { "" };
                (format!("{mark}limit {} s", precise(*max)), style)
            }
            (Limit::Never, _) => (
                "unstable at every dt".to_string(),
                theme.fg(Color::LightRed).add_modifier(Modifier::BOLD),
            ),
            (Limit::Always, _) => ("stable at any dt".to_string(), Style::default()),
            (Limit::NotCovered, _) => ("limit: no theory".to_string(), theme.dim()),
        };
        let (text, style) = if run.computing() {
            ("limit: computing…".to_string(), theme.dim())
        } else {
            (text, style)
        };
        first.push((1, vec![Span::styled(text, style)]));
        first.extend(stable);
    }
    if let Some(c) = run.uniform_drag().filter(|c| *c > 0.0) {
        first.push(raw(priority("`c`", 4), format!("c {} N·s/m", number(c))));
    }
    if let Some(g) = run.verlet_gamma().filter(|g| *g > 0.0) {
        first.push(raw(priority("γ", 4), format!("γ {}", number(g))));
    }
    if let Some(p) = run.verlet_passes() {
        first.push(raw(
            5,
            format!("{p} pass{}", if p == 1 { "" } else { "es" }),
        ));
    }
    if let Some(k) = run.uniform_stiffness() {
        first.push(raw(priority("`k`", 5), format!("k {} N/m", number(k))));
    }
    if let Some(c) = run.uniform_damping() {
        first.push(raw(priority("k_d", 6), format!("k_d {} N·s/m", number(c))));
    }
    if run.speed() != 1.0 {
        first.push((
            2,
            vec![Span::styled(
                format!("speed ×{}", number(run.speed())),
                theme.fg(Color::Yellow),
            )],
        ));
    }
    // The view, after the coefficients are gone.
    first.push((
        3,
        vec![Span::styled(
            format!("view: {view} (v)"),
            theme.fg(Color::Cyan),
        )],
    ));

    let dash = |v: Option<f64>| v.map_or_else(|| "—".to_string(), number);
    let second: Vec<Field> = if let Some(d) = &sim.diverged {
        vec![
            (
                0,
                vec![Span::styled(
                    format!(
                        "✗ unstable at step {}, t = {} s",
                        d.step,
                        time_text(d.time, dt)
                    ),
                    theme.fg(Color::LightRed).add_modifier(Modifier::BOLD),
                )],
            ),
            (
                1,
                vec![Span::styled(
                    format!("max |v| = {} m/s", number(d.max_speed)),
                    theme.fg(Color::LightRed),
                )],
            ),
            (
                0,
                vec![Span::styled("r to start over", theme.fg(Color::LightRed))],
            ),
        ]
    } else {
        let (mark, style) = if run.is_running() {
            ("▶ running", theme.fg(Color::LightGreen))
        } else {
            ("‖ paused", theme.fg(Color::Yellow))
        };
        vec![
            (
                0,
                vec![Span::styled(mark, style.add_modifier(Modifier::BOLD))],
            ),
            raw(0, format!("t = {} s", time_text(sim.time(), dt))),
            raw(4, format!("step {}", sim.steps)),
            raw(
                5,
                format!(
                    "{}/{} steps/frame",
                    run.last_frame_steps(),
                    run.max_steps_per_frame()
                ),
            ),
            raw(1, format!("×{} real time", dash(run.real_time_factor()))),
            raw(3, format!("{} steps/s", dash(run.steps_per_second()))),
            raw(
                2,
                format!(
                    "{} fps",
                    fps.map_or_else(|| "—".to_string(), |f| format!("{f:.0}"))
                ),
            ),
        ]
    };
    let width = usize::from(area.width);
    // Where a field kept as long as the limit would go, the method gives its short label
    // ("SIE" for semi-implicit-euler) instead.
    let needed = |fs: &[Field]| fs.iter().filter(|f| f.0 <= 1).count();
    let mut shown = kept(first.clone(), width);
    if needed(&shown) < needed(&first) {
        let labels: Vec<&str> = sim
            .scene
            .bodies
            .iter()
            .map(|b| b.method.declaration().label)
            .collect();
        let label = if labels.windows(2).all(|w| w[0] == w[1]) {
            labels.first().copied().unwrap_or_default().to_string()
        } else {
            labels.join(",")
        };
        first[0].1 = vec![Span::styled(
            label,
            theme.fg(Color::Cyan).add_modifier(Modifier::BOLD),
        )];
        shown = kept(first, width);
    }
    buf.set_line(area.x, area.y, &line(shown, theme.dim()), area.width);
    if area.height > 1 {
        buf.set_line(
            area.x,
            area.y + 1,
            &fit(second, width, theme.dim()),
            area.width,
        );
    }
}
