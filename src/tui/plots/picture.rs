//! The plots as pictures for the raster view: the same data as the braille charts, drawn by the
//! chart renderer ([`crate::render::chart`]: labelled axes, the legend in rows above the data,
//! log-log axes with fitted orders for the studies) in the colours of the terminal's theme, and
//! sent through the graphics protocol beside the scene. The stability table stays text.
//!
//! ```text
//! UI thread:  History, Studies ──picture()──▶ Picture (charts + cells) ──Job──▶ encoder thread
//! encoder:    Picture ──draw()──▶ Pixmap ──▶ sixel / kitty / iTerm2 (a second image)
//! ```
//! A picture is only made when its [`Picture::key`] changed (new samples, methods shown, size,
//! theme), and at most [`PICTURE_PERIOD`] apart while the simulation runs.

use std::hash::{Hash, Hasher};
use std::time::Duration;

use ratatui::layout::Rect;
use ratatui::style::Color;
use tiny_skia::{Pixmap, PixmapPaint, Transform};

use super::View;
use super::series::{envelope, exact_data, time_plot};
use super::study::method_style;
use crate::lesson::Plot;
use crate::render::chart::{self, Chart, Ink, Series, SeriesStyle};
use crate::render::colour::Colour;
use crate::tui::theme::{self, Background};

/// Shortest time between two pictures while the simulation runs: four a second.
pub const PICTURE_PERIOD: Duration = Duration::from_millis(250);

/// The charts of the plot area drawn as one picture.
#[derive(Clone, Debug, PartialEq)]
pub struct Picture {
    /// The cells the picture covers (inside the plot area).
    pub area: Rect,
    /// Each chart with the columns it takes, left to right.
    pub charts: Vec<(Chart, u16)>,
    /// The terminal's background (the picture's own).
    pub background: Background,
}

/// The rectangles of `count` plots side by side in `area` (the braille layout: equal widths,
/// the last one takes the remainder).
#[must_use]
pub fn plot_rects(count: usize, area: Rect) -> Vec<Rect> {
    if count == 0 {
        return Vec::new();
    }
    let n = count as u16;
    let width = area.width / n;
    (0..n)
        .map(|i| {
            let w = if i + 1 == n {
                area.width - width * i
            } else {
                width
            };
            Rect::new(area.x + width * i, area.y, w, area.height)
        })
        .collect()
}

/// True for the plots drawn as a picture (all but the stability table and lesson 8's own).
#[must_use]
pub fn is_picture(plot: Plot) -> bool {
    // The stability table is text; lesson 8's observable and resolution plots are drawn from
    // the run's records by `tui::observed_view`.
    !matches!(plot, Plot::Stability | Plot::Observable | Plot::Resolution)
}

/// The cells the pictures of `plots` cover in `area`: the first run of neighbouring plots drawn
/// as pictures; `None` when there is none.
#[must_use]
pub fn picture_area(plots: &[Plot], area: Rect) -> Option<Rect> {
    let rects = plot_rects(plots.len(), area);
    let first = plots.iter().position(|p| is_picture(*p))?;
    let last = first
        + plots[first..]
            .iter()
            .take_while(|p| is_picture(**p))
            .count()
        - 1;
    let (a, b) = (rects[first], rects[last]);
    Some(Rect::new(a.x, a.y, b.x + b.width - a.x, a.height))
}

/// A number that changes when the pictures of `plots` would: the samples, the methods shown,
/// the studies present, the full-history mode, the area and the theme.
#[must_use]
pub(super) fn key(plots: &[Plot], v: &View, area: Rect) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for p in plots {
        (*p as u8).hash(&mut h);
    }
    let history = v.history;
    history.bins.len().hash(&mut h);
    history.last_time().map(f64::to_bits).hash(&mut h);
    history.recent.back().map(|p| p.0.to_bits()).hash(&mut h);
    history.full_exact.hash(&mut h);
    history.labels.hash(&mut h);
    v.shown.hash(&mut h);
    v.studies.convergence.is_some().hash(&mut h);
    v.studies.work_precision.is_some().hash(&mut h);
    v.oscillator.map(|o| o.t0.to_bits()).hash(&mut h);
    (area.x, area.y, area.width, area.height).hash(&mut h);
    (v.theme.background == Background::Light).hash(&mut h);
    h.finish()
}

