//! Lesson 7's charts: error against dt and against work (log-log, per method, with fitted
//! orders and slope guides), and the stability limits; the studies behind them.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Widget};

use crate::lesson::Plot;
use crate::physics::Method;
use crate::scene::Scene;
use crate::study::convergence::{self, ConvergenceOptions, ConvergenceReport};
use crate::study::stability::{self, StabilityOptions};
use crate::study::{Stability, StabilityReport};
use crate::tui::Theme;

use super::View;
use super::axis::{Series, decade, not_available, number};

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
pub(super) const LIVE_STUDY_MAX_SPRINGS: usize = 200;

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
pub(super) fn method_style(method: Method) -> (Color, &'static str) {
    let d = method.declaration();
    (ansi(d.colour), d.label)
}

/// The terminal's named colour for an ANSI colour number (0–15; others are white).
fn ansi(n: u8) -> Color {
    const NAMED: [Color; 16] = [
        Color::Black,
        Color::Red,
        Color::Green,
        Color::Yellow,
        Color::Blue,
        Color::Magenta,
        Color::Cyan,
        Color::Gray,
        Color::DarkGray,
        Color::LightRed,
        Color::LightGreen,
        Color::LightYellow,
        Color::LightBlue,
        Color::LightMagenta,
        Color::LightCyan,
        Color::White,
    ];
    NAMED.get(usize::from(n)).copied().unwrap_or(Color::White)
}

/// One log-log series per shown method: log10 error against log10 dt (or log10 force
/// evaluations), named with its number key and fitted order.
pub(super) fn study_series(
    report: &ConvergenceReport,
    work: bool,
    shown: [bool; Method::COUNT],
) -> Vec<Series> {
    report
        .methods
        .iter()
        .filter(|m| shown[m.method.index()])
        .map(|m| {
            let (color, short) = method_style(m.method);
            let key = m.method.index() + 1;
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

/// The convergence or work-precision chart: log-log with decade labels, slope guides 1, 2 and
/// 4 through the top corner, the shown methods with their fitted orders in the legend.
pub(super) fn render_study(plot: Plot, v: &View, area: Rect, buf: &mut Buffer) {
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
    // Every legend name padded to the longest: each row of the legend box then covers its
    // whole width (the chart does not clear the box, and a curve behind it would show through).
    let name_width = series
        .iter()
        .filter(|s| !s.guide)
        .map(|s| s.short.chars().count())
        .max()
        .unwrap_or(0);
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
            if s.guide {
                d
            } else {
                d.name(format!("{:<name_width$}", s.short))
            }
        })
        .collect();
    let title = if work {
        "log-log: error (m) vs force evals"
    } else {
        "log-log: error (m) vs dt (s)"
    };
    let mut spans = vec![Span::raw(title)];
    if series.iter().all(|s| s.guide) {
        spans.push(Span::styled(" (none shown: press a number)", theme.dim()));
    } else {
        spans.push(Span::styled(" · grey: slopes 1 2 4", theme.dim()));
    }
    let corner = if work {
        ratatui::widgets::LegendPosition::TopRight
    } else {
        ratatui::widgets::LegendPosition::TopLeft
    };
    Chart::new(datasets)
        .block(Block::bordered().title(super::axis::fit_title(spans, area.width)))
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
pub(super) fn render_stability(
    report: Option<&StabilityReport>,
    shown: [bool; Method::COUNT],
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
        if !shown[m.method.index()] {
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
            Span::styled(
                format!("{} {name:<name_width$} ", m.method.index() + 1),
                theme.fg(color),
            ),
            Span::raw(format!("{measured:>w$} {theory:>w$}")),
        ]));
    }
    ratatui::widgets::Paragraph::new(lines).render(inner, buf);
}
