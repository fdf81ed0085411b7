//! Charts into a [`Pixmap`]: line and scatter series on linear or log-log axes, with ticks,
//! labels, a legend (in rows between the title and the plot, so it never hides data) and a title. `springlab render --energy-chart` and the studies draw with it.
//!
//! # Theory
//!
//! **Axes.** A value `v` between the axis ends `lo < hi` goes to the fraction
//!
//! ```text
//! linear:  t = (v - lo) / (hi - lo)
//! log:     t = (log10 v - log10 lo) / (log10 hi - log10 lo)        (v > 0)
//! ```
//! of the plot's width (x, left to right) or height (y, bottom to top). Points that a log axis
//! cannot show (`v ≤ 0`) and non-finite points are left out; a line is broken there.
//!
//! **Nice ticks** (Heckbert, "Nice numbers for graph labels", Graphics Gems, 1990). For a linear
//! axis over the data range `[a, b]` and about `n` ticks:
//!
//! ```text
//! R  = nice(b - a)                    1, 2, 5 or 10 times a power of ten, rounding up
//! d  = nice(R / (n - 1), rounded)     the tick spacing, rounding to the nearest
//! lo = floor(a / d) d,   hi = ceil(b / d) d
//! ticks: lo, lo + d, …, hi     labelled with max(0, -floor(log10 d)) decimals
//! ```
//! A log axis has a labelled tick at every decade `10^k` (every second, third … when there are
//! more than eight) and unlabelled minor ticks at `2, 3, …, 9 × 10^k` when there are at most
//! six decades; with fewer than two decades in view the ticks at 1, 2 and 5 times a power of
//! ten are labelled too (every tick, if that still makes fewer than two labels). A label that would overlap the previous one is left out.
//!
//! The plot shows the data range plus a margin of 4 % of it at each end (of the range in
//! decades on a log axis), so no point sits on the frame; only the ticks inside are drawn.
//!
//! Reference: P. S. Heckbert, "Nice Numbers for Graph Labels", in *Graphics Gems*, A. Glassner
//! (ed.), Academic Press 1990, pp. 61–63.

use std::path::Path;

use tiny_skia::{FillRule, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

use super::colour::{self, Colour};
use super::paint::stroke_line;
use super::text::{Align, draw_text, draw_text_vertical, text_width, vertical_metrics};
use super::{Quality, RenderError, check_size, export};

mod axis;
mod series;
pub use axis::{Axis, Tick};
use axis::{data_range, make_axis};
use series::{SeriesCanvas, plot_mask};

/// How an axis maps values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scale {
    /// Evenly spaced values.
    #[default]
    Linear,
    /// Evenly spaced decades (values must be > 0).
    Log,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SeriesStyle {
    /// A polyline through the points in order.
    #[default]
    Line,
    /// A marker at each point.
    Scatter,
    /// Both.
    LineAndPoints,
}

/// One named set of points.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Name shown in the legend (an empty name is left out of the legend).
    pub name: String,
    /// `(x, y)` points, in data units.
    pub points: Vec<(f64, f64)>,
    /// Line, markers or both.
    pub style: SeriesStyle,
    /// Colour; `None` takes the next colour of [`colour::SERIES`].
    pub colour: Option<Colour>,
    /// A band: the area between `points` and these lower points (same x values) is filled in
    /// the series' colour, translucent, under the line (the energy chart's dissipated energy).
    pub band: Option<Vec<(f64, f64)>>,
}

impl Series {
    /// A line series with the palette's next colour.
    #[must_use]
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            name: name.into(),
            points,
            style: SeriesStyle::Line,
            colour: None,
            band: None,
        }
    }

    /// A scatter series with the palette's next colour.
    #[must_use]
    pub fn scatter(name: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            style: SeriesStyle::Scatter,
            ..Series::line(name, points)
        }
    }

    /// The same series drawn as `style`.
    #[must_use]
    pub fn with_style(mut self, style: SeriesStyle) -> Series {
        self.style = style;
        self
    }

    /// The same series drawn as a band down to `lower` (the same x values).
    #[must_use]
    pub fn with_band(mut self, lower: Vec<(f64, f64)>) -> Series {
        self.band = Some(lower);
        self
    }

    /// The same series in `colour`.
    #[must_use]
    pub fn with_colour(mut self, colour: Colour) -> Series {
        self.colour = Some(colour);
        self
    }
}