/// The pictures of `plots` laid out in `area` (cells), `cell` pixels a cell; `None` when no
/// plot there is drawn as a picture.
#[must_use]
pub(super) fn picture(plots: &[Plot], v: &View, area: Rect, cell: (u16, u16)) -> Option<Picture> {
    let covered = picture_area(plots, area)?;
    let rects = plot_rects(plots.len(), area);
    let charts = plots
        .iter()
        .zip(&rects)
        .filter(|(_, r)| r.x >= covered.x && r.x < covered.x + covered.width)
        .map(|(p, r)| {
            // Points across: one per two pixels.
            let columns = usize::from(r.width) * usize::from(cell.0) / 2;
            (chart_of(*p, v, columns), r.width)
        })
        .collect();
    Some(Picture {
        area: covered,
        charts,
        background: v.theme.background,
    })
}

/// The chart renderer's colours for `background`.
#[must_use]
pub fn ink(background: Background) -> Ink {
    match background {
        Background::Light => Ink::LIGHT,
        Background::Dark => Ink::DARK,
    }
}

/// A terminal colour as the picture draws it on `background`: the theme's palette (the one
/// the contrast test checks).
#[must_use]
pub fn colour(c: Color, background: Background) -> Colour {
    let (r, g, b) = theme::rgb(theme::for_background(c, background)).unwrap_or((128, 128, 128));
    Colour::rgb(r, g, b)
}

/// The chart of one plot, `columns` points across for the plots over time.
#[must_use]
pub(super) fn chart_of(plot: Plot, v: &View, columns: usize) -> Chart {
    let bg = v.theme.background;
    let mut chart = match plot {
        Plot::Convergence | Plot::WorkPrecision => study_chart(plot, v),
        Plot::Exact => exact_chart(v, columns),
        _ => time_chart(plot, v, columns),
    };
    chart.ink = ink(bg);
    chart
}

fn time_chart(plot: Plot, v: &View, columns: usize) -> Chart {
    let bg = v.theme.background;
    let Some(tp) = time_plot(plot, v.history) else {
        return Chart::new("", "", "");
    };
    let t_end = v.now.max(1.0);
    let title = match plot {
        Plot::Energy => "energy",
        Plot::Speed => "largest speed",
        Plot::Stretch => "largest spring stretch",
        _ => "error against the exact solution",
    };
    let y_label = tp.title.trim_end_matches(':');
    // A chart under ~440 px wide: the two long energy names without their remark, which
    // goes into the title.
    let narrow = columns < 220;
    let title = if narrow && plot == Plot::Energy && v.history.labels.len() <= 1 {
        "energy (+D flat if exact)"
    } else {
        title
    };
    let mut chart = Chart::new(title, "time t (s)", y_label);
    chart.x_range = Some((0.0, t_end));
    for c in tp.curves {
        let (upper, lower) = envelope(v.history, c.q, t_end, columns);
        let name = match c.name.split_once(" (") {
            Some((short, _)) if narrow && plot == Plot::Energy && c.q >= 4 => short.to_string(),
            _ => c.name,
        };
        let mut s = Series::line(name, upper).with_colour(colour(c.colour, bg));
        if !lower.is_empty() {
            // A min / max envelope: the band between the two, the line on its top.
            s = s.with_band(lower);
        }
        chart.series.push(s);
    }
    if tp.nonneg {
        let hi = chart
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .filter(|y| y.is_finite())
            .fold(0.0f64, f64::max);
        chart.y_range = Some((0.0, if hi > 0.0 { hi } else { 1.0 }));
    }
    chart
}

fn exact_chart(v: &View, columns: usize) -> Chart {
    let bg = v.theme.background;
    let title = if v.history.full_exact {
        "x(t) vs exact, the whole run (x: last periods)"
    } else {
        "x(t) vs exact, last three periods (x: whole run)"
    };
    let mut chart = Chart::new(title, "time t (s)", "x (m)");
    let Some(o) = v.oscillator else {
        chart.title = "no exact solution: not a one-spring oscillator".into();
        return chart;
    };
    let d = exact_data(v, o, columns);
    chart.x_range = Some((d.range[0], d.range[1]));
    chart
        .series
        .push(Series::line("exact", d.exact).with_colour(colour(Color::Yellow, bg)));
    let mut sim = Series::line("simulated", d.simulated).with_colour(colour(Color::Cyan, bg));
    if !d.simulated_low.is_empty() {
        sim = sim.with_band(d.simulated_low);
    }
    chart.series.push(sim);
    chart
}

