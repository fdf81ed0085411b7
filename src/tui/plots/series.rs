//! The time-series plots: energy, the oscillator beside its exact solution, the largest speed,
//! the error and the stretch, each drawn as min/max envelopes per body.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;

use crate::lesson::Plot;

use super::View;
use super::axis::{Points, Series, draw_chart, not_available};
use super::history::{Bin, History, Oscillator, POSITION, body_index};
use super::study::{render_stability, render_study};

pub(super) fn render_one(plot: Plot, v: &View, area: Rect, buf: &mut Buffer) {
    let theme = v.theme;
    let history = v.history;
    let x_range = [0.0, v.now.max(1.0)];
    // Braille dots across the plotting area (borders and a y label of ~7 cells left out).
    let columns = usize::from(area.width.saturating_sub(9)) * 2;
    match plot {
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
        _ => {}
    }
    let Some(TimePlot {
        title,
        nonneg,
        curves,
    }) = time_plot(plot, history)
    else {
        return;
    };
    let mut series = Vec::new();
    for c in curves {
        let (upper, lower) = envelope(history, c.q, x_range[1], columns);
        let mut s = Series::new(&c.name, c.short, c.colour, upper);
        let envelope = !lower.is_empty();
        if envelope {
            s.name = format!("{} (min/max)", c.name);
        }
        series.push(s);
        if envelope {
            let mut l = Series::new(&c.name, c.short, c.colour, lower);
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

/// One curve of a time plot: its legend name, short name, colour and quantity
/// ([`Sample`](super::Sample)'s order).
pub(super) struct Curve {
    pub(super) name: String,
    pub(super) short: &'static str,
    pub(super) colour: Color,
    pub(super) q: usize,
}

/// A plot over time: its y title, whether its quantity is never negative, its curves.
pub(super) struct TimePlot {
    pub(super) title: &'static str,
    pub(super) nonneg: bool,
    pub(super) curves: Vec<Curve>,
}

/// The curves of `plot` when it is a plot over time of the history (energy, speed, stretch,
/// error), else `None`.
pub(super) fn time_plot(plot: Plot, history: &History) -> Option<TimePlot> {
    let bodies = history.labels.len();
    let curve = |name: String, short: &'static str, colour: Color, q: usize| Curve {
        name,
        short,
        colour,
        q,
    };
    let mut curves = Vec::new();
    let (title, nonneg) = match plot {
        Plot::Stability | Plot::Convergence | Plot::WorkPrecision | Plot::Exact => return None,
        // Drawn from the run's own records by the lesson screen (tui::observed_view).
        Plot::Observable | Plot::Resolution => return None,
        Plot::Energy if bodies > 1 => {
            // Eight distinct colours: a total and a kinetic energy per body, no two alike.
            const TOTALS: [Color; 4] = [Color::Green, Color::Magenta, Color::Cyan, Color::LightRed];
            const KINETIC: [Color; 4] = [
                Color::Yellow,
                Color::LightBlue,
                Color::LightMagenta,
                Color::LightCyan,
            ];
            const SHORT_E: [&str; 4] = ["E1", "E2", "E3", "E4"];
            const SHORT_K: [&str; 4] = ["K1", "K2", "K3", "K4"];
            for (b, label) in history.labels.iter().enumerate() {
                curves.push(curve(
                    format!("total {label}"),
                    SHORT_E[b % 4],
                    TOTALS[b % TOTALS.len()],
                    body_index(b, 0),
                ));
            }
            for (b, label) in history.labels.iter().enumerate() {
                curves.push(curve(
                    format!("kin {label}"),
                    SHORT_K[b % 4],
                    KINETIC[b % KINETIC.len()],
                    body_index(b, 1),
                ));
            }
            ("E (J):", false)
        }
        Plot::Energy => {
            for (name, short, colour, q) in ENERGY {
                curves.push(curve(name.into(), short, colour, q));
            }
            ("E (J):", false)
        }
        Plot::Speed if bodies > 1 => {
            curves.extend(per_body(history, 2));
            ("max |v| (m/s):", true)
        }
        Plot::Speed => {
            curves.push(curve("max |v|".into(), "|v|", Color::Cyan, 6));
            ("max |v| (m/s)", true)
        }
        Plot::Stretch => {
            curves.extend(per_body(history, 3));
            ("max |L/L0 - 1|:", true)
        }
        Plot::Error => {
            curves.push(curve("error".into(), "err", Color::LightRed, 7));
            ("|x - x_exact| (m)", true)
        }
    };
    Some(TimePlot {
        title,
        nonneg,
        curves,
    })
}

/// The energy plot's curves of one body: (legend name, short name, colour, quantity). The
/// dissipated energy stacked on the total is flat at E0 for an exact integrator; the residual
/// is the method's own energy error.
pub(super) const ENERGY: [(&str, &str, Color, usize); 6] = [
    ("kinetic", "kin", Color::Yellow, 0),
    ("gravity", "grav", Color::Blue, 1),
    ("elastic", "el", Color::Green, 2),
    ("total", "tot", Color::White, 3),
    (
        "+D = total + dissipated (flat if exact)",
        "+D",
        // Not light blue: that is gravity's blue on a dark background (`theme::for_background`).
        Color::LightCyan,
        4,
    ),
    (
        "res = E + D - E0 (method's error)",
        "res",
        Color::LightRed,
        5,
    ),
];

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

/// The exact-vs-simulated plot's data: its time range, the exact curve and the simulated
/// points (upper and lower envelope in the full-history mode; the lower one empty otherwise).
pub(super) struct ExactData {
    pub(super) range: [f64; 2],
    pub(super) exact: Points,
    pub(super) simulated: Points,
    pub(super) simulated_low: Points,
}

/// What the exact-vs-simulated plot shows for oscillator `o`: the last three periods (finely
/// sampled) or, in the full-history mode, the whole run at `columns` points across.
pub(super) fn exact_data(v: &View, o: &Oscillator, columns: usize) -> ExactData {
    let history = v.history;
    let (start, end, simulated, simulated_low) = if history.full_exact {
        let end = v.now.max(history.recent_span);
        let (upper, lower) = envelope(history, POSITION, end, columns);
        (0.0, end, upper, lower)
    } else {
        let span = history.recent_span;
        let start = (v.now - span).max(0.0);
        let simulated = history
            .recent
            .iter()
            .copied()
            .filter(|(_, x)| x.is_finite())
            .collect();
        (start, start + span, simulated, Vec::new())
    };
    // The exact curve over the whole range, ahead of the simulation too: 800 points in the
    // window (4 per braille column of the widest chart), 4000 over the whole run.
    let n = if history.full_exact { 4000 } else { 800 };
    let exact = (0..=n)
        .map(|i| start + (end - start) * f64::from(i) / f64::from(n))
        .map(|t| (t, o.exact(t)))
        .collect();
    ExactData {
        range: [start, end],
        exact,
        simulated,
        simulated_low,
    }
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
    let columns = usize::from(area.width.saturating_sub(9)) * 2;
    let d = exact_data(v, o, columns);
    let mut series = vec![
        Series::new("exact", "exact", Color::Yellow, d.exact),
        Series::new("simulated", "sim", Color::Cyan, d.simulated),
    ];
    if !d.simulated_low.is_empty() {
        let mut low = Series::new("simulated", "sim", Color::Cyan, d.simulated_low);
        low.guide = true;
        series.push(low);
    }
    let title = if v.history.full_exact {
        "x (m), whole run:"
    } else {
        "x (m):"
    };
    draw_chart(title, &series, d.range, " s", false, true, theme, area, buf);
}

/// One curve per body of the history's per-body quantity `q` (2: speed, 3: stretch), coloured
/// in turn green, yellow, cyan, magenta.
fn per_body(history: &History, q: usize) -> Vec<Curve> {
    const COLOURS: [Color; 4] = [Color::Green, Color::Yellow, Color::Cyan, Color::Magenta];
    const SHORT: [&str; 4] = ["1", "2", "3", "4"];
    history
        .labels
        .iter()
        .enumerate()
        .map(|(b, label)| Curve {
            name: label.clone(),
            short: SHORT[b % 4],
            colour: COLOURS[b % 4],
            q: body_index(b, q),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::theme::{Background, for_background, rgb};

    /// The energy plot's six curves are six colours as drawn on either background: a dark
    /// terminal draws blue as light blue, so gravity and "+D" were one colour there.
    #[test]
    fn the_energy_curves_are_six_colours_on_either_background() {
        for background in [Background::Dark, Background::Light] {
            let drawn: Vec<_> = ENERGY
                .iter()
                .map(|&(name, _, colour, _)| (name, rgb(for_background(colour, background))))
                .collect();
            for (i, (a, ca)) in drawn.iter().enumerate() {
                for (b, cb) in &drawn[i + 1..] {
                    assert_ne!(ca, cb, "{background:?}: {a} and {b} are drawn alike");
                }
            }
        }
    }
}