/// A chart: title, axis labels (with units, for example `time t (s)`), scales and series.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Chart {
    /// Title above the plot.
    pub title: String,
    /// Label under the x axis.
    pub x_label: String,
    /// Label beside the y axis (drawn reading upwards).
    pub y_label: String,
    /// Scale of the x axis.
    pub x_scale: Scale,
    /// Scale of the y axis.
    pub y_scale: Scale,
    /// The data.
    pub series: Vec<Series>,
    /// Fixed x range `(lo, hi)` instead of one fitted to the data.
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range `(lo, hi)` instead of one fitted to the data.
    pub y_range: Option<(f64, f64)>,
    /// Background, text, grid and frame colours ([`Ink::LIGHT`] by default).
    pub ink: Ink,
}

/// The colours of everything but the series: a chart on white paper or on a black terminal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ink {
    /// The image's background.
    pub background: Colour,
    /// Title, tick labels, axis labels and legend names.
    pub text: Colour,
    /// Grid lines at labelled ticks.
    pub grid: Colour,
    /// Grid lines at unlabelled (minor) ticks.
    pub minor_grid: Colour,
    /// The frame and the ticks.
    pub axis: Colour,
}

impl Ink {
    /// Dark text on white (the files the studies write).
    pub const LIGHT: Ink = Ink {
        background: Colour::rgb(255, 255, 255),
        text: colour::TEXT,
        grid: Colour::rgb(228, 231, 236),
        minor_grid: Colour::rgb(242, 243, 246),
        axis: Colour::rgb(70, 74, 82),
    };
    /// Light text on black (a dark terminal).
    pub const DARK: Ink = Ink {
        background: Colour::rgb(0, 0, 0),
        text: Colour::rgb(225, 228, 234),
        grid: Colour::rgb(52, 56, 64),
        minor_grid: Colour::rgb(30, 32, 37),
        axis: Colour::rgb(160, 165, 175),
    };
}

impl Default for Ink {
    fn default() -> Ink {
        Ink::LIGHT
    }
}

impl Chart {
    /// An empty linear chart with a title and axis labels.
    #[must_use]
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Chart {
        Chart {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            ..Chart::default()
        }
    }

    /// The same chart with both axes logarithmic.
    #[must_use]
    pub fn log_log(mut self) -> Chart {
        self.x_scale = Scale::Log;
        self.y_scale = Scale::Log;
        self
    }

    /// The same chart with `series` added.
    #[must_use]
    pub fn with(mut self, series: Series) -> Chart {
        self.series.push(series);
        self
    }
}

/// Draws `chart` on a `width × height` image with the default [`Quality`].
///
/// # Panics
/// If a side is 0 or larger than [`super::MAX_SIDE`]; see [`try_draw`] for user input.
#[must_use]
pub fn draw(chart: &Chart, width: u32, height: u32) -> Pixmap {
    draw_with(chart, width, height, Quality::default())
}

/// Draws `chart`, checking the size first.
///
/// # Errors
/// [`RenderError::Size`] for a side of 0 or larger than [`super::MAX_SIDE`].
pub fn try_draw(chart: &Chart, width: u32, height: u32) -> Result<Pixmap, RenderError> {
    check_size(width, height)?;
    Ok(draw(chart, width, height))
}

/// Draws `chart` and writes it as a PNG file.
///
/// # Errors
/// A bad size ([`RenderError::Size`]) or a file that cannot be written.
pub fn save_png(chart: &Chart, path: &Path, width: u32, height: u32) -> Result<(), RenderError> {
    let pixmap = try_draw(chart, width, height)?;
    export::save_png(&pixmap, path)
}

/// The plot rectangle of `chart` drawn at `width × height` (px): `(left, top, right, bottom)`,
/// inside the title and legend rows above, the tick labels and axis labels below and left.
#[must_use]
pub fn plot_rect(chart: &Chart, width: u32, height: u32) -> (f32, f32, f32, f32) {
    let m = Metrics::new(width as f32, height as f32, chart.ink);
    let (x_axis, y_axis) = axes(chart);
    let l = Layout::new(chart, &m, &x_axis, &y_axis);
    (l.left, l.top, l.left + l.pw, l.top + l.ph)
}