fn study_chart(plot: Plot, v: &View) -> Chart {
    let bg = v.theme.background;
    let work = plot == Plot::WorkPrecision;
    // Short legend entries (key, label, fitted order p), so that several share a row.
    let (title, x_label) = if work {
        ("error vs work, order p", "force evaluations")
    } else {
        ("error vs dt, order p", "time step dt (s)")
    };
    let mut chart = Chart::new(title, x_label, "error (m)").log_log();
    let report = if work {
        v.studies.work_precision.as_ref()
    } else {
        v.studies.convergence.as_ref()
    };
    let Some(report) = report else {
        chart.title = "too large to study live: see `springlab study`".into();
        return chart;
    };
    let mut lo = (f64::INFINITY, f64::INFINITY);
    let mut hi = (0.0f64, 0.0f64);
    for m in report.methods.iter().filter(|m| v.shown[m.method.index()]) {
        let (c, label) = method_style(m.method);
        let points: Vec<(f64, f64)> = m
            .points
            .iter()
            .filter_map(|p| {
                let x = if work { p.force_evals as f64 } else { p.dt };
                p.error.filter(|e| *e > 0.0 && x > 0.0).map(|e| (x, e))
            })
            .collect();
        for &(x, y) in &points {
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        let order = m
            .order
            .map_or_else(|| "—".to_string(), |o| format!("{o:.2}"));
        let name = format!("{} {label} {order}", m.method.index() + 1);
        chart.series.push(
            Series::line(name, points)
                .with_style(SeriesStyle::LineAndPoints)
                .with_colour(colour(c, bg)),
        );
    }
    if chart.series.is_empty() {
        chart.title = format!("{title} (none shown: press a number)");
        return chart;
    }
    // Slope guides 1, 2, 4 from the corner where the curves start (largest dt, or fewest
    // evaluations, at the largest error), to the other end of the data's x range.
    let grey = colour(Color::DarkGray, bg);
    for p in [1.0, 2.0, 4.0] {
        let (x0, x1) = if work { (lo.0, hi.0) } else { (hi.0, lo.0) };
        let sign = if work { -1.0 } else { 1.0 };
        let guide: Vec<(f64, f64)> = (0..=16)
            .map(|i| x0 * (x1 / x0).powf(f64::from(i) / 16.0))
            .map(|x| (x, hi.1 * (x / x0).powf(sign * p)))
            .filter(|&(_, y)| y >= lo.1)
            .collect();
        chart.series.push(Series {
            // One legend entry for the three guides.
            name: if p == 1.0 {
                "slopes 1 2 4".into()
            } else {
                String::new()
            },
            points: guide,
            style: SeriesStyle::Line,
            colour: Some(grey),
            band: None,
        });
    }
    chart.x_range = Some((lo.0, hi.0));
    chart.y_range = Some((lo.1, hi.1));
    chart
}

/// Draws `picture` at `width × height` pixels: each chart in its share of the width.
#[must_use]
pub fn draw(picture: &Picture, width: u32, height: u32) -> Pixmap {
    let (width, height) = (
        width.clamp(1, crate::render::MAX_SIDE),
        height.clamp(1, crate::render::MAX_SIDE),
    );
    let mut pixmap = Pixmap::new(width, height).expect("size clamped");
    pixmap.fill(ink(picture.background).background.to_skia());
    let cells: u32 = picture
        .charts
        .iter()
        .map(|(_, w)| u32::from(*w))
        .sum::<u32>()
        .max(1);
    let mut x = 0u32;
    let mut used = 0u32;
    for (i, (c, w)) in picture.charts.iter().enumerate() {
        used += u32::from(*w);
        let end = if i + 1 == picture.charts.len() {
            width
        } else {
            width * used / cells
        };
        let cw = end.saturating_sub(x);
        if cw >= 8 && height >= 8 {
            let part = chart::draw(c, cw, height);
            pixmap.draw_pixmap(
                x as i32,
                0,
                part.as_ref(),
                &PixmapPaint::default(),
                Transform::identity(),
                None,
            );
        }
        x = end;
    }
    pixmap
}
