//! What every chart shares: the series, the axes' padding and tick labels, the short number
//! format, and the one function that draws a braille chart.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Widget};

use crate::tui::Theme;

/// One series of a chart: name, colour, points.
pub(super) struct Series {
    pub(super) name: String,
    pub(super) short: String,
    pub(super) color: Color,
    pub(super) points: Vec<(f64, f64)>,
    /// Drawn dim as a guide (slope lines), left out of the legend.
    pub(super) guide: bool,
}

impl Series {
    pub(super) fn new(name: &str, short: &str, color: Color, points: Vec<(f64, f64)>) -> Series {
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
pub(super) type Points = Vec<(f64, f64)>;

/// A linear chart of `series` with the legend in the title.
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_chart(
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

pub(super) fn not_available(title: &str, text: &str, theme: Theme, area: Rect, buf: &mut Buffer) {
    let block = Block::bordered().title(title);
    let inner = block.inner(area);
    block.render(area, buf);
    ratatui::widgets::Paragraph::new(text)
        .style(theme.dim())
        .wrap(ratatui::widgets::Wrap { trim: true })
        .render(inner, buf);
}

/// A y range with a margin, never empty (a constant series gets ±10 % or ±1).
pub(super) fn padded(lo: f64, hi: f64) -> (f64, f64) {
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

/// A chart's title for a block `width` columns wide (its borders included): the first span,
/// then each following span while the whole fits, so a title never ends cut inside a word or
/// a number (the later spans hold the less needed fields, each starting with ` · `).
#[must_use]
pub fn fit_title(spans: Vec<Span<'static>>, width: u16) -> Line<'static> {
    let room = usize::from(width.saturating_sub(2));
    let mut used = 0;
    let mut kept = Vec::new();
    for (i, span) in spans.into_iter().enumerate() {
        let w = span.content.chars().count();
        if i > 0 && used + w > room {
            break;
        }
        used += w;
        kept.push(span);
    }
    Line::from(kept)
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

/// `1e-3` for -3: the label of a decade.
pub(super) fn decade(p: i32) -> String {
    match p {
        0 => "1".into(),
        1 => "10".into(),
        _ => format!("1e{p}"),
    }
}