/// The x and y axes of `chart`: its data ranges (or the ranges it sets) on its scales.
fn axes(chart: &Chart) -> (Axis, Axis) {
    let x = make_axis(
        data_range(chart, true, chart.x_scale),
        chart.x_range,
        chart.x_scale,
    );
    let y = make_axis(
        data_range(chart, false, chart.y_scale),
        chart.y_range,
        chart.y_scale,
    );
    (x, y)
}

/// Draws `chart` with the rasteriser settings `quality`: layout, title, grid with ticks and
/// labels, the series clipped to the plot, the frame and the legend, in that order.
///
/// # Panics
/// If a side is 0 or larger than [`super::MAX_SIDE`].
#[must_use]
pub fn draw_with(chart: &Chart, width: u32, height: u32, quality: Quality) -> Pixmap {
    assert!(check_size(width, height).is_ok(), "chart size out of range");
    let mut pixmap = Pixmap::new(width, height).expect("size checked");
    pixmap.fill(chart.ink.background.to_skia());
    let mut paint = Paint {
        anti_alias: quality.anti_alias,
        force_hq_pipeline: quality.force_hq_pipeline,
        ..Paint::default()
    };
    let m = Metrics::new(width as f32, height as f32, chart.ink);
    let (x_axis, y_axis) = axes(chart);
    let layout = Layout::new(chart, &m, &x_axis, &y_axis);
    let plot = Plot {
        layout: &layout,
        x_axis: &x_axis,
        y_axis: &y_axis,
    };
    let colours = series_colours(chart);

    draw_title(&mut pixmap, chart, &m, &layout);
    draw_x_ticks(&mut pixmap, &mut paint, &m, &plot);
    draw_y_ticks(&mut pixmap, &mut paint, &m, &plot);
    draw_axis_labels(&mut pixmap, chart, &m, &layout);
    let mask = plot_mask(width, height, &layout);
    let mut canvas = SeriesCanvas {
        pixmap: &mut pixmap,
        paint: &mut paint,
        m: &m,
        plot: &plot,
        mask: &mask,
    };
    for (series, &c) in chart.series.iter().zip(&colours) {
        if let Some(lower) = &series.band {
            canvas.band(series, lower, c);
        }
        if matches!(series.style, SeriesStyle::Line | SeriesStyle::LineAndPoints) {
            canvas.line(series, c);
        }
        if matches!(
            series.style,
            SeriesStyle::Scatter | SeriesStyle::LineAndPoints
        ) {
            canvas.points(series, c);
        }
    }
    draw_frame(&mut pixmap, &mut paint, &m, &layout);
    draw_legend(&mut pixmap, &mut paint, chart, &m, &layout, &colours);
    pixmap
}

/// Sizes that scale with the image (px): line scale, text sizes and their metrics, padding.
struct Metrics {
    w: f32,
    h: f32,
    /// Line width scale (1 at 480 px, at least 0.5).
    s: f32,
    /// Text size of labels and legend; `title_px` of the title.
    px: f32,
    title_px: f32,
    ascent: f32,
    descent: f32,
    t_ascent: f32,
    t_descent: f32,
    pad: f32,
    /// Length of a major tick.
    tick: f32,
    /// The colours.
    ink: Ink,
}

impl Metrics {
    fn new(w: f32, h: f32, ink: Ink) -> Metrics {
        let s = (w.min(h) / 480.0).max(0.5);
        let px = (h.min(w) / 32.0).clamp(10.0, 40.0).round();
        let title_px = (1.2 * px).round();
        let (ascent, descent) = vertical_metrics(px);
        let (t_ascent, t_descent) = vertical_metrics(title_px);
        Metrics {
            w,
            h,
            s,
            px,
            title_px,
            ascent,
            descent,
            t_ascent,
            t_descent,
            pad: 0.6 * px,
            tick: 0.4 * px,
            ink,
        }
    }

    /// Length of the legend's line sample.
    fn sample(&self) -> f32 {
        1.8 * self.px
    }

    /// Width of one legend entry: sample, gap, name and the space before the next entry.
    fn entry_width(&self, series: &Series) -> f32 {
        self.sample() + 0.4 * self.px + text_width(&series.name, self.px) + 1.2 * self.px
    }
}

