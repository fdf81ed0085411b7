//! The time-series plots: energy, the oscillator beside its exact solution, the largest speed,
//! the error and the stretch, each drawn as min/max envelopes per body.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;

use crate::lesson::Plot;

use super::View;
use super::axis::{Points, Series, draw_chart, not_available};
use super::history::{Bin, History, body_index};
use super::study::{render_stability, render_study};

pub(super) fn render_one(plot: Plot, v: &View, area: Rect, buf: &mut Buffer) {
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
        // Drawn from the run's own records by the lesson screen (tui::observed_view).
        Plot::Observable | Plot::Resolution => return,
        Plot::Energy if bodies > 1 => {
            // Eight distinct colours: a total and a kinetic energy per body, no two alike.
            let totals = [Color::Green, Color::Magenta, Color::Cyan, Color::LightRed];
            let kinetic = [
                Color::Yellow,
                Color::LightBlue,
                Color::LightMagenta,
                Color::LightCyan,
            ];
            for (b, label) in history.labels.iter().enumerate() {
                curves.push((
                    format!("total {label}"),
                    format!("E{}", b + 1),
                    totals[b % totals.len()],
                    body_index(b, 0),
                ));
            }
            for (b, label) in history.labels.iter().enumerate() {
                curves.push((
                    format!("kin {label}"),
                    format!("K{}", b + 1),
                    kinetic[b % kinetic.len()],
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
            curves.extend(per_body(history, 2));
            ("max |v| (m/s):", true)
        }
        Plot::Speed => {
            curves.push(("max |v|".into(), "|v|".into(), Color::Cyan, 6));
            ("max |v| (m/s)", true)
        }
        Plot::Stretch => {
            curves.extend(per_body(history, 3));
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

/// The curve of quantity `q` ([`Sample::values`] order) over the run, drawn into a chart
/// `columns` braille dots wide: one point per bin while the bins fit, else per column its
/// largest and its smallest value as two lines (a min / max envelope). Returns (upper, lower);
/// lower is empty when every column holds a single value.
pub(super) fn envelope(
    history: &History,
    q: usize,
    t_end: f64,
    columns: usize,
) -> (Points, Points) {
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

pub(super) fn render_exact(v: &View, area: Rect, buf: &mut Buffer) {
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

/// One curve per body of the history's per-body quantity `q` (2: speed, 3: stretch), coloured
/// in turn green, yellow, cyan, magenta.
fn per_body(history: &History, q: usize) -> Vec<(String, String, Color, usize)> {
    const COLOURS: [Color; 4] = [Color::Green, Color::Yellow, Color::Cyan, Color::Magenta];
    history
        .labels
        .iter()
        .enumerate()
        .map(|(b, label)| {
            (
                label.clone(),
                format!("{}", b + 1),
                COLOURS[b % 4],
                body_index(b, q),
            )
        })
        .collect()
}