/// Where things go: title on top, then the legend rows; y label and tick labels on the left;
/// x tick labels and label below; the plot rectangle in between.
struct Layout {
    left: f32,
    right: f32,
    top: f32,
    bottom: f32,
    /// Plot width and height (px).
    pw: f32,
    ph: f32,
    legend_top: f32,
    legend_line: f32,
    /// Legend rows: indices of the named series, as many per row as fit.
    rows: Vec<Vec<usize>>,
}

impl Layout {
    fn new(chart: &Chart, m: &Metrics, x_axis: &Axis, y_axis: &Axis) -> Layout {
        let y_tick_w = y_axis
            .ticks
            .iter()
            .map(|t| text_width(&t.label, m.px))
            .fold(0.0f32, f32::max);
        let rows = legend_rows(chart, m);
        let legend_line = (m.ascent + m.descent) * 1.2;
        let title_h = if chart.title.is_empty() {
            0.0
        } else {
            m.t_ascent + m.t_descent + 0.5 * m.pad
        };
        let legend_top = m.pad + title_h;
        let top = legend_top + rows.len() as f32 * legend_line + 0.5 * m.pad;
        let left = m.pad
            + if chart.y_label.is_empty() {
                0.0
            } else {
                m.ascent + m.descent + m.pad
            }
            + y_tick_w
            + m.tick
            + 0.5 * m.pad;
        let bottom = m.h
            - m.pad
            - if chart.x_label.is_empty() {
                0.0
            } else {
                m.ascent + m.descent + 0.5 * m.pad
            }
            - (m.ascent + m.descent)
            - m.tick;
        // Room for the last x tick label to the right.
        let right = m.w
            - m.pad
            - 0.5
                * x_axis
                    .ticks
                    .last()
                    .map_or(0.0, |t| text_width(&t.label, m.px));
        Layout {
            left,
            right,
            top,
            bottom,
            pw: (right - left).max(1.0),
            ph: (bottom - top).max(1.0),
            legend_top,
            legend_line,
            rows,
        }
    }
}

/// The plot rectangle with its two axes: data coordinates to pixels.
struct Plot<'a> {
    layout: &'a Layout,
    x_axis: &'a Axis,
    y_axis: &'a Axis,
}

impl Plot<'_> {
    /// The pixel of data point `(x, y)`, or `None` where an axis cannot place it (a logarithmic
    /// axis and a value ≤ 0).
    fn to_px(&self, x: f64, y: f64) -> Option<(f32, f32)> {
        let tx = self.x_axis.fraction(x)?;
        let ty = self.y_axis.fraction(y)?;
        let l = self.layout;
        Some((l.left + tx as f32 * l.pw, l.bottom - ty as f32 * l.ph))
    }
}

/// The colour of each series: its own, else the palette's in turn.
fn series_colours(chart: &Chart) -> Vec<Colour> {
    chart
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| s.colour.unwrap_or(colour::SERIES[i % colour::SERIES.len()]))
        .collect()
}

/// The named series in legend rows, as many entries per row as fit in the image's width.
fn legend_rows(chart: &Chart, m: &Metrics) -> Vec<Vec<usize>> {
    let mut rows: Vec<Vec<usize>> = Vec::new();
    let mut row_w = 0.0f32;
    for (i, series) in chart.series.iter().enumerate() {
        if series.name.is_empty() {
            continue;
        }
        let ew = m.entry_width(series);
        match rows.last_mut() {
            Some(row) if row_w + ew <= m.w - 2.0 * m.pad => {
                row.push(i);
                row_w += ew;
            }
            _ => {
                rows.push(vec![i]);
                row_w = ew;
            }
        }
    }
    rows
}

fn draw_title(pixmap: &mut Pixmap, chart: &Chart, m: &Metrics, layout: &Layout) {
    if !chart.title.is_empty() {
        draw_text(
            pixmap,
            &chart.title,
            0.5 * (layout.left + layout.right),
            m.pad + m.t_ascent,
            m.title_px,
            m.ink.text,
            Align::Centre,
        );
    }
}

/// Vertical grid lines, x ticks and the x tick labels that do not overlap the previous one.
fn draw_x_ticks(pixmap: &mut Pixmap, paint: &mut Paint, m: &Metrics, plot: &Plot<'_>) {
    let (l, axis) = (plot.layout, plot.x_axis);
    // Right end of the last x label drawn (px).
    let mut last_x_label = f32::NEG_INFINITY;
    for t in &axis.ticks {
        let Some(f) = axis.fraction(t.value) else {
            continue;
        };
        let x = l.left + f as f32 * l.pw;
        let major = !t.label.is_empty() || axis.scale == Scale::Linear;
        let g = if major { m.ink.grid } else { m.ink.minor_grid };
        stroke_line(pixmap, paint, pt(x, l.top), pt(x, l.bottom), m.s, g);
        let len = if major { m.tick } else { 0.5 * m.tick };
        stroke_line(
            pixmap,
            paint,
            pt(x, l.bottom),
            pt(x, l.bottom + len),
            m.s,
            m.ink.axis,
        );
        let half = 0.5 * text_width(&t.label, m.px);
        if !t.label.is_empty() && x - half >= last_x_label + 0.5 * m.px {
            last_x_label = x + half;
            draw_text(
                pixmap,
                &t.label,
                x,
                l.bottom + m.tick + m.ascent,
                m.px,
                m.ink.text,
                Align::Centre,
            );
        }
    }
}

/// Horizontal grid lines, y ticks and the y tick labels that do not overlap the previous one.
fn draw_y_ticks(pixmap: &mut Pixmap, paint: &mut Paint, m: &Metrics, plot: &Plot<'_>) {
    let (l, axis) = (plot.layout, plot.y_axis);
    // Top of the last y label drawn (px).
    let mut last_y_label = f32::INFINITY;
    for t in &axis.ticks {
        let Some(f) = axis.fraction(t.value) else {
            continue;
        };
        let y = l.bottom - f as f32 * l.ph;
        let major = !t.label.is_empty() || axis.scale == Scale::Linear;
        let g = if major { m.ink.grid } else { m.ink.minor_grid };
        stroke_line(pixmap, paint, pt(l.left, y), pt(l.right, y), m.s, g);
        let len = if major { m.tick } else { 0.5 * m.tick };
        stroke_line(
            pixmap,
            paint,
            pt(l.left - len, y),
            pt(l.left, y),
            m.s,
            m.ink.axis,
        );
        // Labels go upwards: the next one must end above this one's top.
        if !t.label.is_empty() && y + 0.5 * m.ascent <= last_y_label - 0.2 * m.px {
            last_y_label = y - 0.5 * m.ascent;
            draw_text(
                pixmap,
                &t.label,
                l.left - m.tick - 0.3 * m.pad,
                y + 0.35 * m.ascent,
                m.px,
                m.ink.text,
                Align::Right,
            );
        }
    }
}

fn draw_axis_labels(pixmap: &mut Pixmap, chart: &Chart, m: &Metrics, layout: &Layout) {
    if !chart.x_label.is_empty() {
        draw_text(
            pixmap,
            &chart.x_label,
            layout.left + 0.5 * layout.pw,
            m.h - m.pad - m.descent,
            m.px,
            m.ink.text,
            Align::Centre,
        );
    }
    if !chart.y_label.is_empty() {
        draw_text_vertical(
            pixmap,
            &chart.y_label,
            m.pad + m.ascent,
            layout.top + 0.5 * layout.ph,
            m.px,
            m.ink.text,
        );
    }
}

/// The frame around the plot.
fn draw_frame(pixmap: &mut Pixmap, paint: &mut Paint, m: &Metrics, layout: &Layout) {
    if let Some(rect) = Rect::from_xywh(layout.left, layout.top, layout.pw, layout.ph) {
        paint.set_color(m.ink.axis.to_skia());
        let stroke = Stroke {
            width: m.s,
            ..Stroke::default()
        };
        pixmap.stroke_path(
            &PathBuilder::from_rect(rect),
            paint,
            &stroke,
            Transform::identity(),
            None,
        );
    }
}

/// The legend rows, each centred over the plot: a sample of the series' line or point, then
/// its name.
fn draw_legend(
    pixmap: &mut Pixmap,
    paint: &mut Paint,
    chart: &Chart,
    m: &Metrics,
    layout: &Layout,
    colours: &[Colour],
) {
    let (px, sample) = (m.px, m.sample());
    for (r, row) in layout.rows.iter().enumerate() {
        let total: f32 = row
            .iter()
            .map(|&i| m.entry_width(&chart.series[i]))
            .sum::<f32>()
            - 1.2 * px;
        let mut x = (0.5 * (layout.left + layout.right) - 0.5 * total)
            .min(m.w - m.pad - total)
            .max(m.pad);
        let baseline = layout.legend_top + m.ascent + r as f32 * layout.legend_line;
        let mid = baseline - 0.35 * m.ascent;
        for &i in row {
            let series = &chart.series[i];
            let c = colours[i];
            if matches!(series.style, SeriesStyle::Line | SeriesStyle::LineAndPoints) {
                stroke_line(pixmap, paint, pt(x, mid), pt(x + sample, mid), 2.0 * m.s, c);
            }
            if matches!(
                series.style,
                SeriesStyle::Scatter | SeriesStyle::LineAndPoints
            ) && let Some(path) = PathBuilder::from_circle(x + 0.5 * sample, mid, 3.2 * m.s)
            {
                paint.set_color(c.to_skia());
                pixmap.fill_path(&path, paint, FillRule::Winding, Transform::identity(), None);
            }
            draw_text(
                pixmap,
                &series.name,
                x + sample + 0.4 * px,
                baseline,
                px,
                m.ink.text,
                Align::Left,
            );
            x += m.entry_width(series);
        }
    }
}

fn pt(x: f32, y: f32) -> tiny_skia::Point {
    tiny_skia::Point::from_xy(x, y)
}

#[cfg(test)]
mod tests {
    use super::axis::format_number;
    use super::*;

    #[test]
    fn linear_ticks_are_nice() {
        let a = Axis::linear(0.13, 9.7, 6);
        assert_eq!((a.lo, a.hi), (0.0, 10.0));
        let labels: Vec<&str> = a.ticks.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(labels, ["0", "2", "4", "6", "8", "10"]);
        let b = Axis::linear(-0.031, 0.012, 6);
        let labels: Vec<&str> = b.ticks.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(
            labels,
            ["-0.04", "-0.03", "-0.02", "-0.01", "0.00", "0.01", "0.02"]
        );
    }

    #[test]
    fn log_ticks_are_decades() {
        let a = Axis::log(0.003, 42.0);
        assert_eq!(a.lo, 1e-3);
        assert_eq!(a.hi, 100.0);
        let labels: Vec<&str> = a
            .ticks
            .iter()
            .filter(|t| !t.label.is_empty())
            .map(|t| t.label.as_str())
            .collect();
        assert_eq!(labels, ["10⁻³", "10⁻²", "10⁻¹", "10⁰", "10¹", "10²"]);
        assert!((a.fraction(0.1).expect("positive") - 0.4).abs() < 1e-12);
        assert_eq!(a.fraction(-1.0), None);
    }

    #[test]
    fn chart_axes_leave_a_margin_and_keep_inner_ticks() {
        let a = make_axis(Some((0.0, 0.5)), None, Scale::Linear);
        assert!(a.lo < 0.0 && a.hi > 0.5);
        let labels: Vec<&str> = a.ticks.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(labels, ["0.0", "0.1", "0.2", "0.3", "0.4", "0.5"]);
        let l = make_axis(Some((0.002, 0.003)), None, Scale::Log);
        let labels: Vec<&str> = l.ticks.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(labels, ["0.002", "0.003"]);
        let l = make_axis(Some((6e-4, 5e-3)), None, Scale::Log);
        let labels: Vec<&str> = l
            .ticks
            .iter()
            .filter(|t| !t.label.is_empty())
            .map(|t| t.label.as_str())
            .collect();
        assert_eq!(labels, ["0.001", "0.002", "0.005"]);
        assert_eq!(format_number(123456.0), "1.23×10⁵");
        assert_eq!(format_number(1e-6), "10⁻⁶");
        assert_eq!(format_number(0.25), "0.25");
    }

    #[test]
    fn degenerate_ranges_widen() {
        let a = Axis::linear(5.0, 5.0, 6);
        assert!(a.lo < 5.0 && a.hi > 5.0);
        let b = Axis::linear(0.0, 0.0, 6);
        assert!(b.lo < 0.0 && b.hi > 0.0);
    }
}
